//! The dataset spec (`version: 1`): Rust types that serve loading, defaults, validation and the JSON Schema.
//!
//! Every default is the paper's value (ARCANE-PedSynth, its tables) or, where the paper is silent, the value of
//! its public code. A spec states only what differs: the loader deep-merges the user's YAML onto
//! `Spec::default()` key by key, except that a *mix* (a key named `mix` or ending in `_mix`) and a list are
//! replaced as a whole.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The spec language version this build understands.
pub const SPEC_VERSION: u32 = 1;

/// A closed interval `[min, max]` of real numbers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Range(pub f64, pub f64);

impl Range {
    /// Lower bound.
    pub fn min(&self) -> f64 {
        self.0
    }
    /// Upper bound.
    pub fn max(&self) -> f64 {
        self.1
    }
    /// Midpoint of the interval.
    pub fn mid(&self) -> f64 {
        0.5 * (self.0 + self.1)
    }
}

/// A closed interval `[min, max]` of counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct CountRange(pub u32, pub u32);

impl CountRange {
    /// Lower bound.
    pub fn min(&self) -> u32 {
        self.0
    }
    /// Upper bound.
    pub fn max(&self) -> u32 {
        self.1
    }
}

/// A pedsynth dataset spec.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
#[schemars(title = "pedsynth dataset spec", extend("required" = ["version"]))]
pub struct Spec {
    /// Spec language version; must be 1.
    pub version: u32,
    /// What to generate: towns, weathers, clip counts and durations, splits.
    pub dataset: Dataset,
    /// Pedestrian population: counts, archetypes and situational speed profiles.
    pub pedestrians: Pedestrians,
    /// Crossing-rate control: the four layers, gap acceptance, lookahead, retreat, patience.
    pub crossing: Crossing,
    /// Traffic vehicles, driving profiles and the ego vehicle.
    pub traffic: Traffic,
    /// Sensors mounted on the ego vehicle.
    pub sensors: Sensors,
    /// Which pedestrians are annotated, and how labels are derived.
    pub annotations: Annotations,
    /// Output encodings and compression.
    pub output: Output,
    /// Sanity limits on the size of a dataset; exceeding one is an error unless `--allow-large` is given.
    pub limits: Limits,
}

impl Default for Spec {
    fn default() -> Self {
        Spec {
            version: SPEC_VERSION,
            dataset: Dataset::default(),
            pedestrians: Pedestrians::default(),
            crossing: Crossing::default(),
            traffic: Traffic::default(),
            sensors: Sensors::default(),
            annotations: Annotations::default(),
            output: Output::default(),
            limits: Limits::default(),
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// dataset

/// What to generate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Dataset {
    /// Dataset name (used in the output's metadata).
    pub name: String,
    /// Dataset seed; each clip's seed derives from it and the clip's identity.
    pub seed: u64,
    /// Towns: built-in names or `{name, opendrive: path}` (path relative to the spec file).
    pub towns: Vec<TownRef>,
    /// Weathers: `all` (the paper's 12 presets), or a list of preset names and custom weathers.
    pub weathers: WeatherSelection,
    /// Clip counts (the paper's `--videos_per_weather` and `--dataset_mode`).
    pub clips: Clips,
    /// Clip duration range in seconds; each clip draws its duration uniformly from it.
    pub clip_duration_s: Range,
    /// Simulation and sensor frame rate.
    pub fps: u32,
    /// Split of each town (paper: Town01/02 train, Town03 val, Town05 test).
    pub splits: BTreeMap<String, Split>,
    /// Split of towns not named in `splits`.
    pub default_split: Split,
}

impl Default for Dataset {
    fn default() -> Self {
        Dataset {
            name: "pedsynth".to_owned(),
            seed: 0,
            towns: BuiltinTown::ALL.iter().map(|t| TownRef::Builtin(*t)).collect(),
            weathers: WeatherSelection::All(AllKeyword::All),
            clips: Clips::default(),
            clip_duration_s: Range(10.0, 15.0),
            fps: 30,
            splits: BTreeMap::from([
                (BuiltinTown::Town01Like.name().to_owned(), Split::Train),
                (BuiltinTown::Town02Like.name().to_owned(), Split::Train),
                (BuiltinTown::Town03Like.name().to_owned(), Split::Val),
                (BuiltinTown::Town05Like.name().to_owned(), Split::Test),
            ]),
            default_split: Split::Train,
        }
    }
}

/// A town: a built-in procedural town, or an OpenDRIVE map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum TownRef {
    /// A built-in town (no files needed).
    Builtin(BuiltinTown),
    /// A town loaded from an OpenDRIVE (.xodr) file.
    OpenDrive(OpenDriveTown),
}

impl TownRef {
    /// The town's name as used in clip ids and splits.
    pub fn name(&self) -> &str {
        match self {
            TownRef::Builtin(t) => t.name(),
            TownRef::OpenDrive(t) => &t.name,
        }
    }
}

/// The built-in procedural towns. They are modelled on the paper's CARLA towns but are not CARLA's maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BuiltinTown {
    /// Small two-lane town with T-junctions (like CARLA's Town01).
    Town01Like,
    /// Compact two-lane town (like CARLA's Town02).
    Town02Like,
    /// Multi-lane town with varied junctions (like CARLA's Town03).
    Town03Like,
    /// Grid with multi-lane avenues (like CARLA's Town05).
    Town05Like,
}

