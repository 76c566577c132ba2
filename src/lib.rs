//! pedsynth: compile a YAML dataset spec into a synthetic pedestrian-crossing dataset.
pub mod dsl;
pub mod world;
