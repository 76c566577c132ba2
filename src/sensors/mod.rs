//! Observation of a simulated clip: pure functions of (script, trace, frame), no IO.
//!
//! - [`body`] — the articulated pedestrian body (COCO-17 joints, capsule silhouette).
//! - [`cyclist`] — a cyclist's rider (riding pose, same joints) and bicycle.
//! - [`keypoints`] — keypoint formats (COCO-17, OpenPose-18).
//! - [`annotate`] — visibility gate, boxes, keypoints, occlusion and crossing labels.
//! - [`scene`] — the renderable geometry of a frame (one source for cameras and LiDAR).
//! - [`camera`] — RGB, depth, semantic, instance and DVS, rendered on the CPU.
//! - [`lidar`] — CARLA's ray-cast (and semantic) LiDAR, traced against the same scene.
//!
//! Sensor streams are too large to hold for a whole clip, so [`render_cameras`] and [`scan_lidar`] hand each
//! frame to a sink (the writer) as soon as it is produced; the sink does the IO, this module none.

pub mod annotate;
pub mod annotator;
pub mod body;
pub mod camera;
pub mod cyclist;
pub mod keypoints;
pub mod lidar;
mod occlusion;
pub mod realise;
pub mod scene;

use glam::{DAffine3, DVec3};

use crate::plan::ClipScript;
use crate::sim::rig::Rig;
use crate::sim::trace::ClipTrace;
use crate::spec::Spec;
use crate::spec::types::{Lidar, Sensors};
use crate::world::RoadNetwork;
use annotate::ClipAnnotations;

/// Everything observed of one clip.
#[derive(Clone, Debug, PartialEq)]
pub struct Observations {
    /// The annotation of every pedestrian-frame (and the rejections of the visibility gate).
    pub annotations: ClipAnnotations,
}

/// Observes a simulated clip with the rig.
pub fn observe(script: &ClipScript, trace: &ClipTrace, spec: &Spec, rig: &Rig, town: &RoadNetwork) -> Observations {
    Observations {
        annotations: annotate::annotate(script, trace, &spec.annotations, &rig.camera, town),
    }
}

/// One rendered frame of the camera streams, as handed to the sink.
#[derive(Debug)]
pub struct SensorFrame<'a> {
    /// Frame index.
    pub frame: u32,
    /// Simulated time of the frame, nanoseconds.
    pub timestamp_ns: i64,
    /// The frame's images.
    pub images: &'a camera::CameraImages,
    /// DVS events in (previous frame, this frame], sorted by time (empty without DVS).
    pub events: &'a [camera::dvs::Event],
}

/// The simulated time of frame `frame` plus `k / substeps` of a frame, nanoseconds.
pub fn frame_time_ns(frame: u32, fps: u32, k: u32, substeps: u32) -> i64 {
    let ns = i128::from(frame) * 1_000_000_000 * i128::from(substeps) + i128::from(k) * 1_000_000_000;
    (ns / (i128::from(fps.max(1)) * i128::from(substeps.max(1)))) as i64
}

