//! The executor: turns each clip script of a plan into files of the dataset, in three stages per clip:
//!
//! ```text
//! ClipScript ──simulate──▶ ClipTrace ──observe──▶ observations ──write──▶ files under --out
//! ```
//!
//! - [`simulate`] — everything that moves: vehicles, the ego, pedestrians and their 12-state behaviour machine.
//! - [`trace`] — what the simulation produces (per-frame agent states and events).
//! - [`observe`] — pure functions of (script, trace, frame): sensor rig, bodies, annotations.
//! - [`write`] — the only code that touches the output directory: layout, tables, manifest.
//! - [`generate`] — orchestration of `pedsynth generate`: clips in parallel, resume, progress.
//! - [`read`] — code that reads a written dataset (`pedsynth stats`).
pub mod generate;
pub mod observe;
pub mod read;
pub mod simulate;
pub mod trace;
pub mod write;
