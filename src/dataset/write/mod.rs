//! Writing the dataset: the only code that touches the output directory.
//!
//! - [`layout`] — every path of the dataset, in one place.
//! - [`manifest`] — `manifest.json`.
//! - [`card`] — the dataset card `README.md` (Hugging Face front matter) of a finished dataset.
//! - [`tables`] — the Parquet tables: schemas and record batches.
//! - [`sensors`] — the camera streams' files, the DVS events and the sensor index table.
//! - [`lidar`] — the LiDAR's points (a Parquet file per clip, or the seed's `.bin` per frame).
//!
//! A [`DatasetWriter`] opens `--out` for a plan (refusing a directory that holds anything else), writes each
//! clip's files atomically (`util::files::write_atomically`: a complete file or none), and derives the manifest from
//! the files on disk. A clip's sensor files are written first, then its tables (the `sensors` index among
//! them, `clips` last): a clip is finished when all of its table files exist, which is what a resumed run
//! skips, so a clip interrupted while rendering is rendered again whole.

pub mod card;
pub(crate) mod columns;
pub mod layout;
pub mod lidar;
pub mod manifest;
pub mod sensors;
pub mod tables;
pub mod video;

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, code};
use crate::plan::{ClipScript, Plan, PreparedPlan};
use crate::sensors::Observations;
use crate::sim::trace::ClipTrace;
use crate::util::files::write_atomically;
pub use layout::Layout;
pub use manifest::{DATASET_FORMAT, Manifest, ManifestClip};
use tables::{FileMeta, TABLES};

/// An output directory opened for the dataset of one plan.
#[derive(Debug)]
pub struct DatasetWriter {
    /// The directory's lock ([`LOCK_FILE`]), held while the writer lives.
    _lock: std::fs::File,
    layout: Layout,
    /// The manifest without its clips (their list is written from the plan, clip by clip: `PreparedPlan::clips`).
    manifest: Manifest<()>,
    meta: FileMeta,
}

impl DatasetWriter {
    /// Opens `out` for `plan`: `out` must be missing, empty, or a dataset of the same spec and plan (which is
    /// then resumed, after removing the temporary files an interrupted run left). Writes `spec.resolved.yaml`
    /// and, for a new dataset, a manifest with every clip pending.
    ///
    /// A whole run holds an exclusive lock on [`LOCK_FILE`]; a shard (`shared`) holds a shared one, so shards
    /// of one run write side by side while a whole run and a shard exclude each other. Temporaries are removed
    /// only when nothing else holds the lock (a running shard's are in use).
    pub fn open(out: &Path, plan: &PreparedPlan, shared: bool) -> Result<DatasetWriter, Error> {
        let layout = Layout::new(out);
        let header = plan.header();
        check_out_dir(&layout, &header.spec_hash, &plan.plan_hash)?;
        std::fs::create_dir_all(out).map_err(|e| Error::write(out, e))?;
        // The manifest lock is taken first and held through the start: it makes a shard wait while the first
        // one cleans up and writes the initial manifest (holding the directory lock exclusively for that
        // moment), instead of finding the directory lock taken and refusing; nothing blocks on the directory
        // lock while holding the manifest lock, so the two cannot deadlock.
        let manifest_guard = lock_manifest(&layout)?;
        let (lock, alone) = lock_out_dir(&layout, shared)?;
        // Checked again under the locks: another run, or another shard of this one, may have started the
        // dataset in between.
        let existing = check_out_dir(&layout, &header.spec_hash, &plan.plan_hash)?;
        let spec_yaml = crate::spec::to_yaml(&header.spec)?;
        let spec_path = layout.spec_resolved();
        write_atomically(&spec_path, spec_yaml.as_bytes()).map_err(|e| Error::write(&spec_path, e))?;
        let manifest = Manifest {
            pedsynth_dataset: DATASET_FORMAT,
            pedsynth_version: env!("CARGO_PKG_VERSION").to_owned(),
            schema_version: tables::SCHEMA_VERSION,
            dataset: header.dataset.clone(),
            spec_hash: header.spec_hash.clone(),
            plan_hash: plan.plan_hash.clone(),
            target_crossing_ratio: header.target_crossing_ratio,
            tables: TABLES.iter().map(|t| t.to_string()).collect(),
            sensors: sensor_status(header),
            clips: (),
        };
        let writer = DatasetWriter {
            _lock: lock,
            layout,
            manifest,
            meta: FileMeta {
                spec_hash: header.spec_hash.clone(),
            },
        };
        if alone {
            writer.remove_temporaries(plan)?;
        }
        if shared && alone {
            share_lock(&writer._lock, &writer.layout)?;
        }
        if !existing {
            writer.write_manifest(plan, |_| Ok(None))?;
        }
        drop(manifest_guard);
        Ok(writer)
    }

