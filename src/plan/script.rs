//! The plan and its clip scripts: everything the executor needs to simulate one clip, fully determined and
//! seeded. A plan serialises to stable JSON (`pedsynth plan --emit`), which the executor accepts as input.
//!
//! Positions are world coordinates (right-handed, x east, y north, metres); headings are radians
//! counter-clockwise from +x.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::spec::types::{
    Body, Cyclists, GapAcceptance, Gestures, Idm, Lookahead, Patience, Range, Retreat, Rgb, Signals, Spec,
    SpeedProfiles, Split, Visibility, WeatherParams,
};

/// Version of the plan format.
pub const PLAN_FORMAT_VERSION: u32 = 6;

/// A compiled dataset: the clip scripts in a stable order (town, weather, index).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Plan format version.
    pub format_version: u32,
    /// pedsynth version that made the plan.
    pub pedsynth_version: String,
    /// Dataset name.
    pub dataset: String,
    /// Dataset seed.
    pub seed: u64,
    /// blake3 of the resolved spec.
    pub spec_hash: String,
    /// Target sequence-level crossing ratio.
    pub target_crossing_ratio: f64,
    /// Behaviour and traffic parameters shared by every clip.
    pub sim: SimParams,
    /// The resolved spec the plan was compiled from (sensors, annotation rules, output encodings), so that a
    /// plan file alone is enough to generate the dataset.
    pub spec: Spec,
    /// Directory the spec's relative paths (OpenDRIVE maps) resolve against: as it was given while planning;
    /// in a plan file (`plan --emit`), relative to the plan file's directory (format 3; format 2 recorded it
    /// relative to the working directory).
    pub spec_dir: String,
    /// Each town's [`crate::world::RoadNetwork::fingerprint`] (format 4): a plan is refused for a map that
    /// differs from the one it was made for.
    pub towns: std::collections::BTreeMap<String, String>,
    /// The clips.
    pub clips: Vec<ClipScript>,
}

/// Behaviour and traffic parameters shared by every clip (from the spec), so that a plan file alone is
/// enough to simulate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimParams {
    /// Time-to-collision gap acceptance.
    pub gap_acceptance: GapAcceptance,
    /// In-road lookahead.
    pub lookahead: Lookahead,
    /// Mid-crossing retreat.
    pub retreat: Retreat,
    /// Patience expiry.
    pub patience: Patience,
    /// A potential crosser commits when the ego is this far away, metres.
    pub decision_window_m: Range,
    /// Intelligent Driver Model constants.
    pub idm: Idm,
    /// Situational speed profiles (multipliers, switching).
    pub speed_profiles: SpeedProfiles,
    /// The ego's camera (the pedestrians' timelines count the time they are in its view).
    pub camera: Rgb,
    /// The visibility gate, as the simulation estimates what the camera sees.
    pub visibility: Visibility,
    /// Gestures to the ego's driver.
    pub gestures: Gestures,
    /// Traffic lights (absent when they do not run, and then absent from the plan file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signals: Option<Signals>,
    /// Cyclists' riding and overtaking parameters (absent when no clip has cyclists, and then absent from the
    /// plan file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cyclists: Option<Cyclists>,
    /// The ego's heading wobble (absent when off, and then absent from the plan file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego_heading: Option<crate::spec::types::Wobble>,
    /// The ego's pitch wobble (absent when off, and then absent from the plan file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego_pitch: Option<crate::spec::types::Wobble>,
}

impl SimParams {
    /// The parameters of `spec`.
    pub fn from_spec(spec: &Spec) -> Self {
        SimParams {
            gap_acceptance: spec.crossing.gap_acceptance.clone(),
            lookahead: spec.crossing.lookahead.clone(),
            retreat: spec.crossing.retreat.clone(),
            patience: spec.crossing.patience.clone(),
            decision_window_m: spec.crossing.decision_window_m,
            idm: spec.traffic.idm.clone(),
            speed_profiles: spec.pedestrians.speed_profiles.clone(),
            camera: spec.sensors.rgb.clone(),
            visibility: spec.annotations.visibility.clone(),
            gestures: spec.pedestrians.gestures.clone(),
            signals: spec.traffic.signals.enabled.then(|| spec.traffic.signals.clone()),
            cyclists: (spec.traffic.cyclists.per_clip.max() > 0).then(|| spec.traffic.cyclists.clone()),
            ego_heading: Some(spec.traffic.ego.heading_wobble).filter(|w| w.sd_deg > 0.0),
            ego_pitch: Some(spec.traffic.ego.pitch_wobble).filter(|w| w.sd_deg > 0.0),
        }
    }
}

