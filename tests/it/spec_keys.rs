//! Every key of the spec language is used: a walk over every leaf of the resolved spec perturbs it (to a value
//! that passes validation) and proves that the change reaches the plan's clip scripts or the written tables, or
//! changes validation (the sanity limits), or that the key is on the explicit not-implemented list
//! (`spec::not_yet::NOT_YET`) and setting it is reported as `pedsynth::spec::not_implemented`. A key that is
//! accepted and silently ignored fails this test.

use crate::common;

use std::collections::BTreeMap;
use std::path::Path;

use pedsynth::dataset::write::lidar::ClipLidarWriter;
use pedsynth::dataset::write::sensors::ClipSensorWriter;
use pedsynth::dataset::write::tables::{self, FileMeta};
use pedsynth::plan::{self, TownContext};
use pedsynth::sensors;
use pedsynth::sensors::scene::StaticScene;
use pedsynth::sim;
use pedsynth::sim::rig::Rig;
use pedsynth::spec::not_yet::NOT_YET;
use pedsynth::spec::{self, LoadOptions, Spec};
use serde_json::{Value as Json, json};

/// What a spec produces, in the parts a key can reach.
#[derive(PartialEq)]
struct Outcome {
    /// The plan's clip scripts, dataset name and target (not its copy of the spec or the simulation
    /// parameters, which hold every key verbatim: those must prove themselves in the tables), and the dataset
    /// card generate would write for it (with placeholder counts).
    plan: String,
    /// blake3 of every table file of every clip (with fixed file metadata, so the spec hash does not count),
    /// and, for the keys of `sensors` and `output`, of the sensor files of the first frames of the first clip.
    tables: Option<String>,
}

struct Walker {
    base: Json,
    /// The base spec's tables (computed once).
    base_tables: std::cell::OnceCell<Option<String>>,
    /// The base spec's tables and sensor files (computed once).
    base_sensors: std::cell::OnceCell<Option<String>>,
    /// Whether the key being judged may show in the sensor files only.
    sensors: std::cell::Cell<bool>,
    towns: BTreeMap<String, TownContext>,
    base_dir: std::path::PathBuf,
}

enum Verdict {
    Used,
    Exported,
    NotImplemented,
    Validation,
    Ignored,
    Invalid(String),
}

impl Walker {
    fn load(&self, spec: &Json) -> Result<spec::LoadedSpec, spec::SpecErrors> {
        let text = serde_json::to_string(spec).expect("json");
        spec::load_bytes(text.as_bytes(), "walk.yaml", &self.base_dir, &LoadOptions::default())
    }

