//! Articulated pedestrian body: COCO-17 joints and a capsule silhouette, animated from the simulation trace
//! (gait phase and speed for walking, running and standing; head yaw for scanning and traffic checks; a phone
//! pose when distracted; gestures to the driver: a raised hand, a wave, a nod), and the head's gaze direction.
//!
//! Built in the body frame (x forward, y left, z up; origin on the ground under the body's centre) from
//! anthropometric proportions of the body height, then placed in the world by the pedestrian's position and
//! yaw. Allocation-free: everything is fixed-size arrays.

use std::f64::consts::TAU;

use glam::{DMat3, DVec3};

use crate::sim::trace::{Gesture, PedFrame};
use crate::spec::types::PoseFormat;

/// COCO-17 keypoint names, in COCO order.
pub const COCO17: [&str; 17] = [
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

/// OpenPose-18 joints (PedestrianActionBenchmark's order) as COCO-17 indices; the neck (`None`) is the
/// shoulders' midpoint.
pub const OPENPOSE18_FROM_COCO17: [Option<usize>; 18] = [
    Some(0),  // nose
    None,     // neck
    Some(6),  // right shoulder
    Some(8),  // right elbow
    Some(10), // right wrist
    Some(5),  // left shoulder
    Some(7),  // left elbow
    Some(9),  // left wrist
    Some(12), // right hip
    Some(14), // right knee
    Some(16), // right ankle
    Some(11), // left hip
    Some(13), // left knee
    Some(15), // left ankle
    Some(1),  // left eye
    Some(2),  // right eye
    Some(3),  // left ear
    Some(4),  // right ear
];

/// The number of joints of a keypoint format.
pub fn joint_count(format: PoseFormat) -> usize {
    match format {
        PoseFormat::Coco17 => 17,
        PoseFormat::Openpose18 => 18,
    }
}

/// Appends the 17 COCO-order triplets of `coco` to `out` in `format`'s joint order. The third value of each
/// triplet is a visibility flag when `flags` (a derived joint takes the lower of its sources' flags) and a
/// coordinate otherwise (averaged like the first two).
pub fn push_keypoints(coco: &[f32; 51], format: PoseFormat, flags: bool, out: &mut Vec<f32>) {
    match format {
        PoseFormat::Coco17 => out.extend_from_slice(coco),
        PoseFormat::Openpose18 => {
            for joint in OPENPOSE18_FROM_COCO17 {
                match joint {
                    Some(k) => out.extend_from_slice(&coco[3 * k..3 * k + 3]),
                    None => {
                        let (l, r) = (&coco[15..18], &coco[18..21]);
                        let third = if flags { l[2].min(r[2]) } else { 0.5 * (l[2] + r[2]) };
                        out.extend_from_slice(&[0.5 * (l[0] + r[0]), 0.5 * (l[1] + r[1]), third]);
                    }
                }
            }
        }
    }
}

/// Number of capsules in a body silhouette.
pub const CAPSULES: usize = 17;

/// A capsule: the set of points within `radius_m` of the segment `a`–`b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// One end.
    pub a: DVec3,
    /// Other end.
    pub b: DVec3,
    /// Radius, metres.
    pub radius_m: f64,
}

/// A posed body in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPose {
    /// COCO-17 joints.
    pub joints: [DVec3; 17],
    /// The silhouette: torso, head, limbs, feet.
    pub capsules: [Capsule; CAPSULES],
    /// Body height, metres.
    pub height_m: f64,
    /// Ground point under the body centre.
    pub ground: DVec3,
    /// Body yaw.
    pub yaw_rad: f64,
    /// The head's forward direction in the world (unit): where the pedestrian looks.
    pub gaze: DVec3,
}

/// A capsule's mesh (`sensors::scene`) puts its vertices this many radii from its axis (so that the polygon's
/// silhouette matches the capsule's on average): what the cameras and the LiDAR see reaches this far, and the
/// 3D boxes ([`BodyPose::box3d`]) do too.
pub const CAPSULE_MESH_SCALE: f32 = 1.04;

