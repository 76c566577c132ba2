//! Cyclists as observers see them: the rider's articulated body in a riding pose (COCO-17 joints and capsules,
//! the same layout as a pedestrian's [`BodyPose`], so the renderer and the keypoints share one geometry) and
//! the bicycle as capsules (tubes, wheels as rings, cranks turning with the pedals).
//!
//! Built in the bicycle's frame (x forward, y left, z up; origin on the ground midway between the wheels'
//! contact points), then placed by the trace's position and yaw. Allocation-free: fixed-size arrays.

use std::f64::consts::{PI, TAU};

use glam::{DMat3, DVec3};

use super::body::{BodyPose, Capsule};
use crate::plan::Figure;
use crate::sim::trace::CyclistFrame;

/// Wheel radius (a 700c / 28" wheel with its tyre), metres.
pub const WHEEL_RADIUS_M: f64 = 0.34;
/// Wheelbase, metres.
pub const WHEELBASE_M: f64 = 1.05;
/// Crank length, metres.
const CRANK_M: f64 = 0.17;
/// The bottom bracket (crank axle), in the bicycle frame.
const BOTTOM_BRACKET: DVec3 = DVec3::new(-0.05, 0.0, 0.30);
/// Segments of a wheel's ring.
const WHEEL_SEGMENTS: usize = 16;
/// Capsules of a bicycle: 9 tubes, two cranks, two wheel rings.
pub const BICYCLE_CAPSULES: usize = 11 + 2 * WHEEL_SEGMENTS;
/// Forward lean of the rider's torso from the vertical, radians (an upright city-bike posture, ~35°).
const TORSO_LEAN_RAD: f64 = 0.61;

/// Height of the hips (the saddle) above the ground for a rider of height `height_m`: the leg almost
/// straight (95 % of its length) with the pedal at the bottom, metres.
pub fn hip_height_m(height_m: f64) -> f64 {
    let leg = (0.245 + 0.246) * height_m;
    BOTTOM_BRACKET.z - CRANK_M + 0.08 + 0.95 * leg
}

/// The middle joint of a two-segment limb from `root` to `target` (segment lengths `l1`, `l2`) bending towards
/// `hint`; a target out of reach is approached as far as the limb goes.
fn two_link(root: DVec3, target: DVec3, l1: f64, l2: f64, hint: DVec3) -> (DVec3, DVec3) {
    let to = target - root;
    let d = to.length().clamp((l1 - l2).abs() + 1e-6, l1 + l2 - 1e-6);
    let u = to.normalize_or(DVec3::NEG_Z);
    let along = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
    let h = (l1 * l1 - along * along).max(0.0).sqrt();
    let w = (hint - u * hint.dot(u)).normalize_or(DVec3::X);
    let mid = root + u * along + w * h;
    let end = mid + (root + u * d - mid).normalize_or(u) * l2;
    (mid, end)
}