    fn outcome(&self, loaded: &spec::LoadedSpec, with_tables: bool) -> Outcome {
        let base: Spec = serde_json::from_value(self.base.clone()).expect("base spec");
        let own;
        let towns = if loaded.spec.dataset.towns == base.dataset.towns {
            &self.towns
        } else {
            own = pedsynth::dataset::inputs::load_spec_towns(&loaded.spec, &self.base_dir).expect("towns");
            &own
        };
        let plan = plan::plan(&loaded.spec, "walk", "", towns, None).unwrap_or_else(|p| panic!("plan: {p:?}"));
        let manifest: pedsynth::dataset::write::manifest::Manifest = serde_json::from_value(json!({
            "pedsynth_dataset": 1, "pedsynth_version": "walk", "schema_version": 0, "dataset": plan.dataset,
            "spec_hash": "walk", "plan_hash": "walk", "target_crossing_ratio": plan.target_crossing_ratio,
            "tables": [], "sensors": {}, "clips": []
        }))
        .expect("manifest");
        let card = pedsynth::dataset::write::card::render(
            &plan.spec,
            &manifest,
            &|_| {},
            &BTreeMap::new(),
            &Default::default(),
        );
        let plan_text =
            serde_json::to_string(&(&plan.clips, &plan.dataset, plan.target_crossing_ratio, card)).expect("json");
        let tables = with_tables.then(|| {
            let meta = FileMeta {
                spec_hash: "fixed".to_owned(),
            };
            let mut hasher = blake3::Hasher::new();
            for script in &plan.clips {
                let net = &towns[&script.town].network;
                let rig = Rig::for_clip(&plan.spec.sensors, script.seed);
                let trace = sim::simulate(script, &plan.sim, net);
                let obs = sensors::observe(script, &trace, &plan.spec, &rig, net);
                let ann = &obs.annotations;
                let batches = [
                    tables::frames_batch(script, &trace),
                    tables::pedestrians_batch(script, ann),
                    tables::annotations_batch(script, ann, plan.spec.annotations.pose_format),
                    tables::tracks_batch(script, &trace, ann),
                    tables::vehicles_batch(script, &trace),
                    tables::events_batch(script, &trace),
                    tables::sensor_poses_batch(script, &trace, &rig, &plan.spec.sensors),
                    tables::clips_batch(script, &trace, ann),
                ];
                for batch in &batches {
                    let bytes =
                        tables::parquet_bytes(batch, &plan.spec.output, &meta, "t", &script.clip_id).expect("parquet");
                    hasher.update(&bytes);
                }
                if self.sensors.get() && script.clip_id == plan.clips[0].clip_id {
                    // The sensor files of the first frames, written to a scratch directory and hashed through
                    // the sensor index (path, size, SHA-256).
                    let dir = std::env::temp_dir().join(format!("pedsynth-keys-{}", std::process::id()));
                    let layout = pedsynth::dataset::write::Layout::new(&dir);
                    let sensors = &plan.spec.sensors;
                    let mut files =
                        ClipSensorWriter::new(&layout, &script.clip_id, script.fps, sensors, &plan.spec.output, &meta)
                            .expect("sensor writer");
                    let stat = StaticScene::build(script, &trace, net, &ann.scenery);
                    let _ = sensors::render_cameras(&stat, script, &trace, sensors, &rig, |f| {
                        let last = f.frame >= 4;
                        files.frame(f).expect("sensor files");
                        if last { Err(()) } else { Ok(()) }
                    });
                    let mut rows = files.finish().expect("sensor files");
                    if sensors.lidar.enabled {
                        let mut lidar =
                            ClipLidarWriter::new(&layout, &script.clip_id, &sensors.lidar, &plan.spec.output, &meta)
                                .expect("lidar writer");
                        let _ = sensors::scan_lidar(&stat, script, &trace, &sensors.lidar, &rig, |t| {
                            let last = t.frame >= 4;
                            lidar.tick(t).expect("lidar files");
                            if last { Err(()) } else { Ok(()) }
                        });
                        rows.extend(lidar.finish().expect("lidar files"));
                    }
                    for r in rows {
                        hasher.update(format!("{}|{}|{}", r.path, r.bytes, r.sha256).as_bytes());
                    }
                    std::fs::remove_dir_all(&dir).ok();
                }
            }
            hasher.finalize().to_hex().to_string()
        });
        Outcome {
            plan: plan_text,
            tables,
        }
    }

    /// Tries the perturbations of `path`: any valid one that changes the outcome proves the key used.
    fn judge(&self, path: &str, candidates: &[Json], context: &[(&str, Json)]) -> Verdict {
        let with_context = |mut spec: Json| {
            for (p, v) in context {
                *pointer(&mut spec, p) = v.clone();
            }
            spec
        };
        self.sensors
            .set(path.starts_with("sensors.") || path.starts_with("output."));
        let cache = if self.sensors.get() {
            &self.base_sensors
        } else {
            &self.base_tables
        };
        let base_spec = with_context(self.base.clone());
        let base_loaded = self
            .load(&base_spec)
            .unwrap_or_else(|e| panic!("{path}: the context is invalid: {}", e.render_plain(100)));
        let base_plan = self.outcome(&base_loaded, false);
        let mut base_tables = None;
        let mut errors = Vec::new();
        let mut saw_valid = false;
        for value in candidates {
            let mut spec = base_spec.clone();
            *pointer(&mut spec, path) = value.clone();
            match self.load(&spec) {
                Ok(loaded) => {
                    saw_valid = true;
                    if self.outcome(&loaded, false).plan != base_plan.plan {
                        return Verdict::Used;
                    }
                    let base_tables = base_tables.get_or_insert_with(|| {
                        if context.is_empty() {
                            cache.get_or_init(|| self.outcome(&base_loaded, true).tables).clone()
                        } else {
                            self.outcome(&base_loaded, true).tables
                        }
                    });
                    if self.outcome(&loaded, true).tables != *base_tables {
                        return Verdict::Used;
                    }
                }
                Err(e) => {
                    let codes = e.codes();
                    if VALIDATION_KEYS.contains(&path) && codes.iter().any(|c| *c != "pedsynth::spec::not_implemented")
                    {
                        return Verdict::Validation;
                    }
                    errors.push(format!("{value}: {}", e.render_plain(100)));
                }
            }
        }
        if saw_valid {
            Verdict::Ignored
        } else {
            Verdict::Invalid(errors.join("\n"))
        }
    }

