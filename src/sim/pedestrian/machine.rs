//! The behaviour machine: one transition per step for each pedestrian that decides for itself (a single or a
//! group leader), as one explicit `match` on its [`Activity`]; group followers copy their leader's.
//!
//! Triggers follow the paper's table of states: a timer or the crossing trigger ends WALKING_SIDEWALK, the
//! attention threshold drives LOOKING_AROUND, the TTC gap-acceptance rule ends CHECKING_TRAFFIC, hesitation
//! ends at the archetype's hesitation time, the in-road lookahead pauses or (once per conflict, with the
//! retreat probability, in the first part of the crossing) turns back a crosser, vehicle proximity makes it
//! run, the patience cap makes a waiting crosser give up or cross suddenly, phone use comes at its planned time.

use glam::DVec2;
use rand::RngExt;

use super::params::{
    BASELINE_CLEAR_M, BLOCKED_RETREAT_S, CHECK_MIN_S, COMFORTABLE_STOP_DECEL_MPS2, COMMIT_MIN_TTC_S, CONFLICT_CLEAR_S,
    CURB_STANDOFF_M, CUT_SHORT_EGO_DISTANCE_M, CUT_SHORT_EGO_SPEED_MPS, CUT_SHORT_MIN_IN_VIEW_S, DISTRACTION_PAUSE_S,
    FINISH_BEYOND_CURB_M, FINISHED_ARRIVAL_M, FINISHED_MAX_S, HESITATION_CUTOFF_M, JAYWALK_MIN_TTC_S, RUN_TTC_FRACTION,
    RUSHED_GAP_FACTOR, STOP_MARGIN_M, SUDDEN_FROM_CURB_M, SUDDEN_MIN_EGO_M,
};
use super::state::{Activity, AfterPhone, Attempt, CrossMode, Distraction, PauseCause};
use super::walker::SidewalkWalker;
use super::{LeaderFacts, Ped, StepCtx, motion};
use crate::plan::{Behaviour, CrosserSource, Role, SimParams, SpeedProfile};
use crate::sim::signals::WalkSignal;
use crate::sim::trace::{Event, PedState, VehicleId};
use crate::sim::ttc;

/// Enters `to`: a state change (event, timer reset) when its label differs from the current one.
fn enter(p: &mut Ped, to: Activity, frame: u32, events: &mut Vec<Event>) {
    let (from, label) = (p.state(), to.label());
    if from != label {
        events.push(Event::StateChange {
            frame,
            pedestrian: p.traits.id,
            from,
            to: label,
        });
        p.state_time_s = 0.0;
    }
    p.activity = to;
}

/// Takes the decision to cross (the intention onset), once.
fn decide_to_cross(p: &mut Ped, frame: u32, events: &mut Vec<Event>) {
    if p.attempt.decide() {
        events.push(Event::CrossingDecision {
            frame,
            pedestrian: p.traits.id,
        });
    }
}

fn switch_profile(p: &mut Ped, params: &SimParams, to: SpeedProfile) {
    if params.speed_profiles.switching {
        p.profile = to;
    }
}

/// Gives up the crossing attempt and walks off along the sidewalk, either way.
fn abandon(p: &mut Ped, ctx: &StepCtx) {
    p.attempt.end();
    let dir = p.traits.line.map_or(DVec2::X, |l| l.dir.perp());
    let side = if p.rng.random_bool(0.5) { 1.0 } else { -1.0 };
    p.walker = SidewalkWalker::start(ctx.net, p.body.pos, dir * side);
}

/// The gap-acceptance threshold of `p` for its crossing, seconds.
fn gap_threshold_s(p: &Ped, params: &SimParams) -> f64 {
    let width = p.traits.line.map_or(0.0, |l| l.width_m);
    let speed = p.traits.base_speed_mps * p.multiplier(&params.speed_profiles.multipliers);
    ttc::gap_threshold_s(p.traits.ttc_threshold_s, p.traits.safety_margin_s, width, speed)
}

/// Whether the ego's position allows an allocated crosser to commit: inside the decision window while
/// approaching, or already past.
fn ego_in_window_or_past(p: &Ped, params: &SimParams) -> bool {
    !p.percept.ego_ahead || ego_in_window(p, params)
}

