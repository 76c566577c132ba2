//! End-to-end tests of the Parquet dataset: `pedsynth generate` writes small datasets into temporary
//! directories, the tests read the tables back with `parquet`/`arrow-array` and check the dataset's
//! invariants — keys and joins, the crossing label C and its smoothing, TTE, sequence labels, keypoints,
//! boxes against an independent dense projection of the re-simulated body, clip-level counts — and that the
//! files are byte-identical across job counts, interruption and resumption, and spec vs plan file; and that
//! `generate` refuses directories it must not write into.

use crate::common;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use arrow_array::cast::AsArray;
use arrow_array::types::{Float32Type, Float64Type, Int32Type, Int64Type, UInt32Type, UInt64Type};
use arrow_array::{Array, RecordBatch};
use glam::{DVec2, DVec3};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

use pedsynth::cli::{self, PlanArgs};
use pedsynth::sensors::body;
use pedsynth::sim::rig::Camera;
use pedsynth::spec::LoadOptions;

const TABLES: [&str; 7] = [
    "clips",
    "frames",
    "pedestrians",
    "annotations",
    "tracks",
    "vehicles",
    "events",
];
const CROSSING_STATES: [&str; 5] = [
    "CROSSING_ROAD",
    "SUDDEN_CROSSING",
    "JAYWALKING",
    "RUNNING_ACROSS",
    "PAUSING_MID_CROSS",
];

/// A temporary directory under the system's temp dir, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("pedsynth-dataset-{}-{tag}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).expect("create temp dir");
        TempDir(path)
    }

    fn join(&self, p: &str) -> PathBuf {
        self.0.join(p)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

/// Load options with `overrides`, cameras off (tests/camera.rs tests the sensor files).
fn options(overrides: &[&str]) -> LoadOptions {
    LoadOptions {
        overrides: common::NO_SENSORS
            .iter()
            .chain(overrides)
            .map(|s| s.to_string())
            .collect(),
        allow_large: false,
        profile: None,
    }
}

/// Runs `pedsynth generate` with the cameras off (a plan file takes no overrides: plan it with them off).
fn generate(input: &Path, overrides: &[&str], out: &Path, jobs: usize) -> (i32, String, String) {
    let is_plan = input.extension().is_some_and(|x| x == "json");
    let all: Vec<&str> = if is_plan {
        Vec::new()
    } else {
        common::NO_SENSORS.iter().chain(overrides).copied().collect()
    };
    common::generate(input, &all, out, Some(jobs))
}

fn generate_ok(input: &Path, overrides: &[&str], out: &Path, jobs: usize) -> String {
    let (code, stdout, stderr) = generate(input, overrides, out, jobs);
    assert_eq!(code, 0, "generate {} failed:\n{stdout}\n{stderr}", input.display());
    stdout
}

use common::all_files;

fn assert_same_files(a: &Path, b: &Path, what: &str) {
    let (fa, fb) = (all_files(a), all_files(b));
    let (na, nb): (Vec<&String>, Vec<&String>) = (fa.keys().collect(), fb.keys().collect());
    assert_eq!(na, nb, "{what}: different sets of files");
    for (name, bytes) in &fa {
        assert!(bytes == &fb[name], "{what}: {name} differs");
    }
}

// ---------------------------------------------------------------------------------------------------------
// Reading the tables back.

/// The record batches of one table (all clips, files in name order); checks each file's key-value metadata.
fn read_table(dir: &Path, table: &str, spec_hash: &str) -> Vec<RecordBatch> {
    let tdir = dir.join("tables").join(table);
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&tdir)
        .unwrap_or_else(|e| panic!("{}: {e}", tdir.display()))
        .map(|e| e.expect("dir entry").path())
        .collect();
    paths.sort();
    let mut out = Vec::new();
    for path in paths {
        assert_eq!(
            path.extension().and_then(|x| x.to_str()),
            Some("parquet"),
            "only Parquet files in {}: {}",
            tdir.display(),
            path.display()
        );
        let clip_id = path.file_stem().and_then(|s| s.to_str()).expect("file stem").to_owned();
        let builder = ParquetRecordBatchReaderBuilder::try_new(File::open(&path).expect("open")).expect("parquet");
        let kv: HashMap<String, String> = builder
            .metadata()
            .file_metadata()
            .key_value_metadata()
            .expect("key-value metadata")
            .iter()
            .map(|kv| (kv.key.clone(), kv.value.clone().unwrap_or_default()))
            .collect();
        assert_eq!(kv["pedsynth.table"], table, "{}", path.display());
        assert_eq!(kv["pedsynth.clip_id"], clip_id, "{}", path.display());
        assert_eq!(kv["pedsynth.spec_hash"], spec_hash, "{}", path.display());
        assert_eq!(kv["pedsynth.schema_version"], "12", "{}", path.display());
        assert_eq!(kv["pedsynth.version"], env!("CARGO_PKG_VERSION"), "{}", path.display());
        for batch in builder.build().expect("reader") {
            let batch = batch.expect("batch");
            let ids = batch.column_by_name("clip_id").expect("clip_id").as_string::<i32>();
            assert!(
                ids.iter().all(|id| id == Some(clip_id.as_str())),
                "{}: clip_id column matches the file name",
                path.display()
            );
            out.push(batch);
        }
    }
    out
}

fn column<'a>(b: &'a RecordBatch, name: &str) -> &'a dyn Array {
    b.column_by_name(name)
        .unwrap_or_else(|| panic!("no column {name}"))
        .as_ref()
}

fn strs(b: &RecordBatch, name: &str) -> Vec<Option<String>> {
    column(b, name)
        .as_string::<i32>()
        .iter()
        .map(|s| s.map(str::to_owned))
        .collect()
}

