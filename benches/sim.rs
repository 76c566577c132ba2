//! Benchmark of the simulation: one 13 s clip (390 frames at 30 fps) with 10 pedestrians and 10 traffic vehicles
//! plus the ego, on one core. Figure of merit: agent-steps per second (agents × frames / time), goal ≥ 2M.
//! Run: `cargo bench --bench sim`.

use std::path::Path;

use pedsynth::dsl::LoadOptions;
use pedsynth::exec::sim;

fn main() {
    divan::main();
}

#[divan::bench(args = ["town01_like", "town03_like"], sample_count = 20)]
fn simulate_13s_clip_10_peds_10_vehicles(bencher: divan::Bencher, town: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/pedsynth_pp.yaml");
    let options = LoadOptions {
        overrides: vec![
            format!("dataset.towns=[{town}]"),
            "dataset.weathers=[clear_noon]".to_owned(),
            "dataset.clips.count=1".to_owned(),
            "dataset.clip_duration_s=[13, 13]".to_owned(),
            "pedestrians.per_clip=[10, 10]".to_owned(),
            "traffic.vehicles_per_clip=[10, 10]".to_owned(),
        ],
        allow_large: true,
    };
    let (_, towns, plan) = pedsynth::commands::plan_spec_file(&path, &options).expect("feasible spec");
    let clip = &plan.clips[0];
    let net = &towns[&clip.town].network;
    let agents = (clip.pedestrians.len() + clip.vehicles.len() + 1) as u64;
    bencher
        .counter(divan::counter::ItemsCount::new(agents * u64::from(clip.frame_count)))
        .bench(|| sim::simulate(divan::black_box(clip), &plan.sim, net));
}
