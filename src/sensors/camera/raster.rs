//! A depth-buffered triangle rasteriser into a visibility buffer: per sample, the nearest primitive id and its
//! depth key. The camera draws bands of rows at 2 × 2 samples per pixel, sparsely ([`BandVisibility`]: every
//! pixel's first sample, all four only where a pixel may hold an edge), the sun's shadow map every sample
//! with an orthographic projection.
//!
//! Triangles arrive already projected: `x, y` in sample units (the sample `(i, j)` is centred at
//! `(i + 0.5, j + 0.5)`) and a depth key `k` that is affine in screen space and grows towards the viewer
//! (`1 / z` for a perspective camera, minus the distance for an orthographic one). Coverage is inclusive on
//! edges, so triangles that share an edge leave no gap; the depth test then picks one. Setup is in `f64`
//! (large coordinates after near-plane clipping), the per-sample loop in `f32`, allocation-free.

use glam::{DVec3, Vec3, Vec4};
use wide::bytemuck;

use super::lanes::F;
use super::round::{ceil_f64, floor_f64};

/// A visibility buffer.
#[derive(Clone, Debug)]
pub struct Raster {
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// Depth key per sample (0: empty).
    pub key: Vec<f32>,
    /// Primitive per sample ([`EMPTY`]: nothing drawn).
    pub prim: Vec<u32>,
}

/// The primitive id of a sample where nothing was drawn (the sky).
pub const EMPTY: u32 = u32::MAX;

impl Raster {
    /// An empty buffer of `width × height` samples.
    pub fn new(width: usize, height: usize) -> Raster {
        Raster {
            width,
            height,
            key: vec![0.0; width * height],
            prim: vec![EMPTY; width * height],
        }
    }

    /// A buffer of depth keys only (`prim` stays empty: a shadow map needs no primitive ids, and drawing
    /// into it then writes half as much).
    pub fn depth_only(width: usize, height: usize) -> Raster {
        Raster {
            width,
            height,
            key: vec![0.0; width * height],
            prim: Vec::new(),
        }
    }

    /// Empties the buffer (depth keys below every drawable key).
    pub fn clear(&mut self, empty_key: f32) {
        self.key.fill(empty_key);
        self.prim.fill(EMPTY);
    }

    /// Draws a projected triangle: vertices `(x, y, key)`.
    pub fn draw(&mut self, v: [DVec3; 3], prim: u32) {
        if let Some(t) = Setup::new(v, prim, self.width, self.height) {
            self.draw_rows(&t, t.row0 as usize..=t.row1 as usize, 0);
        }
    }

    /// Draws the sample rows `rows` of a set-up triangle into this buffer, which holds the rows from
    /// `origin_row` on (a band of a larger image; rows outside it are skipped).
    pub fn draw_rows(&mut self, t: &Setup, rows: std::ops::RangeInclusive<usize>, origin_row: usize) {
        let first = (*rows.start()).max(t.row0 as usize).max(origin_row);
        let last = (*rows.end()).min(t.row1 as usize).min(origin_row + self.height - 1);
        for row in first..=last {
            let Some(span) = t.span(row) else { continue };
            let base = (row - origin_row) * self.width;
            let keys = &mut self.key[base + span.x0..=base + span.x1];
            match self.prim.get_mut(base + span.x0..=base + span.x1) {
                Some(prims) => depth_test_span(keys, prims, span.k_row, span.kx, span.x0 as f32, 1.0, t.prim),
                None => depth_test_span_keys(keys, span.k_row, span.kx, span.x0 as f32),
            }
        }
    }

    /// Draws a set-up triangle into a grid of every other sample: this buffer's sample `(i, j)` is the
    /// triangle's image sample `(2i, 2j)` (the first of each 2 × 2 block), with the same coverage and the same
    /// key bits as [`Raster::draw_rows`] gives that sample. The buffer holds the grid rows `rows` from
    /// `origin_row` on.
    pub fn draw_grid_rows(&mut self, t: &Setup, rows: std::ops::RangeInclusive<usize>, origin_row: usize) {
        let first = (*rows.start()).max((t.row0 as usize).div_ceil(2)).max(origin_row);
        let last = (*rows.end()).min(t.row1 as usize / 2).min(origin_row + self.height - 1);
        for row in first..=last {
            let Some(span) = t.span(2 * row) else { continue };
            // Even samples of `x0..=x1`.
            let (c0, c1) = (span.x0.div_ceil(2), (span.x1 / 2).min(self.width - 1));
            if c1 < c0 {
                continue;
            }
            let base = (row - origin_row) * self.width;
            let keys = &mut self.key[base + c0..=base + c1];
            let prims = &mut self.prim[base + c0..=base + c1];
            depth_test_span(keys, prims, span.k_row, span.kx, c0 as f32, 2.0, t.prim);
        }
    }
}

