//! Post-processing of a band's colours: tone mapping to sRGB eight pixels at a time (through a lookup table of
//! the sRGB curve), and rain streaks placed once per frame and drawn band by band.

use super::*;
use crate::util::srgb;

/// A rain streak: a slanted, semi-transparent line from `(x0, y0)` down `steps` pixel rows.
#[derive(Clone, Copy, Debug)]
pub(super) struct Streak {
    pub(super) x0: f32,
    pub(super) y0: f32,
    pub(super) steps: usize,
    pub(super) alpha: f32,
}

/// Linear → sRGB lookup: `LUT[sqrt(x / LUT_MAX) × (LUT_LEN − 1)]` with a soft shoulder, the exposure's gain
/// applied to the linear light first.
pub(super) const LUT_LEN: usize = 4096;

pub(super) const LUT_MAX: f32 = 8.0;

pub(super) fn build_lut(gain: f32) -> Box<[u8; LUT_LEN]> {
    Box::new(std::array::from_fn(|i| {
        let s = i as f32 / (LUT_LEN - 1) as f32;
        let x = s * s * LUT_MAX * gain;
        (tone_curve(x) * 255.0 + 0.5).clamp(0.0, 255.0) as u8
    }))
}

/// The tone curve: linear light (after the exposure's gain) to sRGB's encoded value in [0, 1] — a soft
/// shoulder `1 − e^(−1.1 x)`, then sRGB's encoding.
pub(super) fn tone_curve(x: f32) -> f32 {
    srgb::encode(1.0 - (-1.1 * x).exp())
}

/// The tone curve's shoulder undone: the linear light whose shoulder value is `mapped` (< 1).
pub(super) fn shoulder_inverse(mapped: f64) -> f64 {
    -(1.0 - mapped).ln() / 1.1
}

/// Maps a row of linear colours (one slice per channel, at least `LANES − 1` longer than the row, rounded up to
/// whole vectors) to interleaved sRGB bytes through each channel's lookup table: `LUT[sqrt(x / LUT_MAX) ×
/// (LUT_LEN − 1)]`, `LANES` pixels at a time (`wide`: square roots correctly rounded, and truncations, so the same
/// values as one at a time; at eight lanes 5.2 % of a clear-noon frame's perf samples, at four 9.3 %).
pub(super) fn tone_map(rgb: &[Vec<f32>; 3], luts: [&[u8; LUT_LEN]; 3], out: &mut [u8]) {
    #[inline(always)]
    fn index(v: F) -> [i32; LANES] {
        let s = (v.fast_max(F::ZERO) * (1.0 / LUT_MAX)).fast_min(F::ONE).sqrt();
        (s * (LUT_LEN - 1) as f32).fast_trunc_int().to_array()
    }
    let w = out.len() / 3;
    let [r, g, b] = rgb.each_ref().map(|c| &c[..w.div_ceil(LANES) * LANES]);
    // `s ≤ 1`: the mask changes no index and lets the compiler drop the bounds checks.
    let m = LUT_LEN - 1;
    for (((px, r), g), b) in out
        .chunks_mut(3 * LANES)
        .zip(r.chunks_exact(LANES))
        .zip(g.chunks_exact(LANES))
        .zip(b.chunks_exact(LANES))
    {
        let load = |c: &[f32]| index(lanes_from(|i| c[i]));
        let (r, g, b) = (load(r), load(g), load(b));
        let mut bytes = [0u8; 3 * LANES];
        for (i, o) in bytes.chunks_exact_mut(3).enumerate() {
            o[0] = luts[0][r[i] as usize & m];
            o[1] = luts[1][g[i] as usize & m];
            o[2] = luts[2][b[i] as usize & m];
        }
        px.copy_from_slice(&bytes[..px.len()]);
    }
}

impl Renderer {
    /// Rain: thin, slanted, semi-transparent streaks at seeded places (none without rain), listed per band of
    /// rows they reach; [`Renderer::draw_streaks`] draws them.
    pub(super) fn place_streaks(&mut self, seed: u64) {
        self.streaks.clear();
        for bin in &mut self.streak_bins {
            bin.clear();
        }
        if self.light.rain <= 0.0 {
            return;
        }
        let (w, h) = (self.camera.width_px as f32, self.camera.height_px as f32);
        let mut rng = ChaCha8Rng::seed_from_u64(splitmix64(seed ^ 0x7a1f));
        let count = (self.light.rain * 1500.0 * (w * h) / (1280.0 * 720.0)) as usize;
        let last_bin = self.streak_bins.len() - 1;
        for i in 0..count {
            let x0: f32 = rng.random_range(-50.0..w + 50.0);
            let y0: f32 = rng.random_range(-50.0..h);
            let len: f32 = rng.random_range(0.02..0.07) * h;
            let alpha: f32 = rng.random_range(0.12..0.3);
            let streak = Streak {
                x0,
                y0,
                steps: len as usize,
                alpha,
            };
            self.streaks.push(streak);
            // Rows `y0 + k` for `k < steps`, one row of margin each side (the bands' own test is exact).
            let first = (y0 - 1.0).max(0.0) as usize / BAND_ROWS;
            let last = ((y0 + streak.steps as f32 + 1.0).max(0.0) as usize / BAND_ROWS).min(last_bin);
            for bin in &mut self.streak_bins[first.min(last_bin)..=last] {
                bin.push(i as u32);
            }
        }
    }

    /// Draws the rain streaks over the rows `y0..y0 + rgb.len() / (3 w)` (`rgb`: those rows of the image), in
    /// the streaks' order, brighter against dark backgrounds: each pixel sees the same blends in the same order
    /// as a pass over the whole image.
    pub(super) fn draw_streaks(&self, y0: usize, rgb: &mut [u8]) {
        let width = self.camera.width_px as usize;
        let (w, h) = (width as f32, self.camera.height_px as f32);
        let rows = y0..y0 + rgb.len() / (3 * width);
        let slant = 0.08 + 0.35 * self.light.wind;
        let bright = 150.0 + 60.0 * (1.0 - self.light.night);
        for &i in &self.streak_bins[y0 / BAND_ROWS] {
            let s = self.streaks[i as usize];
            // The steps that can land in the band (a row of margin each side; the test below is exact).
            let k0 = (rows.start as f32 - s.y0 - 1.0).max(0.0) as usize;
            let k1 = ((rows.end as f32 - s.y0 + 1.0).max(0.0) as usize).min(s.steps);
            for k in k0..k1 {
                let t = k as f32;
                let (x, y) = (s.x0 + t * slant, s.y0 + t);
                if y < 0.0 || y >= h || x < 0.0 || x >= w - 1.0 {
                    continue;
                }
                let row = y as usize;
                if !rows.contains(&row) {
                    continue;
                }
                let xf = super::round::floor_f32(x);
                let (xi, fx) = (xf as usize, x - xf);
                let base = (row - rows.start) * width;
                for (dx, cov) in [(0usize, 1.0 - fx), (1, fx)] {
                    let o = (base + xi + dx) * 3;
                    let a = s.alpha * cov;
                    for ch in &mut rgb[o..o + 3] {
                        *ch = (f32::from(*ch) * (1.0 - a) + bright * a) as u8;
                    }
                }
            }
        }
    }
}
