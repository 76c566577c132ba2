//! The camera streams, rendered on the CPU: RGB, depth, semantic and instance segmentation from one
//! rasterisation of the scene, and DVS events from the rendered luminance.
//!
//! - [`raster`] — the visibility buffers (nearest primitive and depth per sample).
//! - [`group`] — grouping of edge samples by primitive for shading.
//! - [`lanes`] — lane math for shading several pixels at once.
//! - [`light`] — lighting from the weather.
//! - [`shade`] — textures, road paint, lights, reflections, fog.
//! - [`dvs`] — the ESIM event simulator.
//!
//! A frame is drawn at `SS × SS` samples per pixel, in bands of rows, with the same
//! [`CameraPose`](crate::sim::rig::CameraPose) (intrinsics and pose) that the annotations project
//! with: every pixel's first sample, and all four where the first samples of the pixel and of its right,
//! lower and diagonal neighbours differ ([`raster::BandVisibility`]). Label streams are point samples (the
//! pixel's first sample, at `(u + 0.25, v + 0.25)`; road paint's semantic label at the pixel centre when all
//! samples see one primitive, where the colour is shaded); RGB shades a pixel once where its samples see one
//! primitive and each sample where they differ (edge antialiasing), then adds rain streaks and maps to sRGB.

pub mod dvs;
pub mod group;
pub mod lanes;
pub mod light;
pub mod raster;
pub mod shade;

use glam::{DAffine3, DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::sync::Mutex;

use super::scene::{FrameScene, Material, Prim, StaticScene, tag};
use crate::sim::rig::{Camera, CameraPose};
use crate::util::mix::splitmix64;
use group::Grouper;
use lanes::{F, LANES, V3, floor_int, lanes_from};
use light::Lighting;
use raster::{BandVisibility, EDGE, EMPTY, Raster, Setup, clip_near};
use shade::{ActiveLights, Noise, ShadeContext};
use wide::f32x4;

/// Samples per pixel along each axis.
pub const SS: usize = 2;
/// Near clipping distance, metres.
pub const NEAR_M: f32 = 0.05;
/// Static clusters farther than this are not drawn (fog and the terrain plane take over), metres.
const FAR_M: f32 = 450.0;
/// The [`Lighting::night`] from which street lamps are lit (from a sun about 4.6° above the horizon down). At
/// dawn's 5° (0.03) lamps at 3 % of their night intensity changed 0.2 % of a frame's pixels by 3–7 levels and
/// the rest by at most 2 (PSNR 54.7 dB), and cost a fifth of the frame.
const LAMPS_ON_NIGHT: f32 = 0.05;
/// Depth written for sky pixels, metres (CARLA's far plane).
pub const SKY_DEPTH_M: f32 = 1000.0;
/// Shadow map: resolution and half-size of the square it covers, metres.
const SHADOW_PX: usize = 1024;
const SHADOW_HALF_M: f32 = 60.0;

/// The images of one rendered frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraImages {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// sRGB, 3 bytes per pixel, row-major from the top-left.
    pub rgb: Vec<u8>,
    /// Depth along the optical axis, metres ([`SKY_DEPTH_M`] for the sky).
    pub depth_m: Vec<f32>,
    /// CARLA semantic tag per pixel.
    pub semantic: Vec<u8>,
    /// Instance id per pixel (see [`super::scene::CHILD_INSTANCE_BASE`]).
    pub instance: Vec<u16>,
}

/// Rows of the images resolved as one task.
const BAND_ROWS: usize = 8;

/// Rows `y0..` of the images (as many as the slices hold).
struct Band<'a> {
    y0: usize,
    rgb: &'a mut [u8],
    depth_m: &'a mut [f32],
    semantic: &'a mut [u8],
    instance: &'a mut [u16],
}

/// Band buffers not in use (a clone starts without any).
#[derive(Debug, Default)]
struct BandBuffers(Mutex<Vec<BandScratch>>);

/// What resolving a band needs besides the images: its visibility grid, its edge pixels and a row's scratch,
/// kept from band to band (one set per worker at a time) so that a frame allocates nothing. Every band
/// rewrites what it reads.
#[derive(Debug)]
struct BandScratch {
    /// The band's visibility.
    vis: BandVisibility,
    /// The samples of the band's edge pixels (four per pixel, in (row, column) order) and their shaded colours
    /// and tags, by the sample's index in that list; their groups by primitive, shaded group by group.
    edges: Vec<Sample>,
    groups: Grouper,
    edge_colour: Vec<Vec3>,
    edge_tag: Vec<u8>,
    /// The row's linear colours, one channel each (`LANES − 1` of slack for whole-vector stores; the tone map
    /// reads groups of four).
    rgb: [Vec<f32>; 3],
}

