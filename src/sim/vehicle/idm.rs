//! Car following: the Intelligent Driver Model with vehicles **and** pedestrians in the path ahead as leaders,
//! junction conflict zones, the end of the route, and the ego's braking rule for crossing pedestrians.

use super::super::signals::LightState;
use super::conflict_zones::{ConflictZone, zone_yield_gap_m};
use super::{PedView, Vehicle};
use crate::sim::PED_RADIUS_M;
use crate::spec::types::Idm;

/// Lateral margin of the vehicle corridor beyond half the vehicle width, metres.
const VEHICLE_CORRIDOR_MARGIN_M: f64 = 0.4;
/// Lateral margin of the corridor for pedestrians, metres.
const PED_CORRIDOR_MARGIN_M: f64 = 0.6;

/// The ego stops at least this many metres short of a waiting pedestrian per metre it stands to the side (1.4:
/// about 35° off the heading, inside the camera's 45° half field of view).
const COURTESY_STOP_PER_LATERAL: f64 = 1.4;
/// A yielding ego rolls up to this fraction of the distance a waiting crosser waits for it to come within.
const COURTESY_INVITE_FRACTION: f64 = 0.7;
/// ... but its front stops at least this far short of the pedestrian (along its path), metres.
const COURTESY_MIN_STOP_SHORT_M: f64 = 2.0;
/// A vehicle stopping for a light aims this far short of the stop line, metres.
const STOP_LINE_MARGIN_M: f64 = 1.0;
/// Time constant of the ego's easing off to its courtesy speed, seconds.
const COURTESY_RESPONSE_S: f64 = 1.5;

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
    if me.yielding {
        // Stopping for an emergency vehicle, at a comfortable rate.
        accel = accel.min(-idm.comfortable_decel_mps2.min(v / 0.5));
    }

    // A red or amber light at a line it has not committed to (it could stop when it first saw it): a standing
    // obstacle at the stop line.
    if let Some((gap, _)) = me
        .light_ahead
        .filter(|&(_, state)| state != LightState::Green && me.bound_by_light())
    {
        // Aim a little short of the line, so that the car-following's overshoot never crosses it.
        let short = (gap - STOP_LINE_MARGIN_M).max(0.0);
        accel = accel.min(idm_to(short + me.min_gap_m, 0.0));
        let need = v * v / (2.0 * short.max(0.05));
        if need > idm.comfortable_decel_mps2 {
            accel = accel.min(-need.min(idm.max_decel_mps2));
        }
    }

    // End of route: a standing obstacle.
    let end_gap = me.path.length_m() - me.s_m - me.half_length_m;
    if end_gap < look {
        accel = accel.min(idm_to(end_gap + me.min_gap_m, 0.0));
    }

    for (j, other) in vehicles.iter().enumerate() {
        if j == i {
            continue;
        }
        let d = other.pose.pos - me.pose.pos;
        if d.length_squared() > (look + (me.half_length_m + other.half_length_m)).powi(2) || d.dot(fwd) <= 0.0 {
            continue;
        }
        // Moving out to overtake a cyclist: behind it until far enough out to pass with the clearance.
        let passing = me.overtaking.is_some_and(|(c, _)| c == j);
        let in_path = if passing && (me.lane_offset_m - me.target_offset_m).abs() > 0.05 {
            vehicle_in_path_unshifted(me, other, look)
        } else {
            vehicle_in_path(me, other, look)
        };
        let Some((gap, lead_speed)) = in_path else {
            continue;
        };
        // Mutual intrusion (both in each other's path, e.g. at a junction): the lower id goes first, the ego
        // before everyone -- unless the other is right in front (then both wait rather than touch).
        if gap > 1.0 && vehicle_in_path(other, me, lookahead_m(other.speed_mps, idm)).is_some() && me.id < other.id {
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
    let ped_margin = if me.is_cyclist() {
        super::CYCLIST_PED_MARGIN_M
    } else {
        PED_CORRIDOR_MARGIN_M
    };
    for p in peds {
        let d = p.pos - me.pose.pos;
        if d.length_squared() > (look + me.half_length_m).powi(2) || d.dot(fwd) <= 0.0 {
            continue;
        }
        let mut corridor = me.half_width_m + PED_RADIUS_M + ped_margin;
        if p.crossing {
            // A crosser walking towards the path counts a second early.
            corridor += p.velocity.length();
        }
        // Farther from the path than this, the pedestrian matters neither as a leader nor to the ego's rule.
        let reach = match me.ego_brake_m {
            Some((_, side)) if p.crossing => corridor.max(side),
            _ => corridor,
        };
        let Some((s_p, lateral, _)) = me.path.project(
            p.pos,
            me.s_m,
            me.s_m + look + me.half_length_m,
            reach + me.lane_offset_m.abs(),
        ) else {
            continue;
        };
        if s_p <= me.s_m {
            continue;
        }
        let lateral = me.corridor_lateral_m(p.pos, s_p, lateral);
        let gap = s_p - me.s_m - me.half_length_m - PED_RADIUS_M;
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

    // The ego's courtesy: it eases off, at a comfortable rate, for a pedestrian heading for the curb ahead, and
    // stops short of one waiting there attentively, until its patience for waiting runs out.
    if let Some(c) = me.courtesy {
        let mut approaching = false;
        for p in peds.iter().filter(|p| p.approaching_curb) {
            let Some((s_p, lateral, _)) = me.path.project(p.pos, me.s_m, me.s_m + c.ahead_m, c.lateral_m) else {
                continue;
            };
            // Only pedestrians beside the zone: `project` clamps to the zone's end, which would make a disc
            // of `lateral_m` beyond it count too.
            if s_p <= me.s_m || s_p >= me.s_m + c.ahead_m {
                continue;
            }
            approaching = true;
            if p.waiting_at_curb && !c.patience_spent() {
                // Far enough back that the pedestrian stays in the driver's (and the camera's) view (IDM's
                // minimum gap short of that); for one that waits for the ego to come near, near enough for it to
                // go: the ego's centre rolls up to within `COURTESY_INVITE_FRACTION` of that distance, its front
                // at least `COURTESY_MIN_STOP_SHORT_M` short of the pedestrian.
                let gap = match p.steps_out_ego_within_m.filter(|_| c.roll_up) {
                    Some(d) => {
                        let along_m = ((COURTESY_INVITE_FRACTION * d).powi(2) - lateral * lateral)
                            .max(0.0)
                            .sqrt();
                        let stop_short = (along_m - me.half_length_m)
                            .min(c.stop_short_m)
                            .max(COURTESY_MIN_STOP_SHORT_M);
                        s_p - me.s_m - me.half_length_m - stop_short + me.min_gap_m
                    }
                    None => {
                        let stop_short = c.stop_short_m.max(COURTESY_STOP_PER_LATERAL * lateral);
                        s_p - me.s_m - me.half_length_m - stop_short
                    }
                };
                accel = accel.min(idm_to(gap.max(0.0), 0.0));
            }
        }
        if approaching {
            let target = me.target_speed_mps().min(c.speed_mps);
            let ease = ((target - v) / COURTESY_RESPONSE_S).clamp(-idm.comfortable_decel_mps2, idm.max_accel_mps2);
            accel = accel.min(ease);
        }
    }
    accel
}

/// If `other`'s footprint intrudes on the corridor of `me`'s path ahead within `look` metres: the gap from
/// `me`'s front bumper to it along the path and its speed along the path.
fn vehicle_in_path(me: &Vehicle, other: &Vehicle, look: f64) -> Option<(f64, f64)> {
    in_corridor(me, other, look, true)
}

/// [`vehicle_in_path`] with `me`'s corridor on its path's centre line (a cyclist rides there: a vehicle about
/// to overtake one stays behind it until it has moved out).
pub(crate) fn vehicle_in_path_unshifted(me: &Vehicle, other: &Vehicle, look: f64) -> Option<(f64, f64)> {
    in_corridor(me, other, look, false)
}

fn in_corridor(me: &Vehicle, other: &Vehicle, look: f64, shifted: bool) -> Option<(f64, f64)> {
    // The footprint's lateral extent is at most its half diagonal, so a centre farther than this is clear.
    let reach = me.half_width_m
        + VEHICLE_CORRIDOR_MARGIN_M
        + other.half_length_m.hypot(other.half_width_m)
        + me.lane_offset_m.abs()
        + 1e-6;
    let (s_o, lateral, path_heading) = me.path.project(
        other.pose.pos,
        me.s_m,
        me.s_m + look + (me.half_length_m + other.half_length_m),
        reach,
    )?;
    if s_o <= me.s_m {
        return None;
    }
    let lateral = if shifted {
        me.corridor_lateral_m(other.pose.pos, s_o, lateral)
    } else {
        lateral
    };
    let delta = other.pose.heading_rad - path_heading;
    let (sd, cd) = (delta.sin().abs(), delta.cos().abs());
    let extent_lat = other.half_length_m * sd + other.half_width_m * cd;
    let extent_long = other.half_length_m * cd + other.half_width_m * sd;
    if lateral - extent_lat >= me.half_width_m + VEHICLE_CORRIDOR_MARGIN_M {
        return None;
    }
    let gap = s_o - me.s_m - me.half_length_m - extent_long;
    Some((gap, (other.speed_mps * delta.cos()).max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

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
