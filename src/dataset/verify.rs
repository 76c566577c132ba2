//! `pedsynth verify DIR`: checks a written dataset against its manifest and itself, and lists every problem.
//!
//! - Completeness: the manifest parses and is of this schema version, every planned clip is `done`, every
//!   table file of every clip exists, no table directory holds a file of a clip the manifest does not plan,
//!   and no temporary file of an interrupted write is left.
//! - Integrity: every table file's blake3 equals the manifest's; with `sensors`, every sensor file of the
//!   `sensors` index exists with the indexed size and SHA-256 (the expensive part: it reads every image).
//! - Schemas: every file of a table carries the table's, the clip's, the spec's and the schema version's
//!   metadata, and all files of a table have one Arrow schema (names, types, nullability).
//! - Rows and joins: `clips` has one row; `frames` has `frame_count` rows numbered 0..; `pedestrians` has the
//!   clip's pedestrians; `tracks` one row per pedestrian and frame; `annotations` the clip's annotated samples,
//!   each on a `tracks` row marked annotated and no other; `vehicles` one row per vehicle and frame;
//!   `parked_cars` numbered 0.. with their instance ids.
//!
//! Problems are collected, never panicked on: a dataset is input (another tool may have written or changed it).

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::path::Path;

use arrow_schema::Schema;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use sha2::{Digest, Sha256};

use super::read::tables;
use crate::dataset::write::Layout;
use crate::dataset::write::manifest::Manifest;
use crate::dataset::write::tables::{SCHEMA_VERSION, TABLES};
use crate::error::{Error, code};

/// What `verify` checked, and what it found.
#[derive(Debug, Default)]
pub struct Report {
    pub clips: usize,
    pub table_files: usize,
    pub sensor_files: usize,
    pub sensor_bytes: u64,
    pub problems: Vec<String>,
}

/// How much to check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    /// Everything but the sensor files' contents (what `stats` and the exporters check before reading).
    Tables,
    /// Everything, including the size and SHA-256 of every sensor file.
    Full,
}

/// A file's Arrow schema and key-value metadata (schema-level metadata stripped from the schema).
fn schema_and_meta(path: &Path) -> Result<(Schema, BTreeMap<String, String>, u64), String> {
    let file = File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file).map_err(|e| format!("{}: {e}", path.display()))?;
    let meta: BTreeMap<String, String> = builder
        .metadata()
        .file_metadata()
        .key_value_metadata()
        .map(|kv| {
            kv.iter()
                .filter_map(|e| e.value.clone().map(|v| (e.key.clone(), v)))
                .collect()
        })
        .unwrap_or_default();
    let rows = builder.metadata().file_metadata().num_rows().max(0) as u64;
    let schema = Schema::new(builder.schema().fields().clone());
    Ok((schema, meta, rows))
}