impl BandScratch {
    /// Buffers for bands of a `w`-pixel-wide image.
    fn new(w: usize) -> BandScratch {
        BandScratch {
            vis: BandVisibility::new(w, BAND_ROWS),
            edges: Vec::new(),
            groups: Grouper::default(),
            edge_colour: Vec::new(),
            edge_tag: Vec::new(),
            rgb: [
                vec![0.0; w + LANES - 1],
                vec![0.0; w + LANES - 1],
                vec![0.0; w + LANES - 1],
            ],
        }
    }
}

impl Clone for BandBuffers {
    fn clone(&self) -> BandBuffers {
        BandBuffers::default()
    }
}

/// The orthographic sun camera of the shadow map.
#[derive(Clone, Copy, Debug)]
struct SunView {
    centre: Vec3,
    u: Vec3,
    v: Vec3,
    dir: Vec3,
    scale: f32,
}

impl SunView {
    /// Shadow-map pixel coordinates and depth towards the sun of a scene point.
    #[inline]
    fn project_f32(&self, p: Vec3) -> Vec3 {
        let d = p - self.centre;
        Vec3::new(
            d.dot(self.u) * self.scale + SHADOW_PX as f32 * 0.5,
            d.dot(self.v) * self.scale + SHADOW_PX as f32 * 0.5,
            d.dot(self.dir),
        )
    }

    /// [`SunView::project_f32`] for the rasteriser.
    fn project(&self, p: Vec3) -> DVec3 {
        self.project_f32(p).as_dvec3()
    }

    /// The sun's visibility at the lanes' scene points of a surface (1 lit, 0 in shadow) from the shadow map's
    /// depth keys, 2×2 percentage-closer filtered: the points are lifted off the surface by 5 cm and
    /// compared with a bias of 8 cm; texel centres at integers, bilinear between.
    #[inline(always)]
    fn sunlit(&self, key: &[f32], p: V3, normal: Vec3) -> F {
        let d = p + V3::splat(normal * 0.05) - V3::splat(self.centre);
        let half = SHADOW_PX as f32 * 0.5;
        let x = d.dot_v(self.u) * self.scale + half - 0.5;
        let y = d.dot_v(self.v) * self.scale + half - 0.5;
        let depth = (d.dot_v(self.dir) + 0.08).to_array();
        let (x0, y0) = (floor_int(x), floor_int(y));
        let (fx, fy) = (x - x0.round_float(), y - y0.round_float());
        let (xa, ya) = (x0.to_array(), y0.to_array());
        let last = (SHADOW_PX - 1) as i32;
        let mut c = [[1.0f32; LANES]; 4];
        for i in 0..LANES {
            if xa[i] < 0 || ya[i] < 0 || xa[i] >= last || ya[i] >= last {
                continue;
            }
            let k = ya[i] as usize * SHADOW_PX + xa[i] as usize;
            // One bounds check for the four texels.
            let Some(q) = key.get(k..k + SHADOW_PX + 2) else {
                continue;
            };
            let lit = |key: f32| if key > depth[i] { 0.0 } else { 1.0 };
            c[0][i] = lit(q[0]);
            c[1][i] = lit(q[1]);
            c[2][i] = lit(q[SHADOW_PX]);
            c[3][i] = lit(q[SHADOW_PX + 1]);
        }
        let [l00, l10, l01, l11] = c.map(F::new);
        let a = l00 + (l10 - l00) * fx;
        let b = l01 + (l11 - l01) * fx;
        a + (b - a) * fy
    }
}

/// The camera's view in a render: its centre (scene-relative), axes and intrinsics.
struct View {
    cam: Vec3,
    right: Vec3,
    down: Vec3,
    fwd: Vec3,
    cx: f32,
    cy: f32,
    inv_f: f32,
}

/// One sample of an edge pixel to shade.
#[derive(Clone, Copy, Debug)]
struct Sample {
    prim: u32,
    key: f32,
    u: f32,
    v: f32,
}

