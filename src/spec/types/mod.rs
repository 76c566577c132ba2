//! The dataset spec (`version: 1`): Rust types that serve loading, defaults, validation and the JSON Schema.
//!
//! Every default is the paper's value (ARCANE-PedSynth, its tables) or, where the paper is silent, the value of
//! its public code. A spec states only what differs: the loader deep-merges the user's YAML onto
//! `Spec::default()` key by key, except that a *mix* (a key named `mix` or ending in `_mix`) and a list are
//! replaced as a whole.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

mod annotations;
mod crossing;
mod dataset;
mod pedestrians;
mod randomisation;
mod sensors;
mod traffic;

pub use annotations::*;
pub use crossing::*;
pub use dataset::*;
pub use pedestrians::*;
pub use randomisation::*;
pub use sensors::*;
pub use traffic::*;

/// The spec language version this build understands.
pub const SPEC_VERSION: u32 = 1;

/// Whether `x` is 0: keys added after a spec's hash was first published are serialised only when they differ
/// from their default, so that the hash of a spec that does not use them stays what it was.
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// Whether `x` is its type's default (see [`is_zero`]).
fn is_default<T: Default + PartialEq>(x: &T) -> bool {
    *x == T::default()
}

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
    /// Domain randomisation: how each clip's light and camera vary, drawn per clip. Off by default.
    #[serde(skip_serializing_if = "is_default")]
    pub domain_randomisation: DomainRandomisation,
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
            domain_randomisation: DomainRandomisation::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_town_names_serialise_as_their_names() {
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
        for split in [Split::Train, Split::Val, Split::Test] {
            assert_eq!(
                serde_json::to_value(split).unwrap(),
                serde_json::Value::from(split.name())
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
            (1.0, 0.4)
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
        assert_eq!(spec.annotations.visibility.min_box_far_px, BoxSize::new(8.0, 15.0));
    }
}
