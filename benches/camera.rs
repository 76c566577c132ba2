//! Benchmark of the camera: one 1280 × 720 frame of a quickstart clip (its busiest annotated frame), on one
//! core. `render_rgb_frame` is the renderer alone (visibility buffer, shadow map, shading, labels, rain: no
//! encoding), `render_rgb_clip_frames` the same over every 16th frame of the clip (shown as frames/s);
//! `encode_*` time the PNG encoders of one frame; `build_frame_scene` the per-frame scene. The target
//! is ≥ 60 rendered frames per second on one core.
//! Run: `cargo bench --bench camera`.

use pedsynth::dataset::write::sensors::{rgb_png, semantic_png};
use pedsynth::sensors;
use pedsynth::sensors::camera::light::Lighting;
use pedsynth::sensors::camera::{CameraImages, Renderer, streak_seed};
use pedsynth::sensors::scene::{FrameScene, SceneTime};

mod common;

fn main() {
    divan::main();
}

type Setup = common::BusyClip;

fn setup(weather: &str) -> Setup {
    common::busy_quickstart_clip(&[format!("dataset.weathers=[{weather}]")])
}

#[divan::bench(args = ["clear_noon", "night_rainy"])]
fn render_rgb_frame(bencher: divan::Bencher, weather: &str) {
    let s = setup(weather);
    let mut r = s.busy_render();
    // One core: the renderer resolves bands of rows on the current rayon pool.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    bencher.bench_local(|| pool.install(|| s.render_busy(&mut r)));
}

/// Every 16th frame of the clip (not only its busiest), rendered one after another on one core: the mean over a
/// clip's frames, shown as frames per second.
#[divan::bench(args = ["clear_noon", "night_rainy"], sample_count = 10)]
fn render_rgb_clip_frames(bencher: divan::Bencher, weather: &str) {
    let s = setup(weather);
    let light = Lighting::from_weather(&s.script.weather_params);
    let mut renderer = Renderer::new(&s.rig.camera, light, s.script.seed);
    let frames: Vec<_> = (0..s.trace.frame_count)
        .step_by(16)
        .map(|f| {
            let (frame, pose) = s.camera_frame(f);
            (f, frame, pose)
        })
        .collect();
    let mut img = CameraImages::default();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    bencher
        .counter(divan::counter::ItemsCount::new(frames.len()))
        .bench_local(|| {
            pool.install(|| {
                for (f, frame, pose) in &frames {
                    renderer.render(&s.scene, frame, pose, streak_seed(s.script.seed, *f, 0), &mut img);
                }
            })
        });
}

/// The sensor noise of the `jaad` profile (`shot` 0.012, `read` 0.0005) added to the busiest night-rain frame,
/// on one core: what a noisy camera costs per frame.
#[divan::bench]
fn add_noise(bencher: divan::Bencher) {
    let s = common::busy_quickstart_clip(&[
        "dataset.weathers=[night_rainy]".to_owned(),
        "sensors.rgb.noise.shot=0.012".to_owned(),
        "sensors.rgb.noise.read=0.0005".to_owned(),
    ]);
    let mut r = s.busy_render();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    pool.install(|| s.render_busy(&mut r));
    let clean = r.img.clone();
    bencher.bench_local(|| {
        r.img.rgb.copy_from_slice(&clean.rgb);
        pool.install(|| {
            r.renderer
                .add_noise(&mut r.img, sensors::camera::noise_seed(s.script.seed, s.frame))
        });
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
    let img = sensors::render_frame(&s.script, &s.trace, &s.rig, &s.net, s.frame);
    bencher.bench_local(|| rgb_png(&img).expect("png").len());
}

#[divan::bench]
fn encode_semantic_png(bencher: divan::Bencher) {
    let s = setup("clear_noon");
    let img = sensors::render_frame(&s.script, &s.trace, &s.rig, &s.net, s.frame);
    bencher.bench_local(|| semantic_png(&img).expect("png").len());
}
