//! `crossing`: crossing-rate control — the target, the four layers (paper, Table "Four-layer crossing rate
//! engineering strategy"), gap acceptance, the in-road lookahead, retreat and patience.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::Range;

/// Crossing-rate control and crossing behaviour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Crossing {
    /// Target share of pedestrians that cross (sequence level).
    pub target_ratio: f64,
    /// Share of pedestrians not allocated as crossers that still cross on their own, as CARLA's AI walkers do
    /// (about 9%).
    pub baseline_ratio: f64,
    /// The paper's four crossing-rate layers.
    pub layers: Layers,
    /// Time-to-collision gap acceptance.
    pub gap_acceptance: GapAcceptance,
    /// In-road lookahead while crossing.
    pub lookahead: Lookahead,
    /// Mid-crossing retreat.
    pub retreat: Retreat,
    /// What happens when a waiting pedestrian's patience cap expires.
    pub patience: Patience,
    /// A potential crosser commits when the ego vehicle is this far away, metres `[min, max]`.
    pub decision_window_m: Range,
    /// What a crosser does before it steps out: approach, time in view.
    pub timeline: Timeline,
    /// Non-crossers that approach the curb, stop and look, and then do not cross.
    pub hard_negatives: HardNegatives,
    /// Where each class is relative to the ego around the event, as real driving shows it (off by default:
    /// the paper's behaviour; `pedsynth calibrate`'s profiles turn it on).
    #[serde(skip_serializing_if = "Scenario::is_off")]
    pub scenario: Scenario,
}

impl Default for Crossing {
    fn default() -> Self {
        Crossing {
            target_ratio: 0.6,
            baseline_ratio: 0.09,
            layers: Layers::default(),
            gap_acceptance: GapAcceptance::default(),
            lookahead: Lookahead::default(),
            retreat: Retreat::default(),
            patience: Patience::default(),
            decision_window_m: Range(10.0, 40.0),
            timeline: Timeline::default(),
            hard_negatives: HardNegatives::default(),
            scenario: Scenario::default(),
        }
    }
}

/// Per-class scenario distributions. In real dashcam data (JAAD) crossers are near the car in the 1–2 s before
/// they cross (the driver approaches and slows for them), while bystanders who do not cross are seen at every
/// distance; a `[0, 0]` range turns its rule off.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// A crosser steps out only once the ego is within this distance of it (or has passed), metres `[min, max]`,
    /// drawn per crosser; the ego, easing off for a waiting pedestrian, comes close. `[0, 0]` (default): no
    /// such condition.
    pub crosser_ego_within_m: Range,
    /// A crosser that waits for the ego to come within `crosser_ego_within_m` also steps out once the ego has
    /// stopped (below 0.3 m/s) within this distance of it, metres: real crossers go in front of a car that
    /// waits, for them or for others crossing before it (a car held by a stream of crossers never comes near
    /// those who wait for it). `0` (default): off. Needs `crosser_ego_within_m`.
    pub crosser_stopped_ego_within_m: f64,
    /// Where non-crossers walking along the sidewalk start, ahead of the ego along its route, metres
    /// `[min, max]`. `[0, 0]` (default): from layer 1's `spawn_ahead_m` minimum to the visibility distance.
    pub walker_ahead_m: Range,
    /// How far to the side of the ego's route non-crossers walking along a sidewalk start, metres `[min, max]`,
    /// drawn per walker: the planner looks for free sidewalk at that distance (beside a wide road, along a side
    /// street, across a junction) and falls back to the sidewalk beside the route where there is none in reach.
    /// Real bystanders stand at every distance to the side; the sidewalk beside a two-lane road is 2–9 m out.
    /// `[0, 0]` (default): the sidewalk beside the route.
    pub walker_lateral_m: Range,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario {
            crosser_ego_within_m: Range(0.0, 0.0),
            crosser_stopped_ego_within_m: 0.0,
            walker_ahead_m: Range(0.0, 0.0),
            walker_lateral_m: Range(0.0, 0.0),
        }
    }
}

