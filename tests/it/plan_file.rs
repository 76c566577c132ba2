//! Plan files are input too (issue 16): `generate PLAN.json` reads a plan losslessly (every float bit for bit,
//! so a plan file and its spec generate the same bytes), and refuses a plan that is not exactly what its spec
//! compiles to — an edited lane index, count, range or seed, an edited spec, a spec hash that does not match, a
//! map that changed since planning (town fingerprint), unknown or repeated clips, another format or pedsynth
//! version — naming every problem by its JSON path, exit 2, without writing anything. A plan of a subset of
//! the clips (`plan --emit --only`) is accepted, and no plan holds an absolute path.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn pedsynth(args: &[&std::ffi::OsStr]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{stderr}");
    (o.status.code().unwrap_or(-1), stderr)
}

/// `pedsynth plan SPEC --emit PLAN [--only ID] --set ...`.
fn emit(spec: &Path, plan: &Path, extra: &[&str]) {
    let mut args: Vec<std::ffi::OsString> = vec!["plan".into(), spec.into(), "--emit".into(), plan.into()];
    args.extend(extra.iter().map(|a| a.into()));
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let (code, stderr) = pedsynth(&refs);
    assert_eq!(code, 0, "{stderr}");
}

/// `generate PLAN --out OUT` on an edited copy of `plan`; returns the exit code and stderr, and checks that
/// nothing was written.
fn generate_edited(tmp: &Path, plan: &Value, edit: impl FnOnce(&mut Value)) -> (i32, String) {
    let mut edited = plan.clone();
    edit(&mut edited);
    let path = tmp.join("edited.json");
    std::fs::write(&path, serde_json::to_string(&edited).unwrap()).unwrap();
    let out = tmp.join("edited-out");
    let (code, stderr) = pedsynth(&[
        "generate".as_ref(),
        path.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
    ]);
    assert!(!out.exists(), "a refused plan writes nothing");
    (code, stderr)
}

fn quickstart() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml")
}

#[test]
fn plan_files_are_read_losslessly_and_edited_plans_are_refused_by_path() {
    let tmp = common::Scratch::new("planfile");
    let plan_path = tmp.path().join("plans/plan.json");
    std::fs::create_dir_all(plan_path.parent().unwrap()).unwrap();
    emit(&quickstart(), &plan_path, &["--set", "dataset.clips.count=3"]);
    let text = std::fs::read_to_string(&plan_path).unwrap();
    assert!(!text.contains("\"/"), "no string of the plan is an absolute path");

    // Lossless: the plan read back equals the compiled plan, every float bit for bit.
    let (plan_read, _) = pedsynth::dataset::inputs::read_plan(&plan_path).unwrap_or_else(|e| panic!("{}", e.render()));
    let options = pedsynth::spec::LoadOptions {
        overrides: vec!["dataset.clips.count=3".into()],
        allow_large: false,
        profile: None,
    };
    let (_, compiled) = pedsynth::dataset::inputs::compile_plan(&quickstart(), &options, None).unwrap();
    assert_eq!(
        plan_read.clips, compiled.clips,
        "a plan file holds the compiled clips exactly"
    );
    assert_eq!(plan_read.towns, compiled.towns);

    let plan: Value = serde_json::from_str(&text).unwrap();
    let t = tmp.path().join("plans");
    let refused = |edit: &dyn Fn(&mut Value), expect: &[&str]| {
        let (code, stderr) = generate_edited(&t, &plan, |v| edit(v));
        assert_eq!(code, 2, "{stderr}");
        for e in expect {
            assert!(stderr.contains(e), "expected `{e}` in:\n{stderr}");
        }
    };
    // A lane index, a count, a range, a seed.
    refused(
        &|v| v["clips"][0]["vehicles"][0]["route"]["lanes"][0] = 99_999.into(),
        &[
            "pedsynth::plan::invalid",
            "clips[0].vehicles[0].route.lanes[0]: 99999, but the spec compiles to",
        ],
    );
    refused(
        &|v| {
            v["clips"][1]["pedestrians"].as_array_mut().unwrap().pop();
        },
        &["clips[1].pedestrians: "],
    );
    refused(
        &|v| v["clips"][2]["frame_count"] = 4_000_000_000u64.into(),
        &["clips[2].frame_count: 4000000000"],
    );
    refused(&|v| v["clips"][0]["seed"] = 7.into(), &["clips[0].seed: 7"]);
    // Several problems at once, each named.
    refused(
        &|v| {
            v["clips"][0]["seed"] = 7.into();
            v["clips"][2]["pedestrians"][0]["base_speed_mps"] = 9.5.into();
        },
        &[
            "2 problems",
            "clips[0].seed",
            "clips[2].pedestrians[0].base_speed_mps: 9.5",
        ],
    );
    // Unknown and repeated clips.
    refused(
        &|v| v["clips"][1]["clip_id"] = "town01_like-clear_noon-0099".into(),
        &["its spec makes no clip `town01_like-clear_noon-0099`"],
    );
    refused(
        &|v| {
            let first = v["clips"][0].clone();
            v["clips"].as_array_mut().unwrap().push(first);
        },
        &["appears twice"],
    );
    // The spec: an invalid value is diagnosed as in a spec file; a valid edit no longer matches the hash.
    refused(
        &|v| v["spec"]["crossing"]["target_ratio"] = 7.into(),
        &["pedsynth::spec::out_of_range", "(its spec)"],
    );
    refused(
        &|v| v["spec"]["dataset"]["seed"] = 12_345.into(),
        &["its spec does not hash to its spec_hash"],
    );
    refused(
        &|v| v["spec_hash"] = "00".into(),
        &["its spec does not hash to its spec_hash"],
    );
    // Versions.
    refused(
        &|v| v["format_version"] = 2.into(),
        &["pedsynth::plan::unsupported_version", "plan format 2"],
    );
    refused(
        &|v| v["pedsynth_version"] = "0.0.1".into(),
        &["pedsynth::plan::unsupported_version", "made by pedsynth 0.0.1"],
    );
    // Not a plan at all.
    refused(&|v| *v = Value::from(vec![1, 2, 3]), &["not a pedsynth plan"]);

    // A subset of the clips (`--only`) is a valid plan.
    let only = t.join("only.json");
    emit(
        &quickstart(),
        &only,
        &[
            "--set",
            "dataset.clips.count=3",
            "--only",
            "town01_like-clear_noon-0001",
        ],
    );
    pedsynth::dataset::inputs::read_plan(&only).unwrap_or_else(|e| panic!("{}", e.render()));
}