/// One clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClipScript {
    /// Stable, human-readable id: `<town>-<weather>-<NNNN>`.
    pub clip_id: String,
    /// The clip's seed, derived from the dataset seed and the clip id.
    pub seed: u64,
    /// Town name.
    pub town: String,
    /// Weather name.
    pub weather: String,
    /// Resolved weather parameters.
    pub weather_params: WeatherParams,
    /// Dataset split.
    pub split: Split,
    /// Frames per second.
    pub fps: u32,
    /// Number of frames.
    pub frame_count: u32,
    /// The ego vehicle.
    pub ego: EgoScript,
    /// Traffic vehicles.
    pub vehicles: Vec<VehicleScript>,
    /// Pedestrians.
    pub pedestrians: Vec<PedestrianScript>,
    /// Cyclists (`traffic.cyclists`; absent from the plan file when there are none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cyclists: Vec<CyclistScript>,
    /// Signal offsets the planner sets in place of the drawn ones, (junction index, offset into its cycle in
    /// seconds): the junction where it stages the clip's signalised crossing. Empty without traffic lights.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub signal_offsets: Vec<(u32, f64)>,
    /// How much the clip was lengthened beyond its drawn duration so that its crossers' timelines fit, seconds.
    pub timeline_extension_s: f64,
    /// How many of the clip's pedestrians the dataset should label crossers (`crossing.target_ratio` of the
    /// stratum's pedestrians, shared among its clips by their planned crossers): the executor re-simulates the
    /// clip, promoting non-crossers or demoting crossers, until it has that many or runs out of candidates
    /// (`sensors::realise`). Absent without layer 1 (crosser allocation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub labelled_crossers: Option<u32>,
    /// How the clip's light and camera look under `domain_randomisation` (absent from the plan file without it).
    #[serde(default, skip_serializing_if = "ClipLook::is_identity")]
    pub look: ClipLook,
    /// Share of the curb's candidate places that hold a parked car (`traffic.parked_cars.share`; absent from
    /// the plan file, and no parked cars, when 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub parked_car_share: f64,
}

/// Whether a share is 0 (left out of the plan file).
fn is_zero(share: &f64) -> bool {
    *share == 0.0
}

/// A clip's draws of `domain_randomisation` for its light, camera, scenery and textures (the identity without
/// it; a field missing from a plan file is the identity's).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ClipLook {
    /// Factor on the sun's and the sky's light.
    pub light_intensity: f64,
    /// The camera's gain per channel (red, green, blue) on the linear light.
    pub white_balance: [f64; 3],
    /// Factor on auto-exposure's key.
    pub exposure_key: f64,
    /// Degrees the scenery's colours turn round the colour wheel.
    pub scenery_hue_deg: f64,
    /// Factor on the scenery's colour saturation.
    pub scenery_saturation: f64,
    /// Factor on the scenery's albedo.
    pub scenery_brightness: f64,
    /// Factor on the procedural textures' contrast.
    pub texture_contrast: f64,
}

impl Default for ClipLook {
    fn default() -> Self {
        ClipLook {
            light_intensity: 1.0,
            white_balance: [1.0; 3],
            exposure_key: 1.0,
            scenery_hue_deg: 0.0,
            scenery_saturation: 1.0,
            scenery_brightness: 1.0,
            texture_contrast: 1.0,
        }
    }
}

impl ClipLook {
    /// Whether the look changes nothing.
    pub fn is_identity(&self) -> bool {
        *self == ClipLook::default()
    }

