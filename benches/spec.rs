//! Benchmarks of the spec language: loading and validating the shipped specs.
//! Run: `cargo bench --bench spec`.

use std::path::Path;

use pedsynth::spec::{self, LoadOptions};

fn main() {
    divan::main();
}

#[divan::bench(args = ["quickstart", "pedsynth_pp", "carla_baseline", "balanced_50"])]
fn validate_spec(bencher: divan::Bencher, name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("specs/{name}.yaml"));
    let options = LoadOptions::default();
    bencher.bench(|| spec::load_file(divan::black_box(&path), &options).expect("valid spec"));
}

#[divan::bench]
fn reject_alias_bomb(bencher: divan::Bencher) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad_specs/alias_bomb.yaml");
    let options = LoadOptions::default();
    bencher.bench(|| spec::load_file(divan::black_box(&path), &options).expect_err("rejected"));
}