/// A camera renderer: buffers reused from frame to frame (one per worker thread).
#[derive(Clone, Debug)]
pub struct Renderer {
    camera: Camera,
    light: Lighting,
    noise: Noise,
    /// The frame's projected triangles, in drawing order, and per band of rows the ones that reach it.
    tris: Vec<Setup>,
    bins: Vec<Vec<u32>>,
    /// Visibility buffers of one band each (one per worker at a time): a band is drawn and resolved while
    /// its buffer is in cache.
    band_buffers: BandBuffers,
    shadow: Raster,
    sun: Option<SunView>,
    lights: ActiveLights,
    /// Scratch of [`nearest`]: (squared distance, index), reused from frame to frame.
    nearby: Vec<(f32, u32)>,
    lut: Box<[u8; LUT_LEN]>,
    /// The frame's rain streaks, in drawing order, and per band of rows the ones that reach it (drawn while
    /// the band is in cache: a whole-image pass misses the cache at every streak pixel).
    streaks: Vec<Streak>,
    streak_bins: Vec<Vec<u32>>,
}

/// A rain streak: a slanted, semi-transparent line from `(x0, y0)` down `steps` pixel rows.
#[derive(Clone, Copy, Debug)]
struct Streak {
    x0: f32,
    y0: f32,
    steps: usize,
    alpha: f32,
}

/// The (up to) `n` items nearest to `from` within `radius_m`, nearest first (ties by index), into `out`.
fn nearest<T>(items: &[T], pos: impl Fn(&T) -> Vec3, from: Vec3, radius_m: f32, n: usize, out: &mut Vec<(f32, u32)>) {
    out.clear();
    out.extend(
        items
            .iter()
            .enumerate()
            .map(|(i, t)| (pos(t).distance_squared(from), i as u32))
            .filter(|(d2, _)| *d2 < radius_m * radius_m),
    );
    out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    out.truncate(n);
}

/// Linear → sRGB lookup: `LUT[sqrt(x / LUT_MAX) × (LUT_LEN − 1)]` with a soft shoulder.
const LUT_LEN: usize = 4096;
const LUT_MAX: f32 = 8.0;

fn build_lut() -> Box<[u8; LUT_LEN]> {
    Box::new(std::array::from_fn(|i| {
        let s = i as f32 / (LUT_LEN - 1) as f32;
        let x = s * s * LUT_MAX;
        let mapped = 1.0 - (-1.1 * x).exp();
        let srgb = if mapped <= 0.003_130_8 {
            12.92 * mapped
        } else {
            1.055 * mapped.powf(1.0 / 2.4) - 0.055
        };
        (srgb * 255.0 + 0.5).clamp(0.0, 255.0) as u8
    }))
}

impl Renderer {
    /// A renderer for a camera, a clip's lighting and its texture seed.
    pub fn new(camera: &Camera, light: Lighting, seed: u64) -> Renderer {
        let h = camera.height_px as usize;
        Renderer {
            camera: *camera,
            light,
            noise: Noise::new(seed ^ 0x7e57_0000),
            tris: Vec::new(),
            bins: vec![Vec::new(); h.div_ceil(BAND_ROWS)],
            band_buffers: BandBuffers::default(),
            shadow: Raster::depth_only(SHADOW_PX, SHADOW_PX),
            sun: None,
            lights: ActiveLights::default(),
            nearby: Vec::new(),
            lut: build_lut(),
            streaks: Vec::new(),
            streak_bins: vec![Vec::new(); h.div_ceil(BAND_ROWS)],
        }
    }

    /// The lighting in use.
    pub fn lighting(&self) -> &Lighting {
        &self.light
    }

    /// Renders one frame seen from `pose` into `out`; `streak_seed` seeds the rain streaks.
    pub fn render(
        &mut self,
        scene: &StaticScene,
        frame: &FrameScene,
        pose: &CameraPose,
        streak_seed: u64,
        out: &mut CameraImages,
    ) {
        let (w, h) = (self.camera.width_px as usize, self.camera.height_px as usize);
        out.width = w;
        out.height = h;
        out.rgb.resize(w * h * 3, 0);
        out.depth_m.resize(w * h, 0.0);
        out.semantic.resize(w * h, 0);
        out.instance.resize(w * h, 0);
        let optical_from_scene = pose.optical_from_world * DAffine3::from_translation(scene.origin);
        self.draw_visibility(scene, frame, &optical_from_scene);
        let cam_rel = (pose.centre - scene.origin).as_vec3();
        self.draw_shadows(scene, frame, cam_rel, pose.forward.as_vec3());
        self.choose_lights(scene, frame, cam_rel, pose);
        self.place_streaks(streak_seed);
        self.resolve(scene, frame, pose, cam_rel, out);
    }

