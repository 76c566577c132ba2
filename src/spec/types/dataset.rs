//! `dataset`: what to generate — towns (built-in or OpenDRIVE), weathers (the paper's 12 presets or custom),
//! clip counts and durations, frame rate, splits.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::Range;

/// What to generate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Dataset {
    /// Dataset name (used in the output's metadata).
    pub name: String,
    /// Licence of the generated data, as the dataset card's `license` field: an SPDX-style identifier as
    /// Hugging Face lists them (`cc-by-4.0`, `cc0-1.0`, `mit`, ...), `other`, or `unknown` (the default: the
    /// data is yours to license).
    pub license: String,
    /// Dataset seed; each clip's seed derives from it and the clip's identity.
    pub seed: u64,
    /// Towns: built-in names or `{name, opendrive: path}` (path relative to the spec file).
    pub towns: Vec<TownRef>,
    /// Weathers: `all` (the paper's 12 presets), or a list of preset names and custom weathers.
    pub weathers: WeatherSelection,
    /// Clip counts (the paper's `--videos_per_weather` and `--dataset_mode`).
    pub clips: Clips,
    /// Clip duration range in seconds; each clip draws its duration uniformly from it. A clip whose crossers'
    /// timelines need more time is lengthened, up to the range's maximum plus `max_extension_s`.
    pub clip_duration_s: Range,
    /// How far beyond `clip_duration_s`'s maximum a clip may be lengthened so that its crossers' timelines fit,
    /// seconds. 0 (the default): every clip's duration lies in `clip_duration_s`.
    #[serde(skip_serializing_if = "super::is_zero")]
    pub max_extension_s: f64,
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
            license: "unknown".to_owned(),
            seed: 0,
            towns: BuiltinTown::ALL.iter().map(|t| TownRef::Builtin(*t)).collect(),
            weathers: WeatherSelection::All(AllKeyword::All),
            clips: Clips::default(),
            clip_duration_s: Range(10.0, 15.0),
            max_extension_s: 0.0,
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

impl Split {
    /// The split's name, as the spec and the tables spell it.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Val => "val",
            Split::Test => "test",
        }
    }
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