impl BuiltinTown {
    /// All built-in towns in listing order.
    pub const ALL: [BuiltinTown; 4] = [
        BuiltinTown::Town01Like,
        BuiltinTown::Town02Like,
        BuiltinTown::Town03Like,
        BuiltinTown::Town05Like,
    ];
    /// The town's name.
    pub fn name(self) -> &'static str {
        match self {
            BuiltinTown::Town01Like => "town01_like",
            BuiltinTown::Town02Like => "town02_like",
            BuiltinTown::Town03Like => "town03_like",
            BuiltinTown::Town05Like => "town05_like",
        }
    }
}

/// A town loaded from an OpenDRIVE map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OpenDriveTown {
    /// Name of the town in clip ids and splits (lowercase letters, digits and `_`).
    pub name: String,
    /// Path to the .xodr file, relative to the spec file.
    pub opendrive: String,
}

/// Dataset split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Split {
    /// Training split.
    Train,
    /// Validation split.
    Val,
    /// Test split.
    Test,
}

/// The keyword `all`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AllKeyword {
    /// Every preset.
    All,
}

/// Weather selection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum WeatherSelection {
    /// `all`: the paper's 12 presets.
    All(AllKeyword),
    /// Preset names and custom weathers.
    List(Vec<WeatherRef>),
}

/// One weather: a preset name or a custom weather.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum WeatherRef {
    /// One of the paper's 12 presets.
    Preset(WeatherPreset),
    /// A custom weather.
    Custom(CustomWeather),
}

impl WeatherRef {
    /// The weather's name as used in clip ids.
    pub fn name(&self) -> &str {
        match self {
            WeatherRef::Preset(p) => p.name(),
            WeatherRef::Custom(c) => &c.name,
        }
    }
    /// The weather's parameters.
    pub fn params(&self) -> WeatherParams {
        match self {
            WeatherRef::Preset(p) => p.params(),
            WeatherRef::Custom(c) => c.params,
        }
    }
}

/// The paper's 12 weather conditions (Table "Twelve weather configurations").
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum WeatherPreset {
    /// Optimal baseline (easy).
    ClearNoon,
    /// Diffuse lighting (easy).
    CloudyNoon,
    /// Post-rain surface effects (easy).
    WetNoon,
    /// Intermediate precipitation (moderate).
    SoftRain,
    /// Visibility limitation (moderate).
    FoggyNoon,
    /// Extreme shadows (moderate).
    ClearSunset,
    /// Artificial lighting only (moderate).
    NightClear,
    /// Transitional lighting (moderate).
    Dawn,
    /// Severe precipitation (hard).
    HeavyRain,
    /// Poor light and precipitation (hard).
    RainySunset,
    /// Minimal light, rain and fog (hard).
    NightRainy,
    /// Extreme darkness and fog (hard).
    NightFoggy,
}

/// Difficulty class of a weather.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Difficulty {
    /// Easy.
    Easy,
    /// Moderate.
    Moderate,
    /// Hard.
    Hard,
}

/// Physical weather parameters (CARLA WeatherParameters semantics; percentages are 0–100).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct WeatherParams {
    /// Sun altitude above the horizon, degrees (negative: night).
    pub sun_altitude_deg: f64,
    /// Sun azimuth, degrees.
    pub sun_azimuth_deg: f64,
    /// Cloud cover, percent.
    pub cloudiness_pct: f64,
    /// Rain intensity, percent.
    pub precipitation_pct: f64,
    /// Fog density, percent.
    pub fog_density_pct: f64,
    /// Road wetness, percent.
    pub wetness_pct: f64,
    /// Wind intensity, percent.
    pub wind_intensity_pct: f64,
    /// Difficulty class.
    pub difficulty: Difficulty,
}

impl Default for WeatherParams {
    fn default() -> Self {
        WeatherPreset::ClearNoon.params()
    }
}

/// A user-defined weather. (No `deny_unknown_fields` here: serde cannot combine it with `flatten`; the
/// schema check rejects unknown keys.)
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(extend("additionalProperties" = false))]
pub struct CustomWeather {
    /// Name used in clip ids (lowercase letters, digits and `_`).
    pub name: String,
    /// Parameters; unspecified ones take clear_noon's values.
    #[serde(flatten)]
    pub params: WeatherParams,
}

