//! The DVS event camera: CARLA's `sensor.camera.dvs`, i.e. the ESIM algorithm, run on the rendered RGB
//! images (reference §1, step by step):
//!
//! - intensity `I = 0.2989 R + 0.587 G + 0.114 B` of the 8-bit image; `L = ln(log_eps + I / 255)` with
//!   `use_log`, else `L = I`;
//! - the first image sets the reference and previous values and emits nothing;
//! - for each later image and each pixel whose value changed by more than 1e-6, contrast thresholds
//!   (`Cp` for a rise, `Cm` for a fall, plus `N(0, sigma)` per pixel per image when sigma > 0, at least
//!   0.01) are crossed from the reference value; each crossing strictly beyond the previous value and up
//!   to the current one gets a timestamp linearly interpolated between the two images' times; it is emitted
//!   when it is not earlier than the pixel's last event and the refractory period has passed (or the pixel
//!   has none), and the reference moves to the crossing whenever it is not earlier;
//! - the events of an image are sorted by time (stably, so pixels in raster order break ties).
//!
//! Sub-frame rendering (`dvs.substeps`) feeds images rendered between frames, so fast motion crosses
//! thresholds at the right times instead of all at once. Noise comes from a ChaCha stream per (clip, image).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use wide::f32x4;

use crate::spec::types::Dvs;

/// One event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event {
    /// Column.
    pub x: u16,
    /// Row.
    pub y: u16,
    /// Time, nanoseconds of simulated time.
    pub t_ns: i64,
    /// True for a brightness increase.
    pub positive: bool,
}

/// The ESIM state of one camera.
#[derive(Clone, Debug)]
pub struct Esim {
    params: Dvs,
    width: usize,
    reference: Vec<f32>,
    previous: Vec<f32>,
    current: Vec<f32>,
    last_ns: Vec<i64>,
    time_ns: i64,
    started: bool,
}

/// The ESIM log-intensity (or intensity) of one 8-bit RGB pixel ([`log_intensity4`]'s value).
pub fn log_intensity(params: &Dvs, rgb: [u8; 3]) -> f32 {
    let [r, g, b] = rgb.map(|c| f32x4::splat(f32::from(c)));
    log_intensity4(params, r, g, b).to_array()[0]
}

/// The ESIM log-intensity (or intensity) of four 8-bit RGB pixels given by channel: the luminance as
/// [`super::luminance`] computes it, its logarithm by `wide`'s polynomial (plain IEEE operations, so the same
/// bits on every machine, unlike libm's `logf`, which picks its code by CPU).
#[inline(always)]
pub fn log_intensity4(params: &Dvs, r: f32x4, g: f32x4, b: f32x4) -> f32x4 {
    let i = f32x4::splat(0.2989) * r + f32x4::splat(0.587) * g + f32x4::splat(0.114) * b;
    if params.use_log {
        (f32x4::splat(params.log_eps as f32) + i / 255.0).ln()
    } else {
        i
    }
}

impl Esim {
    /// A camera of `width × height` pixels.
    pub fn new(params: &Dvs, width: usize, height: usize) -> Esim {
        let n = width * height;
        Esim {
            params: params.clone(),
            width,
            reference: vec![0.0; n],
            previous: vec![0.0; n],
            current: vec![0.0; n],
            last_ns: vec![0; n],
            time_ns: 0,
            started: false,
        }
    }

    /// Feeds the image taken at `now_ns` (RGB, 3 bytes per pixel) and appends its events to `events`, sorted by
    /// time; `noise_seed` seeds the threshold noise of this image.
    pub fn step(&mut self, rgb: &[u8], now_ns: i64, noise_seed: u64, events: &mut Vec<Event>) {
        // Per pixel, so rows in parallel on the rayon pool give the same values.
        let (params, w) = (&self.params, self.width.max(1));
        self.current
            .par_chunks_mut(w * 16)
            .zip(rgb.par_chunks(w * 16 * 3))
            .for_each(|(ls, pxs)| {
                // Four pixels at a time, the rest one by one.
                let whole = ls.len() / 4 * 4;
                for (l, px) in ls[..whole].chunks_exact_mut(4).zip(pxs.chunks_exact(12)) {
                    let c = |o: usize| f32x4::new([px[o], px[o + 3], px[o + 6], px[o + 9]].map(f32::from));
                    l.copy_from_slice(&log_intensity4(params, c(0), c(1), c(2)).to_array());
                }
                for (l, px) in ls[whole..].iter_mut().zip(pxs[whole * 3..].chunks_exact(3)) {
                    *l = log_intensity(params, [px[0], px[1], px[2]]);
                }
            });
        self.step_values(now_ns, noise_seed, events);
    }

