//! Who each pedestrian is: body height, age group, gender and colours, drawn once by the planner so that every
//! observer (the labels, the cameras, the LiDAR, the exports) sees the same person, and so that identities vary
//! per pedestrian rather than per archetype (the seed system gave each archetype one look).
//!
//! Heights come from a blake3 hash of the clip seed and the pedestrian id (adults 1.55–1.95 m, children
//! 1.0–1.3 m); looks from the ChaCha20 stream `ped/<id>/identity` (the child's from `ped/<id>/child`), so that
//! drawing them shifts no other random stream of the plan.

use rand::RngExt;
use rand::seq::IndexedRandom;
use rand_chacha::ChaCha20Rng;

use super::script::{AgeGroup, Gender, Identity};
use super::seeds;
use crate::spec::types::Body;

/// Adult heights, metres: the lowest, and the range above it.
const ADULT_HEIGHT_M: (f64, f64) = (1.55, 0.4);
/// Child heights, metres: the lowest, and the range above it.
const CHILD_HEIGHT_M: (f64, f64) = (1.0, 0.3);

/// Skin tones (sRGB), light to dark.
const SKIN: [[u8; 3]; 7] = [
    [255, 224, 196],
    [241, 194, 160],
    [224, 172, 125],
    [198, 134, 90],
    [161, 102, 64],
    [118, 72, 45],
    [82, 52, 36],
];
/// Hair colours (sRGB) of children and adults.
const HAIR: [[u8; 3]; 6] = [
    [28, 24, 20],
    [58, 40, 28],
    [96, 66, 40],
    [168, 132, 84],
    [206, 178, 120],
    [128, 58, 32],
];
/// Hair colours (sRGB) of seniors.
const GREY_HAIR: [[u8; 3]; 3] = [[150, 148, 145], [188, 186, 182], [222, 220, 214]];
/// Colours of tops (sRGB).
const TOPS: [[u8; 3]; 16] = [
    [24, 32, 64],
    [20, 20, 22],
    [228, 228, 224],
    [120, 122, 126],
    [170, 36, 40],
    [44, 84, 160],
    [40, 110, 64],
    [196, 178, 140],
    [222, 186, 48],
    [110, 30, 42],
    [30, 120, 128],
    [220, 110, 40],
    [214, 130, 160],
    [96, 104, 52],
    [104, 70, 44],
    [126, 170, 210],
];
/// Colours of trousers and skirts (sRGB).
const BOTTOMS: [[u8; 3]; 8] = [
    [52, 74, 112],
    [30, 30, 34],
    [92, 94, 98],
    [170, 150, 110],
    [32, 40, 70],
    [90, 64, 44],
    [52, 70, 48],
    [200, 190, 170],
];
/// Colours of shoes (sRGB).
const SHOES: [[u8; 3]; 4] = [[22, 22, 24], [226, 226, 222], [96, 62, 40], [110, 110, 114]];
/// Share of seniors with grey or white hair.
const SENIOR_GREY_SHARE: f64 = 0.75;
/// Largest jitter of a clothing colour channel, so that no two pedestrians share an exact colour.
const CLOTHING_JITTER: i32 = 14;

/// The identity of pedestrian `id` of a clip (an `archetype` with `body`) and, for a parent with a child, the
/// child's.
pub fn identities(clip_seed: u64, id: u32, archetype: &str, body: Body) -> (Identity, Option<Identity>) {
    let (adult_m, child_m) = heights_m(clip_seed, id);
    let age = match (body, archetype) {
        (Body::Child, _) => AgeGroup::Child,
        (_, "elderly_person") => AgeGroup::Senior,
        (_, "young_person") => AgeGroup::Young,
        _ => AgeGroup::Adult,
    };
    let height_m = if body == Body::Child { child_m } else { adult_m };
    let main = looks(
        &mut seeds::clip_rng(clip_seed, &format!("ped/{id}/identity")),
        height_m,
        age,
    );
    let child = (body == Body::AdultWithChild).then(|| {
        looks(
            &mut seeds::clip_rng(clip_seed, &format!("ped/{id}/child")),
            child_m,
            AgeGroup::Child,
        )
    });
    (main, child)
}

