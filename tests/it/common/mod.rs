//! Helpers shared by the integration tests: where the real CARLA maps are (one setting), and the checks shared
//! by the CARLA-map and built-in-town tests (lane classification of sampled points, routes, crossing vectors).
//!
//! - `PEDSYNTH_CARLA_MAPS`: the directory of CARLA's `Town01.xodr` ... (default `../shared/maps/carla` beside
//!   the repository). The tests that read them are `#[ignore]`d (\"reads CARLA's maps\"); a run that includes them
//!   (`cargo test -- --include-ignored`, as CI does) fails where a map is missing.
//!
//! Also: planning a spec with `--set` overrides (`plan_spec`), `generate` through the library, every file of a dataset (`all_files`), and the overrides that turn the
//! sensors off (`NO_SENSORS`, `NO_CAMERAS`), and the --jobs 1 / --jobs 2 comparison.
#![allow(dead_code)]

use glam::DVec2;
use pedsynth::world::{LaneType, RoadNetwork};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Directory holding the real CARLA maps: `$PEDSYNTH_CARLA_MAPS`, or `../shared/maps/carla` beside the
/// repository (never copied into it).
pub fn carla_dir() -> std::path::PathBuf {
    match std::env::var_os("PEDSYNTH_CARLA_MAPS") {
        Some(dir) if !dir.is_empty() => std::path::PathBuf::from(dir),
        _ => std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/maps/carla")),
    }
}

/// The path of CARLA map `town` (e.g. `Town01`). Panics when it is absent: the tests that call this are
/// `#[ignore]`d for that reason, and a run that includes them must have the maps.
pub fn carla_map(town: &str) -> std::path::PathBuf {
    let path = carla_dir().join(format!("{town}.xodr"));
    assert!(
        path.is_file(),
        "the CARLA map {} is absent (set PEDSYNTH_CARLA_MAPS to the directory of CARLA's Town*.xodr)",
        path.display()
    );
    path
}

/// A point inside lane piece `pi`: `along` ∈ [0,1] between its stations, `across` ∈ [0,1] inner→outer.
pub fn point_in_piece(net: &RoadNetwork, pi: usize, along: f64, across: f64) -> DVec2 {
    let c = net.pieces[pi].corners;
    let inner = c[0].lerp(c[1], along);
    let outer = c[3].lerp(c[2], along);
    inner.lerp(outer, across)
}

/// Samples up to `n` points on lanes of type `t` (pieces at least 0.6 m wide, the middle 60 % of the width)
/// and returns (matching, total).
pub fn classification(net: &RoadNetwork, t: LaneType, n: usize, seed: u64) -> (usize, usize) {
    let pieces: Vec<usize> = (0..net.pieces.len())
        .filter(|&i| {
            let p = &net.pieces[i];
            net.lanes[p.lane as usize].lane_type == t && p.width_m[0].min(p.width_m[1]) > 0.6
        })
        .collect();
    assert!(!pieces.is_empty(), "{}: no {t:?} pieces", net.name);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut ok = 0;
    let mut misses = Vec::new();
    for _ in 0..n {
        let pi = pieces[rng.random_range(0..pieces.len())];
        let p = point_in_piece(net, pi, rng.random_range(0.05..0.95), rng.random_range(0.2..0.8));
        let z = net.pieces[pi].z_m as f64;
        match net.lane_at_3d(p.extend(z)) {
            Some(h) if h.lane_type == t => ok += 1,
            other => misses.push((p, other.map(|h| h.lane_type))),
        }
    }
    if !misses.is_empty() {
        eprintln!(
            "{}: {t:?} misclassified {} of {n}, e.g. {:?}",
            net.name,
            misses.len(),
            &misses[..misses.len().min(5)]
        );
    }
    (ok, n)
}

pub fn assert_classification(net: &RoadNetwork) {
    for t in [LaneType::Driving, LaneType::Sidewalk] {
        let (ok, n) = classification(net, t, 4000, 7);
        let rate = ok as f64 / n as f64;
        assert!(
            rate >= 0.995,
            "{}: {t:?} classification rate {rate:.4} < 0.995",
            net.name
        );
    }
}

