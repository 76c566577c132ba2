//! How people's surfaces look, for the shading: cloth patterns (stripes and checks) on tops, dresses and coats,
//! the hair and face of a head, and a body capsule's smooth normals. Pure functions of a primitive and the lanes'
//! points, in linear RGB.

use glam::Vec3;
use std::ops::Sub;

use super::lanes::{F, V3};
use super::round::floor_int;
use crate::sensors::scene::{PATTERN_STRIPES, Prim, SceneCapsule};

/// Period of a striped top, metres (stripes 4.5 cm wide).
const STRIPE_PERIOD_M: f32 = 0.09;
/// Period of a checked top, metres.
const CHECK_PERIOD_M: f32 = 0.08;

/// How much of the second colour a patterned cloth shows at the lanes' points (0–1): soft-edged stripes of half
/// the period along the height (and across the body, `right` the body's right, for checks), faded to their mean
/// (0.5) from 10 m to 22 m deep, where a period spans under three pixels of a 1280-pixel-wide 90° camera and
/// would alias (labels never see it).
#[inline(always)]
pub(super) fn pattern_share(pattern: u32, p: V3, right: Vec3, depth_m: F) -> F {
    let band = |q: F, period: f32| {
        let t = q * (1.0 / period);
        let f = t - floor_int(t).round_float();
        // A triangle wave (0 at the stripe's middle, 1 at the gap's), edges soft over a sixth of the period.
        let tri = (f * 2.0 - F::ONE).abs();
        (tri * 3.0 - F::ONE).fast_max(F::ZERO).fast_min(F::ONE)
    };
    let m = match pattern {
        PATTERN_STRIPES => band(p.z, STRIPE_PERIOD_M),
        _ => {
            let across = p.x * right.x + p.y * right.y;
            (band(p.z, CHECK_PERIOD_M) + band(across, CHECK_PERIOD_M)) * 0.5
        }
    };
    let fade = ((F::splat(22.0) - depth_m) * (1.0 / 12.0))
        .fast_max(F::ZERO)
        .fast_min(F::ONE);
    F::splat(0.5) + (m - F::splat(0.5)) * fade
}

/// The outward unit normals of a body capsule at the lanes' surface points (`+z` where a point is on the axis).
#[inline(always)]
pub(super) fn capsule_normals(c: &SceneCapsule, p: V3) -> V3 {
    let d = c.b - c.a;
    let rel = p.sub(V3::splat(c.a));
    let t = (rel.dot_v(d) / d.length_squared().max(1e-12))
        .fast_max(F::ZERO)
        .fast_min(F::ONE);
    let off = rel.sub(V3::splat(d).scale(t));
    let len2 = off.length_squared();
    let ok = len2.simd_gt(F::ZERO) & len2.is_finite();
    V3::select(ok, off.scale(F::ONE / len2.sqrt()), V3::splat(Vec3::Z))
}