/// Checks the dataset in `dir`. Errors only when `dir` has no readable manifest; every other finding is a
/// problem in the report.
pub fn verify(dir: &Path, depth: Depth) -> Result<Report, Error> {
    let layout = Layout::new(dir);
    let path = layout.manifest();
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::new(
            code::DATASET_INVALID,
            format!("{}: {e} (is {} a pedsynth dataset?)", path.display(), dir.display()),
        )
    })?;
    let manifest = Manifest::parse(&text, &path.display().to_string())?;
    let mut r = Report {
        clips: manifest.clips.len(),
        ..Report::default()
    };
    let p = &mut r.problems;
    if manifest.schema_version != SCHEMA_VERSION {
        p.push(format!(
            "manifest.json: schema version {} (this pedsynth reads {SCHEMA_VERSION}): regenerate the dataset",
            manifest.schema_version
        ));
        return Ok(r);
    }
    let planned: BTreeSet<&str> = manifest.clips.iter().map(|c| c.clip_id.as_str()).collect();
    let pending: Vec<&str> = manifest
        .clips
        .iter()
        .filter(|c| c.status != "done")
        .map(|c| c.clip_id.as_str())
        .collect();
    if !pending.is_empty() {
        p.push(format!(
            "{} of {} clips are not generated yet (first: {}); re-run `pedsynth generate` to finish",
            pending.len(),
            manifest.clips.len(),
            pending[0]
        ));
    }
    // Stray and temporary files in the table directories.
    for table in TABLES {
        let Ok(entries) = std::fs::read_dir(layout.table_dir(table)) else {
            continue;
        };
        let mut names: Vec<String> = entries
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        for name in names {
            match name.strip_suffix(".parquet") {
                Some(clip) if planned.contains(clip) => {}
                Some(clip) => p.push(format!("tables/{table}/{name}: clip {clip} is not in the manifest")),
                None => p.push(format!(
                    "tables/{table}/{name}: not a table file (a temporary left by an interrupted write?)"
                )),
            }
        }
    }
    let mut schemas: BTreeMap<&str, (Schema, String)> = BTreeMap::new();
    for clip in manifest.clips.iter().filter(|c| c.status == "done") {
        let id = clip.clip_id.as_str();
        let mut rows: BTreeMap<&str, u64> = BTreeMap::new();
        let mut ok = true;
        for table in TABLES {
            let file = layout.table(table, id);
            let rel = format!("tables/{table}/{id}.parquet");
            let bytes = match std::fs::read(&file) {
                Ok(b) => b,
                Err(e) => {
                    p.push(format!("{rel}: {e}"));
                    ok = false;
                    continue;
                }
            };
            r.table_files += 1;
            match clip.files.get(table) {
                Some(h) if blake3::hash(&bytes).to_hex().as_str() == h => {}
                Some(_) => {
                    p.push(format!(
                        "{rel}: its blake3 differs from the manifest's (changed after generate)"
                    ));
                    ok = false;
                }
                None => {
                    p.push(format!("{rel}: the manifest records no hash for it"));
                    ok = false;
                }
            }
            match schema_and_meta(&file) {
                Err(e) => {
                    p.push(format!("{rel}: not a readable Parquet file: {e}"));
                    ok = false;
                }
                Ok((schema, meta, n)) => {
                    rows.insert(table, n);
                    for (key, want) in [
                        ("pedsynth.table", table.to_owned()),
                        ("pedsynth.clip_id", id.to_owned()),
                        ("pedsynth.spec_hash", manifest.spec_hash.clone()),
                        ("pedsynth.schema_version", SCHEMA_VERSION.to_string()),
                    ] {
                        if meta.get(key) != Some(&want) {
                            p.push(format!(
                                "{rel}: metadata {key} is {:?}, expected {want:?}",
                                meta.get(key)
                            ));
                            ok = false;
                        }
                    }
                    match schemas.get(table) {
                        None => {
                            schemas.insert(table, (schema, rel));
                        }
                        Some((first, first_rel)) if *first != schema => {
                            p.push(format!("{rel}: its columns differ from {first_rel}'s"));
                            ok = false;
                        }
                        Some(_) => {}
                    }
                }
            }
        }
        if ok {
            if let Err(e) = check_rows(&layout, id, &rows, p) {
                p.push(format!("{id}: {}", e.render()));
            }
            if depth == Depth::Full
                && let Err(e) = check_sensors(&layout, id, &mut r.sensor_files, &mut r.sensor_bytes, p)
            {
                p.push(format!("{id}: {}", e.render()));
            }
        }
    }
    Ok(r)
}

