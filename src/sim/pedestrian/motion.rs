//! Motion: the two modes of the paper's hybrid control, and the head.
//!
//! - **AI mode** (sidewalk states): walking along the sidewalk graph (crosswalk edges excluded, never onto a
//!   driving lane) or to the curb point of a planned crossing, with simple avoidance of other pedestrians.
//! - **Manual mode** (crossing states, retreat, finishing): direct velocity control along the crossing vector.

use glam::DVec2;
use rand::RngExt;
use rand_chacha::ChaCha20Rng;

use super::params::{
    ACKNOWLEDGE_WINDOW_S, AVOID_RADIUS_M, BRIEF_SCAN_S, CURB_ARRIVAL_M, CURB_SLOWDOWN_M, CURB_SLOWDOWN_MIN,
    CURB_STANDOFF_M, DISTRACTION_STANDSTILL, FOLLOWER_SPEED_SLACK, FULL_SCAN_S, GESTURE_EGO_MAX_DIST_M,
    GESTURE_EGO_MAX_SPEED_MPS, HEADING_MIN_STEP_M, IDLE_HEAD_SWAY, LINE_OFFSET_KEEP, LOOK_AROUND_HEAD,
    MAX_HEAD_TURN_RAD, SCAN_INTERVAL_MEAN_S, STRIDE_M, WALKER_MAX_SKIPS, WALKER_NODE_REACHED_M,
};
use super::state::{Activity, Attempt, CrossMode, PauseCause};
use super::{LeaderFacts, Ped, StepCtx};
use crate::sim::trace::{Gesture, Reaction};
use crate::sim::vehicle::Vehicle;
use crate::spec::types::Gestures;
use crate::world::LaneType;

/// Time until the next attention-driven scan of a walker, seconds (more attentive: more often).
pub(crate) fn scan_interval_s(rng: &mut ChaCha20Rng, attention: f64) -> f64 {
    let mean_s = SCAN_INTERVAL_MEAN_S.0 + SCAN_INTERVAL_MEAN_S.1 * (1.0 - attention.clamp(0.0, 1.0));
    let u: f64 = rng.random_range(1e-6..1.0);
    -mean_s * u.ln()
}

/// How long a scan lasts, seconds (attentive pedestrians look longer).
pub(crate) fn scan_duration_s(attention: f64, brief: bool) -> f64 {
    let (base, per_attention) = if brief { BRIEF_SCAN_S } else { FULL_SCAN_S };
    base + per_attention * attention
}

/// Desired velocity of a pedestrian in AI mode (sidewalk), before avoidance.
fn ai_velocity(p: &mut Ped, ctx: &StepCtx, speed: f64) -> DVec2 {
    if speed <= 0.0 {
        return DVec2::ZERO;
    }
    let pos = p.body.pos;
    if !p.attempt.over() {
        // Walking to the curb point of the planned crossing.
        let Some(line) = p.traits.line else {
            return DVec2::ZERO;
        };
        let to = line.curb_point() - pos;
        let d = to.length();
        if d < CURB_ARRIVAL_M {
            p.attempt.reach_curb();
            return DVec2::ZERO;
        }
        // Slowing down over the last metres to the curb.
        let slowed = speed * (d / CURB_SLOWDOWN_M).clamp(CURB_SLOWDOWN_MIN, 1.0);
        return to / d * slowed.min(d / ctx.dt_s);
    }
    if p.traits.standing || !p.walker.active {
        return DVec2::ZERO;
    }
    let mut target = p.walker.target(ctx.net);
    let mut skips = 0;
    while (target - pos).length() < WALKER_NODE_REACHED_M && skips < WALKER_MAX_SKIPS {
        let heading = (target - pos)
            .try_normalize()
            .unwrap_or_else(|| DVec2::from_angle(p.body.yaw_rad));
        p.walker.advance(ctx.net, heading);
        target = p.walker.target(ctx.net);
        skips += 1;
    }
    let to = target - pos;
    let d = to.length();
    if d < 1e-9 {
        return DVec2::ZERO;
    }
    to / d * speed.min(d / ctx.dt_s)
}

