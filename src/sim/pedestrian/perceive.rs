//! Perception: what a pedestrian knows of the traffic at the start of a step (every decision of the step uses
//! it): TTC against every vehicle in range, where the ego is, and on the road the lookahead conflict.

use glam::{DVec2, DVec3};

use super::Ped;
use super::params::{BLOCKING_CLEARANCE_M, CONFLICT_MIN_VEHICLE_SPEED_MPS};
use super::state::Activity;
use crate::plan::SimParams;
use crate::sim::rig::CameraPose;
use crate::sim::signals::{LightState, WalkSignal};
use crate::sim::trace::VehicleId;
use crate::sim::vehicle::{HALF_LENGTH_M, HALF_WIDTH_M, Vehicle};
use crate::sim::view::ViewProxy;
use crate::sim::{PED_RADIUS_M, ttc};
use crate::world::RoadNetwork;

/// A pedestrian holds at the curb (or hurries across) while an emergency vehicle closes in from nearer than
/// this on a course that passes near it, metres. pedsynth: a siren is heard some 100 m away in a city street.
pub(crate) const SIREN_HOLD_M: f64 = 100.0;
/// ... on a course that passes within this distance of the pedestrian, or while one is within it, metres.
/// pedsynth (before 2026-11-27 any emergency vehicle closing in held pedestrians: one circling the block on the
/// next street kept a whole clip at the curb).
pub(crate) const SIREN_PASSING_M: f64 = 15.0;

/// What a pedestrian perceives of the traffic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Percept {
    /// Minimum TTC over every vehicle in range, seconds.
    pub min_ttc_s: f64,
    /// Minimum TTC over every vehicle but the ego, seconds.
    pub min_ttc_others_s: f64,
    /// Distance to the nearest vehicle centre, metres.
    pub nearest_vehicle_m: f64,
    /// Distance to the ego, metres.
    pub ego_dist_m: f64,
    /// Whether the ego has yet to pass the pedestrian (along the ego's route).
    pub ego_ahead: bool,
    /// The ego's speed, m/s.
    pub ego_speed_mps: f64,
    /// The vehicle of a lookahead conflict this step (own probes; crossing pedestrians on the road only).
    pub conflict_vehicle: Option<VehicleId>,
    /// Whether the last lookahead conflict seen on the road was a standing vehicle blocking the way (kept until
    /// the next lookahead on the road).
    pub blocked_by_standing: bool,
    /// Whether the ego's camera sees the pedestrian (the simulation's estimate, `view`).
    pub in_view: bool,
    /// Whether an emergency vehicle's siren is near: within [`SIREN_PASSING_M`], or closing in from nearer than
    /// [`SIREN_HOLD_M`] on a course that passes within [`SIREN_PASSING_M`].
    pub siren_near: bool,
    /// The pedestrian signal of its signalised crosswalk, if it has one (set by the simulation each step).
    pub walk: Option<WalkSignal>,
}

impl Default for Percept {
    fn default() -> Self {
        Percept {
            min_ttc_s: f64::INFINITY,
            min_ttc_others_s: f64::INFINITY,
            nearest_vehicle_m: f64::INFINITY,
            ego_dist_m: f64::INFINITY,
            ego_ahead: true,
            ego_speed_mps: 0.0,
            conflict_vehicle: None,
            blocked_by_standing: false,
            in_view: false,
            siren_near: false,
            walk: None,
        }
    }
}

/// What a pedestrian perceives needs of the world beyond itself and the vehicles.
pub(crate) struct Surroundings<'a> {
    pub params: &'a SimParams,
    pub net: &'a RoadNetwork,
    pub view: &'a ViewProxy,
    /// The ego's camera this step.
    pub camera: &'a CameraPose,
    /// Every pedestrian's ground point and height at the start of the step (occluders).
    pub people: &'a [(DVec3, f64)],
    /// This pedestrian's index in `people`.
    pub me: usize,
    pub dt_s: f64,
}

/// Whether `v`'s light binds it, shows red or amber, and its stop line is before its front reaches `pos`.
fn held_short_of(v: &Vehicle, pos: DVec2) -> bool {
    v.bound_by_light()
        && v.light_ahead.is_some_and(|(gap_m, state)| {
            state != LightState::Green && gap_m < v.pose.pos.distance(pos) - v.half_length_m
        })
}

