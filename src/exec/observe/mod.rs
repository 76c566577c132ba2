//! Observation of a simulated clip: pure functions of (script, trace, frame), no IO.
//!
//! - [`rig`] — the ego's sensor mounts and intrinsics (the pinhole camera, from the spec).
//! - [`body`] — the articulated pedestrian body (COCO-17 joints, capsule silhouette).
//! - [`annotate`] — visibility gate, boxes, keypoints, occlusion and crossing labels.
pub mod annotate;
pub mod body;
pub mod rig;
