//! The executor: simulates clip scripts and writes the dataset.
//!
//! - `trace` — the simulation's output (per-frame agent states and events).
pub mod trace;
