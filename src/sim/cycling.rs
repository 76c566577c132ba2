//! Cyclists among the traffic: a cyclist swerves around a pedestrian standing in its path at the lane's edge
//! (and brakes when the swerve is not enough: the car-following model does that), and a motor vehicle behind a
//! slower cyclist moves out to overtake it with `traffic.cyclists.overtaking_clearance_m` when the oncoming side
//! is clear, then moves back in. Both only set where the agents head across their lanes; the car-following
//! model ([`super::vehicle::accel_for`]) keeps a vehicle behind the cyclist until it has moved out.
//!
//! Recorded: [`Event::OvertookCyclist`] with the smallest side-to-side clearance while alongside, and
//! [`Event::CyclistYielded`] when a cyclist swerves around or brakes for a pedestrian.

use std::f64::consts::{PI, TAU};

use glam::DVec2;

use super::PED_RADIUS_M;
use super::vehicle::{CYCLIST_PED_MARGIN_M, PedView, Vehicle, vehicle_in_path_unshifted};
use crate::sim::trace::{Event, PedestrianId, VehicleId};
use crate::spec::types::{Cyclists, Idm};

/// A cyclist reacts to pedestrians up to this far ahead, metres.
const CYCLIST_LOOK_M: f64 = 15.0;
/// ... and keeps reacting to one until it is this far behind its rear, metres.
const CYCLIST_PASSED_M: f64 = 1.0;
/// A cyclist swerves around a pedestrian moving across its path slower than this, m/s (faster ones: it brakes).
const SWERVE_MAX_CROSS_SPEED_MPS: f64 = 0.5;
/// A vehicle considers overtaking a cyclist at most this far ahead (front bumper to the bicycle), metres.
const OVERTAKE_START_GAP_M: f64 = 25.0;
/// ... when the cyclist is at least this much slower than the speed it wants, m/s.
const OVERTAKE_MIN_SPEED_GAIN_MPS: f64 = 1.0;
/// The oncoming side is clear when no vehicle comes the other way within at least this distance ahead, metres.
const OVERTAKE_ONCOMING_CLEAR_M: f64 = 80.0;
/// ... and this far to the side of the vehicle, metres ...
const OVERTAKE_ONCOMING_LATERAL_M: f64 = 8.0;
/// ... nor one that would come within this distance before the pass is over, metres.
const OVERTAKE_ONCOMING_MARGIN_M: f64 = 20.0;
/// An overtake is complete when the vehicle's rear is this far past the bicycle's front, metres.
const OVERTAKE_DONE_M: f64 = 2.0;
/// An overtake counts only if the vehicle came this close to the cyclist while alongside, metres (else their
/// paths had parted and it passed nobody).
const OVERTAKE_ALONGSIDE_MAX_M: f64 = 3.0;
/// A vehicle overtakes only where its path turns by less than this over the whole pass and
/// [`OVERTAKE_STRAIGHT_M`] beyond (the way back in), radians ...
const OVERTAKE_MAX_TURN_RAD: f64 = 0.15;
/// ... see [`OVERTAKE_MAX_TURN_RAD`], metres ...
const OVERTAKE_STRAIGHT_M: f64 = 20.0;
/// ... checked every this many metres.
const OVERTAKE_STRAIGHT_STEP_M: f64 = 5.0;
/// A vehicle does not start a pass that would take longer than this at its speeds, seconds.
const OVERTAKE_MAX_S: f64 = 12.0;
/// An overtake is given up (without an event) when the cyclist is farther than this, metres (their paths
/// parted at a junction).
const OVERTAKE_LOST_M: f64 = 40.0;
/// A cyclist braking harder than this for a pedestrian in its corridor yields to it, m/s².
const CYCLIST_BRAKE_MPS2: f64 = 1.0;