fn u32s(b: &RecordBatch, name: &str) -> Vec<Option<u32>> {
    column(b, name).as_primitive::<UInt32Type>().iter().collect()
}

fn u64s(b: &RecordBatch, name: &str) -> Vec<u64> {
    column(b, name)
        .as_primitive::<UInt64Type>()
        .iter()
        .map(|v| v.expect("non-null"))
        .collect()
}

fn f32s(b: &RecordBatch, name: &str) -> Vec<f32> {
    column(b, name)
        .as_primitive::<Float32Type>()
        .iter()
        .map(|v| v.expect("non-null"))
        .collect()
}

fn f64s(b: &RecordBatch, name: &str) -> Vec<f64> {
    column(b, name)
        .as_primitive::<Float64Type>()
        .iter()
        .map(|v| v.expect("non-null"))
        .collect()
}

fn bools(b: &RecordBatch, name: &str) -> Vec<bool> {
    column(b, name)
        .as_boolean()
        .iter()
        .map(|v| v.expect("non-null"))
        .collect()
}

#[derive(Debug)]
struct ClipRow {
    clip: String,
    split: String,
    frame_count: u32,
    pedestrians: u32,
    crossers: u32,
    vehicles: u32,
    contacts: u32,
    annotated_samples: u64,
    rejected: u64,
}

#[derive(Debug, Clone)]
struct PedRow {
    crosser: bool,
    /// `role`, `crosser_source`, `behaviour`.
    roles: [String; 3],
    first_crossing_frame: Option<u32>,
    annotated_frames: u32,
    height_m: f32,
}

#[derive(Debug, Clone)]
struct AnnRow {
    clip: String,
    frame: u32,
    ped: u32,
    bbox: [f32; 4],
    crossing: bool,
    state: String,
    tte: Option<i32>,
    occlusion: f32,
    keypoints: Vec<f32>,
    lane: Option<String>,
}

/// A `tracks` row: (x, y, state, C, lane type, annotated).
type TrackRow = (f32, f32, String, bool, Option<String>, bool);

#[derive(Debug, Clone, Copy)]
struct FrameRow {
    timestamp_ns: i64,
    ego: [f64; 4],
}

struct Dataset {
    clips: Vec<ClipRow>,
    frames: BTreeMap<(String, u32), FrameRow>,
    pedestrians: BTreeMap<(String, u32), PedRow>,
    annotations: Vec<AnnRow>,
    tracks: BTreeMap<(String, u32, u32), TrackRow>,
    vehicles: BTreeMap<String, BTreeSet<u32>>,
    contacts: BTreeMap<String, u32>,
}

