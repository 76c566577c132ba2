//! Pedestrians: the paper's 12-state behaviour machine and the two motion modes of its hybrid control.
//!
//! A [`Ped`] is its constants ([`Traits`], from the clip script and its own random stream), its body's
//! kinematics ([`Body`]), what it is doing ([`Activity`], one variant per behaviour state, with its data),
//! where its crossing attempt stands ([`Attempt`]), what it perceives ([`Percept`]) and its place in a group.
//!
//! - [`perceive`] — TTC, the ego's distance and side, the in-road lookahead (from the state at the start of
//!   the step).
//! - [`machine`] — the transition function (one explicit `match` on the activity) and group following.
//! - [`motion`] — AI mode on the sidewalk graph ([`walker`]) and manual mode along the crossing vector; the head.
//! - [`params`] — every behavioural constant with its source.
//!
//! Speeds are explicit per state ([`state_speed_mps`], [`allowed_speed_range_mps`]): standing states are 0;
//! walking, crossing, sudden and jaywalking move at base × the current speed-profile multiplier; running across
//! at base × the rushed multiplier; distracted at base × the distracted multiplier; retreat at the pedestrian's
//! retreat speed (drawn from `retreat.speed_mps`). Group members cross at the group's speed (the slowest
//! member's), synchronised by progress along their own crossing lines.

pub(crate) mod machine;
pub(crate) mod motion;
pub mod params;
pub(crate) mod perceive;
pub(crate) mod state;
pub(crate) mod walker;

use glam::DVec2;
use rand::RngExt;
use rand_chacha::ChaCha20Rng;

use crate::plan::{Behaviour, CrosserSource, PedestrianScript, Role, SimParams, SpawnPlace, SpeedProfile};
use crate::sim::trace::{Gesture, PedState, PedestrianId, WalkSignal};
use crate::spec::types::SpeedProfileMultipliers;
use crate::world::{LaneType, RoadNetwork};
use params::{CHECK_MIN_S, CURB_STANDOFF_M, DISTRACTION_EPISODE_S, FINISH_BEYOND_CURB_M, STANDING_SHARE};
pub(crate) use perceive::Percept;
use state::{Activity, Attempt, CrossMode, Distraction};
use walker::SidewalkWalker;

/// A crosser spawned this close to its curb point starts there, metres.
const AT_CURB_START_M: f64 = 0.1;

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
    let (mut lo, mut hi) = (initial, initial);
    if params.speed_profiles.switching {
        for k in [m.rushed, m.distracted] {
            lo = lo.min(k);
            hi = hi.max(k);
        }
    }
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

/// A crossing line in the simulation's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Line {
    /// Where the line leaves the near sidewalk.
    pub near_curb: DVec2,
    /// The crossing's goal on the far sidewalk.
    pub end: DVec2,
    /// Unit direction across the road.
    pub dir: DVec2,
    /// Width of the carriageway crossed, metres.
    pub width_m: f64,
}

impl Line {
    /// Signed distance along the crossing from the near curb, metres.
    pub(crate) fn along_m(&self, p: DVec2) -> f64 {
        (p - self.near_curb).dot(self.dir)
    }
    /// Where a crosser waits at the curb.
    pub(crate) fn curb_point(&self) -> DVec2 {
        self.near_curb - self.dir * CURB_STANDOFF_M
    }
    /// Distance along the line from the near curb to the end point, metres.
    pub(crate) fn end_along_m(&self) -> f64 {
        self.along_m(self.end).max(self.width_m + FINISH_BEYOND_CURB_M)
    }
}

