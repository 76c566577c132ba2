//! Fuzz target: the plan reader (JSON, versions, spec, fingerprints, clips), on arbitrary bytes (pedsynth::fuzz::plan).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pedsynth::fuzz::plan(data));
