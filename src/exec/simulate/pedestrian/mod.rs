//! Pedestrians: the 12-state behaviour machine (one transition function, an explicit `match` on
//! [`PedState`]) and the two motion modes of the paper's hybrid control.
//!
//! - **AI mode** (sidewalk states): walking along the sidewalk graph (crosswalk edges excluded, never onto a
//!   driving lane) or to the curb, with simple avoidance of other pedestrians.
//! - **Manual mode** (crossing states, pause, retreat): direct velocity control along the crossing vector
//!   across the carriageway.
//!
//! Speeds are explicit per state ([`state_speed_mps`], [`allowed_speed_range_mps`]): standing states are 0;
//! walking, crossing, sudden and jaywalking move at base × the current speed-profile multiplier; running across
//! at base × the rushed multiplier; distracted at base × the distracted multiplier; retreat at the pedestrian's
//! retreat speed (drawn from `retreat.speed_mps`). Group members cross at the group's speed (the slowest
//! member's), synchronised by progress along their own crossing lines.

use glam::DVec2;
use rand::RngExt;
use rand_chacha::ChaCha20Rng;

use super::ttc;
use super::vehicle::{HALF_LENGTH_M, HALF_WIDTH_M, Vehicle};
use crate::dsl::types::SpeedProfileMultipliers;
use crate::exec::trace::{Event, PedState};
use crate::planner::{Behaviour, CrosserSource, PedestrianScript, Role, SimParams, SpawnPlace, SpeedProfile};
use crate::world::{LaneType, RoadNetwork};

/// Where a crosser stands before stepping onto the road: this far behind the near curb, metres.
const CURB_STANDOFF_M: f64 = 0.3;
/// Shortest traffic check before a decision, seconds.
const CHECK_MIN_S: f64 = 0.5;
/// A jaywalker's brief check only waits while a vehicle would arrive within this time, seconds.
const JAYWALK_MIN_TTC_S: f64 = 2.0;
/// A committed crosser stops hesitating when the ego comes this much closer than the window's near edge, metres.
const HESITATION_CUTOFF_M: f64 = 3.0;
/// A crosser committing inside the decision window waits only for another vehicle this close in time, seconds.
const COMMIT_MIN_TTC_S: f64 = 2.0;
/// A baseline (CARLA-like) crosser waits until no vehicle is this close, metres (CARLA's stop-and-check).
const BASELINE_CLEAR_M: f64 = 6.0;
/// A conflict ends after the lookahead has been clear this long, seconds.
const CONFLICT_CLEAR_S: f64 = 0.5;
/// A vehicle slower than this is not a lookahead conflict (it has stopped for the pedestrian; counting it would
/// make both wait forever), m/s.
const CONFLICT_MIN_VEHICLE_SPEED_MPS: f64 = 0.5;
/// A pedestrian blocked this long by a standing vehicle steps back to the curb (not a retreat draw), seconds.
const BLOCKED_RETREAT_S: f64 = 3.0;
/// How long a distraction (phone) pause mid-road lasts, seconds.
const DISTRACTION_PAUSE_S: f64 = 1.0;
/// Range of a phone-use episode, seconds.
const DISTRACTION_EPISODE_S: (f64, f64) = (2.0, 5.0);
/// The crossing has finished this far beyond the far curb, metres.
const FINISH_BEYOND_CURB_M: f64 = 0.3;
/// Stride length of one gait cycle, metres.
const STRIDE_M: f64 = 1.4;
/// Pedestrians closer than this push each other apart in AI mode, metres.
const AVOID_RADIUS_M: f64 = 1.0;
/// A crosser on the road runs when a vehicle would arrive within this fraction of its own TTC threshold.
const RUN_TTC_FRACTION: f64 = 0.5;
/// Share of non-crossers that stand still (waiting, chatting) rather than walk.
const STANDING_SHARE: f64 = 0.2;

/// Speed multiplier of a profile.
pub fn profile_multiplier(m: &SpeedProfileMultipliers, p: SpeedProfile) -> f64 {
    match p {
        SpeedProfile::Cautious => m.cautious,
        SpeedProfile::Normal => m.normal,
        SpeedProfile::Rushed => m.rushed,
        SpeedProfile::Distracted => m.distracted,
    }
}

/// The speed a pedestrian in `state` moves at with speed profile `profile`, m/s (before group synchronisation,
/// arrival at a target, or a phone pause, which can only lower it).
pub fn state_speed_mps(
    state: PedState,
    base_speed_mps: f64,
    profile: SpeedProfile,
    retreat_speed_mps: f64,
    m: &SpeedProfileMultipliers,
) -> f64 {
    match state {
        PedState::LookingAround | PedState::CheckingTraffic | PedState::Hesitating | PedState::PausingMidCross => 0.0,
        PedState::WalkingSidewalk
        | PedState::CrossingRoad
        | PedState::SuddenCrossing
        | PedState::Jaywalking
        | PedState::FinishedCrossing => base_speed_mps * profile_multiplier(m, profile),
        PedState::RunningAcross => base_speed_mps * m.rushed,
        PedState::DistractedBehavior => base_speed_mps * m.distracted,
        PedState::Retreat => retreat_speed_mps,
    }
}

