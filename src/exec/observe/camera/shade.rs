//! Surface shading: procedural textures (asphalt, paving tiles, façades with windows, grass) seeded per clip,
//! road paint, and the light a surface point receives (sun with shadows, sky and ground ambient, street lamps,
//! headlights, wet reflections), then fog. Everything in linear RGB; pure functions of the scene and the
//! lighting.

use glam::{Vec2, Vec3};

use super::light::{HEADLAMP_INTENSITY, LAMP_INTENSITY, Lighting};
use crate::exec::observe::scene::{FrameScene, Material, Prim, StaticScene, road_paint, tag};
use crate::mix::splitmix64;

/// `x.floor()` without the call into libm that `f32::floor` compiles to on x86-64 without SSE4.1 (a hot
/// spot of texture lookups); the same value for every finite `x` and NaN (only `−0.0` becomes `+0.0`).
#[inline(always)]
pub fn floor_f32(x: f32) -> f32 {
    // Every float of magnitude 2^23 or more is an integer already.
    if x.abs() < 8_388_608.0 { floor_i32(x) as f32 } else { x }
}

/// Adding `1.5 × 2^23` to a float of magnitude below [`ROUNDING_RANGE`] rounds it to an integer, held in the
/// sum's low mantissa bits (its unit in the last place is 1).
const ROUNDING_MAGIC: f32 = 12_582_912.0;
const ROUNDING_RANGE: f32 = 4_194_304.0;

/// `x.floor()` as an integer, for `|x| < 2^31` (texture coordinates; NaN gives 0). Below 2^22 in magnitude
/// (every texture and shadow-map coordinate) without the saturating float-to-integer conversion, whose
/// range checks cost as much as the rest of a texture lookup.
#[inline(always)]
pub fn floor_i32(x: f32) -> i32 {
    if x.abs() < ROUNDING_RANGE {
        let big = x + ROUNDING_MAGIC;
        let nearest = big.to_bits() as i32 - ROUNDING_MAGIC.to_bits() as i32;
        nearest - i32::from(big - ROUNDING_MAGIC > x)
    } else {
        let t = x as i32;
        t - i32::from(t as f32 > x)
    }
}

/// A seeded tileable value-noise table, sampled bilinearly (values in [−1, 1]).
#[derive(Clone, Debug)]
pub struct Noise {
    values: Vec<f32>,
}

const NOISE_SIZE: usize = 256;

impl Noise {
    /// The noise table of a seed.
    pub fn new(seed: u64) -> Noise {
        let values = (0..NOISE_SIZE * NOISE_SIZE)
            .map(|i| (splitmix64(seed ^ splitmix64(i as u64)) >> 40) as f32 / (1u64 << 23) as f32 - 1.0)
            .collect();
        Noise { values }
    }

    /// Bilinear sample at `p` (one cell per unit).
    #[inline(always)]
    pub fn sample(&self, p: Vec2) -> f32 {
        let (ix, iy) = (floor_i32(p.x), floor_i32(p.y));
        let (tx, ty) = (p.x - ix as f32, p.y - iy as f32);
        let m = NOISE_SIZE - 1;
        let (x0, y0) = ((ix as usize) & m, (iy as usize) & m);
        let (x1, y1) = ((x0 + 1) & m, (y0 + 1) & m);
        let v = |x: usize, y: usize| self.values[y * NOISE_SIZE + x];
        let a = v(x0, y0) + (v(x1, y0) - v(x0, y0)) * tx;
        let b = v(x0, y1) + (v(x1, y1) - v(x0, y1)) * tx;
        a + (b - a) * ty
    }

