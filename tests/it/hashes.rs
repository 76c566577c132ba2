//! Committed BLAKE3 hashes of what pedsynth makes, so that "the output did not change" is checked, not believed:
//!
//! - `tests/golden/hashes/frames.txt`: one rendered frame per weather (the 12 weathers of
//!   `tests/data/specs/weathers.yaml`, each clip's busiest annotated frame at 640 × 360): RGB, depth,
//!   semantic and instance buffers;
//! - `tests/golden/hashes/tables.txt`: every Parquet table file of the quickstart (tables only).
//!
//! CI checks them twice: in the normal (AVX2) build and in a build for any x86-64 CPU (`RUSTFLAGS="-C
//! target-cpu=x86-64"`), which must give the same bytes (ARCHITECTURE.md, the renderer's invariant). A change
//! of output re-mints them only with a stated reason, which the file keeps:
//! `PEDSYNTH_HASH_REASON="why" INSTA_UPDATE=always cargo test --test it hashes`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::common;
use pedsynth::sensors;
use pedsynth::sim::{self, rig::Rig};

fn golden(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden/hashes")
        .join(name)
}

/// Compares `lines` (`key hash`, sorted) with the golden file, or re-mints it (`INSTA_UPDATE=always`) with the
/// reason in `PEDSYNTH_HASH_REASON`, appended to the reasons the file already records.
fn check(name: &str, what: &str, lines: &BTreeMap<String, String>) {
    let path = golden(name);
    let text = std::fs::read_to_string(&path).unwrap_or_default();
    let (header, committed): (Vec<&str>, Vec<&str>) = text.lines().partition(|l| l.starts_with('#'));
    let ours: Vec<String> = lines.iter().map(|(k, h)| format!("{k} {h}")).collect();
    if ours.iter().map(String::as_str).eq(committed.iter().copied()) {
        return;
    }
    if std::env::var("INSTA_UPDATE").is_ok_and(|v| v == "always") {
        let reason = std::env::var("PEDSYNTH_HASH_REASON").unwrap_or_default();
        assert!(
            !reason.trim().is_empty(),
            "{name}: the hashes changed; re-minting needs a stated reason in PEDSYNTH_HASH_REASON"
        );
        let mut out: Vec<String> = if header.is_empty() {
            vec![
                format!("# BLAKE3 of {what}."),
                "# Re-mint: PEDSYNTH_HASH_REASON=\"why\" INSTA_UPDATE=always cargo test --test it hashes".to_owned(),
            ]
        } else {
            header.iter().map(|l| l.to_string()).collect()
        };
        out.push(format!("# re-minted: {}", reason.trim()));
        out.extend(ours);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, out.join("\n") + "\n").unwrap();
        return;
    }
    let committed: BTreeMap<&str, &str> = committed.iter().filter_map(|l| l.split_once(' ')).collect();
    let mut differ: Vec<String> = lines
        .iter()
        .filter(|(k, h)| committed.get(k.as_str()) != Some(&h.as_str()))
        .map(|(k, h)| format!("{k}: {h} (committed: {})", committed.get(k.as_str()).unwrap_or(&"none")))
        .collect();
    differ.extend(
        committed
            .keys()
            .filter(|k| !lines.contains_key(**k))
            .map(|k| format!("{k}: no longer made")),
    );
    panic!(
        "{} differ from {} (a change of output: re-mint with a reason, see tests/it/hashes.rs):\n{}",
        what,
        path.display(),
        differ.join("\n")
    );
}

#[test]
fn a_rendered_frame_per_weather_hashes_as_committed() {
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/specs/weathers.yaml");
    let options = pedsynth::spec::LoadOptions {
        overrides: ["sensors.rgb.width_px=640", "sensors.rgb.height_px=360"]
            .map(String::from)
            .to_vec(),
        allow_large: false,
        profile: None,
    };
    let (_, towns, plan) =
        pedsynth::dataset::inputs::plan_spec_file(&spec, &options).unwrap_or_else(|e| panic!("{}", e.render()));
    assert_eq!(plan.clips.len(), 12, "one clip per weather");
    let rig = Rig::from_spec(&plan.spec.sensors);
    let mut lines = BTreeMap::new();
    for script in &plan.clips {
        let net = &towns[&script.town].network;
        let trace = sim::simulate(script, &plan.sim, net);
        let ann = sensors::observe(script, &trace, &plan.spec, &rig, net).annotations;
        let mut counts = vec![0u32; trace.frame_count as usize];
        for r in &ann.rows {
            counts[r.frame as usize] += 1;
        }
        // The busiest frame, the earliest of equals.
        let frame = (0..counts.len())
            .max_by_key(|&f| (counts[f], std::cmp::Reverse(f)))
            .unwrap_or(0) as u32;
        let img = sensors::render_frame(script, &trace, &rig, net, frame);
        let mut h = blake3::Hasher::new();
        h.update(&img.rgb);
        for d in &img.depth_m {
            h.update(&d.to_le_bytes());
        }
        h.update(&img.semantic);
        for i in &img.instance {
            h.update(&i.to_le_bytes());
        }
        lines.insert(format!("{}@{frame}", script.weather), h.finalize().to_hex().to_string());
    }
    check(
        "frames.txt",
        "one rendered frame per weather (RGB, depth, semantic, instance)",
        &lines,
    );
}

#[test]
fn the_quickstart_tables_hash_as_committed() {
    let scratch = common::Scratch::new("hashes");
    let out = scratch.path().join("quickstart");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let (code, _, stderr) = common::generate(&spec, &common::NO_SENSORS, &out, None);
    assert_eq!(code, 0, "{stderr}");
    let lines: BTreeMap<String, String> = common::all_files(&out)
        .into_iter()
        .filter(|(path, _)| path.starts_with("tables/"))
        .map(|(path, bytes)| (path, blake3::hash(&bytes).to_hex().to_string()))
        .collect();
    assert!(lines.len() >= 20, "{} table files", lines.len());
    check("tables.txt", "every table file of the quickstart (tables only)", &lines);
}