impl BodyPose {
    /// The 3D box around the rendered body (its capsules' meshes, which reach [`CAPSULE_MESH_SCALE`] radii from
    /// their axes: every camera pixel and LiDAR point of the body lies in it), aligned with the body's yaw: its centre in the world and
    /// its extents (length along the yaw, width, height), metres.
    pub fn box3d(&self) -> (DVec3, DVec3) {
        let to_body = DMat3::from_rotation_z(-self.yaw_rad);
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let scale = f64::from(CAPSULE_MESH_SCALE);
        for c in &self.capsules {
            for p in [c.a, c.b] {
                let q = to_body * (p - self.ground);
                lo = lo.min(q - DVec3::splat(c.radius_m * scale));
                hi = hi.max(q + DVec3::splat(c.radius_m * scale));
            }
        }
        (
            self.ground + DMat3::from_rotation_z(self.yaw_rad) * ((lo + hi) * 0.5),
            hi - lo,
        )
    }
}

/// Where a parent's child walks, in the parent's body frame, metres (beside the parent, on its left).
pub const CHILD_OFFSET_M: DVec3 = DVec3::new(0.0, 0.55, 0.0);

/// Head pitch of a pedestrian reading a phone, radians (≈ 34° down). pedsynth: a typical texting posture, and
/// beyond the 30° `look` cone, so a pedestrian reading a phone does not count as looking at a level camera.
pub const PHONE_HEAD_PITCH_RAD: f64 = 0.6;

/// Speed below which a pedestrian stands, m/s.
const STAND_MPS: f64 = 0.15;
/// Speed above which the gait is a run, m/s.
const RUN_MPS: f64 = 2.4;

impl BodyPose {
    /// The points besides the 17 joints whose occlusion counts towards a body's: both ends of the torso, the
    /// head's centre and the middle of both thighs (the capsules of [`silhouette`]'s layout).
    pub fn occlusion_samples(&self) -> [DVec3; 5] {
        let c = &self.capsules;
        [c[0].a, c[0].b, c[2].a, (c[7].a + c[7].b) * 0.5, (c[8].a + c[8].b) * 0.5]
    }
}

/// The head's keypoints (nose, left and right eye, left and right ear) and its centre for a body of height
/// `h` whose neck is at `neck` and whose head is turned by `head_rot` about it: the one head layout of walkers
/// and riders (COCO-17's first five joints).
pub(crate) fn head_points(neck: DVec3, head_rot: DMat3, h: f64) -> ([DVec3; 5], DVec3) {
    let head_point =
        |x: f64, y: f64, z: f64| neck + head_rot * (DVec3::new(x, y, z) * h - DVec3::new(0.0, 0.0, 0.87 * h));
    (
        [
            head_point(0.06, 0.0, 0.92),
            head_point(0.05, 0.018, 0.936),
            head_point(0.05, -0.018, 0.936),
            head_point(-0.005, 0.045, 0.93),
            head_point(-0.005, -0.045, 0.93),
        ],
        head_point(0.0, 0.0, 0.93),
    )
}

/// The capsules of a body of height `h` from its joints in the body frame (COCO order) and its torso points
/// `[pelvis, chest, neck, head centre]` (torso, shoulders, head, upper arms, forearms, thighs, shins, feet, neck,
/// hands and hips), placed in the world by `to_world`: the same silhouette for a walker
/// and a cyclist's rider.
pub(crate) fn silhouette(
    joints: &[DVec3; 17],
    [pelvis, chest, neck, head_centre]: [DVec3; 4],
    h: f64,
    to_world: impl Fn(DVec3) -> DVec3,
) -> [Capsule; CAPSULES] {
    let toe = |ankle: DVec3| ankle + DVec3::new(0.09 * h, 0.0, -0.02 * h);
    // A hand: on from the wrist along the forearm (to the knuckles; the fingers' length again is not drawn).
    let hand = |elbow: DVec3, wrist: DVec3| wrist + (wrist - elbow).normalize_or_zero() * (0.05 * h);
    let cap = |a: DVec3, b: DVec3, r: f64| Capsule {
        a: to_world(a),
        b: to_world(b),
        radius_m: r * h,
    };
    let j = |k: usize| joints[k];
    [
        cap(pelvis, chest, 0.085),
        cap(j(5), j(6), 0.04),
        cap(head_centre, head_centre, 0.07),
        cap(j(5), j(7), 0.03),
        cap(j(6), j(8), 0.03),
        cap(j(7), j(9), 0.025),
        cap(j(8), j(10), 0.025),
        cap(j(11), j(13), 0.045),
        cap(j(12), j(14), 0.045),
        cap(j(13), j(15), 0.035),
        cap(j(14), j(16), 0.035),
        cap(j(15), toe(j(15)), 0.022),
        cap(j(16), toe(j(16)), 0.022),
        cap(neck, head_centre, 0.035),
        cap(j(9), hand(j(7), j(9)), 0.02),
        cap(j(10), hand(j(8), j(10)), 0.02),
        cap(j(11), j(12), 0.05),
    ]
}

