//! Vehicles: the route polyline rebuilt from a [`RouteScript`], lane following along it (through junctions),
//! Intelligent Driver Model car following with vehicles **and** pedestrians in the path ahead as leaders, and
//! the ego's braking rule for crossing pedestrians.
//!
//! A vehicle is a point moving along its own path polyline (arc length `s_m`); its footprint is a
//! [`VEHICLE_LENGTH_M`] × [`VEHICLE_WIDTH_M`] box centred on that point and aligned with the path. Leaders are
//! found geometrically: anything whose footprint (a vehicle) or disc (a pedestrian) intrudes on the corridor of
//! half-width `VEHICLE_WIDTH_M / 2 + margin` around the path ahead, within the look-ahead distance. This also
//! covers vehicles on crossing paths inside junctions, since there are no traffic lights in the world model
//! (`ignores_lights` has nothing to act on).

use glam::DVec2;

use super::{PED_RADIUS_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::dsl::types::Idm;
use crate::planner::{EgoScript, RouteScript, VehicleScript};
use crate::world::grid::CellGrid;
use crate::world::{RoadNetwork, bounding_box, segment_projection};

/// Spacing of the resampled path polyline, metres.
const PATH_SPACING_M: f64 = 0.5;
/// Lateral margin of the vehicle corridor beyond half the vehicle width, metres.
const VEHICLE_CORRIDOR_MARGIN_M: f64 = 0.4;
/// Lateral margin of the corridor for pedestrians, metres.
const PED_CORRIDOR_MARGIN_M: f64 = 0.6;
/// Largest lateral acceleration in curves, m/s².
const LATERAL_ACCEL_MPS2: f64 = 2.5;
/// Deceleration used to slow down before a curve, m/s².
const CURVE_DECEL_MPS2: f64 = 2.0;
/// Speed limit used where a lane has none, m/s (30 km/h).
const DEFAULT_SPEED_LIMIT_MPS: f64 = 30.0 / 3.6;
/// The ego's IDM time headway (the ego script has none), seconds.
pub const EGO_TIME_HEADWAY_S: f64 = 1.5;

/// Half the vehicle length, metres.
pub(crate) const HALF_LENGTH_M: f64 = VEHICLE_LENGTH_M * 0.5;
/// Half the vehicle width, metres.
pub(crate) const HALF_WIDTH_M: f64 = VEHICLE_WIDTH_M * 0.5;

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
    pub fn from_route(route: &RouteScript, net: &RoadNetwork) -> VehiclePath {
        // The world joins lanes into a polyline (the same one the planner measured the route on).
        let lanes: Vec<u32> = route
            .lanes
            .iter()
            .copied()
            .filter(|&l| (l as usize) < net.lanes.len())
            .collect();
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
    pub fn advisory_mps(&self, s_m: f64) -> f64 {
        let i = ((s_m.max(0.0) / PATH_SPACING_M) as usize).min(self.advisory_mps.len().saturating_sub(1));
        self.advisory_mps[i]
    }

    /// Length of the path, metres.
    pub fn length_m(&self) -> f64 {
        self.length_m
    }

    /// Pose at arc length `s_m` (clamped to the path).
    pub fn pose_at(&self, s_m: f64) -> PathPose {
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
    pub fn project(&self, p: DVec2, from_s_m: f64, to_s_m: f64, max_lateral_m: f64) -> Option<(f64, f64, f64)> {
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

/// A simulated vehicle (the ego or traffic).
#[derive(Clone, Debug)]
pub(crate) struct Vehicle {
    /// Vehicle id in events ([`crate::exec::trace::EGO_ID`] for the ego).
    pub id: u32,
    pub path: VehiclePath,
    pub s_m: f64,
    pub speed_mps: f64,
    pub accel_mps2: f64,
    /// Target speed as a fraction of the limit: `1 − pct/100`.
    pub speed_factor: f64,
    pub min_gap_m: f64,
    pub time_headway_s: f64,
    pub ignores_walkers: bool,
    /// The ego's braking rule: (ahead, lateral) metres.
    pub ego_brake_m: Option<(f64, f64)>,
    /// Cached pose at `s_m`.
    pub pose: PathPose,
}

impl Vehicle {
    /// The ego vehicle, at its route start, at its target speed.
    pub fn ego(script: &EgoScript, net: &RoadNetwork) -> Vehicle {
        let path = VehiclePath::from_route(&script.route, net);
        Self::new(
            crate::exec::trace::EGO_ID,
            path,
            script.route.start_s_m,
            1.0 - script.speed_below_limit_pct / 100.0,
            script.min_gap_m,
            EGO_TIME_HEADWAY_S,
            false,
            Some((script.brake_ahead_m, script.brake_lateral_m)),
        )
    }

    /// A traffic vehicle, at its route start, at its target speed.
    pub fn traffic(script: &VehicleScript, net: &RoadNetwork) -> Vehicle {
        let path = VehiclePath::from_route(&script.route, net);
        Self::new(
            script.id,
            path,
            script.route.start_s_m,
            1.0 - script.speed_difference_pct / 100.0,
            script.min_gap_m,
            script.time_headway_s,
            script.ignores_walkers,
            None,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn new(
        id: u32,
        path: VehiclePath,
        start_s_m: f64,
        speed_factor: f64,
        min_gap_m: f64,
        time_headway_s: f64,
        ignores_walkers: bool,
        ego_brake_m: Option<(f64, f64)>,
    ) -> Vehicle {
        let s_m = start_s_m.clamp(0.0, path.length_m());
        let pose = path.pose_at(s_m);
        let speed_factor = speed_factor.max(0.05);
        Vehicle {
            id,
            s_m,
            speed_mps: pose.speed_limit_mps * speed_factor,
            accel_mps2: 0.0,
            speed_factor,
            min_gap_m: min_gap_m.max(0.1),
            time_headway_s: time_headway_s.max(0.1),
            ignores_walkers,
            ego_brake_m,
            pose,
            path,
        }
    }

    /// Velocity vector, m/s.
    pub fn velocity(&self) -> DVec2 {
        self.pose.dir * self.speed_mps
    }

    /// Target (desired) speed at the current position, m/s.
    pub fn target_speed_mps(&self) -> f64 {
        (self.pose.speed_limit_mps * self.speed_factor).min(self.path.advisory_mps(self.s_m))
    }

    /// Advances by `dt_s` with acceleration `accel_mps2` (speed never negative), updating the cached pose.
    pub fn integrate(&mut self, accel_mps2: f64, dt_s: f64) {
        let v0 = self.speed_mps;
        let v1 = (v0 + accel_mps2 * dt_s).max(0.0);
        self.s_m = (self.s_m + 0.5 * (v0 + v1) * dt_s).min(self.path.length_m());
        self.accel_mps2 = (v1 - v0) / dt_s;
        self.speed_mps = if self.s_m >= self.path.length_m() { 0.0 } else { v1 };
        self.pose = self.path.pose_at(self.s_m);
    }

    /// Moves the vehicle back along its path by `ds_m` and stops it (contact resolution).
    pub fn back_off_and_stop(&mut self, ds_m: f64) {
        self.s_m = (self.s_m - ds_m).max(0.0);
        self.speed_mps = 0.0;
        self.pose = self.path.pose_at(self.s_m);
    }
}

/// What the vehicle logic needs to know about a pedestrian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PedView {
    pub pos: DVec2,
    pub velocity: DVec2,
    /// In a crossing-type state or retreating (the ego's braking rule applies).
    pub crossing: bool,
}

/// IDM acceleration towards a leader `gap_m` ahead moving at `lead_speed_mps` (`None`: free road).
pub(crate) fn idm_accel_mps2(
    idm: &Idm,
    speed_mps: f64,
    target_speed_mps: f64,
    min_gap_m: f64,
    time_headway_s: f64,
    leader: Option<(f64, f64)>,
) -> f64 {
    let a = idm.max_accel_mps2.max(0.01);
    let b = idm.comfortable_decel_mps2.max(0.01);
    let v0 = target_speed_mps.max(0.1);
    let free = 1.0 - (speed_mps / v0).powf(idm.exponent);
    let interaction = match leader {
        Some((gap_m, lead_speed_mps)) => {
            let dv = speed_mps - lead_speed_mps;
            let s_star = min_gap_m + (speed_mps * time_headway_s + speed_mps * dv / (2.0 * (a * b).sqrt())).max(0.0);
            let s = gap_m.max(0.05);
            (s_star / s).powi(2)
        }
        None => 0.0,
    };
    (a * (free - interaction)).clamp(-idm.max_decel_mps2, a)
}

/// Look-ahead distance for leaders at speed `v`, metres.
fn lookahead_m(v: f64, idm: &Idm) -> f64 {
    (15.0 + 2.0 * v + v * v / (2.0 * idm.comfortable_decel_mps2.max(0.5))).clamp(25.0, 80.0)
}

/// The longitudinal acceleration of vehicle `i` this step: IDM towards the most constraining leader among the
/// other vehicles, the pedestrians in its path (walkers are ignored by vehicles that ignore them until an
/// emergency stop is needed), the ego's braking rule and the end of its route.
pub(crate) fn accel_for(i: usize, vehicles: &[Vehicle], zones: &[ConflictZone], peds: &[PedView], idm: &Idm) -> f64 {
    let me = &vehicles[i];
    let v = me.speed_mps;
    let look = lookahead_m(v, idm);
    let fwd = me.pose.dir;
    let target = me.target_speed_mps();
    let idm_to =
        |gap: f64, lead: f64| idm_accel_mps2(idm, v, target, me.min_gap_m, me.time_headway_s, Some((gap, lead)));
    let mut accel = idm_accel_mps2(idm, v, target, me.min_gap_m, me.time_headway_s, None);

    // End of route: a standing obstacle.
    let end_gap = me.path.length_m() - me.s_m - HALF_LENGTH_M;
    if end_gap < look {
        accel = accel.min(idm_to(end_gap + me.min_gap_m, 0.0));
    }

    for (j, other) in vehicles.iter().enumerate() {
        if j == i {
            continue;
        }
        let d = other.pose.pos - me.pose.pos;
        if d.length_squared() > (look + VEHICLE_LENGTH_M).powi(2) || d.dot(fwd) <= 0.0 {
            continue;
        }
        let Some((gap, lead_speed)) = vehicle_in_path(me, other, look) else {
            continue;
        };
        // Mutual intrusion (both in each other's path, e.g. at a junction): the lower id goes first, the ego
        // before everyone -- unless the other is right in front (then both wait rather than touch).
        if gap > 1.0
            && vehicle_in_path(other, me, lookahead_m(other.speed_mps, idm)).is_some()
            && priority(me.id) < priority(other.id)
        {
            continue;
        }
        accel = accel.min(idm_to(gap, lead_speed));
    }

    for zone in zones {
        if let Some(gap) = zone_yield_gap_m(me, vehicles, zone, look) {
            accel = accel.min(idm_to(gap, 0.0));
        }
    }

    let emergency_gap = v * v / (2.0 * idm.max_decel_mps2.max(0.5)) + me.min_gap_m;
    for p in peds {
        let d = p.pos - me.pose.pos;
        if d.length_squared() > (look + HALF_LENGTH_M).powi(2) || d.dot(fwd) <= 0.0 {
            continue;
        }
        let mut corridor = HALF_WIDTH_M + PED_RADIUS_M + PED_CORRIDOR_MARGIN_M;
        if p.crossing {
            // A crosser walking towards the path counts a second early.
            corridor += p.velocity.length();
        }
        // Farther from the path than this, the pedestrian matters neither as a leader nor to the ego's rule.
        let reach = match me.ego_brake_m {
            Some((_, side)) if p.crossing => corridor.max(side),
            _ => corridor,
        };
        let Some((s_p, lateral, _)) = me.path.project(p.pos, me.s_m, me.s_m + look + HALF_LENGTH_M, reach) else {
            continue;
        };
        if s_p <= me.s_m {
            continue;
        }
        let gap = s_p - me.s_m - HALF_LENGTH_M - PED_RADIUS_M;
        let in_path = lateral < corridor;
        let ego_rule = me
            .ego_brake_m
            .is_some_and(|(ahead, side)| p.crossing && gap < ahead && lateral < side);
        if (in_path && (!me.ignores_walkers || gap < emergency_gap)) || ego_rule {
            accel = accel.min(idm_to(gap, 0.0));
            // Never plan to run into a pedestrian: brake at least as hard as a stop before it needs.
            if in_path && gap > 0.0 {
                let need = v * v / (2.0 * (gap - 0.3).max(0.05));
                if need > idm.comfortable_decel_mps2 {
                    accel = accel.min(-need.min(idm.max_decel_mps2));
                }
            } else if in_path {
                accel = -idm.max_decel_mps2;
            }
        }
    }
    accel
}

/// Where two vehicles' paths cross or merge: the stretch of each path whose centre line comes within
/// [`ZONE_DISTANCE_M`] of the other's at a heading difference above [`ZONE_MIN_ANGLE_RAD`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ConflictZone {
    /// Index of the other vehicle.
    pub other: usize,
    /// The zone on this vehicle's path, arc lengths `[start, end]`.
    pub me_m: (f64, f64),
    /// The zone on the other's path.
    pub other_m: (f64, f64),
}

/// Centre lines closer than this belong to a conflict zone, metres.
const ZONE_DISTANCE_M: f64 = 2.5;
/// Paths meeting at less than this angle are following, not crossing, radians.
const ZONE_MIN_ANGLE_RAD: f64 = 0.35;
/// How far ahead of its start a vehicle's path is searched for conflict zones, metres.
const ZONE_HORIZON_M: f64 = 260.0;
/// Samples of one path closer than this along it belong to the same zone, metres.
const ZONE_GAP_M: f64 = 10.0;

/// The conflict zones of every vehicle with every other, found once at set-up with a grid of cells at least
/// [`ZONE_DISTANCE_M`] wide over the path samples (1 m apart). Sorted by zone start.
pub(crate) fn conflict_zones(vehicles: &[Vehicle]) -> Vec<Vec<ConflictZone>> {
    let samples = zone_samples(vehicles);
    let n = vehicles.len();
    let mut pairs: Vec<Vec<(f64, f64)>> = vec![Vec::new(); n * n];
    let grid = sample_grid(&samples);
    for a in &samples {
        grid.for_items_around(a.pos, |kb| record_close_pair(a, &samples[kb], n, &mut pairs));
    }
    zones_from_pairs(n, pairs)
}

/// The samples by grid cell: cells at least [`ZONE_DISTANCE_M`] wide, so that every sample within that
/// distance of another is in its 3 × 3 cells (wider when the samples are spread so far that the grid would
/// have more than a few cells per sample).
fn sample_grid(samples: &[ZoneSample]) -> CellGrid {
    let (lo, hi) = bounding_box(samples.iter().map(|smp| smp.pos)).unwrap_or_default();
    let max_cells = (4 * samples.len() + 64) as f64;
    CellGrid::build(lo, hi, ZONE_DISTANCE_M, max_cells, samples.len(), |k| {
        Some((samples[k].pos, samples[k].pos))
    })
}

/// A sample of a vehicle's path for the conflict-zone search.
#[derive(Clone, Copy, Debug)]
struct ZoneSample {
    vehicle: usize,
    s_m: f64,
    pos: DVec2,
    heading_rad: f64,
}

/// Every vehicle's path from just behind it to [`ZONE_HORIZON_M`] ahead, sampled every metre.
fn zone_samples(vehicles: &[Vehicle]) -> Vec<ZoneSample> {
    let mut samples = Vec::new();
    for (vehicle, v) in vehicles.iter().enumerate() {
        let end = (v.s_m + ZONE_HORIZON_M).min(v.path.length_m());
        let mut s_m = (v.s_m - VEHICLE_LENGTH_M).max(0.0);
        while s_m <= end {
            let pose = v.path.pose_at(s_m);
            if pose.pos.is_finite() {
                samples.push(ZoneSample {
                    vehicle,
                    s_m,
                    pos: pose.pos,
                    heading_rad: pose.heading_rad,
                });
            }
            s_m += 1.0;
        }
    }
    samples
}

/// Records `(a, b)` in `pairs[a.vehicle · n + b.vehicle]` (and the reverse) when they are samples of two
/// vehicles' paths that are close and cross at an angle. Symmetric: only the order with `a.vehicle <
/// b.vehicle` records, so each unordered pair of samples is recorded once each way.
fn record_close_pair(a: &ZoneSample, b: &ZoneSample, n: usize, pairs: &mut [Vec<(f64, f64)>]) {
    if b.vehicle <= a.vehicle || a.pos.distance_squared(b.pos) > ZONE_DISTANCE_M * ZONE_DISTANCE_M {
        return;
    }
    let mut d = (a.heading_rad - b.heading_rad).abs() % std::f64::consts::TAU;
    if d > std::f64::consts::PI {
        d = std::f64::consts::TAU - d;
    }
    if d > ZONE_MIN_ANGLE_RAD {
        pairs[a.vehicle * n + b.vehicle].push((a.s_m, b.s_m));
        pairs[b.vehicle * n + a.vehicle].push((b.s_m, a.s_m));
    }
}

/// The zones of each vehicle from the close pairs `(s_i, s_j)` per ordered `(i, j)` (in any order: each list
/// is sorted here), sorted by zone start.
fn zones_from_pairs(n: usize, mut pairs: Vec<Vec<(f64, f64)>>) -> Vec<Vec<ConflictZone>> {
    let mut out = vec![Vec::new(); n];
    for i in 0..n {
        for j in 0..n {
            let list = &mut pairs[i * n + j];
            if list.is_empty() {
                continue;
            }
            list.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
            let mut zone: Option<ConflictZone> = None;
            for &(si, sj) in list.iter() {
                match zone.as_mut() {
                    Some(z) if si - z.me_m.1 <= ZONE_GAP_M => {
                        z.me_m.1 = si;
                        z.other_m.0 = z.other_m.0.min(sj);
                        z.other_m.1 = z.other_m.1.max(sj);
                    }
                    _ => {
                        if let Some(z) = zone.take() {
                            out[i].push(z);
                        }
                        zone = Some(ConflictZone {
                            other: j,
                            me_m: (si, si),
                            other_m: (sj, sj),
                        });
                    }
                }
            }
            out[i].extend(zone);
        }
        out[i].sort_by(|a, b| a.me_m.0.total_cmp(&b.me_m.0).then(a.other.cmp(&b.other)));
    }
    out
}

/// The standing obstacle (gap from the front bumper, metres) at which vehicle `i` must yield in a conflict zone,
/// if it must: a vehicle already in the zone goes first; otherwise the one that would reach it first (ties:
/// the ego, then lower ids). Both vehicles evaluate the same rule, so exactly one of them yields.
fn zone_yield_gap_m(me: &Vehicle, vehicles: &[Vehicle], zone: &ConflictZone, look: f64) -> Option<f64> {
    let other = &vehicles[zone.other];
    let my_front = me.s_m + HALF_LENGTH_M;
    let other_front = other.s_m + HALF_LENGTH_M;
    if me.s_m - HALF_LENGTH_M > zone.me_m.1 || other.s_m - HALF_LENGTH_M > zone.other_m.1 {
        return None; // one of us has passed
    }
    let dist_me = zone.me_m.0 - my_front;
    if dist_me > look {
        return None;
    }
    let dist_other = zone.other_m.0 - other_front;
    let (in_me, in_other) = (dist_me <= 0.0, dist_other <= 0.0);
    let yield_now = match (in_me, in_other) {
        (true, false) => false,
        (false, true) => true,
        (true, true) => priority(me.id) > priority(other.id),
        (false, false) => {
            let t_me = dist_me / me.speed_mps.max(0.5);
            let t_other = dist_other / other.speed_mps.max(0.5);
            t_other < t_me || (t_other == t_me && priority(other.id) < priority(me.id))
        }
    };
    yield_now.then_some(dist_me - 1.0)
}

fn priority(id: u32) -> u64 {
    if id == crate::exec::trace::EGO_ID {
        0
    } else {
        u64::from(id) + 1
    }
}

/// If `other`'s footprint intrudes on the corridor of `me`'s path ahead within `look` metres: the gap from
/// `me`'s front bumper to it along the path and its speed along the path.
fn vehicle_in_path(me: &Vehicle, other: &Vehicle, look: f64) -> Option<(f64, f64)> {
    // The footprint's lateral extent is at most its half diagonal, so a centre farther than this is clear.
    let reach = HALF_WIDTH_M + VEHICLE_CORRIDOR_MARGIN_M + HALF_LENGTH_M.hypot(HALF_WIDTH_M) + 1e-6;
    let (s_o, lateral, path_heading) =
        me.path
            .project(other.pose.pos, me.s_m, me.s_m + look + VEHICLE_LENGTH_M, reach)?;
    if s_o <= me.s_m {
        return None;
    }
    let delta = other.pose.heading_rad - path_heading;
    let (sd, cd) = (delta.sin().abs(), delta.cos().abs());
    let extent_lat = HALF_LENGTH_M * sd + HALF_WIDTH_M * cd;
    let extent_long = HALF_LENGTH_M * cd + HALF_WIDTH_M * sd;
    if lateral - extent_lat >= HALF_WIDTH_M + VEHICLE_CORRIDOR_MARGIN_M {
        return None;
    }
    let gap = s_o - me.s_m - HALF_LENGTH_M - extent_long;
    Some((gap, (other.speed_mps * delta.cos()).max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path of straight runs and arcs, sampled every `PATH_SPACING_M` of arc length like `from_route`.
    fn winding_path() -> VehiclePath {
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

    /// Vehicles on copies of the winding path, rotated about `pivot` and shifted, crossing each other.
    fn crossing_vehicles(pivot: DVec2, shifts: &[(f64, DVec2)]) -> Vec<Vehicle> {
        let base = winding_path();
        shifts
            .iter()
            .enumerate()
            .map(|(k, &(angle_rad, shift))| {
                let rot = DVec2::from_angle(angle_rad);
                let points: Vec<PathPoint> = base
                    .points
                    .iter()
                    .map(|q| PathPoint {
                        pos: pivot + rot.rotate(q.pos - pivot) + shift,
                        ..*q
                    })
                    .collect();
                let headings_rad = base.headings_rad.iter().map(|h| h + angle_rad).collect();
                let path = VehiclePath::assemble(points, headings_rad, base.advisory_mps.clone(), base.length_m);
                Vehicle::new(k as u32, path, 3.0 * k as f64, 1.0, 2.0, 1.5, false, None)
            })
            .collect()
    }

    #[test]
    fn conflict_zones_from_the_grid_match_the_all_pairs_search() {
        let pivot = DVec2::new(40.0, 10.0);
        let near = [
            (0.0, DVec2::ZERO),
            (1.2, DVec2::new(5.0, -3.0)),
            (-0.9, DVec2::new(-8.0, 4.0)),
            (0.1, DVec2::new(0.0, 1.0)),
        ];
        // One vehicle kilometres away spreads the points so far that the grid's cells are widened.
        let spread = [
            (0.0, DVec2::ZERO),
            (1.5, DVec2::new(2.0, 2.0)),
            (0.7, DVec2::new(4000.0, -2500.0)),
        ];
        for shifts in [&near[..], &spread[..]] {
            let vehicles = crossing_vehicles(pivot, shifts);
            let samples = zone_samples(&vehicles);
            let n = vehicles.len();
            let mut pairs = vec![Vec::new(); n * n];
            for a in &samples {
                for b in &samples {
                    record_close_pair(a, b, n, &mut pairs);
                }
            }
            let expected = zones_from_pairs(n, pairs);
            let zones: usize = expected.iter().map(Vec::len).sum();
            assert!(zones >= 2, "the paths cross: {expected:?}");
            assert_eq!(conflict_zones(&vehicles), expected);
        }
        let spread = crossing_vehicles(pivot, &spread);
        let grid = sample_grid(&zone_samples(&spread));
        assert!(grid.cell_m() > ZONE_DISTANCE_M, "the spread case widens the cells");
    }

    #[test]
    fn idm_free_road_accelerates_to_target_and_stops_for_standing_leader() {
        let idm = Idm::default();
        assert!(idm_accel_mps2(&idm, 0.0, 10.0, 2.0, 1.5, None) > 1.4);
        assert!(idm_accel_mps2(&idm, 10.0, 10.0, 2.0, 1.5, None).abs() < 1e-9);
        assert!(idm_accel_mps2(&idm, 10.0, 10.0, 2.0, 1.5, Some((10.0, 0.0))) < -3.0);
        // A leader far ahead at the same speed barely matters.
        assert!(idm_accel_mps2(&idm, 10.0, 10.0, 2.0, 1.5, Some((200.0, 10.0))).abs() < 0.05);
    }
}