/// Whether the ego approaches inside the decision window: no farther than its far edge, and no nearer than its
/// near edge unless it is slow enough to stop comfortably before the crossing (a driver easing off for the
/// pedestrian lets it go).
fn ego_in_window(p: &Ped, params: &SimParams) -> bool {
    let w = params.decision_window_m;
    let d = p.percept.ego_dist_m;
    p.percept.ego_ahead && d <= w.max() && (d >= w.min() || ego_can_stop(p))
}

/// Whether an allocated crosser may go now. The paper's crosser "commits to entering the road as soon as the
/// ego-vehicle is within the 10–40 m decision window" (the ego then brakes for it): inside the window it only
/// waits for another vehicle about to arrive (TTC below `COMMIT_MIN_TTC_S`); otherwise the full gap-acceptance
/// rule min TTC > τ_ttc + Δ_safety + w_road / s_cross applies to every vehicle in range.
fn gap_ok(p: &Ped, params: &SimParams) -> bool {
    if ego_in_window(p, params) {
        p.percept.min_ttc_others_s > COMMIT_MIN_TTC_S
    } else {
        ttc::gap_accepted(p.percept.min_ttc_s, gap_threshold_s(p, params))
    }
}

/// Whether the ego has reached the decision window (or passed): the sudden crosser's trigger.
fn ego_reached_window(p: &Ped, params: &SimParams) -> bool {
    !p.percept.ego_ahead || p.percept.ego_dist_m <= params.decision_window_m.max()
}

/// Whether a baseline (CARLA-like) crosser sees the road clear: no vehicle within a few metres, none about to
/// arrive (CARLA's stop-and-check).
fn baseline_clear(p: &Ped) -> bool {
    p.percept.nearest_vehicle_m > BASELINE_CLEAR_M && p.percept.min_ttc_s > JAYWALK_MIN_TTC_S
}

/// Whether the crosser's timeline lets it step out `lead_s` seconds from now: the ego's camera has seen it (and
/// its group's followers) for its planned time; or it has been seen briefly and the ego drives on close by (the
/// timeline is cut short, as real observations sometimes are); or the ego has passed (then no camera sees it
/// either way). Never while an emergency vehicle's siren is near: pedestrians hold at the curb.
fn timeline_allows(p: &Ped, lead_s: f64) -> bool {
    let percept = &p.percept;
    if percept.siren_near {
        // An emergency vehicle is coming: nobody steps out.
        return false;
    }
    if percept.walk.is_some_and(|w| w != WalkSignal::Walk) && !p.traits.red_light_violator {
        // A signalised crosswalk: wait for "walk" (those who cross against the signal go on their gap).
        return false;
    }
    // The ego drives on close by: a crosser seen at least briefly goes now rather than cross behind it, unseen.
    let cut_short = percept.ego_speed_mps > CUT_SHORT_EGO_SPEED_MPS
        && percept.ego_dist_m < CUT_SHORT_EGO_DISTANCE_M
        && p.in_view_s >= CUT_SHORT_MIN_IN_VIEW_S;
    // At a signalised crosswalk the green man, not the camera, sets the moment: the ego waits at its red light
    // (often behind a queue that hides the curb), and the crossing happens in front of it.
    let on_walk = percept.walk == Some(WalkSignal::Walk);
    // Where the scenario asks for it, the crosser waits until the ego is near (it eases off for the waiting
    // pedestrian), as real crossers go in front of a car that slows for them (`Ped::ego_near_enough`).
    !percept.ego_ahead
        || (p.seen_long_enough(lead_s) && p.followers_seen && p.ego_near_enough())
        || cut_short
        || on_walk
}

/// Whether the ego is so close ahead, and moving, that stepping out now would put the crosser under its wheels.
fn ego_too_close(p: &Ped) -> bool {
    p.percept.ego_ahead && p.percept.ego_dist_m < SUDDEN_MIN_EGO_M && !ego_can_stop(p)
}

