//! Every behavioural constant of the pedestrian model, in one place, each with its source.
//!
//! Sources are named as: **paper** (the ARCANE-PedSynth paper's text or tables), **seed** (the paper's public
//! code, `shared/reference/seed-system-facts.md`), **CARLA** (CARLA's walker AI, `carla-sensors-and-behaviour.md`
//! §7), **literature** (a cited observation of real pedestrians), or **pedsynth** (a modelling choice of ours,
//! with the reason). The parameters a spec can set (gap acceptance, lookahead, retreat, patience, decision
//! window, speed profiles, archetypes) are not here: they come from the spec through [`crate::plan::SimParams`]
//! and the clip script.

// --- Approach and waiting at the curb -------------------------------------------------------------------------

/// Where a crosser stands before stepping onto the road: this far behind the near curb, metres. pedsynth: one
/// short step back from the edge (the planner places crossers there too).
pub const CURB_STANDOFF_M: f64 = crate::plan::CURB_STANDOFF_M;
/// A walker heading for its curb point has arrived within this distance, metres. pedsynth: its last step lands
/// on the point (a step never overshoots), so this only absorbs rounding.
pub const CURB_ARRIVAL_M: f64 = 0.005;
/// A pedestrian walking to the curb slows down over this last distance, metres ... literature: pedestrians
/// decelerate on the last step or two before the curb (Rasouli & Tsotsos 2020).
pub const CURB_SLOWDOWN_M: f64 = 1.5;
/// ... to at least this share of its speed.
pub const CURB_SLOWDOWN_MIN: f64 = 0.4;
/// Shortest traffic check before a decision, seconds. pedsynth: one glance each way takes about half a second.
pub const CHECK_MIN_S: f64 = 0.5;
/// A committed crosser stops hesitating when the ego comes this much closer than the decision window's near
/// edge, metres. pedsynth: stepping out later would be unsafe for the ego's braking rule.
pub const HESITATION_CUTOFF_M: f64 = 3.0;
/// A crosser committing inside the decision window waits only for another vehicle this close in time, seconds.
/// pedsynth: the paper's crosser "commits ... as soon as the ego-vehicle is within the decision window"; a
/// vehicle two seconds away is still a hard stop for anyone.
pub const COMMIT_MIN_TTC_S: f64 = 2.0;
/// Inside the decision window's near edge a crosser still commits when the ego can stop before it at this
/// deceleration, m/s² ... pedsynth: the IDM's comfortable deceleration (CARLA reference §6).
pub const COMFORTABLE_STOP_DECEL_MPS2: f64 = 3.0;
/// ... with this much room to spare, metres.
pub const STOP_MARGIN_M: f64 = 4.0;
/// A jaywalker's brief check only waits while a vehicle would arrive within this time, seconds. pedsynth, as
/// [`COMMIT_MIN_TTC_S`].
pub const JAYWALK_MIN_TTC_S: f64 = 2.0;
/// A baseline (CARLA-like) crosser waits until no vehicle is this close, metres. CARLA: the walker AI's
/// stop-and-check waits "until no vehicle is within 6 m".
pub const BASELINE_CLEAR_M: f64 = 6.0;
/// A sudden crosser (or one whose patience runs out) does not step out when the ego is closer than this ahead,
/// metres. pedsynth: "sudden" is sudden for the driver, not a collision the ego cannot avoid (it still has to
/// brake hard: its braking rule starts at 15 m).
pub const SUDDEN_MIN_EGO_M: f64 = 8.0;
/// A crosser's timeline is cut short when the ego drives on (faster than this, m/s) ...
pub const CUT_SHORT_EGO_SPEED_MPS: f64 = 1.0;
/// ... closer than this, metres ...
pub const CUT_SHORT_EGO_DISTANCE_M: f64 = 16.0;
/// ... and the camera has seen the crosser at least this long, seconds (so that its track starts before its
/// crossing). pedsynth: crossing in front of the ego, seen briefly, rather than behind it, unseen.
pub const CUT_SHORT_MIN_IN_VIEW_S: f64 = 0.5;
/// A sudden crosser turns onto the road once within this distance of its curb point, metres (it does not stop
/// at the curb). pedsynth.
pub const SUDDEN_FROM_CURB_M: f64 = 3.0;
/// A group follower needs to have been seen for at most this long before its group steps out, seconds (it is
/// seen with its leader; a follower half hidden behind its leader still gets a track before its crossing).
pub const FOLLOWER_MAX_IN_VIEW_S: f64 = 1.0;
/// A gap tighter than this multiple of the crosser's gap threshold is closed rushed. paper: the rushed profile
/// applies "when closing a tight gap"; pedsynth: 1.5× the threshold is "tight".
pub const RUSHED_GAP_FACTOR: f64 = 1.5;

// --- On the road ----------------------------------------------------------------------------------------------