impl Scenario {
    /// Whether every rule is off (the default).
    pub fn is_off(&self) -> bool {
        *self == Scenario::default()
    }
}

/// The pre-crossing timeline: a crosser walks along the sidewalk to its curb point (slowing as it gets there),
/// waits and checks the traffic, and steps out only once the ego's camera has seen it for its planned time, so
/// that crossing-intention models get the seconds before the event (PedestrianActionBenchmark needs 16 + 60
/// frames up to it). Mid-road jaywalkers (layer 3) start on the road and have no timeline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Timeline {
    /// Time a crosser is in view of the ego's camera before it steps onto the road, seconds `[min, max]`
    /// (drawn uniformly per crosser; the default puts about 70% above JAAD's 2.5 s benchmark minimum, with
    /// short observations too, as in real data).
    pub in_view_before_crossing_s: Range,
    /// Distance a crosser (or a hard negative) walks along the sidewalk to its curb point, metres `[min, max]`.
    pub approach_m: Range,
}

impl Default for Timeline {
    fn default() -> Self {
        Timeline {
            in_view_before_crossing_s: Range(0.5, 5.0),
            approach_m: Range(3.0, 12.0),
        }
    }
}

/// Hard negatives: non-crossers that behave like crossers up to the decision — they walk to the curb, stop, look
/// and check the traffic — and then do not cross (they wait there, as for a bus, or walk on), so that a model
/// cannot tell the classes apart by "walks along the sidewalk" against "walks to the curb".
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct HardNegatives {
    /// Share of non-crossers that are hard negatives.
    pub share_of_non_crossers: f64,
    /// How long a hard negative waits at the curb before walking on, seconds `[min, max]` (a long wait outlasts
    /// the clip: waiting for a bus).
    pub wait_at_curb_s: Range,
}

impl Default for HardNegatives {
    fn default() -> Self {
        HardNegatives {
            share_of_non_crossers: 0.35,
            wait_at_curb_s: Range(3.0, 20.0),
        }
    }
}

/// The four crossing-rate layers (paper, Table "Four-layer crossing rate engineering strategy").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Layers {
    /// Layer 1: crosser allocation at spawn.
    pub crosser_allocation: CrosserAllocation,
    /// Layer 2: behavioural type assignment.
    pub behaviour_mix: BehaviourMixLayer,
    /// Layer 3: mid-road jaywalker injection.
    pub midroad_jaywalkers: MidroadJaywalkers,
    /// Layer 4: group crossing formation.
    pub groups: Groups,
}

/// Layer 1: allocate crossers at spawn, on sidewalk positions ahead of the ego vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct CrosserAllocation {
    /// Whether the layer is on.
    pub enabled: bool,
    /// Largest share of pedestrians allocated as crossers. The planner allocates what the target needs, up to
    /// this share (lifted to 1.0, with a note in `pedsynth plan`, for a target this share does not reach). The
    /// paper's code allocates a fixed 90%; here the default is 1.0, because about 15 % of the allocated crossers
    /// are not seen crossing (`calibration::CROSSER_REALISATION`) and the paper's 75% target must stay
    /// reachable.
    pub max_crosser_ratio: f64,
    /// Crossers spawn on sidewalks this far ahead of the ego vehicle along its route, metres.
    pub spawn_ahead_m: Range,
}

impl Default for CrosserAllocation {
    fn default() -> Self {
        CrosserAllocation {
            enabled: true,
            max_crosser_ratio: 1.0,
            spawn_ahead_m: Range(10.0, 55.0),
        }
    }
}

/// Layer 2: behaviour types of crossers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct BehaviourMixLayer {
    /// Whether the layer is on (off: every crosser is `normal`).
    pub enabled: bool,
    /// Share of each behaviour type among crossers; must sum to 1.
    pub mix: BehaviourMix,
}

