//! Benchmark of the simulation: one 13 s clip (390 frames at 30 fps) with 10 pedestrians and 10 traffic vehicles
//! plus the ego, on one core. Figure of merit: agent-steps per second (agents × frames / time), goal ≥ 2M.
//! Run: `cargo bench --bench sim`. `simulate_13s_clip_*` times the first clip of the plan;
//! `simulate_8_clips_*` times the first eight (eight seeds: different routes, spawns and archetypes), so that
//! the figure is not one lucky seed.

use std::path::Path;

use pedsynth::sim;
use pedsynth::spec::LoadOptions;

fn main() {
    divan::main();
}

/// The plan of `clips` 13 s clips with 10 pedestrians and 10 vehicles in `town`.
fn plan(
    town: &str,
    clips: usize,
) -> (
    std::collections::BTreeMap<String, pedsynth::plan::TownContext>,
    pedsynth::plan::Plan,
) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/pedsynth_pp.yaml");
    let options = LoadOptions {
        overrides: vec![
            format!("dataset.towns=[{town}]"),
            "dataset.weathers=[clear_noon]".to_owned(),
            format!("dataset.clips.count={clips}"),
            "dataset.clip_duration_s=[13, 13]".to_owned(),
            "pedestrians.per_clip=[10, 10]".to_owned(),
            "traffic.vehicles_per_clip=[10, 10]".to_owned(),
        ],
        allow_large: true,
        profile: None,
    };
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(&path, &options).expect("feasible spec");
    (towns, plan)
}

const TOWNS: [&str; 4] = ["town01_like", "town02_like", "town03_like", "town05_like"];

#[divan::bench(args = TOWNS, sample_count = 20)]
fn simulate_13s_clip_10_peds_10_vehicles(bencher: divan::Bencher, town: &str) {
    let (towns, plan) = plan(town, 1);
    let clip = &plan.clips[0];
    let net = &towns[&clip.town].network;
    let agents = (clip.pedestrians.len() + clip.vehicles.len() + 1) as u64;
    bencher
        .counter(divan::counter::ItemsCount::new(agents * u64::from(clip.frame_count)))
        .bench(|| sim::simulate(divan::black_box(clip), &plan.sim, net));
}

#[divan::bench(args = TOWNS, sample_count = 10)]
fn simulate_8_clips_13s_10_peds_10_vehicles(bencher: divan::Bencher, town: &str) {
    let (towns, plan) = plan(town, 8);
    let net = &towns[town].network;
    let steps: u64 = plan
        .clips
        .iter()
        .map(|c| (c.pedestrians.len() + c.vehicles.len() + 1) as u64 * u64::from(c.frame_count))
        .sum();
    bencher.counter(divan::counter::ItemsCount::new(steps)).bench(|| {
        for clip in &plan.clips {
            divan::black_box(sim::simulate(divan::black_box(clip), &plan.sim, net));
        }
    });
}