    /// Whether the scenery's colours stay as they are.
    pub fn keeps_scenery_colours(&self) -> bool {
        self.scenery_hue_deg == 0.0 && self.scenery_saturation == 1.0 && self.scenery_brightness == 1.0
    }
}

impl ClipScript {
    /// Duration in seconds.
    pub fn duration_s(&self) -> f64 {
        f64::from(self.frame_count) / f64::from(self.fps.max(1))
    }
}

/// A route along the lane graph: the lanes in order (indices into the town's lane list) and where on the
/// resulting polyline the agent starts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RouteScript {
    /// Lane indices, in driving order.
    pub lanes: Vec<u32>,
    /// Length of the route, metres.
    pub length_m: f64,
    /// Start position along the route, metres.
    pub start_s_m: f64,
    /// Start position.
    pub start: DVec2,
    /// Start heading, radians.
    pub start_heading_rad: f64,
}

impl RouteScript {
    /// The route's lanes that exist in `net` (a plan made for another version of a map is refused before this;
    /// skipping keeps a hand-made script from indexing out of range).
    pub fn lanes_in(&self, net: &crate::world::RoadNetwork) -> Vec<u32> {
        self.lanes
            .iter()
            .copied()
            .filter(|&l| (l as usize) < net.lanes.len())
            .collect()
    }
}

/// The ego vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EgoScript {
    /// Route.
    pub route: RouteScript,
    /// Percentage below the speed limit it drives at.
    pub speed_below_limit_pct: f64,
    /// Minimum gap to a leader, metres.
    pub min_gap_m: f64,
    /// Brakes for a crossing pedestrian closer than this ahead, metres.
    pub brake_ahead_m: f64,
    /// ... and within this lateral distance, metres.
    pub brake_lateral_m: f64,
    /// Courtesy: it eases off to this speed for a pedestrian heading for, or waiting at, the curb ahead, m/s.
    pub courtesy_speed_mps: f64,
    /// ... up to this far ahead along its route, metres ...
    pub courtesy_ahead_m: f64,
    /// ... and this far to the side, metres; it stops this far short of a pedestrian waiting at the curb ...
    pub courtesy_lateral_m: f64,
    /// ... this far short of it, metres ...
    pub courtesy_stop_short_m: f64,
    /// ... for at most this long, seconds.
    pub courtesy_patience_s: f64,
    /// It rolls up to a crosser that waits for it to come near (`traffic.ego.courtesy_roll_up`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub courtesy_roll_up: bool,
}

/// Driving profiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DrivingProfileKind {
    /// Aggressive.
    Aggressive,
    /// Normal.
    Normal,
    /// Cautious.
    Cautious,
}

impl DrivingProfileKind {
    /// All profiles in spec order.
    pub const ALL: [DrivingProfileKind; 3] = [Self::Aggressive, Self::Normal, Self::Cautious];
    /// The profile's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Aggressive => "aggressive",
            Self::Normal => "normal",
            Self::Cautious => "cautious",
        }
    }
}

/// Kinds of emergency vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EmergencyKind {
    /// An ambulance (white).
    Ambulance,
    /// A fire truck (red).
    FireTruck,
    /// A police car (dark blue).
    Police,
}

impl EmergencyKind {
    /// All kinds in spec order.
    pub const ALL: [EmergencyKind; 3] = [Self::Ambulance, Self::FireTruck, Self::Police];
    /// The kind's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ambulance => "ambulance",
            Self::FireTruck => "fire_truck",
            Self::Police => "police",
        }
    }
}

/// One traffic vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VehicleScript {
    /// Vehicle id within the clip (the ego is not counted).
    pub id: u32,
    /// Driving profile.
    pub profile: DrivingProfileKind,
    /// Percentage below the speed limit (negative: faster).
    pub speed_difference_pct: f64,
    /// IDM minimum gap s0, metres.
    pub min_gap_m: f64,
    /// IDM time headway T, seconds.
    pub time_headway_s: f64,
    /// Whether it ignores traffic lights.
    pub ignores_lights: bool,
    /// Whether it ignores pedestrians.
    pub ignores_walkers: bool,
    /// Route.
    pub route: RouteScript,
    /// An emergency vehicle with lights and siren on (`traffic.emergency`): others stop for it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emergency: Option<EmergencyKind>,
}

