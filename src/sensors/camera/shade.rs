//! Surface shading: procedural textures (asphalt, paving tiles, façades with windows, grass) seeded per clip,
//! road paint, and the light a surface point receives (sun with shadows, sky and ground ambient, street lamps,
//! headlights, wet reflections), then fog. Everything in linear RGB; pure functions of the scene and the
//! lighting.

use glam::{Vec2, Vec3};
use std::ops::{Add, Mul, Sub};

use super::figure::{capsule_normals, face, pattern_share};
use super::lanes::{F, LANES, V3, exp_lanes, lanes_from, transpose_cells};
use super::light::{HEADLAMP_INTENSITY, LAMP_INTENSITY, Lighting};
use super::round::{floor_i32, floor_int};
use crate::sensors::scene::{
    CROSSWALK_PAINT, FrameScene, HEAD_LONG_HAIR, Mark, Material, PATTERN_PLAIN, PieceSurface, Prim, StaticScene,
    body_capsule, body_pattern, crosswalk_across, road_marking, road_paint_near, tag,
};
use crate::util::mix::splitmix64;

/// A seeded tileable value-noise table, sampled bilinearly (values in [−1, 1]).
///
/// Stored as the four corners of each cell (`(x, y)`, `(x + 1, y)`, `(x, y + 1)`, `(x + 1, y + 1)`, wrapped), so
/// that a bilinear sample reads one 16-byte entry instead of four scattered values, from a table whose size
/// the index cannot exceed (no bounds checks).
#[derive(Clone, Debug)]
pub struct Noise {
    cells: Box<[[f32; 4]; NOISE_CELLS]>,
}

const NOISE_SIZE: usize = 256;
const NOISE_CELLS: usize = NOISE_SIZE * NOISE_SIZE;

impl Noise {
    /// The noise table of a seed.
    pub fn new(seed: u64) -> Noise {
        let values: Vec<f32> = (0..NOISE_CELLS)
            .map(|i| (splitmix64(seed ^ splitmix64(i as u64)) >> 40) as f32 / (1u64 << 23) as f32 - 1.0)
            .collect();
        let value = |x: usize, y: usize| values[(y % NOISE_SIZE) * NOISE_SIZE + x % NOISE_SIZE];
        let cells: Vec<[f32; 4]> = (0..NOISE_CELLS)
            .map(|i| {
                let (x, y) = (i % NOISE_SIZE, i / NOISE_SIZE);
                [value(x, y), value(x + 1, y), value(x, y + 1), value(x + 1, y + 1)]
            })
            .collect();
        // Built on the heap (a 1 MiB array would pass through the stack of a worker thread).
        let cells = cells
            .into_boxed_slice()
            .try_into()
            .unwrap_or_else(|_| unreachable!("NOISE_CELLS cells"));
        Noise { cells }
    }

    /// The corners of the cell `(ix, iy)` (wrapped).
    #[inline(always)]
    fn corners(&self, ix: i32, iy: i32) -> [f32; 4] {
        let m = (NOISE_SIZE - 1) as i32;
        self.cells[(iy & m) as usize * NOISE_SIZE + (ix & m) as usize]
    }

    /// Bilinear sample at `p` (one cell per unit).
    #[inline(always)]
    pub fn sample(&self, p: Vec2) -> f32 {
        let (ix, iy) = (floor_i32(p.x), floor_i32(p.y));
        let (tx, ty) = (p.x - ix as f32, p.y - iy as f32);
        let [v00, v10, v01, v11] = self.corners(ix, iy);
        let a = v00 + (v10 - v00) * tx;
        let b = v01 + (v11 - v01) * tx;
        a + (b - a) * ty
    }