/// The samples `x0..=x1` of one sample row that a triangle covers, and their keys: `k_row + kx · x`.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    /// First covered sample.
    pub x0: usize,
    /// Last covered sample.
    pub x1: usize,
    /// The key of sample 0 of the row (the plane extended).
    pub k_row: f32,
    /// The key's step from sample to sample.
    pub kx: f32,
}

impl Span {
    /// The key of sample `x` of the row (the same bits as the depth tests write).
    #[inline(always)]
    pub fn key(&self, x: usize) -> f32 {
        self.k_row + self.kx * x as f32
    }
}

/// A projected triangle set up for drawing in a `width × height`-sample image: its edge functions, the
/// plane of its depth key and its bounds. Setup is in `f64` (large coordinates after near-plane clipping).
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// Per edge, the line `x = a·y + b` (sample units, the half-sample offset and the coverage tolerance
    /// folded in) left of which (`lo`) or right of which (`hi`) a row's samples are outside: an edge bounds
    /// the span on one side only, so its other line is `(0, ∓∞)`. Multiplications per row instead of the
    /// divisions of the edge functions, and no branches.
    lo: [(f64, f64); 3],
    /// See [`Setup::lo`].
    hi: [(f64, f64); 3],
    /// A horizontal edge's function `(ey, e0)` (`ey·y + e0 ≥ −tol` inside; `(0, 0)` where there is none).
    flat: (f64, f64),
    /// The depth key's plane: `k = kx·x + ky·y + k0`.
    kx: f64,
    ky: f64,
    k0: f64,
    /// Horizontal bounds, samples (clamped to the image).
    min_x: f64,
    max_x: f64,
    /// Image width, samples.
    width: f64,
    /// Coverage tolerance: a hair of overlap between neighbours rather than a crack (edge-function units).
    tol: f64,
    /// First and last sample rows covered.
    pub row0: u32,
    /// Last sample row covered.
    pub row1: u32,
    /// Primitive id.
    pub prim: u32,
}