/// The identity of cyclist `id`'s rider (an adult or young adult), from the stream `cyclist/<id>/identity`.
pub fn rider_identity(clip_seed: u64, id: u32) -> Identity {
    let mut rng = seeds::clip_rng(clip_seed, &format!("cyclist/{id}/identity"));
    let height_m = ADULT_HEIGHT_M.0 + ADULT_HEIGHT_M.1 * rng.random_range(0.0..1.0);
    let age = if rng.random_bool(0.4) {
        AgeGroup::Young
    } else {
        AgeGroup::Adult
    };
    looks(&mut rng, height_m, age)
}

/// An adult's and a child's height for pedestrian `id`, metres.
fn heights_m(clip_seed: u64, id: u32) -> (f64, f64) {
    let h = blake3::hash(&[clip_seed.to_le_bytes(), u64::from(id).to_le_bytes()].concat());
    let b = h.as_bytes();
    let u1 = f64::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0;
    let u2 = f64::from(u16::from_le_bytes([b[2], b[3]])) / 65535.0;
    (
        ADULT_HEIGHT_M.0 + ADULT_HEIGHT_M.1 * u1,
        CHILD_HEIGHT_M.0 + CHILD_HEIGHT_M.1 * u2,
    )
}

fn looks(rng: &mut ChaCha20Rng, height_m: f64, age: AgeGroup) -> Identity {
    let gender = if rng.random_bool(0.5) {
        Gender::Female
    } else {
        Gender::Male
    };
    let pick = |rng: &mut ChaCha20Rng, palette: &[[u8; 3]]| *palette.choose(rng).unwrap_or(&[128, 128, 128]);
    let skin_rgb = pick(rng, &SKIN);
    let hair_rgb = if age == AgeGroup::Senior && rng.random_bool(SENIOR_GREY_SHARE) {
        pick(rng, &GREY_HAIR)
    } else {
        pick(rng, &HAIR)
    };
    let jitter = |rgb: [u8; 3], rng: &mut ChaCha20Rng| {
        rgb.map(|c| (i32::from(c) + rng.random_range(-CLOTHING_JITTER..=CLOTHING_JITTER)).clamp(0, 255) as u8)
    };
    let top = pick(rng, &TOPS);
    let top_rgb = jitter(top, rng);
    let bottom = pick(rng, &BOTTOMS);
    let bottom_rgb = jitter(bottom, rng);
    let shoes_rgb = pick(rng, &SHOES);
    Identity {
        height_m,
        age,
        gender,
        skin_rgb,
        hair_rgb,
        top_rgb,
        bottom_rgb,
        shoes_rgb,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identities_are_deterministic_and_in_range() {
        let (a, c) = identities(7, 3, "parent_with_child", Body::AdultWithChild);
        assert_eq!((a, c), identities(7, 3, "parent_with_child", Body::AdultWithChild));
        assert!((1.55..=1.95).contains(&a.height_m));
        let c = c.expect("a child");
        assert!((1.0..=1.3).contains(&c.height_m) && c.age == AgeGroup::Child);
        assert!(identities(7, 3, "casual_person", Body::Child).1.is_none());
        assert_eq!(identities(7, 3, "elderly_person", Body::Adult).0.age, AgeGroup::Senior);
    }

    #[test]
    fn looks_vary_between_pedestrians_of_one_archetype() {
        let tops: std::collections::BTreeSet<[u8; 3]> = (0..40)
            .map(|id| identities(11, id, "business_person", Body::Adult).0.top_rgb)
            .collect();
        assert!(tops.len() > 30, "{} distinct tops of 40", tops.len());
        let genders: std::collections::BTreeSet<Gender> = (0..40)
            .map(|id| identities(11, id, "business_person", Body::Adult).0.gender)
            .collect();
        assert_eq!(genders.len(), 2);
    }
}
