//! Articulated pedestrian body: COCO-17 joints and a capsule silhouette, animated from the simulation trace
//! (gait phase and speed for walking, running and standing; head yaw for scanning and traffic checks; a phone
//! pose when distracted; gestures to the driver: a raised hand, a wave, a nod), and the head's gaze direction.
//!
//! Built in the body frame (x forward, y left, z up; origin on the ground under the body's centre) from
//! anthropometric proportions of the body height, then placed in the world by the pedestrian's position and
//! yaw. Allocation-free: everything is fixed-size arrays.

use std::f64::consts::TAU;

use glam::{DMat3, DVec3};

use crate::plan::{Carry, Figure, Garment, HairStyle};
use crate::sim::trace::{Gesture, PedFrame};

/// Number of capsules in a body silhouette: 18 of the body (always present), 4 of its figure (hair, headwear,
/// bag, garment; absent ones have a radius of 0) and the jaw.
pub const CAPSULES: usize = 23;

/// The jaw's capsule in a silhouette ([`silhouette`]): below the front of the skull (capsule 2), narrower than it.
pub const JAW: usize = 22;

/// A capsule: the set of points within `radius_m` of the segment `a`–`b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// One end.
    pub a: DVec3,
    /// Other end.
    pub b: DVec3,
    /// Radius, metres (0: a part the figure does not have).
    pub radius_m: f64,
}

impl Capsule {
    /// A part a figure does not have.
    pub const ABSENT: Capsule = Capsule {
        a: DVec3::ZERO,
        b: DVec3::ZERO,
        radius_m: 0.0,
    };

    /// Whether the capsule is drawn (a figure's absent parts are not).
    pub fn is_present(&self) -> bool {
        self.radius_m > 0.0
    }
}

/// A posed body in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPose {
    /// COCO-17 joints.
    pub joints: [DVec3; 17],
    /// The silhouette: torso, head, limbs, feet, and the figure's hair, headwear, bag and garment (absent
    /// ones have a radius of 0: iterate [`BodyPose::parts`]).
    pub capsules: [Capsule; CAPSULES],
    /// Body height, metres.
    pub height_m: f64,
    /// Ground point under the body centre.
    pub ground: DVec3,
    /// Body yaw.
    pub yaw_rad: f64,
    /// The head's forward direction in the world (unit): where the pedestrian looks.
    pub gaze: DVec3,
    /// An open umbrella held in the left hand ([`Figure::umbrella`]): not part of the body (its capsules, box and
    /// keypoints leave it out).
    pub umbrella: Option<Umbrella>,
}

/// An open umbrella in the world: a shaft from the hand's grip up to the canopy's centre, and a canopy (a low
/// cone of `radius_m`) around the shaft's axis, its rim [`Umbrella::RIM_DROP_M`] below the top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Umbrella {
    /// Where the hand holds the shaft (the left hand's knuckles).
    pub grip: DVec3,
    /// The shaft's top: the canopy's centre, where its ribs meet.
    pub top: DVec3,
    /// The canopy's radius, metres.
    pub radius_m: f64,
}

impl Umbrella {
    /// How far the canopy's rim hangs below its top along the shaft, metres.
    pub const RIM_DROP_M: f64 = 0.13;
    /// How far the canopy's peak stands above its top along the shaft, metres.
    pub const PEAK_M: f64 = 0.05;
    /// The canopy's radius: a common 95–105 cm umbrella's.
    pub const RADIUS_M: f64 = 0.5;
}

/// A capsule's mesh (`sensors::scene`) puts its vertices this many radii from its axis (so that the polygon's
/// silhouette matches the capsule's on average): what the cameras and the LiDAR see reaches this far, and the
/// 3D boxes ([`BodyPose::box3d`]) do too.
pub const CAPSULE_MESH_SCALE: f32 = 1.04;

impl BodyPose {
    /// The capsules that are drawn (the figure's absent parts left out).
    pub fn parts(&self) -> impl Iterator<Item = &Capsule> + Clone {
        self.capsules.iter().filter(|c| c.is_present())
    }

