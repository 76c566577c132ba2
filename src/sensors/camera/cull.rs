//! Light culling per tile: for each tile of a band (its rows, [`TILE_COLS`] columns), the street lamps and
//! headlights that can light some point the tile shows, so that night shading tests only those instead of
//! all of them at every pixel (the lamp loop was a quarter of a night frame).
//!
//! A tile's points lie in the frustum slab between its least and greatest depth (the keys its pixels and
//! edge samples are shaded with, the sky left out); a light is left out when that slab, padded, lies beyond
//! its reach ([`LAMP_REACH_M2`], [`HEAD_REACH_M2`]) or, for a headlight, wholly behind it, above its beam's
//! cut-off or beside its spread. Shading skips such a light anyway (no lane of any point is lit by it), so the
//! pixels are the same bits with culling as without, the lights' order kept.

use glam::Vec3;

use super::View;
use super::band::{BandVisibility, EDGE};
use super::shade::{ActiveLights, HEAD_AHEAD_M, HEAD_CUTOFF_SLOPE, HEAD_REACH_M2, HEAD_SPREAD, LAMP_REACH_M2};

/// Columns of a tile.
pub(super) const TILE_COLS: usize = 64;

/// Lights per list that the masks can hold; with more, nothing is culled.
const MAX_LIGHTS: usize = 32;

/// Tiles per band that culling handles (images up to 8,192 pixels wide); in a wider one nothing is culled.
const MAX_TILES: usize = 128;

/// Padding of a tile's slab, metres, plus this share of its far depth: far more than the rounding of a
/// shaded point's position, so that culling never leaves out a light shading would use.
const PAD_M: f32 = 0.05;
const PAD_PER_M: f32 = 2.0e-3;

/// Margin of a headlight's half-space tests, metres.
const HEAD_MARGIN_M: f32 = 0.01;

/// The lights of a band's tiles, kept from band to band (no allocation once grown).
#[derive(Debug, Default)]
pub(super) struct TileLights {
    /// Whether the band's lights were culled ([`TileLights::cull`]); when not, every list is the frame's.
    active: bool,
    /// Per tile, the least and greatest depth key shaded (the sky's excluded; `(∞, −∞)` for none).
    keys: Vec<(f32, f32)>,
    /// Per tile, the lamps and headlights kept, as bits over [`ActiveLights`]' lists.
    masks: Vec<(u32, u32)>,
    /// The lists of each slot (the tiles, then each pair of neighbouring tiles, then the whole band) and
    /// where each slot's starts (one more entry than slots).
    lamps: Vec<Vec3>,
    lamp_at: Vec<usize>,
    heads: Vec<(Vec3, Vec3)>,
    head_at: Vec<usize>,
}

