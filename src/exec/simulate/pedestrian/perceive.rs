//! Perception: what a pedestrian knows of the traffic at the start of a step (every decision of the step uses
//! it): TTC against every vehicle in range, where the ego is, and on the road the lookahead conflict.

use glam::DVec2;

use super::Ped;
use super::params::{BLOCKING_CLEARANCE_M, CONFLICT_MIN_VEHICLE_SPEED_MPS};
use super::state::Activity;
use crate::exec::simulate::vehicle::{HALF_LENGTH_M, HALF_WIDTH_M, Vehicle};
use crate::exec::simulate::{PED_RADIUS_M, ttc};
use crate::exec::trace::VehicleId;
use crate::planner::SimParams;

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
    /// The vehicle of a lookahead conflict this step (own probes; crossing pedestrians on the road only).
    pub conflict_vehicle: Option<VehicleId>,
    /// Whether the last lookahead conflict seen on the road was a standing vehicle blocking the way (kept until
    /// the next lookahead on the road).
    pub blocked_by_standing: bool,
}

impl Default for Percept {
    fn default() -> Self {
        Percept {
            min_ttc_s: f64::INFINITY,
            min_ttc_others_s: f64::INFINITY,
            nearest_vehicle_m: f64::INFINITY,
            ego_dist_m: f64::INFINITY,
            ego_ahead: true,
            conflict_vehicle: None,
            blocked_by_standing: false,
        }
    }
}

/// Updates `p.percept` from the vehicles' state at the start of the step (`vehicles[0]` is the ego).
/// `probes` is scratch space.
pub(crate) fn perceive(p: &mut Ped, vehicles: &[Vehicle], params: &SimParams, probes: &mut Vec<DVec2>) {
    let Some((ego, traffic)) = vehicles.split_first() else {
        return;
    };
    let pos = p.body.pos;
    let range_m = params.gap_acceptance.vehicle_range_m;
    let percept = &mut p.percept;
    percept.min_ttc_s = ttc::min_ttc_s(pos, vehicles.iter().map(|v| (v.pose.pos, v.velocity())), range_m);
    percept.min_ttc_others_s = ttc::min_ttc_s(pos, traffic.iter().map(|v| (v.pose.pos, v.velocity())), range_m);
    percept.nearest_vehicle_m = vehicles
        .iter()
        .map(|v| v.pose.pos.distance(pos))
        .fold(f64::INFINITY, f64::min);
    percept.ego_dist_m = ego.pose.pos.distance(pos);
    percept.ego_ahead = ego.s_m < p.traits.route_s_m;
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
            if ttc::distance_to_box_m(next, v.pose.pos, v.pose.heading_rad, HALF_LENGTH_M, HALF_WIDTH_M)
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
        if ttc::probes_hit_box(probes, v.pose.pos, v.pose.heading_rad, HALF_LENGTH_M, HALF_WIDTH_M, r) {
            percept.conflict_vehicle = Some(v.id);
            break;
        }
    }
}