/// The range of speeds a pedestrian of this script may show while moving in `state`, m/s (the honest bound the
/// statistical tests check): the profiles it can be in are its initial one and, with switching, rushed and
/// distracted. Group followers are excluded (they match their leader's progress).
pub fn allowed_speed_range_mps(state: PedState, script: &PedestrianScript, params: &SimParams) -> (f64, f64) {
    let m = &params.speed_profiles.multipliers;
    let base = script.base_speed_mps;
    let initial = profile_multiplier(m, script.speed_profile);
    let mut profiles = vec![initial];
    if params.speed_profiles.switching {
        profiles.extend([m.rushed, m.distracted]);
    }
    let lo = profiles.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = profiles.iter().copied().fold(0.0, f64::max);
    match state {
        PedState::LookingAround | PedState::CheckingTraffic | PedState::Hesitating | PedState::PausingMidCross => {
            (0.0, 0.0)
        }
        PedState::RunningAcross => (base * m.rushed, base * m.rushed),
        PedState::DistractedBehavior => (0.0, base * m.distracted),
        PedState::Retreat => (params.retreat.speed_mps.min(), params.retreat.speed_mps.max()),
        _ => (base * lo, base * hi),
    }
}

/// Greedy walker along the sidewalk graph: from node to node, never over a crosswalk edge, preferring the edge
/// that best continues the current heading.
#[derive(Clone, Debug, Default)]
pub(crate) struct SidewalkWalker {
    pub active: bool,
    prev: u32,
    node: u32,
}

impl SidewalkWalker {
    fn start(net: &RoadNetwork, pos: DVec2, heading: DVec2) -> SidewalkWalker {
        let g = net.sidewalk_graph();
        let Some(n) = g.nearest_node(pos) else {
            return SidewalkWalker::default();
        };
        let mut w = SidewalkWalker {
            active: true,
            prev: u32::MAX,
            node: n,
        };
        // If the nearest node is behind, head straight for the next one.
        if (g.nodes[n as usize] - pos).dot(heading) < 0.0 {
            w.advance(net, heading);
        }
        w
    }

    fn target(&self, net: &RoadNetwork) -> DVec2 {
        net.sidewalk_graph().nodes[self.node as usize]
    }

    /// Moves on to the best next node.
    fn advance(&mut self, net: &RoadNetwork, heading: DVec2) {
        let g = net.sidewalk_graph();
        let here = g.nodes[self.node as usize];
        let mut best: Option<(f64, u32)> = None;
        for e in g.edges(self.node) {
            if e.crosswalk || e.to == self.prev || e.length_m < 1e-6 {
                continue;
            }
            let to = g.nodes[e.to as usize];
            let mid = (here + to) * 0.5;
            if net.lane_at(mid).is_some_and(|h| h.lane_type == LaneType::Driving) {
                continue;
            }
            let score = (to - here).normalize_or_zero().dot(heading);
            if best.is_none_or(|b| score > b.0) {
                best = Some((score, e.to));
            }
        }
        match best {
            Some((_, to)) => {
                self.prev = self.node;
                self.node = to;
            }
            None if self.prev != u32::MAX => std::mem::swap(&mut self.prev, &mut self.node),
            None => self.active = false,
        }
    }

    fn turn_around(&mut self) {
        if self.prev != u32::MAX {
            std::mem::swap(&mut self.prev, &mut self.node);
        }
    }
}

/// A crossing line in the simulation's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Line {
    pub near_curb: DVec2,
    pub end: DVec2,
    pub dir: DVec2,
    pub width_m: f64,
}

impl Line {
    /// Signed distance along the crossing from the near curb, metres.
    pub fn along_m(&self, p: DVec2) -> f64 {
        (p - self.near_curb).dot(self.dir)
    }
    /// Where a crosser waits at the curb.
    pub fn curb_point(&self) -> DVec2 {
        self.near_curb - self.dir * CURB_STANDOFF_M
    }
    /// Distance along the line from the near curb to the end point, metres.
    pub fn end_along_m(&self) -> f64 {
        self.along_m(self.end).max(self.width_m + FINISH_BEYOND_CURB_M)
    }
}

/// One simulated pedestrian.
#[derive(Clone, Debug)]
pub(crate) struct Ped {
    pub id: u32,
    pub behaviour: Behaviour,
    pub source: CrosserSource,
    pub base_speed_mps: f64,
    pub hesitation_s: f64,
    pub attention: f64,
    pub ttc_threshold_s: f64,
    pub safety_margin_s: f64,
    pub patience_s: f64,
    pub distracted_at_s: Option<f64>,
    pub initial_profile: SpeedProfile,
    pub profile: SpeedProfile,
    pub retreat_speed_mps: f64,
    pub line: Option<Line>,
    /// Index of the group leader (followers only).
    pub leader: Option<usize>,
    /// Indices of the followers (leaders only).
    pub followers: Vec<usize>,
    pub standing: bool,

    pub pos: DVec2,
    pub z_m: f64,
    pub yaw_rad: f64,
    pub velocity: DVec2,
    pub state: PedState,
    pub state_time_s: f64,
    pub head_yaw_rad: f64,
    pub gait_phase: f64,
    pub on_phone: bool,
    pub lane_type: Option<LaneType>,