    fn draw_visibility(&mut self, scene: &StaticScene, frame: &FrameScene, optical_from_scene: &DAffine3) {
        let c = &self.camera;
        let m = optical_from_scene.matrix3.as_mat3();
        let t = optical_from_scene.translation.as_vec3();
        let (f, cx, cy) = (c.focal_px as f32, c.width_px as f32 * 0.5, c.height_px as f32 * 0.5);
        let ss = SS as f32;
        // Frustum side slopes (|x| ≤ z·sx, |y| ≤ z·sy) with the corners' secants for the sphere test.
        let (sx, sy) = (cx / f, cy / f);
        let (kx, ky) = ((1.0 + sx * sx).sqrt(), (1.0 + sy * sy).sqrt());
        let (sw, sh) = (c.width_px as usize * SS, c.height_px as usize * SS);
        self.tris.clear();
        let tris = &mut self.tris;
        let mut draw = |tri: &super::scene::Tri| {
            let v = tri.v.map(|p| m * p + t);
            if v.iter().all(|p| p.z < NEAR_M) {
                return;
            }
            let mut poly = [Vec3::ZERO; 4];
            let n = clip_near(v, NEAR_M, &mut poly);
            let proj = |p: Vec3| {
                let inv = 1.0 / p.z;
                DVec3::new(
                    f64::from((f * p.x * inv + cx) * ss),
                    f64::from((f * p.y * inv + cy) * ss),
                    f64::from(inv),
                )
            };
            for k in 1..n.saturating_sub(1) {
                let v = [proj(poly[0]), proj(poly[k]), proj(poly[k + 1])];
                tris.extend(Setup::new(v, tri.prim, sw, sh));
            }
        };
        for cl in &scene.clusters {
            let o = m * cl.centre + t;
            let r = cl.radius_m;
            let visible = o.z + r >= NEAR_M
                && o.x - r * kx <= o.z * sx
                && -o.x - r * kx <= o.z * sx
                && o.y - r * ky <= o.z * sy
                && -o.y - r * ky <= o.z * sy
                && (o.length() - r <= FAR_M || r > 1000.0);
            if visible {
                for tri in &scene.tris[cl.tris.start as usize..cl.tris.end as usize] {
                    draw(tri);
                }
            }
        }
        for tri in &frame.mesh.tris {
            draw(tri);
        }
        // Each triangle into the bands of rows it reaches, in drawing order: a band's sample rows and the
        // first of the band below (its grid's last row).
        let band_samples = BAND_ROWS * SS;
        for bin in &mut self.bins {
            bin.clear();
        }
        let last_bin = self.bins.len() - 1;
        for (i, t) in self.tris.iter().enumerate() {
            let first = (t.row0 as usize).saturating_sub(band_samples).div_ceil(band_samples);
            let last = (t.row1 as usize / band_samples).min(last_bin);
            for bin in &mut self.bins[first..=last] {
                bin.push(i as u32);
            }
        }
    }

    fn draw_shadows(&mut self, scene: &StaticScene, frame: &FrameScene, cam: Vec3, forward: Vec3) {
        if !self.light.shadows {
            self.sun = None;
            return;
        }
        let dir = self.light.sun_dir;
        let u = dir.any_orthonormal_vector();
        let v = dir.cross(u);
        let ahead = Vec3::new(forward.x, forward.y, 0.0).normalize_or_zero();
        let sun = SunView {
            centre: cam + ahead * (SHADOW_HALF_M * 0.7),
            u,
            v,
            dir,
            scale: SHADOW_PX as f32 / (2.0 * SHADOW_HALF_M),
        };
        self.shadow.clear(f32::NEG_INFINITY);
        let reach = SHADOW_HALF_M * 1.5 + 60.0;
        for cl in &scene.clusters {
            if cl.radius_m < 1000.0 && cl.centre.distance(sun.centre) - cl.radius_m <= reach {
                for tri in &scene.tris[cl.tris.start as usize..cl.tris.end as usize] {
                    let p = &scene.prims[tri.prim as usize];
                    // Ground surfaces receive shadows; casting them would only shadow themselves.
                    if matches!(
                        p.material,
                        Material::Road | Material::Sidewalk | Material::Terrain | Material::Curb
                    ) {
                        continue;
                    }
                    self.shadow.draw(tri.v.map(|q| sun.project(q)), tri.prim);
                }
            }
        }
        for tri in &frame.mesh.tris {
            self.shadow.draw(tri.v.map(|q| sun.project(q)), tri.prim);
        }
        self.sun = Some(sun);
    }