/// One cyclist: a bicycle and its rider.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CyclistScript {
    /// Cyclist id within the clip.
    pub id: u32,
    /// Route (along driving lanes; the cyclist rides `edge_offset_m` from the lane's right edge).
    pub route: RouteScript,
    /// Cruising speed, m/s.
    pub speed_mps: f64,
    /// Distance from the right edge of the lane to the bicycle's centre line, metres.
    pub edge_offset_m: f64,
    /// Whether it rides through red lights.
    pub ignores_lights: bool,
    /// The rider.
    pub rider: Identity,
    /// Colour of the bicycle's frame (sRGB).
    pub bike_rgb: [u8; 3],
}

/// Role of a pedestrian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Planned to cross the road in front of the ego.
    Crosser,
    /// Stays on the sidewalk.
    NonCrosser,
}

/// Crossing behaviour type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Behaviour {
    /// Checks traffic and crosses when the gap is accepted.
    Normal,
    /// Enters the road abruptly without checking.
    Sudden,
    /// Crosses mid-block.
    Jaywalk,
    /// Injected directly in a driving lane (layer 3).
    MidroadJaywalker,
    /// A non-crosser that walks to the curb, stops, looks and checks the traffic, and then does not cross.
    HardNegative,
    /// A non-crosser.
    None,
}

impl Behaviour {
    /// All behaviour types.
    pub const ALL: [Behaviour; 6] = [
        Self::Normal,
        Self::Sudden,
        Self::Jaywalk,
        Self::MidroadJaywalker,
        Self::HardNegative,
        Self::None,
    ];
    /// The behaviour's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Normal => "normal",
            Self::Sudden => "sudden",
            Self::Jaywalk => "jaywalk",
            Self::MidroadJaywalker => "midroad_jaywalker",
            Self::HardNegative => "hard_negative",
            Self::None => "none",
        }
    }
}

/// Which mechanism made a pedestrian a crosser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CrosserSource {
    /// Layer 1 (crosser allocation).
    Allocated,
    /// The CARLA-like baseline.
    Baseline,
    /// Made a crosser at a new crossing point by the executor (a non-crosser, or a crosser that was not
    /// labelled) because its clip had fewer labelled crossers than planned (`ClipScript::labelled_crossers`);
    /// only in the written tables, never in a plan.
    Promoted,
    /// Not a crosser.
    None,
}

/// Situational speed profiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedProfile {
    /// 0.8×.
    Cautious,
    /// 1.0×.
    Normal,
    /// 1.3×.
    Rushed,
    /// 0.9×, with phone pauses.
    Distracted,
}

impl SpeedProfile {
    /// All profiles in spec order.
    pub const ALL: [SpeedProfile; 4] = [Self::Cautious, Self::Normal, Self::Rushed, Self::Distracted];
    /// The profile's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cautious => "cautious",
            Self::Normal => "normal",
            Self::Rushed => "rushed",
            Self::Distracted => "distracted",
        }
    }
}

/// A crossing group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GroupRef {
    /// Group id within the clip.
    pub group_id: u32,
    /// Pedestrian id of the leader.
    pub leader: u32,
}

/// Where a pedestrian starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpawnPlace {
    /// On a sidewalk.
    Sidewalk,
    /// In a driving lane (injected mid-road jaywalker).
    DrivingLane,
}

/// A planned crossing: from the spawn point across the carriageway to the far sidewalk.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrossingScript {
    /// Where the pedestrian leaves the near sidewalk.
    pub near_curb: DVec2,
    /// Where the pedestrian reaches the far sidewalk.
    pub far_curb: DVec2,
    /// A point on the far sidewalk (the crossing's goal).
    pub end: DVec2,
    /// Unit direction of the crossing.
    pub direction: DVec2,
    /// Width of the carriageway crossed, metres.
    pub carriageway_width_m: f64,
}

