//! `pedsynth verify DIR` passes a freshly generated dataset and names every kind of damage — a changed table, a
//! changed or missing sensor file, a stray file, an unfinished clip, parked cars numbered out of order — with exit
//! 2, and `stats` and the exporters refuse such a dataset; a second `generate` into a directory another one is
//! writing into refuses (the OS lock on `.pedsynth.lock`) and succeeds once the lock is free, reporting progress
//! as JSON lines when asked.

use crate::common;

use std::path::{Path, PathBuf};

fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

use crate::common::pedsynth;

fn verify(dir: &Path) -> (Option<i32>, String, String) {
    pedsynth(&["verify".as_ref(), dir.as_os_str()])
}

/// RGB only, one second per clip: small, but with sensor files to check.
const SMALL_RGB: [&str; 7] = [
    "sensors.depth.enabled=false",
    "sensors.semantic.enabled=false",
    "sensors.instance.enabled=false",
    "sensors.dvs.enabled=false",
    "sensors.lidar.enabled=false",
    "dataset.clip_duration_s=[1, 1]",
    "sensors.rgb.width_px=320",
];

#[test]
fn verify_passes_a_fresh_dataset_and_names_every_kind_of_damage() {
    let tmp = common::Scratch::new("verify");
    let ds = tmp.path().join("ds");
    let mut overrides = SMALL_RGB.to_vec();
    overrides.push("sensors.rgb.height_px=180");
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &overrides, &ds, Some(2));
    assert_eq!(code, 0, "{stderr}");
    let (code, stdout, stderr) = verify(&ds);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("OK — 2 clips complete; 24 table files"), "{stdout}");
    assert!(stdout.contains("sensor files"), "{stdout}");

    let damage = |what: &str, path: &Path, change: &dyn Fn(&Path), expect: &str| {
        let original = std::fs::read(path).ok();
        change(path);
        let (code, _, stderr) = verify(&ds);
        assert_eq!(code, Some(2), "{what}: {stderr}");
        assert!(stderr.contains(expect), "{what}: expected {expect:?} in\n{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        match original {
            Some(bytes) => std::fs::write(path, bytes).unwrap(),
            None => {
                let _ = std::fs::remove_file(path);
            }
        }
        let (code, _, stderr) = verify(&ds);
        assert_eq!(code, Some(0), "{what} undone: {stderr}");
    };
    let flip = |p: &Path| {
        let mut b = std::fs::read(p).unwrap();
        let mid = b.len() / 2;
        b[mid] ^= 0x55;
        std::fs::write(p, b).unwrap();
    };
    let frame = ds.join("sensors/rgb/town01_like-clear_noon-0001/000003.png");
    assert!(frame.is_file(), "{}", frame.display());
    damage("a changed image", &frame, &flip, "its SHA-256 differs from the index's");
    damage(
        "a missing image",
        &frame,
        &|p| std::fs::remove_file(p).unwrap(),
        "000003.png: No such file",
    );
    damage(
        "a changed table",
        &ds.join("tables/tracks/town01_like-clear_noon-0000.parquet"),
        &flip,
        "its blake3 differs from the manifest's",
    );
    damage(
        "a stray table file",
        &ds.join("tables/frames/town09_like-night-0000.parquet"),
        &|p| std::fs::write(p, b"x").unwrap(),
        "clip town09_like-night-0000 is not in the manifest",
    );
    damage(
        "a leftover temporary",
        &ds.join("tables/frames/.town01_like-clear_noon-0000.parquet.tmp-123"),
        &|p| std::fs::write(p, b"x").unwrap(),
        "not a table file",
    );
    let manifest = ds.join("manifest.json");
    damage(
        "an unfinished clip",
        &manifest,
        &|p| {
            let t = std::fs::read_to_string(p).unwrap();
            std::fs::write(p, t.replacen("\"status\": \"done\"", "\"status\": \"pending\"", 1)).unwrap();
        },
        "1 of 2 clips are not generated yet",
    );

    // stats and the exporters run the same checks before reading.
    flip(&ds.join("tables/annotations/town01_like-clear_noon-0001.parquet"));
    let (code, _, stderr) = pedsynth(&["stats".as_ref(), ds.as_os_str()]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("blake3 differs") && stderr.contains("pedsynth verify"),
        "{stderr}"
    );
    let (code, _, stderr) = pedsynth(&[
        "export".as_ref(),
        "jaad".as_ref(),
        ds.as_os_str(),
        "--out".as_ref(),
        tmp.path().join("jaad").as_os_str(),
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("blake3 differs"), "{stderr}");

    // Not a dataset at all.
    let (code, _, stderr) = verify(tmp.path());
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("a pedsynth dataset"), "{stderr}");
}

