//! A clip's scenery colours under domain randomisation (`domain_randomisation.scenery_*`, drawn into the clip
//! script's `look`): every scenery colour of the static scene (buildings, shop signs, ground, trees, poles,
//! street furniture) and every car's paint turns round the colour wheel, gains or loses saturation and
//! brightness. People, road markings and lights keep theirs. Applied once per clip, when the static scene is
//! built: nothing per pixel.

use glam::{Mat3, Vec3};

use super::{Material, Prim};
use crate::plan::ClipLook;

/// Rec. 709 luminance weights of linear RGB (the grey a colour desaturates to).
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// How a clip's look maps a scenery colour (linear RGB) to its own.
#[derive(Clone, Copy, Debug)]
pub struct SceneryColours {
    hue: Mat3,
    saturation: f32,
    brightness: f32,
}

impl SceneryColours {
    /// The mapping of a look; `None` when it keeps every colour (so the default renders the same bytes).
    pub fn of(look: &ClipLook) -> Option<SceneryColours> {
        if look.keeps_scenery_colours() {
            return None;
        }
        // A rotation about the grey axis (1, 1, 1)/√3: greys stay grey, every hue turns by the angle.
        let (s, c) = (look.scenery_hue_deg as f32).to_radians().sin_cos();
        let (k, r) = ((1.0 - c) / 3.0, s / 3.0f32.sqrt());
        let hue = Mat3::from_cols(
            Vec3::new(c + k, k + r, k - r),
            Vec3::new(k - r, c + k, k + r),
            Vec3::new(k + r, k - r, c + k),
        );
        Some(SceneryColours {
            hue,
            saturation: look.scenery_saturation as f32,
            brightness: look.scenery_brightness as f32,
        })
    }

    /// A colour under the mapping: turned, its saturation scaled about its luminance, scaled, kept in [0, 1].
    pub fn map(&self, colour: Vec3) -> Vec3 {
        let turned = self.hue * colour;
        let grey = Vec3::splat(turned.dot(LUMINANCE));
        ((grey + (turned - grey) * self.saturation) * self.brightness).clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// Recolours the scenery primitives of a static scene (both colours of a wall, so that a shop's sign
    /// colour stays apart from its wall's) and the cars' paint.
    pub fn apply(&self, prims: &mut [Prim], car_paint: &mut [Vec3]) {
        for p in prims.iter_mut().filter(|p| is_scenery(p.material)) {
            p.albedo = self.map(p.albedo);
            p.albedo2 = self.map(p.albedo2);
        }
        for paint in car_paint {
            *paint = self.map(*paint);
        }
    }
}

/// Whether a material is scenery that domain randomisation recolours (not lights, glass, tyres or people).
fn is_scenery(m: Material) -> bool {
    match m {
        Material::Road
        | Material::Sidewalk
        | Material::Curb
        | Material::Terrain
        | Material::Wall
        | Material::Roof
        | Material::Metal
        | Material::Trunk
        | Material::Foliage
        | Material::CarPaint
        | Material::Poster => true,
        Material::LampHead
        | Material::CarGlass
        | Material::Tyre
        | Material::HeadLamp
        | Material::TailLamp
        | Material::Beacon
        | Material::Fabric
        | Material::Body
        | Material::Head => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn look(hue_deg: f64, saturation: f64, brightness: f64) -> ClipLook {
        ClipLook {
            scenery_hue_deg: hue_deg,
            scenery_saturation: saturation,
            scenery_brightness: brightness,
            ..ClipLook::default()
        }
    }

    #[test]
    fn the_identity_look_recolours_nothing() {
        assert!(SceneryColours::of(&ClipLook::default()).is_none());
    }

    #[test]
    fn hue_turns_colours_round_the_wheel_and_keeps_greys() {
        let third = SceneryColours::of(&look(120.0, 1.0, 1.0)).expect("a turn");
        // A third of a turn takes red to green to blue.
        let red = third.map(Vec3::new(0.8, 0.0, 0.0));
        assert!(red.abs_diff_eq(Vec3::new(0.0, 0.8, 0.0), 1e-5), "{red}");
        let green = third.map(Vec3::new(0.0, 0.8, 0.0));
        assert!(green.abs_diff_eq(Vec3::new(0.0, 0.0, 0.8), 1e-5), "{green}");
        let grey = third.map(Vec3::splat(0.4));
        assert!(grey.abs_diff_eq(Vec3::splat(0.4), 1e-5), "{grey}");
    }

    #[test]
    fn saturation_zero_greys_and_brightness_scales() {
        let grey = SceneryColours::of(&look(0.0, 0.0, 1.0)).expect("a change");
        let c = grey.map(Vec3::new(0.6, 0.2, 0.1));
        assert!((c.x - c.y).abs() < 1e-6 && (c.y - c.z).abs() < 1e-6, "{c}");
        assert!((c.x - Vec3::new(0.6, 0.2, 0.1).dot(LUMINANCE)).abs() < 1e-6);
        let dim = SceneryColours::of(&look(0.0, 1.0, 0.5)).expect("a change");
        assert!(
            dim.map(Vec3::new(0.6, 0.2, 0.1))
                .abs_diff_eq(Vec3::new(0.3, 0.1, 0.05), 1e-6)
        );
        // Never out of [0, 1].
        let loud = SceneryColours::of(&look(30.0, 5.0, 5.0)).expect("a change");
        let c = loud.map(Vec3::new(0.9, 0.05, 0.3));
        assert!(c.min_element() >= 0.0 && c.max_element() <= 1.0, "{c}");
    }

    #[test]
    fn people_and_lights_keep_their_colours() {
        let mapping = SceneryColours::of(&look(90.0, 0.5, 0.7)).expect("a change");
        let prim = |material| Prim {
            material,
            tag: 0,
            instance: 0,
            albedo: Vec3::new(0.5, 0.2, 0.1),
            albedo2: Vec3::new(0.1, 0.2, 0.5),
            normal: Vec3::Z,
            aux: 0,
        };
        let mut prims = [prim(Material::Wall), prim(Material::Body), prim(Material::HeadLamp)];
        let mut paint = [Vec3::new(0.7, 0.1, 0.1)];
        mapping.apply(&mut prims, &mut paint);
        assert_ne!(prims[0].albedo, Vec3::new(0.5, 0.2, 0.1));
        assert_ne!(prims[0].albedo2, Vec3::new(0.1, 0.2, 0.5));
        assert_eq!(prims[1].albedo, Vec3::new(0.5, 0.2, 0.1));
        assert_eq!(prims[2].albedo, Vec3::new(0.5, 0.2, 0.1));
        assert_ne!(paint[0], Vec3::new(0.7, 0.1, 0.1));
    }
}