/// Whether the ego can stop comfortably, with room to spare, before the pedestrian.
fn ego_can_stop(p: &Ped) -> bool {
    let v = p.percept.ego_speed_mps;
    v * v / (2.0 * COMFORTABLE_STOP_DECEL_MPS2) + STOP_MARGIN_M < p.percept.ego_dist_m
}

/// Whether a vehicle approaches a crosser on the road so fast that it runs, an emergency vehicle's siren is
/// near, or its crosswalk's signal flashes or shows "don't walk" (it hurries across).
fn must_run(p: &Ped) -> bool {
    p.percept.min_ttc_s < RUN_TTC_FRACTION * p.traits.ttc_threshold_s
        || p.percept.siren_near
        || p.percept.walk.is_some_and(|w| w != WalkSignal::Walk)
}

/// The behaviour machine of a pedestrian that decides for itself (a single or a group leader). `group_ready`
/// says whether every group member has reached its curb point; `group_conflict` is the lookahead conflict of
/// the whole group (any member's), if any.
pub(crate) fn transition(
    p: &mut Ped,
    ctx: &StepCtx,
    group_ready: bool,
    group_conflict: Option<VehicleId>,
    events: &mut Vec<Event>,
) {
    let params = ctx.params;
    let frame = ctx.next_frame;

    // Distraction (phone use) starts at its planned time, whatever the pedestrian is doing. A crosser waiting
    // for the ego's decision window does not pick up its phone before the attempt is over (it would miss the
    // window); the phone comes out afterwards.
    if let Distraction::At(at_s) = p.distraction
        && ctx.time_s >= at_s
        && (!matches!(p.traits.source, CrosserSource::Allocated | CrosserSource::Promoted) || p.attempt.over())
    {
        match p.activity {
            Activity::WalkingSidewalk | Activity::LookingAround | Activity::CheckingTraffic | Activity::Hesitating => {
                p.distraction = Distraction::Done;
                let resume = if matches!(p.attempt, Attempt::Undecided { at_curb: true, .. }) {
                    AfterPhone::LookingAround
                } else {
                    AfterPhone::WalkingSidewalk
                };
                switch_profile(p, params, SpeedProfile::Distracted);
                enter(p, Activity::DistractedBehavior { resume }, frame, events);
                return;
            }
            Activity::Crossing(mode) => {
                p.distraction = Distraction::Done;
                let pause = Activity::PausingMidCross {
                    cause: PauseCause::Phone,
                    resume: mode,
                };
                enter(p, pause, frame, events);
                return;
            }
            _ => {}
        }
    }

    // Patience cap while waiting at the curb (for the approaching ego: the wait counts while in its view).
    if let Attempt::Undecided {
        at_curb: true,
        waited_s,
    } = p.attempt
        && p.traits.role == Role::Crosser
        && waited_s >= p.traits.patience_s
        && matches!(
            p.activity,
            Activity::LookingAround | Activity::CheckingTraffic | Activity::Hesitating
        )
        && !ego_too_close(p)
    {
        let sudden = p
            .rng
            .random_bool(params.patience.sudden_crossing_probability.clamp(0.0, 1.0));
        events.push(Event::PatienceExpired {
            frame,
            pedestrian: p.traits.id,
            sudden_crossing: sudden,
        });
        if sudden && timeline_allows(p, 0.0) {
            decide_to_cross(p, frame, events);
            switch_profile(p, params, SpeedProfile::Rushed);
            enter(p, Activity::Crossing(CrossMode::SuddenCrossing), frame, events);
        } else {
            abandon(p, ctx);
            enter(p, Activity::WalkingSidewalk, frame, events);
        }
        return;
    }

    match p.activity {
        Activity::WalkingSidewalk => walking(p, ctx, group_ready, events),
        Activity::LookingAround => looking_around(p, ctx, events),
        Activity::CheckingTraffic => checking_traffic(p, ctx, events),
        Activity::Hesitating => hesitating(p, ctx, events),
        Activity::Crossing(mode) => crossing(p, ctx, mode, group_conflict, events),
        Activity::PausingMidCross { cause, resume } => pausing(p, ctx, cause, resume, group_conflict, events),
        Activity::Retreat => retreating(p, ctx, events),
        Activity::FinishedCrossing => finished(p, ctx, events),
        Activity::DistractedBehavior { resume } => distracted(p, ctx, resume, events),
    }
}

