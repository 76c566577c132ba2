//! Occlusion for the annotations: what stands between the camera and a pedestrian's joint in a frame (vehicles,
//! other people, lamp poles, street furniture and parked cars, as the renderer draws them; the town's buildings
//! through its obstacle BVH), tested with rays from the camera; and whether a joint is hidden by its own body
//! (a hand behind the back, the far shoulder in profile, the face seen from behind).

use glam::{DVec2, DVec3};
use parry3d::query::{Ray, RayCast};

use super::body::{BodyPose, JAW};
use super::scene;
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

/// The lamp poles, the street furniture and the parked cars of the clip's scenery as the renderer draws them
/// (a lamp's arm and light are above any line of sight to a pedestrian) as occluders: poles and furniture as
/// boxes, cars as vehicles.
pub(super) fn static_occluders(scenery: &scene::ClipScenery) -> Vec<Occluder> {
    let boxes = scenery
        .lamp_posts
        .iter()
        .map(scene::LampPost::pole_box)
        .chain(scenery.furniture.iter().map(|f| (f.centre(), f.half_m)));
    let cars = scenery.parked_cars.iter().map(|car| Occluder::Vehicle {
        centre: car.centre,
        sin_cos: car.yaw_rad.sin_cos(),
    });
    boxes
        .map(|(centre, half_m)| Occluder::Pole { centre, half_m })
        .chain(cars)
        .collect()
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

/// The capsules of [`super::body::silhouette`]'s layout that hide the body's own joints: the body's 18, a bag and
/// the jaw. Hair, headwear and garments are worn over the joints, and COCO's annotators mark a joint under clothes
/// where it is.
const SELF_OCCLUDERS: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 20, JAW];

/// For each COCO-17 joint, the capsules of that layout it lies in (torso halves 0 and 17, shoulders 1, upper
/// arms 3–4, forearms 5–6, thighs 7–8, shins 9–10, hips 16): their surface may come up to their radius before
/// the joint along a line of sight. The head's points (nose, eyes, ears) lie on the head's surface instead
/// ([`HEAD_SURFACE_ALLOWANCE`]).
#[rustfmt::skip]
const JOINT_CAPSULES: [&[usize]; 17] = [
    &[], &[], &[], &[], &[],            // nose, eyes, ears
    &[1, 3, 0, 17], &[1, 4, 0, 17],     // shoulders
    &[3, 5], &[4, 6],                   // elbows
    &[5], &[6],                         // wrists
    &[16, 7, 0, 17], &[16, 8, 0, 17],   // hips
    &[7, 9], &[8, 10],                  // knees
    &[9], &[10],                        // ankles
];

/// The part that belongs to a joint and never hides it: a wrist's hand (capsules 14–15) and an ankle's foot
/// (11–12). Seen from the front a foot points at the camera and covers its ankle's centre, yet an annotator
/// marks the ankle where it shows, above the foot.
fn own_part(k: usize) -> Option<usize> {
    match k {
        9 => Some(14),
        10 => Some(15),
        15 => Some(11),
        16 => Some(12),
        _ => None,
    }
}

/// How far before a head point (nose, eye, ear) the line of sight may enter the head, a fraction of the head's
/// radius: a point on a sphere's surface seen from up to 104° off its normal (the nose shows in profile, not
/// from behind).
const HEAD_SURFACE_ALLOWANCE: f64 = 0.5;

/// How far before a joint the line of sight may enter any other part of the body, metres (a joint's own
/// capsules get their radius on top).
const SELF_OCCLUSION_TOLERANCE_M: f64 = 0.02;

