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

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pedsynth::dataset::export::dataset::AnnotatedFrame;
use pedsynth::dataset::export::pab::pose36;

fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

use crate::common::pedsynth;

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
    // With cyclists: they go into the OpenSCENARIO files as bicycles and into PIE as vehicles of type bicycle.
    let mut overrides = common::NO_SENSORS.to_vec();
    overrides.push("traffic.cyclists.per_clip=[2, 2]");
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &overrides, &ds, None);
    assert_eq!(code, 0, "{stderr}");

    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    for out in [&a, &b] {
        for (format, layout) in [
            ("pie", "pie"),
            ("pab-poses", "pie"),
            ("jaad", "jaad"),
            ("pab-poses-jaad", "jaad"),
            ("seed-csv", "seed"),
            ("openscenario", "xosc"),
            ("coco", "coco"),
        ] {
            let (code, stdout, stderr) = export(format, &ds, &out.join(layout));
            assert_eq!(code, Some(0), "{stderr}");
            if ["pie", "jaad", "seed-csv", "coco"].contains(&format) {
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
        "xosc/towns/town01_like.xodr",
        "xosc/town01_like-clear_noon-0000.xosc",
        "coco/annotations/train.json",
    ] {
        assert!(files.contains_key(file), "{file}: {:?}", files.keys());
    }
    assert!(files == common::all_files(&b), "two exports of one dataset differ");
    // The seed's CSV: one row per annotated pedestrian-frame, none twice, every row as wide as the header.
    let view = pedsynth::dataset::export::dataset::Dataset::open(&ds).expect("opens");
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
    // COCO (tests/interop_coco.py runs pycocotools on it in CI): an image per frame, an annotation per annotated
    // pedestrian-frame and cyclist-frame, no masks without an instance stream.
    let coco: serde_json::Value = serde_json::from_slice(&files["coco/annotations/train.json"]).expect("json");
    let frames: u32 = view.clips.iter().map(|c| c.frame_count).sum();
    assert_eq!(coco["images"].as_array().expect("images").len(), frames as usize);
    let cyclists: usize = view
        .clips
        .iter()
        .map(|info| view.load(info).expect("loads"))
        .map(|c| c.cyclists.iter().filter(|f| f.annotated).count())
        .sum();
    assert!(cyclists > 0, "the spec's cyclists are annotated somewhere");
    let anns = coco["annotations"].as_array().expect("annotations");
    assert_eq!(anns.len(), annotated + cyclists);
    assert_eq!(anns.iter().filter(|a| a["category_id"] == 2).count(), cyclists);
    assert!(
        anns.iter()
            .all(|a| a.get("segmentation").is_none() && a["iscrowd"] == 0)
    );
    let names: Vec<&str> = coco["categories"]
        .as_array()
        .expect("categories")
        .iter()
        .map(|c| c["name"].as_str().expect("name"))
        .collect();
    assert_eq!(names, ["pedestrian", "cyclist"]);
    // OpenSCENARIO: every entity's polyline, evaluated at every frame, is where the tables put it.
    for info in &view.clips {
        let clip = view.load(info).expect("loads");
        let xosc = String::from_utf8(files[&format!("xosc/{}.xosc", clip.clip_id)].clone()).expect("utf-8");
        check_replay(&clip, &xosc);
    }
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
        look: false,
        action: "standing".into(),
        gesture: "none".into(),
        reaction: "none".into(),
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

/// Parses an exported .xosc and checks that each entity's polyline, linearly interpolated in time, passes
/// within the exporter's tolerance (2 cm, 0.02 rad, plus the file's rounding) of every frame of the tables:
/// the ego from `frames`, vehicles from `vehicles`, cyclists (bicycles) from `cyclists`, pedestrians from
/// `tracks`; and that the scenario declares
/// exactly these entities, points at the exported town and carries the clip's weather.
fn check_replay(clip: &pedsynth::dataset::export::dataset::Clip, xosc: &str) {
    use pedsynth::dataset::export::openscenario::{TOLERANCE_M, TOLERANCE_RAD};
    let doc = roxmltree::Document::parse(xosc).expect("well-formed");
    let logic = doc.descendants().find(|n| n.has_tag_name("LogicFile")).unwrap();
    assert_eq!(
        logic.attribute("filepath"),
        Some(format!("towns/{}.xodr", clip.town).as_str())
    );
    let num = |n: roxmltree::Node, a: &str| n.attribute(a).unwrap().parse::<f64>().unwrap();
    let mut polylines: BTreeMap<String, Vec<[f64; 5]>> = BTreeMap::new();
    for t in doc.descendants().filter(|n| n.has_tag_name("Trajectory")) {
        let vertices = t
            .descendants()
            .filter(|n| n.has_tag_name("Vertex"))
            .map(|v| {
                let w = v.descendants().find(|n| n.has_tag_name("WorldPosition")).unwrap();
                [num(v, "time"), num(w, "x"), num(w, "y"), num(w, "z"), num(w, "h")]
            })
            .collect();
        polylines.insert(t.attribute("name").unwrap().to_owned(), vertices);
    }
    let declared: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("ScenarioObject"))
        .map(|n| n.attribute("name").unwrap())
        .collect();
    let vehicles: std::collections::BTreeSet<u32> = clip.vehicles.iter().map(|v| v.vehicle).collect();
    let cyclists: std::collections::BTreeSet<u32> = clip.cyclists.iter().map(|c| c.cyclist).collect();
    assert!(
        !cyclists.is_empty(),
        "{}: the test's dataset has cyclists",
        clip.clip_id
    );
    assert!(
        !clip.parked_cars.is_empty(),
        "{}: the test's dataset has parked cars",
        clip.clip_id
    );
    assert_eq!(
        declared.len(),
        1 + vehicles.len() + cyclists.len() + clip.tracks.len() + clip.parked_cars.len()
    );
    let bicycles = doc
        .descendants()
        .filter(|n| n.has_tag_name("Vehicle") && n.attribute("vehicleCategory") == Some("bicycle"))
        .count();
    assert_eq!(bicycles, cyclists.len());
    assert_eq!(
        polylines.len(),
        declared.len() - clip.parked_cars.len(),
        "every moving entity has a trajectory, no parked car has one"
    );
    // Parked cars: declared with their row's size, teleported to their row's place in `Init`, never moved.
    let init = doc.descendants().find(|n| n.has_tag_name("Init")).unwrap();
    for car in &clip.parked_cars {
        let name = format!("parked_car_{}", car.parked_car);
        assert!(!polylines.contains_key(&name), "{name} has no trajectory");
        let object = doc
            .descendants()
            .find(|n| n.has_tag_name("ScenarioObject") && n.attribute("name") == Some(name.as_str()))
            .unwrap_or_else(|| panic!("{name} declared"));
        let dims = object.descendants().find(|n| n.has_tag_name("Dimensions")).unwrap();
        let size = [num(dims, "length"), num(dims, "width"), num(dims, "height")];
        assert!(
            size.iter().zip(car.size_m).all(|(a, b)| (a - b).abs() < 1e-6),
            "{name}: {size:?} against {:?}",
            car.size_m
        );
        let parked_property = object
            .descendants()
            .any(|n| n.has_tag_name("Property") && n.attribute("name") == Some("parked"));
        assert!(parked_property, "{name} is marked parked");
        let teleport = init
            .descendants()
            .find(|n| n.has_tag_name("Private") && n.attribute("entityRef") == Some(name.as_str()))
            .unwrap_or_else(|| panic!("{name} placed in Init"));
        let w = teleport
            .descendants()
            .find(|n| n.has_tag_name("WorldPosition"))
            .unwrap();
        let d = ((num(w, "x") - car.x_m).powi(2) + (num(w, "y") - car.y_m).powi(2) + (num(w, "z") - car.z_m).powi(2))
            .sqrt();
        let dh =
            (num(w, "h") - car.yaw_rad + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        assert!(
            d < 0.002 && dh.abs() < 0.001,
            "{name}: placed {d} m, {dh} rad from its row"
        );
    }
    assert_eq!(
        clip.tracks.len(),
        clip.pedestrians.len(),
        "tracks cover every pedestrian"
    );
    let at = |name: &str, t: f64| -> [f64; 4] {
        let p = &polylines[name];
        let k = p.partition_point(|v| v[0] <= t + 1e-9).clamp(1, p.len() - 1);
        let (a, b) = (p[k - 1], p[k]);
        let w = if b[0] > a[0] {
            ((t - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0)
        } else {
            0.0
        };
        std::array::from_fn(|i| a[i + 1] + (b[i + 1] - a[i + 1]) * w)
    };
    let fps = f64::from(clip.fps);
    let mut checked = 0;
    let mut check = |name: &str, frame: u32, want: [f64; 4]| {
        let got = at(name, f64::from(frame) / fps);
        let d = ((got[0] - want[0]).powi(2) + (got[1] - want[1]).powi(2) + (got[2] - want[2]).powi(2)).sqrt();
        let dh = (got[3] - want[3] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        assert!(
            d <= TOLERANCE_M + 0.002 && dh.abs() <= TOLERANCE_RAD + 0.001,
            "{} {name} frame {frame}: polyline {got:?}, table {want:?}",
            clip.clip_id
        );
        checked += 1;
    };
    for (f, e) in clip.ego.iter().enumerate() {
        check("ego", f as u32, [e.x_m, e.y_m, e.z_m, e.yaw_rad]);
    }
    for v in &clip.vehicles {
        check(
            &format!("vehicle_{}", v.vehicle),
            v.frame,
            [v.x_m, v.y_m, v.z_m, v.yaw_rad],
        );
    }
    for c in &clip.cyclists {
        check(
            &format!("cyclist_{}", c.cyclist),
            c.frame,
            [c.x_m, c.y_m, c.z_m, c.yaw_rad],
        );
    }
    for (id, track) in &clip.tracks {
        assert_eq!(
            track.len(),
            clip.frame_count as usize,
            "pedestrian {id}: a row per frame"
        );
        for f in track {
            check(&format!("pedestrian_{id}"), f.frame, [f.x_m, f.y_m, f.z_m, f.yaw_rad]);
        }
    }
    assert!(checked > clip.frame_count as usize * 3);
    let vertices: usize = polylines.values().map(Vec::len).sum();
    assert!(
        vertices * 4 < checked,
        "polylines are simplified ({vertices} vertices for {checked} poses)"
    );
    let sun = doc.descendants().find(|n| n.has_tag_name("Sun")).unwrap();
    assert!((num(sun, "elevation") - clip.sun_altitude_deg.to_radians()).abs() < 1e-3);
}

/// nuScenes (tests/interop_nuscenes.py runs nuscenes-devkit on it in CI): a LiDAR-only dataset with cyclists
/// exports to the same bytes twice; keyframes every 15 frames at 30 FPS; every annotated pedestrian of a
/// keyframe has one box; tokens are unique and every `prev`/`next`/`first`/`last` token points at a record of
/// its table; each `LIDAR_TOP` sample_data's ego pose and calibration compose to the `sensor_poses` row of its
/// frame; an altered dataset, a dataset without cameras or LiDAR and `--keyframe-hz 0` are refused with exit 2,
/// and so is `export rerun` of an altered dataset or without a clip the dataset has.
#[test]
fn nuscenes_export_links_its_records_and_composes_the_sensor_poses() {
    use serde_json::Value;
    let tmp = common::Scratch::new("export-nuscenes");
    let ds = tmp.path().join("ds");
    let mut overrides = common::NO_CAMERAS.to_vec();
    overrides.extend([
        "traffic.cyclists.per_clip=[2, 2]",
        "dataset.clips.count=1",
        "dataset.clip_duration_s=[3, 3]",
    ]);
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &overrides, &ds, None);
    assert_eq!(code, 0, "{stderr}");
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    for out in [&a, &b] {
        let (code, stdout, stderr) = export("nuscenes", &ds, out);
        assert_eq!(code, Some(0), "{stderr}");
        assert!(stdout.contains("no CAM_FRONT"), "{stdout}");
    }
    let files = common::all_files(&a);
    assert!(files == common::all_files(&b), "two exports of one dataset differ");
    let table = |name: &str| -> Vec<Value> {
        let bytes = &files[&format!("v1.0-pedsynth/{name}.json")];
        serde_json::from_slice::<Value>(bytes)
            .expect("json")
            .as_array()
            .expect("array")
            .clone()
    };
    let tables: BTreeMap<&str, Vec<Value>> = [
        "category",
        "attribute",
        "visibility",
        "sensor",
        "calibrated_sensor",
        "ego_pose",
        "log",
        "scene",
        "sample",
        "sample_data",
        "instance",
        "sample_annotation",
        "map",
    ]
    .into_iter()
    .map(|t| (t, table(t)))
    .collect();
    let tokens: BTreeMap<&str, std::collections::BTreeSet<String>> = tables
        .iter()
        .map(|(t, rows)| {
            (
                *t,
                rows.iter()
                    .map(|r| r["token"].as_str().expect("token").to_owned())
                    .collect(),
            )
        })
        .collect();
    for (t, rows) in &tables {
        assert_eq!(tokens[t].len(), rows.len(), "{t}: tokens are unique");
    }
    let points_at = |table: &str, value: &Value| {
        let v = value.as_str().expect("a token");
        assert!(v.is_empty() || tokens[table].contains(v), "{v} is not a {table} token");
    };
    for r in &tables["sample"] {
        points_at("sample", &r["prev"]);
        points_at("sample", &r["next"]);
        points_at("scene", &r["scene_token"]);
    }
    for r in &tables["sample_data"] {
        points_at("sample_data", &r["prev"]);
        points_at("sample_data", &r["next"]);
        points_at("sample", &r["sample_token"]);
        points_at("ego_pose", &r["ego_pose_token"]);
        points_at("calibrated_sensor", &r["calibrated_sensor_token"]);
        let file = r["filename"].as_str().expect("filename");
        assert!(files.contains_key(file), "{file} is written");
    }
    for r in &tables["sample_annotation"] {
        points_at("sample_annotation", &r["prev"]);
        points_at("sample_annotation", &r["next"]);
        points_at("sample", &r["sample_token"]);
        points_at("instance", &r["instance_token"]);
    }
    for r in &tables["instance"] {
        points_at("sample_annotation", &r["first_annotation_token"]);
        points_at("sample_annotation", &r["last_annotation_token"]);
        points_at("category", &r["category_token"]);
    }
    // Keyframes: frames 0, 15, ..., 75 of the 90-frame clip.
    let view = pedsynth::dataset::export::dataset::Dataset::open(&ds).expect("opens");
    let clip = view.load(&view.clips[0]).expect("loads");
    assert_eq!(clip.frame_count, 90);
    let samples = &tables["sample"];
    assert_eq!(samples.len(), 6);
    let stamps: Vec<u64> = samples.iter().map(|s| s["timestamp"].as_u64().expect("µs")).collect();
    assert_eq!(stamps, [0, 500_000, 1_000_000, 1_500_000, 2_000_000, 2_500_000]);
    // Each keyframe's pedestrians are the annotations table's; cyclists are there too.
    let sample_frame: BTreeMap<&str, u32> = samples
        .iter()
        .map(|s| {
            (
                s["token"].as_str().expect("token"),
                (s["timestamp"].as_u64().expect("µs") * 30 / 1_000_000) as u32,
            )
        })
        .collect();
    let instance: BTreeMap<&str, &Value> = tables["instance"]
        .iter()
        .map(|i| (i["token"].as_str().expect("t"), i))
        .collect();
    let mut boxed: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    let mut cyclist_boxes = 0;
    for r in &tables["sample_annotation"] {
        let inst = instance[r["instance_token"].as_str().expect("t")];
        match inst["kind"].as_str() {
            Some("pedestrian") => boxed
                .entry(sample_frame[r["sample_token"].as_str().expect("t")])
                .or_default()
                .push(inst["id"].as_u64().expect("id") as u32),
            Some("cyclist") => cyclist_boxes += 1,
            _ => {}
        }
    }
    for f in (0..90).step_by(15) {
        let mut want: Vec<u32> = clip
            .pedestrians
            .values()
            .filter(|p| p.frames.iter().any(|a| a.frame == f))
            .map(|p| p.id)
            .collect();
        let mut got = boxed.remove(&f).unwrap_or_default();
        want.sort_unstable();
        got.sort_unstable();
        assert_eq!(got, want, "pedestrian boxes at keyframe {f}");
    }
    assert!(cyclist_boxes > 0, "the cyclists within 100 m have boxes");
    // Ego pose ∘ calibration = the LiDAR's pose in sensor_poses (in the world: global + the map's origin).
    let origin = &tables["map"][0]["world_origin_m"];
    let origin = glam::DVec3::new(origin[0].as_f64().expect("x"), origin[1].as_f64().expect("y"), 0.0);
    let pose_of = |v: &Value| {
        let t = &v["translation"];
        let q = &v["rotation"];
        let f = |x: &Value| x.as_f64().expect("number");
        glam::DAffine3::from_rotation_translation(
            glam::DQuat::from_xyzw(f(&q[1]), f(&q[2]), f(&q[3]), f(&q[0])),
            glam::DVec3::new(f(&t[0]), f(&t[1]), f(&t[2])),
        )
    };
    let ego: BTreeMap<&str, &Value> = tables["ego_pose"]
        .iter()
        .map(|e| (e["token"].as_str().expect("t"), e))
        .collect();
    let calibrated = &tables["calibrated_sensor"];
    assert_eq!(calibrated.len(), 1, "one LiDAR on one clip");
    let lidar_poses = read_sensor_poses(&ds, &clip.clip_id, "lidar");
    let mut compared = 0;
    for r in &tables["sample_data"] {
        let frame = (r["timestamp"].as_u64().expect("µs") * 30).div_ceil(1_000_000) as u32;
        let global_from_sensor = pose_of(ego[r["ego_pose_token"].as_str().expect("t")]) * pose_of(&calibrated[0]);
        let want = lidar_poses[&frame];
        let got_t = global_from_sensor.translation + origin;
        assert!(
            (got_t - want.translation).length() < 1e-6,
            "frame {frame}: {got_t} vs {}",
            want.translation
        );
        assert!(
            (global_from_sensor.matrix3 - want.matrix3)
                .abs()
                .to_cols_array()
                .iter()
                .all(|&d| d < 1e-9),
            "frame {frame}: rotations differ"
        );
        compared += 1;
    }
    assert_eq!(compared, 6 + 5, "keyframes and the tick before each but the first");

    // A table changed after generate: nuScenes and Rerun refuse it as the other exports do.
    let table = ds.join(format!("tables/annotations/{}.parquet", clip.clip_id));
    let original = std::fs::read(&table).expect("read");
    let mut changed = original.clone();
    let mid = changed.len() / 2;
    changed[mid] ^= 1;
    std::fs::write(&table, &changed).expect("write");
    for format in ["nuscenes", "rerun"] {
        let (code, _, stderr) = pedsynth(&[
            "export".as_ref(),
            format.as_ref(),
            ds.as_os_str(),
            "--out".as_ref(),
            tmp.path().join("altered").as_os_str(),
            "--clip".as_ref(),
            clip.clip_id.as_ref(),
        ]);
        assert_eq!(code, Some(2), "{format}: {stderr}");
        assert!(
            stderr.contains("blake3 differs from the manifest"),
            "{format}: {stderr}"
        );
    }
    std::fs::write(&table, &original).expect("restore");

    // No cameras and no LiDAR: refused.
    let bare = tmp.path().join("bare");
    let mut overrides = common::NO_SENSORS.to_vec();
    overrides.extend(["dataset.clips.count=1", "dataset.clip_duration_s=[1, 1]"]);
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &overrides, &bare, None);
    assert_eq!(code, 0, "{stderr}");
    let (code, _, stderr) = export("nuscenes", &bare, &tmp.path().join("c"));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("CAM_FRONT or LIDAR_TOP"), "{stderr}");
    // A distorting lens: nuScenes' pinhole cannot describe it, so the export refuses rather than mislead.
    let lens = tmp.path().join("lens");
    let mut overrides = common::NO_SENSORS.to_vec();
    overrides.extend([
        "dataset.clips.count=1",
        "dataset.clip_duration_s=[1, 1]",
        "sensors.rgb.enabled=true",
        "sensors.rgb.width_px=160",
        "sensors.rgb.height_px=90",
        "sensors.rgb.distortion.k1=-0.1",
    ]);
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &overrides, &lens, None);
    assert_eq!(code, 0, "{stderr}");
    let (code, _, stderr) = export("nuscenes", &lens, &tmp.path().join("e"));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("lens distortion"), "{stderr}");
    let (code, _, stderr) = pedsynth(&[
        "export".as_ref(),
        "nuscenes".as_ref(),
        ds.as_os_str(),
        "--out".as_ref(),
        tmp.path().join("d").as_os_str(),
        "--keyframe-hz".as_ref(),
        "0".as_ref(),
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not a rate above 0 Hz"), "{stderr}");
    // Rerun records one clip: without --clip, or with one the dataset does not have, exit 2 naming its clips
    // (with or without the `rerun` feature; tests/interop_rerun.py reads a recording in CI).
    for clip in [None, Some("no_such_clip")] {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "export".as_ref(),
            "rerun".as_ref(),
            ds.as_os_str(),
            "--out".as_ref(),
            "x.rrd".as_ref(),
        ];
        if let Some(c) = clip {
            args.extend([std::ffi::OsStr::new("--clip"), std::ffi::OsStr::new(c)]);
        }
        let (code, _, stderr) = pedsynth(&args);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(stderr.contains(&view.clips[0].clip_id), "{stderr}");
    }
}

/// A sensor's `world_from_sensor` by frame, from the `sensor_poses` table.
fn read_sensor_poses(ds: &Path, clip: &str, sensor: &str) -> BTreeMap<u32, glam::DAffine3> {
    let file = ds.join(format!("tables/sensor_poses/{clip}.parquet"));
    let cols = ["frame", "sensor", "x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"];
    let mut out = BTreeMap::new();
    for b in pedsynth::dataset::read::tables::read(&file, &cols).expect("reads") {
        let (f, s) = (b.u32s("frame").expect("frame"), b.strings("sensor").expect("sensor"));
        let v: Vec<_> = cols[2..].iter().map(|c| b.f64s(c).expect("f64")).collect();
        for i in (0..b.rows()).filter(|&i| s[i] == sensor) {
            let q = glam::DQuat::from_xyzw(v[4].value(i), v[5].value(i), v[6].value(i), v[3].value(i));
            let t = glam::DVec3::new(v[0].value(i), v[1].value(i), v[2].value(i));
            out.insert(f.value(i), glam::DAffine3::from_rotation_translation(q.normalize(), t));
        }
    }
    out
}
