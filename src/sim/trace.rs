//! The simulation's output: a per-frame trace of every agent and an event list. The dataset writer and the
//! tests read it; the simulation is its only producer.
//!
//! Positions are world coordinates (right-handed, x east, y north, z up, metres); yaw is radians
//! counter-clockwise from +x; frame `f` is at simulated time `f / fps` seconds.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

pub use crate::sim::signals::{LightState, WalkSignal};

use crate::world::LaneType;

/// The paper's 12 behaviour states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub enum PedState {
    /// AI-controlled navigation along the sidewalk.
    WalkingSidewalk,
    /// Visual scanning (attention-driven).
    LookingAround,
    /// Assessing vehicle proximity (TTC).
    CheckingTraffic,
    /// Pausing at the road edge.
    Hesitating,
    /// Steady crossing at base speed.
    CrossingRoad,
    /// Abrupt entry without checking.
    SuddenCrossing,
    /// Mid-block crossing.
    Jaywalking,
    /// High-speed crossing when a vehicle approaches.
    RunningAcross,
    /// Stopped mid-road (lookahead conflict).
    PausingMidCross,
    /// Phone use / inattention.
    DistractedBehavior,
    /// Reached the opposite sidewalk.
    FinishedCrossing,
    /// Mid-crossing reversal.
    Retreat,
}

impl PedState {
    /// All states in the paper's order.
    pub const ALL: [PedState; 12] = [
        Self::WalkingSidewalk,
        Self::LookingAround,
        Self::CheckingTraffic,
        Self::Hesitating,
        Self::CrossingRoad,
        Self::SuddenCrossing,
        Self::Jaywalking,
        Self::RunningAcross,
        Self::PausingMidCross,
        Self::DistractedBehavior,
        Self::FinishedCrossing,
        Self::Retreat,
    ];

    /// The state's name as written in tables (`WALKING_SIDEWALK`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Self::WalkingSidewalk => "WALKING_SIDEWALK",
            Self::LookingAround => "LOOKING_AROUND",
            Self::CheckingTraffic => "CHECKING_TRAFFIC",
            Self::Hesitating => "HESITATING",
            Self::CrossingRoad => "CROSSING_ROAD",
            Self::SuddenCrossing => "SUDDEN_CROSSING",
            Self::Jaywalking => "JAYWALKING",
            Self::RunningAcross => "RUNNING_ACROSS",
            Self::PausingMidCross => "PAUSING_MID_CROSS",
            Self::DistractedBehavior => "DISTRACTED_BEHAVIOR",
            Self::FinishedCrossing => "FINISHED_CROSSING",
            Self::Retreat => "RETREAT",
        }
    }

    /// Whether the state is crossing-type (the paper's label condition (i)).
    pub fn is_crossing(self) -> bool {
        matches!(
            self,
            Self::CrossingRoad | Self::SuddenCrossing | Self::Jaywalking | Self::RunningAcross | Self::PausingMidCross
        )
    }
}

/// Whether a body pitch is level (left out of serialised traces).
fn is_level(pitch_rad: &f64) -> bool {
    *pitch_rad == 0.0
}

/// A vehicle (ego or traffic) in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VehicleFrame {
    /// Centre of the vehicle's ground footprint.
    pub pos: DVec3,
    /// Heading.
    pub yaw_rad: f64,
    /// Body pitch about the ground point, nose up positive: the ego's pitch wobble (`traffic.ego.pitch_wobble`),
    /// 0 for every other vehicle and without the wobble.
    #[serde(default, skip_serializing_if = "is_level")]
    pub pitch_rad: f64,
    /// Speed along the heading, m/s.
    pub speed_mps: f64,
    /// Longitudinal acceleration, m/s².
    pub accel_mps2: f64,
    /// Whether it is stopping for an emergency vehicle (an approaching siren).
    pub yielding: bool,
    /// The state of the traffic light at the next stop line on its path, if one is within 80 m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightState>,
}

/// A cyclist (bicycle and rider) in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CyclistFrame {
    /// Ground point under the middle of the bicycle (between the wheels' contact points).
    pub pos: DVec3,
    /// Heading.
    pub yaw_rad: f64,
    /// Speed along the heading, m/s.
    pub speed_mps: f64,
    /// Longitudinal acceleration, m/s².
    pub accel_mps2: f64,
    /// Crank angle in [0, 1) turns (advances with distance ridden; the wheels turn with it).
    pub crank_phase: f64,
    /// Distance ridden since the clip's start, metres (the wheels' rotation).
    pub ridden_m: f64,
    /// Whether it is swerving around a pedestrian.
    pub swerving: bool,
    /// Whether it rides in a bike lane (OpenDRIVE `biking`) beside its route's driving lane.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub in_bike_lane: bool,
    /// The state of the traffic light at the next stop line on its path, if one is within 80 m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightState>,
}