/// A pedestrian's constants: from its script, plus a few drawn from its own stream at set-up.
#[derive(Clone, Debug)]
pub(crate) struct Traits {
    pub id: PedestrianId,
    pub role: Role,
    pub behaviour: Behaviour,
    pub source: CrosserSource,
    pub base_speed_mps: f64,
    pub hesitation_s: f64,
    pub attention: f64,
    pub ttc_threshold_s: f64,
    pub safety_margin_s: f64,
    pub patience_s: f64,
    pub initial_profile: SpeedProfile,
    /// Drawn from `retreat.speed_mps`.
    pub retreat_speed_mps: f64,
    /// Length of a phone-use episode on the sidewalk, seconds (drawn).
    pub distraction_len_s: f64,
    /// A non-crosser that stands rather than walks (drawn).
    pub standing: bool,
    /// The planned crossing (crossers).
    pub line: Option<Line>,
    /// The traffic light (index into the town's signals) of the signalised crosswalk its crossing runs along,
    /// where lights run.
    pub signal: Option<u32>,
    /// Whether it crosses against the signal (on "don't walk") when it finds a gap.
    pub red_light_violator: bool,
    /// Where the pedestrian stands along the ego's route, metres: "ahead of the ego" is decided along the route,
    /// which stays right where the route turns.
    pub route_s_m: f64,
    /// Body height, metres.
    pub height_m: f64,
    /// A crosser steps out only after the ego's camera has seen it this long, seconds (its timeline).
    pub in_view_before_crossing_s: Option<f64>,
    /// A crosser steps out only once the ego is within this distance of it, metres (`crossing.scenario`).
    pub step_out_ego_within_m: Option<f64>,
    /// Or once the ego has stopped within this distance of it, metres (`crossing.scenario`).
    pub step_out_stopped_ego_within_m: Option<f64>,
    /// A hard negative waits at the curb this long before walking on, seconds.
    pub curb_wait_s: Option<f64>,
    /// Two uniform draws in [0, 1) from the pedestrian's gesture stream: whether it gestures when the occasion
    /// comes, and which acknowledgement (nod or hand).
    pub gesture_draws: (f64, f64),
}

/// The body's kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Body {
    pub pos: DVec2,
    pub z_m: f64,
    pub yaw_rad: f64,
    pub velocity: DVec2,
    /// Lane type under the pedestrian (None off the road network).
    pub lane_type: Option<LaneType>,
    /// Head yaw relative to the body, radians.
    pub head_yaw_rad: f64,
    /// Gait phase in [0, 1).
    pub gait_phase: f64,
}

/// A pedestrian's place in a crossing group.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Group {
    /// Decides for itself, alone.
    Single,
    /// Decides for its group; the followers' indices.
    Leader(Vec<usize>),
    /// Copies its leader's decisions; the leader's index.
    Follower(usize),
}