    /// The decision to cross has been announced (CrossingDecision emitted).
    pub decided: bool,
    /// The decision to cross was a decision-window commit (the ego approaches inside the window and brakes).
    pub window_commit: bool,
    /// Has been on the road in a crossing state.
    pub entered_road: bool,
    /// The crossing is over (finished) or given up (abandoned): never cross again.
    pub attempt_over: bool,
    /// Arrived at the curb (waiting time counts from here).
    pub at_curb: bool,
    pub wait_s: f64,
    /// State to return to after a pause or a distraction episode.
    pub resume: PedState,
    pub pause_is_distraction: bool,
    pub distraction_done: bool,
    pub distraction_len_s: f64,
    pub next_scan_s: f64,
    pub conflict_active: bool,
    pub conflict_clear_s: f64,
    pub walker: SidewalkWalker,
    pub rng: ChaCha20Rng,

    // Perception (from the state at the start of the step).
    pub min_ttc_s: f64,
    /// Minimum TTC over every vehicle but the ego, seconds.
    pub min_ttc_others_s: f64,
    pub ego_dist_m: f64,
    /// Distance to the nearest vehicle centre, metres.
    pub nearest_vehicle_m: f64,
    pub ego_ahead: bool,
    /// Where the pedestrian stands along the ego's route (its planned distance ahead of the ego's start),
    /// metres: "ahead of the ego" is decided along the route, which stays right where the route turns.
    pub route_s_m: f64,
    /// Vehicle id of a lookahead conflict this step (own probes).
    pub conflict_vehicle: Option<u32>,
    /// The conflict is a standing vehicle blocking the way.
    pub blocked_by_standing: bool,
    /// Speed of the group crossing (leaders), m/s.
    pub group_speed_mps: f64,
}

/// Read-only context of one step.
pub(crate) struct StepCtx<'a> {
    pub params: &'a SimParams,
    pub net: &'a RoadNetwork,
    pub dt_s: f64,
    pub time_s: f64,
    /// Frame whose state the decisions of this step first appear in.
    pub next_frame: u32,
}

impl Ped {
    /// Sets a pedestrian up from its script; draws its per-pedestrian constants from its own stream.
    pub fn new(script: &PedestrianScript, params: &SimParams, net: &RoadNetwork, mut rng: ChaCha20Rng) -> Ped {
        let retreat_speed_mps = draw(&mut rng, params.retreat.speed_mps.min(), params.retreat.speed_mps.max());
        let distraction_len_s = draw(&mut rng, DISTRACTION_EPISODE_S.0, DISTRACTION_EPISODE_S.1);
        let standing = rng.random_bool(STANDING_SHARE);
        let next_scan_s = scan_interval_s(&mut rng, script.attention);
        let line = script.crossing.as_ref().map(|c| Line {
            near_curb: c.near_curb,
            end: c.end,
            dir: c.direction.normalize_or(DVec2::X),
            width_m: c.carriageway_width_m.max(0.1),
        });
        let heading = DVec2::from_angle(script.spawn_heading_rad);
        let role = script.role;
        let mut p = Ped {
            id: script.id,
            behaviour: script.behaviour,
            source: script.crosser_source,
            base_speed_mps: script.base_speed_mps.max(0.05),
            hesitation_s: script.hesitation_s.max(0.0),
            attention: script.attention.clamp(0.0, 1.0),
            ttc_threshold_s: script.ttc_threshold_s,
            safety_margin_s: script.safety_margin_s,
            patience_s: script.patience_s,
            distracted_at_s: script.distracted_at_s,
            initial_profile: script.speed_profile,
            profile: script.speed_profile,
            retreat_speed_mps,
            line,
            leader: None,
            followers: Vec::new(),
            standing,
            pos: script.spawn,
            z_m: 0.0,
            yaw_rad: script.spawn_heading_rad,
            velocity: DVec2::ZERO,
            state: PedState::WalkingSidewalk,
            state_time_s: 0.0,
            head_yaw_rad: 0.0,
            gait_phase: 0.0,
            on_phone: false,
            lane_type: None,
            decided: false,
            entered_road: false,
            attempt_over: role != Role::Crosser || line.is_none(),
            at_curb: false,
            wait_s: 0.0,
            resume: PedState::WalkingSidewalk,
            pause_is_distraction: false,
            distraction_done: false,
            distraction_len_s,
            next_scan_s,
            conflict_active: false,
            conflict_clear_s: 0.0,
            walker: SidewalkWalker::default(),
            rng,
            min_ttc_s: f64::INFINITY,
            min_ttc_others_s: f64::INFINITY,
            window_commit: false,
            ego_dist_m: f64::INFINITY,
            nearest_vehicle_m: f64::INFINITY,
            ego_ahead: true,
            route_s_m: script.ahead_of_ego_m,
            conflict_vehicle: None,
            blocked_by_standing: false,
            group_speed_mps: 0.0,
        };
        if let Some(h) = net.lane_at(p.pos) {
            p.z_m = h.z_m;
            p.lane_type = Some(h.lane_type);
        }
        if p.attempt_over {
            p.walker = SidewalkWalker::start(net, p.pos, heading);
        }
        if script.behaviour == Behaviour::MidroadJaywalker && script.spawn_place == SpawnPlace::DrivingLane {
            p.state = PedState::Jaywalking;
            p.decided = true;
        } else if script.crosser_source != CrosserSource::None
            && matches!(script.behaviour, Behaviour::Normal | Behaviour::Jaywalk)
            && p.line.is_some_and(|l| l.curb_point().distance(p.pos) < 0.1)
            && script.ahead_of_ego_m <= params.decision_window_m.max()
        {
            // A crosser that starts at its curb with the ego already inside the decision window has been waiting
            // there before the clip began: it is already checking traffic (a jaywalker: glancing).
            p.at_curb = true;
            p.state = if script.behaviour == Behaviour::Jaywalk {
                PedState::LookingAround
            } else {
                PedState::CheckingTraffic
            };
            p.state_time_s = CHECK_MIN_S;
        }
        p
    }

