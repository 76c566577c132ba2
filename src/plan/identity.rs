//! Who each pedestrian is: body height, age group, gender and colours, drawn once by the planner so that every
//! observer (the labels, the cameras, the LiDAR, the exports) sees the same person, and so that identities vary
//! per pedestrian rather than per archetype (the seed system gave each archetype one look).
//!
//! Heights come from a blake3 hash of the clip seed and the pedestrian id (adults 1.55–1.95 m, children
//! 1.0–1.3 m); looks from the ChaCha20 stream `ped/<id>/identity` (the child's from `ped/<id>/child`), and the
//! figure (build, hair style, headwear, garment, bag) from `ped/<id>/identity/figure` (`ped/<id>/child/figure`,
//! a rider's `cyclist/<id>/figure`), so that drawing them shifts no other random stream of the plan.
//!
//! The figure's shares are pedsynth's choices for a city street (no dataset we have publishes them): a
//! backpack on a quarter of adults and on 45 % of young people and children, a shoulder bag on 30 % of women and
//! 10 % of men, a hat on 15 %, a coat on 15 %, a skirt or dress on 30 % of women and girls, long hair or a bun on
//! 75 % of women and girls and 5 % of men, baldness on a third of senior men.

use rand::RngExt;
use rand::seq::IndexedRandom;
use rand_chacha::ChaCha20Rng;

