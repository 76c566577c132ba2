//! Renders the camera benchmark's frame (the busiest annotated frame of the first quickstart clip) N times on
//! one core in one weather and prints the mean time per frame: a target for `perf record`, which the divan
//! benchmark is not (it runs every weather). Run: `cargo build --release --example profile_frame &&
//! perf record target/release/examples/profile_frame clear_noon 400 && perf report`. A third argument renders
//! that frame instead of the busiest (to compare builds whose boxes, and so whose busiest frame, differ).

#[path = "../benches/common/mod.rs"]
mod common;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let weather = args.get(1).cloned().unwrap_or_else(|| "clear_noon".into());
    let frames: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200).max(1);
    let mut s = common::busy_quickstart_clip(&[format!("dataset.weathers=[{weather}]")]);
    if let Some(frame) = args.get(3).and_then(|s| s.parse().ok()) {
        s.frame = frame;
    }
    let mut r = s.busy_render();
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() else {
        eprintln!("no thread pool");
        std::process::exit(1);
    };
    let start = std::time::Instant::now();
    pool.install(|| {
        for _ in 0..frames {
            s.render_busy(&mut r);
        }
    });
    let per_frame_ms = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
    println!(
        "{weather}: {per_frame_ms:.3} ms per frame (frame {}, {frames} frames, one core)",
        s.frame
    );
}
