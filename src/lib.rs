//! pedsynth: compile a YAML dataset spec into a synthetic pedestrian-crossing dataset, without CARLA.
//!
//! Pipeline: `dsl` (spec → validated, defaulted `Spec`) → `world` (road networks) → planner → executor.
pub mod calibration;
pub mod commands;
pub mod dsl;
pub mod error;
pub mod exec;
pub mod fsutil;
#[doc(hidden)]
pub mod fuzz;
pub mod mix;
pub mod planner;
pub mod stream_json;
pub mod world;
pub(crate) mod xml;
