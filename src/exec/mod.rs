//! The executor: simulates clip scripts and writes the dataset.
//!
//! - `trace` — the simulation's output (per-frame agent states and events).
//! - `sim` — the simulation engine (vehicles, pedestrians and their 12-state behaviour machine).
pub mod sim;
pub mod trace;
