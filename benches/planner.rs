//! Benchmarks of the planner: compiling a 10,000-clip spec (goal < 1 s on one core).
//! Run: `cargo bench --bench planner`.

use std::path::Path;

use pedsynth::dataset::inputs::load_towns;
use pedsynth::plan;
use pedsynth::spec::{self, LoadOptions};

fn main() {
    divan::main();
}

fn spec(town_override: &str, clips: u32) -> (spec::LoadedSpec, std::collections::BTreeMap<String, plan::TownContext>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let options = LoadOptions {
        overrides: vec![
            town_override.to_owned(),
            "dataset.weathers=all".to_owned(),
            format!("dataset.clips.count={clips}"),
        ],
        allow_large: true,
        profile: None,
    };
    let loaded = spec::load_file(&path, &options).expect("valid spec");
    let towns = load_towns(&loaded).expect("towns load");
    (loaded, towns)
}

/// 10,008 clips (834 per weather × 12 weathers) in one town.
#[divan::bench(args = ["town01_like", "town03_like", "town05_like"], sample_count = 5)]
fn plan_10k_clips(bencher: divan::Bencher, town: &str) {
    let (loaded, towns) = spec(&format!("dataset.towns=[{town}]"), 834);
    let hash = loaded.hash().expect("hash");
    bencher.bench(|| {
        let plan = plan::plan(divan::black_box(&loaded.spec), &hash, "specs", &towns, None).expect("feasible");
        assert_eq!(plan.clips.len(), 10_008);
        plan
    });
}