fn read_dataset(dir: &Path) -> Dataset {
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).expect("manifest")).expect("json");
    let spec_hash = manifest["spec_hash"].as_str().expect("spec_hash").to_owned();
    let mut d = Dataset {
        clips: Vec::new(),
        frames: BTreeMap::new(),
        pedestrians: BTreeMap::new(),
        annotations: Vec::new(),
        tracks: BTreeMap::new(),
        vehicles: BTreeMap::new(),
        contacts: BTreeMap::new(),
    };
    for b in read_table(dir, "clips", &spec_hash) {
        let ids = strs(&b, "clip_id");
        let split = strs(&b, "split");
        let (fc, peds, cr, veh, con) = (
            u32s(&b, "frame_count"),
            u32s(&b, "pedestrians"),
            u32s(&b, "crossers"),
            u32s(&b, "vehicles"),
            u32s(&b, "contacts"),
        );
        let samples = u64s(&b, "annotated_samples");
        let rejected: Vec<Vec<u64>> = ["too_far", "behind", "too_small", "outside_image", "occluded"]
            .iter()
            .map(|r| u64s(&b, &format!("rejected_{r}")))
            .collect();
        for i in 0..b.num_rows() {
            d.clips.push(ClipRow {
                clip: ids[i].clone().expect("clip_id"),
                split: split[i].clone().expect("split"),
                frame_count: fc[i].expect("frame_count"),
                pedestrians: peds[i].expect("pedestrians"),
                crossers: cr[i].expect("crossers"),
                vehicles: veh[i].expect("vehicles"),
                contacts: con[i].expect("contacts"),
                annotated_samples: samples[i],
                rejected: rejected.iter().map(|r| r[i]).sum(),
            });
        }
    }
    for b in read_table(dir, "frames", &spec_hash) {
        let (ids, frame) = (strs(&b, "clip_id"), u32s(&b, "frame"));
        let ts = column(&b, "timestamp_ns").as_primitive::<Int64Type>();
        let (x, y, z, yaw) = (
            f64s(&b, "ego_x_m"),
            f64s(&b, "ego_y_m"),
            f64s(&b, "ego_z_m"),
            f64s(&b, "ego_yaw_rad"),
        );
        for i in 0..b.num_rows() {
            let key = (ids[i].clone().expect("id"), frame[i].expect("frame"));
            let row = FrameRow {
                timestamp_ns: ts.value(i),
                ego: [x[i], y[i], z[i], yaw[i]],
            };
            assert!(d.frames.insert(key.clone(), row).is_none(), "duplicate frame {key:?}");
        }
    }
    for b in read_table(dir, "pedestrians", &spec_hash) {
        let (ids, ped) = (strs(&b, "clip_id"), u32s(&b, "pedestrian"));
        let (crosser, fcf, annotated, height) = (
            bools(&b, "crosser"),
            u32s(&b, "first_crossing_frame"),
            u32s(&b, "annotated_frames"),
            f32s(&b, "height_m"),
        );
        let (role, source, behaviour) = (strs(&b, "role"), strs(&b, "crosser_source"), strs(&b, "behaviour"));
        for i in 0..b.num_rows() {
            let key = (ids[i].clone().expect("id"), ped[i].expect("pedestrian"));
            let text = |c: &[Option<String>]| c[i].clone().expect("string");
            let row = PedRow {
                crosser: crosser[i],
                roles: [text(&role), text(&source), text(&behaviour)],
                first_crossing_frame: fcf[i],
                annotated_frames: annotated[i].expect("annotated_frames"),
                height_m: height[i],
            };
            assert!(
                d.pedestrians.insert(key.clone(), row).is_none(),
                "duplicate pedestrian {key:?}"
            );
        }
    }
    for b in read_table(dir, "annotations", &spec_hash) {
        let (ids, frame, ped) = (strs(&b, "clip_id"), u32s(&b, "frame"), u32s(&b, "pedestrian"));
        let bbox = ["bbox_x_min", "bbox_y_min", "bbox_x_max", "bbox_y_max"].map(|c| f32s(&b, c));
        let (crossing, state, lane) = (bools(&b, "crossing"), strs(&b, "state"), strs(&b, "lane_type"));
        let tte = column(&b, "tte_frames").as_primitive::<Int32Type>();
        let occlusion = f32s(&b, "occlusion");
        let kp = column(&b, "keypoints").as_fixed_size_list();
        assert_eq!(kp.value_length(), 51, "COCO-17: 17 × (x, y, v)");
        for i in 0..b.num_rows() {
            d.annotations.push(AnnRow {
                clip: ids[i].clone().expect("id"),
                frame: frame[i].expect("frame"),
                ped: ped[i].expect("pedestrian"),
                bbox: [bbox[0][i], bbox[1][i], bbox[2][i], bbox[3][i]],
                crossing: crossing[i],
                state: state[i].clone().expect("state"),
                tte: tte.is_valid(i).then(|| tte.value(i)),
                occlusion: occlusion[i],
                keypoints: kp.value(i).as_primitive::<Float32Type>().values().to_vec(),
                lane: lane[i].clone(),
            });
        }
    }
    for b in read_table(dir, "tracks", &spec_hash) {
        let (ids, frame, ped) = (strs(&b, "clip_id"), u32s(&b, "frame"), u32s(&b, "pedestrian"));
        let (x, y, state, crossing) = (
            f32s(&b, "x_m"),
            f32s(&b, "y_m"),
            strs(&b, "state"),
            bools(&b, "crossing"),
        );
        let (lane, annotated) = (strs(&b, "lane_type"), bools(&b, "annotated"));
        for i in 0..b.num_rows() {
            let key = (
                ids[i].clone().expect("id"),
                frame[i].expect("frame"),
                ped[i].expect("pedestrian"),
            );
            let row = (
                x[i],
                y[i],
                state[i].clone().expect("state"),
                crossing[i],
                lane[i].clone(),
                annotated[i],
            );
            assert!(d.tracks.insert(key.clone(), row).is_none(), "tracks: {key:?} twice");
        }
    }
    for b in read_table(dir, "vehicles", &spec_hash) {
        let (ids, veh) = (strs(&b, "clip_id"), u32s(&b, "vehicle"));
        for i in 0..b.num_rows() {
            d.vehicles
                .entry(ids[i].clone().expect("id"))
                .or_default()
                .insert(veh[i].expect("vehicle"));
        }
    }
    for b in read_table(dir, "events", &spec_hash) {
        let (ids, kind) = (strs(&b, "clip_id"), strs(&b, "kind"));
        for i in 0..b.num_rows() {
            let n = d.contacts.entry(ids[i].clone().expect("id")).or_default();
            *n += u32::from(kind[i].as_deref() == Some("contact"));
        }
    }
    d
}

// ---------------------------------------------------------------------------------------------------------
// Invariants computed from the tables alone.

