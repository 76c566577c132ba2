//! The executor: simulates clip scripts and writes the dataset.
//!
//! - `sim` — the simulation engine (vehicles, pedestrians and their 12-state behaviour machine).
//! - `trace` — the simulation's output (per-frame agent states and events).
//! - `camera` — the ego's pinhole camera: mount, intrinsics, projection.
//! - `body` — the articulated pedestrian body (COCO-17 joints, capsule silhouette).
//! - `annotate` — visibility gate, boxes, keypoints, occlusion and crossing labels of a simulated clip.
//! - `tables` — the Parquet tables: schemas, record batches, atomic writes.
//! - `generate` — `pedsynth generate`: plan → simulate → annotate → write, resumable and parallel.
//! - `stats` — `pedsynth stats`: statistics computed from the written tables.
pub mod annotate;
pub mod body;
pub mod camera;
pub mod generate;
pub mod sim;
pub mod stats;
pub mod tables;
pub mod trace;
