//! Crossing-rate control, end to end, on a spec the calibration was not fitted on
//! (`tests/data/specs/heldout_crossing.yaml`): for every target 0, 0.05, 0.1, ..., 0.95, 1, generate a dataset
//! of more than 1,000 pedestrians and check the sequence-level crossing ratio that `pedsynth stats` (computed
//! from the written tables only) reports: within 1 percentage point of the target, as issue 15 asks, and so
//! with traffic lights, cyclists and emergency vehicles on as well (the same 21 targets). The
//! planner gives each clip a count of labelled crossers and `generate` promotes or demotes pedestrians until
//! the clip has it (`sensors::realise`); rare-event targets (0, 0.05, 0.1: below what the default 9 % baseline
//! alone gives) also lower the baseline, crossing-heavy ones (0.9, 0.95, 1) also adapt the layers (every
//! pedestrian a crosser, no crossing groups, more crossers mid-road). Measured with the realisation example
//! (the same clips as `generate`): misses of at most 0.52 pp. Slow statistical tests: `#[ignore]`d, run by
//! `cargo test -- --include-ignored` (CI).

use crate::common;

use std::path::PathBuf;

use pedsynth::dataset::read::stats;

/// Traffic lights, 1–3 cyclists per clip and emergency vehicles in a fifth of the clips: parts 1, 2 and 4 of
/// issue 15 on at once (part 3, the gaze labels, is always on).
const EVERY_FEATURE: [&str; 4] = [
    "traffic.signals.enabled=true",
    "traffic.cyclists.per_clip=[1, 3]",
    "traffic.emergency.enabled=true",
    "traffic.emergency.clip_share=0.2",
];

/// Generates the held-out spec, tables only, at `target` with the `extra` overrides; its directory and
/// statistics.
fn generate_with(target: f64, extra: &[&str]) -> (PathBuf, stats::DatasetStats) {
    let out = std::env::temp_dir().join(format!(
        "pedsynth-crossing-rate-{}-{target}-{}",
        std::process::id(),
        extra.len()
    ));
    let _ = std::fs::remove_dir_all(&out);
    let target_set = format!("crossing.target_ratio={target}");
    let overrides: Vec<&str> = common::NO_SENSORS
        .iter()
        .copied()
        .chain(extra.iter().copied())
        .chain([target_set.as_str()])
        .collect();
    let spec = std::path::Path::new("tests/data/specs/heldout_crossing.yaml");
    let (code, _, stderr) = common::generate(spec, &overrides, &out, None);
    assert_eq!(code, 0, "{stderr}");
    let stats = stats::compute(&out).expect("the tables read back");
    (out, stats)
}

/// Generates the held-out spec at each target and checks the achieved ratio within `tolerance`; returns the
/// datasets' statistics, in target order (their directories are removed).
fn sweep(targets: &[f64], tolerance: f64) -> Vec<stats::DatasetStats> {
    sweep_with(targets, tolerance, &[])
}

/// [`sweep`] with more `--set` overrides.
fn sweep_with(targets: &[f64], tolerance: f64, extra: &[&str]) -> Vec<stats::DatasetStats> {
    targets
        .iter()
        .map(|&target| {
            let (out, stats) = generate_with(target, extra);
            eprintln!(
                "target {target}: achieved {:.3} over {} pedestrians",
                stats.achieved_crossing_ratio, stats.pedestrians
            );
            assert!(stats.pedestrians >= 1000, "{} pedestrians", stats.pedestrians);
            assert_eq!(stats.target_crossing_ratio, Some(target));
            let achieved = stats.achieved_crossing_ratio;
            assert!(
                (achieved - target).abs() <= tolerance,
                "target {target}: achieved {achieved:.3} over {} pedestrians",
                stats.pedestrians
            );
            std::fs::remove_dir_all(&out).ok();
            stats
        })
        .collect()
}