/// The rider of a cyclist in frame `frame`: height `height_m`, hands on the handlebar, feet on the pedals (the
/// crank angle from the frame), torso leaning forward, head level looking ahead.
pub fn rider_pose(frame: &CyclistFrame, height_m: f64, figure: &Figure) -> BodyPose {
    let h = height_m;
    let hip_z = hip_height_m(h);
    let pelvis = DVec3::new(-0.25, 0.0, hip_z);
    let hip_y = 0.055 * h;
    let (thigh, shin) = (0.245 * h, 0.246 * h);
    let crank = TAU * frame.crank_phase;
    let leg = |side: f64, angle: f64| {
        let pedal = BOTTOM_BRACKET + DVec3::new(CRANK_M * angle.cos(), side * 0.12, CRANK_M * angle.sin());
        let hip = pelvis + DVec3::new(0.0, side * hip_y, 0.0);
        let ankle_target = pedal + DVec3::new(-0.02, 0.0, 0.07);
        let (knee, ankle) = two_link(hip, ankle_target, thigh, shin, DVec3::new(1.0, 0.0, 0.3));
        (hip, knee, ankle)
    };
    let (l_hip, l_knee, l_ankle) = leg(1.0, crank);
    let (r_hip, r_knee, r_ankle) = leg(-1.0, crank + PI);

    let lean = DVec3::new(TORSO_LEAN_RAD.sin(), 0.0, TORSO_LEAN_RAD.cos());
    let chest = pelvis + lean * (0.25 * h);
    let shoulder_mid = pelvis + lean * (0.288 * h);
    let neck = pelvis + lean * (0.34 * h);
    let shoulder_y = 0.11 * h;
    let bar_z = hip_z - 0.02;
    let (upper, fore) = (0.186 * h, 0.146 * h);
    let arm = |side: f64| {
        let shoulder = shoulder_mid + DVec3::new(0.0, side * shoulder_y, 0.0);
        let grip = DVec3::new(0.40, side * 0.25, bar_z + 0.03);
        let (elbow, wrist) = two_link(shoulder, grip, upper, fore, DVec3::new(0.0, side * 0.6, -1.0));
        (shoulder, elbow, wrist)
    };
    let (l_shoulder, l_elbow, l_wrist) = arm(1.0);
    let (r_shoulder, r_elbow, r_wrist) = arm(-1.0);
    // The head is level (the rider looks ahead), its points placed around the neck as in the standing body.
    let ([nose, l_eye, r_eye, l_ear, r_ear], head_centre) = super::body::head_points(neck, DMat3::IDENTITY, h);

    let local = [
        nose, l_eye, r_eye, l_ear, r_ear, l_shoulder, r_shoulder, l_elbow, r_elbow, l_wrist, r_wrist, l_hip, r_hip,
        l_knee, r_knee, l_ankle, r_ankle,
    ];
    let rot = DMat3::from_rotation_z(frame.yaw_rad);
    let to_world = |p: DVec3| frame.pos + rot * p;
    BodyPose {
        joints: local.map(to_world),
        capsules: super::body::silhouette(
            &local,
            [pelvis, chest, neck, head_centre],
            DMat3::IDENTITY,
            h,
            figure,
            to_world,
        ),
        height_m,
        ground: frame.pos,
        yaw_rad: frame.yaw_rad,
        gaze: rot * DVec3::X,
        umbrella: None,
    }
}