/// Checks every table-level invariant; `smoothing` is `annotations.crossing_label_smoothing_frames`.
fn check_table_invariants(d: &Dataset, smoothing: u32, width: f32, height: f32) {
    assert!(!d.clips.is_empty(), "no clips");
    assert!(!d.annotations.is_empty(), "no annotations");

    // Keys and joins.
    let mut seen = BTreeSet::new();
    for a in &d.annotations {
        assert!(
            seen.insert((a.clip.clone(), a.frame, a.ped)),
            "duplicate annotation ({}, {}, {})",
            a.clip,
            a.frame,
            a.ped
        );
        assert!(
            d.frames.contains_key(&(a.clip.clone(), a.frame)),
            "annotation's frame ({}, {}) is not in frames",
            a.clip,
            a.frame
        );
        assert!(
            d.pedestrians.contains_key(&(a.clip.clone(), a.ped)),
            "annotation's pedestrian ({}, {}) is not in pedestrians",
            a.clip,
            a.ped
        );
    }

    // Annotations of each pedestrian, in frame order.
    let mut by_ped: BTreeMap<(String, u32), Vec<&AnnRow>> = BTreeMap::new();
    for a in &d.annotations {
        by_ped.entry((a.clip.clone(), a.ped)).or_default().push(a);
    }
    for rows in by_ped.values_mut() {
        rows.sort_by_key(|a| a.frame);
    }

    for (key, rows) in &by_ped {
        let p = &d.pedestrians[key];
        let fcf = p.first_crossing_frame;
        for (i, a) in rows.iter().enumerate() {
            let ctx = format!("clip {} frame {} pedestrian {}", a.clip, a.frame, a.ped);
            // C = 1 only in a crossing-type state, and on a driving lane except within the smoothing window
            // after the last driving-lane frame.
            if a.crossing {
                assert!(
                    CROSSING_STATES.contains(&a.state.as_str()),
                    "{ctx}: C=1 in state {}",
                    a.state
                );
                assert!(
                    fcf.is_some_and(|f| f <= a.frame),
                    "{ctx}: C=1 before first_crossing_frame {fcf:?}"
                );
                if fcf == Some(a.frame) {
                    assert_eq!(
                        a.lane.as_deref(),
                        Some("driving"),
                        "{ctx}: the first C=1 frame is on a driving lane"
                    );
                }
                if a.lane.as_deref() != Some("driving") {
                    // Held by the smoothing: the last driving-lane frame lies within the window before, with
                    // crossing-type states in between. Look for it among the annotated frames of the window;
                    // where the window has frames that are not annotated, the first crossing frame (always on a
                    // driving lane) must at least precede this one.
                    let window: Vec<&&AnnRow> = rows[..i]
                        .iter()
                        .rev()
                        .take_while(|b| a.frame - b.frame <= smoothing)
                        .collect();
                    let mut last_driving = None;
                    let mut expected = a.frame;
                    let mut gap = false;
                    for b in &window {
                        gap |= b.frame + 1 != expected;
                        expected = b.frame;
                        if gap {
                            break;
                        }
                        assert!(
                            CROSSING_STATES.contains(&b.state.as_str()),
                            "{ctx}: C=1 off the driving lane but frame {} of the window is in state {}",
                            b.frame,
                            b.state
                        );
                        if b.lane.as_deref() == Some("driving") {
                            last_driving = Some(b.frame);
                            break;
                        }
                    }
                    let covered = !gap && window.len() == smoothing as usize;
                    assert!(
                        last_driving.is_some() || !covered,
                        "{ctx}: C=1 on {:?} with no driving-lane frame in the {smoothing} frames before",
                        a.lane
                    );
                    assert!(
                        fcf.is_some_and(|f| f < a.frame),
                        "{ctx}: held C=1 before any raw C=1 ({fcf:?})"
                    );
                }
            }
            // TTE counts down to 0 at the first C=1 frame and is null after it and for non-crossing pedestrians.
            match fcf {
                Some(f) if a.frame <= f => {
                    assert_eq!(
                        a.tte,
                        Some((f - a.frame) as i32),
                        "{ctx}: TTE (first crossing frame {f})"
                    )
                }
                _ => assert_eq!(a.tte, None, "{ctx}: TTE after the first crossing frame {fcf:?}"),
            }
            if i > 0 && a.frame == rows[i - 1].frame + 1 && rows[i - 1].tte.is_some_and(|t| t > 0) {
                assert_eq!(
                    a.tte,
                    rows[i - 1].tte.map(|t| t - 1),
                    "{ctx}: TTE decreases by one per frame"
                );
            }
            if fcf == Some(a.frame) {
                assert!(a.crossing, "{ctx}: the first crossing frame is annotated but C=0");
            }
            // Keypoints flagged visible lie inside the box and the image.
            assert_eq!(a.keypoints.len(), 51);
            for k in 0..17 {
                let (x, y, v) = (a.keypoints[3 * k], a.keypoints[3 * k + 1], a.keypoints[3 * k + 2]);
                assert!(v == 0.0 || v == 1.0 || v == 2.0, "{ctx}: keypoint {k} flag {v}");
                if v == 2.0 {
                    let [x0, y0, x1, y1] = a.bbox;
                    assert!(
                        x >= x0 - 0.5 && x <= x1 + 0.5 && y >= y0 - 0.5 && y <= y1 + 0.5,
                        "{ctx}: visible keypoint {k} ({x}, {y}) outside the box {:?}",
                        a.bbox
                    );
                    assert!(
                        (0.0..=width).contains(&x) && (0.0..=height).contains(&y),
                        "{ctx}: visible keypoint {k} ({x}, {y}) outside the image"
                    );
                }
            }
            assert!((0.0..=1.0).contains(&a.occlusion), "{ctx}: occlusion {}", a.occlusion);
            let [x0, y0, x1, y1] = a.bbox;
            assert!(
                x0 < x1 && y0 < y1 && x0 >= 0.0 && y0 >= 0.0 && x1 <= width && y1 <= height,
                "{ctx}: box {:?} (the gate requires it inside the image)",
                a.bbox
            );
        }
        // Sequence label: a crosser has C=1 in at least one annotated frame.
        assert_eq!(
            p.crosser,
            rows.iter().any(|a| a.crossing),
            "{key:?}: pedestrians.crosser vs the annotations' C"
        );
        assert_eq!(p.annotated_frames as usize, rows.len(), "{key:?}: annotated_frames");
    }
    for (key, p) in &d.pedestrians {
        if !by_ped.contains_key(key) {
            assert!(!p.crosser, "{key:?}: a crosser without any annotated frame");
            assert_eq!(p.annotated_frames, 0, "{key:?}");
        }
    }

    // The clips table agrees with the other tables.
    for c in &d.clips {
        let frames: Vec<u32> = d
            .frames
            .keys()
            .filter(|(id, _)| id == &c.clip)
            .map(|(_, f)| *f)
            .collect();
        assert_eq!(
            frames,
            (0..c.frame_count).collect::<Vec<_>>(),
            "{}: frames 0..frame_count",
            c.clip
        );
        let peds: Vec<&PedRow> = d
            .pedestrians
            .iter()
            .filter(|((id, _), _)| id == &c.clip)
            .map(|(_, p)| p)
            .collect();
        assert_eq!(peds.len() as u32, c.pedestrians, "{}: pedestrians", c.clip);
        assert_eq!(
            peds.iter().filter(|p| p.crosser).count() as u32,
            c.crossers,
            "{}: crossers",
            c.clip
        );
        assert_eq!(
            d.annotations.iter().filter(|a| a.clip == c.clip).count() as u64,
            c.annotated_samples,
            "{}: annotated_samples",
            c.clip
        );
        assert!(
            d.vehicles.get(&c.clip).map_or(0, |v| v.len()) as u32 <= c.vehicles,
            "{}: more vehicles in the vehicles table than planned",
            c.clip
        );
        assert_eq!(
            d.contacts.get(&c.clip).copied().unwrap_or(0),
            c.contacts,
            "{}: contacts",
            c.clip
        );
        assert_eq!(
            c.annotated_samples + c.rejected,
            u64::from(c.frame_count) * u64::from(c.pedestrians),
            "{}: every pedestrian-frame is annotated or rejected by exactly one gate stage",
            c.clip
        );
        assert!(
            ["train", "val", "test"].contains(&c.split.as_str()),
            "{}: split {}",
            c.clip,
            c.split
        );
    }
    let ids: BTreeSet<&String> = d.clips.iter().map(|c| &c.clip).collect();
    assert_eq!(ids.len(), d.clips.len(), "one clips row per clip");
    assert!(
        d.frames.keys().all(|(id, _)| ids.contains(id)),
        "frames of unknown clips"
    );
}