use super::script::{AgeGroup, Carry, Figure, Garment, Gender, HairStyle, Identity, Pattern};
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
/// Hair colours (sRGB) of children and adults, each with the twentieths of heads that have it: black and dark
/// brown 30 % each, brown 20 %, light brown 5 %, blonde 10 % and auburn 5 %, dark hair being the most common on
/// city streets. (An even draw over the six gave the light ones half the heads; a light head seen from behind
/// read as a face to MediaPipe, which then took the person to face the camera and swapped left and right.)
const HAIR: [([u8; 3], usize); 6] = [
    ([28, 24, 20], 6),
    ([58, 40, 28], 6),
    ([96, 66, 40], 4),
    ([168, 132, 84], 1),
    ([206, 178, 120], 2),
    ([128, 58, 32], 1),
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
/// Least distance (sRGB, Euclidean, before the jitter) between a top's colour and the wearer's skin: none to four
/// of the 16 tops are left out per skin tone.
const MIN_TOP_SKIN_DISTANCE: f64 = 64.0;

/// Euclidean distance of two sRGB colours.
fn rgb_distance(a: [u8; 3], b: [u8; 3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (f64::from(*x) - f64::from(y)).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Largest jitter of a clothing colour channel, so that no two pedestrians share an exact colour.
const CLOTHING_JITTER: i32 = 14;

/// Colours of umbrellas' canopies (sRGB): mostly black and dark, some bright.
const UMBRELLAS: [[u8; 3]; 8] = [
    [18, 18, 20],
    [18, 18, 20],
    [22, 28, 58],
    [60, 62, 66],
    [150, 24, 30],
    [30, 80, 150],
    [226, 190, 40],
    [48, 96, 62],
];

/// Share of pedestrians (not children) who hold an open umbrella in a weather with `precipitation_pct` of rain:
/// none in dry weather, `0.6 · min(1, p / 60)` in rain (30 % in soft rain's 30, 60 % from 60 up). Of those
/// without one (children included) the same share wear a hood up. pedsynth's choice: no dataset we have counts
/// umbrellas or hoods.
pub fn umbrella_share(precipitation_pct: f64) -> f64 {
    (0.6 * precipitation_pct.max(0.0) / 60.0).min(0.6)
}

/// The identity of pedestrian `id` of a clip (an `archetype` with `body`) and, for a parent with a child, the
/// child's; `umbrella_share`: the probability that the (grown-up) pedestrian holds an umbrella
/// ([`umbrella_share`]), and that one without an umbrella (or the child) wears a hood up, drawn from the stream
/// `ped/<id>/identity/umbrella` so that it shifts no other draw.
pub fn identities(
    clip_seed: u64,
    id: u32,
    archetype: &str,
    body: Body,
    umbrella_share: f64,
) -> (Identity, Option<Identity>) {
    let (adult_m, child_m) = heights_m(clip_seed, id);
    let age = match (body, archetype) {
        (Body::Child, _) => AgeGroup::Child,
        (_, "elderly_person") => AgeGroup::Senior,
        (_, "young_person") => AgeGroup::Young,
        _ => AgeGroup::Adult,
    };
    let height_m = if body == Body::Child { child_m } else { adult_m };
    let person = |stream: &str, height_m: f64, age: AgeGroup| {
        let identity = looks(&mut seeds::clip_rng(clip_seed, stream), height_m, age);
        with_pattern(with_figure(identity, clip_seed, stream, true), clip_seed, stream)
    };
    let mut main = person(&format!("ped/{id}/identity"), height_m, age);
    let mut child =
        (body == Body::AdultWithChild).then(|| person(&format!("ped/{id}/child"), child_m, AgeGroup::Child));
    if umbrella_share > 0.0 {
        let share = umbrella_share.min(1.0);
        let mut rng = seeds::clip_rng(clip_seed, &format!("ped/{id}/identity/umbrella"));
        let (umbrella, colour, hood, child_hood) = (
            rng.random_bool(share),
            *UMBRELLAS.choose(&mut rng).unwrap_or(&UMBRELLAS[0]),
            rng.random_bool(share),
            rng.random_bool(share),
        );
        if umbrella && age != AgeGroup::Child {
            main.figure.umbrella = Some(colour);
        } else if hood {
            main.figure = Figure {
                hood: true,
                headwear: None,
                ..main.figure
            };
        }
        if let Some(c) = child.as_mut().filter(|_| child_hood) {
            c.figure = Figure {
                hood: true,
                headwear: None,
                ..c.figure
            };
        }
    }
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
    with_figure(
        looks(&mut rng, height_m, age),
        clip_seed,
        &format!("cyclist/{id}"),
        false,
    )
}

/// `identity` with its figure drawn from the stream `<stream>/figure`; `skirts`: as [`figure`]'s.
fn with_figure(identity: Identity, clip_seed: u64, stream: &str, skirts: bool) -> Identity {
    let mut rng = seeds::clip_rng(clip_seed, &format!("{stream}/figure"));
    Identity {
        figure: figure(&mut rng, identity.age, identity.gender, skirts),
        ..identity
    }
}

/// Shares of pedestrians whose top is striped, and checked. pedsynth's choice: about what a city street shows.
const STRIPES_SHARE: f64 = 0.15;
const CHECKS_SHARE: f64 = 0.12;

/// `identity` with a pattern on its top drawn from the stream `<stream>/pattern` (so that it shifts no other
/// draw): stripes or checks in a contrasting colour, a darker shade of a light top or a lighter one of a dark top.
fn with_pattern(identity: Identity, clip_seed: u64, stream: &str) -> Identity {
    let mut rng = seeds::clip_rng(clip_seed, &format!("{stream}/pattern"));
    let u = rng.random_range(0.0..1.0);
    let kind = if u < STRIPES_SHARE {
        Pattern::Stripes
    } else if u < STRIPES_SHARE + CHECKS_SHARE {
        Pattern::Checks
    } else {
        return identity;
    };
    let top = identity.top_rgb.map(f64::from);
    let luma = 0.299 * top[0] + 0.587 * top[1] + 0.114 * top[2];
    let second = if luma > 120.0 {
        top.map(|c| c * 0.4)
    } else {
        // Off-white, or a red where the top is not itself reddish.
        let red = !rng.random_bool(0.5) && rgb_distance(identity.top_rgb, [200, 60, 50]) >= 120.0;
        let light = if red {
            [200.0, 60.0, 50.0]
        } else {
            [232.0, 230.0, 224.0]
        };
        std::array::from_fn(|i| 0.3 * top[i] + 0.7 * light[i])
    };
    let mut out = identity;
    out.figure.pattern = Some((kind, second.map(|c| c.round().clamp(0.0, 255.0) as u8)));
    out
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

/// Colours of hats and bags (sRGB).
const ACCESSORIES: [[u8; 3]; 8] = [
    [20, 20, 22],
    [60, 40, 30],
    [120, 84, 52],
    [40, 52, 90],
    [150, 30, 36],
    [90, 92, 96],
    [200, 196, 186],
    [46, 86, 60],
];

/// A person's figure; `skirts`: whether a skirt, dress or coat may be drawn (not for a cyclist's rider).
fn figure(rng: &mut ChaCha20Rng, age: AgeGroup, gender: Gender, skirts: bool) -> Figure {
    let female = gender == Gender::Female;
    let build = match age {
        AgeGroup::Child => rng.random_range(0.92..1.08),
        _ => rng.random_range(0.85..1.25),
    };
    let u = rng.random_range(0.0..1.0);
    let hair = match (female, age) {
        (true, _) if u < 0.5 => HairStyle::Long,
        (true, _) if u < 0.75 => HairStyle::Bun,
        (false, AgeGroup::Senior) if u < 0.33 => HairStyle::Bald,
        (false, AgeGroup::Adult) if u < 0.08 => HairStyle::Bald,
        (false, _) if u > 0.95 => HairStyle::Long,
        _ => HairStyle::Short,
    };
    let pick = |rng: &mut ChaCha20Rng| *ACCESSORIES.choose(rng).unwrap_or(&[60, 60, 60]);
    let headwear = rng.random_bool(0.15).then(|| pick(rng));
    let u = rng.random_range(0.0..1.0);
    let garment = match (skirts, female) {
        (false, _) => Garment::Trousers,
        (true, true) if u < 0.2 => Garment::Skirt,
        (true, true) if u < 0.3 => Garment::Dress,
        (true, _) if u > 0.85 && age != AgeGroup::Child => Garment::Coat,
        _ => Garment::Trousers,
    };
    let u = rng.random_range(0.0..1.0);
    let backpack = if matches!(age, AgeGroup::Young | AgeGroup::Child) {
        0.45
    } else {
        0.25
    };
    let bag = if female { 0.3 } else { 0.1 };
    let carry = if u < backpack {
        Some((Carry::Backpack, pick(rng)))
    } else if u < backpack + bag && age != AgeGroup::Child {
        Some((Carry::ShoulderBag, pick(rng)))
    } else {
        None
    };
    Figure {
        build,
        hair,
        headwear,
        garment,
        carry,
        umbrella: None,
        hood: false,
        pattern: None,
    }
}

/// A colour of `palette` drawn with its weight: one index below the weights' sum, the same draw as picking from
/// the palette written out with each colour repeated its weight's number of times.
fn weighted_pick(rng: &mut ChaCha20Rng, palette: &[([u8; 3], usize)]) -> [u8; 3] {
    let total: usize = palette.iter().map(|&(_, n)| n).sum();
    let mut k = rng.random_range(..total.max(1));
    for &(rgb, n) in palette {
        if k < n {
            return rgb;
        }
        k -= n;
    }
    [128, 128, 128]
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
        weighted_pick(rng, &HAIR)
    };
    let jitter = |rgb: [u8; 3], rng: &mut ChaCha20Rng| {
        rgb.map(|c| (i32::from(c) + rng.random_range(-CLOTHING_JITTER..=CLOTHING_JITTER)).clamp(0, 255) as u8)
    };
    // A top stands apart from the skin it borders (neck, hands, face above it): a top in the wearer's own skin
    // tone drew a person as one shape, whom real-trained detectors missed. (Bottoms are not held to it: dark
    // trousers on dark skin are as common as anywhere.)
    let far = |c: &&[u8; 3]| rgb_distance(**c, skin_rgb) >= MIN_TOP_SKIN_DISTANCE;
    let k = rng.random_range(0..TOPS.iter().filter(far).count().max(1));
    let top = *TOPS.iter().filter(far).nth(k).unwrap_or(&TOPS[0]);
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
        figure: Figure::PLAIN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hair_colours_are_drawn_with_their_weights() {
        let mut rng = seeds::clip_rng(7, "hair-test");
        let n = 20_000;
        let mut counts = [0usize; HAIR.len()];
        for _ in 0..n {
            let rgb = weighted_pick(&mut rng, &HAIR);
            counts[HAIR.iter().position(|&(c, _)| c == rgb).expect("a palette colour")] += 1;
        }
        let total: usize = HAIR.iter().map(|&(_, w)| w).sum();
        for (&(rgb, weight), &count) in HAIR.iter().zip(&counts) {
            let share = count as f64 / f64::from(n);
            let want = weight as f64 / total as f64;
            assert!((share - want).abs() < 0.015, "{rgb:?}: {share} drawn, {want} wanted");
        }
    }

    #[test]
    fn identities_are_deterministic_and_in_range() {
        let (a, c) = identities(7, 3, "parent_with_child", Body::AdultWithChild, 0.0);
        assert_eq!((a, c), identities(7, 3, "parent_with_child", Body::AdultWithChild, 0.0));
        assert!((1.55..=1.95).contains(&a.height_m));
        let c = c.expect("a child");
        assert!((1.0..=1.3).contains(&c.height_m) && c.age == AgeGroup::Child);
        assert!(identities(7, 3, "casual_person", Body::Child, 0.0).1.is_none());
        assert_eq!(
            identities(7, 3, "elderly_person", Body::Adult, 0.0).0.age,
            AgeGroup::Senior
        );
    }

    #[test]
    fn looks_vary_between_pedestrians_of_one_archetype() {
        let tops: std::collections::BTreeSet<[u8; 3]> = (0..40)
            .map(|id| identities(11, id, "business_person", Body::Adult, 0.0).0.top_rgb)
            .collect();
        assert!(tops.len() > 30, "{} distinct tops of 40", tops.len());
        let genders: std::collections::BTreeSet<Gender> = (0..40)
            .map(|id| identities(11, id, "business_person", Body::Adult, 0.0).0.gender)
            .collect();
        assert_eq!(genders.len(), 2);
    }

    #[test]
    fn tops_stand_apart_from_the_skin() {
        // The jitter moves a colour by at most CLOTHING_JITTER per channel.
        let least = MIN_TOP_SKIN_DISTANCE - f64::from(CLOTHING_JITTER) * 3f64.sqrt();
        for id in 0..600 {
            let a = identities(5, id, "casual_person", Body::Adult, 0.0).0;
            let d = rgb_distance(a.top_rgb, a.skin_rgb);
            assert!(
                d >= least,
                "pedestrian {id}: top {:?} on skin {:?} ({d:.0})",
                a.top_rgb,
                a.skin_rgb
            );
        }
    }

    /// Umbrellas and hoods come from a stream of their own: with or without rain a pedestrian is the same person
    /// (a hood takes a hat's place), and in rain about the share's fraction of grown-ups hold an umbrella (none of
    /// the children) and the same share of the others wear a hood.
    #[test]
    fn umbrellas_change_nothing_else_and_follow_the_share() {
        let (mut held, mut hooded, mut grown_ups) = (0, 0, 0);
        for id in 0..600 {
            let dry = identities(13, id, "casual_person", Body::AdultWithChild, 0.0);
            let (mut wet, wet_child) = identities(13, id, "casual_person", Body::AdultWithChild, 0.6);
            assert!(dry.0.figure.umbrella.is_none() && !dry.0.figure.hood);
            let mut wet_child = wet_child.expect("a child");
            assert!(wet_child.figure.umbrella.is_none(), "a child holds an umbrella");
            grown_ups += 1;
            held += usize::from(wet.figure.umbrella.is_some());
            hooded += usize::from(wet.figure.hood);
            assert!(
                !(wet.figure.hood && wet.figure.umbrella.is_some()),
                "a hood under an umbrella"
            );
            assert!(!wet.figure.hood || wet.figure.headwear.is_none(), "a hat over a hood");
            // Without the umbrella, the hood and the hat the hood replaced, the same person.
            for (person, before) in [(&mut wet, dry.0), (&mut wet_child, dry.1.expect("a child"))] {
                person.figure.umbrella = None;
                if person.figure.hood {
                    person.figure.hood = false;
                    person.figure.headwear = before.figure.headwear;
                }
                assert_eq!(*person, before, "pedestrian {id}");
            }
            assert!(
                identities(13, id, "casual_person", Body::Child, 1.0)
                    .0
                    .figure
                    .umbrella
                    .is_none()
            );
        }
        let share = held as f64 / f64::from(grown_ups);
        assert!((share - 0.6).abs() < 0.06, "{held} of {grown_ups} hold an umbrella");
        // Of the 40 % without one, 60 % wear a hood: 24 %.
        let hoods = hooded as f64 / f64::from(grown_ups);
        assert!((hoods - 0.24).abs() < 0.05, "{hooded} of {grown_ups} wear a hood");
    }

    /// Patterns come from a stream of their own (nothing else of a person changes with them), about 15 % of tops
    /// are striped and 12 % checked, and the second colour stands apart from the top's.
    #[test]
    fn patterned_tops_follow_their_shares_and_contrast() {
        let (mut stripes, mut checks) = (0u32, 0u32);
        for id in 0..2000 {
            let (a, _) = identities(17, id, "casual_person", Body::Adult, 0.0);
            let mut looks_only = looks(
                &mut seeds::clip_rng(17, &format!("ped/{id}/identity")),
                a.height_m,
                a.age,
            );
            looks_only.figure = a.figure;
            assert_eq!(a, looks_only, "pedestrian {id}");
            if let Some((kind, second)) = a.figure.pattern {
                stripes += u32::from(kind == Pattern::Stripes);
                checks += u32::from(kind == Pattern::Checks);
                assert!(rgb_distance(second, a.top_rgb) >= 50.0, "{second:?} on {:?}", a.top_rgb);
            }
        }
        assert!(
            (f64::from(stripes) / 2000.0 - STRIPES_SHARE).abs() < 0.025,
            "{stripes} striped"
        );
        assert!(
            (f64::from(checks) / 2000.0 - CHECKS_SHARE).abs() < 0.025,
            "{checks} checked"
        );
    }
}