    /// Waits for and takes the lock that serialises manifest (and card) writes between shards; released when
    /// the returned file is dropped.
    pub fn manifest_lock(&self) -> Result<std::fs::File, Error> {
        lock_manifest(&self.layout)
    }

    /// The spec and plan hashes of the dataset being written.
    pub fn manifest_hashes(&self) -> (&str, &str) {
        (&self.manifest.spec_hash, &self.manifest.plan_hash)
    }

    /// The dataset's manifest without its clips.
    pub fn manifest(&self) -> &Manifest<()> {
        &self.manifest
    }

    /// The dataset's layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Whether every file of a clip exists (a finished clip, which a resumed run skips).
    pub fn is_clip_done(&self, clip_id: &str) -> bool {
        TABLES.iter().all(|t| self.layout.table(t, clip_id).is_file())
    }

    /// Writes the files of one clip (each atomically; `clips` last, so its presence marks completion).
    pub fn write_clip(
        &self,
        plan: &Plan,
        script: &ClipScript,
        trace: &ClipTrace,
        obs: &Observations,
        rig: &crate::sim::rig::Rig,
        sensor_rows: &[sensors::IndexRow],
    ) -> Result<(), Error> {
        let ann = &obs.annotations;
        let batches = [
            ("frames", tables::frames_batch(script, trace)),
            ("pedestrians", tables::pedestrians_batch(script, ann)),
            (
                "annotations",
                tables::annotations_batch(script, ann, plan.spec.annotations.pose_format),
            ),
            ("tracks", tables::tracks_batch(script, trace, ann)),
            ("vehicles", tables::vehicles_batch(script, trace)),
            (
                "cyclists",
                tables::cyclists_batch(script, trace, ann, plan.spec.annotations.pose_format),
            ),
            ("parked_cars", tables::parked_cars_batch(script, ann)),
            ("events", tables::events_batch(script, trace)),
            ("traffic_lights", tables::traffic_lights_batch(script, trace)),
            (
                "sensor_poses",
                tables::sensor_poses_batch(script, trace, rig, &plan.spec.sensors),
            ),
            ("sensors", sensors::index_batch(&script.clip_id, sensor_rows)),
            ("clips", tables::clips_batch(script, trace, ann)),
        ];
        debug_assert!(batches.iter().map(|b| b.0).eq(TABLES));
        for (table, batch) in &batches {
            let path = self.layout.table(table, &script.clip_id);
            let bytes = tables::parquet_bytes(batch, &plan.spec.output, &self.meta, table, &script.clip_id)?;
            write_atomically(&path, &bytes).map_err(|e| Error::write(&path, e))?;
        }
        Ok(())
    }