pub fn assert_route(net: &RoadNetwork, min_m: f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for k in 0..5 {
        let r = net
            .random_route(&mut rng, min_m)
            .unwrap_or_else(|| panic!("{}: no route of {min_m} m (try {k})", net.name));
        assert!(r.length_m() >= min_m);
        let mut on_driving = 0;
        for w in r.points.windows(2) {
            let gap = (w[1].pos - w[0].pos).length();
            assert!(gap < 3.0, "{}: route jumps {gap:.2} m at s={:.1}", net.name, w[0].s_m);
            assert!(w[1].s_m > w[0].s_m);
        }
        for p in &r.points {
            match net.lane_at_3d(p.pos.extend(p.z_m)) {
                Some(h) if h.lane_type == LaneType::Driving => on_driving += 1,
                other => eprintln!(
                    "{}: route point {:?} (lane {}) classifies as {:?}",
                    net.name,
                    p.pos,
                    p.lane,
                    other.map(|h| (h.lane_type, h.lane))
                ),
            }
        }
        let frac = on_driving as f64 / r.points.len() as f64;
        assert!(
            frac >= 0.99,
            "{}: only {frac:.3} of route points on driving lanes",
            net.name
        );
        let mid = r.pose_at(0.5 * r.length_m());
        assert!(mid.pos.is_finite());
    }
}