/// Poses a body of height `height_m` for one trace frame; `offset_body` shifts it in the body frame (used for
/// a parent's child).
pub fn pose(frame: &PedFrame, height_m: f64, offset_body: DVec3) -> BodyPose {
    let h = height_m;
    let speed = frame.velocity.length();
    let swing = if speed < STAND_MPS {
        0.0
    } else if speed > RUN_MPS {
        0.75
    } else {
        0.3 + 0.2 * (speed / 1.4).min(1.5)
    };
    let phase = TAU * frame.gait_phase;
    let theta = swing * phase.sin();
    let knee = 0.6 * swing * (phase + 1.2).sin().max(0.0);

    // Lower body: legs swing about the hips in the sagittal plane (x forward, z up).
    let hip_z = 0.53 * h;
    let thigh = 0.245 * h;
    let shin = 0.246 * h;
    let hip_y = 0.055 * h;
    let leg = |side: f64, angle: f64, bend: f64| {
        let hip = DVec3::new(0.0, side * hip_y, hip_z);
        let knee_p = hip + DVec3::new(angle.sin(), 0.0, -angle.cos()) * thigh;
        let shin_angle = angle - bend;
        let ankle = knee_p + DVec3::new(shin_angle.sin(), 0.0, -shin_angle.cos()) * shin;
        (hip, knee_p, ankle)
    };
    let (l_hip, l_knee, l_ankle) = leg(1.0, theta, knee);
    let (r_hip, r_knee, r_ankle) = leg(
        -1.0,
        -theta,
        0.6 * swing * (phase + 1.2 + std::f64::consts::PI).sin().max(0.0),
    );

    // Upper body: arms swing opposite to the legs; the right hand holds a phone in front of the chest.
    let shoulder_z = 0.818 * h;
    let shoulder_y = 0.11 * h;
    let upper = 0.186 * h;
    let fore = 0.146 * h;
    let arm = |side: f64, angle: f64| {
        let shoulder = DVec3::new(0.0, side * shoulder_y, shoulder_z);
        let elbow = shoulder + DVec3::new(angle.sin(), 0.0, -angle.cos()) * upper;
        let fore_angle = angle + 0.25;
        let wrist = elbow + DVec3::new(fore_angle.sin(), 0.0, -fore_angle.cos()) * fore;
        (shoulder, elbow, wrist)
    };
    let (l_shoulder, l_elbow, l_wrist) = arm(1.0, -0.8 * theta);
    let (r_shoulder, r_elbow, mut r_wrist) = arm(-1.0, 0.8 * theta);
    let mut head_pitch = 0.0;
    if frame.on_phone {
        r_wrist = DVec3::new(0.25 * h * 0.8, -0.02 * h, 0.72 * h);
        head_pitch = PHONE_HEAD_PITCH_RAD;
    }
    let mut r_elbow = if frame.on_phone {
        DVec3::new(0.06 * h, -shoulder_y, 0.66 * h)
    } else {
        r_elbow
    };
    // Gestures to the driver: the right hand raised (acknowledging) or waving the car on, or a nod; the arm
    // blends in and out of the walking swing over a quarter of a second.
    if let Some((gesture, t)) = frame.gesture {
        let blend = ((t / 0.25).min((gesture.duration_s() - t) / 0.25)).clamp(0.0, 1.0);
        let blend = blend * blend * (3.0 - 2.0 * blend);
        let raised = match gesture {
            Gesture::HandAck => Some((DVec3::new(0.35, -0.6, 0.25), DVec3::new(0.15, 0.0, 1.0))),
            Gesture::HandYield => {
                let sweep = (TAU * 1.2 * t).sin();
                Some((DVec3::new(0.6, -0.6, -0.1), DVec3::new(0.8, -0.3 + 0.6 * sweep, 0.1)))
            }
            Gesture::Nod => {
                head_pitch += 0.35 * blend * (std::f64::consts::PI * t / 0.4).sin().powi(2);
                None
            }
        };
        if let Some((upper_dir, fore_dir)) = raised {
            let elbow = r_shoulder + upper_dir.normalize() * upper;
            let wrist = elbow + fore_dir.normalize() * fore;
            r_elbow = r_elbow.lerp(elbow, blend);
            r_wrist = r_wrist.lerp(wrist, blend);
        }
    }

    // Head: turned by the head yaw about the neck, pitched down when reading a phone.
    let neck = DVec3::new(0.0, 0.0, 0.87 * h);
    let head_rot = DMat3::from_rotation_z(frame.head_yaw_rad) * DMat3::from_rotation_y(head_pitch);
    let ([nose, l_eye, r_eye, l_ear, r_ear], head_centre) = head_points(neck, head_rot, h);

    let local = [
        nose, l_eye, r_eye, l_ear, r_ear, l_shoulder, r_shoulder, l_elbow, r_elbow, l_wrist, r_wrist, l_hip, r_hip,
        l_knee, r_knee, l_ankle, r_ankle,
    ];
    let rot = DMat3::from_rotation_z(frame.yaw_rad);
    let to_world = |p: DVec3| frame.pos + rot * (p + offset_body);
    let joints = local.map(to_world);
    let pelvis = DVec3::new(0.0, 0.0, hip_z);
    let chest = DVec3::new(0.0, 0.0, 0.78 * h);
    BodyPose {
        joints,
        capsules: silhouette(&local, [pelvis, chest, neck, head_centre], h, to_world),
        height_m,
        ground: to_world(DVec3::ZERO),
        yaw_rad: frame.yaw_rad,
        gaze: rot * head_rot * DVec3::X,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::trace::PedState;
    use glam::DVec2;

    fn frame(speed: f64, phase: f64) -> PedFrame {
        PedFrame {
            pos: DVec3::new(5.0, 2.0, 0.0),
            yaw_rad: 0.3,
            velocity: DVec2::from_angle(0.3) * speed,
            state: PedState::WalkingSidewalk,
            lane_type: None,
            head_yaw_rad: 0.0,
            gait_phase: phase,
            on_phone: false,
            gesture: None,
            reaction: None,
            walk_signal: None,
            on_crosswalk: false,
        }
    }

    #[test]
    fn standing_body_has_plausible_proportions() {
        let p = pose(&frame(0.0, 0.0), 1.75, DVec3::ZERO);
        let z = |i: usize| p.joints[i].z;
        assert!(
            z(0) > z(5) && z(5) > z(11) && z(11) > z(13) && z(13) > z(15),
            "nose > shoulder > hip > knee > ankle"
        );
        assert!((z(15) - 0.039 * 1.75).abs() < 0.02, "ankle near the ground: {}", z(15));
        let ext = p.box3d().1;
        assert!((ext.z - 1.75).abs() < 0.05 && ext.y > 0.35 && ext.y < 0.7, "{ext}");
        // Left joints are on the body's left (yaw 0.3: left is +y rotated).
        let left = DVec2::from_angle(0.3).perp();
        assert!((p.joints[5] - p.joints[6]).truncate().dot(left) > 0.0);
    }

    #[test]
    fn walking_swings_the_legs_in_opposition() {
        let p = pose(&frame(1.4, 0.25), 1.75, DVec3::ZERO);
        let fwd = DVec2::from_angle(0.3);
        let l = (p.joints[15] - p.joints[11]).truncate().dot(fwd);
        let r = (p.joints[16] - p.joints[12]).truncate().dot(fwd);
        assert!(l > 0.1 && r < -0.1, "left ankle forward, right back: {l} {r}");
    }

    /// The gaze's heading equals the heading from the ears' midpoint to the nose (the keypoints show where the
    /// head looks), for any head yaw and with the phone's pitch; reading a phone looks down by its pitch.
    #[test]
    fn the_gaze_follows_the_head_keypoints() {
        for (head_yaw, on_phone) in [(0.0, false), (0.7, false), (-1.2, false), (0.4, true)] {
            let mut f = frame(1.0, 0.3);
            f.head_yaw_rad = head_yaw;
            f.on_phone = on_phone;
            let p = pose(&f, 1.7, DVec3::ZERO);
            assert!((p.gaze.length() - 1.0).abs() < 1e-12);
            let nose_dir = p.joints[0] - (p.joints[3] + p.joints[4]) * 0.5;
            let heading = |v: DVec3| v.y.atan2(v.x);
            assert!(
                (heading(p.gaze) - heading(nose_dir)).abs() < 1e-9,
                "yaw {head_yaw}: gaze {} vs nose {}",
                heading(p.gaze),
                heading(nose_dir)
            );
            assert!((heading(p.gaze) - (f.yaw_rad + head_yaw)).abs() < 1e-9);
            let down = (-p.gaze.z).asin();
            let want = if on_phone { PHONE_HEAD_PITCH_RAD } else { 0.0 };
            assert!((down - want).abs() < 1e-9, "pitch {down} vs {want}");
        }
    }

    /// A raised hand puts the right wrist above the head in the middle of the gesture and returns it to the
    /// walking swing at its end; a wave-through holds the arm out in front at shoulder height; a nod pitches
    /// the head down and leaves the arms alone.
    #[test]
    fn gestures_move_the_right_arm_or_the_head() {
        let h = 1.7;
        let plain = pose(&frame(0.0, 0.0), h, DVec3::ZERO);
        let at = |g: Gesture, t: f64| {
            let mut f = frame(0.0, 0.0);
            f.gesture = Some((g, t));
            pose(&f, h, DVec3::ZERO)
        };
        let up = at(Gesture::HandAck, 0.6);
        assert!(up.joints[10].z > up.joints[0].z, "wrist above the nose");
        assert_eq!(up.joints[9], plain.joints[9], "the left wrist does not move");
        let end = at(Gesture::HandAck, Gesture::HandAck.duration_s());
        assert!(
            end.joints[10].distance(plain.joints[10]) < 1e-9,
            "back to the swing at the end"
        );
        let wave = at(Gesture::HandYield, 0.8);
        let fwd = (wave.joints[10] - wave.joints[6])
            .truncate()
            .dot(glam::DVec2::from_angle(0.3));
        assert!(fwd > 0.2 * h, "the hand is held out in front: {fwd}");
        assert!(
            (wave.joints[10].z - wave.joints[6].z).abs() < 0.1 * h,
            "at shoulder height"
        );
        let nod = at(Gesture::Nod, 0.2);
        assert!(nod.gaze.z < -0.3, "nodding looks down: {}", nod.gaze.z);
        assert_eq!(nod.joints[10], plain.joints[10]);
    }

    #[test]
    fn openpose18_reorders_coco17_and_derives_the_neck() {
        let mut coco = [0f32; 51];
        for k in 0..17 {
            coco[3 * k..3 * k + 3].copy_from_slice(&[k as f32, 100.0 + k as f32, 2.0]);
        }
        coco[3 * 6 + 2] = 1.0; // the right shoulder is occluded
        let mut out = Vec::new();
        push_keypoints(&coco, PoseFormat::Openpose18, true, &mut out);
        assert_eq!(out.len(), 54);
        assert_eq!(&out[0..3], &[0.0, 100.0, 2.0], "nose first");
        assert_eq!(
            &out[3..6],
            &[5.5, 105.5, 1.0],
            "neck: shoulders' midpoint, the lower flag"
        );
        assert_eq!(&out[6..9], &[6.0, 106.0, 1.0], "right shoulder");
        assert_eq!(&out[15..18], &[5.0, 105.0, 2.0], "left shoulder");
        assert_eq!(&out[42..45], &[1.0, 101.0, 2.0], "left eye");
        assert_eq!(&out[51..54], &[4.0, 104.0, 2.0], "right ear last");
        out.clear();
        push_keypoints(&coco, PoseFormat::Coco17, true, &mut out);
        assert_eq!(out, coco);
    }
}