/// Moves pedestrian `self_index` for one step. `others` are every pedestrian's positions at the start of the
/// step (for avoidance); `leader` is set for group followers.
pub(crate) fn move_ped(p: &mut Ped, ctx: &StepCtx, others: &[DVec2], self_index: usize, leader: Option<&LeaderFacts>) {
    let m = &ctx.params.speed_profiles.multipliers;
    let dt = ctx.dt_s;
    let old = p.body.pos;
    let finishing = p.activity == Activity::FinishedCrossing;
    let manual = p.activity.crossing_motion() || finishing;
    let mut new_pos;
    if manual && let Some(line) = p.traits.line {
        let along = line.along_m(old);
        let on_line = line.near_curb + line.dir * along;
        let off = old - on_line;
        if let (Some(l), false) = (leader, finishing) {
            // Followers keep their leader's progress along their own line.
            let step = line.near_curb + line.dir * (l.fraction * line.width_m) + off * LINE_OFFSET_KEEP - old;
            // Never faster than its own speed in this state (with slack for a wider line than the leader's).
            new_pos = old + clamp_length(step, FOLLOWER_SPEED_SLACK * p.own_speed_mps(m) * dt);
        } else {
            let retreat = p.activity == Activity::Retreat;
            let speed = match p.activity {
                Activity::PausingMidCross { .. } => 0.0,
                Activity::Retreat => p.traits.retreat_speed_mps,
                _ if p.group_speed_mps > 0.0 && !finishing => p.group_speed_mps,
                _ => p.own_speed_mps(m),
            };
            let target_along = if retreat {
                (along - speed * dt).max(-CURB_STANDOFF_M)
            } else {
                (along + speed * dt).min(line.end_along_m())
            };
            // Manual control: along the crossing vector, pulled back onto the line if off it, never faster
            // than the state's speed.
            let step = line.near_curb + line.dir * target_along + off * LINE_OFFSET_KEEP - old;
            new_pos = old + clamp_length(step, speed * dt);
        }
    } else {
        let speed = match p.activity {
            Activity::DistractedBehavior { .. } => {
                let f = p.state_time_s / p.traits.distraction_len_s.max(1e-6);
                if DISTRACTION_STANDSTILL.contains(&f) {
                    0.0
                } else {
                    p.own_speed_mps(m)
                }
            }
            _ if p.holds_for_ego(p.own_speed_mps(m)) => 0.0,
            _ => p.own_speed_mps(m),
        };
        let mut v = ai_velocity(p, ctx, speed);
        // On the last metres to its curb point a crosser steps onto its spot: pushed aside by a neighbour waiting
        // there (a group member on a parallel line, someone else's spot), it would never arrive.
        let final_approach = !p.attempt.over()
            && !p.attempt.at_curb()
            && p.traits
                .line
                .is_some_and(|l| l.curb_point().distance(old) < CURB_SLOWDOWN_M);
        if speed > 0.0 && v != DVec2::ZERO && !final_approach {
            // Simple avoidance: a push away from pedestrians closer than AVOID_RADIUS_M, speed capped.
            let mut push = DVec2::ZERO;
            for (j, &q) in others.iter().enumerate() {
                if j == self_index {
                    continue;
                }
                let d = old - q;
                let dist = d.length();
                if dist < AVOID_RADIUS_M && dist > 1e-6 {
                    push += d / dist * (AVOID_RADIUS_M - dist);
                }
            }
            if push != DVec2::ZERO {
                v += push * speed;
                let len = v.length();
                if len > speed {
                    v *= speed / len;
                }
            }
        }
        new_pos = old + v * dt;
    }
    // AI mode never steps onto a driving lane; the lane under the new position is recorded.
    let body = &mut p.body;
    let hit = ctx.net.lane_at(new_pos);
    if !manual
        && new_pos != old
        && hit.is_some_and(|h| h.lane_type == LaneType::Driving)
        && body.lane_type != Some(LaneType::Driving)
    {
        p.walker.turn_around();
        new_pos = old;
    } else if let Some(h) = hit {
        body.z_m = h.z_m;
        body.lane_type = Some(h.lane_type);
    } else {
        body.lane_type = None;
    }
    let step = new_pos - old;
    body.velocity = step / dt;
    body.pos = new_pos;
    let dist = step.length();
    if dist > HEADING_MIN_STEP_M {
        // Facing the way it walks (turned around when retreating).
        body.yaw_rad = step.y.atan2(step.x);
    } else if let Some(line) = p.traits.line
        && !p.attempt.over()
        && p.attempt.at_curb()
    {
        // Standing at its curb: facing the road.
        body.yaw_rad = line.dir.y.atan2(line.dir.x);
    }
    body.gait_phase = (body.gait_phase + dist / STRIDE_M).fract();
    p.state_time_s += dt;
    // The patience clock runs while waiting at the curb for a gap: once the crosser's timeline would let it go
    // (seen long enough, or the ego has passed), not while it waits for the approaching ego, nor while it waits
    // for "walk" at a signalised crosswalk (waiting for the signal is no gap to lose patience over).
    let trying = (!p.percept.ego_ahead || (p.seen_long_enough(0.0) && p.ego_near_enough())) && !p.waits_for_walk();
    if let Attempt::Undecided {
        at_curb: true,
        waited_s,
    } = &mut p.attempt
        && trying
    {
        *waited_s += dt;
    }
}

