//! Tests of the articulated body ([`super`]): proportions, feet, figures on one skeleton, gait, gestures and
//! the umbrella.

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
    let p = pose(&frame(0.0, 0.0), 1.75, &Figure::PLAIN, DVec3::ZERO);
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

/// A foot runs from a heel behind the ankle to a toe ahead of it, on the ground when standing, and rolls
/// with the stride, square to its shin: toes up where the shin leans forward (heel strike), heel up where it
/// leans back (push-off).
#[test]
fn feet_have_heels_and_roll_with_the_stride() {
    let standing = pose(&frame(0.0, 0.0), 1.75, &Figure::PLAIN, DVec3::ZERO);
    let forward = DVec2::from_angle(standing.yaw_rad).extend(0.0);
    for (foot, ankle) in [(11, 15), (12, 16)] {
        let (c, a) = (standing.capsules[foot], standing.joints[ankle]);
        assert!((c.a - a).dot(forward) < -0.04, "the heel 4+ cm behind the ankle: {c:?}");
        assert!((c.b - a).dot(forward) > 0.12, "the toe ahead of it: {c:?}");
        for end in [c.a, c.b] {
            assert!((-0.02..0.03).contains(&(end.z - c.radius_m)), "on the ground: {c:?}");
        }
    }
    let (mut toes_up, mut heels_up) = (0, 0);
    for step in 0..40 {
        let p = pose(&frame(1.3, f64::from(step) / 40.0), 1.75, &Figure::PLAIN, DVec3::ZERO);
        for (foot, knee, ankle) in [(11, 13, 15), (12, 14, 16)] {
            let (c, shin) = (p.capsules[foot], p.joints[ankle] - p.joints[knee]);
            let along = (c.b - c.a).normalize();
            assert!(
                along.dot(shin.normalize()).abs() < 0.1,
                "square to the shin: {c:?} {shin}"
            );
            let lean = shin.dot(forward);
            if lean > 0.05 {
                assert!(c.b.z > c.a.z + 0.02, "toes up at heel strike: {c:?}");
                toes_up += 1;
            } else if lean < -0.05 {
                assert!(c.a.z > c.b.z + 0.02, "heel up at push-off: {c:?}");
                heels_up += 1;
            }
        }
    }
    assert!(toes_up > 5 && heels_up > 5, "{toes_up} {heels_up}");
}

/// A figure's parts hang on the body: each present one touches the body's own capsules (hair and hat on
/// the head, a bag at the back or the hip, a skirt or coat over the thighs) and leaves the joints where they
/// are (the build alone broadens the shoulders); absent ones are left out of the
/// parts and the box; a heavy build is wider than a slim one; a child's head is larger against its height.
#[test]
fn figures_dress_the_same_skeleton() {
    use crate::plan::{Carry, Garment, HairStyle};
    let f = frame(1.3, 0.4);
    let plain = pose(&f, 1.75, &Figure::PLAIN, DVec3::ZERO);
    assert_eq!(plain.parts().count(), 19, "the body's 18 capsules and the jaw");
    // The head: a skull from the head's centre up, and a jaw narrower than it, below its front, touching it.
    let (skull, jaw) = (plain.capsules[2], plain.capsules[JAW]);
    let forward = DVec2::from_angle(plain.yaw_rad).extend(0.0);
    assert!(jaw.radius_m < 0.7 * skull.radius_m, "{jaw:?} {skull:?}");
    assert!(
        jaw.b.z < skull.a.z && (jaw.b - skull.a).dot(forward) > 0.0,
        "the chin below and before the centre"
    );
    assert!(jaw.a.distance(skull.a) < skull.radius_m, "the jaw hangs on the skull");
    let touches = |c: &Capsule, body: &[Capsule]| {
        body.iter().any(|b| {
            let d = (0..=20)
                .flat_map(|i| (0..=20).map(move |k| (f64::from(i) / 20.0, f64::from(k) / 20.0)))
                .map(|(s, t)| c.a.lerp(c.b, s).distance(b.a.lerp(b.b, t)))
                .fold(f64::INFINITY, f64::min);
            d <= c.radius_m + b.radius_m + 0.01
        })
    };
    for (hair, garment, carry) in [
        (HairStyle::Long, Garment::Skirt, Carry::Backpack),
        (HairStyle::Bun, Garment::Coat, Carry::ShoulderBag),
        (HairStyle::Bald, Garment::Dress, Carry::Backpack),
    ] {
        let figure = Figure {
            build: 1.2,
            hair,
            headwear: Some([10, 10, 10]),
            garment,
            carry: Some((carry, [20, 20, 20])),
            umbrella: None,
            hood: false,
            pattern: None,
        };
        let p = pose(&f, 1.75, &figure, DVec3::ZERO);
        let average = pose(&f, 1.75, &Figure { build: 1.0, ..figure }, DVec3::ZERO);
        assert_eq!(
            average.joints, plain.joints,
            "only the build moves joints (the shoulders)"
        );
        let extra: Vec<&Capsule> = p.capsules[18..JAW].iter().filter(|c| c.is_present()).collect();
        assert_eq!(extra.len(), if hair == HairStyle::Bald { 3 } else { 4 });
        for c in extra {
            assert!(
                touches(c, &p.capsules[..18]),
                "{hair:?} {garment:?} {carry:?}: a part off the body: {c:?}"
            );
        }
        assert!(p.box3d().1.y > plain.box3d().1.y, "{carry:?} widens the body");
        assert!(
            carry != Carry::ShoulderBag || p.capsules[20].radius_m * 2.0 < 0.11,
            "a pouch, not a ball"
        );
    }
    let slim = pose(
        &f,
        1.75,
        &Figure {
            build: 0.85,
            ..Figure::PLAIN
        },
        DVec3::ZERO,
    );
    assert!(slim.capsules[0].radius_m < plain.capsules[0].radius_m);
    let child = pose(&f, 1.0, &Figure::PLAIN, DVec3::ZERO);
    assert!(child.capsules[2].radius_m / 1.0 > 1.2 * plain.capsules[2].radius_m / 1.75);
    let top = |p: &BodyPose| p.parts().map(|c| c.a.z.max(c.b.z) + c.radius_m).fold(0.0, f64::max);
    assert!((top(&child) - 1.0).abs() < 0.03 && (top(&plain) - 1.75).abs() < 0.03);
}

