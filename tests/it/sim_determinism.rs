//! Determinism: a clip's trace is byte-identical across runs and across rayon pools of 1 and 2 threads.

use std::path::Path;

use pedsynth::sim;
use pedsynth::spec::LoadOptions;

#[test]
fn traces_are_identical_across_runs_and_thread_counts() -> Result<(), Box<dyn std::error::Error>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/pedsynth_pp.yaml");
    let options = LoadOptions {
        overrides: vec![
            "dataset.clips.count=4".to_owned(),
            "dataset.weathers=[clear_noon, night_rainy]".to_owned(),
        ],
        allow_large: true,
        profile: None,
    };
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(&path, &options)?;
    assert!(plan.clips.len() >= 8);
    let run = |threads: usize| -> Result<(String, String), Box<dyn std::error::Error>> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        let traces = pool.install(|| sim::simulate_all(&plan, &towns))?;
        Ok((serde_json::to_string(&traces)?, serde_json::to_string(&traces[3])?))
    };
    let one = run(1)?;
    let two = run(2)?;
    let again = run(2)?;
    assert!(one == two, "1 vs 2 threads differ");
    assert!(two == again, "two runs differ");
    // A single clip alone gives the same trace as within the batch.
    let alone = serde_json::to_string(&sim::simulate(
        &plan.clips[3],
        &plan.sim,
        &towns[&plan.clips[3].town].network,
    ))?;
    assert!(one.1 == alone, "a clip alone differs from the same clip in a batch");
    Ok(())
}