    fn choose_lights(&mut self, scene: &StaticScene, frame: &FrameScene, cam: Vec3, pose: &CameraPose) {
        self.lights.lamps.clear();
        self.lights.heads.clear();
        if self.light.night <= 0.0 {
            return;
        }
        // Street lamps switch on as the day fades (headlights are on whenever it is not full day).
        if self.light.night >= LAMPS_ON_NIGHT {
            nearest(&scene.lamps, |l| l.pos, cam, 90.0, 16, &mut self.nearby);
            self.lights
                .lamps
                .extend(self.nearby.iter().map(|&(_, i)| scene.lamps[i as usize].pos));
        }
        // The ego's own headlights (under the camera), then the nearest traffic's.
        let fwd = pose.forward.as_vec3();
        let axis = Vec3::new(fwd.x, fwd.y, 0.0).normalize_or_zero();
        let left = Vec3::new(-axis.y, axis.x, 0.0);
        for side in [0.7f32, -0.7] {
            let lamp = cam + axis * 1.5 + left * (side - 0.3) - Vec3::Z * 0.7;
            self.lights.heads.push((lamp, axis));
        }
        nearest(&frame.head_lamps, |h| h.0, cam, 70.0, 6, &mut self.nearby);
        self.lights
            .heads
            .extend(self.nearby.iter().map(|&(_, i)| frame.head_lamps[i as usize]));
    }

    /// Resolves the visibility buffer into the images, in bands of rows on the current rayon pool (each pixel
    /// is a pure function of the buffers, so the bytes do not depend on how the bands are spread).
    fn resolve(&self, scene: &StaticScene, frame: &FrameScene, pose: &CameraPose, cam: Vec3, out: &mut CameraImages) {
        let w = self.camera.width_px as usize;
        let rows = BAND_ROWS;
        out.rgb
            .par_chunks_mut(w * 3 * rows)
            .zip(out.depth_m.par_chunks_mut(w * rows))
            .zip(out.semantic.par_chunks_mut(w * rows))
            .zip(out.instance.par_chunks_mut(w * rows))
            .enumerate()
            .for_each(|(band, (((rgb, depth_m), semantic), instance))| {
                let band = Band {
                    y0: band * rows,
                    rgb,
                    depth_m,
                    semantic,
                    instance,
                };
                self.resolve_band(scene, frame, pose, cam, band);
            });
    }

