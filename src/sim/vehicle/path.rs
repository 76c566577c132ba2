//! Vehicle paths: a route polyline rebuilt from a [`RouteScript`] (the world's `route_through` of its lane
//! list), resampled every [`PATH_SPACING_M`] so that a pose lookup is O(1), with advisory curve speeds and a
//! two-level chord bound that lets [`VehiclePath::project`] skip whole stretches exactly.

use glam::DVec2;

use crate::plan::RouteScript;
use crate::world::{RoadNetwork, segment_projection};

/// Spacing of the resampled path polyline, metres.
pub(crate) const PATH_SPACING_M: f64 = 0.5;
/// Largest lateral acceleration in curves, m/s².
const LATERAL_ACCEL_MPS2: f64 = 2.5;
/// Deceleration used to slow down before a curve, m/s².
const CURVE_DECEL_MPS2: f64 = 2.0;
/// Speed limit used where a lane has none, m/s (30 km/h).
const DEFAULT_SPEED_LIMIT_MPS: f64 = 30.0 / 3.6;

/// One point of a resampled path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PathPoint {
    pub pos: DVec2,
    pub z_m: f64,
    pub speed_limit_mps: f64,
}

/// A route polyline resampled at a fixed arc-length spacing, so that a pose lookup is O(1).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct VehiclePath {
    points: Vec<PathPoint>,
    /// Heading of the segment from point `i` to `i + 1` (last one repeated).
    headings_rad: Vec<f64>,
    /// `DVec2::from_angle(headings_rad[i])`, computed once.
    dirs: Vec<DVec2>,
    /// Advisory speed at each point: what the curvature ahead allows (lateral acceleration at most
    /// [`LATERAL_ACCEL_MPS2`]) when braking at [`CURVE_DECEL_MPS2`] to meet it, m/s.
    advisory_mps: Vec<f64>,
    length_m: f64,
    /// Chord bounds of blocks of [`BLOCK_SEGMENTS`] segments (block `k`: segments `k·B .. (k+1)·B`).
    blocks: Vec<Chord>,
    /// Chord bounds of super-blocks of [`SUPER_BLOCK_BLOCKS`] blocks.
    super_blocks: Vec<Chord>,
}

/// Segments per block of the projection's two-level bound.
const BLOCK_SEGMENTS: usize = 8;
/// Blocks per super-block.
const SUPER_BLOCK_BLOCKS: usize = 8;

/// A chord `a`–`b` with every point of a stretch of the path within `eps_m` of it, so that every point of the
/// stretch is at least `dist(p, chord) − eps_m` from any `p` (distance to a segment is 1-Lipschitz, and convex
/// along each path segment, so its maximum over the stretch is at a sample).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Chord {
    a: DVec2,
    b: DVec2,
    eps_m: f64,
}

impl Chord {
    /// The chord over samples `points[first..=last]`.
    fn over(points: &[PathPoint], first: usize, last: usize) -> Chord {
        let (a, b) = (points[first].pos, points[last].pos);
        let eps2 = points[first..=last]
            .iter()
            .map(|q| segment_projection(a, b, q.pos).1)
            .fold(0.0, f64::max);
        Chord {
            a,
            b,
            eps_m: eps2.sqrt(),
        }
    }

    /// A lower bound on the distance from `p` to every point of the stretch, metres.
    fn lower_bound_m(&self, p: DVec2) -> f64 {
        segment_projection(self.a, self.b, p).1.sqrt() - self.eps_m
    }
}

/// A pose on a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PathPose {
    pub pos: DVec2,
    pub heading_rad: f64,
    /// `DVec2::from_angle(heading_rad)` (the unit heading), bit for bit.
    pub dir: DVec2,
    pub z_m: f64,
    pub speed_limit_mps: f64,
}

