//! The dataset on disk: everything that writes, generates, reads, checks or converts a dataset directory.
//!
//! - [`write`] — the only code that touches `--out`: layout, Parquet tables, sensor files, manifest, card.
//! - [`generate`] — `pedsynth generate`: each clip realised, rendered and written, clips in parallel, resume,
//!   shards, merge.
//! - [`read`] — code that reads a written dataset (statistics, benchmark protocol, previews), never
//!   re-simulating.
//! - [`verify`] — `pedsynth verify`: completeness, hashes, schemas, joins, sensor files.
//! - [`export`] — a written dataset in other tools' layouts (PIE, JAAD, PedestrianActionBenchmark, the seed
//!   system's CSV, OpenSCENARIO).
//! - [`report`] — `pedsynth report`: a dataset's distributions (and another's beside them) as one HTML page.
//! - [`calibrate`] — `pedsynth calibrate`: real annotations measured, a profile fitted, real against generated.
//! - [`inputs`] — what a dataset is made from, read from disk: a spec's towns, the compiled plan, a plan file
//!   checked against its spec.

pub mod calibrate;
pub mod export;
pub mod generate;
pub mod inputs;
pub mod read;
pub mod report;
pub mod verify;
pub mod write;