    fn mult(&self, m: &SpeedProfileMultipliers) -> f64 {
        profile_multiplier(m, self.profile)
    }

    /// The pedestrian's own speed in its current state, m/s.
    pub fn own_speed_mps(&self, m: &SpeedProfileMultipliers) -> f64 {
        state_speed_mps(self.state, self.base_speed_mps, self.profile, self.retreat_speed_mps, m)
    }

    fn is_crossing_motion(&self) -> bool {
        self.state.is_crossing() || self.state == PedState::Retreat
    }
}

fn draw(rng: &mut ChaCha20Rng, lo: f64, hi: f64) -> f64 {
    if hi > lo { rng.random_range(lo..=hi) } else { lo }
}

/// Time until the next attention-driven scan of a walker, seconds (more attentive: more often).
fn scan_interval_s(rng: &mut ChaCha20Rng, attention: f64) -> f64 {
    let mean_s = 4.0 + 8.0 * (1.0 - attention.clamp(0.0, 1.0));
    let u: f64 = rng.random_range(1e-6..1.0);
    -mean_s * u.ln()
}

/// How long a scan lasts, seconds (attentive pedestrians look longer).
fn scan_duration_s(attention: f64, brief: bool) -> f64 {
    if brief {
        0.3 + 0.5 * attention
    } else {
        0.5 + 1.5 * attention
    }
}

/// Perception from the state at the start of the step: TTC against every vehicle in range, the ego's distance
/// and side, and the in-road lookahead.
pub(crate) fn perceive(p: &mut Ped, vehicles: &[Vehicle], params: &SimParams, probes: &mut Vec<DVec2>) {
    p.min_ttc_s = ttc::min_ttc_s(
        p.pos,
        vehicles.iter().map(|v| (v.pose.pos, v.velocity())),
        params.gap_acceptance.vehicle_range_m,
    );
    p.min_ttc_others_s = ttc::min_ttc_s(
        p.pos,
        vehicles.iter().skip(1).map(|v| (v.pose.pos, v.velocity())),
        params.gap_acceptance.vehicle_range_m,
    );
    p.nearest_vehicle_m = vehicles
        .iter()
        .map(|v| v.pose.pos.distance(p.pos))
        .fold(f64::INFINITY, f64::min);
    let ego = &vehicles[0];
    p.ego_dist_m = ego.pose.pos.distance(p.pos);
    p.ego_ahead = ego.s_m < p.route_s_m;
    p.conflict_vehicle = None;
    let Some(line) = p.line else {
        return;
    };
    let along = line.along_m(p.pos);
    if !(p.state.is_crossing() && along > 0.0 && along < line.width_m) {
        return;
    }
    // A pausing pedestrian probes as if walking on.
    let dir = line.dir;
    let velocity = if p.state == PedState::PausingMidCross {
        dir * p.base_speed_mps
    } else {
        p.velocity
    };
    ttc::probe_points(
        p.pos,
        dir,
        velocity,
        &params.lookahead.points_m,
        params.lookahead.prediction_s,
        probes,
    );
    let r = params.lookahead.radius_m;
    p.blocked_by_standing = false;
    for v in vehicles {
        if v.speed_mps < CONFLICT_MIN_VEHICLE_SPEED_MPS {
            // A standing vehicle only matters when it physically blocks the next step.
            let next = p.pos + dir * params.lookahead.points_m.first().copied().unwrap_or(0.5);
            if ttc::distance_to_box_m(next, v.pose.pos, v.pose.heading_rad, HALF_LENGTH_M, HALF_WIDTH_M)
                < super::PED_RADIUS_M + 0.2
            {
                p.conflict_vehicle = Some(v.id);
                p.blocked_by_standing = true;
                break;
            }
            continue;
        }
        if v.pose.pos.distance_squared(p.pos) > (r + 2.5 + HALF_LENGTH_M + 2.0).powi(2) {
            continue;
        }
        if ttc::probes_hit_box(probes, v.pose.pos, v.pose.heading_rad, HALF_LENGTH_M, HALF_WIDTH_M, r) {
            p.conflict_vehicle = Some(v.id);
            break;
        }
    }
}