impl WeatherPreset {
    /// All presets, in the paper's order.
    pub const ALL: [WeatherPreset; 12] = [
        WeatherPreset::ClearNoon,
        WeatherPreset::CloudyNoon,
        WeatherPreset::WetNoon,
        WeatherPreset::SoftRain,
        WeatherPreset::FoggyNoon,
        WeatherPreset::ClearSunset,
        WeatherPreset::NightClear,
        WeatherPreset::Dawn,
        WeatherPreset::HeavyRain,
        WeatherPreset::RainySunset,
        WeatherPreset::NightRainy,
        WeatherPreset::NightFoggy,
    ];

    /// The preset's name.
    pub fn name(self) -> &'static str {
        match self {
            WeatherPreset::ClearNoon => "clear_noon",
            WeatherPreset::CloudyNoon => "cloudy_noon",
            WeatherPreset::WetNoon => "wet_noon",
            WeatherPreset::SoftRain => "soft_rain",
            WeatherPreset::FoggyNoon => "foggy_noon",
            WeatherPreset::ClearSunset => "clear_sunset",
            WeatherPreset::NightClear => "night_clear",
            WeatherPreset::Dawn => "dawn",
            WeatherPreset::HeavyRain => "heavy_rain",
            WeatherPreset::RainySunset => "rainy_sunset",
            WeatherPreset::NightRainy => "night_rainy",
            WeatherPreset::NightFoggy => "night_foggy",
        }
    }

    /// The preset's parameters: sun altitude from the paper's table, the rest from its public code.
    pub fn params(self) -> WeatherParams {
        use Difficulty::*;
        // (sun altitude, cloud, precipitation, fog, wetness, azimuth, wind, difficulty)
        let (alt, cloud, precip, fog, wet, az, wind, difficulty) = match self {
            WeatherPreset::ClearNoon => (70.0, 10.0, 0.0, 0.0, 0.0, 0.0, 5.0, Easy),
            WeatherPreset::CloudyNoon => (60.0, 90.0, 0.0, 10.0, 0.0, 0.0, 30.0, Easy),
            WeatherPreset::WetNoon => (65.0, 50.0, 0.0, 5.0, 80.0, 0.0, 15.0, Easy),
            WeatherPreset::SoftRain => (60.0, 70.0, 30.0, 5.0, 50.0, 0.0, 25.0, Moderate),
            WeatherPreset::FoggyNoon => (45.0, 70.0, 0.0, 80.0, 30.0, 0.0, 10.0, Moderate),
            WeatherPreset::ClearSunset => (10.0, 5.0, 0.0, 0.0, 0.0, 270.0, 5.0, Moderate),
            WeatherPreset::NightClear => (-40.0, 10.0, 0.0, 0.0, 0.0, 0.0, 5.0, Moderate),
            WeatherPreset::Dawn => (5.0, 30.0, 0.0, 10.0, 20.0, 90.0, 10.0, Moderate),
            WeatherPreset::HeavyRain => (50.0, 95.0, 80.0, 15.0, 90.0, 0.0, 50.0, Hard),
            WeatherPreset::RainySunset => (12.0, 85.0, 60.0, 10.0, 85.0, 270.0, 40.0, Hard),
            WeatherPreset::NightRainy => (-35.0, 90.0, 70.0, 25.0, 95.0, 0.0, 45.0, Hard),
            WeatherPreset::NightFoggy => (-35.0, 80.0, 0.0, 85.0, 40.0, 0.0, 15.0, Hard),
        };
        WeatherParams {
            sun_altitude_deg: alt,
            sun_azimuth_deg: az,
            cloudiness_pct: cloud,
            precipitation_pct: precip,
            fog_density_pct: fog,
            wetness_pct: wet,
            wind_intensity_pct: wind,
            difficulty,
        }
    }
}

impl WeatherSelection {
    /// The selected weathers, `all` expanded to the 12 presets.
    pub fn resolved(&self) -> Vec<WeatherRef> {
        match self {
            WeatherSelection::All(_) => WeatherPreset::ALL.iter().map(|p| WeatherRef::Preset(*p)).collect(),
            WeatherSelection::List(list) => list.clone(),
        }
    }
}

/// Clip counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Clips {
    /// Number of clips per unit given by `per`.
    pub count: u32,
    /// `weather`: `count` clips for each weather, spread evenly over the towns (the paper's dataset mode);
    /// `town_and_weather`: `count` clips for each (town, weather) pair.
    pub per: ClipsPer,
}

impl Default for Clips {
    fn default() -> Self {
        Clips {
            count: 50,
            per: ClipsPer::Weather,
        }
    }
}

/// What a clip count is per.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ClipsPer {
    /// Per weather, towns spread evenly.
    Weather,
    /// Per (town, weather) pair.
    TownAndWeather,
}

