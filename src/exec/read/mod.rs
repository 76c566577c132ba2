//! Reading a written dataset (never re-simulating).
//!
//! - [`stats`] — `pedsynth stats`: statistics computed from the written tables.
pub mod stats;
