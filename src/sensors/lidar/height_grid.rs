//! A 2D uniform grid over the low, ground-hugging static triangles (roads, sidewalks, curbs, terrain,
//! markings) with the height interval of each cell: a ray walks the cells under it (Amanatides–Woo) only
//! while its height can meet the ground, and tests the few triangles of those cells. Near the sensor a
//! downward ray is metres above every cell, so the walk starts where the ray comes down to the ground's
//! height band; heights per cell keep hills (OpenDRIVE elevation) as cheap as flat towns.

use glam::{Vec2, Vec3};

use super::PreTri;

/// Cell edge, metres (a lane is 3–3.5 m wide, a sidewalk 2–4 m).
const CELL_M: f32 = 2.0;
/// At most this many cells (larger maps get larger cells).
const MAX_CELLS: f32 = 4.0e6;
/// Triangles wider than this (the terrain plane under the whole scene) stay out of the cells and are tested
/// by every ray: they would fill the grid and stretch it over kilometres.
const WIDE_M: f32 = 400.0;
/// Slack on heights and cell edges, metres (the triangle test itself is exact).
const SLACK_M: f32 = 1e-3;

/// The grid: cells in rows of `nx`, a CSR list of triangle indices per cell and its height interval.
#[derive(Debug, Default)]
pub(super) struct HeightGrid {
    min_xy: Vec2,
    cell_m: f32,
    nx: i32,
    ny: i32,
    /// Height interval of each cell's triangles within the cell (empty: `(∞, −∞)`).
    z: Vec<(f32, f32)>,
    start: Vec<u32>,
    items: Vec<u32>,
    /// Height interval of all the triangles in cells.
    z_all: (f32, f32),
    /// Triangles too wide for cells ([`WIDE_M`]).
    wide: Vec<u32>,
}

/// Whether a triangle's projection meets the rectangle `lo..hi` (separating axes: the rectangle's two and
/// the triangle's three edge normals).
fn overlaps(p: [Vec2; 3], lo: Vec2, hi: Vec2) -> bool {
    let (tmin, tmax) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
    if tmax.x < lo.x || tmax.y < lo.y || tmin.x > hi.x || tmin.y > hi.y {
        return false;
    }
    let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    for k in 0..3 {
        let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let n = (b - a).perp();
        let side = n.dot(c - a);
        if side == 0.0 {
            continue; // degenerate projection (a vertical triangle): its box decides
        }
        if corners.iter().all(|&q| n.dot(q - a) * side < 0.0) {
            return false;
        }
    }
    true
}

/// The height interval of a triangle above the rectangle `lo..hi` (where they overlap): its plane over the
/// rectangle's corners for a sloped or flat triangle, its own height interval for a steep one.
fn height_over(t: &PreTri, lo: Vec2, hi: Vec2) -> (f32, f32) {
    let (a, b, c) = (t.v0, t.v0 + t.e1, t.v0 + t.e2);
    let own = (a.z.min(b.z).min(c.z), a.z.max(b.z).max(c.z));
    if t.normal.z.abs() < 0.2 {
        return own;
    }
    let (tlo, thi) = (
        a.truncate().min(b.truncate()).min(c.truncate()),
        a.truncate().max(b.truncate()).max(c.truncate()),
    );
    let (lo, hi) = (lo.max(tlo), hi.min(thi));
    let z_at = |q: Vec2| a.z - (t.normal.x * (q.x - a.x) + t.normal.y * (q.y - a.y)) / t.normal.z;
    let zs = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)].map(z_at);
    let (zmin, zmax) = zs
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &z| (l.min(z), h.max(z)));
    (zmin.max(own.0), zmax.min(own.1))
}