    /// A listed not-yet key: every value that would change what is generated (all but a sensor's
    /// `enabled: false`) is reported as not implemented.
    fn reported(&self, path: &str, candidates: &[Json]) -> Result<(), String> {
        for value in candidates {
            if path.ends_with(".enabled") && value == &json!(false) {
                continue;
            }
            let mut spec = self.base.clone();
            *pointer(&mut spec, path) = value.clone();
            match self.load(&spec) {
                Err(e) if e.codes().contains(&"pedsynth::spec::not_implemented") => {}
                Ok(_) => return Err(format!("{path} = {value} is accepted without a report")),
                Err(e) => return Err(format!("{path} = {value}: {}", e.render_plain(100))),
            }
        }
        Ok(())
    }
}

/// Keys of enums with a single variant in this version (no other value to try).
const SINGLE_VALUED: &[&str] = &["output.dvs_encoding"];

/// Keys whose only effect is on validation: the sanity limits, a gate stage that cannot be turned off, and the
/// cap on allocated crossers (every valid spec allocates at most the cap, so it bounds the reachable target).
const VALIDATION_KEYS: &[&str] = &[
    "limits.max_clips",
    "limits.max_image_pixels",
    "limits.max_dataset_bytes",
    "annotations.visibility.require_in_front",
    "crossing.layers.crosser_allocation.max_crosser_ratio",
];

/// Keys whose only effect is on what the exporters read (not the plan or the tables): the walk checks that
/// their values load, and tests/it/calibrate.rs that they change an export.
const EXPORT_KEYS: &[&str] = &["annotations.export_box"];

