//! Renders one frame of each clip of a spec (the frame with the most annotated pedestrians, or `--frame F`)
//! and writes its RGB and semantic images as PNG, without generating the dataset: for looking at the camera
//! in every weather, and for the README's pictures. Prints each image's mean luminance.
//!
//! Run: `cargo run --release --example render_frame -- tests/data/specs/weathers.yaml --out DIR [--frame F]
//! [--clip ID] [--set KEY=VALUE]...` (`--clip`: only that clip).

use std::path::{Path, PathBuf};

use pedsynth::dataset::write::sensors::{rgb_png, semantic_png};
use pedsynth::sensors;
use pedsynth::sim;
use pedsynth::sim::rig::Rig;
use pedsynth::spec::LoadOptions;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| args.windows(2).find(|w| w[0] == flag).map(|w| w[1].clone());
    let overrides: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let Some(spec) = args.first() else {
        eprintln!("usage: render_frame SPEC --out DIR [--frame F] [--set KEY=VALUE]...");
        std::process::exit(2);
    };
    let out = PathBuf::from(value("--out").unwrap_or_else(|| "render".into()));
    let fixed: Option<u32> = value("--frame").and_then(|f| f.parse().ok());
    let only = value("--clip");
    let options = LoadOptions {
        overrides,
        allow_large: false,
        profile: None,
    };
    let (_, towns, plan) = match pedsynth::dataset::inputs::plan_spec_file(Path::new(spec), &options) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    std::fs::create_dir_all(&out).expect("output directory");
    for clip in plan
        .clips
        .iter()
        .filter(|c| only.as_ref().is_none_or(|id| *id == c.clip_id))
    {
        let net = &towns[&clip.town].network;
        let rig = Rig::for_clip(&plan.spec.sensors, clip.seed);
        let trace = sim::simulate(clip, &plan.sim, net);
        let ann = sensors::observe(clip, &trace, &plan.spec, &rig, net).annotations;
        let frame = fixed.unwrap_or_else(|| {
            let mut counts = vec![0u32; trace.frame_count as usize];
            for r in &ann.rows {
                counts[r.frame as usize] += 1;
            }
            counts
                .iter()
                .enumerate()
                .max_by_key(|(f, c)| (**c, std::cmp::Reverse(*f)))
                .map_or(0, |(f, _)| f as u32)
        });
        let start = std::time::Instant::now();
        let img = sensors::render_frame(clip, &trace, &rig, net, frame);
        let took = start.elapsed();
        let (rgb, sem) = (rgb_png(&img).expect("png"), semantic_png(&img).expect("png"));
        let name = format!("{}-{frame:06}", clip.clip_id);
        std::fs::write(out.join(format!("{name}.rgb.png")), rgb).expect("write");
        std::fs::write(out.join(format!("{name}.semantic.png")), sem).expect("write");
        let mean: f64 = img
            .rgb
            .chunks_exact(3)
            .map(|p| f64::from(pedsynth::sensors::camera::luminance(p)))
            .sum::<f64>()
            / (img.width * img.height) as f64;
        println!(
            "{name}: mean luminance {mean:.1}, rendered in {:.1} ms (with the scene)",
            took.as_secs_f64() * 1e3
        );
    }
}