/// Emits a state change into `events` and resets the state timer.
fn set_state(p: &mut Ped, to: PedState, frame: u32, events: &mut Vec<Event>) {
    if p.state != to {
        events.push(Event::StateChange {
            frame,
            pedestrian: p.id,
            from: p.state,
            to,
        });
        p.state = to;
        p.state_time_s = 0.0;
    }
}

fn decide_to_cross(p: &mut Ped, frame: u32, events: &mut Vec<Event>) {
    if !p.decided {
        p.decided = true;
        events.push(Event::CrossingDecision {
            frame,
            pedestrian: p.id,
        });
    }
}

/// The gap-acceptance threshold of `p` for its crossing, seconds.
fn gap_threshold_s(p: &Ped, params: &SimParams) -> f64 {
    let width = p.line.map_or(0.0, |l| l.width_m);
    let speed = p.base_speed_mps * p.mult(&params.speed_profiles.multipliers);
    ttc::gap_threshold_s(p.ttc_threshold_s, p.safety_margin_s, width, speed)
}

/// Whether the ego's position allows an allocated crosser to commit: inside the decision window while
/// approaching, or already past.
fn ego_in_window_or_past(p: &Ped, params: &SimParams) -> bool {
    let w = params.decision_window_m;
    !p.ego_ahead || (p.ego_dist_m >= w.min() && p.ego_dist_m <= w.max())
}

/// Whether the ego approaches inside the decision window.
fn ego_in_window(p: &Ped, params: &SimParams) -> bool {
    let w = params.decision_window_m;
    p.ego_ahead && p.ego_dist_m >= w.min() && p.ego_dist_m <= w.max()
}

/// Whether an allocated crosser may go now. The paper's crosser "commits to entering the road as soon as the
/// ego-vehicle is within the 10–40 m decision window" (the ego then brakes for it): inside the window it only
/// waits for another vehicle about to arrive (TTC below `COMMIT_MIN_TTC_S`); otherwise the full gap-acceptance
/// rule min TTC > τ_ttc + Δ_safety + w_road / s_cross applies to every vehicle in range.
fn gap_ok(p: &Ped, params: &SimParams) -> bool {
    if ego_in_window(p, params) {
        p.min_ttc_others_s > COMMIT_MIN_TTC_S
    } else {
        ttc::gap_accepted(p.min_ttc_s, gap_threshold_s(p, params))
    }
}

/// Whether the ego has reached the decision window (or passed): the sudden crosser's trigger.
fn ego_reached_window(p: &Ped, params: &SimParams) -> bool {
    !p.ego_ahead || p.ego_dist_m <= params.decision_window_m.max()
}

fn switch_profile(p: &mut Ped, params: &SimParams, to: SpeedProfile) {
    if params.speed_profiles.switching {
        p.profile = to;
    }
}

