//! What the ego's camera sees, as the simulation estimates it, so that a crosser's timeline can count the time
//! it has been in view before it steps out (`crossing.timeline`). It applies the visibility gate's size stage
//! exactly as the annotation does (the walker's gate box, `sim::gate::gate_box_size_px`), the image
//! stage to an upright box of the body's height and [`BODY_EXTENT_M`], and tests one line of sight, to the
//! chest, against vehicles, other pedestrians and buildings. The annotation then decides exactly; this estimate
//! is kept a little stricter (margins) so that what the simulation counts as seen is annotated.

use glam::DVec3;

use super::gate::{PED_OCCLUDER_RADIUS_PER_M, gate_box_size_px, min_box};
use super::vehicle::Vehicle;
use super::vehicle::{BICYCLE_HEIGHT_M, BICYCLE_LENGTH_M, BICYCLE_WIDTH_M};
use super::{VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::plan::SimParams;
use crate::sim::rig::{Camera, CameraPose};
use crate::spec::types::Visibility;
use crate::world::{RoadNetwork, segment_hits_box, segment_hits_cylinder};

/// Width of the box that must lie inside the image, metres (tight boxes of walking adults are 0.5–1.2 m wide:
/// the wide end, so the estimate is strict).
const BODY_EXTENT_M: f64 = 1.1;
/// The estimated box must lie this far inside the image, pixels.
const IMAGE_MARGIN_PX: f64 = 4.0;
/// The estimated box must exceed the gate's minimum size by this factor.
const SIZE_MARGIN: f64 = 1.1;
/// Height of the line of sight's end on the body, as a share of the body height (the chest).
const CHEST_SHARE: f64 = 0.72;

/// The estimate of what the camera sees.
#[derive(Clone, Debug)]
pub(crate) struct ViewProxy {
    camera: Camera,
    gate: Visibility,
}

impl ViewProxy {
    /// The proxy of a plan's camera (on the clip seeded `clip_seed`: its mount) and gate.
    pub(crate) fn new(params: &SimParams, clip_seed: u64) -> ViewProxy {
        ViewProxy {
            camera: Camera::for_clip(&params.camera, clip_seed),
            gate: params.visibility.clone(),
        }
    }

    /// The camera on the ego for this step.
    pub(crate) fn camera_at(&self, ego: &Vehicle) -> CameraPose {
        self.camera.at(
            DVec3::new(ego.pose.pos.x, ego.pose.pos.y, ego.pose.z_m),
            ego.pose.heading_rad,
            // The pitch wobble is added to the trace after the simulation: the gate sees a level car.
            0.0,
        )
    }

    /// Whether a pedestrian standing at `ground` (height `height_m`, facing `yaw_rad`) passes the gate and can be
    /// seen past the other vehicles (`vehicles[0]` is the ego itself), the other pedestrians (`people`: ground
    /// point and height, this one's own entry `me` skipped) and the town's buildings.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn sees(
        &self,
        cam: &CameraPose,
        ground: DVec3,
        yaw_rad: f64,
        height_m: f64,
        vehicles: &[Vehicle],
        people: &[(DVec3, f64)],
        me: usize,
        net: &RoadNetwork,
    ) -> bool {
        let gate = &self.gate;
        let distance_m = (ground - cam.centre).truncate().length();
        if distance_m > gate.max_distance_m {
            return false;
        }
        let foot = cam.project(ground);
        let head = cam.project(ground + DVec3::Z * height_m);
        if foot.depth_m < 0.5 || head.depth_m < 0.5 {
            return false;
        }
        let c = &cam.camera;
        let min = min_box(gate, distance_m);
        let Some((width_px, height_px)) = gate_box_size_px(cam, ground, yaw_rad, height_m) else {
            return false;
        };
        if width_px < SIZE_MARGIN * min.width_px || height_px < SIZE_MARGIN * min.height_px {
            return false;
        }
        let (w, h) = (f64::from(c.width_px), f64::from(c.height_px));
        let u = 0.5 * (foot.px.x + head.px.x);
        let half_extent_px = 0.5 * c.focal_px * BODY_EXTENT_M / foot.depth_m;
        let inside = u - half_extent_px >= IMAGE_MARGIN_PX
            && u + half_extent_px <= w - IMAGE_MARGIN_PX
            && head.px.y >= IMAGE_MARGIN_PX
            && foot.px.y <= h - IMAGE_MARGIN_PX;
        if !inside {
            return false;
        }
        let chest = ground + DVec3::Z * (CHEST_SHARE * height_m);
        let d = chest - cam.centre;
        let car = DVec3::new(VEHICLE_LENGTH_M, VEHICLE_WIDTH_M, VEHICLE_HEIGHT_M) * 0.5;
        let bike = DVec3::new(BICYCLE_LENGTH_M, BICYCLE_WIDTH_M, BICYCLE_HEIGHT_M) * 0.5;
        let blocked_by_vehicle = || {
            vehicles.iter().skip(1).any(|v| {
                let half = if v.is_cyclist() { bike } else { car };
                let centre = DVec3::new(v.pose.pos.x, v.pose.pos.y, v.pose.z_m + half.z);
                segment_hits_box(cam.centre, d, 1.0, centre, v.pose.heading_rad.sin_cos(), half)
            })
        };
        let blocked_by_person = || {
            people.iter().enumerate().any(|(k, &(other, h))| {
                k != me && segment_hits_cylinder(cam.centre, d, 1.0, other, PED_OCCLUDER_RADIUS_PER_M * h, h)
            })
        };
        !blocked_by_vehicle() && !blocked_by_person() && net.first_obstacle_hit(cam.centre, chest).is_none()
    }
}