/// Sets where each cyclist and each overtaking vehicle heads across its lane this step (from the state at the
/// start of the vehicles' step, the pedestrians already moved).
pub(super) fn decide(vehicles: &mut [Vehicle], peds: &[PedView], c: &Cyclists, idm: &Idm) {
    // Cyclists: swerve around a pedestrian standing in the riding line, where the swerve clears it.
    for v in vehicles.iter_mut().filter(|v| v.is_cyclist()) {
        v.swerving_for = None;
        v.follow_bike_lane();
        v.target_offset_m = v.ride_offset_m;
        if let Some((k, left_m)) = nearest_ped_in_line(v, peds) {
            let p = &peds[k];
            let across = p.velocity.dot(v.pose.dir.perp()).abs();
            let corridor = corridor_m(v);
            let ride_centre = -v.ride_offset_m;
            let swerved_centre = ride_centre + c.swerve_m;
            if across < SWERVE_MAX_CROSS_SPEED_MPS
                && (left_m - ride_centre).abs() < corridor
                && left_m <= ride_centre + 0.5 * corridor
                && (left_m - swerved_centre).abs() >= corridor
            {
                v.swerving_for = Some(k);
                v.target_offset_m = v.ride_offset_m - c.swerve_m;
            }
        }
    }
    // Motor vehicles: overtake a slower cyclist ahead when the oncoming side is clear.
    for i in 0..vehicles.len() {
        if vehicles[i].is_cyclist() {
            continue;
        }
        if let Some((j, _)) = vehicles[i].overtaking {
            let (me, cyc) = (&vehicles[i], &vehicles[j]);
            let shift = c.overtaking_clearance_m + me.half_width_m + cyc.half_width_m - cyc.lane_offset_m;
            vehicles[i].target_offset_m = -shift.max(0.0);
            continue;
        }
        vehicles[i].target_offset_m = 0.0;
        let me = &vehicles[i];
        let target = me.target_speed_mps();
        let candidate = vehicles.iter().enumerate().find_map(|(j, cyc)| {
            if !cyc.is_cyclist() || cyc.pose.dir.dot(me.pose.dir) <= 0.8 {
                return None;
            }
            vehicle_in_path_unshifted(me, cyc, OVERTAKE_START_GAP_M)
                .filter(|&(gap, lead_mps)| {
                    gap < OVERTAKE_START_GAP_M && lead_mps + OVERTAKE_MIN_SPEED_GAIN_MPS < target
                })
                .map(|(gap, lead_mps)| (j, gap, lead_mps))
        });
        let Some((j, gap, lead_mps)) = candidate else { continue };
        // The pass takes until its rear is past the bicycle's front: the oncoming side must stay clear that long
        // at both vehicles' speeds, with a margin.
        let pass_m = gap + 2.0 * (me.half_length_m + vehicles[j].half_length_m) + OVERTAKE_DONE_M;
        let pass_s = pass_m / (target - lead_mps).max(0.5);
        let oncoming = vehicles.iter().any(|o| {
            let d = o.pose.pos - me.pose.pos;
            let clear_m = OVERTAKE_ONCOMING_CLEAR_M.max((target + o.speed_mps) * pass_s + OVERTAKE_ONCOMING_MARGIN_M);
            !o.is_cyclist()
                && o.pose.dir.dot(me.pose.dir) < -0.5
                && (-5.0..clear_m).contains(&d.dot(me.pose.dir))
                && d.dot(me.pose.dir.perp()).abs() < OVERTAKE_ONCOMING_LATERAL_M
        });
        // Only where the whole pass (the distance driven while passing, and the way back in) is straight.
        let pass_along_m = target * pass_s + OVERTAKE_STRAIGHT_M;
        if pass_s > OVERTAKE_MAX_S || me.s_m + pass_along_m > me.path.length_m() {
            continue;
        }
        let steps = (pass_along_m / OVERTAKE_STRAIGHT_STEP_M).ceil() as usize;
        let bends = (1..=steps).any(|k| {
            let ahead = me.path.pose_at(me.s_m + pass_along_m * k as f64 / steps as f64);
            let turn = (ahead.heading_rad - me.pose.heading_rad + PI).rem_euclid(TAU) - PI;
            turn.abs() > OVERTAKE_MAX_TURN_RAD
        });
        if bends {
            continue;
        }
        let stopping = me.light_ahead.is_some_and(|(gap, _)| gap < OVERTAKE_ONCOMING_CLEAR_M) || me.yielding;
        if !oncoming && !stopping && idm.max_accel_mps2 > 0.0 {
            vehicles[i].overtaking = Some((j, f64::INFINITY));
            let (me, cyc) = (&vehicles[i], &vehicles[j]);
            let shift = c.overtaking_clearance_m + me.half_width_m + cyc.half_width_m - cyc.lane_offset_m;
            vehicles[i].target_offset_m = -shift.max(0.0);
        }
    }
}