/// Updates `p.percept` from the vehicles' state at the start of the step (`vehicles[0]` is the ego), and the
/// time the camera has seen the pedestrian. `probes` is scratch space.
pub(crate) fn perceive(p: &mut Ped, vehicles: &[Vehicle], around: &Surroundings, probes: &mut Vec<DVec2>) {
    let Some((ego, traffic)) = vehicles.split_first() else {
        return;
    };
    let params = around.params;
    let pos = p.body.pos;
    p.percept.in_view = around.view.sees(
        around.camera,
        DVec3::new(pos.x, pos.y, p.body.z_m),
        p.body.yaw_rad,
        p.traits.height_m,
        vehicles,
        around.people,
        around.me,
        around.net,
    );
    if p.percept.in_view {
        p.in_view_s += around.dt_s;
    }
    let range_m = params.gap_acceptance.vehicle_range_m;
    let percept = &mut p.percept;
    // At "walk", a vehicle that its red (or amber) light holds short of the pedestrian stops at its line: no
    // threat to a crossing on the green man (those that run the light, or cannot stop, still count).
    let walk = percept.walk == Some(WalkSignal::Walk);
    let threat = |v: &&Vehicle| !(walk && held_short_of(v, pos));
    percept.min_ttc_s = ttc::min_ttc_s(
        pos,
        vehicles.iter().filter(threat).map(|v| (v.pose.pos, v.velocity())),
        range_m,
    );
    percept.min_ttc_others_s = ttc::min_ttc_s(
        pos,
        traffic.iter().filter(threat).map(|v| (v.pose.pos, v.velocity())),
        range_m,
    );
    percept.nearest_vehicle_m = vehicles
        .iter()
        .map(|v| v.pose.pos.distance(pos))
        .fold(f64::INFINITY, f64::min);
    percept.ego_dist_m = ego.pose.pos.distance(pos);
    percept.ego_speed_mps = ego.speed_mps;
    percept.ego_ahead = ego.s_m < p.traits.route_s_m;
    percept.siren_near = vehicles.iter().filter(|v| v.emergency.is_some()).any(|v| {
        let d = pos - v.pose.pos;
        let dist = d.length();
        if dist < SIREN_PASSING_M {
            return true;
        }
        // Closing in from nearer than SIREN_HOLD_M on a course that passes within SIREN_PASSING_M (down the
        // pedestrian's street, or across it close by): not one driving by on another street.
        let vel = v.velocity();
        let closing = vel.dot(d);
        if dist >= SIREN_HOLD_M || closing <= 0.0 {
            return false;
        }
        let t_s = closing / vel.length_squared();
        (d - vel * t_s).length() < SIREN_PASSING_M
    });
    percept.conflict_vehicle = None;
    let Some(line) = p.traits.line else {
        return;
    };
    let along = line.along_m(pos);
    if !(p.activity.label().is_crossing() && along > 0.0 && along < line.width_m) {
        return;
    }
    // A pausing pedestrian probes as if walking on.
    let dir = line.dir;
    let velocity = if matches!(p.activity, Activity::PausingMidCross { .. }) {
        dir * p.traits.base_speed_mps
    } else {
        p.body.velocity
    };
    ttc::probe_points(
        pos,
        dir,
        velocity,
        &params.lookahead.points_m,
        params.lookahead.prediction_s,
        probes,
    );
    let r = params.lookahead.radius_m;
    // A vehicle whose centre is farther than this from the pedestrian is beyond the radius of every probe.
    let reach_m =
        probes.iter().map(|q| q.distance(pos)).fold(0.0, f64::max) + r + HALF_LENGTH_M.hypot(HALF_WIDTH_M) + 1e-6;
    percept.blocked_by_standing = false;
    for v in vehicles {
        if v.speed_mps < CONFLICT_MIN_VEHICLE_SPEED_MPS {
            // A standing vehicle only matters when it physically blocks the next step.
            let next = pos + dir * params.lookahead.points_m.first().copied().unwrap_or(0.5);
            if ttc::distance_to_box_m(next, v.pose.pos, v.pose.heading_rad, v.half_length_m, v.half_width_m)
                < PED_RADIUS_M + BLOCKING_CLEARANCE_M
            {
                percept.conflict_vehicle = Some(v.id);
                percept.blocked_by_standing = true;
                break;
            }
            continue;
        }
        if v.pose.pos.distance_squared(pos) > reach_m * reach_m {
            continue;
        }
        if ttc::probes_hit_box(
            probes,
            v.pose.pos,
            v.pose.heading_rad,
            v.half_length_m,
            v.half_width_m,
            r,
        ) {
            percept.conflict_vehicle = Some(v.id);
            break;
        }
    }
}