// ---------------------------------------------------------------------------------------------------------------
// pedestrians

/// The pedestrian population.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Pedestrians {
    /// Pedestrians per clip, `[min, max]`.
    pub per_clip: CountRange,
    /// Share of each archetype; must sum to 1. Replaced as a whole when given.
    pub archetype_mix: BTreeMap<String, f64>,
    /// Archetype parameters: the paper's five, overridable key by key, plus any new ones (which start from
    /// casual_person's parameters).
    pub archetypes: BTreeMap<String, Archetype>,
    /// Situational speed profiles.
    pub speed_profiles: SpeedProfiles,
}

impl Default for Pedestrians {
    fn default() -> Self {
        let archetypes = Archetype::paper_table();
        Pedestrians {
            per_clip: CountRange(5, 10),
            archetype_mix: archetypes
                .iter()
                .map(|(name, (share, _))| (name.clone(), *share))
                .collect(),
            archetypes: archetypes.into_iter().map(|(name, (_, a))| (name, a)).collect(),
            speed_profiles: SpeedProfiles::default(),
        }
    }
}

/// Body model of an archetype.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Body {
    /// One adult.
    Adult,
    /// One child.
    Child,
    /// An adult walking with a child.
    AdultWithChild,
}

/// Behavioural parameters of a character archetype (paper, Table "Character archetypes").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Archetype {
    /// Base walking speed range, m/s.
    pub speed_mps: Range,
    /// Hesitation duration at the curb, seconds.
    pub hesitation_s: Range,
    /// Attention level 0–1: how often and how long the pedestrian scans traffic.
    pub attention: f64,
    /// Intrinsic crossing propensity 0–1 (the archetype check before a crossing).
    pub crossing_probability: f64,
    /// Gap-acceptance threshold τ_ttc, seconds (paper: 3–6 s by archetype).
    pub ttc_threshold_s: Range,
    /// Patience cap: longest wait at the curb before abandoning or crossing suddenly, seconds (paper: 6–18 s).
    pub patience_s: Range,
    /// Probability of distracted behaviour (phone use) during a clip.
    pub distraction_probability: f64,
    /// Body model.
    pub body: Body,
}

impl Default for Archetype {
    fn default() -> Self {
        Archetype::paper_table()
            .remove("casual_person")
            .map(|(_, a)| a)
            .unwrap_or(Archetype {
                speed_mps: Range(1.0, 1.4),
                hesitation_s: Range(0.5, 1.5),
                attention: 0.7,
                crossing_probability: 0.7,
                ttc_threshold_s: Range(4.0, 5.0),
                patience_s: Range(9.0, 13.0),
                distraction_probability: 0.15,
                body: Body::Adult,
            })
    }
}

impl Archetype {
    /// The paper's five archetypes with their proportions. Speed, hesitation, attention and crossing
    /// probability are the paper's table; τ_ttc and patience spread the paper's ranges (3–6 s, 6–18 s) from
    /// risk-taking to cautious; distraction probabilities are pedsynth's choice.
    pub fn paper_table() -> BTreeMap<String, (f64, Archetype)> {
        let row =
            |share, speed: (f64, f64), hes: (f64, f64), att, cross, ttc: (f64, f64), pat: (f64, f64), dis, body| {
                (
                    share,
                    Archetype {
                        speed_mps: Range(speed.0, speed.1),
                        hesitation_s: Range(hes.0, hes.1),
                        attention: att,
                        crossing_probability: cross,
                        ttc_threshold_s: Range(ttc.0, ttc.1),
                        patience_s: Range(pat.0, pat.1),
                        distraction_probability: dis,
                        body,
                    },
                )
            };
        BTreeMap::from([
            (
                "business_person".to_owned(),
                row(
                    0.30,
                    (1.4, 1.8),
                    (0.3, 0.8),
                    0.5,
                    0.85,
                    (3.5, 4.5),
                    (7.0, 10.0),
                    0.20,
                    Body::Adult,
                ),
            ),
            (
                "casual_person".to_owned(),
                row(
                    0.25,
                    (1.0, 1.4),
                    (0.5, 1.5),
                    0.7,
                    0.70,
                    (4.0, 5.0),
                    (9.0, 13.0),
                    0.15,
                    Body::Adult,
                ),
            ),
            (
                "elderly_person".to_owned(),
                row(
                    0.10,
                    (0.6, 1.0),
                    (1.0, 2.0),
                    0.9,
                    0.50,
                    (5.0, 6.0),
                    (14.0, 18.0),
                    0.05,
                    Body::Adult,
                ),
            ),
            (
                "young_person".to_owned(),
                row(
                    0.20,
                    (1.2, 2.0),
                    (0.2, 0.6),
                    0.4,
                    0.90,
                    (3.0, 4.0),
                    (6.0, 9.0),
                    0.25,
                    Body::Adult,
                ),
            ),
            (
                "parent_with_child".to_owned(),
                row(
                    0.15,
                    (0.8, 1.2),
                    (0.8, 1.8),
                    0.8,
                    0.60,
                    (4.5, 5.5),
                    (11.0, 15.0),
                    0.10,
                    Body::AdultWithChild,
                ),
            ),
        ])
    }
}