impl Setup {
    /// Sets a triangle up (`None` where it is degenerate or outside the image).
    pub fn new(v: [DVec3; 3], prim: u32, width: usize, height: usize) -> Option<Setup> {
        let [a, b, c] = v;
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if !area.is_finite() || area.abs() < 1e-12 {
            return None;
        }
        // Edge functions oriented so that the interior is positive.
        let sign = area.signum();
        let edge = |p: DVec3, q: DVec3| {
            // E(x, y) = (q.x − p.x)(y − p.y) − (q.y − p.y)(x − p.x), times the orientation.
            let ex = -(q.y - p.y) * sign;
            let ey = (q.x - p.x) * sign;
            let e0 = -(ex * p.x + ey * p.y);
            (ex, ey, e0)
        };
        let edges = [edge(a, b), edge(b, c), edge(c, a)];
        let (w, h) = (width as f64, height as f64);
        let tol = 1e-7 * (1.0 + w.max(h));
        // `ex·x + ey·y + e0 ≥ −tol` ⇔ `x ≥ (−(ey·y + e0) − tol) / ex` where `ex > 0` (≤ where `ex < 0`); sample
        // `i` is centred at `i + 0.5`.
        let (mut lo, mut hi) = ([(0.0, f64::NEG_INFINITY); 3], [(0.0, f64::INFINITY); 3]);
        let mut flat = (0.0, 0.0);
        for (i, &(ex, ey, e0)) in edges.iter().enumerate() {
            let line = (-ey / ex, (-e0 - tol) / ex - 0.5);
            if ex > 0.0 {
                lo[i] = line;
            } else if ex < 0.0 {
                hi[i] = line;
            } else {
                flat = (ey, e0);
            }
        }
        let inv = 1.0 / area;
        let kx = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) * inv;
        let ky = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) * inv;
        let k0 = a.z - kx * a.x - ky * a.y;

        let min_y = a.y.min(b.y).min(c.y).max(0.0);
        let max_y = a.y.max(b.y).max(c.y).min(h);
        let min_x = a.x.min(b.x).min(c.x).max(0.0);
        let max_x = a.x.max(b.x).max(c.x).min(w);
        if min_y >= max_y || min_x >= max_x {
            return None;
        }
        let row0 = (min_y - 0.5).ceil().max(0.0) as usize;
        let row1 = ((max_y - 0.5).floor() as usize).min(height - 1);
        if row1 < row0 {
            return None;
        }
        Some(Setup {
            lo,
            hi,
            flat,
            kx,
            ky,
            k0,
            min_x,
            max_x,
            width: w,
            tol,
            row0: row0 as u32,
            row1: row1 as u32,
            prim,
        })
    }

    /// The pixels (of `SS × SS` = 2 × 2 samples, at most `w`) that the triangle's horizontal bounds reach:
    /// every span's samples belong to pixels `lo..=hi` (`lo > hi`: none).
    #[inline(always)]
    pub(super) fn pixel_reach(&self, w: usize) -> (usize, usize) {
        // Spans start at or after `ceil(min_x − 0.5)` and end at or before `floor(max_x − 0.5)`.
        let lo = ceil_f64(self.min_x - 0.5).max(0.0) as usize / 2;
        let hi = (floor_f64(self.max_x - 0.5).max(0.0) as usize / 2).min(w - 1);
        (lo, hi)
    }

    /// The samples of sample row `row` (centred at `row + 0.5`) that the triangle covers (`None`: none).
    #[inline(always)]
    pub fn span(&self, row: usize) -> Option<Span> {
        let y = row as f64 + 0.5;
        // Spelled out (`array::map` is not always inlined).
        let at = |(a, b): (f64, f64)| a * y + b;
        let lo = (self.min_x - 0.5)
            .max(at(self.lo[0]))
            .max(at(self.lo[1]))
            .max(at(self.lo[2]));
        let hi = (self.max_x - 0.5)
            .min(at(self.hi[0]))
            .min(at(self.hi[1]))
            .min(at(self.hi[2]));
        if lo > hi || self.flat.0 * y + self.flat.1 < -self.tol {
            return None;
        }
        let x0 = ceil_f64(lo).max(0.0) as usize;
        let x1 = (floor_f64(hi).min(self.width - 1.0)) as isize;
        if x1 < x0 as isize {
            return None;
        }
        Some(Span {
            x0,
            x1: x1 as usize,
            k_row: (self.ky * y + self.k0 + self.kx * 0.5) as f32,
            kx: self.kx as f32,
        })
    }
}

/// The keys of the four samples `(x0 + start + i) · step` of a span (see [`depth_test_span`]): sample
/// numbers are exact in `f32`, so the keys have the bits of [`Span::key`].
#[inline(always)]
fn span_keys4(k_row: f32, kx: f32, x0: f32, step: f32, start: usize) -> Vec4 {
    Vec4::splat(k_row)
        + Vec4::splat(kx) * ((Vec4::splat(x0 + start as f32) + Vec4::new(0.0, 1.0, 2.0, 3.0)) * Vec4::splat(step))
}

/// [`span_keys4`] for eight samples (each lane the same bits).
#[inline(always)]
fn span_keys8(k_row: f32, kx: f32, x0: f32, step: f32, start: usize) -> F {
    let offsets = F::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    F::splat(k_row) + F::splat(kx) * ((F::splat(x0 + start as f32) + offsets) * F::splat(step))
}

/// The key of the sample `(x0 + i) · step` of a span, one at a time (the same value as its lane of
/// [`span_keys4`]).
#[inline(always)]
fn span_key(k_row: f32, kx: f32, x0: f32, step: f32, i: usize) -> f32 {
    k_row + kx * ((x0 + i as f32) * step)
}

