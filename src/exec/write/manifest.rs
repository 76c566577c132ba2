//! `manifest.json`: what a dataset is (format, versions, spec and plan hashes) and each clip's status and file
//! hashes. It is derived from the files on disk, so an interrupted and resumed run writes the same manifest as an
//! uninterrupted one.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{Error, code};
use crate::planner::Plan;

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

/// `manifest.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
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
    pub clips: Vec<ManifestClip>,
}

impl Manifest {
    /// The manifest's JSON text (pretty, with a final newline).
    pub fn to_json(&self) -> Result<String, Error> {
        let mut text = crate::error::to_json(self, true)?;
        text.push('\n');
        Ok(text)
    }

    /// Parses a manifest; `what` names it in the error.
    pub fn parse(text: &str, what: &str) -> Result<Manifest, Error> {
        serde_json::from_str(text)
            .map_err(|e| Error::new(code::DATASET_INVALID, format!("{what} is not a pedsynth manifest: {e}")))
    }
}

/// blake3 of a plan's canonical JSON, without `spec_dir`: where the spec file lies (and how its path was
/// spelled) does not change the dataset, so the same spec run from another directory, or its
/// `spec.resolved.yaml`, resumes the same dataset and writes the same manifest.
pub fn plan_hash(plan: &Plan) -> Result<String, Error> {
    // The plan's fields by reference, `spec_dir` blanked: the JSON of the plan without cloning it (a
    // 6,000-clip plan is tens of megabytes), streamed into the hasher instead of held as a string. The test
    // below holds it equal to the JSON of a clone with an empty `spec_dir`, field for field.
    #[derive(Serialize)]
    struct Hashed<'a> {
        format_version: u32,
        pedsynth_version: &'a str,
        dataset: &'a str,
        seed: u64,
        spec_hash: &'a str,
        target_crossing_ratio: f64,
        sim: &'a crate::planner::SimParams,
        spec: &'a crate::dsl::Spec,
        spec_dir: &'a str,
        towns: &'a BTreeMap<String, String>,
        clips: &'a [crate::planner::ClipScript],
    }
    let hashed = Hashed {
        format_version: plan.format_version,
        pedsynth_version: &plan.pedsynth_version,
        dataset: &plan.dataset,
        seed: plan.seed,
        spec_hash: &plan.spec_hash,
        target_crossing_ratio: plan.target_crossing_ratio,
        sim: &plan.sim,
        spec: &plan.spec,
        spec_dir: "",
        towns: &plan.towns,
        clips: &plan.clips,
    };
    let mut hasher = blake3::Hasher::new();
    serde_json::to_writer(&mut hasher, &hashed)
        .map_err(|e| Error::new(code::INTERNAL_SERIALIZE, format!("cannot serialise the plan: {e}")))?;
    Ok(hasher.finalize().to_hex().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_hash_is_the_hash_of_the_plans_json_without_its_spec_dir() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
        let (_, plan) = crate::commands::compile_plan(&path, &Default::default(), None).expect("quickstart");
        let mut blank = plan.clone();
        blank.spec_dir = String::new();
        let json = serde_json::to_string(&blank).expect("json");
        let expected = blake3::hash(json.as_bytes()).to_hex().to_string();
        // Equal when every field of `Plan` is in `plan_hash`'s mirror, in order.
        assert_eq!(plan_hash(&plan).expect("hash"), expected);
        let mut moved = plan.clone();
        moved.spec_dir = "../elsewhere".into();
        assert_eq!(
            plan_hash(&moved).expect("hash"),
            expected,
            "where the spec lies does not matter"
        );
        moved.seed += 1;
        assert_ne!(plan_hash(&moved).expect("hash"), expected);
    }
}