/// Whether joint `k` (COCO-17) of `pose` is hidden from `camera` by the body's own parts ([`SELF_OCCLUDERS`]):
/// the line of sight enters one of them farther before the joint than the joint's depth inside that part allows
/// ([`JOINT_CAPSULES`]; a joint's hand or foot never hides it, [`own_part`]). Such a joint is labelled as
/// occluded (COCO's flag 1) but does not count towards the body's occlusion by other things.
pub(super) fn hidden_by_own_body(pose: &BodyPose, k: usize, camera: DVec3) -> bool {
    let joint = pose.joints[k];
    let distance_m = joint.distance(camera);
    let dir = (joint - camera) / distance_m;
    // In the joint's frame (single precision is plenty there): the ray reaches the joint at time 1.
    let ray = Ray::new((camera - joint).as_vec3(), (joint - camera).as_vec3());
    SELF_OCCLUDERS.iter().any(|&i| {
        let c = &pose.capsules[i];
        if !c.is_present() || own_part(k) == Some(i) {
            return false;
        }
        let allowance_m = if k < 5 && (i == 2 || i == JAW) {
            HEAD_SURFACE_ALLOWANCE * c.radius_m
        } else if JOINT_CAPSULES[k].contains(&i) {
            c.radius_m + SELF_OCCLUSION_TOLERANCE_M
        } else {
            SELF_OCCLUSION_TOLERANCE_M
        };
        // Cheap rejections first (a millimetre to spare, so that the ray cast alone decides near the bounds): a
        // capsule wholly beyond the depth it would have to reach, or whose bounding sphere the line of sight
        // misses, cannot hide the joint.
        let (da, db) = ((c.a - camera).dot(dir), (c.b - camera).dot(dir));
        if da.min(db) - c.radius_m > distance_m - allowance_m + 1e-3 {
            return false;
        }
        let centre = (c.a + c.b) * 0.5 - camera;
        let bound_m = c.a.distance(c.b) * 0.5 + c.radius_m + 1e-3;
        if centre.reject_from_normalized(dir).length_squared() > bound_m * bound_m {
            return false;
        }
        let shape = parry3d::shape::Capsule::new((c.a - joint).as_vec3(), (c.b - joint).as_vec3(), c.radius_m as f32);
        shape
            .cast_local_ray(&ray, 1.0, true)
            .is_some_and(|t| (1.0 - f64::from(t)) * distance_m > allowance_m)
    })
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

    /// A body standing at the origin facing +x, seen from 8 m at the camera's height in the direction `bearing_rad`
    /// (0: in front of it, π: behind it, π/2: on its left): the joints its own body hides.
    fn self_hidden(figure: &crate::plan::Figure, bearing_rad: f64) -> Vec<usize> {
        let frame = crate::sim::trace::PedFrame::STILL;
        let pose = super::super::body::pose(&frame, 1.75, figure, DVec3::ZERO);
        let camera = DVec2::from_angle(bearing_rad).extend(1.4) * DVec3::new(8.0, 8.0, 1.0);
        (0..17).filter(|&k| hidden_by_own_body(&pose, k, camera)).collect()
    }

    #[test]
    fn a_body_hides_its_own_far_side() {
        use crate::plan::Figure;
        use std::f64::consts::{FRAC_PI_2, PI};
        // From the front every joint shows; from behind the face (nose, eyes) does not, the rest does.
        assert_eq!(self_hidden(&Figure::PLAIN, 0.0), Vec::<usize>::new());
        assert_eq!(self_hidden(&Figure::PLAIN, PI), vec![0, 1, 2]);
        // In profile from its left: the right eye, ear, shoulder, elbow, wrist and hip are behind the head and
        // the body; the nose and the left side show (the left hip is behind the hanging forearm: not asserted).
        // Standing, the legs are side by side: the right knee and ankle hide too.
        let from_left = self_hidden(&Figure::PLAIN, FRAC_PI_2);
        for k in [2, 4, 6, 8, 10, 12, 14, 16] {
            assert!(from_left.contains(&k), "joint {k} shows from the left: {from_left:?}");
        }
        for k in [0, 1, 3, 5, 7, 9, 13, 15] {
            assert!(
                !from_left.contains(&k),
                "joint {k} is hidden from the left: {from_left:?}"
            );
        }
        // An umbrella's hand is held in front of the chest: hidden from behind, shown from the front.
        let umbrella = Figure {
            umbrella: Some([20, 20, 20]),
            ..Figure::PLAIN
        };
        assert!(self_hidden(&umbrella, PI).contains(&9));
        assert!(!self_hidden(&umbrella, 0.0).contains(&9));
    }
}
