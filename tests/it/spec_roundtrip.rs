//! Property tests of the spec loader: any valid spec round-trips (load → fully defaulted form → serialise →
//! load gives an equal value), and no input, however malformed, makes the loader panic.

use std::path::Path;

use pedsynth::spec::{self, LoadOptions};
use proptest::prelude::*;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn load_text(text: &[u8], overrides: Vec<String>) -> Result<spec::LoadedSpec, spec::SpecErrors> {
    spec::load_bytes(
        text,
        "prop.yaml",
        &root().join("specs"),
        &LoadOptions {
            overrides,
            allow_large: false,
            profile: None,
        },
    )
}

fn assert_round_trips(loaded: &spec::LoadedSpec) {
    let yaml = spec::to_yaml(&loaded.spec).expect("yaml");
    let again = load_text(yaml.as_bytes(), Vec::new()).unwrap_or_else(|e| panic!("{}\n{yaml}", e.render_plain(100)));
    assert_eq!(again.spec, loaded.spec, "{yaml}");
    assert_eq!(again.hash().expect("hash"), loaded.hash().expect("hash"));
}

/// `min_box_px` is a width and a height, not a range: a box wider than tall is valid in either form (it was
/// once parsed as a range, so `[30, 15]` was rejected as empty and its values read as min/max).
#[test]
fn box_sizes_are_width_by_height_in_either_form() {
    for text in [
        "version: 1\nannotations: {visibility: {min_box_px: [30, 15]}}\n",
        "version: 1\nannotations: {visibility: {min_box_px: {width_px: 30, height_px: 15}}}\n",
    ] {
        let loaded = load_text(text.as_bytes(), Vec::new()).unwrap_or_else(|e| panic!("{}", e.render_plain(100)));
        let b = loaded.spec.annotations.visibility.min_box_px;
        assert_eq!((b.width_px, b.height_px), (30.0, 15.0), "{text}");
        assert_round_trips(&loaded);
    }
    let bad = load_text(
        b"version: 1\nannotations: {visibility: {min_box_px: {width_px: 3, heigth_px: 4}}}\n",
        Vec::new(),
    )
    .expect_err("a misspelt key");
    assert_eq!(
        bad.codes(),
        ["pedsynth::spec::missing_key", "pedsynth::spec::unknown_key"]
    );
}

#[test]
fn shipped_specs_round_trip() {
    for entry in std::fs::read_dir(root().join("specs")).unwrap() {
        let path = entry.unwrap().path();
        let loaded = spec::load_file(&path, &LoadOptions::default()).unwrap();
        assert_round_trips(&loaded);
    }
}

const WEATHERS: [&str; 12] = [
    "clear_noon",
    "cloudy_noon",
    "wet_noon",
    "soft_rain",
    "foggy_noon",
    "clear_sunset",
    "night_clear",
    "dawn",
    "heavy_rain",
    "rainy_sunset",
    "night_rainy",
    "night_foggy",
];
const ARCHETYPES: [&str; 5] = [
    "business_person",
    "casual_person",
    "elderly_person",
    "young_person",
    "parent_with_child",
];

/// Overrides that keep a spec valid, built from random choices.
fn valid_overrides() -> impl Strategy<Value = Vec<String>> {
    (
        any::<u64>(),
        0.1f64..0.8,
        proptest::sample::subsequence(WEATHERS.to_vec(), 1..=12),
        proptest::sample::subsequence(vec!["town01_like", "town02_like", "town03_like", "town05_like"], 1..=4),
        (1u32..20, 1u32..20, 1u32..20),
        (0usize..5, 0.2f64..1.8, 0.0f64..1.0, -90.0f64..90.0, 0.0f64..100.0),
        (any::<bool>(), any::<bool>(), 0.0f64..1.0, 1u32..=240),
    )
        .prop_map(|(seed, target, weathers, towns, (a, b, clips), (arch, speed, p, alt, fog), (lidar, groups, retreat, fps))| {
            let (lo, hi) = (a.min(b), a.max(b));
            vec![
                format!("dataset.seed={seed}"),
                format!("dataset.weathers=[{}, {{name: custom_{clips}, sun_altitude_deg: {alt}, fog_density_pct: {fog}}}]", weathers.join(", ")),
                format!("dataset.towns=[{}]", towns.join(", ")),
                format!("dataset.clips.count={clips}"),
                format!("dataset.fps={fps}"),
                format!("pedestrians.per_clip=[{lo}, {hi}]"),
                format!("crossing.target_ratio={target}"),
                format!("pedestrians.archetypes.{}.speed_mps=[{speed}, {}]", ARCHETYPES[arch], speed + 0.4),
                format!("pedestrians.archetypes.{}.attention={p}", ARCHETYPES[arch]),
                format!("pedestrians.archetypes.runner={{speed_mps: [2.0, 3.0], crossing_probability: {p}}}"),
                format!("pedestrians.archetype_mix={{{}: 0.5, runner: 0.5}}", ARCHETYPES[arch]),
                format!("sensors.lidar.enabled={lidar}"),
                format!("crossing.layers.groups.enabled={groups}"),
                format!("crossing.retreat.probability={retreat}"),
            ]
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn any_valid_spec_round_trips(overrides in valid_overrides()) {
        let base = std::fs::read(root().join("specs/quickstart.yaml")).unwrap();
        let loaded = load_text(&base, overrides).unwrap_or_else(|e| panic!("{}", e.render_plain(100)));
        assert_round_trips(&loaded);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let _ = load_text(&bytes, Vec::new());
    }

    #[test]
    fn mutated_specs_never_panic(edits in proptest::collection::vec((0usize..4096, any::<u8>(), 0u8..3), 1..8)) {
        let mut bytes = std::fs::read(root().join("specs/pedsynth_pp.yaml")).unwrap();
        for (pos, byte, op) in edits {
            let pos = pos % (bytes.len() + 1);
            match op {
                0 => bytes.insert(pos, byte),
                1 if pos < bytes.len() => { bytes.remove(pos); }
                _ if pos < bytes.len() => bytes[pos] = byte,
                _ => {}
            }
        }
        let _ = load_text(&bytes, Vec::new());
    }

    #[test]
    fn arbitrary_overrides_never_panic(key in "[a-z_.\\[\\]0-9]{0,40}", value in "\\PC{0,40}") {
        let base = std::fs::read(root().join("specs/quickstart.yaml")).unwrap();
        let _ = load_text(&base, vec![format!("{key}={value}")]);
    }
}
