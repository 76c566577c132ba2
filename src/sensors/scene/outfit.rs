//! What a person wears, as the renderer draws it ([`Outfit`]): the material and colour of each body capsule, the
//! hair and its style, the umbrella's canopy, and which capsules wear the top's cloth pattern. Worked out once per
//! clip from a pedestrian's, child's or rider's identity ([`crate::plan::Identity`]).

use super::*;

/// The share of a flat surface's albedo that hair of the same colour reflects (strands self-shadow).
const HAIR_ALBEDO_SCALE: f32 = 0.6;

/// What a body wears: the material and colour of each capsule (see [`body::pose`]'s order), and its hair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outfit {
    /// Per capsule: shading model and linear colour.
    pub parts: [(Material, Vec3); CAPSULES],
    /// Hair colour, linear RGB.
    pub hair: Vec3,
    /// How the hair falls about the face ([`HEAD_SHORT_HAIR`] or [`HEAD_LONG_HAIR`]).
    pub head_style: u32,
    /// The umbrella's canopy colour, linear RGB (none: no umbrella).
    pub umbrella: Option<Vec3>,
    /// The cloth pattern ([`body_aux`]'s code) and its second colour (linear RGB), and which capsules wear it
    /// (the torso and shoulders, a dress or coat).
    pub pattern: (u32, Vec3),
    pub patterned: [bool; CAPSULES],
}