/// Situational speed profiles (paper: cautious 0.8×, normal 1.0×, rushed 1.3×, distracted 0.9×).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SpeedProfiles {
    /// Share of pedestrians starting in each profile; must sum to 1.
    pub mix: SpeedProfileMix,
    /// Speed multiplier of each profile.
    pub multipliers: SpeedProfileMultipliers,
    /// Whether profiles switch during a clip (rushed when closing a tight gap, distracted on phone use).
    pub switching: bool,
}

impl Default for SpeedProfiles {
    fn default() -> Self {
        SpeedProfiles {
            mix: SpeedProfileMix {
                cautious: 0.2,
                normal: 0.4,
                rushed: 0.3,
                distracted: 0.1,
            },
            multipliers: SpeedProfileMultipliers {
                cautious: 0.8,
                normal: 1.0,
                rushed: 1.3,
                distracted: 0.9,
            },
            switching: true,
        }
    }
}

/// Shares of the four speed profiles (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpeedProfileMix {
    /// Share of cautious pedestrians.
    #[serde(default)]
    pub cautious: f64,
    /// Share of normal pedestrians.
    #[serde(default)]
    pub normal: f64,
    /// Share of rushed pedestrians.
    #[serde(default)]
    pub rushed: f64,
    /// Share of distracted pedestrians.
    #[serde(default)]
    pub distracted: f64,
}

/// Speed multipliers of the four profiles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SpeedProfileMultipliers {
    /// Cautious (poor visibility, elderly).
    pub cautious: f64,
    /// Normal.
    pub normal: f64,
    /// Rushed (closing a tight gap).
    pub rushed: f64,
    /// Distracted (phone use, with pauses).
    pub distracted: f64,
}

impl Default for SpeedProfileMultipliers {
    fn default() -> Self {
        SpeedProfiles::default().multipliers
    }
}

// ---------------------------------------------------------------------------------------------------------------
// crossing

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
    /// Largest share of pedestrians allocated as crossers (paper: 90%). The planner allocates what the
    /// target needs, up to this share.
    pub max_crosser_ratio: f64,
    /// Crossers spawn on sidewalks this far ahead of the ego vehicle along its route, metres.
    pub spawn_ahead_m: Range,
}

impl Default for CrosserAllocation {
    fn default() -> Self {
        CrosserAllocation {
            enabled: true,
            max_crosser_ratio: 0.9,
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
// traffic

/// Traffic and the ego vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Traffic {
    /// Traffic vehicles per clip (besides the ego), `[min, max]`.
    pub vehicles_per_clip: CountRange,
    /// Share of each driving profile; must sum to 1.
    pub profile_mix: DrivingProfileMix,
    /// Parameters of each driving profile.
    pub profiles: DrivingProfiles,
    /// Intelligent Driver Model constants shared by all vehicles.
    pub idm: Idm,
    /// The ego vehicle.
    pub ego: Ego,
    /// Emergency scenarios (a vehicle braking hard or a pedestrian darting out close to the ego).
    pub emergency: Emergency,
}

impl Default for Traffic {
    fn default() -> Self {
        Traffic {
            vehicles_per_clip: CountRange(5, 10),
            profile_mix: DrivingProfileMix {
                aggressive: 0.2,
                normal: 0.6,
                cautious: 0.2,
            },
            profiles: DrivingProfiles::default(),
            idm: Idm::default(),
            ego: Ego::default(),
            emergency: Emergency::default(),
        }
    }
}

/// Shares of driving profiles (missing ones are 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DrivingProfileMix {
    /// Aggressive drivers.
    #[serde(default)]
    pub aggressive: f64,
    /// Normal drivers.
    #[serde(default)]
    pub normal: f64,
    /// Cautious drivers.
    #[serde(default)]
    pub cautious: f64,
}

/// The three driving profiles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DrivingProfiles {
    /// Aggressive: faster than the limit, short gaps, may ignore lights or pedestrians.
    pub aggressive: DrivingProfile,
    /// Normal.
    pub normal: DrivingProfile,
    /// Cautious: slower, long gaps.
    pub cautious: DrivingProfile,
}