/// Settings applied to both sides of a comparison, so that a key's effect can show (an event the key shapes must
/// happen in the walk's few clips, or another key must make the perturbation valid).
fn context(path: &str) -> Vec<(&'static str, Json)> {
    match path {
        "crossing.retreat.speed_mps" | "crossing.retreat.window_fraction" => {
            vec![("crossing.retreat.probability", json!(1.0))]
        }
        "crossing.patience.sudden_crossing_probability" => [
            "business_person",
            "casual_person",
            "elderly_person",
            "parent_with_child",
            "young_person",
        ]
        .iter()
        .map(|a| {
            let p: &'static str = Box::leak(format!("pedestrians.archetypes.{a}.patience_s").into_boxed_str());
            (p, json!([0.5, 1.0]))
        })
        .collect(),
        // With layer 1 off, only the baseline crosses: the target must be the baseline's; thirty pedestrians per
        // clip make layer 1 allocate one crosser at a target just above it.
        "crossing.layers.crosser_allocation.enabled" => vec![
            ("crossing.target_ratio", json!(0.105)),
            ("pedestrians.per_clip", json!([30, 30])),
        ],
        // Beyond 50 m the default 8 px width already rejects everyone: the height shows with a lower width.
        // The JPEG quality shows in JPEG files only.
        "output.jpeg_quality" => vec![("output.rgb_encoding", json!("jpeg"))],
        "output.h264_qp" => vec![("output.rgb_encoding", json!("h264"))],
        // Motion blur shows where auto-exposure opens the shutter past 2 ms (at night), after a clip's first frame.
        "sensors.rgb.motion_blur.shutter_ms" => vec![("dataset.weathers", json!(["night_clear"]))],
        p if p.starts_with("sensors.rgb.motion_blur.") => vec![
            ("dataset.weathers", json!(["night_clear"])),
            ("sensors.rgb.motion_blur.shutter_ms", json!(2.0)),
        ],
        // Emergency vehicles exist only when enabled, in the walk's few clips only with a large share.
        "traffic.emergency.enabled" => vec![("traffic.emergency.clip_share", json!(1.0))],
        "traffic.emergency.clip_share" => vec![("traffic.emergency.enabled", json!(true))],
        // A kind's share shows in the exact quota of a few emergency clips per stratum.
        p if p.starts_with("traffic.emergency.mix.") => vec![
            ("traffic.emergency.enabled", json!(true)),
            ("traffic.emergency.clip_share", json!(1.0)),
            ("dataset.clips.count", json!(5)),
        ],
        p if p.starts_with("traffic.emergency.") => vec![
            ("traffic.emergency.enabled", json!(true)),
            ("traffic.emergency.clip_share", json!(1.0)),
        ],
        // Red-light violators exist only where lights run.
        p if p.starts_with("pedestrians.archetypes.") && p.ends_with(".red_light_violation_probability") => {
            vec![("traffic.signals.enabled", json!(true))]
        }
        // The lights' timing shows only where they run.
        p if p.starts_with("traffic.signals.") && p != "traffic.signals.enabled" => {
            vec![("traffic.signals.enabled", json!(true))]
        }
        // Cyclists exist only with a count above 0; overtakes show with several per clip; a swerve needs a
        // pedestrian standing on the riding line: cyclists hugging the curb meet those waiting there.
        "traffic.cyclists.swerve_m" => vec![
            ("traffic.cyclists.per_clip", json!([8, 8])),
            ("traffic.cyclists.edge_offset_m", json!(0.3)),
        ],
        p if p.starts_with("traffic.cyclists.") && p != "traffic.cyclists.per_clip" => {
            vec![("traffic.cyclists.per_clip", json!([5, 5]))]
        }
        // A nod shows only where a crosser acknowledges a yielding driver in an annotated frame: with parked cars
        // hiding some pedestrians, the walk's few clips no longer have one; every crosser acknowledging makes more.
        "pedestrians.gestures.nod_share" => vec![("pedestrians.gestures.acknowledge_probability", json!(1.0))],
        // The stopped-ego rule applies only to crossers that wait for the ego to come near.
        "crossing.scenario.crosser_stopped_ego_within_m" => {
            vec![("crossing.scenario.crosser_ego_within_m", json!([5, 8]))]
        }
        // The lookahead's predicted position matters only in in-road conflicts: more pedestrians make some.
        "crossing.lookahead.prediction_s" => vec![("pedestrians.per_clip", json!([20, 20]))],
        "annotations.visibility.min_box_far_px.height_px" => {
            vec![("annotations.visibility.min_box_far_px.width_px", json!(2.0))]
        }
        _ => Vec::new(),
    }
}

fn pointer<'a>(v: &'a mut Json, path: &str) -> &'a mut Json {
    path.split('.').fold(v, |v, k| &mut v[k])
}

/// Every leaf of a spec's JSON: objects are descended; scalars and lists are leaves.
fn leaves(v: &Json, path: String, out: &mut Vec<(String, Json)>) {
    match v {
        Json::Object(map) => {
            for (k, x) in map {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                leaves(x, p, out);
            }
        }
        _ => out.push((path, v.clone())),
    }
}

