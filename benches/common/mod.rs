//! What the sensor benchmarks share: the first clip of `specs/quickstart.yaml` (with `--set` overrides), its
//! simulation, and its busiest annotated frame (most annotated pedestrians, earliest on ties).
#![allow(dead_code)]

use std::path::Path;

use pedsynth::dsl::LoadOptions;
use pedsynth::dsl::types::Sensors;
use pedsynth::exec::observe::rig::Rig;
use pedsynth::exec::observe::scene::StaticScene;
use pedsynth::exec::observe::{self};
use pedsynth::exec::simulate;
use pedsynth::exec::trace::ClipTrace;
use pedsynth::planner::ClipScript;
use pedsynth::world::RoadNetwork;

/// A simulated clip and its busiest annotated frame.
pub struct BusyClip {
    pub script: ClipScript,
    pub trace: ClipTrace,
    pub rig: Rig,
    pub sensors: Sensors,
    pub net: RoadNetwork,
    pub scene: StaticScene,
    pub frame: u32,
}

/// The first quickstart clip under `overrides`, simulated, with its static scene and busiest frame.
pub fn busy_quickstart_clip(overrides: &[String]) -> BusyClip {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let options = LoadOptions {
        overrides: overrides.to_vec(),
        allow_large: false,
    };
    let (_, towns, plan) = pedsynth::commands::plan_spec_file(&path, &options).expect("quickstart plans");
    let script = plan.clips[0].clone();
    let net = towns[&script.town].network.clone();
    let trace = simulate::simulate(&script, &plan.sim, &net);
    let rig = Rig::from_spec(&plan.spec.sensors);
    let ann = observe::observe(&script, &trace, &plan.spec, &rig, &net).annotations;
    let mut counts = vec![0u32; trace.frame_count as usize];
    for r in &ann.rows {
        counts[r.frame as usize] += 1;
    }
    let frame = (0..counts.len())
        .max_by_key(|&f| (counts[f], std::cmp::Reverse(f)))
        .unwrap_or(0) as u32;
    let scene = StaticScene::build(&script, &trace, &net);
    BusyClip {
        script,
        trace,
        rig,
        sensors: plan.spec.sensors.clone(),
        net,
        scene,
        frame,
    }
}