impl TileLights {
    /// Culls `lights` for the band whose visibility `vis` holds `h` rows from `y0` of a `w`-pixel-wide
    /// image seen through `view`. Lights are culled only at night (with none, there is nothing to cull).
    pub(super) fn cull(&mut self, lights: &ActiveLights, vis: &BandVisibility, view: &View, y0: usize, h: usize) {
        let w = vis.grid.width;
        self.active = !(lights.lamps.is_empty() && lights.heads.is_empty())
            && lights.lamps.len() <= MAX_LIGHTS
            && lights.heads.len() <= MAX_LIGHTS
            && w.div_ceil(TILE_COLS) <= MAX_TILES;
        if !self.active {
            return;
        }
        let tiles = w.div_ceil(TILE_COLS);
        self.bound_keys(vis, w, h, tiles);
        self.masks.clear();
        for (t, &(k_min, k_max)) in self.keys.iter().enumerate() {
            let x0 = (t * TILE_COLS) as f32;
            let x1 = ((t + 1) * TILE_COLS).min(w) as f32;
            let slab = slab_box(view, [x0, x1], [y0 as f32, (y0 + h) as f32], k_min, k_max);
            let masks = match slab {
                None => (0, 0),
                Some((lo, hi)) => (lamp_mask(lights, lo, hi), head_mask(lights, lo, hi)),
            };
            self.masks.push(masks);
        }
        // The slots' lists: each tile's, each pair of neighbours' (a run of pixels may cross into the next
        // tile), the band's (edge samples are shaded over the band).
        self.lamps.clear();
        self.heads.clear();
        self.lamp_at.clear();
        self.head_at.clear();
        let union = |a: (u32, u32), b: (u32, u32)| (a.0 | b.0, a.1 | b.1);
        let band = self.masks.iter().fold((0, 0), |a, &b| union(a, b));
        let slots = (0..tiles)
            .map(|t| self.masks[t])
            .chain((0..tiles).map(|t| union(self.masks[t], *self.masks.get(t + 1).unwrap_or(&(0, 0)))))
            .chain([band]);
        for (lamps, heads) in slots {
            self.lamp_at.push(self.lamps.len());
            self.head_at.push(self.heads.len());
            let kept = |mask: u32| (0..MAX_LIGHTS).filter(move |&i| mask & (1 << i) != 0);
            self.lamps.extend(kept(lamps).map(|i| lights.lamps[i]));
            self.heads.extend(kept(heads).map(|i| lights.heads[i]));
        }
        self.lamp_at.push(self.lamps.len());
        self.head_at.push(self.heads.len());
    }

    /// The least and greatest depth key each tile's pixels (at their centres) and edge samples are shaded
    /// with, the sky left out. Keys are positive, so their bits order as they do (a loop the compiler
    /// vectorises).
    fn bound_keys(&mut self, vis: &BandVisibility, w: usize, h: usize, tiles: usize) {
        let mut bits = [(u32::MAX, 0u32); MAX_TILES];
        let bits = &mut bits[..tiles];
        for row in 0..h {
            let (prims, keys) = (&vis.prim[row * w..(row + 1) * w], &vis.key[row * w..(row + 1) * w]);
            for ((range, prims), keys) in bits.iter_mut().zip(prims.chunks(TILE_COLS)).zip(keys.chunks(TILE_COLS)) {
                let (mut lo, mut hi) = *range;
                for (&p, &k) in prims.iter().zip(keys) {
                    // Primitives below `EDGE` are surfaces (not the sky, not an edge pixel).
                    let surface = p < EDGE;
                    lo = lo.min(if surface { k.to_bits() } else { u32::MAX });
                    hi = hi.max(if surface { k.to_bits() } else { 0 });
                }
                *range = (lo, hi);
            }
            for e in vis.edge_rows[row]..vis.edge_rows[row + 1] {
                let x = vis.edge_x[e] as usize;
                if vis.prim[row * w + x] != EDGE {
                    continue;
                }
                let range = &mut bits[x / TILE_COLS];
                for (&p, &k) in vis.edge_prim[e].iter().zip(&vis.edge_key[e]) {
                    if p < EDGE {
                        *range = (range.0.min(k.to_bits()), range.1.max(k.to_bits()));
                    }
                }
            }
        }
        self.keys.clear();
        self.keys.extend(bits.iter().map(|&(lo, hi)| match lo <= hi {
            true => (f32::from_bits(lo), f32::from_bits(hi)),
            false => (f32::INFINITY, f32::NEG_INFINITY),
        }));
    }

    /// The lamps and headlights to test for a run of pixels `x..end` of the band (within two neighbouring
    /// tiles).
    pub(super) fn run<'a>(
        &'a self,
        lights: &'a ActiveLights,
        x: usize,
        end: usize,
    ) -> (&'a [Vec3], &'a [(Vec3, Vec3)]) {
        let (t0, t1) = (x / TILE_COLS, (end - 1) / TILE_COLS);
        let tiles = self.keys.len();
        self.slot(lights, if t1 == t0 { t0 } else { tiles + t0 })
    }

    /// The lamps and headlights to test for samples anywhere in the band.
    pub(super) fn band<'a>(&'a self, lights: &'a ActiveLights) -> (&'a [Vec3], &'a [(Vec3, Vec3)]) {
        self.slot(lights, 2 * self.keys.len())
    }

    fn slot<'a>(&'a self, lights: &'a ActiveLights, s: usize) -> (&'a [Vec3], &'a [(Vec3, Vec3)]) {
        if !self.active {
            return (&lights.lamps, &lights.heads);
        }
        (
            &self.lamps[self.lamp_at[s]..self.lamp_at[s + 1]],
            &self.heads[self.head_at[s]..self.head_at[s + 1]],
        )
    }
}

