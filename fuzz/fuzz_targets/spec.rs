//! Fuzz target: the spec loader (YAML, schema, validation), on arbitrary bytes (pedsynth::fuzz::spec).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pedsynth::fuzz::spec(data));