/// WALKING_SIDEWALK: a crosser at its curb (with its group) starts looking (a sudden crosser steps out once the
/// ego reaches the decision window); a walker scans from time to time.
fn walking(p: &mut Ped, ctx: &StepCtx, group_ready: bool, events: &mut Vec<Event>) {
    let (params, frame) = (ctx.params, ctx.next_frame);
    if !p.attempt.over() {
        // A sudden crosser turns onto the road from its last steps to the curb, without stopping there.
        let near_curb = p.traits.behaviour == Behaviour::Sudden
            && p.traits
                .line
                .is_some_and(|l| l.curb_point().distance(p.body.pos) < SUDDEN_FROM_CURB_M);
        if (p.attempt.at_curb() || near_curb) && group_ready {
            if p.traits.behaviour == Behaviour::Sudden {
                if ego_reached_window(p, params) && timeline_allows(p, 0.0) && !ego_too_close(p) {
                    decide_to_cross(p, frame, events);
                    switch_profile(p, params, SpeedProfile::Rushed);
                    enter(p, Activity::Crossing(CrossMode::SuddenCrossing), frame, events);
                }
            } else {
                enter(p, Activity::LookingAround, frame, events);
            }
        }
    } else if ctx.time_s >= p.next_scan_s {
        p.next_scan_s = ctx.time_s + motion::scan_interval_s(&mut p.rng, p.traits.attention);
        enter(p, Activity::LookingAround, frame, events);
    }
}

/// LOOKING_AROUND: after the scan, a walker walks on, a jaywalker crosses if no vehicle is about to arrive, a
/// crosser checks the traffic.
fn looking_around(p: &mut Ped, ctx: &StepCtx, events: &mut Vec<Event>) {
    let (params, frame, t) = (ctx.params, ctx.next_frame, p.state_time_s);
    let over = p.attempt.over();
    // A jaywalker, or any crosser with the ego already inside the decision window, only glances.
    let brief = p.traits.behaviour == Behaviour::Jaywalk || (!over && ego_in_window(p, params));
    if t < motion::scan_duration_s(p.traits.attention, brief || over) {
        return;
    }
    if over {
        enter(p, Activity::WalkingSidewalk, frame, events);
    } else if p.traits.behaviour == Behaviour::Jaywalk {
        // Mid-block crossing after a brief check: only a vehicle about to arrive holds it back.
        let ttc = if ego_in_window(p, params) {
            p.percept.min_ttc_others_s
        } else {
            p.percept.min_ttc_s
        };
        if ego_in_window_or_past(p, params) && ttc > JAYWALK_MIN_TTC_S && timeline_allows(p, 0.0) {
            decide_to_cross(p, frame, events);
            enter(p, Activity::Crossing(CrossMode::Jaywalking), frame, events);
        }
    } else {
        enter(p, Activity::CheckingTraffic, frame, events);
    }
}

/// CHECKING_TRAFFIC: after a minimum check, the gap-acceptance rule (or CARLA's stop-and-check for a baseline
/// crosser) decides to cross.
fn checking_traffic(p: &mut Ped, ctx: &StepCtx, events: &mut Vec<Event>) {
    let (params, frame) = (ctx.params, ctx.next_frame);
    if let Some(wait_s) = p.traits.curb_wait_s {
        // A hard negative: it looks and checks like a crosser, and after its wait walks on without crossing.
        if p.state_time_s >= wait_s {
            abandon(p, ctx);
            enter(p, Activity::WalkingSidewalk, frame, events);
        }
        return;
    }
    if p.state_time_s < CHECK_MIN_S {
        return;
    }
    let baseline = p.traits.source == CrosserSource::Baseline;
    let go = timeline_allows(p, p.traits.hesitation_s)
        && if baseline {
            baseline_clear(p)
        } else {
            ego_in_window_or_past(p, params) && gap_ok(p, params)
        };
    if go {
        let window_commit = !baseline && ego_in_window(p, params);
        decide_to_cross(p, frame, events);
        if let Attempt::Committed { window_commit: w, .. } = &mut p.attempt {
            *w = window_commit;
        }
        enter(p, Activity::Hesitating, frame, events);
    }
}