/// The depth test along a span of samples whose keys are `k_row + kx · (x0 + i) · step`: where the key is
/// greater, it and `prim` replace the buffer's. Eight samples at a time (`wide`, one AVX register in the
/// x86-64 build), then four (glam's `Vec4`), then one by one; primitive ids travel as the bit patterns of
/// `f32` lanes, which moves and bitwise selects keep exactly.
#[inline]
fn depth_test_span(keys: &mut [f32], prims: &mut [u32], k_row: f32, kx: f32, x0: f32, step: f32, prim: u32) {
    let n = keys.len().min(prims.len());
    let (keys, prims) = (&mut keys[..n], &mut prims[..n]);
    let eights = n / 8 * 8;
    let prim_lanes = F::splat(f32::from_bits(prim));
    for (start, (kk, pp)) in keys[..eights]
        .chunks_exact_mut(8)
        .zip(prims[..eights].chunks_exact_mut(8))
        .enumerate()
        .map(|(c, chunk)| (c * 8, chunk))
    {
        let (Ok(kk), Ok(pp)) = (<&mut [f32; 8]>::try_from(kk), <&mut [u32; 8]>::try_from(pp)) else {
            unreachable!("chunks of eight")
        };
        let k = span_keys8(k_row, kx, x0, step, start);
        let old_k = F::new(*kk);
        let nearer = k.simd_gt(old_k);
        // `fast_max` is `vmaxps(k, old)`: `k` where it is greater, else the old key, NaN and signed zeros
        // included, so the same bits as the selection; the primitives merge bitwise under the mask (the same
        // bits as a selection too). Written as selections of the loaded values, both stores became masked
        // stores (`vmaskmovps`), which are microcoded and slow on AMD's cores (a tenth of a clear-noon frame).
        *kk = k.fast_max(old_k).to_array();
        let old_p: F = bytemuck::cast(*pp);
        *pp = bytemuck::cast(old_p ^ ((old_p ^ prim_lanes) & nearer));
    }
    let mut i = eights;
    if i + 4 <= n {
        let k = span_keys4(k_row, kx, x0, step, i);
        let old_k = Vec4::from_slice(&keys[i..i + 4]);
        let nearer = k.cmpgt(old_k);
        Vec4::select(nearer, k, old_k).write_to_slice(&mut keys[i..i + 4]);
        let pp = &mut prims[i..i + 4];
        let old_p = Vec4::new(
            f32::from_bits(pp[0]),
            f32::from_bits(pp[1]),
            f32::from_bits(pp[2]),
            f32::from_bits(pp[3]),
        );
        let new_p = Vec4::select(nearer, Vec4::splat(f32::from_bits(prim)), old_p).to_array();
        for (p, v) in pp.iter_mut().zip(new_p) {
            *p = v.to_bits();
        }
        i += 4;
    }
    for i in i..n {
        let k = span_key(k_row, kx, x0, step, i);
        if k > keys[i] {
            keys[i] = k;
            prims[i] = prim;
        }
    }
}

/// [`depth_test_span`] for a buffer of keys only: the greater key stays.
#[inline]
fn depth_test_span_keys(keys: &mut [f32], k_row: f32, kx: f32, x0: f32) {
    let n = keys.len();
    let eights = n / 8 * 8;
    for (start, kk) in keys[..eights]
        .chunks_exact_mut(8)
        .enumerate()
        .map(|(c, chunk)| (c * 8, chunk))
    {
        let Ok(kk) = <&mut [f32; 8]>::try_from(kk) else {
            unreachable!("chunks of eight")
        };
        let k = span_keys8(k_row, kx, x0, 1.0, start);
        let old_k = F::new(*kk);
        // The selection's bits without a masked store (see `depth_test_span`).
        *kk = k.fast_max(old_k).to_array();
    }
    let mut i = eights;
    if i + 4 <= n {
        let k = span_keys4(k_row, kx, x0, 1.0, i);
        let old_k = Vec4::from_slice(&keys[i..i + 4]);
        Vec4::select(k.cmpgt(old_k), k, old_k).write_to_slice(&mut keys[i..i + 4]);
        i += 4;
    }
    for (i, key) in keys.iter_mut().enumerate().skip(i) {
        let k = span_key(k_row, kx, x0, 1.0, i);
        if k > *key {
            *key = k;
        }
    }
}

