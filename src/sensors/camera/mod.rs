//! The camera streams, rendered on the CPU: RGB, depth, semantic and instance segmentation from one
//! rasterisation of the scene, and DVS events from the rendered luminance.
//!
//! The frame's stages, in order: [`projection`] (triangles to the optical frame, binned by bands),
//! [`shadows`] (the sun's shadow map, the lights that matter), [`resolve`] (per band: labels and shading)
//! and [`post`] (tone map, rain streaks). Their building blocks:
//!
//! - [`raster`] — the visibility buffers (nearest primitive and depth per sample).
//! - [`cull`] — the lights each tile of a band can see.
//! - [`group`] — grouping of edge samples by primitive for shading.
//! - [`lanes`] — lane math for shading several pixels at once.
//! - [`light`] — lighting from the weather.
//! - [`shade`] — textures, road paint, lights, reflections, fog.
//! - [`dvs`] — the ESIM event simulator.
//! - [`expose`] — the sensor: auto-exposure's meter and gain, vignetting, noise.
//!
//! A camera with lens distortion draws its frame on a pinhole canvas and resamples it through the lens
//! ([`lens`]).
//!
//! A frame is drawn at `SS × SS` samples per pixel, in bands of rows, with the same
//! [`CameraPose`](crate::sim::rig::CameraPose) (intrinsics and pose) that the annotations project
//! with: every pixel's first sample, and all four where the first samples of the pixel and of its right,
//! lower and diagonal neighbours differ ([`band::BandVisibility`]). Label streams are point samples (the
//! pixel's first sample, at `(u + 0.25, v + 0.25)`; road paint's semantic label at the pixel centre when all
//! samples see one primitive, where the colour is shaded); RGB shades a pixel once where its samples see one
//! primitive and each sample where they differ (edge antialiasing), then adds rain streaks and maps to sRGB.

pub mod band;
mod cull;
pub mod dvs;
pub mod expose;
mod figure;
pub mod group;
pub mod lanes;
mod lens;
pub mod light;
mod post;
mod projection;
pub mod raster;
mod resolve;
pub mod round;
pub mod shade;
mod shadows;