// ---------------------------------------------------------------------------------------------------------
// Invariants against an independent re-simulation: boxes from a dense projection of the body, the trace
// columns, and the crossing label recomputed from the trace.

/// `n` unit directions spread evenly over the sphere (Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The crossing label from its definition, for one pedestrian's trace.
fn labels_from_definition(states: &[&str], lanes: &[Option<&str>], smoothing: u32) -> Vec<bool> {
    let mut out = Vec::with_capacity(states.len());
    let mut last_driving: Option<usize> = None;
    for f in 0..states.len() {
        let crossing_state = CROSSING_STATES.contains(&states[f]);
        if !crossing_state {
            last_driving = None;
            out.push(false);
            continue;
        }
        if lanes[f] == Some("driving") {
            last_driving = Some(f);
            out.push(true);
        } else {
            out.push(last_driving.is_some_and(|l| f - l <= smoothing as usize));
        }
    }
    out
}

fn lane_name(l: pedsynth::world::LaneType) -> String {
    let s = format!("{l:?}");
    s.to_lowercase()
}

/// An enum's snake_case name, as the tables write it (serde's).
fn snake<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_value(v)
        .expect("serialises")
        .as_str()
        .expect("a unit variant")
        .to_owned()
}

/// Re-simulates every clip of the dataset and checks the boxes, the trace columns and the labels.
fn check_against_resimulation(d: &Dataset, spec_path: &Path, overrides: &[&str]) {
    let (loaded, plan) = pedsynth::dataset::inputs::compile_plan(spec_path, &options(overrides), None)
        .unwrap_or_else(|e| panic!("plan: {}", e.render()));
    let towns = pedsynth::dataset::inputs::load_towns(&loaded).expect("towns");
    let camera = Camera::from_spec(&plan.spec.sensors.rgb);
    let smoothing = plan.spec.annotations.crossing_label_smoothing_frames;
    let dirs = sphere_directions(256);
    let mut checked_boxes = 0usize;
    let mut worst = 0f64;
    let rig = pedsynth::sim::rig::Rig::from_spec(&plan.spec.sensors);
    for planned in &plan.clips {
        // The clip as `generate` realised it (with any pedestrians promoted or demoted to meet its count).
        let net = &towns[&planned.town].network;
        let realised = pedsynth::sensors::realise::realise(planned, &plan.spec, &plan.sim, &rig, net);
        let (script, trace) = (realised.script.as_ref(), &realised.trace);
        // The re-simulation is the one that was written: the ego's trajectory matches exactly.
        for (f, ego) in trace.ego.iter().enumerate() {
            let row = d.frames[&(script.clip_id.clone(), f as u32)];
            assert_eq!(
                row.ego,
                [ego.pos.x, ego.pos.y, ego.pos.z, ego.yaw_rad],
                "{} frame {f}: ego state",
                script.clip_id
            );
            assert_eq!(
                row.timestamp_ns,
                (f as i64 * 1_000_000_000) / i64::from(script.fps),
                "{} frame {f}: timestamp",
                script.clip_id
            );
        }
        // The crossing label from the definition, on every frame of the trace.
        let labels: Vec<Vec<bool>> = trace
            .pedestrians
            .iter()
            .map(|frames| {
                let states: Vec<&str> = frames.iter().map(|f| f.state.name()).collect();
                let lanes: Vec<Option<String>> = frames.iter().map(|f| f.lane_type.map(lane_name)).collect();
                let lanes: Vec<Option<&str>> = lanes.iter().map(|l| l.as_deref()).collect();
                labels_from_definition(&states, &lanes, smoothing)
            })
            .collect();
        // `tracks`: every pedestrian in every frame, with the trace's position and state, C from the
        // definition, and `annotated` exactly where the annotations table has a row.
        let annotated: BTreeSet<(u32, u32)> = d
            .annotations
            .iter()
            .filter(|a| a.clip == script.clip_id)
            .map(|a| (a.frame, a.ped))
            .collect();
        let rows = d.tracks.keys().filter(|k| k.0 == script.clip_id).count();
        assert_eq!(
            rows,
            trace.pedestrians.iter().map(Vec::len).sum::<usize>(),
            "{}: tracks rows",
            script.clip_id
        );
        for (id, frames) in trace.pedestrians.iter().enumerate() {
            for (f, pf) in frames.iter().enumerate() {
                let key = (script.clip_id.clone(), f as u32, id as u32);
                let t = d.tracks.get(&key).unwrap_or_else(|| panic!("tracks: no row {key:?}"));
                assert_eq!(
                    (t.0, t.1, t.2.as_str(), t.3, t.4.clone(), t.5),
                    (
                        pf.pos.x as f32,
                        pf.pos.y as f32,
                        pf.state.name(),
                        labels[id][f],
                        pf.lane_type.map(lane_name),
                        annotated.contains(&(f as u32, id as u32))
                    ),
                    "tracks {key:?}"
                );
            }
        }
        // The pedestrians table describes the realised script (roles after promotions and demotions) and its
        // sequence labels; every change from the plan is one `sensors::realise` makes.
        for (id, (q, planned_p)) in script.pedestrians.iter().zip(&planned.pedestrians).enumerate() {
            let p = &d.pedestrians[&(script.clip_id.clone(), id as u32)];
            assert_eq!(
                p.roles,
                [snake(&q.role), snake(&q.crosser_source), q.behaviour.name().to_owned()],
                "{} pedestrian {id}: roles vs the realised script",
                script.clip_id
            );
            assert_eq!(
                p.crosser, realised.observations.annotations.pedestrians[id].crosser,
                "{} pedestrian {id}: crosser",
                script.clip_id
            );
            if q != planned_p {
                assert!(
                    q.crosser_source == pedsynth::plan::CrosserSource::Promoted
                        || q.behaviour == pedsynth::plan::Behaviour::HardNegative
                            && planned_p.role == pedsynth::plan::Role::Crosser,
                    "{} pedestrian {id}: changed from the plan, neither promoted nor demoted",
                    script.clip_id
                );
            }
        }
        for (id, l) in labels.iter().enumerate() {
            let p = &d.pedestrians[&(script.clip_id.clone(), id as u32)];
            assert_eq!(
                p.first_crossing_frame,
                l.iter().position(|c| *c).map(|f| f as u32),
                "{} pedestrian {id}: first_crossing_frame vs the trace",
                script.clip_id
            );
        }
        for a in d.annotations.iter().filter(|a| a.clip == script.clip_id) {
            let ctx = format!("clip {} frame {} pedestrian {}", a.clip, a.frame, a.ped);
            let f = &trace.pedestrians[a.ped as usize][a.frame as usize];
            assert_eq!(a.state, f.state.name(), "{ctx}: state vs the trace");
            assert_eq!(a.lane, f.lane_type.map(lane_name), "{ctx}: lane_type vs the trace");
            assert_eq!(
                a.crossing, labels[a.ped as usize][a.frame as usize],
                "{ctx}: C vs its definition on the trace"
            );
            if a.occlusion != 0.0 {
                continue;
            }
            // The box of a fully visible pedestrian is the projected body: dense samples of every capsule.
            let height = f64::from(d.pedestrians[&(a.clip.clone(), a.ped)].height_m);
            let figure = &script.pedestrians[a.ped as usize].identity.figure;
            let pose = body::pose(f, height, figure, DVec3::ZERO);
            let ego = &trace.ego[a.frame as usize];
            let cam = camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
            let mut lo = DVec2::splat(f64::INFINITY);
            let mut hi = DVec2::splat(f64::NEG_INFINITY);
            let mut add = |p: DVec3| {
                let q = cam.project(p);
                assert!(q.depth_m > 0.0, "{ctx}: a body point behind the camera");
                lo = lo.min(q.px);
                hi = hi.max(q.px);
            };
            for c in pose.parts() {
                for dir in &dirs {
                    add(c.a + *dir * c.radius_m);
                    add(c.b + *dir * c.radius_m);
                }
                // The cylinder between the end spheres: rings of points along the segment.
                let axis = c.b - c.a;
                if axis.length() > 1e-9 {
                    let (u, v) = axis.normalize().any_orthonormal_pair();
                    for s in 1..16 {
                        let centre = c.a + axis * (f64::from(s) / 16.0);
                        for k in 0..64 {
                            let t = std::f64::consts::TAU * f64::from(k) / 64.0;
                            add(centre + (u * t.cos() + v * t.sin()) * c.radius_m);
                        }
                    }
                }
            }
            let dense = [lo.x, lo.y, hi.x, hi.y];
            for k in 0..4 {
                let diff = (f64::from(a.bbox[k]) - dense[k]).abs();
                worst = worst.max(diff);
                assert!(
                    diff <= 1.0,
                    "{ctx}: box {:?} vs dense projection {dense:?} (side {k} off by {diff:.2} px)",
                    a.bbox
                );
            }
            checked_boxes += 1;
        }
    }
    assert!(checked_boxes > 0, "no fully visible pedestrian to check boxes on");
    eprintln!("checked {checked_boxes} boxes against the dense projection; worst side {worst:.3} px");
}