    /// [`Noise::sample`] at the lanes' places `(qx, qy)`, lane by lane the same values.
    #[inline(always)]
    pub fn sample_lanes(&self, qx: F, qy: F) -> F {
        let (ix, iy) = (floor_int(qx), floor_int(qy));
        let (tx, ty) = (qx - ix.round_float(), qy - iy.round_float());
        let (xa, ya) = (ix.to_array(), iy.to_array());
        let c: [[f32; 4]; LANES] = std::array::from_fn(|i| self.corners(xa[i], ya[i]));
        let [v00, v10, v01, v11] = transpose_cells(&c);
        let a = v00 + (v10 - v00) * tx;
        let b = v01 + (v11 - v01) * tx;
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
    /// The street lamps to test (those near the camera that can reach the points shaded: [`super::cull`]).
    pub lamps: &'a [Vec3],
    /// The headlights to test, likewise.
    pub heads: &'a [(Vec3, Vec3)],
}

/// A street lamp lights points within 40 m (squared, m²).
pub const LAMP_REACH_M2: f32 = 1600.0;
/// A headlight lights points within 60 m (squared, m²)…
pub const HEAD_REACH_M2: f32 = 3600.0;
/// …more than 0.1 m ahead of it…
pub const HEAD_AHEAD_M: f32 = 0.1;
/// …below its cut-off, a slope of 2 % above its horizontal…
pub const HEAD_CUTOFF_SLOPE: f32 = 0.02;
/// …and at most 0.7 times as far to the side as ahead.
pub const HEAD_SPREAD: f32 = 0.7;

/// Surface points of one primitive (one per lane), as the camera sees them.
#[derive(Clone, Copy, Debug)]
pub struct Points {
    /// The points, scene-relative.
    pub p: V3,
    /// The camera's rays to them (not unit: `forward + right·x + down·y`).
    pub ray: V3,
    /// The rays' lengths.
    pub ray_len: F,
    /// The sun's visibility at each (0–1).
    pub shadow: F,
    /// The points' depths along the optical axis, metres.
    pub depth_m: F,
}

/// A noise value per lane, scaled: `1 + amp × noise(q)`.
#[inline(always)]
fn grain(nz: &Noise, qx: F, qy: F, amp: f32) -> F {
    F::ONE + F::splat(amp) * nz.sample_lanes(qx, qy)
}

/// Road wear at the lanes' road points: repair patches (darker, newer asphalt: a 3 × 2 m rectangle in one cell
/// of a 7 × 5 m grid in five or so, drawn from the clip's noise table) and cracks (thin dark lines along the zero
/// crossings of a noise of 2 m cells, fading out beyond 25 m, where they would be thinner than a pixel and
/// only flicker); `tex` is domain randomisation's texture contrast. A factor on the albedo.
#[inline(always)]
fn road_wear(nz: &Noise, x: F, y: F, ray_len: F, tex: f32) -> F {
    let (gx, gy) = (x * (1.0 / 7.0), y * (1.0 / 5.0));
    let (ix, iy) = (floor_int(gx), floor_int(gy));
    let (cx, cy) = (ix.round_float(), iy.round_float());
    let (fx, fy) = (gx - cx, gy - cy);
    let inside = fx.simd_gt(F::splat(0.2))
        & fx.simd_lt(F::splat(0.63))
        & fy.simd_gt(F::splat(0.25))
        & fy.simd_lt(F::splat(0.65));
    let mut wear = F::ONE;
    if inside.any() {
        // The noise table's value at the cell's corner (a sample at integer coordinates), in [-1, 1).
        let patched = nz.sample_lanes(cx, cy + 91.0).simd_gt(F::splat(0.6));
        wear = (patched & inside).select(F::splat(1.0 - 0.2 * tex), F::ONE);
    }
    let near = (F::ONE - ray_len * (1.0 / 25.0)).fast_max(F::ZERO);
    if near.simd_gt(F::ZERO).any() {
        let c = nz.sample_lanes(x * 0.5 + 11.0, y * 0.5 - 5.0).abs();
        wear *= c
            .simd_lt(F::splat(0.016))
            .select(F::ONE - F::splat((0.45 * tex).min(1.0)) * near, F::ONE);
    }
    wear
}

/// The shaded colours of the lanes' points of one primitive, before fog, and their semantic tags (road paint
/// turns road into road line): textures, then the light each point receives (sun with shadows, sky and
/// ground ambient, street lamps, headlights) and reflections where the surface is glossy.
#[inline(always)]
pub fn surface(ctx: &ShadeContext, prim: &Prim, pts: &Points) -> (V3, [u8; LANES]) {
    let l = ctx.light;
    let nz = ctx.noise;
    let p = pts.p;
    let (x, y, z) = (p.x, p.y, p.z);
    let one = F::ONE;
    let mut normal = V3::splat(prim.normal);
    let mut albedo = V3::splat(prim.albedo);
    let mut emissive = V3::ZERO;
    // Mirror-like reflection share (wet ground, glass, paint).
    let mut gloss = F::ZERO;
    let mut ground = false;
    let mut semantic = [prim.tag; LANES];
    // Domain randomisation's factor on every texture's amplitude (1: as drawn below).
    let tex = ctx.scene.texture_contrast;
    match prim.material {
        Material::Road => {
            ground = true;
            let g = F::ONE
                + F::splat(0.16 * tex) * nz.sample_lanes(x * 1.3, y * 1.3)
                + F::splat(0.08 * tex) * nz.sample_lanes(x * 6.1 + 37.0, y * 6.1 + 37.0);
            albedo = albedo.scale(road_wear(nz, x, y, pts.ray_len, tex) * g);
            if let Some(piece) = ctx.scene.pieces.get(prim.aux as usize)
                && road_paint_near(
                    ctx.scene,
                    piece,
                    Vec2::new(lane_min(x), lane_min(y)),
                    Vec2::new(lane_max(x), lane_max(y)),
                )
            {
                let (painted, paint, paint_tags) = road_paint_lanes(ctx.scene, piece, x, y);
                if painted != 0 {
                    // The paint's grain: lane by lane `0.92 + 0.08 · noise(9 p)`.
                    let f = (F::splat(0.92) + F::splat(0.08 * tex) * nz.sample_lanes(x * 9.0, y * 9.0)).to_array();
                    let mut lanes = albedo.lanes();
                    for i in (0..LANES).filter(|&i| painted & (1 << i) != 0) {
                        lanes[i] = paint[i] * f[i];
                        if prim.tag == tag::ROAD {
                            semantic[i] = paint_tags[i];
                        }
                    }
                    albedo = V3::from_lanes(lanes);
                }
            }
        }
        Material::Sidewalk => {
            ground = true;
            if prim.tag == tag::SIDEWALK {
                let (gx, gy) = (x / 0.6, y / 0.6);
                let (ix, iy) = (floor_int(gx), floor_int(gy));
                let (fx, fy) = (gx - ix.round_float(), gy - iy.round_float());
                let joint = fx.simd_lt(F::splat(0.05)) | fy.simd_lt(F::splat(0.05));
                let (ixs, iys) = (ix.to_array(), iy.to_array());
                let cell = lanes_from(|i| nz.cell(ixs[i], iys[i], 7));
                let tile = F::splat(0.88) + F::splat(0.2 * tex) * cell;
                albedo = albedo.scale(joint.select(F::splat(0.62), tile));
            }
            albedo = albedo.scale(grain(nz, x * 3.7, y * 3.7, 0.08 * tex));
        }
        Material::Curb => {
            ground = true;
            albedo = albedo.scale(grain(nz, x * 4.0 + z, y * 4.0 + z, 0.1 * tex));
        }
        Material::Terrain => {
            ground = true;
            let patch = nz.sample_lanes(x * 0.21, y * 0.21);
            let s = (F::splat(0.5) + F::splat(0.6 * tex) * patch)
                .fast_max(F::ZERO)
                .fast_min(one);
            albedo = V3::lerp(prim.albedo, Vec3::new(0.11, 0.09, 0.05), s);
            albedo = albedo.scale(grain(nz, x * 2.9, y * 2.9, 0.2 * tex));
        }
        Material::Wall => {
            let n = prim.normal;
            let a = (x * -n.y + y * n.x) / 2.8;
            let zz = z / 3.2;
            let (cell_a, cell_z) = (floor_int(a), floor_int(zz));
            let (fa, fz) = (a - cell_a.round_float(), zz - cell_z.round_float());
            // A building with a shop on its ground floor has a second colour, its signs' (see `StaticScene`).
            let shop = prim.albedo2 != prim.albedo;
            let ground_floor = if shop {
                zz.simd_lt(F::ONE)
            } else {
                F::ZERO.simd_gt(F::ONE)
            };
            let window = fa.simd_gt(F::splat(0.22))
                & fa.simd_lt(F::splat(0.78))
                & fz.simd_gt(F::splat(0.3))
                & fz.simd_lt(F::splat(0.82))
                & z.simd_gt(F::splat(1.2))
                & !ground_floor;
            let plain = albedo.scale(grain(nz, a * 4.0, z * 2.0, 0.07 * tex));
            let floor_line = fz.simd_lt(F::splat(0.04));
            let wall = V3::select(floor_line, albedo.scale(F::splat(0.7)), plain);
            albedo = V3::select(window, V3::splat(Vec3::new(0.03, 0.035, 0.045)), wall);
            gloss = window.select(F::splat(0.35), F::ZERO);
            // Shop fronts: a display window across each bay (mullions between), a sign band above it.
            let display = ground_floor
                & fa.simd_gt(F::splat(0.05))
                & fa.simd_lt(F::splat(0.95))
                & fz.simd_gt(F::splat(0.06))
                & fz.simd_lt(F::splat(0.7));
            if shop {
                let sign = ground_floor & fz.simd_gt(F::splat(0.76)) & fz.simd_lt(F::splat(0.95));
                let sign_colour = V3::splat(prim.albedo2).scale(grain(nz, a * 7.0, z * 5.0, 0.12 * tex));
                albedo = V3::select(sign, sign_colour, albedo);
                // Goods behind the glass: dim, mottled colours.
                let goods = F::splat(0.05) + F::splat(0.03 * tex) * nz.sample_lanes(a * 9.0, z * 3.0);
                let glass = V3 {
                    x: goods,
                    y: goods * F::splat(0.95),
                    z: goods * F::splat(1.1),
                };
                albedo = V3::select(display, glass, albedo);
                gloss = display.select(F::splat(0.4), gloss);
            }
            let lit_window = window | display;
            if lit_window.any() && l.night > 0.0 {
                let (ca, cz, win, shop_lanes) = (
                    cell_a.to_array(),
                    cell_z.to_array(),
                    window.to_bitmask(),
                    display.to_bitmask(),
                );
                // One window in five is lit at night; three shops in five are, a little brighter.
                let lit = lanes_from(|i| {
                    let on = |share: f32| nz.cell(ca[i], cz[i], prim.aux) < share;
                    if win & (1 << i) != 0 && on(0.22) {
                        1.0
                    } else if shop_lanes & (1 << i) != 0 && on(0.6) {
                        1.3
                    } else {
                        0.0
                    }
                });
                emissive = V3::splat(Vec3::new(0.9, 0.7, 0.42) * (0.35 * l.night)).scale(lit);
            }
        }
        Material::Roof | Material::Metal | Material::Tyre | Material::Fabric => {}
        Material::LampHead => emissive = V3::splat(Vec3::new(3.0, 2.5, 1.8) * l.night),
        Material::Trunk => albedo = albedo.scale(grain(nz, x * 9.0, z * 3.0, 0.2 * tex)),
        Material::Foliage => {
            let f = F::splat(0.8) + F::splat(0.45 * tex) * nz.sample_lanes(x * 2.2 + z, y * 2.2 - z);
            albedo = albedo.scale(f);
        }
        Material::CarPaint => gloss = F::splat(0.18),
        Material::CarGlass => gloss = F::splat(0.12),
        Material::HeadLamp => emissive = V3::splat(Vec3::new(4.0, 3.9, 3.5) * (0.08 + l.night)),
        Material::TailLamp => emissive = V3::splat(Vec3::new(2.5, 0.1, 0.08) * (0.05 + l.night)),
        Material::Beacon => emissive = V3::splat(prim.albedo * (1.5 + 2.0 * l.night)),
        Material::Poster => emissive = V3::splat(prim.albedo * (0.8 * l.night)),
        Material::Body | Material::Head => {
            let pattern = body_pattern(prim.aux);
            if prim.material == Material::Body && pattern != PATTERN_PLAIN {
                let right = Vec3::new(prim.normal.y, -prim.normal.x, 0.0);
                let m = pattern_share(pattern, p, right, pts.depth_m);
                albedo = albedo.add(V3::splat(prim.albedo2).sub(albedo).scale(m));
            }
            if let Some(c) = ctx.frame.capsules.get(body_capsule(prim.aux)) {
                normal = capsule_normals(c, p);
                if prim.material == Material::Head {
                    // The face is placed by the directions from the head's centre (a sphere's normals): the skull
                    // capsule's lower end (`body::silhouette`).
                    let rel = p.sub(V3::splat(c.a));
                    let dir = rel.scale(F::ONE / rel.length_squared().fast_max(F::splat(1.0e-12)).sqrt());
                    albedo = face(prim, dir, albedo, pattern == HEAD_LONG_HAIR);
                }
                // Cloth and skin darken towards a body part's outline (folds, self-shadowing, a rough
                // surface's view dependence): `0.6 + 0.4 (n·v)⁺`, so that a limb shows against a torso of its
                // own colour.
                let n_dot_v = -normal.dot(pts.ray) / pts.ray_len.fast_max(F::splat(1.0e-6));
                albedo = albedo.scale(F::splat(0.6) + F::splat(0.4) * n_dot_v.fast_max(F::ZERO));
            }
            albedo = albedo.scale(grain(nz, z * 23.0, x * 7.0 + y * 5.0, 0.06 * tex));
        }
    }
    if ground && l.wet > 0.0 {
        // Darker when wet, and puddles (a low-frequency noise mask) that mirror the sky and the lights.
        let mask = (nz.sample_lanes(x * 0.35, y * 0.35) - 0.15) * 4.0;
        let puddle = mask.fast_max(F::ZERO).fast_min(one) * l.wet;
        albedo = albedo.scale(F::splat(1.0 - 0.4 * l.wet) - F::splat(0.2) * puddle);
        gloss = gloss.fast_max(F::splat(l.wet * 0.25) + F::splat(0.6) * puddle);
    }
    let glossy = gloss.simd_gt(F::ZERO).any();

    // The unit vectors from the points to the camera, for reflections (glossy surfaces only).
    let view = if glossy {
        pts.ray.scale(-(one / pts.ray_len))
    } else {
        V3::ZERO
    };

    // Light received.
    let ndl = normal.dot_v(l.sun_dir).fast_max(F::ZERO);
    let up = F::splat(0.5) + F::splat(0.5) * normal.z;
    let mut light = V3::lerp(l.ground_ambient, l.sky_ambient, up).add(V3::splat(l.sun).scale(ndl * pts.shadow));
    let mut glints = V3::ZERO;
    if l.night > 0.0 {
        // Street lamps: `d` from the point to the lamp, `dir = d / |d|`. Written without normalising `d` (a
        // square root and a division per lamp and lane saved, the costliest part of a night frame). All lamps
        // have one colour, so their light is summed as one factor per lane and coloured once.
        let lamp_intensity = F::splat(LAMP_INTENSITY * l.night);
        let (n_dot_v, one_plus_v2) = (normal.dot(view), one + view.length_squared());
        let (mut lamps_sum, mut glints_sum) = (F::ZERO, F::ZERO);
        for &lamp in ctx.lamps {
            let d = V3::splat(lamp).sub(p);
            let d2 = d.length_squared();
            let near = d2.simd_le(F::splat(LAMP_REACH_M2));
            if !near.any() {
                continue;
            }
            // Diffuse, from a lamp that shines downwards (light falls off away from below it):
            // `fall · (n·dir)⁺ · dir.z⁺` with `fall = I / (|d|² + 1)`, as `I · (n·d)⁺ · d.z⁺ / ((|d|² + 1) |d|²)`.
            let fall_per_d2 = lamp_intensity / ((d2 + one) * d2.fast_max(F::splat(1.0e-12)));
            let n_dot_d = normal.dot(d);
            let k = fall_per_d2 * n_dot_d.fast_max(F::ZERO) * d.z.fast_max(F::ZERO);
            lamps_sum += near.select(k, F::ZERO);
            if glossy {
                // Blinn-Phong `(n·h)^32` with the half vector `h ∝ dir + view`, here `h = d + view · |d|` (the
                // same direction), as `((n·h)⁺² / |h|²)^16`: `n·h = n·d + |d| n·view` and
                // `|h|² = |d|² (1 + |view|²) + 2 |d| d·view`, from what the diffuse term has worked out.
                let len = d2.sqrt();
                let nh = (n_dot_d + len * n_dot_v).fast_max(F::ZERO);
                let h2 = d2 * one_plus_v2 + (len + len) * d.dot(view);
                let s2 = nh * nh / h2.fast_max(F::splat(1.0e-12));
                let s4 = s2 * s2;
                let s8 = s4 * s4;
                let s16 = s8 * s8;
                glints_sum += near.select(fall_per_d2 * d2 * (s16 * s16), F::ZERO);
            }
        }
        let lamp_colour = Vec3::new(1.0, 0.78, 0.5);
        light = light.add(V3::splat(lamp_colour).scale(lamps_sum));
        if glossy {
            glints = V3::splat(lamp_colour).scale(glints_sum * gloss * 6.0);
        }
        let mut heads_sum = F::ZERO;
        for &(pos, axis) in ctx.heads {
            let d = p.sub(V3::splat(pos));
            let d2 = d.length_squared();
            // A low beam: wide sideways, cut off just above the lamp's horizontal.
            let ahead = d.x * axis.x + d.y * axis.y;
            let mut on = d2.simd_ge(F::splat(1e-4))
                & d2.simd_le(F::splat(HEAD_REACH_M2))
                & ahead.simd_gt(F::splat(HEAD_AHEAD_M));
            // A lane is in the beam only if it is within its spread (`|side| < 1`) and below its cut-off
            // (`up < HEAD_CUTOFF_SLOPE`): tested first without a division, with a margin far beyond rounding, so
            // that a lamp whose beam misses every lane costs no division (the light is the same either way).
            let cross = d.x * axis.y - d.y * axis.x;
            let margin = F::splat(1.0 + 1.0e-4);
            let may = cross.abs().simd_lt(ahead * (HEAD_SPREAD * margin))
                & d.z.simd_lt(ahead * (HEAD_CUTOFF_SLOPE * margin) + ahead.abs() * 1.0e-4);
            if !(on & may).any() {
                continue;
            }
            // Lanes behind the lamp divide by zero or less; `on` masks them.
            let per_ahead = one / ahead;
            let side = (cross * per_ahead * (1.0 / HEAD_SPREAD)).abs();
            let up = d.z * per_ahead;
            let cut = ((F::splat(HEAD_CUTOFF_SLOPE) - up) * 25.0)
                .fast_max(F::ZERO)
                .fast_min(one);
            let beam = (one - side * side).fast_max(F::ZERO) * cut;
            on &= beam.simd_gt(F::ZERO);
            if !on.any() {
                continue;
            }
            // `fall · (−n·dir)⁺` with `fall = I · beam / (|d|² + 30)` and `dir = d / |d|`, in one division (`I`
            // applied after the loop, with the colour).
            let fall_per_d = beam / ((d2 + 30.0) * d2.sqrt());
            heads_sum += on.select(fall_per_d * (-normal.dot(d)).fast_max(F::ZERO), F::ZERO);
        }
        // Every headlight has one colour and intensity too.
        light = light.add(V3::splat(Vec3::new(1.0, 0.97, 0.9) * (HEADLAMP_INTENSITY * l.night)).scale(heads_sum));
    }
    let mut colour = albedo.mul(light).add(emissive).add(glints);
    if glossy {
        let r = normal.scale(F::splat(2.0) * view.dot(normal)).sub(view);
        let r = V3 { z: r.z.abs(), ..r };
        let cos = normal.dot(view).fast_max(F::ZERO);
        let c5 = {
            let m = one - cos;
            let m2 = m * m;
            m2 * m2 * m
        };
        let fresnel = F::splat(0.04) + F::splat(0.96) * c5;
        colour = colour.add(l.sky(r).scale(gloss * (F::splat(0.08) + F::splat(0.92) * fresnel)));
    }
    (colour, semantic)
}

/// [`road_paint`] at the lanes' points `(x, y)` of a road piece, lane by lane the same paint: a bit per painted
/// lane, and their colours and tags. The crosswalk (its polygon and stripes) is worked out for all lanes at
/// once, markings point by point for the lanes off it.
#[inline(always)]
fn road_paint_lanes(scene: &StaticScene, piece: &PieceSurface, x: F, y: F) -> (u32, [Vec3; LANES], [u8; LANES]) {
    let (mut painted, mut colour, mut tags) = (0u32, [Vec3::ZERO; LANES], [0u8; LANES]);
    let mut off_crosswalk = u32::MAX;
    if let Some(cw) = piece.crosswalk {
        let inside = inside_polygon_lanes(&scene.crosswalks[cw as usize], x, y);
        if inside.any() {
            off_crosswalk = !(inside.to_bitmask() as u32);
            let across = crosswalk_across(piece);
            let k = x * across.x + y * across.y;
            painted = (inside & (k - k.floor()).simd_lt(F::splat(0.5))).to_bitmask() as u32;
            for i in (0..LANES).filter(|&i| painted & (1 << i) != 0) {
                (colour[i], tags[i]) = (CROSSWALK_PAINT, tag::ROAD_LINE);
            }
        }
    }
    if piece.marks != [Mark::None, Mark::None] {
        let (xs, ys) = (x.to_array(), y.to_array());
        for i in (0..LANES).filter(|&i| off_crosswalk & (1 << i) != 0) {
            if let Some(paint) = road_marking(piece, Vec2::new(xs[i], ys[i])) {
                (colour[i], tags[i]) = paint;
                painted |= 1 << i;
            }
        }
    }
    (painted, colour, tags)
}

/// [`point_in_polygon`](crate::sensors::scene::point_in_polygon) at the lanes' points `(x, y)`: the
/// same even-odd crossings, lane by lane the same result.
#[inline(always)]
fn inside_polygon_lanes(poly: &[Vec2], x: F, y: F) -> F {
    let mut inside = F::ZERO.simd_gt(F::ZERO);
    let mut j = poly.len().wrapping_sub(1);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[j];
        let straddles = y.simd_lt(F::splat(a.y)) ^ y.simd_lt(F::splat(b.y));
        // Lanes that do not straddle the edge may divide by zero here; they are masked out.
        let left = x.simd_lt(F::splat(b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x);
        inside ^= straddles & left;
        j = i;
    }
    inside
}

/// The least of the lanes.
#[inline(always)]
fn lane_min(v: F) -> f32 {
    v.to_array().into_iter().fold(f32::INFINITY, f32::min)
}

/// The greatest of the lanes.
#[inline(always)]
fn lane_max(v: F) -> f32 {
    v.to_array().into_iter().fold(f32::NEG_INFINITY, f32::max)
}

/// Applies fog over the lanes' distances.
#[inline(always)]
pub fn fog(light: &Lighting, colour: V3, dist_m: F) -> V3 {
    let f = exp_lanes(F::splat(-light.fog_per_m) * dist_m);
    colour.scale(f).add(V3::splat(light.fog).scale(F::ONE - f))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn lane_noise_samples_equal_single_ones(x in proptest::array::uniform8(-3.0e3f32..3.0e3), y in proptest::array::uniform8(-3.0e3f32..3.0e3)) {
            let nz = Noise::new(17);
            let got = nz.sample_lanes(F::new(x), F::new(y)).to_array();
            for i in 0..LANES {
                prop_assert_eq!(got[i], nz.sample(Vec2::new(x[i], y[i])));
            }
        }
    }