/// Renders the camera streams of a clip frame by frame and hands each frame to `sink` (in frame order).
/// Every image is a pure function of (script, trace, frame); `stat` is the clip's static scene
/// ([`scene::StaticScene::build`]).
pub fn render_cameras<E>(
    stat: &scene::StaticScene,
    script: &ClipScript,
    trace: &ClipTrace,
    sensors: &Sensors,
    rig: &Rig,
    mut sink: impl FnMut(SensorFrame) -> Result<(), E>,
) -> Result<(), E> {
    let mut renderer = clip_renderer(stat, script, trace, rig);
    let mut frame_scene = scene::FrameScene::default();
    let mut images = camera::CameraImages::default();
    let mut shutter = Shutter::new(&rig.camera.imaging, renderer.gain(), script.fps);
    let (w, h) = (rig.camera.width_px as usize, rig.camera.height_px as usize);
    let mut esim = sensors.dvs.enabled.then(|| camera::dvs::Esim::new(&sensors.dvs, w, h));
    let substeps = sensors.dvs.substeps.max(1);
    let mut events = Vec::new();
    let frames = trace.frame_count.min(trace.ego.len() as u32);
    let clip = ClipView {
        stat,
        script,
        trace,
        rig,
    };
    for frame in 0..frames {
        events.clear();
        if let Some(esim) = esim.as_mut()
            && frame > 0
        {
            for k in 1..substeps {
                let t = scene::SceneTime {
                    frame: frame - 1,
                    alpha: f64::from(k) / f64::from(substeps),
                };
                let streaks = camera::streak_seed(script.seed, t.frame, k);
                clip.render(&mut renderer, &mut frame_scene, t, streaks, &mut images);
                let now = frame_time_ns(frame - 1, script.fps, k, substeps);
                esim.step(
                    &images.rgb,
                    now,
                    camera::streak_seed(script.seed ^ 0xd75, frame - 1, k),
                    &mut events,
                );
            }
        }
        clip.render_exposed(&mut renderer, &mut frame_scene, frame, &mut shutter, &mut images);
        let now = frame_time_ns(frame, script.fps, 0, 1);
        if let Some(esim) = esim.as_mut() {
            esim.step(
                &images.rgb,
                now,
                camera::streak_seed(script.seed ^ 0xd75, frame, 0),
                &mut events,
            );
        }
        // The DVS saw the frame's instant; the RGB stream gets the open shutter's blur and the sensor's noise.
        shutter.blend(&mut images.rgb);
        renderer.add_noise(&mut images, camera::noise_seed(script.seed, frame));
        sink(SensorFrame {
            frame,
            timestamp_ns: now,
            images: &images,
            events: &events,
        })?;
    }
    Ok(())
}

/// One LiDAR tick, as handed to the sink.
#[derive(Debug)]
pub struct LidarFrame<'a> {
    /// Frame index (one tick per frame).
    pub frame: u32,
    /// Simulated time of the frame, nanoseconds.
    pub timestamp_ns: i64,
    /// The kept returns, in CARLA's sensor frame (x forward, y right, z up).
    pub points: &'a [lidar::LidarPoint],
    /// What the tick did (rays, drop-off).
    pub stats: lidar::TickStats,
}

/// The scene-relative `f32` pose of a world pose (the scene's coordinates are relative to its origin).
pub fn scene_from(stat: &scene::StaticScene, world_from_sensor: &DAffine3) -> glam::Affine3A {
    let mut rel = *world_from_sensor;
    rel.translation -= stat.origin;
    glam::Affine3A::from_mat3_translation(rel.matrix3.as_mat3(), rel.translation.as_vec3())
}

/// Scans a clip with the LiDAR tick by tick (one tick per frame) and hands each tick to `sink` (in frame
/// order). Every point is a pure function of (script, trace, frame).
pub fn scan_lidar<E>(
    stat: &scene::StaticScene,
    script: &ClipScript,
    trace: &ClipTrace,
    spec: &Lidar,
    rig: &Rig,
    mut sink: impl FnMut(LidarFrame) -> Result<(), E>,
) -> Result<(), E> {
    let mut tracer = lidar::Tracer::new(stat);
    let mut frame_scene = scene::FrameScene::default();
    let mut scratch = lidar::ScanScratch::default();
    let mut points = Vec::new();
    let frames = trace.frame_count.min(trace.ego.len() as u32);
    for frame in 0..frames {
        let t = scene::SceneTime::at(frame);
        frame_scene.build(stat, script, trace, t);
        let (pos, yaw, pitch) = scene::ego_at(trace, t);
        let pose = scene_from(stat, &rig.world_from_lidar(pos, yaw, pitch));
        tracer.set_agents(&frame_scene, &pose);
        points.clear();
        let stats = lidar::scan(
            spec,
            script.fps,
            frame,
            script.seed,
            &pose,
            &tracer,
            |id| frame_scene.prim(stat, id),
            &mut scratch,
            &mut points,
        );
        sink(LidarFrame {
            frame,
            timestamp_ns: frame_time_ns(frame, script.fps, 0, 1),
            points: &points,
            stats,
        })?;
    }
    Ok(())
}