/// Clips a triangle (optical frame: z forward) against the plane `z = near`; the result is a convex polygon
/// of 0, 3 or 4 vertices written into `out`, whose count is returned.
pub fn clip_near(v: [Vec3; 3], near: f32, out: &mut [Vec3; 4]) -> usize {
    let mut n = 0;
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        let (pin, qin) = (p.z >= near, q.z >= near);
        if pin {
            out[n] = p;
            n += 1;
        }
        if pin != qin {
            let t = (near - p.z) / (q.z - p.z);
            out[n] = p + (q - p) * t;
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles_of_a_square_cover_it_exactly_once_without_cracks() {
        let mut r = Raster::new(16, 16);
        r.clear(0.0);
        let q = [
            DVec3::new(2.3, 1.7, 1.0),
            DVec3::new(13.1, 2.2, 1.0),
            DVec3::new(12.6, 14.4, 1.0),
            DVec3::new(1.9, 13.3, 1.0),
        ];
        r.draw([q[0], q[1], q[2]], 1);
        r.draw([q[0], q[2], q[3]], 2);
        // Every sample centre strictly inside the quad is covered.
        let inside = |x: f64, y: f64| {
            (0..4).all(|i| {
                let (p, n) = (q[i], q[(i + 1) % 4]);
                (n.x - p.x) * (y - p.y) - (n.y - p.y) * (x - p.x) > 1e-9
            })
        };
        for j in 0..16 {
            for i in 0..16 {
                let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
                let covered = r.prim[j * 16 + i] != EMPTY;
                if inside(x, y) {
                    assert!(covered, "crack at {i},{j}");
                }
                if !covered {
                    assert!(!inside(x, y));
                }
            }
        }
    }

    #[test]
    fn the_nearer_triangle_wins_and_depth_is_interpolated() {
        let mut r = Raster::new(8, 8);
        r.clear(0.0);
        let t = |k: f64| {
            [
                DVec3::new(0.0, 0.0, k),
                DVec3::new(8.0, 0.0, k),
                DVec3::new(0.0, 8.0, k),
            ]
        };
        r.draw(t(0.5), 1);
        r.draw(t(0.25), 2); // farther (smaller key)
        assert_eq!(r.prim[0], 1);
        assert!((r.key[0] - 0.5).abs() < 1e-6);
        // A sloped key: k = x.
        let mut r = Raster::new(8, 1);
        r.clear(-1.0);
        r.draw(
            [
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(8.0, 0.0, 8.0),
                DVec3::new(0.0, 8.0, 0.0),
            ],
            3,
        );
        assert!((r.key[3] - 3.5).abs() < 1e-5, "{}", r.key[3]);
    }

    #[test]
    fn the_simd_depth_test_equals_the_scalar_one() {
        // Spans of every length 0..=29 (eights, a four, single samples) over keys with ties (signed zeros
        // included), NaN keys old and new, NaN-pattern ids (EMPTY) and sloped keys, at every sample and every
        // other one: the vector path's maximum must keep the scalar test's bits.
        for (n, step) in (0..=29usize).flat_map(|n| [(n, 1.0f32), (n, 2.0)]) {
            for (k_row, kx) in [
                (0.5f32, 0.0f32),
                (0.2, 0.05),
                (0.9, -0.07),
                (0.45, 1.0e-3),
                (0.0, 0.0),
                (f32::NAN, 0.0),
            ] {
                let keys: Vec<f32> = (0..n)
                    .map(|i| [0.0, 0.5, 0.3, 0.7, 0.45, -0.0, f32::NAN][i % 7])
                    .collect();
                let prims: Vec<u32> = (0..n).map(|i| if i % 3 == 0 { EMPTY } else { i as u32 * 7 }).collect();
                let (mut k1, mut p1) = (keys.clone(), prims.clone());
                depth_test_span(&mut k1, &mut p1, k_row, kx, 3.0, step, 42);
                let (mut k2, mut p2) = (keys.clone(), prims.clone());
                for i in 0..n {
                    let k = k_row + kx * ((3.0 + i as f32) * step);
                    if k > k2[i] {
                        k2[i] = k;
                        p2[i] = 42;
                    }
                }
                assert_eq!(p1, p2, "n {n} k_row {k_row} kx {kx} step {step}");
                assert_eq!(
                    k1.iter().map(|k| k.to_bits()).collect::<Vec<_>>(),
                    k2.iter().map(|k| k.to_bits()).collect::<Vec<_>>()
                );
                if step != 1.0 {
                    continue;
                }
                let mut k3 = keys.clone();
                depth_test_span_keys(&mut k3, k_row, kx, 3.0);
                assert_eq!(
                    k3.iter().map(|k| k.to_bits()).collect::<Vec<_>>(),
                    k2.iter().map(|k| k.to_bits()).collect::<Vec<_>>()
                );
            }
        }
    }

    #[test]
    fn near_clipping_keeps_the_front_part() {
        let mut out = [Vec3::ZERO; 4];
        let n = clip_near(
            [
                Vec3::new(0.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            0.1,
            &mut out,
        );
        assert_eq!(n, 4);
        assert!(out[..n].iter().all(|v| v.z >= 0.1 - 1e-6));
        assert_eq!(clip_near([Vec3::new(0.0, 0.0, -1.0); 3], 0.1, &mut out), 0);
    }
}