/// The box (least and greatest corner, padded) around the points seen through pixel columns `u` and rows `v`
/// (pixel coordinates of the image plane) with depth keys from `k_min` to `k_max`; `None` where no key was
/// seen. A key of 0 or less (infinitely far) gives an unbounded box.
fn slab_box(view: &View, u: [f32; 2], v: [f32; 2], k_min: f32, k_max: f32) -> Option<(Vec3, Vec3)> {
    if k_min > k_max {
        return None;
    }
    if !(k_min > 0.0 && k_max > 0.0 && k_max.is_finite()) {
        return Some((Vec3::NEG_INFINITY, Vec3::INFINITY));
    }
    let (z_near, z_far) = (1.0 / k_max, 1.0 / k_min);
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for su in u.map(|u| (u - view.cx) * view.inv_f) {
        for sv in v.map(|v| (v - view.cy) * view.inv_f) {
            let ray = view.fwd + view.right * su + view.down * sv;
            for z in [z_near, z_far] {
                let p = view.cam + ray * z;
                (lo, hi) = (lo.min(p), hi.max(p));
            }
        }
    }
    let pad = Vec3::splat(PAD_M + PAD_PER_M * z_far);
    Some((lo - pad, hi + pad))
}

/// The squared distance from `p` to the box `lo..hi`.
fn distance2_to_box(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    (lo - p).max(p - hi).max(Vec3::ZERO).length_squared()
}

/// The least of `c · (q − origin)` over the points `q` of the box `lo..hi`.
fn least_over_box(c: Vec3, origin: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let corner = Vec3::select(c.cmpgt(Vec3::ZERO), lo, hi);
    c.dot(corner - origin)
}

/// The lamps that can reach the box.
fn lamp_mask(lights: &ActiveLights, lo: Vec3, hi: Vec3) -> u32 {
    let reaches = |&lamp: &Vec3| distance2_to_box(lamp, lo, hi) <= LAMP_REACH_M2;
    bits(lights.lamps.iter().map(reaches))
}

/// The headlights whose beam can reach the box: within reach, some of it ahead of the lamp, below the beam's
/// cut-off and inside its sideways spread.
fn head_mask(lights: &ActiveLights, lo: Vec3, hi: Vec3) -> u32 {
    let lit = |&(pos, axis): &(Vec3, Vec3)| {
        let ahead = Vec3::new(axis.x, axis.y, 0.0);
        // `d · left` with `d` from the lamp to the point: what shading calls `side` before dividing by `ahead`.
        let across = Vec3::new(axis.y, -axis.x, 0.0);
        let outside = |c: Vec3, margin: f32| least_over_box(c, pos, lo, hi) > margin;
        distance2_to_box(pos, lo, hi) <= HEAD_REACH_M2
            && !outside(-ahead, -HEAD_AHEAD_M + HEAD_MARGIN_M)
            && !outside(Vec3::Z - ahead * HEAD_CUTOFF_SLOPE, HEAD_MARGIN_M)
            && !outside(across - ahead * HEAD_SPREAD, HEAD_MARGIN_M)
            && !outside(-across - ahead * HEAD_SPREAD, HEAD_MARGIN_M)
    };
    bits(lights.heads.iter().map(lit))
}

