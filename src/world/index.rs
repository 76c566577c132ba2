//! Spatial index over lane pieces: a uniform grid (4 m cells, [`CellGrid`]) in compressed-row layout. Each
//! cell lists the pieces whose bounding box touches it, so `lane_at` is one cell lookup plus a handful of
//! point-in-quad tests, without allocation. Zero-width pieces are left out.

use glam::DVec2;

use crate::world::grid::CellGrid;
use crate::world::{Lane, LaneHit, LaneType, RoadNetwork, TravelDirection};

const CELL_M: f64 = 4.0;
const MAX_CELLS: f64 = 16_000_000.0;
/// Pieces whose elevations differ by more than this are on different levels (bridges over roads).
pub(crate) const LEVEL_M: f64 = 3.0;

#[derive(Clone, Debug, Default)]
pub(crate) struct LaneIndex {
    /// Pieces by the cells their bounding boxes touch.
    grid: CellGrid,
    /// Per piece: true when the quad is convex (tested with 4 half-planes), else tested by its hull.
    convex: Vec<bool>,
}

fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Point in a convex quad of either orientation, boundary included (so a point on the edge shared by two
/// consecutive pieces is in both). For the rare non-convex quad (sharp curves) this is conservative.
#[inline]
fn in_quad(c: &[DVec2; 4], p: DVec2) -> bool {
    let s = if cross(c[2] - c[0], c[3] - c[1]) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    let mut j = 3;
    for i in 0..4 {
        if cross(c[i] - c[j], p - c[j]) * s < -1e-9 {
            return false;
        }
        j = i;
    }
    true
}

/// Whether a quad is convex (consecutive edges all turn the same way).
fn is_convex(c: &[DVec2; 4]) -> bool {
    let mut pos = false;
    let mut neg = false;
    for i in 0..4 {
        let z = cross(c[(i + 1) % 4] - c[i], c[(i + 2) % 4] - c[(i + 1) % 4]);
        pos |= z > 0.0;
        neg |= z < 0.0;
    }
    !(pos && neg)
}

#[inline]
fn in_tri(a: DVec2, b: DVec2, c: DVec2, p: DVec2) -> bool {
    let d1 = cross(b - a, p - a);
    let d2 = cross(c - b, p - b);
    let d3 = cross(a - c, p - c);
    let has_neg = d1 < -1e-9 || d2 < -1e-9 || d3 < -1e-9;
    let has_pos = d1 > 1e-9 || d2 > 1e-9 || d3 > 1e-9;
    !(has_neg && has_pos)
}

/// Point in the convex hull of a quad (the union of its four corner triangles). Used for the non-convex
/// pieces of sidewalks around tight junction corners, where the outer border folds back on itself and the
/// swept fan is better described by the hull than by the folded quad.
fn in_hull(c: &[DVec2; 4], p: DVec2) -> bool {
    in_tri(c[0], c[1], c[2], p)
        || in_tri(c[0], c[2], c[3], p)
        || in_tri(c[0], c[1], c[3], p)
        || in_tri(c[1], c[2], c[3], p)
}

fn quad_dist(c: &[DVec2; 4], p: DVec2) -> f64 {
    if in_quad(c, p) {
        return 0.0;
    }
    let mut d = f64::INFINITY;
    for i in 0..4 {
        d = d.min(super::segment_projection(c[i], c[(i + 1) % 4], p).1.sqrt());
    }
    d
}

/// Projection of `p` on a piece's centre segment: (fraction along, signed lateral offset, centre direction).
#[inline]
fn project(c: &[DVec2; 4], p: DVec2) -> (f64, f64, DVec2) {
    let m0 = (c[0] + c[3]) * 0.5;
    let m1 = (c[1] + c[2]) * 0.5;
    let d = m1 - m0;
    let l2 = d.length_squared();
    if l2 <= 1e-18 {
        return (0.0, 0.0, DVec2::X);
    }
    let t = ((p - m0).dot(d) / l2).clamp(0.0, 1.0);
    let len = l2.sqrt();
    (t, cross(d, p - m0) / len, d / len)
}

/// Builds a [`LaneHit`] for `p` on piece `pi`.
pub(crate) fn hit_on_piece(net: &RoadNetwork, pi: u32, p: DVec2) -> LaneHit {
    let piece = &net.pieces[pi as usize];
    let lane: &Lane = &net.lanes[piece.lane as usize];
    let (t, lat, dir) = project(&piece.corners, p);
    let lerp = |a: f32, b: f32| a as f64 + (b as f64 - a as f64) * t;
    let mut heading = dir.y.atan2(dir.x);
    if lane.travel == TravelDirection::Backward {
        heading = super::opendrive::geometry::wrap_angle(heading + std::f64::consts::PI);
    }
    LaneHit {
        lane_type: lane.lane_type,
        road: lane.road,
        lane: piece.lane,
        lane_id: lane.lane_id,
        piece: pi,
        s_m: piece.s_m[0] + (piece.s_m[1] - piece.s_m[0]) * t,
        lateral_offset_m: lat,
        lane_width_m: lerp(piece.width_m[0], piece.width_m[1]),
        road_width_m: lerp(piece.road_width_m[0], piece.road_width_m[1]),
        heading_rad: heading,
        travel: lane.travel,
        speed_limit_mps: lane.speed_limit_mps,
        distance_m: quad_dist(&piece.corners, p),
        z_m: piece.z_m as f64,
    }
}

impl LaneIndex {
    pub(crate) fn build(net: &RoadNetwork) -> LaneIndex {
        let (lo, hi) = net.bounds;
        let live = |p: &crate::world::LanePiece| p.width_m[0].max(p.width_m[1]) > 0.01;
        let grid = CellGrid::build(lo, hi, CELL_M, MAX_CELLS, net.pieces.len(), |k| {
            let piece = &net.pieces[k];
            live(piece).then(|| super::bounding_box(piece.corners)).flatten()
        });
        let convex = net.pieces.iter().map(|p| is_convex(&p.corners)).collect();
        LaneIndex { grid, convex }
    }

    /// The best piece containing `p`; with `z`, only pieces within [`LEVEL_M`] of it count. Without `z`, where
    /// pieces at different levels overlap (bridges), the lower one wins.
    pub(crate) fn lane_at(&self, net: &RoadNetwork, p: DVec2, z: Option<f64>) -> Option<LaneHit> {
        if self.grid.is_empty() {
            return None;
        }
        let (x, y) = self.grid.cell_containing(p)?;
        let mut best = u32::MAX;
        let mut best_score = f64::INFINITY;
        let mut best_z = 0.0f32;
        for &pi in self.grid.items_in(x, y) {
            let piece = &net.pieces[pi as usize];
            if let Some(z) = z
                && (piece.z_m as f64 - z).abs() > LEVEL_M
            {
                continue;
            }
            let inside = if self.convex[pi as usize] {
                in_quad(&piece.corners, p)
            } else {
                in_hull(&piece.corners, p)
            };
            if !inside {
                continue;
            }
            let (t, lat, _) = project(&piece.corners, p);
            let w = piece.width_m[0] as f64 + (piece.width_m[1] as f64 - piece.width_m[0] as f64) * t;
            let mut score = lat.abs() / (0.5 * w).max(1e-3);
            // Lanes of no particular type (OpenDRIVE `none`, ...) lose against any typed lane they overlap.
            if net.lanes[piece.lane as usize].lane_type == LaneType::Other {
                score += 1e3;
            }
            let better = if best == u32::MAX {
                true
            } else if ((piece.z_m - best_z) as f64).abs() > LEVEL_M {
                piece.z_m < best_z
            } else {
                score < best_score
            };
            if better {
                best_score = score;
                best = pi;
                best_z = piece.z_m;
            }
        }
        (best != u32::MAX).then(|| hit_on_piece(net, best, p))
    }

    /// Nearest piece whose lane passes `filter`, within `max_d` (ring search over cells).
    pub(crate) fn nearest(
        &self,
        net: &RoadNetwork,
        p: DVec2,
        max_d: f64,
        filter: impl Fn(&Lane) -> bool,
    ) -> Option<LaneHit> {
        if self.grid.is_empty() || !p.is_finite() {
            return None;
        }
        let (cx, cy) = self.grid.cell_coords(p);
        let (nx, ny) = self.grid.size();
        let cell_m = self.grid.cell_m();
        let rings = (max_d / cell_m).ceil() as i64 + 1;
        let mut best = u32::MAX;
        let mut best_d = max_d;
        for r in 0..=rings {
            for y in cy - r..=cy + r {
                if y < 0 || y >= ny as i64 {
                    continue;
                }
                let on_edge_row = y == cy - r || y == cy + r;
                let mut x = cx - r;
                while x <= cx + r {
                    if x >= 0 && x < nx as i64 {
                        for &pi in self.grid.items_in(x as usize, y as usize) {
                            let piece = &net.pieces[pi as usize];
                            if !filter(&net.lanes[piece.lane as usize]) {
                                continue;
                            }
                            let d = quad_dist(&piece.corners, p);
                            let better = if best == u32::MAX {
                                d <= best_d
                            } else if d == 0.0 && best_d == 0.0 {
                                let (_, l1, _) = project(&piece.corners, p);
                                let (_, l0, _) = project(&net.pieces[best as usize].corners, p);
                                l1.abs() < l0.abs()
                            } else {
                                d < best_d
                            };
                            if better {
                                best_d = d;
                                best = pi;
                            }
                        }
                    }
                    x += if on_edge_row || r == 0 { 1 } else { 2 * r };
                }
            }
            if best != u32::MAX && best_d <= r as f64 * cell_m {
                break;
            }
        }
        (best != u32::MAX).then(|| hit_on_piece(net, best, p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_containment_and_distance() {
        let c = [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(in_quad(&c, DVec2::new(1.0, 0.5)));
        assert!(!in_quad(&c, DVec2::new(3.0, 0.5)));
        assert!((quad_dist(&c, DVec2::new(3.0, 0.5)) - 1.0).abs() < 1e-12);
        let (t, lat, _) = project(&c, DVec2::new(1.0, 0.75));
        assert!((t - 0.5).abs() < 1e-12 && (lat - 0.25).abs() < 1e-12, "{t} {lat}");
    }
}