impl Outfit {
    /// The outfit of an identity; `key` seeds sleeve and leg length.
    pub fn of(identity: &Identity, seed: u64, key: u64) -> Outfit {
        let h = splitmix64(seed ^ 0xb0d1 ^ splitmix64(key));
        let figure = &identity.figure;
        let coat = figure.garment == Garment::Coat;
        let short_sleeves = h & 3 == 0 && !coat;
        // Under a skirt or a dress: bare legs or dark tights, as often as shorts under trousers are rare.
        let bare_legs = match figure.garment {
            Garment::Skirt | Garment::Dress => (h >> 2) & 1 == 0,
            Garment::Trousers => (h >> 2) & 7 == 0,
            Garment::Coat => false,
        };
        let (skin, top, bottom) = (
            linear(identity.skin_rgb),
            linear(identity.top_rgb),
            linear(identity.bottom_rgb),
        );
        let tights = linear([28, 26, 30]);
        let shoes = linear(identity.shoes_rgb);
        // Hair shades darker than a flat surface of its colour: light enters between the strands and is absorbed
        // there (a head of dark hair seen from behind reads as nearly black in a photo).
        let hair = linear(identity.hair_rgb) * HAIR_ALBEDO_SCALE;
        let accessory = |c: Option<[u8; 3]>| linear(c.unwrap_or([60, 60, 60]));
        // A dress is one garment in the top's colour; a skirt is the bottom's.
        let skirt = if figure.garment == Garment::Skirt { bottom } else { top };
        Outfit {
            parts: WEAR.map(|w| match w {
                Wear::Top => (Material::Body, top),
                Wear::Bottom => (Material::Body, bottom),
                Wear::Skin => (Material::Body, skin),
                Wear::Shoes => (Material::Body, shoes),
                Wear::Head => (Material::Head, skin),
                Wear::Sleeve if short_sleeves => (Material::Body, skin),
                Wear::Sleeve => (Material::Body, top),
                Wear::Leg if bare_legs => (Material::Body, skin),
                Wear::Leg if figure.garment != Garment::Trousers && figure.garment != Garment::Coat => {
                    (Material::Body, tights)
                }
                Wear::Leg => (Material::Body, bottom),
                // A hood's fabric gathered at the nape takes the hair's capsule ([`crate::sensors::body`]).
                Wear::Hair if figure.hood => (Material::Body, top),
                Wear::Hair => (Material::Body, hair),
                Wear::Headwear if figure.hood => (Material::Body, top),
                Wear::Headwear => (Material::Body, accessory(figure.headwear)),
                Wear::Carry => (Material::Body, accessory(figure.carry.map(|c| c.1))),
                Wear::Garment => (Material::Body, skirt),
            }),
            // A bald head shows its scalp where hair would be.
            hair: if figure.hair == HairStyle::Bald { skin } else { hair },
            head_style: if figure.hair == HairStyle::Long {
                HEAD_LONG_HAIR
            } else {
                HEAD_SHORT_HAIR
            },
            umbrella: figure.umbrella.map(linear),
            pattern: match figure.pattern {
                Some((Pattern::Stripes, c)) => (PATTERN_STRIPES, linear(c)),
                Some((Pattern::Checks, c)) => (PATTERN_CHECKS, linear(c)),
                None => (PATTERN_PLAIN, top),
            },
            // The torso and shoulders (capsules 0, 1 and 17) and a dress or coat; the arms stay plain in the top's
            // colour: stripes running on from the torso across the arms hid their outline (MediaPipe found people
            // in striped tops on arms and torso in 75 % of crops against 97 % when plain). A striped top's
            // shoulders stay plain too, as a Breton top's yoke: stripes are bands of height, and the shoulders'
            // capsule lies level, so its top showed one broad band across the whole shoulder line (a white bar
            // from behind, which MediaPipe did not take for shoulders: a man in a maroon top with off-white
            // stripes, seen from behind, was found in 6 of his 18 crops, 17 with plain shoulders). Checks vary
            // across the body as well, and keep theirs.
            patterned: std::array::from_fn(|i| match WEAR[i] {
                Wear::Top if i == 1 => !matches!(figure.pattern, Some((Pattern::Stripes, _))),
                Wear::Top => matches!(i, 0 | 17),
                Wear::Garment => matches!(figure.garment, Garment::Dress | Garment::Coat),
                _ => false,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::identity::rider_identity;

    /// A hood is the top's colour, and so is the capsule that takes the hair's place under it (the hood's
    /// fabric gathered at the nape); without a hood the hair is the hair's colour.
    #[test]
    fn a_hoods_gathered_back_is_the_tops_colour() {
        let mut identity = rider_identity(7, 0);
        let hair = WEAR.iter().position(|w| matches!(w, Wear::Hair)).unwrap();
        let headwear = WEAR.iter().position(|w| matches!(w, Wear::Headwear)).unwrap();
        let top = WEAR.iter().position(|w| matches!(w, Wear::Top)).unwrap();
        identity.figure.hood = true;
        let o = Outfit::of(&identity, 7, 0);
        assert_eq!(o.parts[hair].1, o.parts[top].1);
        assert_eq!(o.parts[headwear].1, o.parts[top].1);
        identity.figure.hood = false;
        let o = Outfit::of(&identity, 7, 0);
        assert_eq!(o.parts[hair].1, o.hair);
    }

    /// A top's pattern lies on the torso's two halves; a checked top's on the shoulders too, a striped top's
    /// shoulders stay plain (level bands of height would paint the shoulder line one colour); the arms are never
    /// patterned, and a coat or dress wears the pattern over the legs.
    #[test]
    fn a_striped_top_leaves_the_shoulders_and_arms_plain() {
        let mut identity = rider_identity(7, 0);
        identity.figure.garment = Garment::Trousers;
        let patterned = |identity: &Identity| {
            let outfit = Outfit::of(identity, 7, 0);
            (0..CAPSULES).filter(|&i| outfit.patterned[i]).collect::<Vec<_>>()
        };
        identity.figure.pattern = None;
        assert_eq!(Outfit::of(&identity, 7, 0).pattern.0, PATTERN_PLAIN);
        identity.figure.pattern = Some((Pattern::Stripes, [230, 230, 224]));
        assert_eq!(patterned(&identity), [0, 17], "stripes: the torso only");
        identity.figure.pattern = Some((Pattern::Checks, [230, 230, 224]));
        assert_eq!(patterned(&identity), [0, 1, 17], "checks: the torso and shoulders");
        identity.figure.garment = Garment::Coat;
        let garment = WEAR.iter().position(|w| matches!(w, Wear::Garment)).unwrap();
        assert_eq!(patterned(&identity), [0, 1, 17, garment], "checks: and the coat");
    }
}