    fn resolve_band(&self, scene: &StaticScene, frame: &FrameScene, pose: &CameraPose, cam: Vec3, out: Band) {
        let c = &self.camera;
        let w = c.width_px as usize;
        let y0 = out.y0;
        let h = out.depth_m.len() / w;
        let ctx = ShadeContext {
            scene,
            frame,
            light: &self.light,
            noise: &self.noise,
            lights: &self.lights,
        };
        let view = View {
            cam,
            right: pose.right.as_vec3(),
            down: pose.down.as_vec3(),
            fwd: pose.forward.as_vec3(),
            cx: c.width_px as f32 * 0.5,
            cy: c.height_px as f32 * 0.5,
            inv_f: 1.0 / c.focal_px as f32,
        };
        let inv_ss = 1.0 / SS as f32;
        let mut taken = self.band_buffers.0.lock().map_or(None, |mut b| b.pop());
        let BandScratch {
            vis,
            edges,
            groups,
            edge_colour,
            edge_tag,
            rgb,
        } = taken.get_or_insert_with(|| BandScratch::new(w));
        vis.draw(&self.tris, &self.bins[y0 / BAND_ROWS], y0, h, c.height_px as usize);
        // The edge pixels' samples, listed and shaded up to `LANES` of one primitive at a time (over the band, so
        // that the lanes fill).
        edges.clear();
        for row in 0..h {
            let y = y0 + row;
            for e in vis.edge_rows[row]..vis.edge_rows[row + 1] {
                let x = vis.edge_x[e] as usize;
                if vis.prim[row * w + x] != EDGE {
                    continue;
                }
                for (i, (prim, key)) in vis.edge_prim[e].into_iter().zip(vis.edge_key[e]).enumerate() {
                    let (sx, sy) = ((i % SS) as f32, (i / SS) as f32);
                    edges.push(Sample {
                        prim,
                        key,
                        u: x as f32 + (sx + 0.5) * inv_ss,
                        v: y as f32 + (sy + 0.5) * inv_ss,
                    });
                }
            }
        }
        groups.group(edges.iter().map(|s| s.prim));
        edge_colour.resize(edges.len(), Vec3::ZERO);
        edge_tag.resize(edges.len(), 0);
        for group in groups.groups() {
            for chunk in group.chunks(LANES) {
                let at = |i: usize| &edges[chunk[i.min(chunk.len() - 1)] as usize];
                let lane = |f: fn(&Sample) -> f32| lanes_from(|i| f(at(i)));
                let (colour, tags) = self.shade(&ctx, &view, at(0).prim, lane(|s| s.key), lane(|s| s.u), lane(|s| s.v));
                for (&o, (c, t)) in chunk.iter().zip(colour.lanes().into_iter().zip(tags)) {
                    edge_colour[o as usize] = c;
                    edge_tag[o as usize] = t;
                }
            }
        }
        // The edge pixels' samples in `edge_colour`, in (row, column) order.
        let mut e = 0;
        for row in 0..h {
            let y = y0 + row;
            let v_centre = F::splat(y as f32 + 0.5);
            let labels = row * w..(row + 1) * w;
            let (grid_prim, grid_key) = (&vis.grid.prim[labels.clone()], &vis.grid.key[labels.clone()]);
            // Labels: the first sample's depth (the sky's key 0 gives the far plane) and instance.
            depth_labels(grid_key, &mut out.depth_m[labels.clone()]);
            let mut last = (EMPTY, 0u16);
            for (i, &p) in out.instance[labels.clone()].iter_mut().zip(grid_prim) {
                if p != last.0 {
                    last = (p, if p == EMPTY { 0 } else { frame.prim(scene, p).instance });
                }
                *i = last.1;
            }
            let row_prim = &vis.prim[labels.clone()];
            let row_key = &vis.key[labels.clone()];
            // Pixels whose samples see one primitive: shaded at their centres, up to `LANES` neighbours of one
            // primitive at a time.
            let semantic = &mut out.semantic[labels];
            let mut x = 0;
            while x < w {
                let prim = row_prim[x];
                if prim == EDGE {
                    x += 1;
                    continue;
                }
                let mut end = x + 1;
                while end < w && end - x < LANES && row_prim[end] == prim {
                    end += 1;
                }
                let n = end - x;
                let key = lanes_from(|i| row_key[x + i.min(n - 1)]);
                let u = F::splat(x as f32 + 0.5) + lanes_from(|i| i as f32);
                let (colour, tags) = self.shade(&ctx, &view, prim, key, u, v_centre);
                // All lanes are stored: those past `n` are overwritten by the pixels they fall on.
                for (channel, lanes) in rgb.iter_mut().zip([colour.x, colour.y, colour.z]) {
                    channel[x..x + LANES].copy_from_slice(&lanes.to_array());
                }
                match semantic.get_mut(x..x + LANES) {
                    Some(all) => all.copy_from_slice(&tags),
                    None => semantic[x..end].copy_from_slice(&tags[..n]),
                }
                x = end;
            }
            // Edge pixels (candidates whose samples differ): the mean of their samples' colours, the first
            // sample's tag.
            let candidates = &vis.edge_x[vis.edge_rows[row]..vis.edge_rows[row + 1]];
            for x in candidates.iter().map(|&x| x as usize).filter(|&x| row_prim[x] == EDGE) {
                let c = &edge_colour[e..e + 4];
                let colour = (c[0] + c[1] + c[2] + c[3]) * 0.25;
                for (channel, v) in rgb.iter_mut().zip(colour.to_array()) {
                    channel[x] = v;
                }
                semantic[x] = edge_tag[e];
                e += 4;
            }
            tone_map(rgb, &self.lut, &mut out.rgb[row * w * 3..(row + 1) * w * 3]);
        }
        self.draw_streaks(y0, out.rgb);
        if let (Ok(mut pool), Some(scratch)) = (self.band_buffers.0.lock(), taken) {
            pool.push(scratch);
        }
    }

    /// The fogged colours and the semantic tags of `LANES` samples of one primitive (or of the sky) at pixel
    /// coordinates `(u, v)` with depth keys `key`.
    #[inline(always)]
    fn shade(&self, ctx: &ShadeContext, view: &View, prim: u32, key: F, u: F, v: F) -> (V3, [u8; LANES]) {
        let su = (u - view.cx) * view.inv_f;
        let sv = (v - view.cy) * view.inv_f;
        let ray = V3::splat(view.fwd) + V3::splat(view.right).scale(su) + V3::splat(view.down).scale(sv);
        if prim == EMPTY {
            let dir = ray.scale(F::ONE / ray.length_squared().sqrt());
            let sky = self.light.sky(dir);
            return (shade::fog(&self.light, sky, F::splat(1.0e4)), [tag::SKY; LANES]);
        }
        let prim: &Prim = ctx.frame.prim(ctx.scene, prim);
        let z = F::ONE / key;
        let p = V3::splat(view.cam) + ray.scale(z);
        let ray_len = ray.length_squared().sqrt();
        // A flat surface turned away from the sun gets none of it whether in shadow or not (bodies shade
        // with per-point normals).
        let away =
            prim.normal.dot(self.light.sun_dir) <= 0.0 && !matches!(prim.material, Material::Body | Material::Head);
        let shadow = match &self.sun {
            Some(sun) if !away => sun.sunlit(&self.shadow.key, p, prim.normal),
            _ => F::ONE,
        };
        let pts = shade::Points {
            p,
            ray,
            ray_len,
            shadow,
        };
        let (colour, semantic) = shade::surface(ctx, prim, &pts);
        (shade::fog(&self.light, colour, ray_len * z), semantic)
    }

