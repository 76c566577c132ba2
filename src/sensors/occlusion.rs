//! Occlusion for the annotations: what stands between the camera and a pedestrian's joint in a frame (vehicles,
//! other people, lamp poles, street furniture and parked cars, as the renderer draws them; the town's buildings
//! through its obstacle BVH), tested with rays from the camera.

use glam::{DVec2, DVec3};

use super::scene::{self, ParkedCar};
use crate::plan::ClipScript;
use crate::sim::trace::ClipTrace;
use crate::sim::{VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::world::RoadNetwork;

/// An obstacle for occlusion rays in one frame.
#[derive(Clone, Copy, Debug)]
pub(super) enum Occluder {
    /// A vehicle: ground centre and `yaw.sin_cos()` (computed once per frame, not once per ray).
    Vehicle { centre: DVec3, sin_cos: (f64, f64) },
    /// A pedestrian body as an upright cylinder: ground point, radius, height, owner id.
    Person {
        ground: DVec3,
        radius_m: f64,
        height_m: f64,
        owner: u32,
    },
    /// A street lamp's pole or a piece of street furniture (the axis-aligned box the renderer draws): its centre
    /// and half extents.
    Pole { centre: DVec3, half_m: DVec3 },
}

/// Whether the segment `from + t·d`, t ∈ (0, t_max), passes through the occluder.
pub(super) fn blocks(occ: &Occluder, from: DVec3, d: DVec3, t_max: f64) -> bool {
    match *occ {
        Occluder::Vehicle { centre, sin_cos } => crate::world::segment_hits_box(
            from,
            d,
            t_max,
            centre + DVec3::new(0.0, 0.0, VEHICLE_HEIGHT_M * 0.5),
            sin_cos,
            DVec3::new(VEHICLE_LENGTH_M * 0.5, VEHICLE_WIDTH_M * 0.5, VEHICLE_HEIGHT_M * 0.5),
        ),
        Occluder::Person {
            ground,
            radius_m,
            height_m,
            ..
        } => crate::world::segment_hits_cylinder(from, d, t_max, ground, radius_m, height_m),
        Occluder::Pole { centre, half_m } => crate::world::segment_hits_box(from, d, t_max, centre, (0.0, 1.0), half_m),
    }
}

/// The lamp poles, the street furniture and the parked cars of the clip's scene as the renderer draws them
/// ([`scene::clip_lamp_posts`], [`scene::clip_furniture`], [`scene::clip_parked_cars`]; a lamp's arm and light are
/// above any line of sight to a pedestrian) as occluders (poles and furniture as boxes, cars as vehicles), and
/// the parked cars.
pub(super) fn static_occluders(
    script: &ClipScript,
    trace: &ClipTrace,
    town: &RoadNetwork,
) -> (Vec<Occluder>, Vec<ParkedCar>) {
    let posts = scene::clip_lamp_posts(trace, town);
    let furniture = scene::clip_furniture(trace, town, script.seed, &posts);
    let parked = scene::clip_parked_cars(script, trace, town, &posts, &furniture);
    let boxes = posts
        .iter()
        .map(scene::LampPost::pole_box)
        .chain(furniture.iter().map(|f| (f.centre(), f.half_m)));
    let cars = parked.iter().map(|car| Occluder::Vehicle {
        centre: car.centre,
        sin_cos: car.yaw_rad.sin_cos(),
    });
    let occluders = boxes
        .map(|(centre, half_m)| Occluder::Pole { centre, half_m })
        .chain(cars)
        .collect();
    (occluders, parked)
}

/// Whether the line of sight from the camera to `target` is blocked by one of `occluders` (already stripped of
/// the target pedestrian's own body) or by a static obstacle.
pub(super) fn occluded(town: &RoadNetwork, occluders: &[Occluder], camera: DVec3, target: DVec3) -> bool {
    let d = target - camera;
    let t_max = 1.0 - 0.05 / d.length().max(0.05);
    occluders.iter().any(|occ| blocks(occ, camera, d, t_max))
        || town.first_obstacle_hit(camera, camera + d * t_max).is_some()
}

/// Whether `occ` could block any line of sight from `camera` to a point within `reach_m` (in plan view) of
/// `target`: such a line stays within `reach_m` of the segment `camera → target` in plan view, and an
/// occluder lies within its bounding circle, so one farther than both radii from that segment blocks none.
pub(super) fn may_block(occ: &Occluder, camera: DVec2, target: DVec2, reach_m: f64) -> bool {
    let (centre, radius_m) = match *occ {
        Occluder::Vehicle { centre, .. } => (centre.truncate(), VEHICLE_LENGTH_M.hypot(VEHICLE_WIDTH_M) * 0.5),
        Occluder::Person { ground, radius_m, .. } => (ground.truncate(), radius_m),
        Occluder::Pole { centre, half_m } => (centre.truncate(), half_m.truncate().length()),
    };
    let r = radius_m + reach_m + 1e-6;
    crate::world::segment_projection(camera, target, centre).1 <= r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn occluders_block_only_what_they_cover() {
        let car = Occluder::Vehicle {
            centre: DVec3::new(10.0, 0.0, 0.0),
            sin_cos: 0.3_f64.sin_cos(),
        };
        let from = DVec3::new(0.0, 0.0, 1.0);
        assert!(blocks(&car, from, DVec3::new(20.0, 0.0, 0.0), 1.0));
        assert!(
            !blocks(&car, from, DVec3::new(20.0, 0.0, 0.0), 0.3),
            "target in front of the car"
        );
        assert!(
            !blocks(&car, from, DVec3::new(20.0, 0.0, 3.0), 1.0),
            "the ray passes over the roof"
        );
        let person = Occluder::Person {
            ground: DVec3::new(5.0, 0.0, 0.0),
            radius_m: 0.25,
            height_m: 1.7,
            owner: 1,
        };
        assert!(blocks(&person, from, DVec3::new(10.0, 0.0, 0.0), 1.0));
        assert!(!blocks(&person, from, DVec3::new(10.0, 1.0, 0.0), 1.0));
        assert!(!blocks(&person, from, DVec3::new(10.0, 0.0, 4.0), 1.0), "over the head");
    }
}