fn check_dataset(dir: &Path, spec_path: &Path, overrides: &[&str]) -> Dataset {
    let d = read_dataset(dir);
    check_table_invariants(&d, 5, 1280.0, 720.0);
    check_against_resimulation(&d, spec_path, overrides);
    d
}

// ---------------------------------------------------------------------------------------------------------
// Tests.

#[test]
fn quickstart_tables_satisfy_the_invariants() {
    let tmp = TempDir::new("qs");
    let out = tmp.join("out");
    generate_ok(&spec("quickstart.yaml"), &[], &out, 1);
    for f in ["manifest.json", "spec.resolved.yaml"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let d = check_dataset(&out, &spec("quickstart.yaml"), &[]);
    assert_eq!(d.clips.len(), 2, "quickstart has 2 clips");
    assert!(
        d.annotations.iter().any(|a| a.crossing),
        "quickstart has crossing samples (the invariants on C are not vacuous)"
    );
    assert!(
        d.annotations.iter().any(|a| a.tte.is_some_and(|t| t > 0)),
        "quickstart has samples before a first crossing (the TTE invariants are not vacuous)"
    );
}

#[test]
fn a_spec_with_groups_and_several_towns_satisfies_the_invariants() {
    let tmp = TempDir::new("pp");
    let out = tmp.join("out");
    let overrides = [
        "dataset.clips.count=1",
        "dataset.weathers=[clear_noon, night_rainy, rainy_sunset]",
        "dataset.clip_duration_s=[8, 9]",
    ];
    generate_ok(&spec("pedsynth_pp.yaml"), &overrides, &out, 2);
    let d = check_dataset(&out, &spec("pedsynth_pp.yaml"), &overrides);
    assert_eq!(d.clips.len(), 3);
    assert!(d.annotations.iter().any(|a| a.crossing), "crossing samples");
}

#[test]
fn tables_are_byte_identical_across_jobs_plan_files_and_resumption() {
    let tmp = TempDir::new("det");
    let overrides = ["dataset.clips.count=3", "dataset.clip_duration_s=[6, 8]"];
    let qs = spec("quickstart.yaml");
    let one = tmp.join("jobs1");
    let two = tmp.join("jobs2");
    generate_ok(&qs, &overrides, &one, 1);
    generate_ok(&qs, &overrides, &two, 2);
    assert_same_files(&one, &two, "--jobs 1 vs --jobs 2");

    // A plan file generates the same dataset as its spec.
    let plan_path = tmp.join("plan.json");
    let (mut o, mut e) = (Vec::new(), Vec::new());
    let result = cli::plan(
        &qs,
        &options(&overrides),
        &PlanArgs {
            json: false,
            emit: Some(plan_path.clone()),
            only: None,
        },
        &mut o,
    );
    let code = cli::finish(result, &mut e);
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&e));
    let from_plan = tmp.join("from_plan");
    generate_ok(&plan_path, &[], &from_plan, 2);
    assert_same_files(&one, &from_plan, "spec vs plan file");

    // Interrupt: the manifest is back to its initial state, one clip lost only its completion marker (the
    // clips file), one lost everything and left a temporary file behind, one is finished.
    let resumed = &two;
    let manifest_path = resumed.join("manifest.json");
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest_path).expect("manifest")).expect("json");
    let ids: Vec<String> = manifest["clips"]
        .as_array()
        .expect("clips")
        .iter()
        .map(|c| c["clip_id"].as_str().expect("clip_id").to_owned())
        .collect();
    assert_eq!(ids.len(), 3);
    for c in manifest["clips"].as_array_mut().expect("clips") {
        c["status"] = "pending".into();
        c["files"] = serde_json::json!({});
    }
    std::fs::write(&manifest_path, serde_json::to_string_pretty(&manifest).expect("json")).expect("write");
    std::fs::remove_file(resumed.join("tables/clips").join(format!("{}.parquet", ids[0]))).expect("rm");
    for t in TABLES {
        std::fs::remove_file(resumed.join("tables").join(t).join(format!("{}.parquet", ids[1]))).expect("rm");
    }
    let stray = resumed
        .join("tables/annotations")
        .join(format!(".{}.parquet.tmp-4242", ids[1]));
    std::fs::write(&stray, b"half a parquet file").expect("write stray");
    std::fs::write(resumed.join("tables/frames/leftover.tmp"), b"junk").expect("write stray");
    let finished = resumed.join("tables/frames").join(format!("{}.parquet", ids[2]));
    let before = std::fs::metadata(&finished).and_then(|m| m.modified()).expect("mtime");
    std::thread::sleep(std::time::Duration::from_millis(20));
    let stdout = generate_ok(&qs, &overrides, resumed, 2);
    assert!(
        stdout.contains("generated 2 clips (1 already done)"),
        "resume skips the finished clip: {stdout}"
    );
    let after = std::fs::metadata(&finished).and_then(|m| m.modified()).expect("mtime");
    assert_eq!(before, after, "the finished clip's files are not rewritten");
    assert!(!stray.exists(), "the stray temporary file is removed");
    assert_same_files(&one, resumed, "uninterrupted vs interrupted and resumed");

    // A finished dataset re-run: nothing to do, nothing changes.
    let stdout = generate_ok(&qs, &overrides, &one, 2);
    assert!(stdout.contains("generated 0 clips (3 already done)"), "{stdout}");
    assert_same_files(&one, &from_plan, "re-run of a finished dataset");

    // The same spec from another directory — the dataset's own spec.resolved.yaml, copied elsewhere — is the
    // same dataset: it resumes (nothing to do) instead of being refused.
    let elsewhere = tmp.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).expect("mkdir");
    std::fs::copy(one.join("spec.resolved.yaml"), elsewhere.join("resolved.yaml")).expect("copy");
    let stdout = generate_ok(&elsewhere.join("resolved.yaml"), &[], &one, 1);
    assert!(stdout.contains("generated 0 clips (3 already done)"), "{stdout}");
    assert_same_files(&one, &from_plan, "re-run from spec.resolved.yaml");

    // A dataset of another spec is refused (exit 2) and left untouched.
    let (code, _, stderr) = generate(&qs, &["dataset.clips.count=3", "dataset.seed=8"], &one, 1);
    assert_eq!(code, 2, "another spec's dataset: {stderr}");
    assert!(stderr.contains("another spec"), "{stderr}");
    assert_same_files(&one, &from_plan, "after a refused run");
}

