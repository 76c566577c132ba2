//! Intention before action, end to end, measured from the written tables the way the field's benchmark reads
//! them: on PedSynth++ (`specs/pedsynth_pp.yaml`, the spec the defaults were chosen on) and on a held-out spec
//! (`tests/data/specs/heldout_crossing.yaml`: another seed, towns and weathers),
//! - at least 60 % of crossers have 76 or more annotated frames up to their first C = 1 frame (real JAAD: 44 %),
//!   and short observations still exist (at least 5 % below 76);
//! - under PedestrianActionBenchmark's sampling (`stats --protocol pab`, defaults as the benchmark) the
//!   window-level crossing share is within 5 percentage points of the spec's target ratio, and every split has
//!   windows of both classes;
//! - no crosser but a mid-road jaywalker has C = 1 in its first annotated frame.
//!
//! Slow statistical tests: `#[ignore]`d, run by `cargo test -- --include-ignored` (CI).

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pedsynth::dataset::read::protocol::{self, PabOptions};
use pedsynth::dataset::read::tables;
use pedsynth::dataset::write::Layout;

fn generate(spec: &str, name: &str) -> PathBuf {
    let out = std::env::temp_dir().join(format!("pedsynth-intention-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let (code, _, stderr) = common::generate(Path::new(spec), &common::NO_SENSORS, &out, None);
    assert_eq!(code, 0, "{stderr}");
    out
}

/// A pedestrian as the tables describe it.
#[derive(Default)]
struct Pedestrian {
    crosser: bool,
    midroad: bool,
    /// (frame, C) of each annotated frame.
    frames: Vec<(u32, bool)>,
}

fn pedestrians(dir: &Path) -> Vec<Pedestrian> {
    let layout = Layout::new(dir);
    let mut all = Vec::new();
    for path in tables::files(&layout, "pedestrians").unwrap() {
        let clip = path.file_stem().unwrap().to_string_lossy().into_owned();
        let mut by_id: BTreeMap<u32, Pedestrian> = BTreeMap::new();
        for b in tables::read(&path, &["pedestrian", "crosser", "behaviour"]).unwrap() {
            let (ids, crossers, behaviours) = (
                b.u32s("pedestrian").unwrap(),
                b.bools("crosser").unwrap(),
                b.strings("behaviour").unwrap(),
            );
            for (i, behaviour) in behaviours.iter().enumerate() {
                let p = by_id.entry(ids.value(i)).or_default();
                p.crosser = crossers.value(i);
                p.midroad = *behaviour == "midroad_jaywalker";
            }
        }
        let annotations = layout.table("annotations", &clip);
        for b in tables::read(&annotations, &["pedestrian", "frame", "crossing"]).unwrap() {
            let (ids, frames, crossing) = (
                b.u32s("pedestrian").unwrap(),
                b.u32s("frame").unwrap(),
                b.bools("crossing").unwrap(),
            );
            for i in 0..b.rows() {
                by_id
                    .get_mut(&ids.value(i))
                    .expect("every annotated pedestrian is in the pedestrians table")
                    .frames
                    .push((frames.value(i), crossing.value(i)));
            }
        }
        all.extend(by_id.into_values().map(|mut p| {
            p.frames.sort_unstable();
            p
        }));
    }
    all
}

fn check(spec: &str, name: &str) {
    let dir = generate(spec, name);
    let peds = pedestrians(&dir);

    // Frames in view up to and including the first C = 1 frame, per crosser with a track.
    let mut to_event: Vec<usize> = peds
        .iter()
        .filter(|p| p.crosser && !p.frames.is_empty())
        .map(|p| p.frames.iter().position(|f| f.1).map_or(0, |k| k + 1))
        .collect();
    to_event.sort_unstable();
    let n = to_event.len();
    assert!(n >= 300, "{name}: only {n} crossers with a track");
    let long = to_event.iter().filter(|&&f| f >= 76).count() as f64 / n as f64;
    let quantile = |q: f64| to_event[((n - 1) as f64 * q).round() as usize];
    eprintln!(
        "{name}: {n} crossers, frames up to the first C = 1 frame: median {} (p25 {}, p75 {}), {:.1} % with >= 76",
        quantile(0.5),
        quantile(0.25),
        quantile(0.75),
        100.0 * long
    );
    assert!(
        long >= 0.60,
        "{name}: {:.1} % of crossers with >= 76 frames",
        100.0 * long
    );
    assert!(
        1.0 - long >= 0.05,
        "{name}: short observations vanished ({:.1} % below 76 frames)",
        100.0 * (1.0 - long)
    );

    let sudden_at_first_frame = peds
        .iter()
        .filter(|p| p.crosser && !p.midroad && p.frames.first().is_some_and(|f| f.1))
        .count();
    // The simulation decides when a crosser has been seen from its view proxy (one ray to the chest); the
    // annotation's occlusion test samples 22 points. Rarely the proxy counts as seen a pedestrian the gate
    // finds too hidden (held-out spec: 1 of 665, a parent with a child following its group, 77 % hidden in its
    // first annotated frame): at most 0.5 % of the crossers.
    eprintln!(
        "{name}: {sudden_at_first_frame} crossers (not mid-road jaywalkers) with C = 1 in their first annotated frame"
    );
    assert!(
        sudden_at_first_frame as f64 <= 0.005 * n as f64,
        "{name}: {sudden_at_first_frame} of {n} crossers (not mid-road jaywalkers) with C = 1 in their first \
         annotated frame"
    );

    let pab = protocol::compute(&dir, &PabOptions::default()).unwrap();
    eprint!("{name}: {pab}");
    let target = pab.target_crossing_ratio.expect("the manifest has the target");
    let share = pab.all.window_crossing_share;
    assert!(
        (share - target).abs() <= 0.05,
        "{name}: window-level crossing share {share:.3}, target {target}"
    );
    assert_eq!(pab.splits.len(), 3, "{name}: splits {:?}", pab.splits.keys());
    for (split, s) in &pab.splits {
        assert!(
            s.crossing.windows > 0 && s.not_crossing.windows > 0,
            "{name}: split {split} lacks a class: {s:?}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
#[ignore = "slow statistical test (the held-out intention statistics): cargo test -- --include-ignored"]
fn crossers_are_seen_before_they_cross_on_a_held_out_spec() {
    check("tests/data/specs/heldout_crossing.yaml", "heldout");
}

#[test]
#[ignore = "slow statistical test (the PedSynth++ intention statistics): cargo test -- --include-ignored"]
fn crossers_are_seen_before_they_cross_on_pedsynth_pp() {
    check("specs/pedsynth_pp.yaml", "pedsynth_pp");
}