impl VehiclePath {
    /// Rebuilds the route polyline of `route` from its lane list, joining lanes exactly as
    /// `RoadNetwork::route_from` does, and resamples it. Lane indices outside the network are skipped.
    pub(crate) fn from_route(route: &RouteScript, net: &RoadNetwork) -> VehiclePath {
        // The world joins lanes into a polyline (the same one the planner measured the route on).
        let lanes = route.lanes_in(net);
        let mut raw: Vec<(DVec2, f64, f64, f64)> = net // pos, z, limit, s
            .route_through(&lanes)
            .map(|r| {
                r.points
                    .iter()
                    .map(|q| {
                        let limit = if q.speed_limit_mps > 0.5 {
                            q.speed_limit_mps
                        } else {
                            DEFAULT_SPEED_LIMIT_MPS
                        };
                        (q.pos, q.z_m, limit, q.s_m)
                    })
                    .collect()
            })
            .unwrap_or_default();
        let mut s = raw.last().map_or(0.0, |x| x.3);
        if raw.is_empty() {
            raw.push((route.start, 0.0, DEFAULT_SPEED_LIMIT_MPS, 0.0));
        }
        if raw.len() == 1 {
            let (p, z, l, _) = raw[0];
            let ahead = p + DVec2::from_angle(route.start_heading_rad);
            raw.push((ahead, z, l, 1.0));
            s = 1.0;
        }
        let n = (s / PATH_SPACING_M).floor() as usize + 1;
        let mut points = Vec::with_capacity(n + 1);
        let mut seg = 0;
        for k in 0..=n {
            let sk = (k as f64 * PATH_SPACING_M).min(s);
            while seg + 2 < raw.len() && raw[seg + 1].3 <= sk {
                seg += 1;
            }
            let (a, b) = (raw[seg], raw[seg + 1]);
            let span = b.3 - a.3;
            let t = if span > 0.0 {
                ((sk - a.3) / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            points.push(PathPoint {
                pos: a.0.lerp(b.0, t),
                z_m: a.1 + (b.1 - a.1) * t,
                speed_limit_mps: a.2,
            });
            if sk >= s {
                break;
            }
        }
        let headings_rad = segment_headings_rad(&points, route.start_heading_rad);
        // Curvature from the heading change over ±2 m, then a backward pass so that every curve is announced.
        let k = (2.0 / PATH_SPACING_M) as usize;
        let n = points.len();
        let mut advisory_mps: Vec<f64> = (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(k), (i + k).min(n - 1));
                let span = (b - a) as f64 * PATH_SPACING_M;
                let mut dh = (headings_rad[b.min(n - 1)] - headings_rad[a]).abs() % std::f64::consts::TAU;
                if dh > std::f64::consts::PI {
                    dh = std::f64::consts::TAU - dh;
                }
                let curvature = if span > 0.0 { dh / span } else { 0.0 };
                if curvature > 1e-4 {
                    (LATERAL_ACCEL_MPS2 / curvature).sqrt()
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        for i in (0..n.saturating_sub(1)).rev() {
            let next = advisory_mps[i + 1];
            advisory_mps[i] = advisory_mps[i].min((next * next + 2.0 * CURVE_DECEL_MPS2 * PATH_SPACING_M).sqrt());
        }
        VehiclePath::assemble(points, headings_rad, advisory_mps, s)
    }

    /// The path over resampled `points` with their segment headings: unit headings and chord bounds added.
    fn assemble(points: Vec<PathPoint>, headings_rad: Vec<f64>, advisory_mps: Vec<f64>, length_m: f64) -> VehiclePath {
        let dirs = headings_rad.iter().map(|&h| DVec2::from_angle(h)).collect();
        let segments = points.len().saturating_sub(1);
        let chords = |per: usize| -> Vec<Chord> {
            (0..segments.div_ceil(per))
                .map(|k| Chord::over(&points, k * per, ((k + 1) * per).min(segments)))
                .collect()
        };
        let blocks = chords(BLOCK_SEGMENTS);
        let super_blocks = chords(BLOCK_SEGMENTS * SUPER_BLOCK_BLOCKS);
        VehiclePath {
            points,
            headings_rad,
            dirs,
            advisory_mps,
            length_m,
            blocks,
            super_blocks,
        }
    }

    /// Advisory (curve) speed at arc length `s_m`, m/s.
    pub(crate) fn advisory_mps(&self, s_m: f64) -> f64 {
        let i = ((s_m.max(0.0) / PATH_SPACING_M) as usize).min(self.advisory_mps.len().saturating_sub(1));
        self.advisory_mps[i]
    }

    /// Length of the path, metres.
    pub(crate) fn length_m(&self) -> f64 {
        self.length_m
    }

    /// Pose at arc length `s_m` (clamped to the path).
    pub(crate) fn pose_at(&self, s_m: f64) -> PathPose {
        let s = s_m.clamp(0.0, self.length_m);
        let i = ((s / PATH_SPACING_M) as usize).min(self.points.len().saturating_sub(2));
        let a = &self.points[i];
        let b = &self.points[(i + 1).min(self.points.len() - 1)];
        let s0 = i as f64 * PATH_SPACING_M;
        let span = (self.length_m.min(s0 + PATH_SPACING_M) - s0).max(1e-9);
        let t = ((s - s0) / span).clamp(0.0, 1.0);
        PathPose {
            pos: a.pos.lerp(b.pos, t),
            heading_rad: self.headings_rad[i],
            dir: self.dirs[i],
            z_m: a.z_m + (b.z_m - a.z_m) * t,
            speed_limit_mps: a.speed_limit_mps,
        }
    }

    /// Projects `p` onto the path between arc lengths `from_s_m` and `to_s_m`: `(s_m, lateral_m, heading_rad)`
    /// of the nearest point (lateral distance unsigned), or `None` when no point of that stretch lies within
    /// `max_lateral_m` of `p` (callers pass the largest lateral distance whose answer they would act on).
    ///
    /// The result is exactly that of scanning every segment of the stretch and keeping the first nearest one,
    /// but most segments are skipped with exact lower bounds on their distance from `p`: whole super-blocks and
    /// blocks by their [`Chord`], and single segments because samples are at most [`PATH_SPACING_M`] apart
    /// along the path, so every point of segment `k ≥ i` is within `(k − i + 1)·PATH_SPACING_M` of sample
    /// `a_i`, hence at least `|p − a_i| − (k − i + 1)·PATH_SPACING_M` from `p`. Anything whose bound exceeds
    /// both the best distance so far and `max_lateral_m` can neither win nor matter.
    pub(crate) fn project(&self, p: DVec2, from_s_m: f64, to_s_m: f64, max_lateral_m: f64) -> Option<(f64, f64, f64)> {
        let last = self.points.len().saturating_sub(1);
        if last == 0 {
            return None;
        }
        let i0 = ((from_s_m.max(0.0) / PATH_SPACING_M) as usize).min(last - 1);
        let i1 = ((to_s_m.max(0.0) / PATH_SPACING_M).ceil() as usize).min(last);
        let end = i1.max(i0 + 1);
        // A little slack so that rounding never skips a segment that could tie.
        const SLACK_M: f64 = 1e-6;
        // (squared distance, segment, s, heading) of the best segment; ties go to the lower segment index.
        let mut best = (f64::INFINITY, usize::MAX, from_s_m, 0.0);
        // Anything farther than `bound` is skipped; `far2` is the squared |p − a_i| beyond which the next
        // segment can be skipped too.
        let mut bound = max_lateral_m + SLACK_M;
        let mut far2 = (bound + 2.0 * PATH_SPACING_M).powi(2);
        // The next segment not yet proven too far.
        let mut i = i0;
        const SUPER: usize = BLOCK_SEGMENTS * SUPER_BLOCK_BLOCKS;
        for sb in i0 / SUPER..end.div_ceil(SUPER) {
            if self.super_blocks[sb].lower_bound_m(p) > bound {
                continue;
            }
            let sb_end = ((sb + 1) * SUPER).min(end);
            for b in (sb * SUPER).max(i0) / BLOCK_SEGMENTS..sb_end.div_ceil(BLOCK_SEGMENTS) {
                if self.blocks[b].lower_bound_m(p) > bound {
                    continue;
                }
                let b_end = ((b + 1) * BLOCK_SEGMENTS).min(end);
                i = i.max(b * BLOCK_SEGMENTS);
                while i < b_end {
                    let a = self.points[i].pos;
                    let (t, d2, len2) = segment_projection(a, self.points[i + 1].pos, p);
                    if d2 < best.0 {
                        best = (d2, i, i as f64 * PATH_SPACING_M + t * len2.sqrt(), self.headings_rad[i]);
                        bound = best.0.sqrt().min(max_lateral_m) + SLACK_M;
                        far2 = (bound + 2.0 * PATH_SPACING_M).powi(2);
                    }
                    // Segments k ≥ i with (k − i + 1)·spacing < |p − a_i| − bound are farther than `bound`.
                    let da2 = (p - a).length_squared();
                    i += if da2 > far2 {
                        ((da2.sqrt() - bound) / PATH_SPACING_M) as usize - 1
                    } else {
                        1
                    };
                }
            }
        }
        let lateral = best.0.sqrt();
        (lateral <= max_lateral_m).then_some((best.2, lateral, best.3))
    }
}

/// The heading of each segment `points[i] → points[i + 1]`, the last one repeated for the last point
/// (`fallback_rad` when there is no segment).
fn segment_headings_rad(points: &[PathPoint], fallback_rad: f64) -> Vec<f64> {
    let mut headings_rad: Vec<f64> = points
        .windows(2)
        .map(|w| {
            let d = w[1].pos - w[0].pos;
            d.y.atan2(d.x)
        })
        .collect();
    headings_rad.push(headings_rad.last().copied().unwrap_or(fallback_rad));
    headings_rad
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    impl VehiclePath {
        /// A copy turned by `angle_rad` about `pivot`, then shifted by `shift`.
        pub(crate) fn moved(&self, pivot: DVec2, angle_rad: f64, shift: DVec2) -> VehiclePath {
            let rot = DVec2::from_angle(angle_rad);
            let points: Vec<PathPoint> = self
                .points
                .iter()
                .map(|q| PathPoint {
                    pos: pivot + rot.rotate(q.pos - pivot) + shift,
                    ..*q
                })
                .collect();
            let headings_rad = self.headings_rad.iter().map(|h| h + angle_rad).collect();
            VehiclePath::assemble(points, headings_rad, self.advisory_mps.clone(), self.length_m)
        }
    }

    /// A path of straight runs and arcs, sampled every `PATH_SPACING_M` of arc length like `from_route`.
    pub(crate) fn winding_path() -> VehiclePath {
        let mut points = Vec::new();
        let (mut pos, mut heading) = (DVec2::new(3.0, -7.0), 0.3_f64);
        for k in 0..400 {
            points.push(PathPoint {
                pos,
                z_m: 0.0,
                speed_limit_mps: 10.0,
            });
            // Straight, left turn of radius 8 m, straight, tight right turn of radius 4 m, straight.
            let curvature = match k {
                60..=110 => 1.0 / 8.0,
                180..=230 => -1.0 / 4.0,
                _ => 0.0,
            };
            let next = heading + curvature * PATH_SPACING_M;
            // The chord of the arc between two samples.
            let chord = if curvature == 0.0 {
                PATH_SPACING_M
            } else {
                2.0 / curvature.abs() * (curvature.abs() * PATH_SPACING_M / 2.0).sin()
            };
            pos += DVec2::from_angle(0.5 * (heading + next)) * chord;
            heading = next;
        }
        let headings_rad = segment_headings_rad(&points, 0.0);
        let (length_m, advisory_mps) = (
            (points.len() - 1) as f64 * PATH_SPACING_M,
            vec![f64::INFINITY; points.len()],
        );
        VehiclePath::assemble(points, headings_rad, advisory_mps, length_m)
    }

    /// The plain scan over every segment of the window that `project` must reproduce exactly.
    fn project_by_scan(path: &VehiclePath, p: DVec2, from_s_m: f64, to_s_m: f64) -> (f64, f64, f64) {
        let last = path.points.len() - 1;
        let i0 = ((from_s_m.max(0.0) / PATH_SPACING_M) as usize).min(last - 1);
        let i1 = ((to_s_m.max(0.0) / PATH_SPACING_M).ceil() as usize).min(last);
        let mut best = (f64::INFINITY, from_s_m, 0.0);
        for i in i0..i1.max(i0 + 1) {
            let (t, d2, len2) = segment_projection(path.points[i].pos, path.points[i + 1].pos, p);
            if d2 < best.0 {
                best = (d2, i as f64 * PATH_SPACING_M + t * len2.sqrt(), path.headings_rad[i]);
            }
        }
        (best.1, best.0.sqrt(), best.2)
    }

    #[test]
    fn projection_skipping_segments_matches_the_full_scan() {
        let path = winding_path();
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let mut uniform = |lo: f64, hi: f64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
        };
        let (mut near, mut far) = (0, 0);
        for _ in 0..20_000 {
            let s = uniform(0.0, path.length_m());
            let pose = path.pose_at(s);
            // Points near the path (on it, beside it, on the inside of bends) and far from it.
            let offset = DVec2::new(uniform(-3.0, 3.0), uniform(-3.0, 3.0)) * uniform(0.0, 1.0).powi(2) * 12.0;
            let p = pose.pos + offset;
            let from = uniform(-5.0, path.length_m());
            let to = from + uniform(0.0, 90.0);
            let expected = project_by_scan(&path, p, from, to);
            assert_eq!(
                path.project(p, from, to, f64::INFINITY),
                Some(expected),
                "p {p} window {from}..{to}"
            );
            let reach = uniform(0.5, 6.0);
            let got = path.project(p, from, to, reach);
            if expected.1 <= reach {
                assert_eq!(got, Some(expected), "p {p} window {from}..{to} reach {reach}");
                near += 1;
            } else {
                assert_eq!(got, None, "p {p} window {from}..{to} reach {reach}");
                far += 1;
            }
        }
        assert!(
            near > 1000 && far > 1000,
            "both cases exercised: {near} near, {far} far"
        );
    }
}