/// A bit per `true`, in order.
fn bits(flags: impl Iterator<Item = bool>) -> u32 {
    flags.enumerate().fold(0, |m, (i, on)| m | (u32::from(on) << i))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The point a pixel position `(u, v)` with depth key `key` shades: `resolve`'s arithmetic, in the same
    /// order (lane arithmetic is this, lane by lane).
    fn shaded_point(view: &View, u: f32, v: f32, key: f32) -> Vec3 {
        let (su, sv) = ((u - view.cx) * view.inv_f, (v - view.cy) * view.inv_f);
        let ray = view.fwd + view.right * su + view.down * sv;
        view.cam + ray * (1.0 / key)
    }

    /// Whether shading lights `p` with the lamp: `shade::surface`'s test.
    fn lamp_lights(lamp: Vec3, p: Vec3) -> bool {
        (lamp - p).length_squared() <= LAMP_REACH_M2
    }

    /// Whether shading lights `p` with the headlight: `shade::surface`'s tests (`on`, then `beam > 0`).
    fn head_lights((pos, axis): (Vec3, Vec3), p: Vec3) -> bool {
        let d = p - pos;
        let d2 = d.length_squared();
        let ahead = d.x * axis.x + d.y * axis.y;
        if !((1e-4..=HEAD_REACH_M2).contains(&d2) && ahead > HEAD_AHEAD_M) {
            return false;
        }
        let per_ahead = 1.0 / ahead;
        let side = ((d.x * axis.y - d.y * axis.x) * per_ahead * (1.0 / HEAD_SPREAD)).abs();
        let cut = ((HEAD_CUTOFF_SLOPE - d.z * per_ahead) * 25.0).clamp(0.0, 1.0);
        (1.0 - side * side).max(0.0) * cut > 0.0
    }

    /// Over random views, bands of surfaces at random depths (sky and edge pixels among them) and lights
    /// around them: every light that lights a shaded point of a pixel is in the lists of that pixel's run and
    /// of the band (culling never leaves out a light shading uses), while most lights are culled somewhere.
    #[test]
    fn culling_keeps_every_light_that_lights_a_shaded_point() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(44);
        let (w, h) = (320usize, 8usize);
        let (mut used, mut kept, mut listed) = (0usize, 0usize, 0usize);
        for case in 0..60 {
            let yaw = rng.random_range(0.0..std::f32::consts::TAU);
            let pitch: f32 = rng.random_range(-0.2..0.2);
            let fwd = Vec3::new(yaw.cos() * pitch.cos(), yaw.sin() * pitch.cos(), -pitch.sin());
            let right = Vec3::new(yaw.sin(), -yaw.cos(), 0.0);
            let view = View {
                cam: Vec3::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0), 1.5),
                right,
                down: fwd.cross(right),
                fwd,
                cx: w as f32 * 0.5,
                cy: 90.0,
                inv_f: 1.0 / 160.0,
            };
            let y0 = rng.random_range(0..22usize) * h;
            // Surfaces at depths from 1 to 100 m (each 40 columns at a depth of their own, give or take a
            // fifth), a little sky and some edge pixels with four samples.
            let mut vis = BandVisibility::new(w, h);
            let depth_m: Vec<f32> = (0..w.div_ceil(40)).map(|_| rng.random_range(1.0..100.0f32)).collect();
            let key_at =
                |rng: &mut rand_chacha::ChaCha8Rng, x: usize| 1.0 / (depth_m[x / 40] * rng.random_range(0.8..1.2f32));
            for i in 0..w * h {
                let r: f32 = rng.random_range(0.0..1.0);
                vis.prim[i] = if r < 0.1 {
                    crate::sensors::camera::raster::EMPTY
                } else {
                    7
                };
                vis.key[i] = if r < 0.1 { 0.0 } else { key_at(&mut rng, i % w) };
            }
            vis.edge_rows.clear();
            for row in 0..h {
                vis.edge_rows.push(vis.edge_x.len());
                for x in (rng.random_range(0..40)..w).step_by(37) {
                    vis.prim[row * w + x] = EDGE;
                    vis.edge_x.push(x as u32);
                    vis.edge_key.push(std::array::from_fn(|_| key_at(&mut rng, x)));
                    vis.edge_prim.push([7, 7, crate::sensors::camera::raster::EMPTY, 7]);
                }
            }
            vis.edge_rows.push(vis.edge_x.len());
            let around = |rng: &mut rand_chacha::ChaCha8Rng| {
                let along = rng.random_range(0.0..100.0f32);
                view.cam
                    + fwd * along
                    + Vec3::new(rng.random_range(-60.0..60.0), rng.random_range(-60.0..60.0), 0.0)
                    + Vec3::Z * rng.random_range(-1.0..7.0)
            };
            let lamps: Vec<Vec3> = (0..16).map(|_| around(&mut rng)).collect();
            let heads: Vec<(Vec3, Vec3)> = (0..8)
                .map(|_| {
                    let a: f32 = rng.random_range(0.0..std::f32::consts::TAU);
                    (around(&mut rng), Vec3::new(a.cos(), a.sin(), 0.0))
                })
                .collect();
            let lights = ActiveLights { lamps, heads };
            let mut tiles = TileLights::default();
            tiles.cull(&lights, &vis, &view, y0, h);
            let (band_lamps, band_heads) = tiles.band(&lights);
            for row in 0..h {
                for x in 0..w {
                    let i = row * w + x;
                    // The pixel's shaded points: its centre, or its edge samples.
                    let mut points = Vec::new();
                    if vis.prim[i] == EDGE {
                        let e = (vis.edge_rows[row]..vis.edge_rows[row + 1])
                            .find(|&e| vis.edge_x[e] as usize == x)
                            .unwrap_or_else(|| unreachable!("an edge pixel is listed"));
                        for (s, (&p, &k)) in vis.edge_prim[e].iter().zip(&vis.edge_key[e]).enumerate() {
                            let (sx, sy) = ((s % 2) as f32 * 0.5 + 0.25, (s / 2) as f32 * 0.5 + 0.25);
                            if p < EDGE {
                                points.push(shaded_point(&view, x as f32 + sx, (y0 + row) as f32 + sy, k));
                            }
                        }
                    } else if vis.prim[i] < EDGE {
                        points.push(shaded_point(&view, x as f32 + 0.5, (y0 + row) as f32 + 0.5, vis.key[i]));
                    }
                    // A run of up to eight pixels from here, and one reaching back to here.
                    let runs = [(x, (x + 8).min(w)), (x.saturating_sub(7), x + 1)];
                    for p in points {
                        for &lamp in lights.lamps.iter().filter(|&&l| lamp_lights(l, p)) {
                            used += 1;
                            assert!(band_lamps.contains(&lamp), "case {case}: band lost lamp {lamp} for {p}");
                            if vis.prim[i] != EDGE {
                                for (a, b) in runs {
                                    assert!(tiles.run(&lights, a, b).0.contains(&lamp), "case {case}: run {a}..{b}");
                                }
                            }
                        }
                        for &head in lights.heads.iter().filter(|&&hd| head_lights(hd, p)) {
                            used += 1;
                            assert!(
                                band_heads.contains(&head),
                                "case {case}: band lost head {head:?} for {p}"
                            );
                            if vis.prim[i] != EDGE {
                                for (a, b) in runs {
                                    assert!(tiles.run(&lights, a, b).1.contains(&head), "case {case}: run {a}..{b}");
                                }
                            }
                        }
                    }
                }
            }
            for t in 0..w.div_ceil(TILE_COLS) {
                let (l, hd) = tiles.run(&lights, t * TILE_COLS, t * TILE_COLS + 1);
                kept += l.len() + hd.len();
                listed += lights.lamps.len() + lights.heads.len();
            }
        }
        // Lights did light points, and culling left out more than a third of the lights in a tile's list.
        assert!(used > 10_000, "{used}");
        assert!(kept * 3 < listed * 2, "{kept} of {listed} kept");
    }
}