impl HeightGrid {
    /// A grid over `tris` (indices in the grid are indices into `tris`).
    pub(super) fn new(tris: &[PreTri]) -> HeightGrid {
        let corners = |t: &PreTri| [t.v0, t.v0 + t.e1, t.v0 + t.e2];
        let is_wide = |t: &PreTri| {
            let p = corners(t).map(|v| v.truncate());
            (p[0].max(p[1]).max(p[2]) - p[0].min(p[1]).min(p[2])).max_element() > WIDE_M
        };
        let wide: Vec<u32> = (0..tris.len() as u32).filter(|&i| is_wide(&tris[i as usize])).collect();
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for t in tris.iter().filter(|t| !is_wide(t)) {
            for v in corners(t) {
                (lo, hi) = (lo.min(v), hi.max(v));
            }
        }
        if lo.x > hi.x {
            return HeightGrid {
                wide,
                ..HeightGrid::default()
            };
        }
        let size = (hi - lo).truncate().max(Vec2::splat(CELL_M));
        let cell_m = CELL_M.max((size.x * size.y / MAX_CELLS).sqrt());
        let (nx, ny) = ((size.x / cell_m).ceil() as i32 + 1, (size.y / cell_m).ceil() as i32 + 1);
        let min_xy = lo.truncate() - Vec2::splat(cell_m * 0.5);
        let mut grid = HeightGrid {
            min_xy,
            cell_m,
            nx,
            ny,
            z: vec![(f32::INFINITY, f32::NEG_INFINITY); (nx * ny) as usize],
            start: vec![0; (nx * ny) as usize + 1],
            items: Vec::new(),
            z_all: (f32::INFINITY, f32::NEG_INFINITY),
            wide,
        };
        // Two passes (count, fill) over every (triangle, cell) overlap.
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        // Wide triangles too, where they meet the grid: the walk then finds them like the others.
        for (i, t) in tris.iter().enumerate() {
            let p = corners(t).map(|v| v.truncate());
            let (tlo, thi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            let (c0, c1) = (grid.cell_of(tlo - SLACK_M), grid.cell_of(thi + SLACK_M));
            for cy in c0.1..=c1.1 {
                for cx in c0.0..=c1.0 {
                    let clo = min_xy + Vec2::new(cx as f32, cy as f32) * cell_m - SLACK_M;
                    let chi = clo + Vec2::splat(cell_m + 2.0 * SLACK_M);
                    if overlaps(p, clo, chi) {
                        let c = (cy * nx + cx) as usize;
                        let (zl, zh) = height_over(t, clo, chi);
                        grid.z[c] = (grid.z[c].0.min(zl), grid.z[c].1.max(zh));
                        pairs.push((c as u32, i as u32));
                    }
                }
            }
        }
        grid.z_all = grid
            .z
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), z| (l.min(z.0), h.max(z.1)));
        for &(c, _) in &pairs {
            grid.start[c as usize + 1] += 1;
        }
        for c in 0..grid.z.len() {
            grid.start[c + 1] += grid.start[c];
        }
        let mut cursor = grid.start.clone();
        grid.items = vec![0; pairs.len()];
        for &(c, i) in &pairs {
            grid.items[cursor[c as usize] as usize] = i;
            cursor[c as usize] += 1;
        }
        grid
    }

    /// The cell holding a point, clamped into the grid.
    fn cell_of(&self, p: Vec2) -> (i32, i32) {
        let c = ((p - self.min_xy) / self.cell_m).floor();
        ((c.x as i32).clamp(0, self.nx - 1), (c.y as i32).clamp(0, self.ny - 1))
    }

    /// The nearest of `tris` (the grid's triangles) along the unit ray `o + t·d` closer than `max_t`: its
    /// index and distance.
    pub(super) fn cast(&self, tris: &[PreTri], o: Vec3, d: Vec3, max_t: f32) -> Option<(usize, f32)> {
        let mut best = self.walk(tris, o, d, max_t);
        // A wide triangle closer than the walk's hit would have been met in the walk, unless the ray starts
        // outside the grid (the grid is convex): the wide ones are tested after a miss only.
        let rect_hi = self.min_xy + Vec2::new(self.nx as f32, self.ny as f32) * self.cell_m;
        let inside = o.x >= self.min_xy.x && o.y >= self.min_xy.y && o.x <= rect_hi.x && o.y <= rect_hi.y;
        if best.is_none() || !inside {
            let mut limit = best.map_or(max_t, |b| b.1);
            for &i in &self.wide {
                if let Some(t) = tris[i as usize].hit(o, d, limit) {
                    limit = t;
                    best = Some((i as usize, t));
                }
            }
        }
        best
    }

    /// The nearest triangle in the cells along the ray.
    fn walk(&self, tris: &[PreTri], o: Vec3, d: Vec3, max_t: f32) -> Option<(usize, f32)> {
        let mut best: Option<(usize, f32)> = None;
        let mut limit = max_t;
        if self.items.is_empty() {
            return best;
        }
        // The part of the ray inside the grid's box: the slab test on x, y and the height band.
        let lo = self.min_xy.extend(self.z_all.0 - SLACK_M);
        let hi = (self.min_xy + Vec2::new(self.nx as f32, self.ny as f32) * self.cell_m).extend(self.z_all.1 + SLACK_M);
        let inv = d.recip();
        let (t1, t2) = ((lo - o) * inv, (hi - o) * inv);
        let (near, far) = (t1.min(t2), t1.max(t2));
        // A zero direction component gives ±∞ (or NaN when the origin is on a face); `max`/`min` drop NaNs.
        let mut t_in = near.x.max(near.y).max(near.z).max(0.0);
        let t_end = far.x.min(far.y).min(far.z).min(limit);
        if t_in.is_nan() || t_end.is_nan() || t_in > t_end {
            return best;
        }
        let p = o + d * t_in;
        let (mut cx, mut cy) = self.cell_of(p.truncate());
        let step = (if d.x >= 0.0 { 1 } else { -1 }, if d.y >= 0.0 { 1 } else { -1 });
        let edge = |c: i32, s: i32, min: f32| min + (c + i32::from(s > 0)) as f32 * self.cell_m;
        let mut next_x = if d.x != 0.0 {
            (edge(cx, step.0, self.min_xy.x) - o.x) * inv.x
        } else {
            f32::INFINITY
        };
        let mut next_y = if d.y != 0.0 {
            (edge(cy, step.1, self.min_xy.y) - o.y) * inv.y
        } else {
            f32::INFINITY
        };
        let (dx, dy) = (self.cell_m * inv.x.abs(), self.cell_m * inv.y.abs());
        loop {
            let t_out = next_x.min(next_y).min(t_end);
            let c = (cy * self.nx + cx) as usize;
            let (zl, zh) = self.z[c];
            let (za, zb) = (o.z + d.z * t_in, o.z + d.z * t_out);
            if za.max(zb) >= zl - SLACK_M && za.min(zb) <= zh + SLACK_M {
                for &i in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                    if let Some(t) = tris[i as usize].hit(o, d, limit) {
                        limit = t;
                        best = Some((i as usize, t));
                    }
                }
            }
            if limit <= t_out || t_out >= t_end {
                return best;
            }
            if next_x < next_y {
                cx += step.0;
                t_in = next_x;
                next_x += dx;
            } else {
                cy += step.1;
                t_in = next_y;
                next_y += dy;
            }
            if cx < 0 || cy < 0 || cx >= self.nx || cy >= self.ny {
                return best;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::scene::Tri;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> PreTri {
        PreTri::of(&Tri {
            v: [a.into(), b.into(), c.into()],
            prim: 0,
            closed: false,
        })
    }

    /// Brute force: the nearest triangle.
    fn nearest(tris: &[PreTri], o: Vec3, d: Vec3, max_t: f32) -> Option<f32> {
        let mut limit = max_t;
        let mut best = None;
        for t in tris {
            if let Some(h) = t.hit(o, d, limit) {
                limit = h;
                best = Some(h);
            }
        }
        best
    }

    #[test]
    fn the_walk_finds_the_nearest_triangle_as_brute_force_does() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut tris = Vec::new();
        // Sloped ground patches, curbs (vertical strips), a large terrain triangle and slivers.
        for _ in 0..400 {
            let c = Vec3::new(rng.random_range(-60.0..60.0), rng.random_range(-60.0..60.0), 0.0);
            let z = |p: Vec3| 0.05 * p.x + 0.02 * p.y + rng_free_bump(p);
            let (a, b) = (
                c + Vec3::new(rng.random_range(0.1..6.0), 0.0, 0.0),
                c + Vec3::new(0.0, rng.random_range(0.1..6.0), 0.0),
            );
            tris.push(tri([c.x, c.y, z(c)], [a.x, a.y, z(a)], [b.x, b.y, z(b)]));
            if rng.random::<f32>() < 0.3 {
                let h = 0.15;
                tris.push(tri([c.x, c.y, z(c)], [a.x, a.y, z(a)], [a.x, a.y, z(a) + h]));
            }
        }
        tris.push(tri([-80.0, -80.0, -4.0], [80.0, -80.0, 4.0], [-80.0, 80.0, -1.0]));
        // A terrain plane far wider than the rest.
        tris.push(tri(
            [-900.0, -900.0, -0.5],
            [900.0, -900.0, -0.5],
            [-900.0, 900.0, -0.5],
        ));
        // A wide raised deck beside the grid: rays from above it towards the grid meet it first.
        tris.push(tri([100.0, -300.0, 3.0], [600.0, -300.0, 3.0], [100.0, 300.0, 3.0]));
        let grid = HeightGrid::new(&tris);
        assert_eq!(grid.wide.len(), 2);
        assert!(grid.nx < 100 && grid.ny < 100, "{} x {} cells", grid.nx, grid.ny);
        let mut checked = 0;
        for _ in 0..40_000 {
            let o = Vec3::new(
                rng.random_range(-130.0..130.0),
                rng.random_range(-130.0..130.0),
                rng.random_range(-2.0..8.0),
            );
            let d = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.6..0.3),
            );
            let d = match d.try_normalize() {
                Some(d) => d,
                None => continue,
            };
            // Axis-aligned rays too.
            let d = if rng.random::<f32>() < 0.1 {
                Vec3::new(d.x, 0.0, d.z).normalize_or(Vec3::X)
            } else {
                d
            };
            let expected = nearest(&tris, o, d, 100.0);
            let got = grid.cast(&tris, o, d, 100.0).map(|(_, t)| t);
            assert_eq!(got, expected, "ray from {o} along {d}");
            checked += usize::from(expected.is_some());
        }
        assert!(checked > 5_000, "{checked} rays hit something");
        // Rays from beside the grid that meet the deck first and would meet the ramp in the grid after it.
        for o in [Vec3::new(125.0, -40.0, 3.5), Vec3::new(115.0, -50.0, 3.3)] {
            let target = Vec3::new(0.0, o.y, -4.0 + 80.0 * 8.0 / 160.0 + (o.y + 80.0) * 3.0 / 160.0);
            let d = (target - o).normalize();
            let expected = nearest(&tris, o, d, 200.0).expect("the deck");
            let behind = grid.walk(&tris, o, d, 200.0).expect("the grid").1;
            assert!(expected < behind, "{expected} < {behind}");
            assert_eq!(grid.cast(&tris, o, d, 200.0).map(|(_, t)| t), Some(expected));
        }
    }

    fn rng_free_bump(p: Vec3) -> f32 {
        0.1 * (p.x * 0.3).sin() * (p.y * 0.2).cos()
    }
}