/// One pedestrian.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PedestrianScript {
    /// Pedestrian id within the clip.
    pub id: u32,
    /// Archetype name.
    pub archetype: String,
    /// Body model.
    pub body: Body,
    /// Base walking speed, m/s.
    pub base_speed_mps: f64,
    /// Hesitation at the curb, seconds.
    pub hesitation_s: f64,
    /// Attention 0–1.
    pub attention: f64,
    /// Gap-acceptance threshold τ_ttc, seconds.
    pub ttc_threshold_s: f64,
    /// Safety margin Δ_safety, seconds.
    pub safety_margin_s: f64,
    /// Patience cap, seconds.
    pub patience_s: f64,
    /// Whether the pedestrian becomes distracted (phone use), and when, seconds into the clip.
    pub distracted_at_s: Option<f64>,
    /// Role.
    pub role: Role,
    /// Which mechanism made it a crosser.
    pub crosser_source: CrosserSource,
    /// Behaviour type.
    pub behaviour: Behaviour,
    /// Crossing group, if any.
    pub group: Option<GroupRef>,
    /// Initial situational speed profile.
    pub speed_profile: SpeedProfile,
    /// Where it starts.
    pub spawn_place: SpawnPlace,
    /// Start position.
    pub spawn: DVec2,
    /// Start heading, radians.
    pub spawn_heading_rad: f64,
    /// Distance ahead of the ego's start along its route, metres.
    pub ahead_of_ego_m: f64,
    /// The planned crossing (crossers), or the curb a hard negative walks to.
    pub crossing: Option<CrossingScript>,
    /// Time the pedestrian must have been in view of the ego's camera before it steps onto the road, seconds
    /// (crossers that start on a sidewalk; `crossing.timeline`).
    pub in_view_before_crossing_s: Option<f64>,
    /// A crosser steps out only once the ego is within this distance of it, metres (`crossing.scenario`; absent
    /// where that rule is off).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step_out_ego_within_m: Option<f64>,
    /// A crosser that waits for the ego to come near also steps out once the ego has stopped within this
    /// distance of it, metres (`crossing.scenario.crosser_stopped_ego_within_m`; absent where off).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step_out_stopped_ego_within_m: Option<f64>,
    /// How long a hard negative waits at the curb before walking on, seconds.
    pub curb_wait_s: Option<f64>,
    /// Who the pedestrian is: body height and looks, the same for every sensor and label.
    pub identity: Identity,
    /// The child walking beside a parent (`parent_with_child` bodies).
    pub child: Option<Identity>,
    /// At a signalised crosswalk: whether it crosses against the signal (drawn from its archetype's
    /// `red_light_violation_probability` where traffic lights run).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub red_light_violator: bool,
}

/// Age group of a person (for the renderer's body proportions and the PIE/JAAD attributes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AgeGroup {
    /// Under about 12.
    Child,
    /// Teenager or young adult.
    Young,
    /// Adult.
    Adult,
    /// Senior.
    Senior,
}

impl AgeGroup {
    /// The group's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Child => "child",
            Self::Young => "young",
            Self::Adult => "adult",
            Self::Senior => "senior",
        }
    }
}

/// Gender presentation of a person (for the renderer and the PIE/JAAD attributes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Gender {
    /// Female.
    Female,
    /// Male.
    Male,
}

impl Gender {
    /// The gender's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Female => "female",
            Self::Male => "male",
        }
    }
}

/// Who a person is: drawn once by the planner, so that every observer (labels, cameras, LiDAR, exports) sees the
/// same person. Colours are sRGB.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Identity {
    /// Body height, metres.
    pub height_m: f64,
    /// Age group.
    pub age: AgeGroup,
    /// Gender presentation.
    pub gender: Gender,
    /// Skin colour.
    pub skin_rgb: [u8; 3],
    /// Hair colour.
    pub hair_rgb: [u8; 3],
    /// Colour of the top (shirt, coat).
    pub top_rgb: [u8; 3],
    /// Colour of the trousers, skirt or shorts.
    pub bottom_rgb: [u8; 3],
    /// Colour of the shoes.
    pub shoes_rgb: [u8; 3],
    /// Build, hair style, headwear, garment and what the person carries (plans written before figures existed
    /// read as [`Figure::PLAIN`]).
    #[serde(default)]
    pub figure: Figure,
}

