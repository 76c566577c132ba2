//! Reading a written dataset (never re-simulating).
//!
//! - [`tables`] — reading tables: files, columns, typed access that reports bad input as errors.
//! - [`stats`] — `pedsynth stats`: statistics computed from the written tables.
//! - [`protocol`] — `pedsynth stats --protocol pab`: PedestrianActionBenchmark's sampling of the tables.
//! - [`preview`] — `pedsynth preview`: a contact sheet or GIF of a clip's camera stream with its labels.
//! - [`verify`] — `pedsynth verify`: the dataset against its manifest and itself (also run by `stats` and the
//!   exporters before they read).
pub mod lidar_view;
pub mod preview;
pub mod protocol;
pub mod stats;
pub mod tables;
pub mod verify;