    /// The 3D box around the rendered body (its capsules' meshes, which reach [`CAPSULE_MESH_SCALE`] radii from
    /// their axes: every camera pixel and LiDAR point of the body lies in it), aligned with the body's yaw: its centre in the world and
    /// its extents (length along the yaw, width, height), metres.
    pub fn box3d(&self) -> (DVec3, DVec3) {
        let to_body = DMat3::from_rotation_z(-self.yaw_rad);
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let scale = f64::from(CAPSULE_MESH_SCALE);
        for c in self.parts() {
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
    /// middle of the skull (capsule 2's; since the jaw, 1.6 cm above the head's centre for a 1.75 m adult) and the
    /// middle of both thighs (the capsules of [`silhouette`]'s layout: the torso's two halves are capsules 0 and
    /// 17).
    pub fn occlusion_samples(&self) -> [DVec3; 5] {
        let c = &self.capsules;
        let mid = |a: DVec3, b: DVec3| (a + b) * 0.5;
        [
            mid(c[0].a, c[17].a),
            mid(c[0].b, c[17].b),
            mid(c[2].a, c[2].b),
            mid(c[7].a, c[7].b),
            mid(c[8].a, c[8].b),
        ]
    }
}

/// How much larger a head is, against the body's height, than an adult's: 1 for adults (1.5 m and taller),
/// up to 1.25 for a 1.0 m child (a young child's head is about a sixth of its height, an adult's about an
/// eighth).
pub(crate) fn head_scale(h: f64) -> f64 {
    1.0 + 0.25 * ((1.5 - h) / 0.5).clamp(0.0, 1.0)
}

/// A hand's length from the wrist along the forearm to the knuckles (the fingers' length again is not drawn), a
/// fraction of the body height.
const HAND_LENGTH: f64 = 0.05;
/// A foot's heel and toe in the body frame relative to the ankle (forward, up), in body heights, before its
/// pitch.
const FOOT_HEEL: (f64, f64) = (-0.035, -0.014);
/// See [`FOOT_HEEL`].
const FOOT_TOE: (f64, f64) = (0.09, -0.02);
/// The share of the shin's lean from vertical that the foot's pitch follows.
const FOOT_PITCH: f64 = 1.0;
/// Shoulders follow a large head turn: a head turned beyond [`SHOULDER_TWIST`]`.0` radians from the hips
/// (30°) takes the shoulders along by [`SHOULDER_TWIST`]`.1` of the excess (a look over the shoulder at the
/// 80° limit: the shoulders 25° round, the head 55° on them). Land (2004), gaze shifts: the trunk joins the
/// eyes and the head for shifts beyond about 60°.
const SHOULDER_TWIST: (f64, f64) = (0.52, 0.5);

/// The shoulders' twist about the spine for a head yaw (radians, relative to the hips), radians.
fn shoulder_twist(head_yaw_rad: f64) -> f64 {
    head_yaw_rad.signum() * SHOULDER_TWIST.1 * (head_yaw_rad.abs() - SHOULDER_TWIST.0).max(0.0)
}

/// The skull: an upright capsule of this radius (its width: 16.5 cm for a 1.75 m adult) and length, fractions of
/// the body height (an adult's), from the head's centre (ear level: its lower end) up; with the jaw below its front
/// the head is 23 cm tall.
const HEAD_RADIUS: f64 = 0.047;
const SKULL_LENGTH: f64 = 0.018;
/// The jaw: a capsule of this radius (10 cm wide for a 1.75 m adult: narrower than the skull, so that a head seen
/// from behind or three-quarters behind shows a round head of hair over a neck, not a face as wide as the skull)
/// from below the ears forward and down to the chin, in the head's frame (forward, up), fractions of the body
/// height.
const JAW_RADIUS: f64 = 0.028;
const JAW_BACK: (f64, f64) = (-0.004, -0.022);
const JAW_CHIN: (f64, f64) = (0.016, -0.037);

/// The head's keypoints (nose, left and right eye, left and right ear) and its centre for a body of height
/// `h` whose neck is at `neck` and whose head is turned by `head_rot` about it: the one head layout of walkers
/// and riders (COCO-17's first five joints), on or just inside the head's surface (its capsule renders no nose).
/// The head's top is at the body's height; a child's larger head ([`head_scale`]) sits on a shorter neck.
pub(crate) fn head_points(neck: DVec3, head_rot: DMat3, h: f64) -> ([DVec3; 5], DVec3) {
    let s = head_scale(h);
    let centre = neck + head_rot * DVec3::new(0.0, 0.0, (0.13 - (HEAD_RADIUS + SKULL_LENGTH) * s) * h);
    let head_point = |x: f64, y: f64, z: f64| centre + head_rot * (DVec3::new(x, y, z - 0.93) * (h * s));
    (
        [
            head_point(0.045, 0.0, 0.92),
            head_point(0.04, 0.018, 0.936),
            head_point(0.04, -0.018, 0.936),
            head_point(-0.005, 0.045, 0.93),
            head_point(-0.005, -0.045, 0.93),
        ],
        centre,
    )
}

/// The capsules of a body of height `h` and figure `figure` from its joints in the body frame (COCO order), its
/// torso points `[pelvis, chest, neck, head centre]` and its head's rotation (torso, shoulders, head, upper
/// arms, forearms, thighs, shins, feet, neck, hands and hips, then the figure's hair (a hood's gathered back
/// when the hood is up), headwear, bag and garment), placed in the world by `to_world`: the same silhouette for a walker and a cyclist's rider.
pub(crate) fn silhouette(
    joints: &[DVec3; 17],
    [pelvis, chest, neck, head_centre]: [DVec3; 4],
    head_rot: DMat3,
    h: f64,
    figure: &Figure,
    to_world: impl Fn(DVec3) -> DVec3,
) -> [Capsule; CAPSULES] {
    // A foot from its heel, a little behind and below the ankle, to its toe, pitched with the shin (by
    // `FOOT_PITCH` of the shin's lean): toes up as the leading foot strikes, heel up as the trailing one pushes
    // off, so that a walker seen from behind shows the heels and soles.
    let foot = |knee: DVec3, ankle: DVec3| {
        let shin = ankle - knee;
        let pitch = FOOT_PITCH * shin.x.atan2(-shin.z);
        let (sin, cos) = pitch.sin_cos();
        let at = |x: f64, z: f64| ankle + DVec3::new(x * cos - z * sin, 0.0, x * sin + z * cos) * h;
        (at(FOOT_HEEL.0, FOOT_HEEL.1), at(FOOT_TOE.0, FOOT_TOE.1))
    };
    let (l_heel, l_toe) = foot(joints[13], joints[15]);
    let (r_heel, r_toe) = foot(joints[14], joints[16]);
    let hand = |elbow: DVec3, wrist: DVec3| wrist + (wrist - elbow).normalize_or_zero() * (HAND_LENGTH * h);
    let cap = |a: DVec3, b: DVec3, r: f64| Capsule {
        a: to_world(a),
        b: to_world(b),
        radius_m: r * h,
    };
    let j = |k: usize| joints[k];
    let g = figure.build.clamp(0.7, 1.4);
    let head_s = head_scale(h);
    let head_r = HEAD_RADIUS * head_s;
    let in_head = |x: f64, z: f64| head_centre + head_rot * (DVec3::new(x, 0.0, z) * (h * head_s));
    // The torso's axis (up the spine) and the direction out of the back, perpendicular to it.
    let torso_m = (chest - pelvis).length();
    let up = (chest - pelvis).normalize_or(DVec3::Z);
    let back = DVec3::new(-up.z, 0.0, up.x);
    // The torso: two capsules side by side (wider than deep: 35 cm by 21 cm for an average 1.75 m adult), axes closer at
    // the waist than at the chest; the hem about the hip joints, so that trousers show the seat (BENCHMARKS).
    let torso_r = 0.06 * g;
    // The chest turns with the shoulders (their line's twist about the spine, see [`shoulder_twist`]).
    let across = joints[5] - joints[6];
    let twist = DMat3::from_rotation_z((-across.x).atan2(across.y));
    let torso_half = |side: f64| {
        (
            pelvis + DVec3::new(0.0, side * 0.03 * h * g, 0.0) + up * (0.05 * h),
            chest + twist * DVec3::new(0.0, side * 0.042 * h * g, 0.0),
        )
    };
    let ((l_waist, l_chest), (r_waist, r_chest)) = (torso_half(1.0), torso_half(-1.0));
    let skull_axis = head_rot * DVec3::Z * (SKULL_LENGTH * head_s * h);
    let hair = match figure.hair {
        // Under a hood the hair is tucked in; its capsule is the hood's fabric gathered at the nape, behind the
        // neck and as wide as it (a bare dome read as a face-less front: MediaPipe mirrored 69 % of hooded back
        // views, 52 % with this; BENCHMARKS).
        _ if figure.hood => {
            let (behind, across) = (twist * back * (0.035 * h), twist * DVec3::new(0.0, 0.03 * h, 0.0));
            cap(neck + behind + across, neck + behind - across, 0.025)
        }
        // Long hair falls from the crown down the back of the head onto the shoulder blades, as wide as the skull
        // (narrower, MediaPipe took more long-haired people seen from behind for people facing it).
        HairStyle::Long => cap(in_head(-0.018, 0.015), in_head(-0.035, -0.105), HEAD_RADIUS * head_s),
        HairStyle::Bun => cap(in_head(-0.062, 0.03), in_head(-0.062, 0.03), 0.026 * head_s),
        HairStyle::Short | HairStyle::Bald => Capsule::ABSENT,
    };
    // A hat: a dome a little larger than the head's top, down to above the eyebrows. A hood: a capsule a little
    // larger than the head, set back so that the face shows, down over the back of the neck.
    let headwear = match (figure.hood, figure.headwear) {
        (true, _) => cap(
            in_head(-0.012, 0.015),
            in_head(-0.025, -0.045),
            (HEAD_RADIUS + 0.006) * head_s,
        ),
        (false, Some(_)) => cap(in_head(0.0, 0.032), in_head(0.0, 0.032), 0.049 * head_s),
        (false, None) => Capsule::ABSENT,
    };
    let carry = match figure.carry {
        Some((Carry::Backpack, _)) => {
            let off = twist * back * ((torso_r + 0.045) * h);
            cap(
                pelvis + up * (0.45 * torso_m) + off,
                pelvis + up * (0.95 * torso_m) + off,
                0.055,
            )
        }
        // A shoulder bag: a pouch at the hip, 10 cm thick and 24 cm tall for a 1.75 m adult (a ball 14 cm thick
        // stood out from behind; MediaPipe missed a woman carrying one in 5 of her 30 crops, none with this one).
        Some((Carry::ShoulderBag, _)) => {
            let side = DVec3::new(-0.02 * h, (0.055 + 0.045 * g + 0.032) * h, 0.0);
            cap(pelvis + side + up * (0.025 * h), pelvis + side - up * (0.05 * h), 0.03)
        }
        None => Capsule::ABSENT,
    };
    let garment = match figure.garment {
        // Over the thighs, about as wide as the hips (the thighs swing through it when striding); a coat's skirt
        // stays narrower than the hanging arms' reach, so that the arms show against it.
        Garment::Skirt | Garment::Dress => cap(pelvis - up * (0.02 * h), pelvis - up * (0.15 * h), 0.085 * g),
        Garment::Coat => cap(pelvis + up * (0.3 * torso_m), pelvis - up * (0.7 * torso_m), 0.075 * g),
        Garment::Trousers => Capsule::ABSENT,
    };
    let jaw = cap(
        in_head(JAW_BACK.0, JAW_BACK.1),
        in_head(JAW_CHIN.0, JAW_CHIN.1),
        JAW_RADIUS * head_s,
    );
    [
        cap(l_waist, l_chest, torso_r),
        cap(j(5), j(6), 0.04 * g),
        cap(head_centre, head_centre + skull_axis, head_r),
        cap(j(5), j(7), 0.03 * g),
        cap(j(6), j(8), 0.03 * g),
        cap(j(7), j(9), 0.025 * g),
        cap(j(8), j(10), 0.025 * g),
        cap(j(11), j(13), 0.045 * g),
        cap(j(12), j(14), 0.045 * g),
        cap(j(13), j(15), 0.035 * g),
        cap(j(14), j(16), 0.035 * g),
        cap(l_heel, l_toe, 0.022),
        cap(r_heel, r_toe, 0.022),
        cap(neck, head_centre, 0.035),
        cap(j(9), hand(j(7), j(9)), 0.02),
        cap(j(10), hand(j(8), j(10)), 0.02),
        cap(j(11), j(12), 0.055 * g), // hips 38.5 cm across, dressed, for an average 1.75 m adult
        cap(r_waist, r_chest, torso_r),
        hair,
        headwear,
        carry,
        garment,
        jaw,
    ]
}

/// Poses a body of height `height_m` and figure `figure` for one trace frame; `offset_body` shifts it in the body frame (used for
/// a parent's child).
pub fn pose(frame: &PedFrame, height_m: f64, figure: &Figure, offset_body: DVec3) -> BodyPose {
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
    // Broader shoulders for a heavier build, and arms that hang a little away from the body (abducted by
    // about 7° at the shoulder and 9° at the elbow), so that they stay clear of the torso's sides.
    let g = figure.build.clamp(0.7, 1.4);
    let shoulder_y = 0.11 * h * (0.6 + 0.4 * g);
    let upper = 0.186 * h;
    let fore = 0.146 * h;
    let arm = |side: f64, angle: f64| {
        let shoulder = DVec3::new(0.0, side * shoulder_y, shoulder_z);
        let elbow = shoulder + DVec3::new(angle.sin(), side * 0.12, -angle.cos()).normalize() * upper;
        let fore_angle = angle + 0.25;
        let wrist = elbow + DVec3::new(fore_angle.sin(), side * 0.16, -fore_angle.cos()).normalize() * fore;
        (shoulder, elbow, wrist)
    };
    let (l_shoulder, mut l_elbow, mut l_wrist) = arm(1.0, -0.8 * theta);
    // An umbrella: the left arm holds it still (no swing), the upper arm hanging a little forward, the forearm
    // raised about 45° forward and across to a grip at chest height some 20 cm ahead of the chest, so that the
    // bent arm shows beside the body seen from the side (a forearm raised steeply put the grip against the chest,
    // where a side view hid the arm; MediaPipe then found the holder in fewer crops); the shaft leans back from
    // the grip to a top above and just ahead of the head's centre, so the canopy's rim clears the head.
    let umbrella = figure.umbrella.map(|_| {
        l_elbow = l_shoulder + DVec3::new(0.15, 0.1, -1.0).normalize() * upper;
        let fore_dir = DVec3::new(0.65, -0.35, 0.65).normalize();
        l_wrist = l_elbow + fore_dir * fore;
        let grip = l_wrist + fore_dir * (HAND_LENGTH * h);
        (grip, DVec3::new(0.07 * h, 0.3 * grip.y, h + 0.33))
    });
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

    // The shoulders, arms and what the hands hold turn about the spine with a large head turn.
    let twist = DMat3::from_rotation_z(shoulder_twist(frame.head_yaw_rad));
    let [l_shoulder, r_shoulder, l_elbow, r_elbow, l_wrist, r_wrist] =
        [l_shoulder, r_shoulder, l_elbow, r_elbow, l_wrist, r_wrist].map(|p| twist * p);
    let umbrella = umbrella.map(|(grip, top)| (twist * grip, twist * top));

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
        capsules: silhouette(
            &local,
            [pelvis, chest, neck, head_centre],
            head_rot,
            h,
            figure,
            to_world,
        ),
        height_m,
        ground: to_world(DVec3::ZERO),
        yaw_rad: frame.yaw_rad,
        gaze: rot * head_rot * DVec3::X,
        umbrella: umbrella.map(|(grip, top)| Umbrella {
            grip: to_world(grip),
            top: to_world(top),
            radius_m: Umbrella::RADIUS_M,
        }),
    }
}

#[cfg(test)]
#[path = "body_tests.rs"]
mod tests;