/// The bicycle of a cyclist in frame `frame` ridden by a rider of height `rider_height_m` (the saddle and the
/// handlebar follow the rider): frame tubes, fork, handlebar, saddle, cranks, then the two wheels' rings.
pub fn bicycle(frame: &CyclistFrame, rider_height_m: f64) -> [Capsule; BICYCLE_CAPSULES] {
    let hip_z = hip_height_m(rider_height_m);
    let rear = DVec3::new(-0.5 * WHEELBASE_M, 0.0, WHEEL_RADIUS_M);
    let front = DVec3::new(0.5 * WHEELBASE_M, 0.0, WHEEL_RADIUS_M);
    let seat_cluster = DVec3::new(-0.22, 0.0, hip_z - 0.16);
    let head_top = DVec3::new(0.40, 0.0, 0.86);
    let head_bottom = DVec3::new(0.43, 0.0, 0.72);
    let bar = DVec3::new(0.40, 0.0, hip_z - 0.02);
    let crank = TAU * frame.crank_phase;
    let pedal =
        |angle: f64, side: f64| BOTTOM_BRACKET + DVec3::new(CRANK_M * angle.cos(), side * 0.12, CRANK_M * angle.sin());
    let rot = DMat3::from_rotation_z(frame.yaw_rad);
    let to_world = |p: DVec3| frame.pos + rot * p;
    let cap = |a: DVec3, b: DVec3, r: f64| Capsule {
        a: to_world(a),
        b: to_world(b),
        radius_m: r,
    };
    let tube = 0.022;
    let mut out = [cap(DVec3::ZERO, DVec3::ZERO, 0.0); BICYCLE_CAPSULES];
    let fixed = [
        cap(BOTTOM_BRACKET, seat_cluster + DVec3::Z * 0.06, tube), // seat tube and post
        cap(seat_cluster, head_top, tube),                         // top tube
        cap(BOTTOM_BRACKET, head_bottom, 0.028),                   // down tube
        cap(BOTTOM_BRACKET, rear, 0.014),                          // chain stay
        cap(seat_cluster, rear, 0.014),                            // seat stay
        cap(head_top, front, 0.018),                               // fork
        cap(head_top, bar, 0.016),                                 // stem
        cap(bar + DVec3::Y * 0.28, bar - DVec3::Y * 0.28, 0.014),  // handlebar
        cap(
            DVec3::new(-0.33, 0.0, hip_z - 0.09),
            DVec3::new(-0.16, 0.0, hip_z - 0.09),
            0.045,
        ), // saddle
        cap(BOTTOM_BRACKET, pedal(crank, 1.0), 0.014),
        cap(BOTTOM_BRACKET, pedal(crank + PI, -1.0), 0.014),
    ];
    out[..fixed.len()].copy_from_slice(&fixed);
    // The wheels' rings turn with the distance ridden (a mark on the tyre would; the ring looks the same).
    let turn = frame.ridden_m / WHEEL_RADIUS_M;
    for (w, hub) in [rear, front].into_iter().enumerate() {
        for k in 0..WHEEL_SEGMENTS {
            let a0 = turn + TAU * k as f64 / WHEEL_SEGMENTS as f64;
            let a1 = turn + TAU * (k + 1) as f64 / WHEEL_SEGMENTS as f64;
            let at = |a: f64| hub + DVec3::new(a.cos(), 0.0, a.sin()) * (WHEEL_RADIUS_M - 0.02);
            out[fixed.len() + w * WHEEL_SEGMENTS + k] = cap(at(a0), at(a1), 0.02);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(crank_phase: f64) -> CyclistFrame {
        CyclistFrame {
            pos: DVec3::new(10.0, 5.0, 0.0),
            yaw_rad: 0.4,
            speed_mps: 5.0,
            accel_mps2: 0.0,
            crank_phase,
            ridden_m: 3.0,
            swerving: false,
            in_bike_lane: false,
            light: None,
        }
    }

    /// The rider sits on the saddle with its feet on the pedals and its hands on the handlebar, its limbs keep
    /// their lengths, and the whole cyclist is about as tall as the simulation's bicycle box.
    #[test]
    fn the_rider_sits_on_the_bicycle() {
        let h = 1.75;
        for phase in [0.0, 0.13, 0.5, 0.77] {
            let f = frame(phase);
            let rider = rider_pose(&f, h, &Figure::PLAIN);
            let bike = bicycle(&f, h);
            let rot = DMat3::from_rotation_z(-f.yaw_rad);
            let local = |p: DVec3| rot * (p - f.pos);
            // Feet on the pedals (the crank ends), within 10 cm.
            for (ankle, crank) in [(15, 9), (16, 10)] {
                let d = local(rider.joints[ankle]).distance(local(bike[crank].b));
                assert!(d < 0.1, "phase {phase}: ankle {ankle} is {d} m from its pedal");
            }
            // Hands at the handlebar's ends.
            for (wrist, end) in [(9, bike[7].a), (10, bike[7].b)] {
                let d = local(rider.joints[wrist]).distance(local(end));
                assert!(d < 0.12, "phase {phase}: wrist {wrist} is {d} m from the grip");
            }
            // Segment lengths as in the standing body.
            let len = |a: usize, b: usize| rider.joints[a].distance(rider.joints[b]);
            assert!((len(11, 13) - 0.245 * h).abs() < 1e-6 && (len(13, 15) - 0.246 * h).abs() < 1e-6);
            assert!((len(5, 7) - 0.186 * h).abs() < 1e-6 && (len(7, 9) - 0.146 * h).abs() < 1e-6);
            let top = rider
                .capsules
                .iter()
                .map(|c| c.a.z.max(c.b.z) + c.radius_m)
                .fold(0.0, f64::max);
            assert!((1.45..1.8).contains(&top), "cyclist height {top} m for a 1.75 m rider");
            // Knees forward of the hips, and the nose ahead of the ears (looking along the yaw).
            assert!(local(rider.joints[13]).x > local(rider.joints[11]).x);
            assert!(local(rider.joints[0]).x > local(rider.joints[3]).x);
        }
    }

    /// Pedalling moves the feet in opposition: half a crank turn swaps the pedals' heights.
    #[test]
    fn the_cranks_turn_in_opposition() {
        let a = bicycle(&frame(0.25), 1.75);
        let b = bicycle(&frame(0.75), 1.75);
        assert!((a[9].b.z - b[10].b.z).abs() < 1e-9 && a[9].b.z > a[10].b.z);
    }
}
