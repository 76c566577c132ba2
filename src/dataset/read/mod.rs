//! Reading a written dataset (never re-simulating).
//!
//! - [`tables`] — reading tables: files, columns, typed access that reports bad input as errors.
//! - [`stats`] — `pedsynth stats`: statistics computed from the written tables.
//! - [`protocol`] — `pedsynth stats --protocol pab`: PedestrianActionBenchmark's sampling of the tables.
//! - [`preview`] — `pedsynth preview`: a contact sheet or GIF of a clip's camera stream with its labels.
//! - [`lidar_view`] — the LiDAR from above with the 3D boxes, for `preview --stream lidar`.
pub mod lidar_view;
pub mod preview;
pub mod protocol;
pub mod stats;
pub mod tables;