use crate::common::pedsynth;

#[test]
fn generate_refuses_directories_it_must_not_write_into() {
    let tmp = TempDir::new("refuse");
    let qs = spec("quickstart.yaml");
    let gen_args = |out: &Path, extra: &[&str]| -> Vec<std::ffi::OsString> {
        let mut v: Vec<std::ffi::OsString> = vec!["generate".into(), qs.clone().into(), "--out".into(), out.into()];
        for set in common::NO_SENSORS {
            v.extend(["--set".into(), set.into()]);
        }
        v.extend(extra.iter().map(|s| s.into()));
        v
    };
    let run = |args: Vec<std::ffi::OsString>| {
        let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
        pedsynth(&refs)
    };

    // One clip of quickstart, quietly: nothing on stderr.
    let dataset = tmp.join("dataset");
    let (code, _, stderr) = run(gen_args(
        &dataset,
        &["--quiet", "--only", "town01_like-clear_noon-0000", "--jobs", "1"],
    ));
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(stderr, "", "--quiet prints nothing on stderr");
    assert!(
        !dataset.join("README.md").exists(),
        "an unfinished dataset gets no card"
    );
    let before = all_files(&dataset);

    // A dataset of another spec.
    let (code, _, stderr) = run(gen_args(&dataset, &["--quiet", "--set", "dataset.seed=8"]));
    assert_eq!(code, Some(2), "another spec's dataset: {stderr}");
    assert!(stderr.contains("another spec"), "{stderr}");
    assert!(all_files(&dataset) == before, "a refused run changes nothing");

    // A non-empty directory that is not a pedsynth dataset.
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).expect("mkdir");
    std::fs::write(out.join("notes.txt"), b"my files").expect("write");
    let (code, _, stderr) = run(gen_args(&out, &["--quiet"]));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not a pedsynth dataset"), "{stderr}");
    let names: Vec<String> = std::fs::read_dir(&out)
        .expect("read")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["notes.txt"], "nothing written");
}

