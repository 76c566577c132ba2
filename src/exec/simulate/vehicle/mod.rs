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
mod path;

use glam::DVec2;

use super::{VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::exec::trace::VehicleId;
use crate::planner::{EgoScript, EmergencyKind, VehicleScript};
use crate::world::RoadNetwork;
pub(crate) use conflict_zones::{ConflictZone, conflict_zones};
pub(crate) use idm::accel_for;
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

/// A simulated vehicle (the ego or traffic).
#[derive(Clone, Debug)]
pub(crate) struct Vehicle {
    /// Which vehicle this is.
    pub id: VehicleId,
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
    pub fn ego(script: &EgoScript, net: &RoadNetwork) -> Vehicle {
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
            yielded_s: 0.0,
        })
    }

    fn with_courtesy(mut self, courtesy: Courtesy) -> Vehicle {
        self.courtesy = Some(courtesy);
        self
    }

    /// A traffic vehicle, at its route start, at its target speed.
    pub fn traffic(script: &VehicleScript, net: &RoadNetwork) -> Vehicle {
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

    fn with_emergency(mut self, emergency: Option<EmergencyKind>) -> Vehicle {
        self.emergency = emergency;
        self
    }

    fn with_ignores_lights(mut self, ignores_lights: bool) -> Vehicle {
        self.ignores_lights = ignores_lights;
        self
    }

    /// Sets the stop lines along its path; those its front bumper has passed are behind it.
    pub fn set_stop_lines(&mut self, stop_lines: Vec<super::signals::StopLine>) {
        let front = self.s_m + HALF_LENGTH_M;
        self.next_stop = stop_lines.iter().take_while(|l| l.s_m <= front).count();
        self.stop_lines = stop_lines;
    }

    /// Whether red lights bind it (not for those drawn to ignore them, nor for emergency vehicles).
    pub fn heeds_lights(&self) -> bool {
        !self.ignores_lights && self.emergency.is_none()
    }

    /// Whether the light at its next stop line binds it: it heeds lights and has not committed to the line.
    pub fn bound_by_light(&self) -> bool {
        self.heeds_lights() && self.committed != Some(self.next_stop)
    }

    /// Whether it yields to the emergency vehicle `e`: `e` is nearer than [`YIELD_TO_SIREN_M`] and closing in,
    /// unless it follows this vehicle in the same direction (it cannot get past a stopped car in its lane).
    pub fn yields_to(&self, e: &Vehicle) -> bool {
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
        // Pulling over to the right while yielding, back to the lane centre after: sideways by at most a
        // fraction of the distance driven (a car steers; it does not slide).
        let target = if self.yielding { PULL_RIGHT_M } else { 0.0 };
        let step = PULL_RIGHT_PER_M * 0.5 * (v0 + v1) * dt_s;
        self.pull_right_m += (target - self.pull_right_m).clamp(-step, step);
        self.place();
    }

    /// Caches the pose at `s_m`, moved `pull_right_m` to the right of the path.
    fn place(&mut self) {
        self.pose = self.path.pose_at(self.s_m);
        if self.pull_right_m > 0.0 {
            self.pose.pos -= self.pose.dir.perp() * self.pull_right_m;
        }
    }

    /// Counts the time the ego yields: while an attentive pedestrian waits at the curb ahead (`yielding`), for
    /// `dt_s` more; the count starts over once none does.
    pub fn count_yield(&mut self, yielding: bool, dt_s: f64) {
        if let Some(c) = self.courtesy.as_mut() {
            c.yielded_s = if yielding { c.yielded_s + dt_s } else { 0.0 };
        }
    }

    /// Whether a pedestrian waiting attentively at the curb is ahead within the courtesy zone.
    pub fn sees_waiting_pedestrian(&self, peds: &[PedView]) -> bool {
        self.courtesy.is_some_and(|c| {
            peds.iter().filter(|p| p.waiting_at_curb).any(|p| {
                self.path
                    .project(p.pos, self.s_m, self.s_m + c.ahead_m, c.lateral_m)
                    .is_some_and(|(s_p, _, _)| s_p > self.s_m && s_p < self.s_m + c.ahead_m)
            })
        })
    }

    /// Moves the vehicle back along its path by `ds_m` and stops it (contact resolution).
    pub fn back_off_and_stop(&mut self, ds_m: f64) {
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
    /// Time it has yielded (a waiting pedestrian ahead), seconds.
    pub yielded_s: f64,
}

impl Courtesy {
    /// Whether the ego has waited long enough and drives on.
    pub fn patience_spent(&self) -> bool {
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
}