    /// A writer of one clip's sensor files.
    pub fn clip_sensors<'a>(
        &'a self,
        plan: &'a Plan,
        script: &'a ClipScript,
    ) -> Result<sensors::ClipSensorWriter<'a>, Error> {
        sensors::ClipSensorWriter::new(
            &self.layout,
            &script.clip_id,
            script.fps,
            &plan.spec.sensors,
            &plan.spec.output,
            &self.meta,
        )
    }

    /// A writer of one clip's LiDAR files.
    pub fn clip_lidar<'a>(
        &'a self,
        plan: &'a Plan,
        script: &'a ClipScript,
    ) -> Result<lidar::ClipLidarWriter<'a>, Error> {
        lidar::ClipLidarWriter::new(
            &self.layout,
            &script.clip_id,
            &plan.spec.sensors.lidar,
            &plan.spec.output,
            &self.meta,
        )
    }

    /// Writes the final manifest: every finished clip `done` with its files' hashes, the others `pending`.
    /// Returns whether every clip is finished.
    pub fn finish(&self, plan: &PreparedPlan) -> Result<bool, Error> {
        let complete = std::cell::Cell::new(true);
        self.write_manifest(plan, |clip_id| {
            if self.is_clip_done(clip_id) {
                self.file_hashes(clip_id).map(Some)
            } else {
                complete.set(false);
                Ok(None)
            }
        })?;
        Ok(complete.get())
    }

    fn file_hashes(&self, clip_id: &str) -> Result<BTreeMap<String, String>, Error> {
        TABLES
            .iter()
            .map(|t| {
                let path = self.layout.table(t, clip_id);
                let bytes = std::fs::read(&path).map_err(|e| Error::read(&path, e))?;
                Ok((t.to_string(), blake3::hash(&bytes).to_hex().to_string()))
            })
            .collect()
    }

    /// Writes the manifest of `plan`'s clips, streamed clip by clip into the file (never held whole): a clip
    /// is `done` with the table hashes `files` gives for it, or `pending` where it gives none.
    fn write_manifest(
        &self,
        plan: &PreparedPlan,
        files: impl Fn(&str) -> Result<Option<BTreeMap<String, String>>, Error>,
    ) -> Result<(), Error> {
        let path = self.layout.manifest();
        let clips = plan.clips().map(|c| {
            files(&c.clip_id).map(|files| ManifestClip {
                clip_id: c.clip_id.into_owned(),
                status: if files.is_some() { "done" } else { "pending" }.into(),
                files: files.unwrap_or_default(),
            })
        });
        let manifest = self
            .manifest
            .with_clips(crate::util::stream_json::Streamed::new(clips, plan.len()));
        let mut file = crate::util::files::AtomicFile::create(&path).map_err(|e| Error::write(&path, e))?;
        if let Err(e) = manifest.write_json(&mut file) {
            // A clip's table that could not be read is that error; anything else is the file's.
            return Err(manifest.clips.take_error().unwrap_or_else(|| match e.io_error_kind() {
                Some(kind) => Error::write(&path, std::io::Error::new(kind, e.to_string())),
                None => Error::new(code::INTERNAL_SERIALIZE, format!("cannot serialise the manifest: {e}")),
            }));
        }
        file.commit_synced().map_err(|e| Error::write(&path, e))?;
        Ok(())
    }

    /// Removes the temporary files an interrupted run left in the dataset's own directories (the root,
    /// `tables/<table>/`, `sensors/<stream>/` and every clip's `sensors/<stream>/<clip_id>/`), so that a
    /// resumed dataset holds exactly the files of an uninterrupted run.
    fn remove_temporaries(&self, plan: &PreparedPlan) -> Result<(), Error> {
        // Made one at a time: a list of every clip's directories would grow with the clips.
        let dirs = std::iter::once(self.layout.root().to_path_buf())
            .chain(TABLES.iter().map(|t| self.layout.table_dir(t)))
            .chain(sensors::STREAMS.iter().flat_map(|stream| {
                std::iter::once(self.layout.root().join(layout::SENSORS_DIR).join(stream))
                    .chain(plan.clips().map(move |c| self.layout.sensor_dir(stream, &c.clip_id)))
            }));
        for dir in dirs {
            let Ok(entries) = std::fs::read_dir(&dir) else { continue };
            for entry in entries.flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                if is_temporary(&name) && entry.file_type().is_ok_and(|t| t.is_file()) {
                    std::fs::remove_file(entry.path()).map_err(|e| Error::write(&entry.path(), e))?;
                }
            }
        }
        Ok(())
    }
}