/// A pedestrian in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PedFrame {
    /// Ground point under the pedestrian's body centre.
    pub pos: DVec3,
    /// Body heading.
    pub yaw_rad: f64,
    /// Velocity in the ground plane, m/s.
    pub velocity: DVec2,
    /// Behaviour state.
    pub state: PedState,
    /// Lane type under the pedestrian (None off the road network).
    pub lane_type: Option<LaneType>,
    /// Head yaw relative to the body, radians (scanning and traffic checks turn the head).
    pub head_yaw_rad: f64,
    /// Gait phase in [0, 1): advances with distance walked.
    pub gait_phase: f64,
    /// Whether the pedestrian is using a phone.
    pub on_phone: bool,
    /// The gesture being made to the ego's driver, with the time since it began, seconds.
    pub gesture: Option<(Gesture, f64)>,
    /// The pedestrian's reaction to a vehicle, in JAAD's terms.
    pub reaction: Option<Reaction>,
    /// The pedestrian signal of the signalised crosswalk its crossing runs along, where lights run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walk_signal: Option<WalkSignal>,
    /// Whether it stands on a crosswalk.
    #[serde(default)]
    pub on_crosswalk: bool,
}

#[cfg(test)]
impl PedFrame {
    /// A pedestrian standing still at the origin on the sidewalk, facing +x, head straight, doing nothing (for
    /// tests: override what matters with `PedFrame { .., ..PedFrame::STILL }`).
    pub(crate) const STILL: PedFrame = PedFrame {
        pos: DVec3::ZERO,
        yaw_rad: 0.0,
        velocity: DVec2::ZERO,
        state: PedState::WalkingSidewalk,
        lane_type: None,
        head_yaw_rad: 0.0,
        gait_phase: 0.0,
        on_phone: false,
        gesture: None,
        reaction: None,
        walk_signal: None,
        on_crosswalk: false,
    };
}

/// A gesture to the ego's driver (PIE's `gesture` labels; DATASET.md maps them to JAAD's).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gesture {
    /// A raised hand acknowledging (thanking) a driver who yields.
    HandAck,
    /// A wave of the hand letting the driver go first.
    HandYield,
    /// A nod acknowledging a driver who yields.
    Nod,
}

impl Gesture {
    /// The gesture's name as written in tables (PIE's words).
    pub fn name(self) -> &'static str {
        match self {
            Self::HandAck => "hand_ack",
            Self::HandYield => "hand_yield",
            Self::Nod => "nod",
        }
    }

    /// How long the gesture lasts, seconds.
    pub fn duration_s(self) -> f64 {
        match self {
            Self::HandAck => 1.2,
            Self::HandYield => 1.6,
            Self::Nod => 0.8,
        }
    }
}

/// A pedestrian's reaction to a vehicle (JAAD's `reaction` labels).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reaction {
    /// Steps back out of the vehicle's path (a retreat).
    ClearPath,
    /// Hurries (running across because a vehicle approaches).
    SpeedUp,
    /// Stops on the road for a vehicle (a lookahead conflict).
    SlowDown,
}

impl Reaction {
    /// The reaction's name as written in tables (JAAD's words).
    pub fn name(self) -> &'static str {
        match self {
            Self::ClearPath => "clear_path",
            Self::SpeedUp => "speed_up",
            Self::SlowDown => "slow_down",
        }
    }
}

