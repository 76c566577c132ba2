//! Benchmark of the LiDAR (the paper's sensor: 64 channels, 100 m, 1,000,000 points/s, 20 Hz) on one core, in
//! the busiest annotated frame of the first quickstart clip of each town:
//!
//! - `tick_all_rays` — one tick (1/30 s: 521 rays × 64 channels = 33,344 rays) with the general drop-off
//!   off, so every ray is traced: the rays/s figure (the target: ≥ 5,000,000 rays/s).
//! - `tick_default` — one tick with the paper's defaults (45 % of the rays dropped before tracing).
//! - `tick_static_only` — `tick_all_rays` without the agents: the static geometry's share of the cost (the
//!   rest is the agents').
//! - `rebuild_agents` — the per-tick rebuild of the agents' angular index; `build_static` — the per-clip
//!   static BVH.
//!
//! Run: `cargo bench --bench lidar`.

use std::path::Path;

use divan::counter::ItemsCount;
use glam::Affine3A;
use pedsynth::dsl::LoadOptions;
use pedsynth::dsl::types::Lidar;
use pedsynth::exec::observe::lidar::{self, ScanScratch, Tracer};
use pedsynth::exec::observe::rig::Rig;
use pedsynth::exec::observe::scene::{FrameScene, SceneTime, StaticScene, ego_at};
use pedsynth::exec::observe::{self};
use pedsynth::exec::simulate;
use pedsynth::exec::trace::ClipTrace;
use pedsynth::planner::ClipScript;

fn main() {
    divan::main();
}

const TOWNS: [&str; 3] = ["town01_like", "town03_like", "town05_like"];

struct Setup {
    script: ClipScript,
    scene: StaticScene,
    frame_scene: FrameScene,
    tracer: Tracer,
    pose: Affine3A,
    lidar: Lidar,
}

fn setup(town: &str) -> Setup {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let options = LoadOptions {
        overrides: vec![format!("dataset.towns=[{town}]")],
        allow_large: false,
    };
    let (_, towns, plan) = pedsynth::commands::plan_spec_file(&path, &options).expect("quickstart plans");
    let script = plan.clips[0].clone();
    let net = &towns[&script.town].network;
    let trace: ClipTrace = simulate::simulate(&script, &plan.sim, net);
    let rig = Rig::from_spec(&plan.spec.sensors);
    let ann = observe::observe(&script, &trace, &plan.spec, &rig, net).annotations;
    let mut counts = vec![0u32; trace.frame_count as usize];
    for r in &ann.rows {
        counts[r.frame as usize] += 1;
    }
    let frame = (0..counts.len())
        .max_by_key(|&f| (counts[f], std::cmp::Reverse(f)))
        .unwrap_or(0) as u32;
    let scene = StaticScene::build(&script, &trace, net);
    let mut frame_scene = FrameScene::default();
    frame_scene.build(&scene, &script, &trace, SceneTime::at(frame));
    let (pos, yaw) = ego_at(&trace, SceneTime::at(frame));
    let pose = observe::scene_from(&scene, &rig.world_from_lidar(pos, yaw));
    let mut tracer = Tracer::new(&scene);
    tracer.set_agents(&frame_scene, &pose);
    Setup {
        script,
        scene,
        frame_scene,
        tracer,
        pose,
        lidar: plan.spec.sensors.lidar.clone(),
    }
}

fn rays(l: &Lidar) -> usize {
    let p = lidar::TickPattern::of(l, 30, 0);
    (p.rays_per_channel * l.channels) as usize
}

fn tick(bencher: divan::Bencher, mut s: Setup, general_dropoff: f64) {
    s.lidar.dropoff_general_rate = general_dropoff;
    let mut scratch = ScanScratch::default();
    let mut points = Vec::new();
    bencher.counter(ItemsCount::new(rays(&s.lidar))).bench_local(|| {
        points.clear();
        lidar::scan(
            &s.lidar,
            30,
            0,
            s.script.seed,
            &s.pose,
            &s.tracer,
            |id| s.frame_scene.prim(&s.scene, id),
            &mut scratch,
            &mut points,
        )
    });
}

#[divan::bench(args = TOWNS)]
fn tick_all_rays(bencher: divan::Bencher, town: &str) {
    tick(bencher, setup(town), 0.0);
}

#[divan::bench(args = TOWNS)]
fn tick_default(bencher: divan::Bencher, town: &str) {
    tick(bencher, setup(town), Lidar::default().dropoff_general_rate);
}

#[divan::bench(args = TOWNS)]
fn tick_static_only(bencher: divan::Bencher, town: &str) {
    let mut s = setup(town);
    s.frame_scene = FrameScene::default();
    s.tracer.set_agents(&s.frame_scene, &s.pose);
    tick(bencher, s, 0.0);
}

#[divan::bench(args = TOWNS)]
fn rebuild_agents(bencher: divan::Bencher, town: &str) {
    let mut s = setup(town);
    bencher.bench_local(|| s.tracer.set_agents(&s.frame_scene, &s.pose));
}

#[divan::bench(args = TOWNS)]
fn build_static(bencher: divan::Bencher, town: &str) {
    let s = setup(town);
    bencher.bench_local(|| Tracer::new(&s.scene));
}