impl Default for BehaviourMixLayer {
    fn default() -> Self {
        BehaviourMixLayer {
            enabled: true,
            mix: BehaviourMix {
                normal: 0.5,
                sudden: 0.25,
                jaywalk: 0.25,
            },
        }
    }
}

/// Shares of crossing behaviour types (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BehaviourMix {
    /// Checks traffic, crosses when the gap is accepted.
    #[serde(default)]
    pub normal: f64,
    /// Enters the road abruptly without checking.
    #[serde(default)]
    pub sudden: f64,
    /// Crosses mid-block, away from crosswalks.
    #[serde(default)]
    pub jaywalk: f64,
}

/// Layer 3: pedestrians injected directly in driving lanes, mid-road.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MidroadJaywalkers {
    /// Whether the layer is on.
    pub enabled: bool,
    /// Share of crossers spawned mid-road instead of on a sidewalk.
    pub share_of_crossers: f64,
    /// Lateral spawn offset from the lane centre, metres (± this value).
    pub lateral_offset_m: f64,
}

impl Default for MidroadJaywalkers {
    fn default() -> Self {
        MidroadJaywalkers {
            enabled: true,
            share_of_crossers: 0.1,
            lateral_offset_m: 1.5,
        }
    }
}

/// Layer 4: synchronised crossing groups.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Groups {
    /// Whether the layer is on.
    pub enabled: bool,
    /// Probability that potential crossers form a group with a shared leader.
    pub probability: f64,
    /// Shares of group sizes; must sum to 1.
    pub size_mix: GroupSizeMix,
}

impl Default for Groups {
    fn default() -> Self {
        Groups {
            enabled: true,
            probability: 0.4,
            size_mix: GroupSizeMix {
                pairs: 0.7,
                triples: 0.3,
            },
        }
    }
}

/// Shares of group sizes (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GroupSizeMix {
    /// Groups of two.
    #[serde(default)]
    pub pairs: f64,
    /// Groups of three.
    #[serde(default)]
    pub triples: f64,
}

/// Time-to-collision gap acceptance: cross when min TTC > τ_ttc + Δ_safety + w_road / s_cross.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct GapAcceptance {
    /// Safety buffer Δ_safety, seconds.
    pub safety_margin_s: Range,
    /// Vehicles within this distance of the pedestrian are considered, metres.
    pub vehicle_range_m: f64,
}

impl Default for GapAcceptance {
    fn default() -> Self {
        GapAcceptance {
            safety_margin_s: Range(0.5, 1.0),
            vehicle_range_m: 60.0,
        }
    }
}

/// In-road lookahead: halt when a vehicle is within `radius_m` of a probe point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Lookahead {
    /// Probe distances along the crossing vector, metres.
    pub points_m: Vec<f64>,
    /// Also probe the position predicted this far ahead, seconds.
    pub prediction_s: f64,
    /// Safety radius around each probe, metres.
    pub radius_m: f64,
}

impl Default for Lookahead {
    fn default() -> Self {
        Lookahead {
            points_m: vec![0.5, 1.5, 2.5],
            prediction_s: 0.5,
            radius_m: 3.0,
        }
    }
}

/// Mid-crossing retreat.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Retreat {
    /// Probability of retreating, drawn once per in-road conflict.
    pub probability: f64,
    /// Retreat is possible only in this first fraction of the crossing path.
    pub window_fraction: f64,
    /// Retreat speed, m/s.
    pub speed_mps: Range,
}

impl Default for Retreat {
    fn default() -> Self {
        Retreat {
            probability: 0.15,
            window_fraction: 0.4,
            speed_mps: Range(2.0, 3.0),
        }
    }
}

/// Patience expiry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Patience {
    /// On expiry, probability of a sudden crossing (otherwise the pedestrian abandons the attempt).
    pub sudden_crossing_probability: f64,
}

impl Default for Patience {
    fn default() -> Self {
        Patience {
            sudden_crossing_probability: 0.5,
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
