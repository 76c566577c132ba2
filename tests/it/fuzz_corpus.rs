//! The fuzz corpus as regression tests: every input the fuzzers keep (`fuzz/corpus/<target>/`, minimised), every
//! crash they ever found (`fuzz/regressions/<target>/`, one file per fixed bug) and the seed inputs (the specs,
//! the bad-spec and malformed-map test files) go through the same entry points as the fuzz targets
//! (`pedsynth::fuzz`) on the stable toolchain: none may panic or take more than 10 s (the bound for a
//! small file). CI also runs the fuzzers themselves for a bounded time (`.ci/run`).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The files directly inside `dir` (none when it is missing).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.flatten().map(|e| e.path()).filter(|p| p.is_file()).collect())
        .unwrap_or_default();
    out.sort();
    out
}

/// Runs `target` on every input of its corpus, its regressions and `seeds`; returns how many it ran.
fn run(name: &str, target: fn(&[u8]), seeds: &[&str]) -> usize {
    let mut inputs = files(&root().join("fuzz/corpus").join(name));
    inputs.extend(files(&root().join("fuzz/regressions").join(name)));
    for seed in seeds {
        inputs.extend(files(&root().join(seed)));
    }
    assert!(!inputs.is_empty(), "{name}: no inputs");
    for input in &inputs {
        let data = std::fs::read(input).unwrap();
        let start = Instant::now();
        target(&data);
        let took = start.elapsed();
        assert!(took < Duration::from_secs(10), "{}: {took:?}", input.display());
    }
    inputs.len()
}

#[test]
fn spec_loader_survives_its_corpus() {
    let n = run(
        "spec",
        pedsynth::fuzz::spec,
        &["specs", "tests/data/specs", "tests/data/bad_specs"],
    );
    eprintln!("spec: {n} inputs");
}

#[test]
fn plan_reader_survives_its_corpus() {
    let n = run("plan", pedsynth::fuzz::plan, &[]);
    eprintln!("plan: {n} inputs");
}

#[test]
fn opendrive_importer_survives_its_corpus() {
    let n = run(
        "xodr",
        pedsynth::fuzz::xodr,
        &["tests/data", "tests/data/xodr_malformed"],
    );
    eprintln!("xodr: {n} inputs");
}
