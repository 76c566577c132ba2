//! Vehicles: the route polyline rebuilt from a [`RouteScript`], lane following along it (through junctions),
//! Intelligent Driver Model car following with vehicles **and** pedestrians in the path ahead as leaders, and
//! the ego's braking rule for crossing pedestrians.
//!
//! A vehicle is a point moving along its own path polyline (arc length `s_m`); its footprint is a
//! [`VEHICLE_LENGTH_M`] × [`VEHICLE_WIDTH_M`] box centred on that point and aligned with the path. Leaders are
//! found geometrically: anything whose footprint (a vehicle) or disc (a pedestrian) intrudes on the corridor of
//! half-width `VEHICLE_WIDTH_M / 2 + margin` around the path ahead, within the look-ahead distance. This also
//! covers vehicles on crossing paths inside junctions. Where traffic lights run, the next stop line on the path
//! whose light is red (or amber, when the vehicle can stop comfortably) is a standing leader, unless the
//! vehicle ignores lights or is an emergency vehicle.

mod conflict_zones;
mod idm;
pub(crate) mod path;

use glam::DVec2;

use super::{VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::plan::{CyclistScript, EgoScript, EmergencyKind, VehicleScript};
use crate::sim::trace::VehicleId;
use crate::world::RoadNetwork;
pub(crate) use conflict_zones::{ConflictZone, conflict_zones};
pub(crate) use idm::{accel_for, vehicle_in_path_unshifted};
use path::{PathPose, VehiclePath};

/// The ego's IDM time headway (the ego script has none), seconds.
pub const EGO_TIME_HEADWAY_S: f64 = 1.5;

/// Half the vehicle length, metres.
pub(crate) const HALF_LENGTH_M: f64 = VEHICLE_LENGTH_M * 0.5;
/// Half the vehicle width, metres.
pub(crate) const HALF_WIDTH_M: f64 = VEHICLE_WIDTH_M * 0.5;

/// A vehicle stops for an emergency vehicle closing in from nearer than this, metres. pedsynth: room to stop
/// from 50 km/h at the default comfortable 3 m/s² (~32 m) before the two meet, at their closing speeds.
pub(crate) const YIELD_TO_SIREN_M: f64 = 70.0;
/// How far a yielding vehicle pulls over to the right, metres (a 1.9 m car stays inside a 3 m lane).
pub(crate) const PULL_RIGHT_M: f64 = 0.5;
/// Sideways metres per metre driven while pulling over or back.
pub(crate) const PULL_RIGHT_PER_M: f64 = 0.15;

/// Length of a bicycle with its rider, metres (a city bike: 1.05 m wheelbase, 0.68 m wheels).
pub const BICYCLE_LENGTH_M: f64 = 1.75;
/// Width of a bicycle with its rider (handlebar and elbows), metres.
pub const BICYCLE_WIDTH_M: f64 = 0.65;
/// Height of a bicycle with its rider (for occlusion), metres.
pub const BICYCLE_HEIGHT_M: f64 = 1.7;
/// Lateral margin of a cyclist's corridor for pedestrians beyond the bicycle and the pedestrian, metres (a
/// bicycle passes a walker closer than a car does).
pub(crate) const CYCLIST_PED_MARGIN_M: f64 = 0.3;
/// Sideways metres per metre ridden while a cyclist swerves or returns (or moves into or out of a bike lane).
const SWERVE_PER_M: f64 = 0.3;
/// A cyclist looks this far ahead along its route for the end of its bike lane, to be back by its driving lane's
/// edge there (3 m sideways at [`SWERVE_PER_M`]), metres.
pub(crate) const BIKE_LANE_LOOKAHEAD_M: f64 = 10.0;
/// Sideways metres per metre driven while a vehicle moves out to overtake a cyclist or back in.
const OVERTAKE_SHIFT_PER_M: f64 = 0.15;

/// A simulated vehicle (the ego, traffic, or a cyclist: a bicycle is a narrow, slow vehicle that rides near its
/// lane's right edge).
#[derive(Clone, Debug)]
pub(crate) struct Vehicle {
    /// Which vehicle this is.
    pub id: VehicleId,
    /// Half its footprint's length and width, metres.
    pub half_length_m: f64,
    pub half_width_m: f64,
    /// A cyclist's cruising speed, m/s (motor vehicles: `None`, their speed follows the limit).
    pub cruise_mps: Option<f64>,
    /// A cyclist rides this far right of its path (the lane's centre line), metres: `edge_offset_m` from the
    /// lane's right edge, or the centre of a bike lane beside it ([`Vehicle::ride_offsets`]).
    pub ride_offset_m: f64,
    /// A cyclist's ride offset along its path where its route has a bike lane: `(s from, offset, in a bike
    /// lane)`, metres, in path order (empty where the route has none: the offset stays `ride_offset_m`).
    pub ride_offsets: Vec<(f64, f64, bool)>,
    /// Whether a cyclist rides in a bike lane at its current position.
    pub in_bike_lane: bool,
    /// Where it is across its lane: metres to the right of the path (a cyclist's ride offset, less a swerve;
    /// negative for a vehicle moved out to overtake). Its corridor is centred here.
    pub lane_offset_m: f64,
    /// Where `lane_offset_m` heads this step.
    pub target_offset_m: f64,
    /// The cyclist (index into the simulation's vehicles) it is overtaking, with the smallest side-to-side
    /// clearance so far, metres.
    pub overtaking: Option<(usize, f64)>,
    /// A cyclist swerving around the pedestrian (index) in its path.
    pub swerving_for: Option<usize>,
    /// Distance ridden or driven since the start, metres.
    pub odometer_m: f64,
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
    /// The ego's courtesy for pedestrians waiting at the curb.
    pub courtesy: Option<Courtesy>,
    /// Cached pose at `s_m`.
    pub pose: PathPose,
    /// An emergency vehicle (lights and siren on).
    pub emergency: Option<EmergencyKind>,
    /// Whether it stops for an approaching emergency vehicle this step.
    pub yielding: bool,
    /// How far it has pulled over to the right of its path (yielding), metres.
    pub pull_right_m: f64,
    /// Whether it drives through red lights (drawn per vehicle from its profile).
    pub ignores_lights: bool,
    /// The stop lines of traffic lights along its path, in path order (empty where lights do not run).
    pub stop_lines: Vec<super::signals::StopLine>,
    /// Index into `stop_lines` of the next one ahead of its front bumper.
    pub next_stop: usize,
    /// The next stop line's light this step, if within [`LIGHT_RANGE_M`]: (front bumper to the line, metres,
    /// its state).
    pub light_ahead: Option<(f64, super::signals::LightState)>,
    /// The stop line (index into `stop_lines`) at which a stop for red has been recorded.
    pub stopped_at: Option<usize>,
    /// The stop line (index into `stop_lines`) it drives through because it could not stop when it first saw
    /// its light amber or red (the dilemma zone; at a clip's start, a vehicle placed too close to a red light).
    pub committed: Option<usize>,
}

/// A vehicle heeds (and the tables report) the light of its next stop line from this far, metres.
pub(crate) const LIGHT_RANGE_M: f64 = 80.0;

impl Vehicle {
    /// The ego vehicle, at its route start, at its target speed.
    pub(crate) fn ego(script: &EgoScript, net: &RoadNetwork) -> Vehicle {
        let path = VehiclePath::from_route(&script.route, net);
        Self::new(
            VehicleId::Ego,
            path,
            script.route.start_s_m,
            1.0 - script.speed_below_limit_pct / 100.0,
            script.min_gap_m,
            EGO_TIME_HEADWAY_S,
            false,
            Some((script.brake_ahead_m, script.brake_lateral_m)),
        )
        .with_courtesy(Courtesy {
            speed_mps: script.courtesy_speed_mps,
            ahead_m: script.courtesy_ahead_m,
            lateral_m: script.courtesy_lateral_m,
            stop_short_m: script.courtesy_stop_short_m,
            patience_s: script.courtesy_patience_s,
            roll_up: script.courtesy_roll_up,
            yielded_s: 0.0,
        })
    }

    fn with_courtesy(mut self, courtesy: Courtesy) -> Vehicle {
        self.courtesy = Some(courtesy);
        self
    }

    /// A traffic vehicle, at its route start, at its target speed.
    pub(crate) fn traffic(script: &VehicleScript, net: &RoadNetwork) -> Vehicle {
        let path = VehiclePath::from_route(&script.route, net);
        Self::new(
            VehicleId::Traffic(script.id),
            path,
            script.route.start_s_m,
            1.0 - script.speed_difference_pct / 100.0,
            script.min_gap_m,
            script.time_headway_s,
            script.ignores_walkers,
            None,
        )
        .with_emergency(script.emergency)
        .with_ignores_lights(script.ignores_lights)
    }

    /// A cyclist, at its route start, at its cruising speed, `edge_offset_m` from its lane's right edge.
    pub(crate) fn cyclist(script: &CyclistScript, net: &RoadNetwork) -> Vehicle {
        let path = VehiclePath::from_route(&script.route, net);
        let lane_width_m = script
            .route
            .lanes
            .first()
            .and_then(|&l| net.lanes.get(l as usize))
            .and_then(|l| net.pieces.get(l.pieces.start as usize))
            .map_or(3.0, |p| f64::from(p.width_m[0]));
        let ride_offset_m = (0.5 * lane_width_m - script.edge_offset_m).max(0.0);
        let mut v = Self::new(
            VehicleId::Cyclist(script.id),
            path,
            script.route.start_s_m,
            1.0,
            1.0,
            1.0,
            false,
            None,
        )
        .with_ignores_lights(script.ignores_lights);
        v.half_length_m = 0.5 * BICYCLE_LENGTH_M;
        v.half_width_m = 0.5 * BICYCLE_WIDTH_M;
        v.cruise_mps = Some(script.speed_mps.max(0.1));
        v.ride_offset_m = ride_offset_m;
        v.ride_offsets = net
            .bike_lane_offsets(&script.route.lanes_in(net))
            .into_iter()
            .map(|(s, bike)| (s, bike.unwrap_or(ride_offset_m), bike.is_some()))
            .collect();
        v.follow_bike_lane();
        v.lane_offset_m = v.ride_offset_m;
        v.target_offset_m = v.ride_offset_m;
        v.place();
        v.speed_mps = v.target_speed_mps();
        v
    }

    /// Whether it is a bicycle.
    pub(crate) fn is_cyclist(&self) -> bool {
        self.cruise_mps.is_some()
    }

    /// The distance of `p` from the centre line of its corridor (its path moved `lane_offset_m` to the right),
    /// given `p`'s projection `s_p` on the path and its unsigned distance `lateral_m` from it, metres.
    pub(crate) fn corridor_lateral_m(&self, p: DVec2, s_p: f64, lateral_m: f64) -> f64 {
        if self.lane_offset_m == 0.0 {
            return lateral_m;
        }
        (self.signed_lateral_m(p, s_p) + self.lane_offset_m).abs()
    }

    /// Sets a cyclist's ride offset for where it is now: a bike lane's centre where its route has one beside
    /// it, else `edge_offset_m` from its lane's edge. It leaves a bike lane early enough to be back at the edge
    /// offset where the lane ends ([`BIKE_LANE_LOOKAHEAD_M`]); it enters one where it begins.
    pub(crate) fn follow_bike_lane(&mut self) {
        if self.ride_offsets.is_empty() {
            return;
        }
        let k = self.ride_offsets.partition_point(|&(s, ..)| s <= self.s_m).max(1) - 1;
        let ahead = self.s_m + BIKE_LANE_LOOKAHEAD_M;
        let window = self.ride_offsets[k..]
            .iter()
            .enumerate()
            .take_while(|&(i, o)| i == 0 || o.0 < ahead);
        let (mut offset, mut in_lane) = (f64::INFINITY, true);
        for (_, &(_, o, bike)) in window {
            offset = offset.min(o);
            in_lane &= bike;
        }
        self.ride_offset_m = offset;
        self.in_bike_lane = in_lane;
    }

    /// Where `p` lies across the path at arc length `s_p`: metres to the left (negative: right).
    pub(crate) fn signed_lateral_m(&self, p: DVec2, s_p: f64) -> f64 {
        let at = self.path.pose_at(s_p);
        (p - at.pos).dot(at.dir.perp())
    }

    fn with_emergency(mut self, emergency: Option<EmergencyKind>) -> Vehicle {
        self.emergency = emergency;
        self
    }

    fn with_ignores_lights(mut self, ignores_lights: bool) -> Vehicle {
        self.ignores_lights = ignores_lights;
        self
    }

    /// Sets the stop lines along its path; those its front bumper has passed are behind it.
    pub(crate) fn set_stop_lines(&mut self, stop_lines: Vec<super::signals::StopLine>) {
        let front = self.s_m + self.half_length_m;
        self.next_stop = stop_lines.iter().take_while(|l| l.s_m <= front).count();
        self.stop_lines = stop_lines;
    }

    /// Whether red lights bind it (not for those drawn to ignore them, nor for emergency vehicles).
    pub(crate) fn heeds_lights(&self) -> bool {
        !self.ignores_lights && self.emergency.is_none()
    }

    /// Whether the light at its next stop line binds it: it heeds lights and has not committed to the line.
    pub(crate) fn bound_by_light(&self) -> bool {
        self.heeds_lights() && self.committed != Some(self.next_stop)
    }

    /// Whether it yields to the emergency vehicle `e`: `e` is nearer than [`YIELD_TO_SIREN_M`] and closing in,
    /// unless it follows this vehicle in the same direction (it cannot get past a stopped car in its lane).
    pub(crate) fn yields_to(&self, e: &Vehicle) -> bool {
        if self.emergency.is_some() || e.emergency.is_none() {
            return false;
        }
        let d = e.pose.pos - self.pose.pos;
        let closing = (e.velocity() - self.velocity()).dot(d) < 0.0;
        let following = d.dot(self.pose.dir) < 0.0 && e.pose.dir.dot(self.pose.dir) > 0.7;
        d.length() < YIELD_TO_SIREN_M && closing && !following
    }

    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        id: VehicleId,
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
            half_length_m: HALF_LENGTH_M,
            half_width_m: HALF_WIDTH_M,
            cruise_mps: None,
            ride_offset_m: 0.0,
            ride_offsets: Vec::new(),
            in_bike_lane: false,
            lane_offset_m: 0.0,
            target_offset_m: 0.0,
            overtaking: None,
            swerving_for: None,
            odometer_m: 0.0,
            s_m,
            speed_mps: pose.speed_limit_mps * speed_factor,
            accel_mps2: 0.0,
            speed_factor,
            min_gap_m: min_gap_m.max(0.1),
            time_headway_s: time_headway_s.max(0.1),
            ignores_walkers,
            ego_brake_m,
            courtesy: None,
            pose,
            path,
            emergency: None,
            yielding: false,
            pull_right_m: 0.0,
            ignores_lights: false,
            stop_lines: Vec::new(),
            next_stop: 0,
            light_ahead: None,
            stopped_at: None,
            committed: None,
        }
    }

    /// Half its footprint's extents: along its heading, across, metres.
    pub(crate) fn half_extents(&self) -> DVec2 {
        DVec2::new(self.half_length_m, self.half_width_m)
    }

    /// Velocity vector, m/s.
    pub(crate) fn velocity(&self) -> DVec2 {
        self.pose.dir * self.speed_mps
    }

    /// Target (desired) speed at the current position, m/s.
    pub(crate) fn target_speed_mps(&self) -> f64 {
        let cruise = self.cruise_mps.unwrap_or(self.pose.speed_limit_mps * self.speed_factor);
        cruise.min(self.path.advisory_mps(self.s_m))
    }

    /// Advances by `dt_s` with acceleration `accel_mps2` (speed never negative), updating the cached pose.
    pub(crate) fn integrate(&mut self, accel_mps2: f64, dt_s: f64) {
        let v0 = self.speed_mps;
        let v1 = (v0 + accel_mps2 * dt_s).max(0.0);
        let s0 = self.s_m;
        self.s_m = (self.s_m + 0.5 * (v0 + v1) * dt_s).min(self.path.length_m());
        self.odometer_m += self.s_m - s0;
        self.accel_mps2 = (v1 - v0) / dt_s;
        self.speed_mps = if self.s_m >= self.path.length_m() { 0.0 } else { v1 };
        // Pulling over to the right while yielding, back to the lane centre after: sideways by at most a
        // fraction of the distance driven (a car steers; it does not slide).
        let target = if self.yielding { PULL_RIGHT_M } else { 0.0 };
        let step = PULL_RIGHT_PER_M * 0.5 * (v0 + v1) * dt_s;
        self.pull_right_m += (target - self.pull_right_m).clamp(-step, step);
        // Moving out to overtake (or a cyclist swerving) and back in: also by distance travelled.
        let rate = if self.is_cyclist() {
            SWERVE_PER_M
        } else {
            OVERTAKE_SHIFT_PER_M
        };
        let step = rate * 0.5 * (v0 + v1) * dt_s;
        self.lane_offset_m += (self.target_offset_m - self.lane_offset_m).clamp(-step, step);
        self.place();
    }

    /// Caches the pose at `s_m`, moved `pull_right_m` to the right of the path.
    pub(crate) fn place(&mut self) {
        self.pose = self.path.pose_at(self.s_m);
        let right = self.pull_right_m + self.lane_offset_m;
        if right != 0.0 {
            self.pose.pos -= self.pose.dir.perp() * right;
        }
    }

    /// Counts the time the ego yields: while an attentive pedestrian waits at the curb ahead (`yielding`), for
    /// `dt_s` more; the count starts over once none does.
    pub(crate) fn count_yield(&mut self, yielding: bool, dt_s: f64) {
        if let Some(c) = self.courtesy.as_mut() {
            c.yielded_s = if yielding { c.yielded_s + dt_s } else { 0.0 };
        }
    }

    /// Whether a pedestrian waiting attentively at the curb is ahead within the courtesy zone.
    pub(crate) fn sees_waiting_pedestrian(&self, peds: &[PedView]) -> bool {
        self.courtesy.is_some_and(|c| {
            peds.iter().filter(|p| p.waiting_at_curb).any(|p| {
                self.path
                    .project(p.pos, self.s_m, self.s_m + c.ahead_m, c.lateral_m)
                    .is_some_and(|(s_p, _, _)| s_p > self.s_m && s_p < self.s_m + c.ahead_m)
            })
        })
    }

    /// Moves the vehicle back along its path by `ds_m` and stops it (contact resolution).
    pub(crate) fn back_off_and_stop(&mut self, ds_m: f64) {
        self.s_m = (self.s_m - ds_m).max(0.0);
        self.speed_mps = 0.0;
        self.place();
    }
}