impl Default for DrivingProfiles {
    fn default() -> Self {
        let p = |speed: (f64, f64), gap: (f64, f64), headway: (f64, f64), lights, walkers| DrivingProfile {
            speed_difference_pct: Range(speed.0, speed.1),
            min_gap_m: Range(gap.0, gap.1),
            time_headway_s: Range(headway.0, headway.1),
            ignore_lights_probability: lights,
            ignore_walkers_probability: walkers,
        };
        DrivingProfiles {
            aggressive: p((-30.0, -15.0), (0.5, 1.0), (0.8, 1.1), 0.2, 0.05),
            normal: p((-10.0, 10.0), (1.0, 2.0), (1.3, 1.7), 0.0, 0.0),
            cautious: p((10.0, 25.0), (2.0, 3.5), (1.9, 2.5), 0.0, 0.0),
        }
    }
}

/// One driving profile (CARLA Traffic Manager semantics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DrivingProfile {
    /// Percentage below the speed limit (negative: faster than the limit).
    pub speed_difference_pct: Range,
    /// IDM minimum gap s0 to the leader, metres.
    pub min_gap_m: Range,
    /// IDM desired time headway T, seconds.
    pub time_headway_s: Range,
    /// Probability that a vehicle of this profile ignores traffic lights.
    pub ignore_lights_probability: f64,
    /// Probability that a vehicle of this profile ignores pedestrians (it still records any contact).
    pub ignore_walkers_probability: f64,
}

impl Default for DrivingProfile {
    fn default() -> Self {
        DrivingProfiles::default().normal
    }
}

/// Intelligent Driver Model constants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Idm {
    /// Maximum acceleration a, m/s².
    pub max_accel_mps2: f64,
    /// Comfortable deceleration b, m/s².
    pub comfortable_decel_mps2: f64,
    /// Largest deceleration a vehicle can apply, m/s².
    pub max_decel_mps2: f64,
    /// Acceleration exponent δ.
    pub exponent: f64,
}

impl Default for Idm {
    fn default() -> Self {
        Idm {
            max_accel_mps2: 1.5,
            comfortable_decel_mps2: 3.0,
            max_decel_mps2: 8.0,
            exponent: 4.0,
        }
    }
}

/// The ego vehicle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Ego {
    /// Percentage below the speed limit the ego drives at.
    pub speed_below_limit_pct: Range,
    /// Minimum gap to a leading vehicle, metres.
    pub min_gap_m: f64,
    /// The ego brakes for a crossing pedestrian closer than this ahead, metres.
    pub brake_ahead_m: f64,
    /// ... and within this lateral distance of its path, metres.
    pub brake_lateral_m: f64,
    /// Route length beyond what the clip needs, metres.
    pub route_margin_m: f64,
}

impl Default for Ego {
    fn default() -> Self {
        Ego {
            speed_below_limit_pct: Range(15.0, 35.0),
            min_gap_m: 2.5,
            brake_ahead_m: 15.0,
            brake_lateral_m: 5.0,
            route_margin_m: 60.0,
        }
    }
}

/// Emergency scenarios.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Emergency {
    /// Whether emergency scenarios are generated.
    pub enabled: bool,
    /// Share of clips with an emergency scenario.
    pub clip_share: f64,
}

impl Default for Emergency {
    fn default() -> Self {
        Emergency {
            enabled: false,
            clip_share: 0.1,
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// sensors

/// Sensors on the ego vehicle. All share the clip's frame clock.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Sensors {
    /// RGB camera.
    pub rgb: Rgb,
    /// Ray-cast LiDAR.
    pub lidar: Lidar,
    /// DVS event camera (co-located with the RGB camera, same intrinsics).
    pub dvs: Dvs,
}

/// A sensor mount in the ego vehicle's body frame (x forward, y left, z up, metres; angles in degrees).
/// CARLA's `(x 0.8, y -0.3, z 1.4)` is `forward_m 0.8, left_m 0.3, up_m 1.4` here.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Mount {
    /// Forward of the vehicle origin, metres.
    pub forward_m: f64,
    /// Left of the vehicle origin, metres.
    pub left_m: f64,
    /// Above the ground, metres.
    pub up_m: f64,
    /// Pitch, degrees (negative looks down).
    pub pitch_deg: f64,
    /// Yaw, degrees (positive turns left).
    pub yaw_deg: f64,
    /// Roll, degrees.
    pub roll_deg: f64,
}

impl Default for Mount {
    fn default() -> Self {
        Mount {
            forward_m: 0.8,
            left_m: 0.3,
            up_m: 1.4,
            pitch_deg: -8.0,
            yaw_deg: 0.0,
            roll_deg: 0.0,
        }
    }
}

/// RGB camera (pinhole; horizontal field of view).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Rgb {
    /// Whether RGB images are written.
    pub enabled: bool,
    /// Image width, pixels.
    pub width_px: u32,
    /// Image height, pixels.
    pub height_px: u32,
    /// Horizontal field of view, degrees.
    pub fov_deg: f64,
    /// Mount at the driver's eye.
    pub mount: Mount,
}

impl Default for Rgb {
    fn default() -> Self {
        Rgb {
            enabled: true,
            width_px: 1280,
            height_px: 720,
            fov_deg: 90.0,
            mount: Mount::default(),
        }
    }
}