    /// Rain: thin, slanted, semi-transparent streaks at seeded places (none without rain), listed per band of
    /// rows they reach; [`Renderer::draw_streaks`] draws them.
    fn place_streaks(&mut self, seed: u64) {
        self.streaks.clear();
        for bin in &mut self.streak_bins {
            bin.clear();
        }
        if self.light.rain <= 0.0 {
            return;
        }
        let (w, h) = (self.camera.width_px as f32, self.camera.height_px as f32);
        let mut rng = ChaCha8Rng::seed_from_u64(splitmix64(seed ^ 0x7a1f));
        let count = (self.light.rain * 1500.0 * (w * h) / (1280.0 * 720.0)) as usize;
        let last_bin = self.streak_bins.len() - 1;
        for i in 0..count {
            let x0: f32 = rng.random_range(-50.0..w + 50.0);
            let y0: f32 = rng.random_range(-50.0..h);
            let len: f32 = rng.random_range(0.02..0.07) * h;
            let alpha: f32 = rng.random_range(0.12..0.3);
            let streak = Streak {
                x0,
                y0,
                steps: len as usize,
                alpha,
            };
            self.streaks.push(streak);
            // Rows `y0 + k` for `k < steps`, one row of margin each side (the bands' own test is exact).
            let first = (y0 - 1.0).max(0.0) as usize / BAND_ROWS;
            let last = ((y0 + streak.steps as f32 + 1.0).max(0.0) as usize / BAND_ROWS).min(last_bin);
            for bin in &mut self.streak_bins[first.min(last_bin)..=last] {
                bin.push(i as u32);
            }
        }
    }

    /// Draws the rain streaks over the rows `y0..y0 + rgb.len() / (3 w)` (`rgb`: those rows of the image), in
    /// the streaks' order, brighter against dark backgrounds: each pixel sees the same blends in the same order
    /// as a pass over the whole image.
    fn draw_streaks(&self, y0: usize, rgb: &mut [u8]) {
        let width = self.camera.width_px as usize;
        let (w, h) = (width as f32, self.camera.height_px as f32);
        let rows = y0..y0 + rgb.len() / (3 * width);
        let slant = 0.08 + 0.35 * self.light.wind;
        let bright = 150.0 + 60.0 * (1.0 - self.light.night);
        for &i in &self.streak_bins[y0 / BAND_ROWS] {
            let s = self.streaks[i as usize];
            // The steps that can land in the band (a row of margin each side; the test below is exact).
            let k0 = (rows.start as f32 - s.y0 - 1.0).max(0.0) as usize;
            let k1 = ((rows.end as f32 - s.y0 + 1.0).max(0.0) as usize).min(s.steps);
            for k in k0..k1 {
                let t = k as f32;
                let (x, y) = (s.x0 + t * slant, s.y0 + t);
                if y < 0.0 || y >= h || x < 0.0 || x >= w - 1.0 {
                    continue;
                }
                let row = y as usize;
                if !rows.contains(&row) {
                    continue;
                }
                let xf = shade::floor_f32(x);
                let (xi, fx) = (xf as usize, x - xf);
                let base = (row - rows.start) * width;
                for (dx, cov) in [(0usize, 1.0 - fx), (1, fx)] {
                    let o = (base + xi + dx) * 3;
                    let a = s.alpha * cov;
                    for ch in &mut rgb[o..o + 3] {
                        *ch = (f32::from(*ch) * (1.0 - a) + bright * a) as u8;
                    }
                }
            }
        }
    }
}

/// A row's depth labels from its pixels' first samples' keys: `1 / key` metres (the sky's key 0 gives the far
/// plane). Four pixels at a time: an IEEE division per lane, the same values as one at a time.
fn depth_labels(keys: &[f32], depth_m: &mut [f32]) {
    for (d, k) in depth_m.chunks_mut(4).zip(keys.chunks(4)) {
        let first = f32x4::new(std::array::from_fn(|i| k.get(i).copied().unwrap_or(1.0)));
        let depth = (f32x4::ONE / first).min(f32x4::splat(SKY_DEPTH_M)).to_array();
        // A fixed-size copy where the chunk is whole (a slice copy of unknown length calls memcpy).
        match <&mut [f32; 4]>::try_from(&mut *d) {
            Ok(d) => *d = depth,
            Err(_) => d.copy_from_slice(&depth[..d.len()]),
        }
    }
}

