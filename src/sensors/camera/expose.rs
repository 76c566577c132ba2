//! The sensor's imaging of light: the tone curve as a function, auto-exposure's meter (the brightness of a
//! rendered image) and gain, vignetting, and sensor noise (shot and read noise through the gain and the tone
//! curve, drawn from a seeded tile of Gaussian samples).
//!
//! Auto-exposure multiplies the linear light by the clip's gain inside the tone curve's lookup table
//! ([`super::post::build_lut`]), so it costs nothing per frame. Noise is added to the 8-bit image, per pixel
//! and channel, with a standard deviation per 8-bit level worked out once per clip.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use crate::util::mix::splitmix64;
use crate::util::srgb;

/// The tone curve ([`super::post::tone_curve`], which the lookup table samples): linear light (at a gain of 1)
/// to an 8-bit level, unrounded.
pub fn tone_level(x: f64) -> f64 {
    f64::from(super::post::tone_curve(x.max(0.0) as f32)) * 255.0
}

/// The tone curve's inverse at the centre of each 8-bit level: the linear light (at a gain of 1) that maps to
/// level `v` (255 to the top of the lookup table's range, [`super::post::LUT_MAX`]).
pub fn linear_of_levels() -> [f64; 256] {
    let top = 1.0 - (-1.1 * f64::from(super::post::LUT_MAX)).exp();
    std::array::from_fn(|v| {
        let mapped = f64::from(srgb::decode(v as f32 / 255.0));
        super::post::shoulder_inverse(mapped.min(top))
    })
}

/// Auto-exposure's meter: the brightness of an 8-bit sRGB image, the geometric mean of the linear luminance
/// (`(r + 2 g + b) / 4` through [`linear_of_levels`], at least 10⁻⁴) of its pixels between the 10th and the
/// 90th percentile. 0 for an empty image.
pub fn brightness(rgb: &[u8]) -> f64 {
    let mut histogram = [0u64; 256];
    for px in rgb.chunks_exact(3) {
        let luma = (u32::from(px[0]) + 2 * u32::from(px[1]) + u32::from(px[2]) + 2) / 4;
        histogram[luma as usize] += 1;
    }
    let n: u64 = histogram.iter().sum();
    if n == 0 {
        return 0.0;
    }
    let linear = linear_of_levels();
    // The pixels ranked in [lo, hi), level by level (a level straddling a bound counts in part).
    let (lo, hi) = (0.1 * n as f64, 0.9 * n as f64);
    let (mut below, mut sum, mut weight) = (0.0f64, 0.0f64, 0.0f64);
    for (v, &count) in histogram.iter().enumerate() {
        let (start, end) = (below, below + count as f64);
        below = end;
        let share = (end.min(hi) - start.max(lo)).max(0.0);
        sum += share * linear[v].max(1.0e-4).ln();
        weight += share;
    }
    if weight > 0.0 { (sum / weight).exp() } else { 0.0 }
}

/// Auto-exposure's gain for a metered brightness: `key / brightness` between 1 and `max_gain` (a brightness of
/// 0, an empty image's, gives `max_gain`).
pub fn auto_gain(brightness: f64, key: f32, max_gain: f32) -> f32 {
    let max_gain = f64::from(max_gain.max(1.0));
    if brightness <= 0.0 {
        return max_gain as f32;
    }
    (f64::from(key) / brightness).clamp(1.0, max_gain) as f32
}

/// Side of the square tile of Gaussian samples the noise is read from, pixels (a power of two).
const TILE: usize = 512;
/// The tile's samples are standard normal × this, rounded to `i8`.
const TILE_SCALE: f32 = 32.0;

/// Sensor noise of one clip: a tile of Gaussian samples drawn from its seed and, at the clip's gain, the noisy
/// level of every (8-bit level, sample).
#[derive(Clone, Debug)]
pub struct NoiseModel {
    tile: Vec<[i8; TILE]>,
    shot: f32,
    read: f32,
    /// The noisy level of every (level, tile sample): `noisy[level × 256 + sample as u8]`.
    noisy: Box<[u8; 256 * 256]>,
}

impl NoiseModel {
    /// The noise of a sensor with shot noise `shot` (standard deviation at a linear signal of 1) and read
    /// noise `read`, at a gain of 1 ([`NoiseModel::set_gain`] changes it); `seed` draws the tile.
    pub fn new(shot: f32, read: f32, seed: u64) -> NoiseModel {
        let mut rng = ChaCha8Rng::seed_from_u64(splitmix64(seed ^ 0x6e01_5e00));
        let tile = (0..TILE)
            .map(|_| {
                std::array::from_fn(|_| {
                    let n: f32 = StandardNormal.sample(&mut rng);
                    (n * TILE_SCALE).round().clamp(-127.0, 127.0) as i8
                })
            })
            .collect();
        let mut model = NoiseModel {
            tile,
            shot,
            read,
            noisy: Box::new([0; 256 * 256]),
        };
        model.set_gain(1.0);
        model
    }