/// The world pose of each sensor at a frame: the camera (whose image the annotations are in) and the LiDAR,
/// each as `world_from_sensor` with sensor axes x forward, y left, z up.
pub fn sensor_poses(trace: &ClipTrace, rig: &Rig, frame: u32) -> [(&'static str, DAffine3); 2] {
    let (pos, yaw, pitch): (DVec3, f64, f64) = scene::ego_at(trace, scene::SceneTime::at(frame));
    [
        ("camera", rig.camera.world_from_sensor(pos, yaw, pitch)),
        ("lidar", rig.world_from_lidar(pos, yaw, pitch)),
    ]
}

/// Renders one frame of a clip (no DVS): for previews, tests and benchmarks.
pub fn render_frame(
    script: &ClipScript,
    trace: &ClipTrace,
    rig: &Rig,
    town: &RoadNetwork,
    frame: u32,
) -> camera::CameraImages {
    let scenery = scene::ClipScenery::new(script, trace, town);
    let stat = scene::StaticScene::build(script, trace, town, &scenery);
    let mut renderer = clip_renderer(&stat, script, trace, rig);
    let mut images = camera::CameraImages::default();
    let mut shutter = Shutter::new(&rig.camera.imaging, renderer.gain(), script.fps);
    let clip = ClipView {
        stat: &stat,
        script,
        trace,
        rig,
    };
    clip.render_exposed(
        &mut renderer,
        &mut scene::FrameScene::default(),
        frame,
        &mut shutter,
        &mut images,
    );
    shutter.blend(&mut images.rgb);
    renderer.add_noise(&mut images, camera::noise_seed(script.seed, frame));
    images
}

/// What rendering a clip's frames needs: its static scene, script, trace and rig.
struct ClipView<'a> {
    stat: &'a scene::StaticScene,
    script: &'a ClipScript,
    trace: &'a ClipTrace,
    rig: &'a Rig,
}

impl ClipView<'_> {
    /// Renders the clip at time `t` with the rain streaks of `streak_seed` ([`camera::streak_seed`]) into
    /// `images`, building the frame's scene in `frame_scene`.
    fn render(
        &self,
        renderer: &mut camera::Renderer,
        frame_scene: &mut scene::FrameScene,
        t: scene::SceneTime,
        streak_seed: u64,
        images: &mut camera::CameraImages,
    ) {
        frame_scene.build(self.stat, self.script, self.trace, t);
        let (pos, yaw, pitch) = scene::ego_at(self.trace, t);
        renderer.render(
            self.stat,
            frame_scene,
            &self.rig.camera.at(pos, yaw, pitch),
            streak_seed,
            images,
        );
    }

    /// Renders frame `frame` as the camera exposes it: with motion blur, first the earlier instants of its open
    /// shutter (summed into `shutter`), then the frame's instant into `images` (whose labels and depth are the
    /// frame's); [`Shutter::blend`] then averages the RGB.
    fn render_exposed(
        &self,
        renderer: &mut camera::Renderer,
        frame_scene: &mut scene::FrameScene,
        frame: u32,
        shutter: &mut Shutter,
        images: &mut camera::CameraImages,
    ) {
        shutter.summed = 0;
        // The rain streaks of the frame's instant in every render (a streak already is the rain's blur).
        let streaks = camera::streak_seed(self.script.seed, frame, 0);
        for k in (1..shutter.samples).rev() {
            // Sample k of the shutter: k/(samples − 1) of the shutter before the frame (clamped to the clip's start).
            let before = shutter.frames * f64::from(k) / f64::from(shutter.samples - 1);
            let t = f64::from(frame) - before;
            let at = if t <= 0.0 {
                scene::SceneTime::at(0)
            } else {
                scene::SceneTime {
                    frame: t.floor() as u32,
                    alpha: t - t.floor(),
                }
            };
            self.render(renderer, frame_scene, at, streaks, images);
            shutter.add(&images.rgb);
        }
        self.render(renderer, frame_scene, scene::SceneTime::at(frame), streaks, images);
    }
}

