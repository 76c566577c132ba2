//! `manifest.json`: what a dataset is (format, versions, spec and plan hashes) and each clip's status and file
//! hashes. It is derived from the files on disk, so an interrupted and resumed run writes the same manifest as an
//! uninterrupted one.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{Error, code};

/// Marker and version of the dataset format (`manifest.json`'s `pedsynth_dataset`).
pub const DATASET_FORMAT: u32 = 1;

/// A clip's entry in the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestClip {
    /// Clip id.
    pub clip_id: String,
    /// `done` or `pending`.
    pub status: String,
    /// blake3 of each table file, by table.
    pub files: BTreeMap<String, String>,
}

/// `manifest.json`. `C` is the clip list: held (`Vec`, what is read), none (`()`, a writer's header), or
/// [`crate::util::stream_json::Streamed`] (written clip by clip, in constant memory).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest<C = Vec<ManifestClip>> {
    /// Dataset format version; its presence marks a pedsynth dataset.
    pub pedsynth_dataset: u32,
    /// pedsynth version that wrote the dataset.
    pub pedsynth_version: String,
    /// Table schema version.
    pub schema_version: u32,
    /// Dataset name.
    pub dataset: String,
    /// blake3 of the resolved spec.
    pub spec_hash: String,
    /// blake3 of the plan's canonical JSON.
    pub plan_hash: String,
    /// Target sequence-level crossing ratio.
    pub target_crossing_ratio: f64,
    /// The tables.
    pub tables: Vec<String>,
    /// Sensors and what was written for each.
    pub sensors: BTreeMap<String, String>,
    /// Every planned clip.
    pub clips: C,
}

impl<C: Serialize> Manifest<C> {
    /// Writes the manifest's JSON text (pretty, with a final newline) to `out`.
    pub fn write_json(&self, out: impl std::io::Write) -> Result<(), serde_json::Error> {
        let mut out = out;
        serde_json::to_writer_pretty(&mut out, self)?;
        out.write_all(b"\n").map_err(serde_json::Error::io)
    }

    /// The same manifest with the clip list `clips`.
    pub fn with_clips<D>(&self, clips: D) -> Manifest<D> {
        Manifest {
            pedsynth_dataset: self.pedsynth_dataset,
            pedsynth_version: self.pedsynth_version.clone(),
            schema_version: self.schema_version,
            dataset: self.dataset.clone(),
            spec_hash: self.spec_hash.clone(),
            plan_hash: self.plan_hash.clone(),
            target_crossing_ratio: self.target_crossing_ratio,
            tables: self.tables.clone(),
            sensors: self.sensors.clone(),
            clips,
        }
    }
}

impl Manifest {
    /// Parses a manifest; `what` names it in the error.
    pub fn parse(text: &str, what: &str) -> Result<Manifest, Error> {
        serde_json::from_str(text)
            .map_err(|e| Error::new(code::DATASET_INVALID, format!("{what} is not a pedsynth manifest: {e}")))
    }
}