/// One simulated pedestrian.
#[derive(Clone, Debug)]
pub(crate) struct Ped {
    pub traits: Traits,
    pub body: Body,
    pub group: Group,
    /// What it is doing.
    pub activity: Activity,
    /// Time in the current behaviour state, seconds.
    pub state_time_s: f64,
    /// Where its crossing attempt stands.
    pub attempt: Attempt,
    /// Current speed profile.
    pub profile: SpeedProfile,
    /// Its phone-use plan.
    pub distraction: Distraction,
    /// Clip time of the next attention-driven scan while walking, seconds.
    pub next_scan_s: f64,
    /// AI mode's place on the sidewalk graph.
    pub walker: SidewalkWalker,
    /// Speed of the group's crossing (leaders), m/s.
    pub group_speed_mps: f64,
    /// Time the ego's camera has seen the pedestrian so far, seconds (the simulation's estimate).
    pub in_view_s: f64,
    /// For a group leader: whether the camera has seen each follower for its planned time (set each step).
    pub followers_seen: bool,
    pub percept: Percept,
    pub rng: ChaCha20Rng,
    /// The gesture it is making and for how long so far, seconds.
    pub gesture: Option<(Gesture, f64)>,
    /// Whether its one occasion to gesture has come (and been taken or not).
    pub gestured: bool,
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

/// A crosser timing its walk to the ego (`Ped::holds_for_ego`) sets off this much earlier than the bare estimate,
/// seconds (the ego slows as it comes).
const HOLD_SLACK_S: f64 = 1.0;
/// Below this speed the ego counts as stopped for a crosser that waits for it to come near, m/s.
const EGO_STOPPED_MPS: f64 = 0.3;

impl Ped {
    /// Sets a pedestrian up from its script; draws its per-pedestrian constants from its own stream, and its
    /// gesture draws from `gesture_rng` (a stream of its own, so gestures shift no other draw).
    pub(crate) fn new(
        script: &PedestrianScript,
        params: &SimParams,
        net: &RoadNetwork,
        mut rng: ChaCha20Rng,
        mut gesture_rng: ChaCha20Rng,
    ) -> Ped {
        let retreat_speed_mps = draw(&mut rng, params.retreat.speed_mps.min(), params.retreat.speed_mps.max());
        let distraction_len_s = draw(&mut rng, DISTRACTION_EPISODE_S.0, DISTRACTION_EPISODE_S.1);
        let standing = rng.random_bool(STANDING_SHARE);
        let next_scan_s = motion::scan_interval_s(&mut rng, script.attention);
        let line = script.crossing.as_ref().map(|c| Line {
            near_curb: c.near_curb,
            end: c.end,
            dir: c.direction.normalize_or(DVec2::X),
            width_m: c.carriageway_width_m.max(0.1),
        });
        // Crossers, and hard negatives (who act like crossers up to the decision), head for their curb.
        let tries = (script.role == Role::Crosser || script.behaviour == Behaviour::HardNegative) && line.is_some();
        let mut p = Ped {
            traits: Traits {
                id: PedestrianId(script.id),
                role: script.role,
                behaviour: script.behaviour,
                source: script.crosser_source,
                base_speed_mps: script.base_speed_mps.max(0.05),
                hesitation_s: script.hesitation_s.max(0.0),
                attention: script.attention.clamp(0.0, 1.0),
                ttc_threshold_s: script.ttc_threshold_s,
                safety_margin_s: script.safety_margin_s,
                patience_s: script.patience_s,
                initial_profile: script.speed_profile,
                retreat_speed_mps,
                distraction_len_s,
                standing,
                line,
                signal: None,
                red_light_violator: script.red_light_violator,
                route_s_m: script.ahead_of_ego_m,
                height_m: script.identity.height_m,
                in_view_before_crossing_s: script.in_view_before_crossing_s,
                step_out_ego_within_m: script.step_out_ego_within_m,
                step_out_stopped_ego_within_m: script.step_out_stopped_ego_within_m,
                curb_wait_s: script.curb_wait_s,
                gesture_draws: (gesture_rng.random::<f64>(), gesture_rng.random::<f64>()),
            },
            body: Body {
                pos: script.spawn,
                z_m: 0.0,
                yaw_rad: script.spawn_heading_rad,
                velocity: DVec2::ZERO,
                lane_type: None,
                head_yaw_rad: 0.0,
                gait_phase: 0.0,
            },
            group: Group::Single,
            activity: Activity::WalkingSidewalk,
            state_time_s: 0.0,
            attempt: if tries {
                Attempt::Undecided {
                    at_curb: false,
                    waited_s: 0.0,
                }
            } else {
                Attempt::Over { decided: false }
            },
            profile: script.speed_profile,
            distraction: script.distracted_at_s.map_or(Distraction::Never, Distraction::At),
            next_scan_s,
            walker: SidewalkWalker::default(),
            group_speed_mps: 0.0,
            in_view_s: 0.0,
            followers_seen: true,
            percept: Percept::default(),
            rng,
            gesture: None,
            gestured: false,
        };
        if let Some(h) = net.lane_at(p.body.pos) {
            p.body.z_m = h.z_m;
            p.body.lane_type = Some(h.lane_type);
        }
        if p.attempt.over() {
            p.walker = SidewalkWalker::start(net, p.body.pos, DVec2::from_angle(script.spawn_heading_rad));
        }
        if script.behaviour == Behaviour::MidroadJaywalker && script.spawn_place == SpawnPlace::DrivingLane {
            p.activity = Activity::Crossing(CrossMode::Jaywalking);
            p.attempt.decide();
        } else if script.crosser_source != CrosserSource::None
            && matches!(script.behaviour, Behaviour::Normal | Behaviour::Jaywalk)
            && line.is_some_and(|l| l.curb_point().distance(p.body.pos) < AT_CURB_START_M)
            && script.ahead_of_ego_m <= params.decision_window_m.max()
        {
            // A crosser that starts at its curb with the ego already inside the decision window has been waiting
            // there before the clip began: it is already checking traffic (a jaywalker: glancing).
            p.attempt.reach_curb();
            p.activity = if script.behaviour == Behaviour::Jaywalk {
                Activity::LookingAround
            } else {
                Activity::CheckingTraffic
            };
            p.state_time_s = CHECK_MIN_S;
        }
        p
    }

    /// The labelled behaviour state.
    pub(crate) fn state(&self) -> PedState {
        self.activity.label()
    }

    /// Whether it holds a phone.
    pub(crate) fn on_phone(&self) -> bool {
        self.activity.on_phone()
    }

    /// The multiplier of its current speed profile.
    fn multiplier(&self, m: &SpeedProfileMultipliers) -> f64 {
        profile_multiplier(m, self.profile)
    }

    /// The pedestrian's own speed in its current state, m/s.
    pub(crate) fn own_speed_mps(&self, m: &SpeedProfileMultipliers) -> f64 {
        state_speed_mps(
            self.state(),
            self.traits.base_speed_mps,
            self.profile,
            self.traits.retreat_speed_mps,
            m,
        )
    }

    /// The leader's index, for a group follower.
    pub(crate) fn leader(&self) -> Option<usize> {
        match self.group {
            Group::Follower(l) => Some(l),
            _ => None,
        }
    }

