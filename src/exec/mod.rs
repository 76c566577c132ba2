//! The executor: simulates clip scripts and writes the dataset.
//!
//! - `trace` — the simulation's output (per-frame agent states and events).
//! - `camera` — the ego's pinhole camera: mount, intrinsics, projection.
//! - `body` — the articulated pedestrian body (COCO-17 joints, capsule silhouette).
//! - `tables` — the Parquet tables: schemas, record batches, atomic writes.
//! - `annotate` — visibility gate, boxes, keypoints, occlusion and crossing labels of a simulated clip.
pub mod annotate;
pub mod body;
pub mod camera;
pub mod tables;
pub mod stats;
pub mod trace;
