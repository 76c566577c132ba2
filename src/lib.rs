//! pedsynth: compile a YAML dataset spec into a synthetic pedestrian-crossing dataset, without CARLA.
//!
//! The rooms follow the pipeline, and each imports only from the rooms before it (ARCHITECTURE.md, "Layers";
//! the `layering` test holds every `use` to it):
//!
//! ```text
//! util, error ─▶ spec ─▶ world ─▶ plan ─▶ sim ─▶ sensors ─▶ dataset ─▶ cli
//! ```
//!
//! - [`util`] and [`error`] — atomic files, seeded mixing, streamed JSON, XML escaping; the one error type, its
//!   codes, exit codes and rendering.
//! - [`spec`] — YAML (plus `--set`) → a validated, fully defaulted `Spec`, or every problem at once.
//! - [`world`] — road networks (built-in towns and OpenDRIVE) and their spatial queries.
//! - [`plan`] — the pure compiler from a spec and its towns to seeded clip scripts.
//! - [`sim`] — everything that moves (ego, traffic, cyclists, pedestrians) and what the ego's camera can see.
//! - [`sensors`] — pure functions of (script, trace, frame): annotations, the scene, cameras, DVS and LiDAR.
//! - [`dataset`] — the dataset on disk: writing, generating, reading, verifying, exporting.
//! - [`cli`] — one function per command, called by `src/main.rs`.
#![forbid(unsafe_code)]
// What only the crate uses is `pub(crate)`: a `pub` item must be reachable from the crate root.
#![warn(unreachable_pub)]

pub mod cli;
pub mod dataset;
pub mod error;
#[doc(hidden)]
pub mod fuzz;
pub mod plan;
pub mod sensors;
pub mod sim;
pub mod spec;
pub mod util;
pub mod world;