/// HESITATING: the decided crosser pauses at the road edge; it steps out after its hesitation time (earlier if
/// the ego comes close) unless the gap is lost.
fn hesitating(p: &mut Ped, ctx: &StepCtx, events: &mut Vec<Event>) {
    let (params, frame, t) = (ctx.params, ctx.next_frame, p.state_time_s);
    let threshold = gap_threshold_s(p, params);
    let window_commit = matches!(
        p.attempt,
        Attempt::Committed {
            window_commit: true,
            ..
        }
    );
    let lost = if p.traits.source == CrosserSource::Baseline {
        !baseline_clear(p)
    } else if window_commit {
        // Committed with the ego in the window: only another vehicle about to arrive holds it back.
        p.percept.min_ttc_others_s <= COMMIT_MIN_TTC_S
    } else {
        !gap_ok(p, params)
    };
    // Committed inside the window, a crosser cuts its hesitation short rather than let the ego come so close
    // that stepping out would be unsafe.
    let ego_closing_in = window_commit
        && p.percept.ego_ahead
        && p.percept.ego_dist_m <= params.decision_window_m.min() + HESITATION_CUTOFF_M;
    let ready = timeline_allows(p, 0.0);
    if lost || (ego_closing_in && !ready) {
        enter(p, Activity::CheckingTraffic, frame, events);
    } else if ready && (t >= p.traits.hesitation_s || ego_closing_in) {
        // Closing a tight gap: rushed.
        if p.percept.min_ttc_s < RUSHED_GAP_FACTOR * threshold {
            switch_profile(p, params, SpeedProfile::Rushed);
        }
        enter(p, Activity::Crossing(CrossMode::CrossingRoad), frame, events);
    }
}

/// A crossing mode: finishes beyond the far curb; a lookahead conflict pauses it (or, once per conflict, turns
/// it back); a vehicle closing in makes it run.
fn crossing(p: &mut Ped, ctx: &StepCtx, mode: CrossMode, group_conflict: Option<VehicleId>, events: &mut Vec<Event>) {
    let (params, frame) = (ctx.params, ctx.next_frame);
    let Some(line) = p.traits.line else {
        return;
    };
    let along = line.along_m(p.body.pos);
    if along >= line.width_m + FINISH_BEYOND_CURB_M {
        p.attempt.end();
        enter(p, Activity::FinishedCrossing, frame, events);
    } else if let Some(vehicle) = group_conflict {
        // A new conflict (a crossing mode is never entered with one open): one retreat draw.
        let in_window = along / line.width_m < params.retreat.window_fraction;
        let retreated = in_window && p.rng.random_bool(params.retreat.probability.clamp(0.0, 1.0));
        events.push(Event::Conflict {
            frame,
            pedestrian: p.traits.id,
            vehicle,
            in_retreat_window: in_window,
            retreated,
        });
        if retreated {
            enter(p, Activity::Retreat, frame, events);
        } else {
            let pause = Activity::PausingMidCross {
                cause: PauseCause::Conflict { clear_s: 0.0 },
                resume: mode,
            };
            enter(p, pause, frame, events);
        }
    } else if along > 0.0 && mode != CrossMode::RunningAcross && must_run(p) {
        // A vehicle is approaching while on the road: run.
        switch_profile(p, params, SpeedProfile::Rushed);
        enter(p, Activity::Crossing(CrossMode::RunningAcross), frame, events);
    }
}

