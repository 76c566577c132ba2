//! Observation of a simulated clip: pure functions of (script, trace, frame), no IO.
//!
//! - [`rig`] — the ego's sensor rig: mounts and intrinsics from the spec (the pinhole camera).
//! - [`body`] — the articulated pedestrian body (COCO-17 joints, capsule silhouette).
//! - [`annotate`] — visibility gate, boxes, keypoints, occlusion and crossing labels.

pub mod annotate;
pub mod body;
pub mod rig;

use crate::dsl::Spec;
use crate::exec::trace::ClipTrace;
use crate::planner::ClipScript;
use crate::world::RoadNetwork;
use annotate::ClipAnnotations;
use rig::Rig;

/// Everything observed of one clip.
#[derive(Clone, Debug, PartialEq)]
pub struct Observations {
    /// The annotation of every pedestrian-frame (and the rejections of the visibility gate).
    pub annotations: ClipAnnotations,
}

/// Observes a simulated clip with the rig.
pub fn observe(script: &ClipScript, trace: &ClipTrace, spec: &Spec, rig: &Rig, town: &RoadNetwork) -> Observations {
    Observations {
        annotations: annotate::annotate(script, trace, &spec.annotations, &rig.camera, town),
    }
}