/// Ray-cast LiDAR (CARLA `sensor.lidar.ray_cast` semantics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Lidar {
    /// Whether LiDAR sweeps are written.
    pub enabled: bool,
    /// Number of laser channels.
    pub channels: u32,
    /// Maximum range, metres.
    pub range_m: f64,
    /// Points per second over all channels.
    pub points_per_second: u32,
    /// Rotation frequency, Hz.
    pub rotation_hz: f64,
    /// Elevation of the top channel, degrees.
    pub upper_fov_deg: f64,
    /// Elevation of the bottom channel, degrees.
    pub lower_fov_deg: f64,
    /// Horizontal field of view, degrees.
    pub horizontal_fov_deg: f64,
    /// Atmospheric attenuation rate, 1/m (intensity = exp(-rate × distance)).
    pub atmosphere_attenuation_per_m: f64,
    /// Share of rays dropped at random.
    pub dropoff_general_rate: f64,
    /// Intensity above which no intensity-based drop-off happens.
    pub dropoff_intensity_limit: f64,
    /// Drop-off probability of a zero-intensity return.
    pub dropoff_zero_intensity: f64,
    /// Standard deviation of range noise along the ray, metres.
    pub noise_stddev_m: f64,
    /// Roof mount.
    pub mount: Mount,
}

impl Default for Lidar {
    fn default() -> Self {
        Lidar {
            enabled: true,
            channels: 64,
            range_m: 100.0,
            points_per_second: 1_000_000,
            rotation_hz: 20.0,
            upper_fov_deg: 15.0,
            lower_fov_deg: -25.0,
            horizontal_fov_deg: 360.0,
            atmosphere_attenuation_per_m: 0.004,
            dropoff_general_rate: 0.45,
            dropoff_intensity_limit: 0.8,
            dropoff_zero_intensity: 0.4,
            noise_stddev_m: 0.0,
            mount: Mount {
                forward_m: 0.0,
                left_m: 0.0,
                up_m: 2.4,
                pitch_deg: 0.0,
                yaw_deg: 0.0,
                roll_deg: 0.0,
            },
        }
    }
}

/// DVS event camera (ESIM, CARLA `sensor.camera.dvs` semantics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Dvs {
    /// Whether events are written.
    pub enabled: bool,
    /// Positive contrast threshold Cp.
    pub positive_threshold: f64,
    /// Negative contrast threshold Cm.
    pub negative_threshold: f64,
    /// Per-pixel, per-frame standard deviation of Cp.
    pub sigma_positive_threshold: f64,
    /// Per-pixel, per-frame standard deviation of Cm.
    pub sigma_negative_threshold: f64,
    /// Refractory period, nanoseconds.
    pub refractory_period_ns: u64,
    /// Work on log intensity.
    pub use_log: bool,
    /// Epsilon added before the logarithm.
    pub log_eps: f64,
}

impl Default for Dvs {
    fn default() -> Self {
        Dvs {
            enabled: true,
            positive_threshold: 0.3,
            negative_threshold: 0.3,
            sigma_positive_threshold: 0.0,
            sigma_negative_threshold: 0.0,
            refractory_period_ns: 0,
            use_log: true,
            log_eps: 0.001,
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// annotations and output

/// Annotation rules.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Annotations {
    /// The visibility gate: which pedestrians are annotated in a frame.
    pub visibility: Visibility,
    /// A pedestrian keeps C=1 for this many frames after briefly leaving a driving lane (label smoothing).
    pub crossing_label_smoothing_frames: u32,
    /// Keypoint format.
    pub pose_format: PoseFormat,
}

impl Default for Annotations {
    fn default() -> Self {
        Annotations {
            visibility: Visibility::default(),
            crossing_label_smoothing_frames: 5,
            pose_format: PoseFormat::Coco17,
        }
    }
}

/// The paper's four-stage visibility gate plus an occlusion threshold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Visibility {
    /// Stage 1: distance to the ego below this, metres.
    pub max_distance_m: f64,
    /// Stage 2: in front of the camera.
    pub require_in_front: bool,
    /// Stage 3: smallest box `[width, height]`, pixels.
    pub min_box_px: Range,
    /// Beyond this distance the far minimum applies, metres.
    pub far_distance_m: f64,
    /// Stage 3 beyond `far_distance_m`: smallest box `[width, height]`, pixels.
    pub min_box_far_px: Range,
    /// Stage 4: the box lies within the image.
    pub require_inside_image: bool,
    /// Pedestrians occluded by more than this fraction are not annotated.
    pub max_occlusion: f64,
}

impl Default for Visibility {
    fn default() -> Self {
        Visibility {
            max_distance_m: 70.0,
            require_in_front: true,
            min_box_px: Range(15.0, 30.0),
            far_distance_m: 50.0,
            min_box_far_px: Range(8.0, 15.0),
            require_inside_image: true,
            max_occlusion: 0.8,
        }
    }
}

/// Keypoint formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PoseFormat {
    /// COCO-17 keypoints with COCO visibility flags.
    Coco17,
}