/// What the manifest records for each sensor of the spec.
fn sensor_status(plan: &Plan) -> BTreeMap<String, String> {
    let s = &plan.spec.sensors;
    let o = &plan.spec.output;
    let rgb = match o.rgb_encoding {
        crate::spec::types::RgbEncoding::Png => "rendered: sensors/rgb/<clip_id>/<frame:06>.png".to_owned(),
        crate::spec::types::RgbEncoding::Jpeg => format!(
            "rendered: sensors/rgb/<clip_id>/<frame:06>.jpg (quality {})",
            o.jpeg_quality
        ),
        crate::spec::types::RgbEncoding::H264 => format!(
            "rendered: sensors/rgb/<clip_id>.mp4 (H.264, QP {}, sample i = frame i)",
            o.h264_qp
        ),
    };
    let depth = match o.depth_encoding {
        crate::spec::types::DepthEncoding::MillimetresU16 => {
            "rendered: sensors/depth/<clip_id>/<frame:06>.png (u16 millimetres)"
        }
        crate::spec::types::DepthEncoding::CarlaRgb24 => {
            "rendered: sensors/depth/<clip_id>/<frame:06>.png (CARLA 24-bit RGB)"
        }
    };
    [
        ("rgb", s.rgb.enabled, rgb),
        ("depth", s.depth.enabled, depth.to_owned()),
        (
            "semantic",
            s.semantic.enabled,
            "rendered: sensors/semantic/<clip_id>/<frame:06>.png (CARLA tag ids, CARLA palette)".to_owned(),
        ),
        (
            "instance",
            s.instance.enabled,
            "rendered: sensors/instance/<clip_id>/<frame:06>.png (u16 instance ids)".to_owned(),
        ),
        (
            "dvs",
            s.dvs.enabled,
            format!(
                "rendered: sensors/dvs/<clip_id>.parquet (ESIM, {} image(s) per frame interval)",
                s.dvs.substeps
            ),
        ),
        (
            "lidar",
            s.lidar.enabled,
            match s.lidar.format {
                crate::spec::types::LidarFormat::Parquet => format!(
                    "rendered: sensors/lidar/<clip_id>.parquet ({} channels, {} points/s, {} Hz; sensor frame: x forward, y right, z up)",
                    s.lidar.channels, s.lidar.points_per_second, s.lidar.rotation_hz
                ),
                crate::spec::types::LidarFormat::CarlaBin => format!(
                    "rendered: sensors/lidar/<clip_id>/<frame:06>.bin (f32 x y z intensity; {} channels, {} points/s, {} Hz)",
                    s.lidar.channels, s.lidar.points_per_second, s.lidar.rotation_hz
                ),
            },
        ),
    ]
    .into_iter()
    .map(|(name, on, status)| (name.to_owned(), if on { status } else { "disabled".to_owned() }))
    .collect()
}

/// Name of the lock file in a dataset directory: `generate` holds an exclusive OS lock on it while it writes,
/// so a second `generate` into the same directory refuses instead of interleaving; the OS releases the lock
/// when the process ends, however it ends (kill -9 included). The (empty) file stays.
pub const LOCK_FILE: &str = ".pedsynth.lock";
/// Name of the lock file that serialises manifest writes between shards writing into one directory.
pub const MANIFEST_LOCK_FILE: &str = ".pedsynth.manifest.lock";

/// Opens (creating it empty) the lock file `name` of the dataset directory.
fn open_lock_file(layout: &Layout, name: &str) -> Result<(std::fs::File, std::path::PathBuf), Error> {
    let path = layout.root().join(name);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| Error::write(&path, e))?;
    Ok((file, path))
}

/// Waits for and takes the manifest lock ([`MANIFEST_LOCK_FILE`]).
fn lock_manifest(layout: &Layout) -> Result<std::fs::File, Error> {
    let (file, path) = open_lock_file(layout, MANIFEST_LOCK_FILE)?;
    file.lock().map_err(|e| Error::write(&path, e))?;
    Ok(file)
}

/// Turns a shard's exclusive lock (taken while it cleaned up alone) into a shared one.
fn share_lock(file: &std::fs::File, layout: &Layout) -> Result<(), Error> {
    let path = layout.root().join(LOCK_FILE);
    file.unlock().map_err(|e| Error::write(&path, e))?;
    file.try_lock_shared().map_err(|_| {
        Error::new(
            code::DATASET_LOCKED,
            format!(
                "another `pedsynth generate` took {} while this shard started",
                layout.root().display()
            ),
        )
    })
}

/// Takes the directory's lock (exclusive for a whole run, shared for a shard), or refuses when another
/// process holds it in a conflicting way. Returns the lock and whether this process is alone; a shard that
/// is alone gets the exclusive lock, to clean up before it shares it ([`share_lock`]).
fn lock_out_dir(layout: &Layout, shared: bool) -> Result<(std::fs::File, bool), Error> {
    use std::fs::TryLockError::{Error as Failed, WouldBlock};
    let (file, path) = open_lock_file(layout, LOCK_FILE)?;
    let busy = || {
        Error::new(
            code::DATASET_LOCKED,
            format!(
                "another `pedsynth generate` is writing into {} (it holds {LOCK_FILE})",
                layout.root().display()
            ),
        )
        .help("wait for it to finish, or use another --out; a run that crashed releases the lock by itself")
    };
    // Alone (even a shard): the exclusive lock; a shard keeps it until it has cleaned up, then shares it
    // (`share_lock`). Not alone: a shard joins the others' shared lock; a whole run refuses.
    match file.try_lock() {
        Ok(()) => Ok((file, true)),
        Err(WouldBlock) if shared => match file.try_lock_shared() {
            Ok(()) => Ok((file, false)),
            Err(WouldBlock) => Err(busy()),
            Err(Failed(e)) => Err(Error::write(&path, e)),
        },
        Err(WouldBlock) => Err(busy()),
        Err(Failed(e)) => Err(Error::write(&path, e)),
    }
}

