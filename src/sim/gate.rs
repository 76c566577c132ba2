//! The visibility gate (the paper's Table 4 stages: distance, in front, box size, inside the image, occlusion):
//! the pieces that the simulation's view proxy (`sim::view`, which times crossers' intentions on what the camera
//! will see) and the annotation (`sensors::annotate`, which labels what it does see) must apply identically.

use glam::{DVec2, DVec3};

use crate::sim::rig::CameraPose;
use crate::spec::types::{BoxSize, Visibility};

/// Radius of the cylinder standing in for another pedestrian when testing occlusion, as a share of height.
pub const PED_OCCLUDER_RADIUS_PER_M: f64 = 0.14;

/// Half the width and depth of the walker bounding box that stage 3 of the gate measures, metres: CARLA's walker
/// box (reference §4: adult capsule extents 0.34 × 0.34 m; children 0.25 × 0.25 m), which is what the paper's
/// 15 × 30 px gate was applied to. The annotated box is the tight silhouette box, narrower than this one; gating
/// the tight box at 15 px would keep a standing adult seen side-on only within about 17 m.
pub fn gate_box_half_width_m(height_m: f64) -> f64 {
    if height_m < CHILD_HEIGHT_LIMIT_M { 0.25 } else { 0.34 }
}

/// People shorter than this get the child's gate box, metres.
const CHILD_HEIGHT_LIMIT_M: f64 = 1.4;

/// The image size (width, height, pixels) of a walker's gate box — the box of [`gate_box_half_width_m`] around
/// its footprint, from the ground to `height_m`, turned by `yaw_rad` — from the 8 projected corners, as CARLA
/// users compute a 2D box. `None` when a corner is not in front of the camera.
pub fn gate_box_size_px(cam: &CameraPose, ground: DVec3, yaw_rad: f64, height_m: f64) -> Option<(f64, f64)> {
    let half = gate_box_half_width_m(height_m);
    let (s, c) = yaw_rad.sin_cos();
    let (ax, ay) = (DVec3::new(c, s, 0.0) * half, DVec3::new(-s, c, 0.0) * half);
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for corner in [ax + ay, ax - ay, -ax - ay, -ax + ay] {
        for z in [0.0, height_m] {
            let p = cam.project(ground + corner + DVec3::Z * z);
            if p.depth_m <= 0.05 {
                return None;
            }
            lo = lo.min(p.px);
            hi = hi.max(p.px);
        }
    }
    Some((hi.x - lo.x, hi.y - lo.y))
}

/// Stage 3 of the gate: whether a `width` × `height` box (pixels) is smaller than `min` in either dimension.
pub fn too_small(width: f64, height: f64, min: BoxSize) -> bool {
    width < min.width_px || height < min.height_px
}

/// Stage 3's minimum box at `distance_m`: the far minimum beyond the gate's far distance, else the near one.
pub fn min_box(gate: &Visibility, distance_m: f64) -> BoxSize {
    if distance_m > gate.far_distance_m {
        gate.min_box_far_px
    } else {
        gate.min_box_px
    }
}