/// A conflict ends after the lookahead has been clear this long, seconds. pedsynth: half a second of clear
/// lookahead before walking on avoids stop-and-go flicker.
pub const CONFLICT_CLEAR_S: f64 = 0.5;
/// A vehicle slower than this is not a lookahead conflict, m/s. pedsynth: it has stopped for the pedestrian;
/// counting it would make both wait forever.
pub const CONFLICT_MIN_VEHICLE_SPEED_MPS: f64 = 0.5;
/// A standing vehicle blocks the next step when its footprint is within the pedestrian's radius plus this,
/// metres. pedsynth.
pub const BLOCKING_CLEARANCE_M: f64 = 0.2;
/// A pedestrian blocked this long by a standing vehicle steps back to the curb (not a retreat draw), seconds.
/// pedsynth: lets the vehicle go rather than wait forever.
pub const BLOCKED_RETREAT_S: f64 = 3.0;
/// A crosser on the road runs when a vehicle would arrive within this fraction of its own TTC threshold.
/// paper: RUNNING_ACROSS is triggered by "vehicle proximity"; pedsynth: half the threshold.
pub const RUN_TTC_FRACTION: f64 = 0.5;
/// The crossing has finished this far beyond the far curb, metres. pedsynth: fully on the far sidewalk.
pub const FINISH_BEYOND_CURB_M: f64 = 0.3;
/// A finished crosser walks on at most this long before resuming its sidewalk walk, seconds. pedsynth.
pub const FINISHED_MAX_S: f64 = 3.0;
/// ... or once within this distance of its crossing's end point, metres. pedsynth.
pub const FINISHED_ARRIVAL_M: f64 = 0.05;
/// Share of the offset from the crossing line kept per step (the rest is corrected), manual mode. pedsynth:
/// a walker drifts back onto its line over a few steps instead of jumping.
pub const LINE_OFFSET_KEEP: f64 = 0.8;
/// A group follower may move this much faster than its own speed to keep its leader's progress on a wider
/// line. pedsynth.
pub const FOLLOWER_SPEED_SLACK: f64 = 1.3;

// --- Distraction (phone use) ----------------------------------------------------------------------------------

/// How long a distraction (phone) pause mid-road lasts, seconds. paper: PAUSING_MID_CROSS is triggered by
/// "distraction / fear"; pedsynth: one second.
pub const DISTRACTION_PAUSE_S: f64 = 1.0;
/// Range of a phone-use episode on the sidewalk, seconds. pedsynth.
pub const DISTRACTION_EPISODE_S: (f64, f64) = (2.0, 5.0);
/// Part of a phone-use episode (as fractions of its length) during which the walker stands still. paper: the
/// distracted profile has "occasional pauses to simulate phone use".
pub const DISTRACTION_STANDSTILL: std::ops::Range<f64> = 0.3..0.6;

// --- Sidewalk walking and scanning ----------------------------------------------------------------------------

/// Share of non-crossers that stand still (waiting, chatting) rather than walk. pedsynth: real footage has
/// standing pedestrians near the curb; they also are the hardest negatives for crossing models.
pub const STANDING_SHARE: f64 = 0.2;
/// Mean time between attention-driven scans of a walker: this at attention 1, plus the second value at
/// attention 0, seconds. paper: LOOKING_AROUND is triggered by an "attention threshold"; pedsynth: exponential
/// waiting times, more attentive walkers scan more often.
pub const SCAN_INTERVAL_MEAN_S: (f64, f64) = (4.0, 8.0);
/// A brief scan (jaywalkers, walkers) lasts this plus the second value × attention, seconds. pedsynth.
pub const BRIEF_SCAN_S: (f64, f64) = (0.3, 0.5);
/// A full scan at the curb lasts this plus the second value × attention, seconds. pedsynth.
pub const FULL_SCAN_S: (f64, f64) = (0.5, 1.5);
/// Pedestrians closer than this push each other apart in AI mode, metres. pedsynth: about two shoulder widths.
pub const AVOID_RADIUS_M: f64 = 1.0;
/// A sidewalk walker moves on to the next graph node within this distance of its target, metres. pedsynth.
pub const WALKER_NODE_REACHED_M: f64 = 0.3;
/// Most graph nodes a walker skips in one step. pedsynth: bounds the work per step.
pub const WALKER_MAX_SKIPS: usize = 4;
/// Stride length of one gait cycle, metres. literature: adult stride ≈ 1.4 m at the preferred walking speed
/// (≈ 1.4 m/s).
pub const STRIDE_M: f64 = 1.4;
/// A step shorter than this leaves the body's heading unchanged, metres.
pub const HEADING_MIN_STEP_M: f64 = 1e-4;

// --- Head ---------------------------------------------------------------------------------------------------

/// Head sweep while looking around: amplitude (radians) and frequency (Hz). pedsynth: a left-right scan of
/// ±57° every two seconds.
pub const LOOK_AROUND_HEAD: (f64, f64) = (1.0, 0.5);
/// Largest head turn relative to the body when checking a vehicle, radians (≈ 80°; literature: the head
/// turns up to about 80° before the shoulders follow).
pub const MAX_HEAD_TURN_RAD: f64 = 1.4;
/// Idle head sway while walking: amplitude (radians) and angular frequency (rad/s). pedsynth.
pub const IDLE_HEAD_SWAY: (f64, f64) = (0.15, 0.7);

// --- Gestures -------------------------------------------------------------------------------------------------

/// The ego counts as yielding to a pedestrian when it is ahead, nearer than this (metres) and slower than
/// [`GESTURE_EGO_MAX_SPEED_MPS`]. pedsynth: near enough for a driver to see a hand or a nod.
pub const GESTURE_EGO_MAX_DIST_M: f64 = 30.0;
/// See [`GESTURE_EGO_MAX_DIST_M`], m/s. pedsynth: a car at walking pace or stopped.
pub const GESTURE_EGO_MAX_SPEED_MPS: f64 = 3.0;
/// A crosser acknowledges a yielding driver only within this long after stepping out, seconds. pedsynth.
pub const ACKNOWLEDGE_WINDOW_S: f64 = 1.0;

// --- Groups ---------------------------------------------------------------------------------------------------

/// A follower walks a line parallel to its leader's when their own crossing lines point in directions whose
/// cosine is below this. pedsynth.
pub const GROUP_LINE_MIN_COS: f64 = 0.95;
/// ... or differ in width by more than this fraction of the leader's. pedsynth.
pub const GROUP_LINE_MAX_WIDTH_DIFF: f64 = 0.15;
