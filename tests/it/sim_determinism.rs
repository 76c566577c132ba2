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

/// The quickstart's first clip simulated with the overrides `off` and with `on`, which must change no clip
/// script: the plan without them and the two traces (the second checked to be a pure function of its clip).
fn first_clip_off_and_on(
    off: &[&str],
    on: &[&str],
) -> (
    pedsynth::plan::Plan,
    pedsynth::sim::trace::ClipTrace,
    pedsynth::sim::trace::ClipTrace,
) {
    let plan_with = |overrides: &[&str]| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
        let options = LoadOptions {
            overrides: overrides.iter().map(|s| s.to_string()).collect(),
            allow_large: false,
            profile: None,
        };
        let (_, towns, plan) =
            pedsynth::dataset::inputs::plan_spec_file(&path, &options).unwrap_or_else(|e| panic!("{}", e.render()));
        (towns, plan)
    };
    let (towns, off) = plan_with(off);
    let (_, on) = plan_with(on);
    assert_eq!(off.clips, on.clips, "the wobble changes no clip script");
    let net = &towns[&off.clips[0].town].network;
    let (a, b) = (
        sim::simulate(&off.clips[0], &off.sim, net),
        sim::simulate(&on.clips[0], &on.sim, net),
    );
    assert_eq!(
        b,
        sim::simulate(&on.clips[0], &on.sim, net),
        "a pure function of the clip"
    );
    (off, a, b)
}

#[test]
fn the_heading_wobble_turns_the_recorded_heading_only_with_the_asked_spread() {
    let (off, a, b) = first_clip_off_and_on(&[], &["traffic.ego.heading_wobble.sd_deg=2"]);
    assert!(off.sim.ego_heading.is_none(), "off: absent from the plan file");
    let offsets: Vec<f64> = a
        .ego
        .iter()
        .zip(&b.ego)
        .map(|(x, y)| (y.yaw_rad - x.yaw_rad).to_degrees())
        .collect();
    for (x, y) in a.ego.iter().zip(&b.ego) {
        assert_eq!((x.pos, x.speed_mps), (y.pos, y.speed_mps), "the path is unchanged");
    }
    assert_eq!(a.pedestrians, b.pedestrians, "nobody else moves differently");
    // A smooth offset of sd 2° and 1 s time constant turns at a rate of sd σ/T = 2°/s, 0.067° a frame (one clip's
    // estimate, so a loose bound; the unit test in `sim` pins it over many clips), and its rate changes smoothly.
    let steps: Vec<f64> = offsets.windows(2).map(|w| w[1] - w[0]).collect();
    let rms = |xs: &[f64]| (xs.iter().map(|d| d * d).sum::<f64>() / xs.len() as f64).sqrt();
    let bends: Vec<f64> = steps.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(
        (rms(&steps) - 0.067).abs() < 0.04,
        "per-frame change rms {}°",
        rms(&steps)
    );
    assert!(
        rms(&bends) < 0.6 * rms(&steps),
        "bends {}° against steps {}°",
        rms(&bends),
        rms(&steps)
    );
    assert!(
        offsets.iter().all(|o| o.abs() < 10.0) && offsets.iter().any(|o| o.abs() > 0.5),
        "{offsets:?}"
    );
}

#[test]
fn the_pitch_wobble_nods_the_recorded_ego_only_with_the_asked_spread() {
    let (off, a, b) = first_clip_off_and_on(
        &["traffic.ego.heading_wobble.sd_deg=2"],
        &[
            "traffic.ego.heading_wobble.sd_deg=2",
            "traffic.ego.pitch_wobble.sd_deg=0.5",
            "traffic.ego.pitch_wobble.correlation_s=0.35",
        ],
    );
    assert!(off.sim.ego_pitch.is_none(), "off: absent from the plan file");
    assert!(a.ego.iter().all(|f| f.pitch_rad == 0.0), "level without it");
    for (x, y) in a.ego.iter().zip(&b.ego) {
        // Its own stream: the heading wobble's draws are the same with the pitch on.
        assert_eq!(
            (x.pos, x.yaw_rad, x.speed_mps),
            (y.pos, y.yaw_rad, y.speed_mps),
            "only the pitch changes"
        );
    }
    assert_eq!(a.pedestrians, b.pedestrians, "nobody else moves differently");
    assert!(
        b.vehicles.iter().flatten().all(|f| f.pitch_rad == 0.0),
        "traffic stays level"
    );
    let pitch_deg: Vec<f64> = b.ego.iter().map(|f| f.pitch_rad.to_degrees()).collect();
    let rms = (pitch_deg.iter().map(|p| p * p).sum::<f64>() / pitch_deg.len() as f64).sqrt();
    // One clip of some 10 s holds ~30 correlation times: its spread is within a third of the asked 0.5°.
    assert!((rms - 0.5).abs() < 0.17, "rms {rms}° over {} frames", pitch_deg.len());
    assert!(pitch_deg.iter().all(|p| p.abs() < 2.5), "{pitch_deg:?}");
}