/// The shape of a person beyond height and colours: drawn by the planner with the identity (its own random
/// stream), so that the labels, the cameras and the LiDAR see the same silhouette.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    /// Girth against an average build of the same height (1.0): scales the torso's, the hips' and the limbs'
    /// radii (0.85 slim … 1.25 heavy).
    pub build: f64,
    /// Hair style.
    pub hair: HairStyle,
    /// A hat or cap, and its colour (sRGB).
    pub headwear: Option<[u8; 3]>,
    /// The garment over the legs or the body.
    pub garment: Garment,
    /// What the person carries, and its colour (sRGB).
    pub carry: Option<(Carry, [u8; 3])>,
    /// An open umbrella held in the left hand, and its canopy's colour (sRGB): drawn only in rain (plans
    /// written before umbrellas existed read as none, and a figure without one writes no key).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub umbrella: Option<[u8; 3]>,
    /// A hood up over the head, in the top's colour (in rain, for some of those without an umbrella; it takes a
    /// hat's place). Plans written before hoods existed read as none, and a figure without one writes no key.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hood: bool,
    /// A pattern on the top (and on a dress or coat) in a second colour (sRGB). Plans written before patterns
    /// existed read as none, and a plain top writes no key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern: Option<(Pattern, [u8; 3])>,
}

/// A cloth pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pattern {
    /// Horizontal stripes, 9 cm from one stripe to the next.
    Stripes,
    /// Checks of 8 cm squares (a plaid shirt).
    Checks,
}

impl Pattern {
    /// The pattern's name (the pedestrians table's `pattern` column).
    pub fn name(self) -> &'static str {
        match self {
            Self::Stripes => "stripes",
            Self::Checks => "checks",
        }
    }
}

impl Figure {
    /// An average build with short hair, trousers and nothing carried.
    pub const PLAIN: Figure = Figure {
        build: 1.0,
        hair: HairStyle::Short,
        headwear: None,
        garment: Garment::Trousers,
        carry: None,
        umbrella: None,
        hood: false,
        pattern: None,
    };
}

impl Default for Figure {
    fn default() -> Self {
        Self::PLAIN
    }
}

/// A hair style.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HairStyle {
    /// No hair: the scalp shows.
    Bald,
    /// Short hair over the top and the back of the head.
    Short,
    /// Hair down to the shoulders, behind the head.
    Long,
    /// Hair tied in a bun at the back of the head.
    Bun,
}

/// The garment that shapes a silhouette.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Garment {
    /// Trousers or shorts: the legs show their shape.
    Trousers,
    /// A skirt to above the knee, in the bottom's colour.
    Skirt,
    /// A dress to above the knee, in the top's colour.
    Dress,
    /// A coat to the knees, in the top's colour.
    Coat,
}

/// Something a person carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Carry {
    /// A backpack on the back.
    Backpack,
    /// A bag hanging from the left shoulder at the hip.
    ShoulderBag,
}

impl HairStyle {
    /// The style's name (the people table's `hair` column).
    pub fn name(self) -> &'static str {
        match self {
            Self::Bald => "bald",
            Self::Short => "short",
            Self::Long => "long",
            Self::Bun => "bun",
        }
    }
}

impl Garment {
    /// The garment's name (the people table's `garment` column).
    pub fn name(self) -> &'static str {
        match self {
            Self::Trousers => "trousers",
            Self::Skirt => "skirt",
            Self::Dress => "dress",
            Self::Coat => "coat",
        }
    }
}

impl Carry {
    /// The object's name (the people table's `carry` column).
    pub fn name(self) -> &'static str {
        match self {
            Self::Backpack => "backpack",
            Self::ShoulderBag => "shoulder_bag",
        }
    }
}
