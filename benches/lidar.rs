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

use divan::counter::ItemsCount;
use glam::Affine3A;
use pedsynth::sensors;
use pedsynth::sensors::lidar::{self, ScanScratch, Tracer};
use pedsynth::sensors::scene::{FrameScene, SceneTime, ego_at};
use pedsynth::spec::types::Lidar;

mod common;

fn main() {
    divan::main();
}

const TOWNS: [&str; 3] = ["town01_like", "town03_like", "town05_like"];

struct Setup {
    clip: common::BusyClip,
    frame_scene: FrameScene,
    tracer: Tracer,
    pose: Affine3A,
    lidar: Lidar,
}

fn setup(town: &str) -> Setup {
    let clip = common::busy_quickstart_clip(&[format!("dataset.towns=[{town}]")]);
    let mut frame_scene = FrameScene::default();
    let t = SceneTime::at(clip.frame);
    frame_scene.build(&clip.scene, &clip.script, &clip.trace, t);
    let (pos, yaw, pitch) = ego_at(&clip.trace, t);
    let pose = sensors::scene_from(&clip.scene, &clip.rig.world_from_lidar(pos, yaw, pitch));
    let mut tracer = Tracer::new(&clip.scene);
    tracer.set_agents(&frame_scene, &pose);
    Setup {
        lidar: clip.sensors.lidar.clone(),
        clip,
        frame_scene,
        tracer,
        pose,
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
            s.clip.script.seed,
            &s.pose,
            &s.tracer,
            |id| s.frame_scene.prim(&s.clip.scene, id),
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
    bencher.bench_local(|| Tracer::new(&s.clip.scene));
}