/// The behaviour machine of a pedestrian that decides for itself (a single or a group leader). `group_ready`
/// says whether every group member has reached its curb point; `group_conflict` is the lookahead conflict of
/// the whole group (any member's), if any.
pub(crate) fn transition(
    p: &mut Ped,
    ctx: &StepCtx,
    group_ready: bool,
    group_conflict: Option<u32>,
    events: &mut Vec<Event>,
) {
    let params = ctx.params;
    let frame = ctx.next_frame;
    let t = p.state_time_s;
    let crosser_waiting = !p.attempt_over && !p.decided;

    // Distraction (phone use) starts at its planned time, whatever the pedestrian is doing.
    // A crosser waiting for the ego's decision window does not pick up its phone before the attempt is over
    // (it would miss the window); the phone comes out afterwards.
    if let Some(at) = p.distracted_at_s
        && !p.distraction_done
        && ctx.time_s >= at
        && (p.source != CrosserSource::Allocated || p.attempt_over)
    {
        match p.state {
            PedState::WalkingSidewalk | PedState::LookingAround | PedState::CheckingTraffic | PedState::Hesitating => {
                p.distraction_done = true;
                p.resume = if p.at_curb && crosser_waiting {
                    PedState::LookingAround
                } else {
                    PedState::WalkingSidewalk
                };
                switch_profile(p, params, SpeedProfile::Distracted);
                p.on_phone = true;
                set_state(p, PedState::DistractedBehavior, frame, events);
                return;
            }
            s if s.is_crossing() && s != PedState::PausingMidCross => {
                p.distraction_done = true;
                p.resume = s;
                p.pause_is_distraction = true;
                p.on_phone = true;
                set_state(p, PedState::PausingMidCross, frame, events);
                return;
            }
            _ => {}
        }
    }

    // Patience cap while waiting at the curb.
    if crosser_waiting
        && p.at_curb
        && p.wait_s >= p.patience_s
        && matches!(
            p.state,
            PedState::LookingAround | PedState::CheckingTraffic | PedState::Hesitating
        )
    {
        let sudden = p
            .rng
            .random_bool(params.patience.sudden_crossing_probability.clamp(0.0, 1.0));
        events.push(Event::PatienceExpired {
            frame,
            pedestrian: p.id,
            sudden_crossing: sudden,
        });
        if sudden {
            decide_to_cross(p, frame, events);
            switch_profile(p, params, SpeedProfile::Rushed);
            set_state(p, PedState::SuddenCrossing, frame, events);
        } else {
            abandon(p, ctx);
            set_state(p, PedState::WalkingSidewalk, frame, events);
        }
        return;
    }

    match p.state {
        PedState::WalkingSidewalk => {
            if !p.attempt_over {
                if p.at_curb && group_ready {
                    match p.behaviour {
                        Behaviour::Sudden => {
                            if ego_reached_window(p, params) {
                                decide_to_cross(p, frame, events);
                                switch_profile(p, params, SpeedProfile::Rushed);
                                set_state(p, PedState::SuddenCrossing, frame, events);
                            }
                        }
                        _ => set_state(p, PedState::LookingAround, frame, events),
                    }
                }
            } else if ctx.time_s >= p.next_scan_s {
                p.next_scan_s = ctx.time_s + scan_interval_s(&mut p.rng, p.attention);
                set_state(p, PedState::LookingAround, frame, events);
            }
        }
        PedState::LookingAround => {
            // A jaywalker, or any crosser with the ego already inside the decision window, only glances.
            let brief = p.behaviour == Behaviour::Jaywalk || (!p.attempt_over && ego_in_window(p, params));
            if t < scan_duration_s(p.attention, brief || p.attempt_over) {
                return;
            }
            if p.attempt_over {
                set_state(p, PedState::WalkingSidewalk, frame, events);
            } else if p.behaviour == Behaviour::Jaywalk {
                // Mid-block crossing after a brief check: only a vehicle about to arrive holds it back.
                let ttc = if ego_in_window(p, params) {
                    p.min_ttc_others_s
                } else {
                    p.min_ttc_s
                };
                if ego_in_window_or_past(p, params) && ttc > JAYWALK_MIN_TTC_S {
                    decide_to_cross(p, frame, events);
                    set_state(p, PedState::Jaywalking, frame, events);
                }
            } else {
                set_state(p, PedState::CheckingTraffic, frame, events);
            }
        }
        PedState::CheckingTraffic => {
            if t < CHECK_MIN_S {
                return;
            }
            let go = if p.source == CrosserSource::Baseline {
                // CARLA's walkers stop and check: no vehicle within a few metres, none about to arrive.
                p.nearest_vehicle_m > BASELINE_CLEAR_M && p.min_ttc_s > JAYWALK_MIN_TTC_S
            } else {
                ego_in_window_or_past(p, params) && gap_ok(p, params)
            };
            if go {
                p.window_commit = p.source != CrosserSource::Baseline && ego_in_window(p, params);
                decide_to_cross(p, frame, events);
                set_state(p, PedState::Hesitating, frame, events);
            }
        }
        PedState::Hesitating => {
            let threshold = gap_threshold_s(p, params);
            let lost = if p.source == CrosserSource::Baseline {
                p.nearest_vehicle_m <= BASELINE_CLEAR_M || p.min_ttc_s <= JAYWALK_MIN_TTC_S
            } else if p.window_commit {
                // Committed with the ego in the window: only another vehicle about to arrive holds it back.
                p.min_ttc_others_s <= COMMIT_MIN_TTC_S
            } else {
                !gap_ok(p, params)
            };
            // Committed inside the window, a crosser cuts its hesitation short rather than let the ego come so
            // close that stepping out would be unsafe.
            let ego_closing_in =
                p.window_commit && p.ego_ahead && p.ego_dist_m <= params.decision_window_m.min() + HESITATION_CUTOFF_M;
            if lost {
                set_state(p, PedState::CheckingTraffic, frame, events);
            } else if t >= p.hesitation_s || ego_closing_in {
                // Closing a tight gap: rushed.
                if p.min_ttc_s < 1.5 * threshold {
                    switch_profile(p, params, SpeedProfile::Rushed);
                }
                set_state(p, PedState::CrossingRoad, frame, events);
            }
        }
        PedState::CrossingRoad | PedState::SuddenCrossing | PedState::Jaywalking | PedState::RunningAcross => {
            let Some(line) = p.line else {
                return;
            };
            let along = line.along_m(p.pos);
            if along >= line.width_m + FINISH_BEYOND_CURB_M {
                p.attempt_over = true;
                set_state(p, PedState::FinishedCrossing, frame, events);
            } else if let Some(vehicle) = group_conflict {
                if !p.conflict_active {
                    p.conflict_active = true;
                    let in_window = along / line.width_m < params.retreat.window_fraction;
                    let retreated = in_window && p.rng.random_bool(params.retreat.probability.clamp(0.0, 1.0));
                    events.push(Event::Conflict {
                        frame,
                        pedestrian: p.id,
                        vehicle,
                        in_retreat_window: in_window,
                        retreated,
                    });
                    if retreated {
                        set_state(p, PedState::Retreat, frame, events);
                        return;
                    }
                }
                p.conflict_clear_s = 0.0;
                p.resume = p.state;
                p.pause_is_distraction = false;
                set_state(p, PedState::PausingMidCross, frame, events);
            } else if along > 0.0
                && p.state != PedState::RunningAcross
                && p.min_ttc_s < RUN_TTC_FRACTION * p.ttc_threshold_s
            {
                // A vehicle is approaching while on the road: run.
                switch_profile(p, params, SpeedProfile::Rushed);
                set_state(p, PedState::RunningAcross, frame, events);
            }
        }
        PedState::PausingMidCross => {
            if p.pause_is_distraction {
                if t >= DISTRACTION_PAUSE_S {
                    p.on_phone = false;
                    p.pause_is_distraction = false;
                    set_state(p, p.resume, frame, events);
                }
                return;
            }
            if group_conflict.is_some() {
                p.conflict_clear_s = 0.0;
                if p.blocked_by_standing && t >= BLOCKED_RETREAT_S {
                    // Blocked by a vehicle that waits for us: step back to the curb and let it go.
                    set_state(p, PedState::Retreat, frame, events);
                }
            } else {
                p.conflict_clear_s += ctx.dt_s;
                if p.conflict_clear_s >= CONFLICT_CLEAR_S {
                    p.conflict_active = false;
                    let next = if p.min_ttc_s < RUN_TTC_FRACTION * p.ttc_threshold_s {
                        PedState::RunningAcross
                    } else {
                        p.resume
                    };
                    if next == PedState::RunningAcross {
                        switch_profile(p, params, SpeedProfile::Rushed);
                    }
                    set_state(p, next, frame, events);
                }
            }
        }
        PedState::Retreat => {
            let Some(line) = p.line else {
                return;
            };
            if line.along_m(p.pos) <= -CURB_STANDOFF_M + 1e-6 {
                p.conflict_active = false;
                p.at_curb = true;
                switch_profile(p, params, p.initial_profile);
                set_state(p, PedState::CheckingTraffic, frame, events);
            }
        }
        PedState::FinishedCrossing => {
            let Some(line) = p.line else {
                return;
            };
            if line.along_m(p.pos) >= line.end_along_m() - 0.05 || t > 3.0 {
                switch_profile(p, params, p.initial_profile);
                let side = if p.rng.random_bool(0.5) { 1.0 } else { -1.0 };
                p.walker = SidewalkWalker::start(ctx.net, p.pos, line.dir.perp() * side);
                set_state(p, PedState::WalkingSidewalk, frame, events);
            }
        }
        PedState::DistractedBehavior => {
            if t >= p.distraction_len_s {
                p.on_phone = false;
                if p.initial_profile != SpeedProfile::Distracted {
                    switch_profile(p, params, p.initial_profile);
                }
                let resume = p.resume;
                set_state(p, resume, frame, events);
            }
        }
    }
}