/// After the vehicles moved to frame `frame`: the overtakes' clearance while alongside and their end
/// ([`Event::OvertookCyclist`]), and each cyclist's first swerve around, or braking for, a pedestrian
/// ([`Event::CyclistYielded`], once per cyclist, pedestrian and kind; `seen` keeps which were recorded).
pub(super) fn record(
    frame: u32,
    vehicles: &mut [Vehicle],
    accels: &[f64],
    peds: &[PedView],
    seen: &mut Vec<(u32, u32, bool)>,
    events: &mut Vec<Event>,
) {
    for i in 0..vehicles.len() {
        let Some((j, min_clearance_m)) = vehicles[i].overtaking else {
            continue;
        };
        let (me, cyc) = (&vehicles[i], &vehicles[j]);
        let d = cyc.pose.pos - me.pose.pos;
        let along = d.dot(me.pose.dir);
        let reach = me.half_length_m + cyc.half_length_m;
        let mut min_clearance_m = min_clearance_m;
        if along.abs() < reach {
            min_clearance_m = min_clearance_m.min(footprint_gap_m(me, cyc));
        }
        let VehicleId::Cyclist(cyclist) = cyc.id else {
            continue;
        };
        if along < -(reach + OVERTAKE_DONE_M) && min_clearance_m < OVERTAKE_ALONGSIDE_MAX_M {
            events.push(Event::OvertookCyclist {
                frame,
                vehicle: me.id,
                cyclist,
                min_clearance_m,
            });
            vehicles[i].overtaking = None;
            vehicles[i].target_offset_m = 0.0;
        } else if d.length() > OVERTAKE_LOST_M || along < -(reach + OVERTAKE_DONE_M) {
            vehicles[i].overtaking = None;
            vehicles[i].target_offset_m = 0.0;
        } else {
            vehicles[i].overtaking = Some((j, min_clearance_m));
        }
    }
    for (v, &a) in vehicles.iter().zip(accels) {
        let VehicleId::Cyclist(cyclist) = v.id else {
            continue;
        };
        let reaction = match v.swerving_for {
            Some(k) => Some((k, true)),
            None if a < -CYCLIST_BRAKE_MPS2 => nearest_ped_in_line(v, peds)
                .filter(|&(k, left_m)| (left_m + v.lane_offset_m).abs() < corridor_m(v) + peds[k].velocity.length())
                .map(|(k, _)| (k, false)),
            None => None,
        };
        if let Some((k, swerved)) = reaction {
            let key = (cyclist, k as u32, swerved);
            if !seen.contains(&key) {
                seen.push(key);
                events.push(Event::CyclistYielded {
                    frame,
                    cyclist,
                    pedestrian: PedestrianId(k as u32),
                    swerved,
                });
            }
        }
    }
}

/// The distance between two vehicles' footprints (0 when they overlap), metres: for two rectangles apart,
/// the nearest points include a corner of one of them.
fn footprint_gap_m(a: &Vehicle, b: &Vehicle) -> f64 {
    let corners = |v: &Vehicle| {
        let (f, l) = (v.pose.dir * v.half_length_m, v.pose.dir.perp() * v.half_width_m);
        [
            v.pose.pos + f + l,
            v.pose.pos + f - l,
            v.pose.pos - f + l,
            v.pose.pos - f - l,
        ]
    };
    let to_box = |p: DVec2, v: &Vehicle| {
        super::ttc::distance_to_box_m(p, v.pose.pos, v.pose.heading_rad, v.half_length_m, v.half_width_m)
    };
    let ab = corners(a)
        .into_iter()
        .map(|p| to_box(p, b))
        .fold(f64::INFINITY, f64::min);
    let ba = corners(b)
        .into_iter()
        .map(|p| to_box(p, a))
        .fold(f64::INFINITY, f64::min);
    ab.min(ba)
}

/// Half the width of a cyclist's corridor for pedestrians, metres.
fn corridor_m(v: &Vehicle) -> f64 {
    v.half_width_m + PED_RADIUS_M + CYCLIST_PED_MARGIN_M
}