#[test]
fn a_plan_made_for_another_version_of_a_map_is_refused() {
    let tmp = common::Scratch::new("planmap");
    let map = tmp.path().join("maps/town.xodr");
    std::fs::create_dir_all(map.parent().unwrap()).unwrap();
    let (code, stderr) = pedsynth(&[
        "town".as_ref(),
        "export".as_ref(),
        "town01_like".as_ref(),
        "--xodr".as_ref(),
        map.as_os_str(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let spec = tmp.path().join("spec.yaml");
    std::fs::write(
        &spec,
        "version: 1\ndataset:\n  name: mapped\n  towns: [{name: mapped, opendrive: maps/town.xodr}]\n  \
         weathers: [clear_noon]\n  clips: {count: 2, per: weather}\n  clip_duration_s: [6, 8]\n",
    )
    .unwrap();
    // Planned from another directory: the plan records the spec's directory relative to itself.
    let plan_path = tmp.path().join("plans/plan.json");
    std::fs::create_dir_all(plan_path.parent().unwrap()).unwrap();
    emit(&spec, &plan_path, &[]);
    let text = std::fs::read_to_string(&plan_path).unwrap();
    assert!(
        text.contains("\"spec_dir\": \"..\"") || text.contains("\"spec_dir\":\"..\""),
        "relative spec_dir"
    );
    pedsynth::dataset::inputs::read_plan(&plan_path).unwrap_or_else(|e| panic!("{}", e.render()));

    // The map changes (one lane 10 cm wider): the plan is refused, naming the town.
    let xodr = std::fs::read_to_string(&map).unwrap();
    let i = xodr.find("<width sOffset=\"0\" a=\"").expect("a lane width") + "<width sOffset=\"0\" a=\"".len();
    let j = i + xodr[i..].find('"').unwrap();
    let width: f64 = xodr[i..j].parse().unwrap();
    std::fs::write(&map, format!("{}{}{}", &xodr[..i], width + 0.1, &xodr[j..])).unwrap();
    let out = tmp.path().join("out");
    let (code, stderr) = pedsynth(&[
        "generate".as_ref(),
        plan_path.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("town `mapped` differs from the map the plan was made for"),
        "{stderr}"
    );
    assert!(!out.exists());
}