/// Motion blur's open shutter for a clip: its length in frames, its renders per frame, and the running sum of
/// a frame's earlier renders.
struct Shutter {
    frames: f64,
    samples: u32,
    sum: Vec<u16>,
    summed: u32,
}

impl Shutter {
    /// The shutter of a camera's imaging at an exposure's gain, for a clip at `fps`.
    fn new(imaging: &crate::sim::rig::Imaging, gain: f32, fps: u32) -> Shutter {
        let (shutter_s, samples) = imaging.blur(gain);
        Shutter {
            frames: shutter_s * f64::from(fps.max(1)),
            samples: if shutter_s > 0.0 { samples } else { 1 },
            sum: Vec::new(),
            summed: 0,
        }
    }

    /// Adds an earlier render's RGB to the sum.
    fn add(&mut self, rgb: &[u8]) {
        if self.summed == 0 {
            self.sum.clear();
            self.sum.extend(rgb.iter().map(|&v| u16::from(v)));
        } else {
            for (s, &v) in self.sum.iter_mut().zip(rgb) {
                *s += u16::from(v);
            }
        }
        self.summed += 1;
    }

    /// Replaces the frame's instant in `rgb` by the mean of it and the earlier renders (rounded; nothing without
    /// blur).
    fn blend(&self, rgb: &mut [u8]) {
        if self.summed == 0 {
            return;
        }
        let n = self.summed + 1;
        for (v, &s) in rgb.iter_mut().zip(&self.sum) {
            *v = ((u32::from(s) + u32::from(*v) + n / 2) / n) as u8;
        }
    }
}

/// Frames auto-exposure meters, as shares of the clip.
const METERED_QUARTERS: u64 = 4;

/// The renderer of a clip's camera, exposed for the clip. With auto-exposure (`sensors.rgb.exposure`), four
/// frames at 0, ¼, ½ and ¾ of the clip are rendered at a gain of 1 and metered
/// ([`camera::expose::brightness`]); the clip is rendered at the gain their geometric mean calls for
/// ([`camera::expose::auto_gain`]). The clip's `look` (domain randomisation) scales the light, sets the colour
/// balance and scales the exposure's key. A pure function of (script, trace, rig): every frame stays a pure
/// function of (script, trace, frame).
pub fn clip_renderer(stat: &scene::StaticScene, script: &ClipScript, trace: &ClipTrace, rig: &Rig) -> camera::Renderer {
    let look = &script.look;
    let light =
        camera::light::Lighting::from_weather(&script.weather_params).with_intensity(look.light_intensity as f32);
    let mut renderer = camera::Renderer::new(&rig.camera, light, script.seed);
    if !look.is_identity() {
        renderer.set_white_balance(look.white_balance.map(|g| g as f32));
    }
    let frames = u64::from(trace.frame_count.min(trace.ego.len() as u32));
    let Some((key, max_gain)) = rig.camera.imaging.auto_exposure else {
        return renderer;
    };
    if frames == 0 {
        return renderer;
    }
    let clip = ClipView {
        stat,
        script,
        trace,
        rig,
    };
    let mut frame_scene = scene::FrameScene::default();
    let mut images = camera::CameraImages::default();
    let mut log_sum = 0.0;
    for k in 0..METERED_QUARTERS {
        let frame = (frames * k / METERED_QUARTERS) as u32;
        let streaks = camera::streak_seed(script.seed, frame, 0);
        clip.render(
            &mut renderer,
            &mut frame_scene,
            scene::SceneTime::at(frame),
            streaks,
            &mut images,
        );
        log_sum += camera::expose::brightness(&images.rgb).max(1.0e-12).ln();
    }
    let brightness = (log_sum / METERED_QUARTERS as f64).exp();
    let key = key * look.exposure_key as f32;
    renderer.set_gain(camera::expose::auto_gain(brightness, key, max_gain));
    renderer
}