    /// Whether the ego's camera has seen the pedestrian for its planned time before crossing, `lead_s` seconds
    /// from now (always, without a timeline).
    pub(crate) fn seen_long_enough(&self, lead_s: f64) -> bool {
        self.traits
            .in_view_before_crossing_s
            .is_none_or(|t| self.in_view_s + lead_s >= t)
    }

    /// Whether the ego is near enough for it to step out, where its scenario asks for that
    /// (`crossing.scenario.crosser_ego_within_m`; always otherwise, and once the ego has passed).
    /// Where the scenario says so (`crosser_stopped_ego_within_m`), a stopped ego within that distance counts as
    /// near: real crossers go in front of a car that waits (for them, or for others crossing before it), and a
    /// car held by a stream of crossers would otherwise never come near those who wait for it.
    pub(crate) fn ego_near_enough(&self) -> bool {
        self.traits
            .step_out_ego_within_m
            .is_none_or(|d| !self.percept.ego_ahead || self.percept.ego_dist_m <= d || self.ego_waits_near())
    }

    /// Whether the ego is ahead and stopped within the crosser's `step_out_stopped_ego_within_m`.
    fn ego_waits_near(&self) -> bool {
        self.traits.step_out_stopped_ego_within_m.is_some_and(|d| {
            self.percept.ego_ahead && self.percept.ego_speed_mps < EGO_STOPPED_MPS && self.percept.ego_dist_m <= d
        })
    }

    /// Whether a crosser that waits for the ego to come near (its scenario) stands where it is for now, rather
    /// than walk on to its curb: it times its walk so that it arrives as the ego comes within its distance, as
    /// real crossers walk up and into the road in front of a car that has slowed for them.
    pub(crate) fn holds_for_ego(&self, speed_mps: f64) -> bool {
        let (Some(d), Some(line)) = (self.traits.step_out_ego_within_m, self.traits.line) else {
            return false;
        };
        if self.attempt.over() || self.attempt.at_curb() || !self.percept.ego_ahead || self.ego_waits_near() {
            return false;
        }
        let walk_s = line.curb_point().distance(self.body.pos) / speed_mps.max(0.3);
        let ego_s = (self.percept.ego_dist_m - d) / self.percept.ego_speed_mps.max(0.5);
        ego_s > walk_s + HOLD_SLACK_S
    }

    /// Whether its signalised crosswalk shows "don't walk" (or flashes) and it is not one to cross against the
    /// signal: it waits for "walk", and drivers with green do not stop for it.
    pub(crate) fn waits_for_walk(&self) -> bool {
        self.percept.walk.is_some_and(|w| w != WalkSignal::Walk) && !self.traits.red_light_violator
    }

    /// Whether it heads for its curb point or waits there (a crosser or hard negative on the sidewalk, not yet
    /// across): what makes the ego ease off.
    pub(crate) fn heading_for_curb(&self) -> bool {
        !self.waits_for_walk() && self.traits.line.is_some() && !self.attempt.over() && !self.activity.crossing_motion()
    }

    /// Whether it waits at its curb point attentively (looking, checking the traffic, hesitating): what makes the
    /// ego stop short and let it go.
    pub(crate) fn waiting_at_curb(&self) -> bool {
        !self.waits_for_walk()
            && self.attempt.at_curb()
            && !self.attempt.over()
            && matches!(
                self.activity,
                Activity::LookingAround | Activity::CheckingTraffic | Activity::Hesitating
            )
    }

    /// The followers' indices (empty unless a group leader).
    pub(crate) fn followers(&self) -> &[usize] {
        match &self.group {
            Group::Leader(f) => f,
            _ => &[],
        }
    }
}

fn draw(rng: &mut ChaCha20Rng, lo: f64, hi: f64) -> f64 {
    if hi > lo { rng.random_range(lo..=hi) } else { lo }
}

/// What followers need of their leader.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeaderFacts {
    pub activity: Activity,
    pub decided: bool,
    pub attempt_over: bool,
    pub profile: SpeedProfile,
    /// Progress along the leader's crossing, as a fraction of its width.
    pub fraction: f64,
    pub walker_heading: DVec2,
}

impl LeaderFacts {
    /// The facts of leader `p`, with its progress `fraction` along its crossing.
    pub(crate) fn of(p: &Ped, fraction: f64) -> LeaderFacts {
        LeaderFacts {
            activity: p.activity,
            decided: p.attempt.decided(),
            attempt_over: p.attempt.over(),
            profile: p.profile,
            fraction,
            walker_heading: DVec2::from_angle(p.body.yaw_rad),
        }
    }
}