/// PAUSING_MID_CROSS: a phone pause ends after its time; a conflict pause once the lookahead has been clear for
/// a while (running on if a vehicle is close), or turns back when a standing vehicle blocks the way too long.
fn pausing(
    p: &mut Ped,
    ctx: &StepCtx,
    cause: PauseCause,
    resume: CrossMode,
    group_conflict: Option<VehicleId>,
    events: &mut Vec<Event>,
) {
    let (params, frame, t) = (ctx.params, ctx.next_frame, p.state_time_s);
    let PauseCause::Conflict { clear_s } = cause else {
        if t >= DISTRACTION_PAUSE_S {
            enter(p, Activity::Crossing(resume), frame, events);
        }
        return;
    };
    if group_conflict.is_some() {
        p.activity = Activity::PausingMidCross {
            cause: PauseCause::Conflict { clear_s: 0.0 },
            resume,
        };
        if p.percept.blocked_by_standing && t >= BLOCKED_RETREAT_S {
            // Blocked by a vehicle that waits for us: step back to the curb and let it go.
            enter(p, Activity::Retreat, frame, events);
        }
        return;
    }
    let clear_s = clear_s + ctx.dt_s;
    p.activity = Activity::PausingMidCross {
        cause: PauseCause::Conflict { clear_s },
        resume,
    };
    if clear_s >= CONFLICT_CLEAR_S {
        let next = if must_run(p) { CrossMode::RunningAcross } else { resume };
        if next == CrossMode::RunningAcross {
            switch_profile(p, params, SpeedProfile::Rushed);
        }
        enter(p, Activity::Crossing(next), frame, events);
    }
}

/// RETREAT: back at the curb, the crosser checks the traffic again.
fn retreating(p: &mut Ped, ctx: &StepCtx, events: &mut Vec<Event>) {
    let Some(line) = p.traits.line else {
        return;
    };
    if line.along_m(p.body.pos) <= -CURB_STANDOFF_M + 1e-6 {
        p.attempt.reach_curb();
        switch_profile(p, ctx.params, p.traits.initial_profile);
        enter(p, Activity::CheckingTraffic, ctx.next_frame, events);
    }
}

/// FINISHED_CROSSING: at the end of its crossing (or after a while), the pedestrian walks on along the far
/// sidewalk, either way.
fn finished(p: &mut Ped, ctx: &StepCtx, events: &mut Vec<Event>) {
    let Some(line) = p.traits.line else {
        return;
    };
    if line.along_m(p.body.pos) >= line.end_along_m() - FINISHED_ARRIVAL_M || p.state_time_s > FINISHED_MAX_S {
        switch_profile(p, ctx.params, p.traits.initial_profile);
        let side = if p.rng.random_bool(0.5) { 1.0 } else { -1.0 };
        p.walker = SidewalkWalker::start(ctx.net, p.body.pos, line.dir.perp() * side);
        enter(p, Activity::WalkingSidewalk, ctx.next_frame, events);
    }
}

/// DISTRACTED_BEHAVIOR: after its phone-use episode, the pedestrian returns to what it was doing.
fn distracted(p: &mut Ped, ctx: &StepCtx, resume: AfterPhone, events: &mut Vec<Event>) {
    if p.state_time_s >= p.traits.distraction_len_s {
        if p.traits.initial_profile != SpeedProfile::Distracted {
            switch_profile(p, ctx.params, p.traits.initial_profile);
        }
        let to = match resume {
            AfterPhone::WalkingSidewalk => Activity::WalkingSidewalk,
            AfterPhone::LookingAround => Activity::LookingAround,
        };
        enter(p, to, ctx.next_frame, events);
    }
}

/// A follower copies its leader's activity in the same frame (and its decision, phone use and speed profile).
pub(crate) fn follow(p: &mut Ped, leader: &LeaderFacts, ctx: &StepCtx, events: &mut Vec<Event>) {
    let frame = ctx.next_frame;
    if leader.decided && !p.attempt.decided() {
        decide_to_cross(p, frame, events);
    }
    if leader.attempt_over && !p.attempt.over() {
        p.attempt.end();
    }
    if p.attempt.over() && leader.activity == Activity::WalkingSidewalk && !p.walker.active {
        p.walker = SidewalkWalker::start(ctx.net, p.body.pos, leader.walker_heading);
    }
    if leader.activity.label() == PedState::CheckingTraffic && p.activity == Activity::Retreat {
        p.attempt.reach_curb();
    }
    p.profile = leader.profile;
    enter(p, leader.activity, frame, events);
}