#[test]
fn a_second_generate_into_a_locked_directory_refuses_and_the_lock_frees_with_its_holder() {
    let tmp = common::Scratch::new("lock");
    let ds = tmp.path().join("ds");
    std::fs::create_dir_all(&ds).unwrap();
    // Another process's lock, as a running generate holds it.
    let holder = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(ds.join(".pedsynth.lock"))
        .unwrap();
    holder.lock().unwrap();
    let mut args: Vec<std::ffi::OsString> = vec![
        "generate".into(),
        spec("quickstart.yaml").into(),
        "--out".into(),
        ds.clone().into(),
        "--quiet".into(),
    ];
    for o in common::NO_SENSORS {
        args.push("--set".into());
        args.push(o.into());
    }
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let (code, _, stderr) = pedsynth(&refs);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("another `pedsynth generate` is writing into"),
        "{stderr}"
    );
    assert!(
        !ds.join("manifest.json").exists(),
        "nothing written under someone else's lock"
    );
    drop(holder);
    let mut json_args = refs.clone();
    json_args.retain(|a| *a != std::ffi::OsStr::new("--quiet"));
    json_args.extend([std::ffi::OsStr::new("--progress"), std::ffi::OsStr::new("json")]);
    let (code, _, stderr) = pedsynth(&json_args);
    assert_eq!(code, Some(0), "{stderr}");
    // --progress json: one JSON object per clip on stderr, for cluster logs.
    let lines: Vec<serde_json::Value> = stderr
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.len(), 2, "{stderr}");
    assert!(
        lines
            .iter()
            .all(|l| l["event"] == "clip_done" && l["total"] == 2 && l["frames"].as_u64() > Some(0))
    );
    assert_eq!(lines[1]["done"], 2);
    let (code, _, stderr) = verify(&ds);
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn verify_names_parked_cars_numbered_out_of_order() {
    use arrow_array::{Array, RecordBatch, UInt32Array};
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    use pedsynth::dataset::write::tables::{FileMeta, parquet_bytes};
    use std::sync::Arc;
    let tmp = common::Scratch::new("verify-parked");
    let ds = tmp.path().join("ds");
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &common::NO_SENSORS, &ds, None);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(verify(&ds).0, Some(0));
    // Swap the first two parked cars' ids in one clip's table, writing it as the writer does and updating the
    // manifest's hash, so that only the rows' check can find it.
    let clip = "town01_like-clear_noon-0000";
    let path = ds.join(format!("tables/parked_cars/{clip}.parquet"));
    let old = std::fs::read(&path).unwrap();
    let batch = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(&path).unwrap())
        .unwrap()
        .build()
        .unwrap()
        .next()
        .expect("a batch")
        .unwrap();
    assert!(batch.num_rows() >= 2, "{} parked cars", batch.num_rows());
    let ids = batch.column_by_name("parked_car").unwrap();
    let ids = ids.as_any().downcast_ref::<UInt32Array>().unwrap();
    let mut swapped: Vec<u32> = ids.values().to_vec();
    swapped.swap(0, 1);
    let k = batch.schema().index_of("parked_car").unwrap();
    let mut columns = batch.columns().to_vec();
    columns[k] = Arc::new(UInt32Array::from(swapped));
    let changed = RecordBatch::try_new(batch.schema(), columns).unwrap();
    let manifest_path = ds.join("manifest.json");
    let manifest = std::fs::read_to_string(&manifest_path).unwrap();
    let spec_hash = serde_json::from_str::<serde_json::Value>(&manifest).unwrap()["spec_hash"]
        .as_str()
        .unwrap()
        .to_owned();
    let meta = FileMeta { spec_hash };
    let bytes = parquet_bytes(&changed, &Default::default(), &meta, "parked_cars", clip).unwrap();
    std::fs::write(&path, &bytes).unwrap();
    let (from, to) = (
        blake3::hash(&old).to_hex().to_string(),
        blake3::hash(&bytes).to_hex().to_string(),
    );
    assert!(manifest.contains(&from));
    std::fs::write(&manifest_path, manifest.replace(&from, &to)).unwrap();
    let (code, _, stderr) = verify(&ds);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("tables/parked_cars/{clip}.parquet: row 0 is parked car 1")),
        "{stderr}"
    );
}