    proptest! {
        #[test]
        fn lane_polygon_tests_equal_single_ones(
            poly in proptest::collection::vec((-20.0f32..20.0, -20.0f32..20.0), 3..7),
            x in proptest::array::uniform8(-25.0f32..25.0),
            y in proptest::array::uniform8(-25.0f32..25.0),
        ) {
            // Vertices on the points' rows too (horizontal edges, points level with a vertex).
            let mut poly: Vec<Vec2> = poly.into_iter().map(|(a, b)| Vec2::new(a, b)).collect();
            poly[0].y = y[0];
            poly[1].y = poly[0].y;
            let got = inside_polygon_lanes(&poly, F::new(x), F::new(y)).to_bitmask();
            for i in 0..LANES {
                let want = crate::sensors::scene::point_in_polygon(&poly, Vec2::new(x[i], y[i]));
                prop_assert_eq!(got & (1 << i) != 0, want, "lane {}", i);
            }
        }
    }

    #[test]
    fn a_sky_hidden_by_fog_is_the_fog_bit_for_bit() {
        use crate::sensors::camera::light::SKY_FOG_M;
        use crate::spec::types::WeatherPreset;
        let mut hidden = Vec::new();
        for preset in WeatherPreset::ALL {
            let l = Lighting::from_weather(&preset.params());
            let Some(fog) = l.sky_hidden_by_fog() else {
                continue;
            };
            hidden.push(preset);
            // Directions all round, the sun's own and below the horizon included.
            let mut dirs: Vec<Vec3> = (0..4000)
                .map(|i| {
                    let (az, el) = (i as f32 * 2.399, (i as f32 / 4000.0) * 3.1 - 1.55);
                    Vec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
                })
                .collect();
            dirs.push(l.sun_dir);
            for chunk in dirs.chunks(LANES) {
                let dir = V3::from_lanes(std::array::from_fn(|i| chunk[i.min(chunk.len() - 1)]));
                let got = super::fog(&l, l.sky(dir), F::splat(SKY_FOG_M)).lanes();
                for c in got {
                    assert_eq!(
                        c.to_array().map(f32::to_bits),
                        fog.to_array().map(f32::to_bits),
                        "{preset:?}"
                    );
                }
            }
        }
        // Thick fog hides the sky (foggy noon, night fog), and so does night rain's light fog over a dark sky;
        // thin fog by day does not.
        assert_eq!(
            hidden,
            [
                WeatherPreset::FoggyNoon,
                WeatherPreset::NightRainy,
                WeatherPreset::NightFoggy
            ]
        );
    }