/// Something that happened in a clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// A pedestrian changed state.
    StateChange {
        /// Frame of the change.
        frame: u32,
        /// The pedestrian.
        pedestrian: PedestrianId,
        /// Previous state.
        from: PedState,
        /// New state.
        to: PedState,
    },
    /// A pedestrian decided to cross (intention onset: gap accepted, sudden trigger, or injection).
    CrossingDecision {
        /// Frame of the decision.
        frame: u32,
        /// The pedestrian.
        pedestrian: PedestrianId,
    },
    /// An in-road conflict: a vehicle within the lookahead radius of a crossing pedestrian.
    Conflict {
        /// Frame.
        frame: u32,
        /// The pedestrian.
        pedestrian: PedestrianId,
        /// The vehicle.
        vehicle: VehicleId,
        /// Whether the conflict happened in the retreat window (the first part of the crossing).
        in_retreat_window: bool,
        /// Whether the once-per-conflict retreat draw said retreat.
        retreated: bool,
    },
    /// A pedestrian's patience cap expired.
    PatienceExpired {
        /// Frame.
        frame: u32,
        /// The pedestrian.
        pedestrian: PedestrianId,
        /// Whether it then crossed suddenly (otherwise it abandoned the attempt).
        sudden_crossing: bool,
    },
    /// A vehicle met a red light: it passed the stop line on red (`ran`), or it came to a stop before it.
    RedLight {
        /// Frame: the first whose recorded state is past the line, or stopped.
        frame: u32,
        /// The vehicle.
        vehicle: VehicleId,
        /// The light (index into the trace's `signals`).
        signal: u32,
        /// Whether it ran the red light (else it stopped for it).
        ran: bool,
        /// It heeds lights but had committed to the line: it could not stop when it first saw the light amber or
        /// red (the dilemma zone, or placed too close to a red light at the clip's start). A light run by a
        /// vehicle drawn to ignore lights, or by an emergency vehicle, never is; nor one run by a vehicle that
        /// could have stopped (none should be: tests/it/signals.rs).
        unavoidable: bool,
    },
    /// A vehicle finished overtaking a cyclist: its rear passed the bicycle's front.
    OvertookCyclist {
        /// Frame: the first whose recorded state is past the cyclist.
        frame: u32,
        /// The vehicle (the ego or traffic).
        vehicle: VehicleId,
        /// The cyclist.
        cyclist: u32,
        /// The smallest side-to-side distance between the vehicle's footprint and the bicycle's while they
        /// were alongside, metres.
        min_clearance_m: f64,
    },
    /// A cyclist reacted to a pedestrian in its path: it swerved around it or braked for it (once per
    /// cyclist, pedestrian and kind).
    CyclistYielded {
        /// Frame: the first whose recorded state reflects the reaction.
        frame: u32,
        /// The cyclist.
        cyclist: u32,
        /// The pedestrian.
        pedestrian: PedestrianId,
        /// Whether it swerved (else it braked).
        swerved: bool,
    },
    /// A vehicle touched a pedestrian or another vehicle (recorded, never hidden).
    Contact {
        /// Frame.
        frame: u32,
        /// The vehicle.
        vehicle: VehicleId,
        /// The pedestrian, if a pedestrian was touched.
        pedestrian: Option<PedestrianId>,
        /// The other vehicle, if a vehicle was touched.
        other_vehicle: Option<VehicleId>,
    },
}

/// A vehicle of a clip: the ego, or traffic vehicle `n` of the clip script (`ClipScript::vehicles[n]`).
///
/// Ordered with the ego first, then traffic by number: the order of right of way when two vehicles tie.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VehicleId {
    /// The ego vehicle (the one carrying the sensors).
    Ego,
    /// A traffic vehicle, by its id in the clip script.
    Traffic(u32),
    /// A cyclist, by its id in the clip script (`ClipScript::cyclists`).
    Cyclist(u32),
}

impl VehicleId {
    /// The traffic vehicle's id, `None` for the ego (the tables' nullable `vehicle` column).
    pub fn traffic(self) -> Option<u32> {
        match self {
            VehicleId::Traffic(n) => Some(n),
            VehicleId::Ego | VehicleId::Cyclist(_) => None,
        }
    }

    /// The cyclist's id, `None` for motor vehicles (the tables' nullable `cyclist` column).
    pub fn cyclist(self) -> Option<u32> {
        match self {
            VehicleId::Cyclist(n) => Some(n),
            VehicleId::Ego | VehicleId::Traffic(_) => None,
        }
    }
}

/// A pedestrian of a clip, by its id in the clip script (`PedestrianScript::id`, also its index there).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct PedestrianId(pub u32);

impl PedestrianId {
    /// The pedestrian's index in the clip script and the trace.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The trace of one simulated clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClipTrace {
    /// Clip id.
    pub clip_id: String,
    /// Frames per second.
    pub fps: u32,
    /// Number of frames.
    pub frame_count: u32,
    /// The ego, per frame.
    pub ego: Vec<VehicleFrame>,
    /// Traffic vehicles, `[vehicle][frame]`.
    pub vehicles: Vec<Vec<VehicleFrame>>,
    /// Pedestrians, `[pedestrian][frame]`.
    pub pedestrians: Vec<Vec<PedFrame>>,
    /// Cyclists, `[cyclist][frame]` (empty without cyclists).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cyclists: Vec<Vec<CyclistFrame>>,
    /// Events in frame order.
    pub events: Vec<Event>,
    /// The town's traffic lights and their state per frame (empty where lights do not run).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub signals: Vec<SignalTrack>,
}

/// One traffic light of a clip's town and its state in every frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalTrack {
    /// The light's id in the town (`pedsynth town show` lists them).
    pub id: String,
    /// Its junction's id.
    pub junction: String,
    /// The phase of the junction's plan in which it is green.
    pub phase: u32,
    /// Centre of the head, world metres.
    pub position: DVec3,
    /// The direction its lamps face, radians.
    pub facing_rad: f64,
    /// State per frame.
    pub states: Vec<LightState>,
}