#[test]
#[ignore = "slow statistical test (the crossing-rate sweep): cargo test -- --include-ignored"]
fn achieved_crossing_ratio_on_a_held_out_spec_is_within_1_pp_of_the_target() {
    let targets: Vec<f64> = (3..=17).map(|k| (f64::from(k) * 5.0).round() / 100.0).collect();
    sweep(&targets, 0.01);
}

#[test]
#[ignore = "slow statistical test (the crossing-rate sweep with every feature on): cargo test -- --include-ignored"]
fn with_lights_cyclists_and_emergency_vehicles_on_the_targets_are_still_met() {
    // Measured 2026-11-27 with the realisation example (same spec, every feature on), every target 0 to 1 by
    // 0.05: misses of at most 0.52 pp (0 to 8 of 180 clips miss their count of labelled crossers).
    let targets: Vec<f64> = (0..=20).map(|k| f64::from(k) * 5.0 / 100.0).collect();
    sweep_with(&targets, 0.01, &EVERY_FEATURE);
}

#[test]
#[ignore = "slow statistical test (the rare-event crossing-rate sweep): cargo test -- --include-ignored"]
fn rare_event_targets_below_the_baseline_are_met_within_1_pp() {
    let stats = sweep(&[0.0, 0.05, 0.1], 0.01);
    assert_eq!(stats[0].crossing, 0, "a target of 0 plans no crosser");
}

#[test]
fn crossing_heavy_targets_are_met_by_adapting_the_layers() {
    // The adaptation is planned, and a target past the heaviest one is refused (fast checks first).
    let plan = |target: f64| {
        let options = pedsynth::spec::LoadOptions {
            overrides: vec![format!("crossing.target_ratio={target}")],
            allow_large: false,
            profile: None,
        };
        pedsynth::dataset::inputs::plan_spec_file(
            std::path::Path::new("tests/data/specs/heldout_crossing.yaml"),
            &options,
        )
    };
    let (_, _, heavy) = plan(0.93).unwrap_or_else(|e| panic!("{e}"));
    let a = pedsynth::plan::crossing_adaptation(&heavy.spec).expect("0.93 needs an adaptation");
    assert_eq!(a.max_crosser_ratio, 1.0);
    assert_eq!(a.group_probability, 0.0);
    assert!(a.midroad_share > heavy.spec.crossing.layers.midroad_jaywalkers.share_of_crossers);
    assert!((a.realisation - 0.93).abs() < 1e-9, "{a:?}");
    assert!(
        heavy
            .clips
            .iter()
            .flat_map(|c| &c.pedestrians)
            .all(|p| p.group.is_none())
    );
    let (_, _, light) = plan(0.86).unwrap_or_else(|e| panic!("{e}"));
    let b = pedsynth::plan::crossing_adaptation(&light.spec).expect("0.86 needs an adaptation");
    assert!(b.group_probability > 0.0 && b.group_probability < light.spec.crossing.layers.groups.probability);
    let (_, _, usual) = plan(0.6).unwrap_or_else(|e| panic!("{e}"));
    assert!(pedsynth::plan::crossing_adaptation(&usual.spec).is_none());
    // A target of 1: every pedestrian a crosser, all starting mid-road, a realisation just short of 1.
    let (_, _, all) = plan(1.0).unwrap_or_else(|e| panic!("{e}"));
    let a = pedsynth::plan::crossing_adaptation(&all.spec).expect("1 needs an adaptation");
    assert_eq!(a.midroad_share, 1.0);
    assert!(a.realisation > 0.98 && a.realisation < 1.0, "{a:?}");
    assert!(
        all.clips
            .iter()
            .flat_map(|c| &c.pedestrians)
            .all(|p| p.role == pedsynth::plan::Role::Crosser)
    );
}

#[test]
#[ignore = "slow statistical test (the crossing-heavy crossing-rate sweep): cargo test -- --include-ignored"]
fn crossing_heavy_targets_are_met_within_1_pp() {
    sweep(&[0.9, 0.95, 1.0], 0.01);
}