    /// [`Esim::step`] on values already in `L` form (tests feed ramps directly).
    pub fn step_log(&mut self, values: &[f32], now_ns: i64, noise_seed: u64, events: &mut Vec<Event>) {
        self.current.copy_from_slice(values);
        self.step_values(now_ns, noise_seed, events);
    }

    fn step_values(&mut self, now_ns: i64, noise_seed: u64, events: &mut Vec<Event>) {
        if !self.started {
            self.reference.copy_from_slice(&self.current);
            self.previous.copy_from_slice(&self.current);
            self.last_ns.fill(0);
            self.time_ns = now_ns;
            self.started = true;
            return;
        }
        let first = events.len();
        let dt = (now_ns - self.time_ns) as f64;
        let p = &self.params;
        let mut rng = ChaCha8Rng::seed_from_u64(noise_seed);
        let noise_pos = Normal::new(0.0, p.sigma_positive_threshold.max(0.0)).ok();
        let noise_neg = Normal::new(0.0, p.sigma_negative_threshold.max(0.0)).ok();
        for i in 0..self.current.len() {
            let it = self.previous[i];
            let itdt = self.current[i];
            if (it - itdt).abs() <= 1e-6 {
                continue;
            }
            let pol: f32 = if itdt >= it { 1.0 } else { -1.0 };
            let (base, sigma, noise) = if pol > 0.0 {
                (p.positive_threshold, p.sigma_positive_threshold, &noise_pos)
            } else {
                (p.negative_threshold, p.sigma_negative_threshold, &noise_neg)
            };
            let mut c = base;
            if sigma > 0.0
                && let Some(n) = noise
            {
                c = (c + n.sample(&mut rng)).max(0.01);
            }
            let c = c as f32;
            let mut cross = self.reference[i];
            loop {
                cross += pol * c;
                let beyond = if pol > 0.0 {
                    cross > it && cross <= itdt
                } else {
                    cross < it && cross >= itdt
                };
                if !beyond {
                    break;
                }
                let t = self.time_ns + (f64::from(cross - it) * dt / f64::from(itdt - it)) as i64;
                let last = self.last_ns[i];
                if t >= last {
                    if last == 0 || t - last >= p.refractory_period_ns as i64 {
                        events.push(Event {
                            x: (i % self.width) as u16,
                            y: (i / self.width) as u16,
                            t_ns: t,
                            positive: pol > 0.0,
                        });
                        self.last_ns[i] = t;
                    }
                    self.reference[i] = cross;
                }
            }
        }
        events[first..].sort_by_key(|e| e.t_ns);
        self.time_ns = now_ns;
        std::mem::swap(&mut self.previous, &mut self.current);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Dvs {
        Dvs::default()
    }

    #[test]
    fn an_image_gives_every_pixel_its_own_log_intensity() {
        // Runs of equal pixels broken by changes, rows not a multiple of four wide, across the rows that are
        // split between workers: every value equals the pixel's own, and the logarithm is within 2·10⁻⁷ of
        // the exact one.
        let (w, h) = (37, 41);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let v = ((i / 3) % 7 * 31) as u8;
                [v, v.wrapping_add((i % 5 == 0) as u8), 200 - v / 2]
            })
            .collect();
        let mut esim = Esim::new(&params(), w, h);
        esim.step(&rgb, 0, 1, &mut Vec::new());
        for (i, px) in rgb.chunks_exact(3).enumerate() {
            assert_eq!(
                esim.current[i],
                log_intensity(&params(), [px[0], px[1], px[2]]),
                "pixel {i}"
            );
        }
        // Every luminance an image can have, at the thresholds' scale: within a few ulps of the exact logarithm.
        let p = params();
        for v in 0..=255u8 {
            for rgb in [[v, v, v], [v, 0, 0], [0, v, 0], [0, 0, v], [v, 255 - v, v / 2]] {
                let arg = p.log_eps as f32 + super::super::luminance(&rgb) / 255.0;
                let exact = f64::from(arg).ln();
                let got = f64::from(log_intensity(&p, rgb));
                assert!(
                    (got - exact).abs() <= 4.0e-7 * exact.abs().max(1.0),
                    "{rgb:?}: {got} against {exact}"
                );
            }
        }
    }

    #[test]
    fn a_ramp_crosses_thresholds_at_interpolated_times() {
        // One pixel rising from L = 0 to 1.0 over 1 ms: crossings at 0.3, 0.6 and 0.9, i.e. at 300, 600 and
        // 900 µs (by hand: t = (cross − it) · dt / (itdt − it)).
        let mut esim = Esim::new(&params(), 1, 1);
        let mut ev = Vec::new();
        esim.step_log(&[0.0], 0, 1, &mut ev);
        assert!(ev.is_empty(), "the first image emits nothing");
        esim.step_log(&[1.0], 1_000_000, 1, &mut ev);
        let t: Vec<i64> = ev.iter().map(|e| e.t_ns).collect();
        assert_eq!(ev.len(), 3);
        for (got, want) in t.iter().zip([300_000, 600_000, 900_000]) {
            assert!((got - want).abs() <= 1, "{t:?}");
        }
        assert!(ev.iter().all(|e| e.positive));
        // Falling back to 0.5 over the next ms: reference 0.9 → crossing at 0.6 only (0.3 is below 0.5).
        ev.clear();
        esim.step_log(&[0.5], 2_000_000, 1, &mut ev);
        assert_eq!(ev.len(), 1);
        assert!(!ev[0].positive);
        assert!(
            (ev[0].t_ns - 1_800_000).abs() <= 1,
            "(0.6 − 1.0)·1ms/(0.5 − 1.0) = 0.8 ms: {}",
            ev[0].t_ns
        );
    }

    #[test]
    fn a_static_scene_gives_no_events() {
        let mut esim = Esim::new(&params(), 4, 2);
        let img = vec![90u8; 4 * 2 * 3];
        let mut ev = Vec::new();
        for k in 0..5 {
            esim.step(&img, k * 33_333_333, k as u64, &mut ev);
        }
        assert!(ev.is_empty());
    }

    #[test]
    fn the_refractory_period_drops_close_events_but_moves_the_reference() {
        let p = Dvs {
            refractory_period_ns: 500_000,
            ..params()
        };
        let mut esim = Esim::new(&p, 1, 1);
        let mut ev = Vec::new();
        esim.step_log(&[0.0], 0, 1, &mut ev);
        esim.step_log(&[1.0], 1_000_000, 1, &mut ev);
        // 300 µs is emitted (no earlier event), 600 µs is too close, 900 µs is 600 µs after the last emitted.
        let t: Vec<i64> = ev.iter().map(|e| e.t_ns).collect();
        assert_eq!(t.len(), 2, "{t:?}");
        assert!((t[1] - 900_000).abs() <= 1);
    }

    #[test]
    fn threshold_noise_is_seeded() {
        let p = Dvs {
            sigma_positive_threshold: 0.1,
            sigma_negative_threshold: 0.1,
            ..params()
        };
        let run = |seed: u64| {
            let mut esim = Esim::new(&p, 64, 1);
            let mut ev = Vec::new();
            esim.step_log(&[0.0; 64], 0, seed, &mut ev);
            let ramp: Vec<f32> = (0..64).map(|i| 1.0 + i as f32 * 0.01).collect();
            esim.step_log(&ramp, 1_000_000, seed, &mut ev);
            ev
        };
        assert_eq!(run(5), run(5), "same seed, same events");
        assert_ne!(run(5), run(6), "another seed, other thresholds");
    }
}