/// A head's colours at unit directions `normal` from its centre: hair on the crown, the temples and the back down
/// to the nape (`albedo2`; `long_hair`: over the ears and the sides of the head too), and a face on the skin
/// around the gaze direction (`prim.normal`, level): a forehead up to the hairline, eyes in shadowed sockets,
/// eyebrows in the hair's colour, a shadow under the nose and a mouth, placed by the direction's components along
/// the gaze, to the side and up.
#[inline(always)]
pub(super) fn face(prim: &Prim, normal: V3, skin: V3, long_hair: bool) -> V3 {
    let fwd = prim.normal;
    let side = Vec3::new(fwd.y, -fwd.x, 0.0).normalize_or_zero();
    let (f, s, u) = (normal.dot_v(fwd), normal.dot_v(side).abs(), normal.z);
    let front = f.simd_gt(F::splat(0.55));
    // Hair as a head of short hair wears it: the crown, the temples down to above the ears, and the whole back
    // half of the head down to the nape, the ears left bare, so that a head seen from behind or three-quarters
    // behind reads as hair, not as a face (MediaPipe took people seen from behind for people facing it when the
    // sides of the back of the head were skin).
    let ear =
        s.simd_gt(F::splat(0.88)) & (u + F::splat(0.05)).abs().simd_lt(F::splat(0.15)) & f.simd_gt(F::splat(-0.05));
    // A forehead of skin between the brows and the hairline, over the face's middle.
    let forehead = f.simd_gt(F::splat(0.78)) & u.simd_lt(F::splat(0.5));
    let hair = (u.simd_gt(F::splat(0.25)) & !forehead)
        | (f.simd_lt(F::splat(0.3)) & u.simd_gt(F::splat(0.08)))
        | (f.simd_lt(F::splat(0.05)) & u.simd_gt(F::splat(-0.7)) & !ear);
    // Long hair falls from the parting over the ears and the sides of the head to below the jaw, so that only the
    // face's oval shows skin (a three-quarter back view showed a bare cheek and temple beside the hair, which
    // MediaPipe read as a face turned towards it).
    let hair = if long_hair {
        hair | (f.simd_lt(F::splat(0.45)) & u.simd_gt(F::splat(-0.8)))
    } else {
        hair
    };
    let sq = |x: F| x * x;
    let eye = front & (sq(s - F::splat(0.33)) + sq(u - F::splat(0.06)) * F::splat(2.0)).simd_lt(F::splat(0.0081));
    let brow = front
        & (s - F::splat(0.33)).abs().simd_lt(F::splat(0.14))
        & (u - F::splat(0.19)).abs().simd_lt(F::splat(0.035));
    let mouth = front & s.simd_lt(F::splat(0.17)) & (u + F::splat(0.5)).abs().simd_lt(F::splat(0.045));
    // Shadows where a face has relief that the head's sphere lacks: the eye sockets under the brow ridge (wider
    // than the eyes, so that at 20–30 px per head the eyes read as two dark patches, as in a photo) and under
    // the nose's tip.
    let socket = front & (sq(s - F::splat(0.33)) + sq(u - F::splat(0.07)) * F::splat(4.0)).simd_lt(F::splat(0.02));
    let nose = front & s.simd_lt(F::splat(0.07)) & (u + F::splat(0.3)).abs().simd_lt(F::splat(0.05));
    let shade = (socket | nose).select(F::splat(0.55), F::ONE);
    let mut colour = V3::select(hair | brow, V3::splat(prim.albedo2), skin.scale(shade));
    colour = V3::select(eye, V3::splat(Vec3::new(0.02, 0.02, 0.025)), colour);
    let lips = V3 {
        x: skin.x * 0.45,
        y: skin.y * 0.25,
        z: skin.z * 0.25,
    };
    V3::select(mouth, lips, colour)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::scene::Material;

    /// Short hair leaves the ears and cheeks bare; long hair covers the sides of the head down below the jaw and
    /// leaves the face's oval bare. Both cover the back of the head and neither covers the face or the forehead;
    /// the eye sockets and the skin under the nose are in shadow.
    #[test]
    fn a_head_shows_its_hair_style_a_forehead_and_shadowed_eye_sockets() {
        let (hair, skin) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let prim = Prim {
            material: Material::Head,
            tag: 0,
            instance: 1,
            albedo: skin,
            albedo2: hair,
            normal: Vec3::X,
            aux: 0,
        };
        // Is the point of the head in direction `(forward, left, up)` drawn as hair? (Skin in shadow counts as
        // skin.)
        let colour = |d: Vec3, long_hair: bool| {
            let c = face(&prim, V3::splat(d.normalize()), V3::splat(skin), long_hair);
            (c.x.to_array()[0], c.y.to_array()[0])
        };
        let is_hair = |d: Vec3, long_hair: bool| {
            let (r, g) = colour(d, long_hair);
            assert!(
                (r, g) == (1.0, 0.0) || (r == 0.0 && g > 0.5),
                "{d}: neither hair nor skin ({r}, {g})"
            );
            r == 1.0
        };
        let ear = Vec3::new(0.0, 1.0, -0.05);
        let cheek = Vec3::new(0.3, 0.9, -0.3);
        let back = Vec3::new(-1.0, 0.1, -0.2);
        let forehead = Vec3::new(0.9, 0.0, 0.4);
        let face_oval = [
            Vec3::new(1.0, 0.0, -0.1),
            Vec3::new(0.8, 0.6, 0.0),
            Vec3::new(0.8, 0.0, -0.6),
            forehead,
        ];
        assert!(
            !is_hair(ear, false) && !is_hair(cheek, false),
            "short hair: the ear and cheek are skin"
        );
        assert!(
            is_hair(ear, true) && is_hair(cheek, true),
            "long hair: the ear and cheek are under hair"
        );
        for long_hair in [false, true] {
            assert!(is_hair(back, long_hair), "the back of the head is hair");
            assert!(is_hair(Vec3::new(0.2, 0.0, 1.0), long_hair), "the crown is hair");
            for d in face_oval {
                assert!(!is_hair(d, long_hair), "{d}: the face is skin");
            }
            // Above the forehead's sides, the hairline.
            assert!(
                is_hair(Vec3::new(0.6, 0.6, 0.5), long_hair),
                "the hairline at the temple"
            );
        }
        // The eye sockets beside the eyes and the shadow under the nose are darker skin than the cheeks.
        let cheek_g = colour(Vec3::new(0.8, 0.6, -0.2), false).1;
        let socket = Vec3::new(0.0, 0.33 + 0.12, 0.07);
        let socket = Vec3::new((1.0 - socket.length_squared()).sqrt(), socket.y, socket.z);
        let under_nose = Vec3::new(0.95, 0.0, -0.3);
        assert_eq!(cheek_g, 1.0, "a cheek is lit skin");
        for d in [socket, under_nose] {
            let (r, g) = colour(d, false);
            assert!(r == 0.0 && g < 0.7 * cheek_g, "{d}: shadowed skin ({r}, {g})");
        }
    }

    /// A striped top shows its second colour in the gaps between stripes, 4.5 cm on and 4.5 cm off along the
    /// height; checks mix both directions; beyond 22 m deep both are their mean (no aliasing), and between 10
    /// and 22 m they fade towards it.
    #[test]
    fn cloth_patterns_alternate_with_their_period_and_fade_with_depth() {
        use crate::sensors::scene::PATTERN_CHECKS;
        let at = |pattern: u32, x: f32, z: f32, depth_m: f32| {
            let p = V3::splat(Vec3::new(x, 0.0, z));
            pattern_share(pattern, p, Vec3::X, F::splat(depth_m)).to_array()[0]
        };
        let period = STRIPE_PERIOD_M;
        // 0 at a stripe's middle (f = 0.5), 1 in the middle of the gap (f = 0), at every period.
        for k in 10..20 {
            let z = k as f32 * period;
            assert!(at(PATTERN_STRIPES, 0.0, z + 0.5 * period, 3.0) < 1e-4, "stripe at {z}");
            assert!(at(PATTERN_STRIPES, 0.0, z + 0.01 * period, 3.0) > 0.9, "gap at {z}");
            assert!(
                (at(PATTERN_STRIPES, 0.0, z + 0.5 * period, 16.0) - 0.25).abs() < 1e-3,
                "half faded"
            );
            assert!((at(PATTERN_STRIPES, 0.0, z, 30.0) - 0.5).abs() < 1e-6, "faded at 30 m");
        }
        // Stripes do not change across the body; checks do.
        let z = 1.2 + 0.5 * CHECK_PERIOD_M;
        assert_eq!(
            at(PATTERN_STRIPES, 0.0, 12.0 * period, 3.0),
            at(PATTERN_STRIPES, 0.37, 12.0 * period, 3.0)
        );
        let across: Vec<f32> = (0..8)
            .map(|i| at(PATTERN_CHECKS, i as f32 * 0.25 * CHECK_PERIOD_M, z, 3.0))
            .collect();
        assert!(
            across.iter().any(|&m| m < 0.05) && across.iter().any(|&m| m > 0.45),
            "{across:?}"
        );
        // The mean over a period is one half.
        let mean = (0..900)
            .map(|i| at(PATTERN_STRIPES, 0.0, i as f32 * period / 900.0 + 1.0, 3.0))
            .sum::<f32>()
            / 900.0;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
    }
}