use glam::{DAffine3, DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::sync::Mutex;

use super::scene::{FrameScene, Material, Prim, StaticScene, tag};
use crate::sim::rig::{Camera, CameraPose};
use crate::util::mix::splitmix64;
use band::{BandVisibility, EDGE};
use group::Grouper;
use lanes::{F, LANES, V3, lanes_from};
use light::Lighting;
use post::*;
use raster::{EMPTY, Raster, Setup, clip_near};
use resolve::*;
use round::floor_int;
use shade::{ActiveLights, Noise, ShadeContext};
use shadows::*;

/// Samples per pixel along each axis.
pub const SS: usize = 2;
/// Near clipping distance, metres.
pub const NEAR_M: f32 = 0.05;
/// Static clusters farther than this are not drawn (fog and the terrain plane take over), metres.
const FAR_M: f32 = 450.0;
/// The [`Lighting::night`] from which street lamps and headlights light the scene (from a sun about 4.6° above
/// the horizon down; a car's lamps themselves glow whenever it is not full day). At dawn's 5° (0.03) lamps at 3 %
/// of their night intensity changed 0.2 % of a frame's pixels by 3–7 levels and the rest by at most 2 (PSNR
/// 54.7 dB), and cost a fifth of the frame. Headlights at 3 % changed 5 % of `tests/data/specs/weathers.yaml`'s
/// dawn frame by 3–10 levels (the road ahead and the car on it) and, through the exposure, most of the rest by
/// 1–2 (PSNR 47.0 dB), where daylight at a 5° sun outshines low beams about a hundredfold; they cost 4 % of
/// the frame.
const LIGHTS_ON_NIGHT: f32 = 0.05;
/// Depth written for sky pixels, metres (CARLA's far plane).
pub const SKY_DEPTH_M: f32 = 1000.0;
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
    /// The sky's colour where fog hides it ([`Lighting::sky_hidden_by_fog`]): no need to work it out.
    fogged_sky: Option<Vec3>,
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
    /// The tone curve per channel (red, green, blue), the exposure's gain and the colour balance in it.
    luts: [Box<[u8; LUT_LEN]>; 3],
    /// The frame's rain streaks, in drawing order, and per band of rows the ones that reach it (drawn while
    /// the band is in cache: a whole-image pass misses the cache at every streak pixel).
    streaks: Vec<Streak>,
    streak_bins: Vec<Vec<u32>>,
    /// A distorting camera's canvas and resampling (`None` for a pinhole: the frame is drawn in place).
    warp: Option<Box<lens::LensWarp>>,
    /// The exposure's gain on the linear light (in `luts`).
    gain: f32,
    /// The colour balance: a gain per channel on the linear light (in `luts`).
    white_balance: [f32; 3],
    /// Vignetting of the canvas (`None` without).
    vignette: Option<expose::Vignette>,
    /// Sensor noise (`None` without), added by [`Renderer::add_noise`].
    noise_model: Option<expose::NoiseModel>,
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

impl Renderer {
    /// A renderer for a camera, a clip's lighting and its texture seed, at a gain of 1 (see
    /// [`Renderer::set_gain`]).
    pub fn new(camera: &Camera, light: Lighting, seed: u64) -> Renderer {
        let warp = lens::LensWarp::new(camera).map(Box::new);
        let (image_w, image_h) = (camera.width_px, camera.height_px);
        let imaging = camera.imaging;
        // The stages draw with the pinhole of the canvas where the camera distorts.
        let camera = warp.as_ref().map_or(*camera, |w| w.canvas_camera);
        let h = camera.height_px as usize;
        let vignette = expose::Vignette::new(imaging.vignetting, camera.width_px, camera.height_px, image_w, image_h);
        let noise_model = imaging
            .noisy()
            .then(|| expose::NoiseModel::new(imaging.shot_noise, imaging.read_noise, seed));
        Renderer {
            camera,
            fogged_sky: light.sky_hidden_by_fog(),
            light,
            noise: Noise::new(seed ^ 0x7e57_0000),
            tris: Vec::new(),
            bins: vec![Vec::new(); h.div_ceil(BAND_ROWS)],
            band_buffers: BandBuffers::default(),
            shadow: Raster::depth_only(SHADOW_PX, SHADOW_PX),
            sun: None,
            lights: ActiveLights::default(),
            nearby: Vec::new(),
            luts: [build_lut(1.0), build_lut(1.0), build_lut(1.0)],
            streaks: Vec::new(),
            streak_bins: vec![Vec::new(); h.div_ceil(BAND_ROWS)],
            warp,
            gain: 1.0,
            white_balance: [1.0; 3],
            vignette,
            noise_model,
        }
    }

    /// Sets the exposure's gain on the linear light (auto-exposure's, [`expose::auto_gain`]): the tone curve's
    /// lookup table and the noise's spread follow it.
    pub fn set_gain(&mut self, gain: f32) {
        self.gain = gain;
        self.luts = self.white_balance.map(|wb| build_lut(gain * wb));
        if let Some(noise) = &mut self.noise_model {
            noise.set_gain(gain);
        }
    }

    /// Sets the colour balance: a gain per channel (red, green, blue) on the linear light, on top of the
    /// exposure's (domain randomisation's `white_balance`).
    pub fn set_white_balance(&mut self, white_balance: [f32; 3]) {
        self.white_balance = white_balance;
        self.set_gain(self.gain);
    }

    /// The exposure's gain on the linear light.
    pub fn gain(&self) -> f32 {
        self.gain
    }

    /// Adds the sensor's noise (if any) to a rendered RGB image; `frame_seed` draws it
    /// ([`noise_seed`]). The label streams are left exact.
    pub fn add_noise(&self, images: &mut CameraImages, frame_seed: u64) {
        if let Some(noise) = &self.noise_model {
            noise.apply(&mut images.rgb, images.width, frame_seed);
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
        if let Some(mut warp) = self.warp.take() {
            self.draw(scene, frame, pose, streak_seed, &mut warp.canvas);
            size_images(out, pose.camera.width_px as usize, pose.camera.height_px as usize);
            warp.apply(out);
            self.warp = Some(warp);
        } else {
            self.draw(scene, frame, pose, streak_seed, out);
        }
    }

    /// Draws one frame with the renderer's pinhole (the camera's, or a distorting camera's canvas) into `out`.
    fn draw(
        &mut self,
        scene: &StaticScene,
        frame: &FrameScene,
        pose: &CameraPose,
        streak_seed: u64,
        out: &mut CameraImages,
    ) {
        size_images(out, self.camera.width_px as usize, self.camera.height_px as usize);
        let optical_from_scene = pose.optical_from_world * DAffine3::from_translation(scene.origin);
        self.draw_visibility(scene, frame, &optical_from_scene);
        let cam_rel = (pose.centre - scene.origin).as_vec3();
        self.draw_shadows(scene, frame, cam_rel, pose.forward.as_vec3());
        self.choose_lights(scene, frame, cam_rel, pose);
        self.place_streaks(streak_seed);
        self.resolve(scene, frame, pose, cam_rel, out);
    }
}

/// Sizes the images of `out` to `w × h` pixels.
fn size_images(out: &mut CameraImages, w: usize, h: usize) {
    out.width = w;
    out.height = h;
    out.rgb.resize(w * h * 3, 0);
    out.depth_m.resize(w * h, 0.0);
    out.semantic.resize(w * h, 0);
    out.instance.resize(w * h, 0);
}

/// The luminance of an 8-bit sRGB pixel (the DVS's intensity, 0–255).
pub fn luminance(rgb: &[u8]) -> f32 {
    0.2989 * f32::from(rgb[0]) + 0.587 * f32::from(rgb[1]) + 0.114 * f32::from(rgb[2])
}

/// The seed of a frame's sensor noise.
pub fn noise_seed(clip_seed: u64, frame: u32) -> u64 {
    splitmix64(clip_seed ^ 0x5e45_0e00 ^ splitmix64(u64::from(frame)))
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
    fn instance_labels_equal_the_per_pixel_lookup_for_every_row_length() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for w in 0..=40usize {
            // Runs of primitives (the sky's among them) of one to twenty pixels.
            let mut prims = Vec::new();
            while prims.len() < w {
                let p = [EMPTY, 3, 7, 12][rng.random_range(0..4usize)];
                prims.extend(std::iter::repeat_n(p, rng.random_range(1..=20usize)));
            }
            prims.truncate(w);
            let instance_of = |p: u32| p as u16 * 10 + 1;
            let mut got = vec![u16::MAX; w];
            resolve::instance_labels(&prims, &mut got, instance_of);
            let expected: Vec<u16> = prims
                .iter()
                .map(|&p| if p == EMPTY { 0 } else { instance_of(p) })
                .collect();
            assert_eq!(got, expected, "w {w}");
        }
    }

    #[test]
    fn the_row_tone_map_equals_the_per_value_formula() {
        let lut = build_lut(1.0);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        // Every row length up to 20 (whole vectors and a rest), values below 0, in range and beyond LUT_MAX.
        for n in 0..=20 {
            let mut value = |i: usize| match i % 4 {
                0 => rng.random_range(-1.0..0.0),
                1 => rng.random_range(0.0..0.01),
                2 => rng.random_range(0.0..LUT_MAX),
                _ => rng.random_range(LUT_MAX..20.0),
            };
            let rgb: [Vec<f32>; 3] = std::array::from_fn(|c| (0..n + LANES - 1).map(|i| value(i + c)).collect());
            let mut out = vec![0u8; n * 3];
            tone_map(&rgb, [&lut, &lut, &lut], &mut out);
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
