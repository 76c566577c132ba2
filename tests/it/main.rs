//! pedsynth's integration tests, in one binary so that a clone links the Arrow, Parquet and OpenH264 stack once.
//! Each module is one area; `common` holds what they share. Slow statistical tests and tests that need the
//! CARLA maps in `../shared/maps/carla` are `#[ignore = "..."]`: `cargo test -- --include-ignored` (CI) runs
//! them, and there a missing map fails.

mod architecture;
mod behaviour_labels;
mod calibrate;
mod camera;
mod common;
mod crash;
mod crossing_rate;
mod cyclists;
mod dataset;
mod disk_errors;
mod docs;
mod emergency;
mod export;
mod fuzz_corpus;
mod hashes;
mod imaging;
mod intention;
mod lens;
mod lidar;
mod parked;
mod plan_file;
mod planner;
mod realise;
mod report;
mod scenery;
mod shard;
mod signals;
mod sim_determinism;
mod sim_rules;
mod sim_stats;
mod spec_diagnostics;
mod spec_keys;
mod spec_roundtrip;
mod spec_schema;
mod umbrellas;
mod verify;
mod world_builtin;
mod world_carla_maps;
mod world_malformed;
mod world_xodr_export;
