//! `pedsynth export` (issue 17), the parts Python does not check (tests/interop_pie.py and
//! tests/interop_jaad.py run PIE's, JAAD's and PedestrianActionBenchmark's own loaders on the exports, in CI):
//!
//! - the same dataset exports to byte-identical files, and a re-run over an export keeps it as it is;
//! - a dataset without cameras exports its annotations and says that images are absent;
//! - an unfinished dataset, a table changed after `generate` and a directory that is no dataset are refused
//!   with exit code 2 and a message naming the problem, never a panic;
//! - the poses' joints: OpenPose-18 order, neck at mid-shoulder, normalised within the box, hidden joints 0;
//! - the seed's CSV layout has one row per annotated pedestrian-frame, none duplicated (the seed wrote each
//!   twice).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use pedsynth::exec::export::dataset::AnnotatedFrame;
use pedsynth::exec::export::pab::pose36;

fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

fn pedsynth(args: &[&std::ffi::OsStr]) -> (Option<i32>, String, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .args(args)
        .output()
        .expect("runs");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

fn export(format: &str, dataset: &Path, out: &Path) -> (Option<i32>, String, String) {
    pedsynth(&[
        "export".as_ref(),
        format.as_ref(),
        dataset.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ])
}

#[test]
fn exports_are_reproducible_and_refuse_unfinished_or_altered_datasets() {
    let tmp = common::Scratch::new("export");
    let ds = tmp.path().join("ds");
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &common::NO_SENSORS, &ds, None);
    assert_eq!(code, 0, "{stderr}");

    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    for out in [&a, &b] {
        for (format, layout) in [
            ("pie", "pie"),
            ("pab-poses", "pie"),
            ("jaad", "jaad"),
            ("pab-poses-jaad", "jaad"),
            ("seed-csv", "seed"),
        ] {
            let (code, stdout, stderr) = export(format, &ds, &out.join(layout));
            assert_eq!(code, Some(0), "{stderr}");
            if ["pie", "jaad", "seed-csv"].contains(&format) {
                assert!(
                    stdout.contains("images absent: the dataset has no RGB stream"),
                    "{stdout}"
                );
            }
        }
    }
    let files = common::all_files(&a);
    for file in [
        "pie/annotations/set01/video_0001_annt.xml",
        "pie/poses/pose_set03.pkl",
        "pie/pedsynth_export.json",
        "jaad/annotations/video_0001.xml",
        "jaad/poses/pose_set01.pkl",
        "jaad/split_ids/default/val.txt",
    ] {
        assert!(files.contains_key(file), "{file}: {:?}", files.keys());
    }
    assert!(files == common::all_files(&b), "two exports of one dataset differ");
    // The seed's CSV: one row per annotated pedestrian-frame, none twice, every row as wide as the header.
    let view = pedsynth::exec::export::dataset::Dataset::open(&ds).expect("opens");
    let annotated: usize = view
        .clips
        .iter()
        .map(|info| view.load(info).expect("loads"))
        .flat_map(|c| c.pedestrians.into_values())
        .map(|p| p.frames.len())
        .sum();
    let labels = String::from_utf8(files["seed/labels.csv"].clone()).expect("utf-8");
    let mut lines = labels.lines();
    let width = lines.next().expect("header").split(',').count();
    assert_eq!(width, 12 + 3 * 17);
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), annotated, "one row per annotated pedestrian-frame");
    let keys: std::collections::BTreeSet<Vec<&str>> = rows.iter().map(|r| r.split(',').take(3).collect()).collect();
    assert_eq!(
        keys.len(),
        rows.len(),
        "no duplicate (video_id, frame_id, pedestrian_id)"
    );
    assert!(rows.iter().all(|r| r.split(',').count() == width));
    // Re-running over an export keeps it byte for byte.
    let (code, _, stderr) = export("pie", &ds, &a.join("pie"));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(files == common::all_files(&a));

    // A table changed after generate.
    let table = ds.join("tables/annotations/town01_like-clear_noon-0000.parquet");
    let original = std::fs::read(&table).expect("read");
    let mut changed = original.clone();
    let mid = changed.len() / 2;
    changed[mid] ^= 1;
    std::fs::write(&table, &changed).expect("write");
    let (code, _, stderr) = export("pie", &ds, &tmp.path().join("c"));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("blake3 differs from the manifest"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    std::fs::write(&table, &original).expect("restore");

    // A clip not generated yet.
    let manifest = ds.join("manifest.json");
    let text = std::fs::read_to_string(&manifest).expect("manifest");
    std::fs::write(
        &manifest,
        text.replacen("\"status\": \"done\"", "\"status\": \"pending\"", 1),
    )
    .expect("write");
    let (code, _, stderr) = export("pab-poses", &ds, &tmp.path().join("d"));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not generated yet"), "{stderr}");

    // Not a dataset.
    let (code, _, stderr) = export("pie", tmp.path(), &tmp.path().join("e"));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("is") && stderr.contains("a pedsynth dataset"),
        "{stderr}"
    );
}

#[test]
fn poses_are_openpose18_normalised_in_the_box_with_hidden_joints_zero() {
    // COCO-17: joint k at (100 + 10 k, 200 + 5 k), visible (2), except the left wrist (9) hidden (1).
    let mut keypoints = Vec::new();
    for k in 0..17 {
        keypoints.extend([
            100.0 + 10.0 * k as f32,
            200.0 + 5.0 * k as f32,
            if k == 9 { 1.0 } else { 2.0 },
        ]);
    }
    let frame = AnnotatedFrame {
        frame: 0,
        bbox_px: [100.0, 200.0, 300.0, 300.0],
        crossing: false,
        state: String::new(),
        occlusion: 0.0,
        speed_mps: 0.0,
        x_m: 0.0,
        y_m: 0.0,
        yaw_rad: 0.0,
        distance_to_ego_m: 0.0,
        box3d_m: [0.0; 6],
        keypoints,
    };
    let p = pose36(&frame);
    assert_eq!(p.len(), 36);
    let at = |k: usize| ((10.0 * k as f64) / 200.0, (5.0 * k as f64) / 100.0);
    assert_eq!((p[0], p[1]), at(0), "nose");
    let (l, r) = (at(5), at(6));
    assert!(
        (p[2] - (l.0 + r.0) / 2.0).abs() < 1e-9 && (p[3] - (l.1 + r.1) / 2.0).abs() < 1e-9,
        "neck"
    );
    assert_eq!((p[4], p[5]), at(6), "right shoulder third");
    assert_eq!((p[14], p[15]), (0.0, 0.0), "the hidden left wrist is 0");
    assert_eq!((p[28], p[29]), at(1), "left eye 15th");
    assert_eq!((p[34], p[35]), at(4), "right ear last");
}