    /// A cell hash in [0, 1).
    #[inline]
    pub fn cell(&self, x: i32, y: i32, salt: u32) -> f32 {
        let h = splitmix64(((x as u32 as u64) << 32 | y as u32 as u64) ^ (u64::from(salt) << 17) ^ 0x9e37_79b9);
        (h >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Lights near the camera in one render, chosen once per frame.
#[derive(Clone, Debug, Default)]
pub struct ActiveLights {
    /// Street lamps (position).
    pub lamps: Vec<Vec3>,
    /// Head lamps (position, unit axis), the ego's first.
    pub heads: Vec<(Vec3, Vec3)>,
}

/// Everything shading reads for one render.
pub struct ShadeContext<'a> {
    /// The static scene.
    pub scene: &'a StaticScene,
    /// The frame's scene.
    pub frame: &'a FrameScene,
    /// Lighting.
    pub light: &'a Lighting,
    /// Texture noise.
    pub noise: &'a Noise,
    /// Lights near the camera.
    pub lights: &'a ActiveLights,
}

/// The shaded colour of a surface point, before fog, and its semantic tag (road paint turns road into road
/// line): `p` scene-relative, `(ray, ray_len)` the camera's ray to it and its length (the view direction is
/// worked out only where a reflection needs it), `shadow` the sun's visibility (0–1).
#[inline(always)]
pub fn surface(ctx: &ShadeContext, prim: &Prim, p: Vec3, (ray, ray_len): (Vec3, f32), shadow: f32) -> (Vec3, u8) {
    let l = ctx.light;
    let nz = ctx.noise;
    let xy = p.truncate();
    let mut normal = prim.normal;
    let mut albedo = prim.albedo;
    let mut emissive = Vec3::ZERO;
    // Mirror-like reflection share (wet ground, glass, paint).
    let mut gloss = 0.0f32;
    let mut ground = false;
    let mut semantic = prim.tag;
    match prim.material {
        Material::Road => {
            ground = true;
            let grain = 1.0 + 0.16 * nz.sample(xy * 1.3) + 0.08 * nz.sample(xy * 6.1 + 37.0);
            albedo *= grain;
            if let Some(piece) = ctx.scene.pieces.get(prim.aux as usize)
                && let Some((paint, paint_tag)) = road_paint(ctx.scene, piece, xy)
            {
                albedo = paint * (0.92 + 0.08 * nz.sample(xy * 9.0));
                if prim.tag == tag::ROAD {
                    semantic = paint_tag;
                }
            }
        }
        Material::Sidewalk => {
            ground = true;
            if prim.tag == tag::SIDEWALK {
                let g = xy / 0.6;
                let (ix, iy) = (floor_i32(g.x), floor_i32(g.y));
                let f = g - Vec2::new(ix as f32, iy as f32);
                albedo *= if f.x < 0.05 || f.y < 0.05 {
                    0.62
                } else {
                    0.88 + 0.2 * nz.cell(ix, iy, 7)
                };
            }
            albedo *= 1.0 + 0.08 * nz.sample(xy * 3.7);
        }
        Material::Curb => {
            ground = true;
            albedo *= 1.0 + 0.1 * nz.sample(xy * 4.0 + p.z);
        }
        Material::Terrain => {
            ground = true;
            let patch = nz.sample(xy * 0.21);
            albedo = albedo.lerp(Vec3::new(0.11, 0.09, 0.05), (0.5 + 0.6 * patch).clamp(0.0, 1.0));
            albedo *= 1.0 + 0.2 * nz.sample(xy * 2.9);
        }
        Material::Wall => {
            let along_dir = Vec2::new(-normal.y, normal.x);
            let a = xy.dot(along_dir) / 2.8;
            let z = p.z / 3.2;
            let (cell_a, cell_z) = (floor_i32(a), floor_i32(z));
            let (fa, fz) = (a - cell_a as f32, z - cell_z as f32);
            if fa > 0.22 && fa < 0.78 && fz > 0.3 && fz < 0.82 && p.z > 1.2 {
                let lit = nz.cell(cell_a, cell_z, prim.aux) < 0.22;
                albedo = Vec3::new(0.03, 0.035, 0.045);
                gloss = 0.35;
                if lit {
                    emissive = Vec3::new(0.9, 0.7, 0.42) * (0.35 * l.night);
                }
            } else if fz < 0.04 {
                albedo *= 0.7;
            } else {
                albedo *= 1.0 + 0.07 * nz.sample(Vec2::new(a * 4.0, p.z * 2.0));
            }
        }
        Material::Roof | Material::Metal | Material::Tyre => {}
        Material::LampHead => emissive = Vec3::new(3.0, 2.5, 1.8) * l.night,
        Material::Trunk => albedo *= 1.0 + 0.2 * nz.sample(Vec2::new(xy.x * 9.0, p.z * 3.0)),
        Material::Foliage => albedo *= 0.8 + 0.45 * nz.sample(Vec2::new(xy.x * 2.2 + p.z, xy.y * 2.2 - p.z)),
        Material::CarPaint => gloss = 0.18,
        Material::CarGlass => gloss = 0.12,
        Material::HeadLamp => emissive = Vec3::new(4.0, 3.9, 3.5) * (0.08 + l.night),
        Material::TailLamp => emissive = Vec3::new(2.5, 0.1, 0.08) * (0.05 + l.night),
        Material::Beacon => emissive = prim.albedo * (1.5 + 2.0 * l.night),
        Material::Body | Material::Head => {
            if let Some(c) = ctx.frame.capsules.get(prim.aux as usize) {
                normal = c.normal(p);
            }
            if prim.material == Material::Head && (normal.z > 0.25 || normal.dot(prim.normal) < -0.3) {
                albedo = prim.albedo2;
            }
            albedo *= 1.0 + 0.06 * nz.sample(Vec2::new(p.z * 23.0, xy.x * 7.0 + xy.y * 5.0));
        }
    }
    if ground && l.wet > 0.0 {
        // Darker when wet, and puddles (a low-frequency noise mask) that mirror the sky and the lights.
        let puddle = ((nz.sample(xy * 0.35) - 0.15) * 4.0).clamp(0.0, 1.0) * l.wet;
        albedo *= 1.0 - 0.4 * l.wet - 0.2 * puddle;
        gloss = gloss.max(l.wet * 0.25 + 0.6 * puddle);
    }

    // The unit vector from the point to the camera, for reflections (glossy surfaces only).
    let view = if gloss > 0.0 { -ray / ray_len } else { Vec3::ZERO };

    // Light received.
    let ndl = normal.dot(l.sun_dir).max(0.0);
    let mut light = l.ground_ambient.lerp(l.sky_ambient, 0.5 + 0.5 * normal.z) + l.sun * (ndl * shadow);
    let mut glints = Vec3::ZERO;
    if l.night > 0.0 {
        for &lamp in &ctx.lights.lamps {
            let d = lamp - p;
            let d2 = d.length_squared();
            if d2 > 1600.0 {
                continue;
            }
            let inv = d2.sqrt().recip();
            let dir = d * inv;
            let fall = LAMP_INTENSITY * l.night / (d2 + 1.0);
            // The lamp shines downwards: light falls off away from below it.
            light += Vec3::new(1.0, 0.78, 0.5) * (fall * normal.dot(dir).max(0.0) * dir.z.max(0.0));
            if gloss > 0.0 {
                let h = (dir + view).normalize_or_zero();
                let s = normal.dot(h).max(0.0);
                let s2 = s * s;
                let s8 = s2 * s2 * s2 * s2;
                glints += Vec3::new(1.0, 0.78, 0.5) * (fall * 6.0 * gloss * s8 * s8 * s8 * s8);
            }
        }
        for &(pos, axis) in &ctx.lights.heads {
            let d = p - pos;
            let d2 = d.length_squared();
            if !(1e-4..=3600.0).contains(&d2) {
                continue;
            }
            // A low beam: wide sideways, cut off just above the lamp's horizontal.
            let ahead = d.truncate().dot(axis.truncate());
            if ahead <= 0.1 {
                continue;
            }
            let side = (d.truncate().perp_dot(axis.truncate()) / ahead / 0.7).abs();
            let up = d.z / ahead;
            let beam = (1.0 - side * side).max(0.0) * ((0.02 - up) / 0.04).clamp(0.0, 1.0);
            if beam > 0.0 {
                let dir = d * d2.sqrt().recip();
                let fall = HEADLAMP_INTENSITY * l.night * beam / (d2 + 30.0);
                light += Vec3::new(1.0, 0.97, 0.9) * (fall * normal.dot(-dir).max(0.0));
            }
        }
    }
    let mut colour = albedo * light + emissive + glints;
    if gloss > 0.0 {
        let r = view.reflect(normal) * -1.0;
        let r = Vec3::new(r.x, r.y, r.z.abs());
        let cos = normal.dot(view).max(0.0);
        let fresnel = 0.04 + 0.96 * (1.0 - cos).powi(5);
        colour += l.sky(r) * (gloss * (0.08 + 0.92 * fresnel));
    }
    (colour, semantic)
}

/// Applies fog over a distance.
#[inline]
pub fn fog(light: &Lighting, colour: Vec3, dist_m: f32) -> Vec3 {
    let f = (-light.fog_per_m * dist_m).exp();
    colour * f + light.fog * (1.0 - f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn fast_floors_equal_the_standard_floor(x in -3.0e9f32..3.0e9f32, small in -1.0e4f32..1.0e4f32) {
            for v in [x, small, small.trunc(), small.trunc() - 0.5] {
                prop_assert_eq!(floor_f32(v), v.floor(), "{}", v);
                if v.abs() < 2.0e9 {
                    prop_assert_eq!(floor_i32(v) as f32, v.floor(), "{}", v);
                }
            }
        }
    }

    #[test]
    fn fast_floor_edge_cases() {
        for v in [
            0.0f32,
            1.0,
            -1.0,
            -0.5,
            0.5,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            1.0e30,
            -1.0e30,
            4_194_303.5,
            -4_194_303.5,
            4_194_304.0,
            -4_194_304.0,
            4_194_304.5,
            -4_194_304.5,
            2.5,
            -2.5,
            3.5,
            -3.5,
            0.999_999_94,
            -0.999_999_94,
        ] {
            assert_eq!(floor_f32(v), v.floor(), "{v}");
            if v.abs() < 2.0e9 {
                assert_eq!(floor_i32(v) as f32, v.floor(), "{v}");
            }
        }
        assert!(floor_f32(f32::NAN).is_nan());
        assert_eq!(floor_f32(f32::INFINITY), f32::INFINITY);
        assert_eq!(floor_f32(f32::NEG_INFINITY), f32::NEG_INFINITY);
    }
}
