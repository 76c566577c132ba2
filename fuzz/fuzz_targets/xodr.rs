//! Fuzz target: the OpenDRIVE importer and the town's derived structures, on arbitrary bytes (pedsynth::fuzz::xodr).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pedsynth::fuzz::xodr(data));