    /// The noise's standard deviation at 8-bit level `level` and gain `gain`, in levels ([`sigma_levels`]).
    pub fn sigma_levels(&self, level: u8, gain: f32) -> f64 {
        sigma_levels(self.shot, self.read, gain, linear_of_levels()[usize::from(level)])
    }

    /// The noise at the exposure's gain `gain`: the table of noisy levels, per level its standard deviation
    /// ([`sigma_levels`]) times the tile's sample, rounded.
    pub fn set_gain(&mut self, gain: f32) {
        let linear = linear_of_levels();
        for (level, row) in self.noisy.chunks_exact_mut(256).enumerate() {
            // Fixed point: 1/256 of a level per unit of a tile sample.
            let sigma = sigma_levels(self.shot, self.read, gain, linear[level]);
            let sigma_fp = (sigma * 256.0 / f64::from(TILE_SCALE)).round() as i32;
            for (sample, out) in row.iter_mut().enumerate() {
                let n = i32::from(sample as u8 as i8);
                *out = (level as i32 + ((sigma_fp * n + 128) >> 8)).clamp(0, 255) as u8;
            }
        }
    }

    /// Adds the noise of frame seed `frame_seed` to an 8-bit sRGB image `width` pixels wide, in bands of rows
    /// on the current rayon pool: each channel reads the tile at its own offset drawn from the frame's seed, so
    /// every pixel's noise is a pure function of (clip, frame, pixel).
    pub fn apply(&self, rgb: &mut [u8], width: usize, frame_seed: u64) {
        if width == 0 {
            return;
        }
        let offsets: [(usize, usize); 3] = std::array::from_fn(|c| {
            let r = splitmix64(frame_seed ^ splitmix64(0x0ff5_e700 + c as u64));
            ((r as usize) % TILE, ((r >> 32) as usize) % TILE)
        });
        const ROWS: usize = 16;
        rgb.par_chunks_mut(width * 3 * ROWS)
            .enumerate()
            .for_each(|(band, rows)| {
                for (r, row) in rows.chunks_exact_mut(width * 3).enumerate() {
                    let y = band * ROWS + r;
                    let tile_rows: [&[i8; TILE]; 3] = std::array::from_fn(|c| &self.tile[(y + offsets[c].1) % TILE]);
                    let noisy = &*self.noisy;
                    // Indices below the tables' lengths by construction (no bounds checks in the loop).
                    let add = |level: u8, sample: i8| noisy[usize::from(u16::from_le_bytes([sample as u8, level]))];
                    for (x, px) in row.chunks_exact_mut(3).enumerate() {
                        let n: [i8; 3] = std::array::from_fn(|c| tile_rows[c][(x + offsets[c].0) & (TILE - 1)]);
                        px[0] = add(px[0], n[0]);
                        px[1] = add(px[1], n[1]);
                        px[2] = add(px[2], n[2]);
                    }
                }
            });
    }
}

/// The standard deviation, in 8-bit levels, of the noise of a sensor with shot noise `shot` and read noise
/// `read` at gain `gain`, on a pixel that shows the linear light `linear` (after the gain): the signal's noise
/// carried through the gain and the tone curve. The gain is the exposure's; a colour balance's gain per channel
/// is not counted (a channel whose balance `b` differs from 1 gets noise off by roughly a factor `√b`).
fn sigma_levels(shot: f32, read: f32, gain: f32, linear: f64) -> f64 {
    let (shot, read, gain) = (f64::from(shot), f64::from(read), f64::from(gain));
    // The signal x before the gain: x × gain = linear.
    let x = linear / gain;
    let sigma = (shot * shot * x + read * read).sqrt();
    0.5 * (tone_level(gain * (x + sigma)) - tone_level(gain * (x - sigma).max(0.0)))
}

/// Vignetting: per canvas column and row, the share of light lost, `vignetting × d² / r_corner²` for the
/// pixel centre's offset `d` from the centre along that axis (the shares add up: `r² = dx² + dy²`).
#[derive(Clone, Debug, Default)]
pub struct Vignette {
    pub(super) cols: Vec<f32>,
    pub(super) rows: Vec<f32>,
}

impl Vignette {
    /// The vignetting of a `width × height` canvas whose image (the camera's) is `image_w × image_h` pixels,
    /// centred on it; `None` without vignetting.
    pub fn new(vignetting: f32, width: u32, height: u32, image_w: u32, image_h: u32) -> Option<Vignette> {
        if vignetting <= 0.0 {
            return None;
        }
        let corner2 = 0.25 * (f64::from(image_w).powi(2) + f64::from(image_h).powi(2));
        let along = |n: u32| -> Vec<f32> {
            (0..n)
                .map(|i| {
                    let d = f64::from(i) + 0.5 - 0.5 * f64::from(n);
                    (f64::from(vignetting) * d * d / corner2) as f32
                })
                .collect()
        };
        Some(Vignette {
            cols: along(width),
            rows: along(height),
        })
    }