/// Maps a row of linear colours (one slice per channel, at least as long as the row) to interleaved sRGB
/// bytes through the lookup table: `LUT[sqrt(x / LUT_MAX) × (LUT_LEN − 1)]`, four pixels at a time (`wide`:
/// SSE square roots, correctly rounded, and truncations, so the same values as one at a time).
fn tone_map(rgb: &[Vec<f32>; 3], lut: &[u8; LUT_LEN], out: &mut [u8]) {
    #[inline(always)]
    fn index(v: f32x4) -> [usize; 4] {
        let s = (v.max(f32x4::ZERO) * (1.0 / LUT_MAX)).min(f32x4::ONE).sqrt();
        // `s ≤ 1`: the mask changes no index and lets the compiler drop the bounds check.
        let i = (s * (LUT_LEN - 1) as f32).fast_trunc_int().to_array();
        let m = LUT_LEN - 1;
        // Spelled out: `array::map` is not always inlined here.
        [
            i[0] as usize & m,
            i[1] as usize & m,
            i[2] as usize & m,
            i[3] as usize & m,
        ]
    }
    let w = out.len() / 3;
    let [r, g, b] = rgb.each_ref().map(|c| &c[..w.div_ceil(4) * 4]);
    for (((px, r), g), b) in out
        .chunks_mut(12)
        .zip(r.chunks_exact(4))
        .zip(g.chunks_exact(4))
        .zip(b.chunks_exact(4))
    {
        let load = |c: &[f32]| index(f32x4::new([c[0], c[1], c[2], c[3]]));
        let (r, g, b) = (load(r), load(g), load(b));
        for (i, o) in px.chunks_exact_mut(3).enumerate() {
            o.copy_from_slice(&[lut[r[i]], lut[g[i]], lut[b[i]]]);
        }
    }
}

/// The luminance of an 8-bit sRGB pixel (the DVS's intensity, 0–255).
pub fn luminance(rgb: &[u8]) -> f32 {
    0.2989 * f32::from(rgb[0]) + 0.587 * f32::from(rgb[1]) + 0.114 * f32::from(rgb[2])
}

/// A random generator for a (clip, frame, sub-step) stream.
pub fn streak_seed(clip_seed: u64, frame: u32, substep: u32) -> u64 {
    splitmix64(clip_seed ^ splitmix64((u64::from(frame) << 16) | u64::from(substep)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_labels_equal_the_per_pixel_formula_for_every_row_length() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for w in 0..=13usize {
            // Keys of the sky (0), of near and of far surfaces.
            let keys: Vec<f32> = (0..w)
                .map(|i| match i % 3 {
                    0 => 0.0,
                    1 => rng.random_range(0.001..20.0),
                    _ => rng.random_range(1.0e-5..0.001),
                })
                .collect();
            let mut got = vec![-1.0f32; w];
            depth_labels(&keys, &mut got);
            let expected: Vec<u32> = (0..w).map(|x| (1.0 / keys[x]).min(SKY_DEPTH_M).to_bits()).collect();
            assert_eq!(got.iter().map(|d| d.to_bits()).collect::<Vec<_>>(), expected, "w {w}");
        }
    }

    #[test]
    fn the_row_tone_map_equals_the_per_value_formula() {
        let lut = build_lut();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        // Every row length up to 13 (whole quads and a rest), values below 0, in range and beyond LUT_MAX.
        for n in 0..=13 {
            let mut value = |i: usize| match i % 4 {
                0 => rng.random_range(-1.0..0.0),
                1 => rng.random_range(0.0..0.01),
                2 => rng.random_range(0.0..LUT_MAX),
                _ => rng.random_range(LUT_MAX..20.0),
            };
            let rgb: [Vec<f32>; 3] = std::array::from_fn(|c| (0..n + 3).map(|i| value(i + c)).collect());
            let mut out = vec![0u8; n * 3];
            tone_map(&rgb, &lut, &mut out);
            let expected: Vec<u8> = (0..n * 3)
                .map(|i| {
                    let v: f32 = rgb[i % 3][i / 3];
                    let s = (v.max(0.0) * (1.0 / LUT_MAX)).min(1.0).sqrt();
                    lut[(s * (LUT_LEN - 1) as f32) as usize]
                })
                .collect();
            assert_eq!(out, expected, "{rgb:?}");
        }
    }
}
