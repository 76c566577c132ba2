//! Benchmark of the camera: one 1280 × 720 frame of a quickstart clip (its busiest annotated frame), on one
//! core. `render_rgb_frame` is the renderer alone (visibility buffer, shadow map, shading, labels, rain: no
//! encoding); `encode_*` time the PNG encoders of one frame; `build_frame_scene` the per-frame scene. The
//! issue's target is ≥ 60 rendered frames per second on one core.
//! Run: `cargo bench --bench camera`.

use std::path::Path;

use pedsynth::dsl::LoadOptions;
use pedsynth::exec::observe::camera::light::Lighting;
use pedsynth::exec::observe::camera::{CameraImages, Renderer, streak_seed};
use pedsynth::exec::observe::rig::Rig;
use pedsynth::exec::observe::scene::{FrameScene, SceneTime, StaticScene, ego_at};
use pedsynth::exec::observe::{self};
use pedsynth::exec::simulate;
use pedsynth::exec::trace::ClipTrace;
use pedsynth::exec::write::sensors::{rgb_png, semantic_png};
use pedsynth::planner::ClipScript;

fn main() {
    divan::main();
}

struct Setup {
    script: ClipScript,
    trace: ClipTrace,
    rig: Rig,
    scene: StaticScene,
    frame: u32,
}

fn setup(weather: &str) -> Setup {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let options = LoadOptions {
        overrides: vec![format!("dataset.weathers=[{weather}]")],
        allow_large: false,
    };
    let (_, towns, plan) = pedsynth::commands::plan_spec_file(&path, &options).expect("quickstart plans");
    let script = plan.clips[0].clone();
    let net = &towns[&script.town].network;
    let trace = simulate::simulate(&script, &plan.sim, net);
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
    Setup {
        script,
        trace,
        rig,
        scene,
        frame,
    }
}

#[divan::bench(args = ["clear_noon", "night_rainy"])]
fn render_rgb_frame(bencher: divan::Bencher, weather: &str) {
    let s = setup(weather);
    let light = Lighting::from_weather(&s.script.weather_params);
    let mut renderer = Renderer::new(&s.rig.camera, light, s.script.seed);
    let mut frame = FrameScene::default();
    let t = SceneTime::at(s.frame);
    frame.build(&s.scene, &s.script, &s.trace, t);
    let (pos, yaw) = ego_at(&s.trace, t);
    let pose = s.rig.camera.at(pos, yaw);
    let mut img = CameraImages::default();
    bencher.bench_local(|| {
        renderer.render(
            &s.scene,
            &frame,
            &pose,
            streak_seed(s.script.seed, s.frame, 0),
            &mut img,
        );
    });
}

#[divan::bench]
fn build_frame_scene(bencher: divan::Bencher) {
    let s = setup("clear_noon");
    let mut frame = FrameScene::default();
    bencher.bench_local(|| frame.build(&s.scene, &s.script, &s.trace, SceneTime::at(s.frame)));
}

#[divan::bench]
fn encode_rgb_png(bencher: divan::Bencher) {
    let s = setup("clear_noon");
    let img = observe::render_frame(&s.script, &s.trace, &s.rig, &towns_net(&s), s.frame);
    bencher.bench_local(|| rgb_png(&img).expect("png").len());
}

#[divan::bench]
fn encode_semantic_png(bencher: divan::Bencher) {
    let s = setup("clear_noon");
    let img = observe::render_frame(&s.script, &s.trace, &s.rig, &towns_net(&s), s.frame);
    bencher.bench_local(|| semantic_png(&img).expect("png").len());
}

/// The clip's town, built again (the setup keeps only its scene).
fn towns_net(s: &Setup) -> pedsynth::world::RoadNetwork {
    pedsynth::world::RoadNetwork::builtin(&s.script.town).expect("built-in town")
}