impl Ped {
    /// Head yaw relative to the body for this frame: scanning sweeps, checks look at the nearest vehicle, a
    /// gesture looks at the ego (`vehicles[0]`).
    pub(crate) fn update_head(&mut self, time_s: f64, vehicles: &[Vehicle]) {
        let pos = self.body.pos;
        let toward = |v: &Vehicle| {
            let d = v.pose.pos - pos;
            wrap(d.y.atan2(d.x) - self.body.yaw_rad).clamp(-MAX_HEAD_TURN_RAD, MAX_HEAD_TURN_RAD)
        };
        self.body.head_yaw_rad = match self.activity {
            _ if self.gesture.is_some() => vehicles.first().map_or(0.0, toward),
            Activity::LookingAround => {
                LOOK_AROUND_HEAD.0 * (std::f64::consts::TAU * LOOK_AROUND_HEAD.1 * self.state_time_s).sin()
            }
            Activity::CheckingTraffic
            | Activity::Hesitating
            | Activity::Crossing(CrossMode::RunningAcross)
            | Activity::PausingMidCross { .. } => {
                let nearest = vehicles.iter().min_by(|a, b| {
                    a.pose
                        .pos
                        .distance_squared(pos)
                        .total_cmp(&b.pose.pos.distance_squared(pos))
                });
                nearest.map_or(0.0, toward)
            }
            _ if self.on_phone() => 0.0,
            _ => IDLE_HEAD_SWAY.0 * (time_s * IDLE_HEAD_SWAY.1 + f64::from(self.traits.id.0)).sin(),
        };
    }

    /// Advances a gesture by `dt_s` and ends it when it is over; starts one the first time the ego yields to
    /// the pedestrian (ahead, near and slow): an acknowledgement by a crosser that has just stepped out, a
    /// wave-through by a hard negative checking the traffic at the curb, each with its probability, decided by
    /// the pedestrian's own gesture draws. At most one gesture per pedestrian; none on the phone.
    pub(crate) fn update_gesture(&mut self, dt_s: f64, ego: &Vehicle, g: &Gestures) {
        if let Some((kind, elapsed_s)) = &mut self.gesture {
            *elapsed_s += dt_s;
            if *elapsed_s >= kind.duration_s() {
                self.gesture = None;
            }
        }
        if self.on_phone() {
            // The phone takes the right hand and the eyes.
            self.gesture = None;
            return;
        }
        if self.gestured {
            return;
        }
        let yielding = self.percept.ego_ahead
            && ego.speed_mps < GESTURE_EGO_MAX_SPEED_MPS
            && ego.pose.pos.distance(self.body.pos) < GESTURE_EGO_MAX_DIST_M;
        if !yielding {
            return;
        }
        let (kind, probability) = match self.activity {
            Activity::Crossing(CrossMode::CrossingRoad | CrossMode::Jaywalking)
                if self.state_time_s <= ACKNOWLEDGE_WINDOW_S =>
            {
                let kind = if self.traits.gesture_draws.1 < g.nod_share {
                    Gesture::Nod
                } else {
                    Gesture::HandAck
                };
                (kind, g.acknowledge_probability)
            }
            Activity::CheckingTraffic if self.traits.curb_wait_s.is_some() => {
                (Gesture::HandYield, g.wave_through_probability)
            }
            _ => return,
        };
        self.gestured = true;
        if self.traits.gesture_draws.0 < probability {
            self.gesture = Some((kind, 0.0));
        }
    }

    /// The reaction to a vehicle that the current activity shows (JAAD's `reaction`).
    pub(crate) fn reaction(&self) -> Option<Reaction> {
        match self.activity {
            Activity::Crossing(CrossMode::RunningAcross) => Some(Reaction::SpeedUp),
            Activity::PausingMidCross {
                cause: PauseCause::Conflict { .. },
                ..
            } => Some(Reaction::SlowDown),
            Activity::Retreat => Some(Reaction::ClearPath),
            _ => None,
        }
    }
}

/// `v` shortened to at most `max_len` (never lengthened).
fn clamp_length(v: DVec2, max_len: f64) -> DVec2 {
    let len = v.length();
    if len > max_len && len > 0.0 {
        v * (max_len / len)
    } else {
        v
    }
}

/// An angle wrapped into (−π, π].
fn wrap(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    } else if a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    }
    a
}