#[test]
fn walking_swings_the_legs_in_opposition() {
    let p = pose(&frame(1.4, 0.25), 1.75, &Figure::PLAIN, DVec3::ZERO);
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
        let p = pose(&f, 1.7, &Figure::PLAIN, DVec3::ZERO);
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

/// A look over the shoulder turns the shoulders, the chest and the arms with the head (by half the turn
/// beyond 30°), while the hips stay square to the walk and the gaze keeps the head's yaw; a glance leaves
/// the shoulders square.
#[test]
fn shoulders_follow_a_look_over_the_shoulder() {
    let line = |p: &BodyPose| {
        let d = p.joints[5] - p.joints[6];
        (-d.x).atan2(d.y)
    };
    let hip_line = |p: &BodyPose| {
        let d = p.joints[11] - p.joints[12];
        (-d.x).atan2(d.y)
    };
    let wrap = crate::world::opendrive::geometry::wrap_angle;
    for (head_yaw, want) in [(0.3, 0.0), (-0.5, 0.0), (1.4, 0.44), (-1.2, -0.34)] {
        let mut f = frame(1.0, 0.3);
        f.head_yaw_rad = head_yaw;
        let p = pose(&f, 1.7, &Figure::PLAIN, DVec3::ZERO);
        let twist = wrap(line(&p) - f.yaw_rad);
        assert!(
            (twist - want).abs() < 1e-9,
            "head {head_yaw}: shoulders {twist}, want {want}"
        );
        assert!(wrap(hip_line(&p) - f.yaw_rad).abs() < 1e-9, "hips stay square");
        assert!((p.gaze.y.atan2(p.gaze.x) - (f.yaw_rad + head_yaw)).abs() < 1e-9);
        // The chest's two halves turn with the shoulders, their waists do not.
        let chest = p.capsules[0].b - p.capsules[17].b;
        let waist = p.capsules[0].a - p.capsules[17].a;
        assert!((wrap((-chest.x).atan2(chest.y) - f.yaw_rad) - want).abs() < 1e-9);
        assert!(wrap((-waist.x).atan2(waist.y) - f.yaw_rad).abs() < 1e-9);
    }
}

/// A raised hand puts the right wrist above the head in the middle of the gesture and returns it to the
/// walking swing at its end; a wave-through holds the arm out in front at shoulder height; a nod pitches
/// the head down and leaves the arms alone.
#[test]
fn gestures_move_the_right_arm_or_the_head() {
    let h = 1.7;
    let plain = pose(&frame(0.0, 0.0), h, &Figure::PLAIN, DVec3::ZERO);
    let at = |g: Gesture, t: f64| {
        let mut f = frame(0.0, 0.0);
        f.gesture = Some((g, t));
        pose(&f, h, &Figure::PLAIN, DVec3::ZERO)
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

/// An umbrella is held in the left hand: only the left elbow and wrist move (the arm stops swinging), the
/// shaft starts at the hand's end, and the canopy's rim stays at least 3 cm above the top of the head (hat,
/// hood and bun included) for every height and gait, so that a camera below it sees the face; the canopy is over the
/// head, and it is not part of the body's box.
#[test]
fn an_umbrella_is_held_in_the_left_hand_above_the_head() {
    use crate::plan::HairStyle;
    for h in [1.55, 1.75, 1.95] {
        for (speed, phase) in [(0.0, 0.0), (1.3, 0.2), (1.3, 0.7), (3.0, 0.4)] {
            let f = frame(speed, phase);
            let dressed = Figure {
                hair: HairStyle::Bun,
                headwear: Some([10, 10, 10]),
                ..Figure::PLAIN
            };
            // A hood stands higher than a hat.
            let dressed = if speed > 2.0 {
                Figure {
                    hood: true,
                    headwear: None,
                    ..dressed
                }
            } else {
                dressed
            };
            let with = Figure {
                umbrella: Some([20, 20, 20]),
                ..dressed
            };
            let (p, bare) = (pose(&f, h, &with, DVec3::ZERO), pose(&f, h, &dressed, DVec3::ZERO));
            assert!(bare.umbrella.is_none());
            let u = p.umbrella.expect("an umbrella");
            for k in (0..17).filter(|k| ![7, 9].contains(k)) {
                assert_eq!(p.joints[k], bare.joints[k], "joint {k}");
            }
            assert!(
                p.capsules[14].b.distance(u.grip) < 1e-9,
                "the grip is the left hand's end"
            );
            let axis = (u.top - u.grip).normalize();
            let lowest_rim_z = u.top.z - Umbrella::RIM_DROP_M * axis.z - u.radius_m * (1.0 - axis.z * axis.z).sqrt();
            let scale = f64::from(CAPSULE_MESH_SCALE);
            let head_top_z = [2, 18, 19]
                .iter()
                .map(|&k| &p.capsules[k])
                .filter(|c| c.is_present())
                .map(|c| c.a.z.max(c.b.z) + c.radius_m * scale)
                .fold(f64::MIN, f64::max);
            assert!(
                lowest_rim_z >= head_top_z + 0.03,
                "h {h}, speed {speed}: rim {lowest_rim_z:.3} m, head top {head_top_z:.3} m"
            );
            let head = (p.capsules[2].a + p.capsules[2].b) * 0.5;
            assert!(
                (u.top - head).truncate().length() < 0.5 * u.radius_m,
                "h {h}: canopy beside the head"
            );
            assert!(p.box3d().1.z < h + 0.05, "h {h}: the umbrella is in the box");
        }
    }
}

/// A top's hem falls about the hip joints, so that trousers show the seat below it from behind (hemmed 10 cm lower,
/// a top hid it and MediaPipe took 30 % of the back views it found for front views, BENCHMARKS.md), and the hips are
/// as wide as a dressed adult's (38.5 cm for 1.75 m of average build).
#[test]
fn a_top_ends_about_the_hip_joints_and_the_seat_shows_below_it() {
    let h = 1.75;
    for speed in [0.0, 1.3] {
        let p = pose(&frame(speed, 0.25), h, &Figure::PLAIN, DVec3::ZERO);
        let hip_z = 0.5 * (p.joints[11].z + p.joints[12].z);
        let bottom = |c: &Capsule| c.a.z.min(c.b.z) - c.radius_m;
        let hem = bottom(&p.capsules[0]).min(bottom(&p.capsules[17]));
        assert!(
            hem < hip_z && hem > hip_z - 0.03,
            "speed {speed}: hem {hem:.3}, hips {hip_z:.3}"
        );
        let hips = p.capsules[16];
        assert!(bottom(&hips) < hem - 0.06, "the seat shows 6+ cm below the hem");
        let across = hips.a.distance(hips.b) + 2.0 * hips.radius_m;
        assert!((0.37..0.40).contains(&across), "hips {across:.3} m across");
    }
}

/// Under a hood the hair is tucked in, and its capsule is the hood's fabric gathered at the nape: behind the
/// neck (4–9 cm), as wide as it (15–22 cm across), at the neck's height, whatever the hair (fails on a hood
/// drawn as a bare dome, where long hair hung below it and short hair had no capsule).
#[test]
fn a_hood_is_gathered_at_the_nape_behind_the_neck() {
    use crate::plan::HairStyle;
    let h = 1.75;
    let forward = DVec2::from_angle(0.3).extend(0.0);
    for hair in [HairStyle::Long, HairStyle::Short, HairStyle::Bun, HairStyle::Bald] {
        for speed in [0.0, 1.3] {
            let hooded = Figure {
                hair,
                hood: true,
                ..Figure::PLAIN
            };
            let p = pose(&frame(speed, 0.25), h, &hooded, DVec3::ZERO);
            let (nape, neck) = (p.capsules[18], p.capsules[13]);
            assert!(nape.radius_m > 0.0, "{hair:?}: a capsule");
            let mid = 0.5 * (nape.a + nape.b);
            let behind = (neck.a - mid).dot(forward);
            assert!(
                (0.04..0.09).contains(&behind),
                "{hair:?}: {behind:.3} m behind the neck"
            );
            let across = nape.a.distance(nape.b) + 2.0 * nape.radius_m;
            assert!((0.15..0.22).contains(&across), "{hair:?}: {across:.3} m across");
            assert!((mid.z - neck.a.z).abs() < 0.03, "{hair:?}: at the neck's height");
        }
    }
    // Without a hood, long hair still falls from the crown.
    let long = Figure {
        hair: HairStyle::Long,
        ..Figure::PLAIN
    };
    let p = pose(&frame(0.0, 0.0), h, &long, DVec3::ZERO);
    assert!(
        p.capsules[18].a.z.max(p.capsules[18].b.z) > p.capsules[13].b.z,
        "from the crown"
    );
}
