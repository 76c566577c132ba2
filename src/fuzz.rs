//! Entry points of the fuzz targets (`fuzz/`, run by `cargo fuzz` in CI) and of the corpus regression test
//! (`tests/it/fuzz_corpus.rs`, run by `cargo test` on every input of `fuzz/corpus` and `fuzz/regressions`). Each
//! takes arbitrary bytes as an untrusted file and must return, with an error where the input is bad, without
//! panicking, hanging or allocating without bound.

use std::path::Path;

/// A directory that does not exist: relative paths in fuzzed inputs resolve into it and find nothing.
const NOWHERE: &str = "pedsynth-fuzz-nowhere";

/// The spec loader: YAML parsing (with its budget), the schema, every validation rule.
pub fn spec(data: &[u8]) {
    let options = crate::spec::LoadOptions::default();
    let _ = crate::spec::load_bytes(data, "fuzz.yaml", Path::new(NOWHERE), &options);
}

/// The plan reader: JSON, versions, the spec inside, town fingerprints, and the clips against their spec.
pub fn plan(data: &[u8]) {
    let _ = crate::dataset::inputs::read_plan_bytes(data, &Path::new(NOWHERE).join("plan.json"));
}

/// The OpenDRIVE importer, then what the planner derives from a town (spawn points, fingerprint).
pub fn xodr(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(network) = crate::world::RoadNetwork::from_xodr_str(text, "fuzz.xodr") {
        let _ = crate::plan::TownContext::new(network);
    }
}