/// The nearest pedestrian (index, metres left of the path) ahead of (or beside) cyclist `v` within
/// [`CYCLIST_LOOK_M`] and near its riding line (within the corridor plus the swerve room of 2 m).
fn nearest_ped_in_line(v: &Vehicle, peds: &[PedView]) -> Option<(usize, f64)> {
    let reach = corridor_m(v) + v.ride_offset_m + 2.0;
    let mut best: Option<(f64, usize, f64)> = None;
    for (k, p) in peds.iter().enumerate() {
        let d: DVec2 = p.pos - v.pose.pos;
        if d.length_squared() > (CYCLIST_LOOK_M + reach).powi(2) {
            continue;
        }
        let from = v.s_m - v.half_length_m - CYCLIST_PASSED_M;
        let Some((s_p, _, _)) = v.path.project(p.pos, from, v.s_m + CYCLIST_LOOK_M, reach) else {
            continue;
        };
        let left_m = v.signed_lateral_m(p.pos, s_p);
        // Only those within the corridor of the riding line or of the swerved line.
        if (left_m + v.ride_offset_m).abs() >= corridor_m(v) + 2.0 {
            continue;
        }
        if best.is_none_or(|(s, _, _)| s_p < s) {
            best = Some((s_p, k, left_m));
        }
    }
    best.map(|(_, k, left)| (k, left))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::vehicle::path::tests::winding_path;

    /// A cyclist 2 m along the winding path's first straight, riding 0.9 m right of it at 5 m/s.
    fn cyclist() -> Vehicle {
        let mut v = Vehicle::new(VehicleId::Cyclist(0), winding_path(), 2.0, 1.0, 1.0, 1.0, false, None);
        v.half_length_m = 0.875;
        v.half_width_m = 0.325;
        v.cruise_mps = Some(5.0);
        v.ride_offset_m = 0.9;
        v.lane_offset_m = 0.9;
        v.speed_mps = 5.0;
        v
    }

    /// A pedestrian `ahead_m` ahead of the cyclist along its path, `left_m` left of the path.
    fn ped(v: &Vehicle, ahead_m: f64, left_m: f64, velocity: DVec2) -> PedView {
        let at = v.path.pose_at(v.s_m + ahead_m);
        PedView {
            pos: at.pos + at.dir.perp() * left_m,
            velocity,
            crossing: velocity != DVec2::ZERO,
            approaching_curb: false,
            waiting_at_curb: false,
            steps_out_ego_within_m: None,
        }
    }

    /// A pedestrian standing on the riding line ahead: the cyclist swerves left by `swerve_m`; one walking
    /// across it, or standing left of the line (where a swerve would lead), is braked for instead.
    #[test]
    fn a_cyclist_swerves_around_a_standing_pedestrian_and_brakes_for_others() {
        let c = Cyclists::default();
        let idm = Idm::default();
        let mut vehicles = vec![cyclist()];
        let standing = [ped(&vehicles[0], 6.0, -0.9, DVec2::ZERO)];
        decide(&mut vehicles, &standing, &c, &idm);
        assert_eq!(vehicles[0].swerving_for, Some(0));
        assert!((vehicles[0].target_offset_m - (0.9 - c.swerve_m)).abs() < 1e-12);
        // Once swerved, the standing pedestrian is outside the car-following corridor: no braking for it.
        vehicles[0].lane_offset_m = vehicles[0].target_offset_m;
        let a = crate::sim::vehicle::accel_for(0, &vehicles, &[], &standing, &idm);
        assert!(a > -0.1, "no braking once swerved: {a}");
        // Walking across the riding line: no swerve, and the car-following brakes.
        let mut vehicles = vec![cyclist()];
        let dir = vehicles[0].pose.dir.perp();
        let walking = [ped(&vehicles[0], 6.0, -0.9, dir * 1.3)];
        decide(&mut vehicles, &walking, &c, &idm);
        assert_eq!(vehicles[0].swerving_for, None);
        let a = crate::sim::vehicle::accel_for(0, &vehicles, &[], &walking, &idm);
        assert!(a < -1.0, "brakes for a walker crossing its line: {a}");
        // Standing at the lane's centre line, left of the riding line: no swerve towards it.
        let mut vehicles = vec![cyclist()];
        let left = [ped(&vehicles[0], 6.0, -0.1, DVec2::ZERO)];
        decide(&mut vehicles, &left, &c, &idm);
        assert_eq!(vehicles[0].swerving_for, None);
        // Nobody near the line: it rides on.
        let mut vehicles = vec![cyclist()];
        let far = [ped(&vehicles[0], 6.0, 4.0, DVec2::ZERO)];
        decide(&mut vehicles, &far, &c, &idm);
        assert_eq!(vehicles[0].swerving_for, None);
        assert_eq!(vehicles[0].target_offset_m, 0.9);
    }

    /// Two footprints side by side are as far apart as their sides; overlapping ones are 0 apart.
    #[test]
    fn the_footprint_gap_is_the_distance_between_the_boxes() {
        let mut car = Vehicle::new(VehicleId::Ego, winding_path(), 10.0, 1.0, 1.0, 1.0, false, None);
        let mut bike = cyclist();
        bike.s_m = 10.0;
        bike.lane_offset_m = 0.0;
        car.lane_offset_m = -2.0;
        car.place();
        bike.place();
        let gap = footprint_gap_m(&car, &bike);
        let want = 2.0 - car.half_width_m - bike.half_width_m;
        assert!((gap - want).abs() < 1e-6, "{gap} vs {want}");
        car.lane_offset_m = -0.5;
        car.place();
        assert_eq!(footprint_gap_m(&car, &bike), 0.0);
    }
}