fn abandon(p: &mut Ped, ctx: &StepCtx) {
    p.attempt_over = true;
    let dir = p.line.map_or(DVec2::X, |l| l.dir.perp());
    let side = if p.rng.random_bool(0.5) { 1.0 } else { -1.0 };
    p.walker = SidewalkWalker::start(ctx.net, p.pos, dir * side);
}

/// A follower copies its leader's state in the same frame (and its decision, phone use and speed profile).
pub(crate) fn follow(p: &mut Ped, leader: &LeaderFacts, ctx: &StepCtx, events: &mut Vec<Event>) {
    let frame = ctx.next_frame;
    if leader.decided && !p.decided {
        decide_to_cross(p, frame, events);
    }
    if leader.attempt_over && !p.attempt_over {
        p.attempt_over = true;
    }
    if p.attempt_over && leader.state == PedState::WalkingSidewalk && !p.walker.active {
        p.walker = SidewalkWalker::start(ctx.net, p.pos, leader.walker_heading);
    }
    if leader.state == PedState::CheckingTraffic && p.state == PedState::Retreat {
        p.at_curb = true;
    }
    p.on_phone = leader.on_phone;
    p.profile = leader.profile;
    set_state(p, leader.state, frame, events);
}

/// What followers need of their leader.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeaderFacts {
    pub state: PedState,
    pub on_phone: bool,
    pub decided: bool,
    pub attempt_over: bool,
    pub profile: SpeedProfile,
    /// Progress along the leader's crossing, as a fraction of its width.
    pub fraction: f64,
    pub walker_heading: DVec2,
}

/// Desired velocity of a pedestrian in AI mode (sidewalk), before avoidance.
fn ai_velocity(p: &mut Ped, ctx: &StepCtx, speed: f64) -> DVec2 {
    if speed <= 0.0 {
        return DVec2::ZERO;
    }
    if !p.attempt_over {
        // Walking to the curb point of the planned crossing.
        let Some(line) = p.line else {
            return DVec2::ZERO;
        };
        let to = line.curb_point() - p.pos;
        let d = to.length();
        if d < 0.05 {
            p.at_curb = true;
            return DVec2::ZERO;
        }
        return to / d * speed.min(d / ctx.dt_s);
    }
    if p.standing || !p.walker.active {
        return DVec2::ZERO;
    }
    let mut target = p.walker.target(ctx.net);
    let mut guard = 0;
    while (target - p.pos).length() < 0.3 && guard < 4 {
        let heading = (target - p.pos)
            .try_normalize()
            .unwrap_or_else(|| DVec2::from_angle(p.yaw_rad));
        p.walker.advance(ctx.net, heading);
        target = p.walker.target(ctx.net);
        guard += 1;
    }
    let to = target - p.pos;
    let d = to.length();
    if d < 1e-9 {
        return DVec2::ZERO;
    }
    to / d * speed.min(d / ctx.dt_s)
}