/// Checks that `out` is missing, empty, or a dataset of the same spec and plan; returns whether it holds one.
fn check_out_dir(layout: &Layout, spec_hash: &str, plan_hash: &str) -> Result<bool, Error> {
    let out = layout.root();
    if out.exists() && !out.is_dir() {
        return Err(Error::new(
            code::IO_WRITE,
            format!("cannot write into {}: it is a file, not a directory", out.display()),
        )
        .help("give --out a directory: a new one, or a dataset of this spec to resume"));
    }
    let entries = match std::fs::read_dir(out) {
        Ok(entries) => entries
            .flatten()
            .filter(|e| !is_startup_file(&e.file_name().to_string_lossy()))
            .count(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(Error::read(out, e)),
    };
    if entries == 0 {
        return Ok(false);
    }
    let refuse = |why: &str| {
        Error::new(
            code::DATASET_REFUSED,
            format!("refusing to write into {}: {why}", out.display()),
        )
        .help("use a new --out directory, or the one this spec's dataset was generated into")
    };
    let text = std::fs::read_to_string(layout.manifest())
        .map_err(|_| refuse("the directory is not empty and is not a pedsynth dataset (no manifest.json)"))?;
    let manifest = Manifest::parse(&text, "manifest.json")
        .map_err(|e| refuse(&format!("its manifest.json is not a pedsynth manifest ({e})")))?;
    if manifest.spec_hash != spec_hash {
        return Err(refuse(&format!(
            "it holds a dataset of another spec ({}…)",
            &manifest.spec_hash[..12.min(manifest.spec_hash.len())]
        )));
    }
    if manifest.plan_hash != plan_hash {
        return Err(refuse(
            "it holds a dataset of another plan of this spec (another pedsynth version?)",
        ));
    }
    Ok(true)
}

/// Whether a top-level file name is one that a starting `generate` writes before the manifest (locks, the
/// resolved spec, temporaries): a directory holding only these is a dataset that never got its manifest (a
/// start that crashed, or another shard starting right now), not someone else's directory.
fn is_startup_file(name: &str) -> bool {
    let own_temporary = |file: &str| {
        name.strip_prefix('.')
            .and_then(|n| n.strip_prefix(file))
            .and_then(|rest| rest.strip_prefix(".tmp-"))
            .is_some_and(|pid| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
    };
    [LOCK_FILE, MANIFEST_LOCK_FILE, layout::SPEC_RESOLVED].contains(&name)
        || own_temporary(layout::SPEC_RESOLVED)
        || own_temporary(layout::MANIFEST)
}

/// Whether a file name is a temporary file left by an interrupted atomic write (`.NAME.tmp-PID`, see
/// `util::files::write_atomically`) or another `*.tmp` file.
fn is_temporary(name: &str) -> bool {
    let pid_suffix = name
        .rsplit_once(".tmp-")
        .is_some_and(|(_, pid)| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()));
    (name.starts_with('.') && pid_suffix) || name.ends_with(".tmp")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporaries_are_recognised_and_tables_are_not() {
        assert!(is_temporary(".town01_like-clear_noon-0001.parquet.tmp-4242"));
        assert!(is_temporary(".manifest.json.tmp-1"));
        assert!(is_temporary("leftover.tmp"));
        assert!(!is_temporary("town01_like-clear_noon-0001.parquet"));
        assert!(!is_temporary("manifest.json"));
        assert!(!is_temporary(".x.tmp-"));
        assert!(!is_temporary(".x.tmp-12a"));
    }

    #[test]
    fn only_pedsynths_own_startup_files_count_as_an_empty_directory() {
        assert!(is_startup_file(LOCK_FILE));
        assert!(is_startup_file(MANIFEST_LOCK_FILE));
        assert!(is_startup_file("spec.resolved.yaml"));
        assert!(is_startup_file(".spec.resolved.yaml.tmp-311"));
        assert!(is_startup_file(".manifest.json.tmp-4"));
        assert!(!is_startup_file("manifest.json"));
        assert!(!is_startup_file("notes.tmp"));
        assert!(!is_startup_file(".thesis.tex.tmp-12"));
        assert!(!is_startup_file(".manifest.json.tmp-"));
    }
}