    /// Dims row `y`'s linear colours (one slice per channel, at least as long as the row).
    pub(super) fn dim_row(&self, y: usize, rgb: &mut [Vec<f32>; 3]) {
        let keep = 1.0 - self.rows[y];
        let w = self.cols.len();
        for channel in rgb.iter_mut() {
            for (v, lost) in channel[..w].iter_mut().zip(&self.cols) {
                *v *= (keep - lost).max(0.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inverse_tone_curve_maps_back_to_its_level() {
        let linear = linear_of_levels();
        for (v, &x) in linear.iter().enumerate().take(255) {
            // Within f32's precision (the tone curve is evaluated as the lookup table is): a thousandth of a level.
            assert!(
                (tone_level(x) - v as f64).abs() < 1.0e-3,
                "level {v}: {}",
                tone_level(x)
            );
        }
        // Levels rise with the light.
        assert!(linear.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn brightness_is_the_geometric_mean_of_the_middle_pixels() {
        // 100 pixels: 10 black, 80 at level 100, 10 white: the middle 80 are all level 100.
        let mut rgb = Vec::new();
        for v in std::iter::repeat_n(0u8, 10)
            .chain(std::iter::repeat_n(100, 80))
            .chain(std::iter::repeat_n(255, 10))
        {
            rgb.extend([v, v, v]);
        }
        let b = brightness(&rgb);
        assert!((b - linear_of_levels()[100]).abs() < 1.0e-12, "{b}");
        // Half at 50, half at 150: the geometric mean of the two.
        let mut rgb = Vec::new();
        for v in std::iter::repeat_n(50u8, 50).chain(std::iter::repeat_n(150, 50)) {
            rgb.extend([v, v, v]);
        }
        let l = linear_of_levels();
        let want = (l[50] * l[150]).sqrt();
        assert!((brightness(&rgb) - want).abs() < 1.0e-12 * want.max(1.0));
        assert_eq!(brightness(&[]), 0.0);
    }

    #[test]
    fn auto_gain_brightens_dark_clips_only_and_within_its_bounds() {
        assert_eq!(auto_gain(0.2, 0.1, 16.0), 1.0);
        assert!((auto_gain(0.02, 0.1, 16.0) - 5.0).abs() < 1.0e-6);
        assert_eq!(auto_gain(0.001, 0.1, 16.0), 16.0);
        assert_eq!(auto_gain(0.0, 0.1, 16.0), 16.0);
    }

    #[test]
    fn noise_has_the_modelled_spread_and_no_bias() {
        // A flat grey image: the noise's standard deviation per channel is the model's at that level (within
        // the sampling error over 256 × 256 pixels), its mean about zero.
        let (w, h) = (256usize, 256usize);
        let mut model = NoiseModel::new(0.012, 0.0005, 3);
        model.set_gain(4.0);
        for level in [20u8, 100, 200] {
            let mut rgb = vec![level; w * h * 3];
            model.apply(&mut rgb, w, 77);
            let d: Vec<f64> = rgb.iter().map(|&v| f64::from(v) - f64::from(level)).collect();
            let mean = d.iter().sum::<f64>() / d.len() as f64;
            let sd = (d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / d.len() as f64).sqrt();
            let want = model.sigma_levels(level, 4.0);
            assert!(want > 0.5, "level {level}: modelled {want}");
            assert!(
                (sd - want).abs() < 0.1 * want + 0.3,
                "level {level}: sd {sd}, modelled {want}"
            );
            assert!(mean.abs() < 0.1, "level {level}: mean {mean}");
        }
        // Another frame draws other noise; the same frame the same.
        let (mut a, mut b, mut c) = (vec![100u8; w * 12], vec![100u8; w * 12], vec![100u8; w * 12]);
        model.apply(&mut a, w, 1);
        model.apply(&mut b, w, 1);
        model.apply(&mut c, w, 2);
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn more_gain_means_more_noise_at_the_same_level() {
        let model = NoiseModel::new(0.012, 0.0005, 1);
        for v in [30u8, 80, 150] {
            let (l, h) = (model.sigma_levels(v, 1.0), model.sigma_levels(v, 16.0));
            assert!(h > 2.0 * l, "level {v}: {h} vs {l}");
        }
    }

    #[test]
    fn vignetting_loses_its_share_at_the_corners_and_none_at_the_centre() {
        let v = Vignette::new(0.4, 101, 51, 101, 51).expect("on");
        let lost = |x: usize, y: usize| v.cols[x] + v.rows[y];
        assert!(lost(50, 25) < 1.0e-6);
        // The corner pixel's centre is half a pixel in from the corner.
        assert!((lost(0, 0) - 0.4).abs() < 0.01, "{}", lost(0, 0));
        assert!(Vignette::new(0.0, 10, 10, 10, 10).is_none());
    }
}