/// Moves pedestrian `i` for one step. `others` are every pedestrian's positions at the start of the step (for
/// avoidance); `leader` is set for group followers.
pub(crate) fn move_ped(p: &mut Ped, ctx: &StepCtx, others: &[DVec2], self_index: usize, leader: Option<&LeaderFacts>) {
    let m = &ctx.params.speed_profiles.multipliers;
    let dt = ctx.dt_s;
    let old = p.pos;
    let manual = p.is_crossing_motion() || p.state == PedState::FinishedCrossing;
    let mut new_pos;
    if manual && let Some(line) = p.line {
        let along = line.along_m(old);
        let on_line = line.near_curb + line.dir * along;
        let off = old - on_line;
        if let (Some(l), false) = (leader, p.state == PedState::FinishedCrossing) {
            // Followers keep their leader's progress along their own line.
            let step = line.near_curb + line.dir * (l.fraction * line.width_m) + off * 0.8 - old;
            // Never faster than its own speed in this state (with slack for a wider line than the leader's).
            new_pos = old + clamp_length(step, 1.3 * p.own_speed_mps(m) * dt);
        } else {
            let speed = match p.state {
                PedState::PausingMidCross => 0.0,
                PedState::Retreat => p.retreat_speed_mps,
                _ if p.group_speed_mps > 0.0 && p.state != PedState::FinishedCrossing => p.group_speed_mps,
                _ => p.own_speed_mps(m),
            };
            let target_along = if p.state == PedState::Retreat {
                (along - speed * dt).max(-CURB_STANDOFF_M)
            } else {
                (along + speed * dt).min(line.end_along_m())
            };
            // Manual control: along the crossing vector, pulled back onto the line if off it, never faster
            // than the state's speed.
            let step = line.near_curb + line.dir * target_along + off * 0.8 - old;
            new_pos = old + clamp_length(step, speed * dt);
        }
    } else {
        let speed = match p.state {
            PedState::DistractedBehavior => {
                let f = p.state_time_s / p.distraction_len_s.max(1e-6);
                if (0.3..0.6).contains(&f) {
                    0.0
                } else {
                    p.own_speed_mps(m)
                }
            }
            _ => p.own_speed_mps(m),
        };
        let mut v = ai_velocity(p, ctx, speed);
        if speed > 0.0 && v != DVec2::ZERO {
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
    let hit = ctx.net.lane_at(new_pos);
    if !manual
        && new_pos != old
        && hit.is_some_and(|h| h.lane_type == LaneType::Driving)
        && p.lane_type != Some(LaneType::Driving)
    {
        p.walker.turn_around();
        new_pos = old;
    } else if let Some(h) = hit {
        p.z_m = h.z_m;
        p.lane_type = Some(h.lane_type);
    } else {
        p.lane_type = None;
    }
    let step = new_pos - old;
    p.velocity = step / dt;
    p.pos = new_pos;
    let dist = step.length();
    if dist > 1e-4 {
        // Facing the way it walks (turned around when retreating).
        p.yaw_rad = step.y.atan2(step.x);
    } else if let Some(line) = p.line
        && !p.attempt_over
        && p.at_curb
    {
        p.yaw_rad = line.dir.y.atan2(line.dir.x);
    }
    p.gait_phase = (p.gait_phase + dist / STRIDE_M).fract();
    if p.state.is_crossing() && p.entered_road_check() {
        p.entered_road = true;
    }
    p.state_time_s += dt;
    if p.at_curb && !p.decided && !p.attempt_over {
        p.wait_s += dt;
    }
}

impl Ped {
    fn entered_road_check(&self) -> bool {
        self.lane_type == Some(LaneType::Driving)
    }

    /// Head yaw relative to the body for this frame: scanning sweeps, checks look at the nearest vehicle side.
    pub fn update_head(&mut self, time_s: f64, vehicles: &[Vehicle]) {
        self.head_yaw_rad = match self.state {
            PedState::LookingAround => 1.0 * (std::f64::consts::TAU * 0.5 * self.state_time_s).sin(),
            PedState::CheckingTraffic | PedState::Hesitating | PedState::RunningAcross | PedState::PausingMidCross => {
                let nearest = vehicles.iter().min_by(|a, b| {
                    a.pose
                        .pos
                        .distance_squared(self.pos)
                        .total_cmp(&b.pose.pos.distance_squared(self.pos))
                });
                match nearest {
                    Some(v) => {
                        let d = v.pose.pos - self.pos;
                        wrap(d.y.atan2(d.x) - self.yaw_rad).clamp(-1.4, 1.4)
                    }
                    None => 0.0,
                }
            }
            _ if self.on_phone => 0.0,
            _ => 0.15 * (time_s * 0.7 + f64::from(self.id)).sin(),
        };
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

fn wrap(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    } else if a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    }
    a
}