    #[test]
    fn lane_road_paint_equals_road_paint_point_by_point() {
        use crate::sensors::scene::{PieceSurface, road_paint};
        use rand::{RngExt, SeedableRng};
        // A diagonal piece 7 m wide with a crosswalk over part of it, and each kind of marking on its borders.
        let (a, b) = (Vec2::new(0.0, 0.0), Vec2::new(30.0, 12.0));
        let side = (b - a).normalize().perp() * 7.0;
        let crosswalk = vec![
            a + (b - a) * 0.4,
            a + (b - a) * 0.55,
            a + (b - a) * 0.55 + side,
            a + (b - a) * 0.4 + side,
        ];
        let scene = StaticScene {
            origin: glam::DVec3::ZERO,
            tris: Vec::new(),
            clusters: Vec::new(),
            prims: Vec::new(),
            pieces: Vec::new(),
            crosswalks: vec![crosswalk],
            lamps: Vec::new(),
            signal_heads: Vec::new(),
            seed: 0,
            outfits: Vec::new(),
            riders: Vec::new(),
            car_paint: Vec::new(),
            texture_contrast: 1.0,
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut lanes_painted, mut crosswalk_painted) = (0, 0);
        for marks in [
            [Mark::Centre, Mark::Dashed],
            [Mark::None, Mark::Solid],
            [Mark::None, Mark::None],
        ] {
            for crosswalk in [Some(0), None] {
                let piece = PieceSurface {
                    inner: [a, b],
                    outer: [a + side, b + side],
                    s_m: [100.0, 100.0 + (b - a).length()],
                    marks,
                    crosswalk,
                };
                for _ in 0..400 {
                    // Points near the borders as well as anywhere on the piece.
                    let near = rng.random_range(0.0..1.0f32) < 0.5;
                    let pts: [Vec2; LANES] = std::array::from_fn(|_| {
                        let t = rng.random_range(-0.05..1.05f32);
                        let u = if near {
                            [0.0f32, 1.0][rng.random_range(0..2usize)] + rng.random_range(-0.04..0.04f32)
                        } else {
                            rng.random_range(-0.1..1.1f32)
                        };
                        a + (b - a) * t + side * u
                    });
                    let (painted, colour, tags) =
                        road_paint_lanes(&scene, &piece, lanes_from(|i| pts[i].x), lanes_from(|i| pts[i].y));
                    for (i, &p) in pts.iter().enumerate() {
                        let got = (painted & (1 << i) != 0).then_some((colour[i], tags[i]));
                        assert_eq!(got, road_paint(&scene, &piece, p), "at {p}");
                        lanes_painted += usize::from(got.is_some());
                        crosswalk_painted += usize::from(got.is_some_and(|g| g.0 == CROSSWALK_PAINT));
                    }
                }
            }
        }
        // Both kinds of paint were hit, and bare asphalt too.
        assert!(
            crosswalk_painted > 100 && lanes_painted > crosswalk_painted + 100,
            "{crosswalk_painted} {lanes_painted}"
        );
        assert!(lanes_painted < 3 * 2 * 400 * LANES / 2, "{lanes_painted}");
    }
}