/// The ego's courtesy: it eases off to `speed_mps` for a pedestrian heading for the curb up to `ahead_m` ahead
/// along its path and `lateral_m` to the side, and stops `stop_short_m` before one waiting there attentively —
/// for `patience_s` at most; then it drives on (at the eased speed) until no waiting pedestrian is ahead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Courtesy {
    pub speed_mps: f64,
    pub ahead_m: f64,
    pub lateral_m: f64,
    pub stop_short_m: f64,
    pub patience_s: f64,
    /// It rolls up to a crosser that waits for it to come near.
    pub roll_up: bool,
    /// Time it has yielded (a waiting pedestrian ahead), seconds.
    pub yielded_s: f64,
}

impl Courtesy {
    /// Whether the ego has waited long enough and drives on.
    pub(crate) fn patience_spent(&self) -> bool {
        self.yielded_s >= self.patience_s
    }
}

/// What the vehicle logic needs to know about a pedestrian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PedView {
    pub pos: DVec2,
    pub velocity: DVec2,
    /// In a crossing-type state or retreating (the ego's braking rule applies).
    pub crossing: bool,
    /// Heading for the curb (or standing there) to cross, or as if to: the ego eases off.
    pub approaching_curb: bool,
    /// Waiting at the curb attentively (looking, checking the traffic, hesitating): the ego stops short.
    pub waiting_at_curb: bool,
    /// How near the ego must come before it steps out (`crossing.scenario.crosser_ego_within_m`), metres from
    /// the ego's centre: a yielding ego rolls up to within that rather than stop short of it.
    pub steps_out_ego_within_m: Option<f64>,
}