/// Row counts and joins of one clip's tables (their hashes and metadata already checked).
fn check_rows(layout: &Layout, id: &str, rows: &BTreeMap<&str, u64>, p: &mut Vec<String>) -> Result<(), Error> {
    let file = |t: &str| layout.table(t, id);
    let mut info = None;
    for b in tables::read(
        &file("clips"),
        &["frame_count", "pedestrians", "vehicles", "annotated_samples"],
    )? {
        if b.rows() == 1 {
            info = Some((
                u64::from(b.u32s("frame_count")?.value(0)),
                u64::from(b.u32s("pedestrians")?.value(0)),
                u64::from(b.u32s("vehicles")?.value(0)),
                b.u64s("annotated_samples")?.value(0),
            ));
        }
    }
    let Some((frames, peds, vehicles, samples)) = info else {
        p.push(format!("tables/clips/{id}.parquet: {} rows, expected 1", rows["clips"]));
        return Ok(());
    };
    for (table, want) in [
        ("frames", frames),
        ("pedestrians", peds),
        ("tracks", frames * peds),
        ("annotations", samples),
        ("vehicles", frames * vehicles),
    ] {
        if rows[table] != want {
            p.push(format!(
                "tables/{table}/{id}.parquet: {} rows, expected {want}",
                rows[table]
            ));
        }
    }
    for b in tables::read(&file("frames"), &["frame"])? {
        let f = b.u32s("frame")?;
        if (0..b.rows()).any(|i| u64::from(f.value(i)) >= frames) {
            p.push(format!(
                "tables/frames/{id}.parquet: a frame index beyond frame_count {frames}"
            ));
        }
    }
    let mut next_car = 0u32;
    for b in tables::read(&file("parked_cars"), &["parked_car", "instance"])? {
        let (car, instance) = (b.u32s("parked_car")?, b.u32s("instance")?);
        for i in 0..b.rows() {
            let want = u32::from(crate::sensors::scene::parked_instance(next_car));
            if car.value(i) != next_car || instance.value(i) != want {
                p.push(format!(
                    "tables/parked_cars/{id}.parquet: row {next_car} is parked car {} with instance {} (expected \
                     {next_car}, {want})",
                    car.value(i),
                    instance.value(i)
                ));
            }
            next_car += 1;
        }
    }
    let mut marked = BTreeSet::new();
    for b in tables::read(&file("tracks"), &["frame", "pedestrian", "annotated"])? {
        let (f, ped, a) = (b.u32s("frame")?, b.u32s("pedestrian")?, b.bools("annotated")?);
        for i in 0..b.rows() {
            if a.value(i) {
                marked.insert((f.value(i), ped.value(i)));
            }
        }
    }
    let mut annotated = BTreeSet::new();
    for b in tables::read(&file("annotations"), &["frame", "pedestrian"])? {
        let (f, ped) = (b.u32s("frame")?, b.u32s("pedestrian")?);
        for i in 0..b.rows() {
            if u64::from(ped.value(i)) >= peds || u64::from(f.value(i)) >= frames {
                p.push(format!(
                    "tables/annotations/{id}.parquet: row for pedestrian {} frame {} outside the clip",
                    ped.value(i),
                    f.value(i)
                ));
            }
            annotated.insert((f.value(i), ped.value(i)));
        }
    }
    if annotated.len() as u64 != rows["annotations"] {
        p.push(format!(
            "tables/annotations/{id}.parquet: a (frame, pedestrian) appears twice"
        ));
    }
    if annotated != marked {
        p.push(format!(
            "tables/annotations/{id}.parquet: {} annotated pedestrian-frames, `tracks` marks {} ({} differ)",
            annotated.len(),
            marked.len(),
            annotated.symmetric_difference(&marked).count()
        ));
    }
    Ok(())
}

/// Every file of the clip's sensor index: present, of the indexed size and SHA-256.
fn check_sensors(
    layout: &Layout,
    id: &str,
    files: &mut usize,
    bytes: &mut u64,
    p: &mut Vec<String>,
) -> Result<(), Error> {
    read_sensor_files(
        layout,
        id,
        |_, data| {
            *files += 1;
            *bytes += data.len() as u64;
            Ok(())
        },
        |problem| p.push(problem),
    )
}

/// Reads every file of clip `id`'s sensor index, in index order, and checks it against its row (the path stays
/// inside the dataset, the file exists, its size and SHA-256 are the indexed ones): `good` gets each file that
/// passes (its path relative to the dataset, its bytes), `bad` a description of each one that does not. Shared
/// by `verify` and `merge`, which must agree on what a good sensor file is.
pub(crate) fn read_sensor_files(
    layout: &Layout,
    id: &str,
    mut good: impl FnMut(&str, &[u8]) -> Result<(), Error>,
    mut bad: impl FnMut(String),
) -> Result<(), Error> {
    for b in tables::read(&layout.table("sensors", id), &["path", "bytes", "sha256"])? {
        let (path, size, sha) = (b.strings("path")?, b.u64s("bytes")?, b.strings("sha256")?);
        for i in 0..b.rows() {
            let rel = path[i];
            if rel.starts_with('/') || rel.split('/').any(|c| c == ".." || c.is_empty()) {
                bad(format!("tables/sensors/{id}.parquet: path {rel:?} leaves the dataset"));
                continue;
            }
            match std::fs::read(layout.root().join(rel)) {
                Err(e) => bad(format!("{rel}: {e}")),
                Ok(data) if data.len() as u64 != size.value(i) => {
                    bad(format!("{rel}: {} bytes, the index says {}", data.len(), size.value(i)));
                }
                Ok(data) if crate::dataset::write::sensors::hex(&Sha256::digest(&data)) != sha[i] => {
                    bad(format!("{rel}: its SHA-256 differs from the index's"));
                }
                Ok(data) => good(rel, &data)?,
            }
        }
    }
    Ok(())
}