#[test]
fn stats_protocol_pab_reads_the_tables_and_refuses_undefined_options() {
    use pedsynth::dataset::read::protocol::PabOptions;
    let tmp = TempDir::new("pab");
    let out = tmp.join("out");
    generate_ok(&spec("quickstart.yaml"), &[], &out, 1);
    let (mut o, mut e) = (Vec::new(), Vec::new());
    let pab = PabOptions::default();
    let code = cli::finish(cli::stats(&out, true, Some(&pab), &mut o), &mut e);
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&e));
    let json: serde_json::Value = serde_json::from_slice(&o).expect("JSON");
    assert_eq!(json["stride"], 6);
    let d = read_dataset(&out);
    let tracks =
        json["all"]["crossing"]["tracks"].as_u64().unwrap() + json["all"]["not_crossing"]["tracks"].as_u64().unwrap();
    let annotated: std::collections::BTreeSet<_> = d.annotations.iter().map(|a| (a.clip.clone(), a.ped)).collect();
    assert_eq!(tracks, annotated.len() as u64, "one track per annotated pedestrian");

    // A minimum track shorter than a window's reach is not the benchmark's sampling: a clear input error.
    let short = PabOptions { min_track: 50, ..pab };
    let (mut o, mut e) = (Vec::new(), Vec::new());
    let code = cli::finish(cli::stats(&out, false, Some(&short), &mut o), &mut e);
    assert_eq!(code, 2);
    assert!(String::from_utf8_lossy(&e).contains("pedsynth::dataset::protocol_options"));
}

#[test]
fn a_finished_dataset_gets_a_card_with_its_licence_counts_and_a_config_per_table() {
    let tmp = TempDir::new("card");
    let out = tmp.join("ds");
    generate_ok(&spec("quickstart.yaml"), &["dataset.license=cc-by-4.0"], &out, 2);
    let card = std::fs::read_to_string(out.join("README.md")).expect("README.md");
    let (front, body) = card
        .strip_prefix("---\n")
        .and_then(|c| c.split_once("\n---\n"))
        .expect("front matter");
    assert!(front.lines().any(|l| l == "license: cc-by-4.0"), "{front}");
    let d = read_dataset(&out);
    for table in ["annotations", "tracks", "pedestrians", "frames", "clips"] {
        assert!(front.contains(&format!("- config_name: {table}\n")), "{table}");
        for clip in &d.clips {
            assert!(front.contains(&format!("\"tables/{table}/{}.parquet\"", clip.clip)));
        }
    }
    // No sensors: the empty `sensors` table gets no config (a split without rows cannot be loaded).
    assert!(!front.contains("config_name: sensors"));
    assert!(body.contains("`sensors`: one row per sensor file (path, size, SHA-256) (no rows in this dataset)"));
    let samples: u64 = d.clips.iter().map(|c| c.annotated_samples).sum();
    assert!(
        body.contains(&format!("| annotated samples (pedestrian-frames) | {samples} |")),
        "{body}"
    );
    assert!(body.contains(&format!("| clips | {} |", d.clips.len())));
    assert!(!card.contains(tmp.0.to_str().unwrap()), "no absolute path in the card");

    // A licence that is not an identifier is refused, pointing at the value.
    let text = std::fs::read_to_string(spec("quickstart.yaml")).unwrap();
    let bad = text.replacen("dataset:\n", "dataset:\n  license: CC BY 4.0\n", 1);
    let Err(err) = pedsynth::spec::load_bytes(bad.as_bytes(), "bad.yaml", Path::new("specs"), &options(&[])) else {
        panic!("a licence with spaces is refused");
    };
    let shown = format!("{err:?}");
    assert!(
        shown.contains("dataset.license") && shown.contains("CC BY 4.0"),
        "{shown}"
    );
}