/// Output encodings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Parquet compression codec of the annotation tables.
    pub compression: Compression,
    /// zstd level (1–22).
    pub zstd_level: u32,
    /// Encoding of RGB frames.
    pub rgb_encoding: RgbEncoding,
    /// Encoding of LiDAR sweeps.
    pub lidar_encoding: LidarEncoding,
    /// Encoding of DVS events.
    pub dvs_encoding: DvsEncoding,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            compression: Compression::Zstd,
            zstd_level: 3,
            rgb_encoding: RgbEncoding::Png,
            lidar_encoding: LidarEncoding::Parquet,
            dvs_encoding: DvsEncoding::Parquet,
        }
    }
}

/// Table compression codecs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// zstd.
    Zstd,
    /// Snappy.
    Snappy,
    /// No compression.
    None,
}

/// RGB frame encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RgbEncoding {
    /// One PNG per frame (fast compression).
    Png,
}

/// LiDAR sweep encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LidarEncoding {
    /// A Parquet table per clip (frame, x, y, z, intensity).
    Parquet,
    /// One little-endian f32 `x y z intensity` file per sweep (the seed system's `.bin`).
    BinF32,
}

/// DVS event encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DvsEncoding {
    /// A Parquet table per clip (frame, x, y, t_ns, polarity).
    Parquet,
}

/// Sanity limits; a spec beyond one is rejected unless `--allow-large` is given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Most clips in a dataset.
    pub max_clips: u64,
    /// Most pixels in one image (width × height).
    pub max_image_pixels: u64,
    /// Largest estimated dataset size, bytes.
    pub max_dataset_bytes: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_clips: 100_000,
            max_image_pixels: 3840 * 2160,
            max_dataset_bytes: 2_000_000_000_000,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_town_names_match_the_world_module() {
        let names: Vec<&str> = BuiltinTown::ALL.iter().map(|t| t.name()).collect();
        assert_eq!(names, crate::world::BUILTIN_TOWN_NAMES);
        for town in BuiltinTown::ALL {
            assert_eq!(
                serde_json::to_value(town).unwrap(),
                serde_json::Value::from(town.name())
            );
        }
        for preset in WeatherPreset::ALL {
            assert_eq!(
                serde_json::to_value(preset).unwrap(),
                serde_json::Value::from(preset.name())
            );
        }
    }

    #[test]
    fn defaults_are_the_papers_values() {
        let spec = Spec::default();
        assert_eq!(spec.dataset.weathers.resolved().len(), 12);
        assert_eq!(spec.dataset.fps, 30);
        assert_eq!(spec.dataset.clip_duration_s, Range(10.0, 15.0));
        assert_eq!(spec.dataset.splits["town03_like"], Split::Val);
        assert_eq!(spec.dataset.splits["town05_like"], Split::Test);
        let mix: f64 = spec.pedestrians.archetype_mix.values().sum();
        assert!((mix - 1.0).abs() < 1e-12);
        assert_eq!(spec.pedestrians.archetype_mix["business_person"], 0.30);
        let young = &spec.pedestrians.archetypes["young_person"];
        assert_eq!(
            (young.speed_mps, young.attention, young.crossing_probability),
            (Range(1.2, 2.0), 0.4, 0.90)
        );
        let elderly = &spec.pedestrians.archetypes["elderly_person"];
        assert_eq!(
            (
                elderly.hesitation_s,
                elderly.patience_s.max(),
                elderly.ttc_threshold_s.max()
            ),
            (Range(1.0, 2.0), 18.0, 6.0)
        );
        let c = &spec.crossing;
        assert_eq!(
            (
                c.layers.crosser_allocation.max_crosser_ratio,
                c.layers.groups.probability
            ),
            (0.9, 0.4)
        );
        assert_eq!((c.retreat.probability, c.retreat.window_fraction), (0.15, 0.4));
        assert_eq!(c.lookahead.points_m, vec![0.5, 1.5, 2.5]);
        assert_eq!(c.decision_window_m, Range(10.0, 40.0));
        assert_eq!(WeatherPreset::NightClear.params().sun_altitude_deg, -40.0);
        assert_eq!(
            (
                spec.sensors.rgb.width_px,
                spec.sensors.rgb.height_px,
                spec.sensors.rgb.fov_deg
            ),
            (1280, 720, 90.0)
        );
        assert_eq!(
            (spec.sensors.lidar.channels, spec.sensors.lidar.points_per_second),
            (64, 1_000_000)
        );
        assert_eq!(spec.annotations.visibility.min_box_far_px, Range(8.0, 15.0));
    }
}