/// Crossing vectors from sidewalk points outside junctions: where one is found, it starts on the sidewalk,
/// ends on another sidewalk lane, crosses a plausible carriageway and is perpendicular to the sidewalk. At
/// least `min_found` of the samples must yield a crossing.
pub fn assert_crossings(net: &RoadNetwork, min_found: f64) {
    let pieces: Vec<usize> = (0..net.pieces.len())
        .filter(|&i| {
            let p = &net.pieces[i];
            let l = &net.lanes[p.lane as usize];
            l.lane_type == LaneType::Sidewalk && !l.in_junction && p.width_m[0].min(p.width_m[1]) > 1.0
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let n = 600;
    let mut found = 0;
    for _ in 0..n {
        let pi = pieces[rng.random_range(0..pieces.len())];
        let p = point_in_piece(net, pi, 0.5, 0.5);
        let p3 = p.extend(net.pieces[pi].z_m as f64);
        let Some(start) = net.lane_at_3d(p3) else {
            continue;
        };
        if start.lane_type != LaneType::Sidewalk {
            continue;
        }
        let Some(c) = net.crossing_at_3d(p3) else {
            continue;
        };
        found += 1;
        let end = net
            .lane_at_3d(c.end.extend(p3.z))
            .unwrap_or_else(|| panic!("{}: crossing end {:?} off every lane", net.name, c.end));
        assert_eq!(
            end.lane_type,
            LaneType::Sidewalk,
            "{}: crossing from {p:?} ends on {:?}",
            net.name,
            end.lane_type
        );
        assert_ne!(end.lane, start.lane);
        assert!(
            (2.0..60.0).contains(&c.carriageway_width_m),
            "{}: carriageway {:.2} m at {p:?}",
            net.name,
            c.carriageway_width_m
        );
        let h = start.heading_rad;
        let along = DVec2::new(h.cos(), h.sin());
        assert!(
            along.dot(c.direction).abs() < 0.2,
            "{}: crossing not perpendicular at {p:?}",
            net.name
        );
    }
    let frac = found as f64 / n as f64;
    eprintln!("{}: crossings found for {found}/{n} sidewalk points", net.name);
    assert!(
        frac >= min_found,
        "{}: crossings found for only {frac:.2} of sidewalk points",
        net.name
    );
}

pub fn assert_queries(net: &RoadNetwork) {
    assert_classification(net);
    assert_route(net, 500.0);
    assert_crossings(net, 0.5);
}

/// `--set` overrides that turn every camera stream off.
pub const NO_CAMERAS: [&str; 5] = [
    "sensors.rgb.enabled=false",
    "sensors.depth.enabled=false",
    "sensors.semantic.enabled=false",
    "sensors.instance.enabled=false",
    "sensors.dvs.enabled=false",
];

/// `--set` overrides that turn every sensor off: for tests of the tables and the simulation, which would
/// otherwise render thousands of images and sweeps (the sensor tests render their own, small ones).
pub const NO_SENSORS: [&str; 6] = [
    NO_CAMERAS[0],
    NO_CAMERAS[1],
    NO_CAMERAS[2],
    NO_CAMERAS[3],
    NO_CAMERAS[4],
    "sensors.lidar.enabled=false",
];

/// Generates `input` with `overrides` into `dir/one` with `--jobs 1` and `dir/two` with `--jobs 2`, asserts
/// that both wrote the same files, and returns them.
pub fn generate_with_jobs_1_and_2(
    input: &std::path::Path,
    overrides: &[&str],
    dir: &std::path::Path,
) -> std::collections::BTreeMap<String, Vec<u8>> {
    let (one, two) = (dir.join("one"), dir.join("two"));
    for (out, jobs) in [(&one, 1), (&two, 2)] {
        let (code, _, stderr) = generate(input, overrides, out, Some(jobs));
        assert_eq!(code, 0, "{stderr}");
    }
    let files = all_files(&one);
    assert!(files == all_files(&two), "--jobs 1 and --jobs 2 wrote different files");
    files
}

/// Runs `pedsynth generate` through the library with `--set` overrides (none for a plan file); returns the
/// exit code, stdout and stderr.
pub fn generate(
    input: &std::path::Path,
    overrides: &[&str],
    out: &std::path::Path,
    jobs: Option<usize>,
) -> (i32, String, String) {
    let args = pedsynth::cli::GenerateArgs {
        out: out.to_path_buf(),
        jobs,
        only: None,
        quiet: true,
        progress_json: false,
        shard: None,
    };
    let options = pedsynth::spec::LoadOptions {
        overrides: overrides.iter().map(|s| s.to_string()).collect(),
        allow_large: false,
        profile: None,
    };
    let (mut o, mut e) = (Vec::new(), Vec::new());
    let code = pedsynth::cli::finish(pedsynth::cli::generate(input, &options, &args, &mut o), &mut e);
    (
        code,
        String::from_utf8_lossy(&o).into_owned(),
        String::from_utf8_lossy(&e).into_owned(),
    )
}

/// Every file under `dir`, by `/`-separated path relative to it.
pub fn all_files(dir: &std::path::Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    fn walk(root: &std::path::Path, dir: &std::path::Path, out: &mut std::collections::BTreeMap<String, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).expect("read dir") {
            let path = entry.expect("dir entry").path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                let rel = path
                    .strip_prefix(root)
                    .expect("under root")
                    .to_string_lossy()
                    .replace('\\', "/");
                out.insert(rel, std::fs::read(&path).expect("read file"));
            }
        }
    }
    let mut out = std::collections::BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// A scratch directory under the system's temporary directory, named after the test and the process, removed
/// when dropped.
pub struct Scratch(std::path::PathBuf);

impl Scratch {
    pub fn new(tag: &str) -> Scratch {
        let root = std::env::temp_dir().join(format!("pedsynth-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).expect("scratch directory");
        Scratch(root)
    }

    pub fn path(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Leaves a clip of the dataset at `out` as a run killed while writing it would: its completion marker
/// (`tables/clips/<clip>.parquet`) and the files `remove` (paths relative to `out`) gone, and a half-written
/// temporary file at `leftover`. Then `resume` runs and the directory must equal `want` byte for byte.
pub fn assert_resume_rewrites_clip(
    out: &std::path::Path,
    clip_id: &str,
    remove: &[String],
    leftover: &str,
    want: &std::collections::BTreeMap<String, Vec<u8>>,
    resume: impl FnOnce(),
) {
    std::fs::remove_file(out.join(format!("tables/clips/{clip_id}.parquet"))).expect("remove completion marker");
    for path in remove {
        std::fs::remove_file(out.join(path)).expect("remove file");
    }
    std::fs::write(out.join(leftover), b"half").expect("write leftover");
    resume();
    assert!(
        all_files(out) == *want,
        "a resumed run differs from an uninterrupted one"
    );
}

/// Plans `spec` (a path relative to the repository) with the `--set` `overrides`: its towns and its plan.
/// Panics with the diagnostic when the spec does not plan.
pub fn plan_spec(
    spec: &str,
    overrides: &[&str],
) -> (
    std::collections::BTreeMap<String, pedsynth::plan::TownContext>,
    pedsynth::plan::Plan,
) {
    let options = pedsynth::spec::LoadOptions {
        overrides: overrides.iter().map(|s| (*s).to_owned()).collect(),
        allow_large: false,
        profile: None,
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(spec);
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(&path, &options).unwrap_or_else(|e| panic!("{e}"));
    (towns, plan)
}

/// Runs the pedsynth binary; returns the exit code, stdout and stderr.
pub fn pedsynth(args: &[&std::ffi::OsStr]) -> (Option<i32>, String, String) {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .args(args)
        .output()
        .expect("run pedsynth");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}