/// Values to try for a leaf, in order (the first that validates is used).
fn candidates(path: &str, value: &Json, parent: &Json) -> Vec<Json> {
    // A refractory period shows only when a pixel fires twice within it: longer than a frame interval.
    if path == "sensors.dvs.refractory_period_ns" {
        return vec![json!(20_000_000)];
    }
    let key = path.rsplit('.').next().unwrap_or(path);
    let parent_key = path.rsplit('.').nth(1).unwrap_or("");
    // Shares of a mix (a mapping of numbers only): swap with a sibling of another value (the sum stays 1).
    let numbers_only = parent.as_object().is_some_and(|m| m.values().all(Json::is_number));
    if (parent_key == "mix" || parent_key.ends_with("_mix")) && numbers_only {
        let here = value.as_f64().unwrap_or(0.0);
        let mut out = Vec::new();
        if let Json::Object(siblings) = parent {
            for (k, v) in siblings {
                if k != key && v.as_f64().is_some_and(|x| (x - here).abs() > 1e-9) {
                    out.push(json!({"__swap__": k}));
                }
            }
        }
        return out;
    }
    // Sanity limits: so low that the walk's spec exceeds them.
    if path.starts_with("limits.") {
        return vec![json!(1)];
    }
    match value {
        Json::Bool(b) => vec![json!(!b)],
        Json::String(s) => {
            let all: &[&str] = match key {
                "per" => &["weather", "town_and_weather"],
                "default_split" => &["train", "val", "test"],
                "body" => &["adult", "child", "adult_with_child"],
                "pose_format" => &["coco17", "openpose18"],
                "export_box" => &["tight", "annotator"],
                "compression" => &["zstd", "snappy", "none"],
                "rgb_encoding" => &["png", "jpeg", "h264"],
                "depth_encoding" => &["mm_u16", "carla_rgb24"],
                "format" => &["parquet", "carla_bin"],
                "dvs_encoding" => &["parquet"],
                "name" => &["walk", "walk_renamed"],
                "license" => &["unknown", "cc-by-4.0"],
                _ if parent_key == "splits" => &["train", "val", "test"],
                _ => &[],
            };
            all.iter().filter(|x| **x != s).map(|x| json!(x)).collect()
        }
        Json::Number(n) => {
            let v = n.as_f64().unwrap_or(0.0);
            let int = n.is_u64() || n.is_i64();
            let mut out = vec![];
            if !int && (0.0..=1.0).contains(&v) {
                out.extend([json!(0.0), json!(1.0)]);
            }
            for f in [0.5, 1.5, 0.25, 2.0, 0.9, 1.1] {
                let x = if v == 0.0 { f - 0.2 } else { v * f };
                out.push(if int {
                    json!(x.round().max(0.0) as u64)
                } else {
                    json!(x)
                });
            }
            if int {
                out.push(json!(n.as_u64().unwrap_or(0) + 1));
            }
            out.retain(|x| x != value);
            out
        }
        Json::Array(items) => {
            let nums: Vec<f64> = items.iter().filter_map(Json::as_f64).collect();
            if nums.len() == items.len() && !nums.is_empty() {
                let int = items.iter().all(|i| i.is_u64());
                let mut out = Vec::new();
                if nums.len() == 2 {
                    let (a, b) = (nums[0], nums[1]);
                    for (x, y) in [
                        (a, (a + b) / 2.0),
                        ((a + b) / 2.0, b),
                        (a * 0.5, b),
                        (a, b * 1.5),
                        (a + 1.0, b + 2.0),
                    ] {
                        out.push(if int {
                            json!([x.round() as u64, y.round() as u64])
                        } else {
                            json!([x, y])
                        });
                    }
                } else {
                    out.push(json!(nums[..nums.len() - 1]));
                    out.push(json!(nums.iter().map(|x| x * 2.0).collect::<Vec<_>>()));
                }
                out.retain(|x| x != value);
                out
            } else if key == "towns" {
                vec![json!(items[..items.len() - 1])]
            } else if key == "weathers" {
                vec![json!(["dawn"]), json!(["night_rainy"])]
            } else {
                Vec::new()
            }
        }
        _ => Vec::new(),
    }
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn every_key_changes_the_plan_or_the_tables_or_is_reported_as_not_implemented() {
    let map = common::carla_map("Town01");
    let base_yaml = format!(
        "version: 1\n\
         dataset:\n  name: walk\n  seed: 3\n  clips: {{count: 1, per: town_and_weather}}\n  weathers: [clear_noon]\n  \
         clip_duration_s: [12, 13]\n  towns: [town01_like, town02_like, town03_like, town05_like, \
         {{name: carla_town01, opendrive: {:?}}}]\n",
        map.display().to_string()
    );
    let base_dir = Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf();
    let loaded = spec::load_bytes(base_yaml.as_bytes(), "walk.yaml", &base_dir, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{}", e.render_plain(100)));
    let towns = pedsynth::dataset::inputs::load_towns(&loaded).expect("towns");
    let walker = Walker {
        base: serde_json::to_value(&loaded.spec).expect("json"),
        base_tables: std::cell::OnceCell::new(),
        base_sensors: std::cell::OnceCell::new(),
        sensors: std::cell::Cell::new(false),
        towns,
        base_dir,
    };

    let mut all = Vec::new();
    leaves(&walker.base, String::new(), &mut all);
    let mut ignored = Vec::new();
    let mut invalid = Vec::new();
    let mut counts = BTreeMap::new();
    for (path, value) in &all {
        if path == "version" {
            continue; // the format marker: validation accepts 1 only
        }
        if SINGLE_VALUED.contains(&path.as_str()) {
            continue; // nothing to perturb: the only value there is
        }
        let parent_path = path.rsplit_once('.').map_or("", |p| p.0);
        let parent = parent_path
            .split('.')
            .filter(|k| !k.is_empty())
            .fold(&walker.base, |v, k| &v[k]);
        let mut cands = candidates(path, value, parent);
        // A swap of mix shares is spelled out here, where the whole mix is at hand.
        for c in &mut cands {
            if let Some(other) = c.get("__swap__").and_then(Json::as_str) {
                let mut mix = parent.clone();
                let (a, b) = (mix[path.rsplit('.').next().unwrap()].clone(), mix[other].clone());
                mix[path.rsplit('.').next().unwrap()] = b;
                mix[other] = a;
                *c = json!({"__mix__": mix});
            }
        }
        let (target, values) = if cands.first().is_some_and(|c| c.get("__mix__").is_some()) {
            let mixes: Vec<Json> = cands.iter().filter_map(|c| c.get("__mix__").cloned()).collect();
            (parent_path, mixes)
        } else {
            (path.as_str(), cands)
        };
        let listed = NOT_YET
            .iter()
            .any(|n| path == n.path || path.starts_with(&format!("{}.", n.path)));
        let verdict = if listed {
            match walker.reported(target, &values) {
                Ok(()) => Verdict::NotImplemented,
                Err(e) => Verdict::Invalid(e),
            }
        } else if EXPORT_KEYS.contains(&path.as_str()) {
            let mut spec = walker.base.clone();
            let loads = values.iter().any(|v| {
                *pointer(&mut spec, target) = v.clone();
                walker.load(&spec).is_ok()
            });
            if loads {
                Verdict::Exported
            } else {
                Verdict::Invalid("no candidate value loads".to_owned())
            }
        } else {
            walker.judge(target, &values, &context(path))
        };
        let name = match verdict {
            Verdict::Used => "used",
            Verdict::Exported => "used by the exporters",
            Verdict::NotImplemented => "not implemented (reported)",
            Verdict::Validation => "validation",
            Verdict::Ignored => {
                ignored.push(path.clone());
                "IGNORED"
            }
            Verdict::Invalid(e) => {
                invalid.push(format!("{path}: {e}"));
                "no valid perturbation"
            }
        };
        eprintln!("{path}: {name}");
        *counts.entry(name).or_insert(0) += 1;
    }
    eprintln!("{counts:?}");
    assert!(
        ignored.is_empty() && invalid.is_empty(),
        "keys accepted but without any effect (use them, or list them in spec::not_yet::NOT_YET): {ignored:#?}\n\
         keys the walk could not perturb to a valid value (add a candidate or a context): {invalid:#?}"
    );
    assert!(counts["used"] > 100, "{counts:?}");
}
