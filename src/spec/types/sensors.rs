//! `sensors`: the sensors on the ego vehicle — RGB camera, ray-cast LiDAR and DVS event camera, with their
//! mounts (the paper's and the seed's values as defaults).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Sensors on the ego vehicle. All share the clip's frame clock.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Sensors {
    /// RGB camera.
    pub rgb: Rgb,
    /// Ray-cast LiDAR.
    pub lidar: Lidar,
    /// DVS event camera (co-located with the RGB camera, same intrinsics).
    pub dvs: Dvs,
    /// Metric depth images from the RGB camera.
    pub depth: LabelStream,
    /// Semantic segmentation (CARLA's tag ids) from the RGB camera.
    pub semantic: LabelStream,
    /// Instance segmentation (pedestrian and vehicle ids) from the RGB camera.
    pub instance: LabelStream,
}

impl Sensors {
    /// Whether any camera stream (RGB, depth, semantic, instance, DVS) is enabled: the frames are rendered.
    pub fn cameras_enabled(&self) -> bool {
        self.rgb.enabled || self.dvs.enabled || self.depth.enabled || self.semantic.enabled || self.instance.enabled
    }
}

/// A label stream rendered from the RGB camera's view (same intrinsics and mount, pixel-aligned with it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LabelStream {
    /// Whether the stream is written.
    pub enabled: bool,
}

impl Default for LabelStream {
    fn default() -> Self {
        LabelStream { enabled: true }
    }
}

/// A sensor mount in the ego vehicle's body frame (x forward, y left, z up, metres; angles in degrees).
/// CARLA's `(x 0.8, y -0.3, z 1.4)` is `forward_m 0.8, left_m 0.3, up_m 1.4` here.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Mount {
    /// Forward of the vehicle origin, metres.
    pub forward_m: f64,
    /// Left of the vehicle origin, metres.
    pub left_m: f64,
    /// Above the ground, metres.
    pub up_m: f64,
    /// Pitch, degrees (negative looks down).
    pub pitch_deg: f64,
    /// Yaw, degrees (positive turns left).
    pub yaw_deg: f64,
    /// Roll, degrees.
    pub roll_deg: f64,
}

impl Default for Mount {
    fn default() -> Self {
        Mount {
            forward_m: 0.8,
            left_m: 0.3,
            up_m: 1.4,
            pitch_deg: -8.0,
            yaw_deg: 0.0,
            roll_deg: 0.0,
        }
    }
}

/// A named camera rig: the resolution, field of view and mount of a real dataset's camera (see
/// [`CameraProfile::preset`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CameraProfile {
    /// CARLA's camera as the paper mounts it: 1280×720, 90°, 1.4 m, pitched 8° down (today's defaults).
    #[default]
    Carla,
    /// JAAD's dashcams: 1920×1080; horizon and mount fitted to JAAD train + val's boxes.
    Jaad,
    /// PIE's camera: 1920×1080, the field of view of its calibrated focal length, its mount height.
    Pie,
}

impl CameraProfile {
    /// The keys under `sensors.rgb` a profile sets (as YAML values), where the spec does not set them itself.
    ///
    /// Sources:
    /// - `carla`: the defaults of this spec language (the paper's camera).
    /// - `jaad`: 1920×1080 from JAAD's annotations (every video, `videos.parquet` in ../shared/real). The mount is
    ///   `pedsynth calibrate --splits train,val` on JAAD's train and val annotations: their 162,999 unoccluded
    ///   boxes lie on `bottom = 0.614 + 0.815 × height` (fractions of the image height), a horizon 0.114 of the
    ///   height below the centre (pitched up 7.3° at 90°) and a camera 0.815 × 1.70 m (a mean pedestrian's
    ///   height) = 1.38 m above the road. JAAD's authors publish no field of view; 90° is assumed.
    /// - `pie`: PIE's `calibration_data.json` (github.com/aras62/PIE): 1920×1080, `fx` 1004.8 px, i.e.
    ///   2·atan(960 / 1004.8) = 87.4° horizontally, and `cam_height_mm` 1270. Its `cam_pitch_deg` (−10) comes
    ///   without a convention and is not used: the pitch is 0, level with the road.
    /// - `jaad` and `pie` also set a dashcam's sensor: vignetting 0.25 and noise (`shot` 0.012, `read` 0.0005:
    ///   about 1.5 levels of 255 on a mid-grey wall by day and 5–8 at night at the highest gain). Neither
    ///   dataset publishes its sensor's noise or vignetting, and their annotations cannot measure it: these are
    ///   chosen to look like a consumer dashcam, not fitted. Likewise motion blur with a 2 ms shutter by day
    ///   (1/500 s: no blur), opened by auto-exposure's gain up to 33 ms at night.
    pub fn preset(self) -> &'static [(&'static str, &'static str)] {
        match self {
            CameraProfile::Carla => &[
                ("width_px", "1280"),
                ("height_px", "720"),
                ("fov_deg", "90"),
                ("mount.up_m", "1.4"),
                ("mount.pitch_deg", "-8"),
            ],
            CameraProfile::Jaad => &[
                ("width_px", "1920"),
                ("height_px", "1080"),
                ("fov_deg", "90"),
                ("mount.up_m", "1.38"),
                ("mount.pitch_deg", "7.3"),
                ("vignetting", "0.25"),
                ("noise.shot", "0.012"),
                ("noise.read", "0.0005"),
                ("motion_blur.shutter_ms", "2"),
            ],
            CameraProfile::Pie => &[
                ("width_px", "1920"),
                ("height_px", "1080"),
                ("fov_deg", "87.4"),
                ("mount.up_m", "1.27"),
                ("mount.pitch_deg", "0"),
                ("vignetting", "0.25"),
                ("noise.shot", "0.012"),
                ("noise.read", "0.0005"),
                ("motion_blur.shutter_ms", "2"),
            ],
        }
    }
}

/// RGB camera (pinhole; horizontal field of view).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Rgb {
    /// Whether RGB images are written.
    pub enabled: bool,
    /// A real camera rig whose resolution, field of view and mount height and pitch are used where this
    /// section does not set them: `carla` (the default), `jaad` or `pie`.
    #[serde(skip_serializing_if = "super::is_default")]
    pub profile: CameraProfile,
    /// Image width, pixels.
    pub width_px: u32,
    /// Image height, pixels.
    pub height_px: u32,
    /// Horizontal field of view, degrees.
    pub fov_deg: f64,
    /// Mount at the driver's eye.
    pub mount: Mount,
    /// How the mount differs from clip to clip, as real datasets are filmed from many cars: offsets drawn per
    /// clip from its seed and added to `mount`. Off (`[0, 0]`) by default.
    #[serde(skip_serializing_if = "super::is_default")]
    pub mount_spread: MountSpread,
    /// Lens distortion (Brown–Conrady, OpenCV's convention), applied to every camera stream and to the boxes
    /// and keypoints. All zero (a pinhole) by default.
    #[serde(skip_serializing_if = "super::is_default")]
    pub distortion: Distortion,
    /// Auto-exposure: how the camera brightens a dark clip (night, dusk) as a dashcam's does. On by default.
    #[serde(skip_serializing_if = "super::is_default")]
    pub exposure: Exposure,
    /// Share of the light lost at the image's corners (vignetting: `1 − vignetting × r² / r_corner²` of the
    /// light reaches a pixel `r` from the centre), 0–0.9. 0 (none) by default.
    #[serde(skip_serializing_if = "super::is_default")]
    pub vignetting: f64,
    /// Sensor noise (shot and read noise, amplified by the exposure's gain). Off by default; the `jaad` and
    /// `pie` profiles turn it on.
    #[serde(skip_serializing_if = "super::is_default")]
    pub noise: SensorNoise,
    /// Motion blur from the ego's and the agents' motion while the shutter is open. Off by default; the `jaad`
    /// and `pie` profiles turn it on.
    pub motion_blur: MotionBlur,
}

/// Motion blur. The shutter is open for `shutter_ms` before each frame's instant; with auto-exposure it stays
/// open `gain` times longer (a dashcam lengthens its exposure before it amplifies), up to `max_shutter_ms`. The
/// RGB image is the mean of renders spread evenly over the open shutter, the last at the frame's instant: one
/// render per 2 ms of shutter, at most `samples` (a shutter under 2 ms costs nothing and blurs nothing). Only the
/// RGB stream is blurred: the labels, the depth, the masks and the DVS are of the frame's instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MotionBlur {
    /// Shutter time at a gain of 1, milliseconds (0: no blur, the default).
    pub shutter_ms: f64,
    /// The longest shutter auto-exposure opens, milliseconds (33: a whole frame at 30 frames/s).
    pub max_shutter_ms: f64,
    /// Renders per frame at most (each one costs a frame's rendering).
    pub samples: u32,
}

impl Default for MotionBlur {
    fn default() -> Self {
        MotionBlur {
            shutter_ms: 0.0,
            max_shutter_ms: 33.0,
            samples: 4,
        }
    }
}

/// How the exposure is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ExposureMode {
    /// Metered per clip: the light is multiplied by a gain of `key` over the clip's metered brightness,
    /// between 1 and `max_gain` (daylight keeps the renderer's exposure; dark clips are brightened).
    #[default]
    Auto,
    /// The renderer's exposure (a gain of 1) in every clip: night stays as dark as the light is.
    Fixed,
}

/// Auto-exposure. The meter: four frames of the clip (at 0, ¼, ½ and ¾ of it) rendered at a gain of 1; their
/// brightness is the geometric mean of the linear luminance of each frame's pixels between its 10th and 90th
/// percentiles, averaged (geometrically) over the four. The clip is then rendered at
/// `gain = clamp(key / brightness, 1, max_gain)`, applied to the linear light before the tone curve (no
/// banding), so that every image is still a pure function of the clip and the frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Exposure {
    /// `auto` (the default) or `fixed`.
    pub mode: ExposureMode,
    /// The metered brightness auto-exposure aims at (linear luminance; a clear noon clip meters 0.11–0.13,
    /// dusk 0.04–0.09, night 0.005–0.02).
    pub key: f64,
    /// The most auto-exposure amplifies the light (a dashcam's highest gain; more gain, more noise).
    pub max_gain: f64,
}

impl Default for Exposure {
    fn default() -> Self {
        Exposure {
            mode: ExposureMode::Auto,
            key: 0.1,
            max_gain: 16.0,
        }
    }
}

/// Sensor noise, per pixel and channel, independent from frame to frame, seeded per clip and frame: a linear
/// signal `x` (the light before the exposure's gain) gets a Gaussian error of standard deviation
/// `sqrt(shot² × x + read²)`, amplified by the gain with the signal, then the tone curve maps both. Only the
/// RGB stream is noisy: the DVS sees the clean image and the label streams are exact.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SensorNoise {
    /// Shot noise: the standard deviation at a linear signal of 1 (about a white wall in full sun), which
    /// grows with the square root of the signal.
    pub shot: f64,
    /// Read noise: the standard deviation at no signal (linear units).
    pub read: f64,
}

/// Brown–Conrady lens distortion in OpenCV's convention (`cv2.projectPoints`, `cv2.undistort` with
/// `D = [k1, k2, p1, p2, k3]`): a point at normalised image coordinates `(x, y) = (X/Z, Y/Z)`, `r² = x² + y²`,
/// is seen at `x' = x·(1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2 x²)` and
/// `y' = y·(1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2 y²) + 2 p2 x y`, then at pixel `(f x' + w/2, f y' + h/2)`.
/// Negative `k1` is barrel distortion (a dashcam's wide lens).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Distortion {
    /// Radial coefficient of r².
    pub k1: f64,
    /// Radial coefficient of r⁴.
    pub k2: f64,
    /// Tangential coefficient p1.
    pub p1: f64,
    /// Tangential coefficient p2.
    pub p2: f64,
    /// Radial coefficient of r⁶.
    pub k3: f64,
}

impl Distortion {
    /// Whether every coefficient is zero: a pinhole.
    pub fn is_zero(&self) -> bool {
        *self == Distortion::default()
    }

    /// The coefficients in OpenCV's order `[k1, k2, p1, p2, k3]`.
    pub fn coefficients(&self) -> [f64; 5] {
        [self.k1, self.k2, self.p1, self.p2, self.k3]
    }
}

/// Per-clip offsets of the camera mount, each drawn uniformly from its range `[min, max]` with the clip's seed
/// (`sim::rig::clip_mount`). JAAD's videos come from several cars and cameras: fitted per video, their horizons
/// and camera heights scatter (`pedsynth calibrate` fits these ranges to a real dataset's spread).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MountSpread {
    /// Offset of the mount's height, metres `[min, max]`.
    pub up_m: super::Range,
    /// Offset of the mount's pitch, degrees `[min, max]` (negative looks down).
    pub pitch_deg: super::Range,
    /// Offset of the mount's pitch drawn from a measured distribution instead of `pitch_deg`'s uniform range:
    /// its quantiles at equal steps of probability from 0 (the lowest) to 1 (the highest), ascending, degrees,
    /// interpolated linearly between them. JAAD's videos' horizons gather near the middle with long tails, which
    /// no uniform range gives (`pedsynth calibrate` writes the per-video horizons' quantiles). Empty (the
    /// default): `pitch_deg`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pitch_quantiles_deg: Vec<f64>,
}

impl Default for MountSpread {
    fn default() -> Self {
        MountSpread {
            up_m: super::Range(0.0, 0.0),
            pitch_deg: super::Range(0.0, 0.0),
            pitch_quantiles_deg: Vec::new(),
        }
    }
}

impl MountSpread {
    /// The pitch offset at probability `u` in [0, 1): `pitch_quantiles_deg` interpolated where given, else
    /// uniform over `pitch_deg`.
    pub fn pitch_at(&self, u: f64) -> f64 {
        let q = &self.pitch_quantiles_deg;
        match q.len() {
            0 => self.pitch_deg.min() + (self.pitch_deg.max() - self.pitch_deg.min()) * u,
            1 => q[0],
            n => {
                let x = u.clamp(0.0, 1.0) * (n - 1) as f64;
                let i = (x.floor() as usize).min(n - 2);
                q[i] + (q[i + 1] - q[i]) * (x - i as f64)
            }
        }
    }
}

impl Default for Rgb {
    fn default() -> Self {
        Rgb {
            enabled: true,
            profile: CameraProfile::Carla,
            width_px: 1280,
            height_px: 720,
            fov_deg: 90.0,
            mount: Mount::default(),
            mount_spread: MountSpread::default(),
            distortion: Distortion::default(),
            exposure: Exposure::default(),
            vignetting: 0.0,
            noise: SensorNoise::default(),
            motion_blur: MotionBlur::default(),
        }
    }
}

/// Ray-cast LiDAR (CARLA `sensor.lidar.ray_cast` semantics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Lidar {
    /// Whether LiDAR sweeps are written.
    pub enabled: bool,
    /// Number of laser channels.
    pub channels: u32,
    /// Maximum range, metres.
    pub range_m: f64,
    /// Points per second over all channels.
    pub points_per_second: u32,
    /// Rotation frequency, Hz.
    pub rotation_hz: f64,
    /// Elevation of the top channel, degrees.
    pub upper_fov_deg: f64,
    /// Elevation of the bottom channel, degrees.
    pub lower_fov_deg: f64,
    /// Horizontal field of view, degrees.
    pub horizontal_fov_deg: f64,
    /// Atmospheric attenuation rate, 1/m (intensity = exp(-rate × distance)).
    pub atmosphere_attenuation_per_m: f64,
    /// Share of rays dropped at random.
    pub dropoff_general_rate: f64,
    /// Intensity above which no intensity-based drop-off happens.
    pub dropoff_intensity_limit: f64,
    /// Drop-off probability of a zero-intensity return.
    pub dropoff_zero_intensity: f64,
    /// Standard deviation of range noise along the ray, metres.
    pub noise_stddev_m: f64,
    /// Roof mount.
    pub mount: Mount,
    /// File format of the points.
    pub format: LidarFormat,
}

/// LiDAR file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LidarFormat {
    /// One Parquet file per clip: frame, time, x, y, z, intensity, cos_incidence, tag, instance, actor_id.
    Parquet,
    /// The seed system's layout: one `NNNNNN.bin` per frame of little-endian f32 `x y z intensity`.
    CarlaBin,
}

impl Default for Lidar {
    fn default() -> Self {
        Lidar {
            enabled: true,
            channels: 64,
            range_m: 100.0,
            points_per_second: 1_000_000,
            rotation_hz: 20.0,
            upper_fov_deg: 15.0,
            lower_fov_deg: -25.0,
            horizontal_fov_deg: 360.0,
            atmosphere_attenuation_per_m: 0.004,
            dropoff_general_rate: 0.45,
            dropoff_intensity_limit: 0.8,
            dropoff_zero_intensity: 0.4,
            noise_stddev_m: 0.0,
            mount: Mount {
                forward_m: 0.0,
                left_m: 0.0,
                up_m: 2.4,
                pitch_deg: 0.0,
                yaw_deg: 0.0,
                roll_deg: 0.0,
            },
            format: LidarFormat::Parquet,
        }
    }
}

/// DVS event camera (ESIM, CARLA `sensor.camera.dvs` semantics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Dvs {
    /// Whether events are written.
    pub enabled: bool,
    /// Positive contrast threshold Cp.
    pub positive_threshold: f64,
    /// Negative contrast threshold Cm.
    pub negative_threshold: f64,
    /// Per-pixel, per-frame standard deviation of Cp.
    pub sigma_positive_threshold: f64,
    /// Per-pixel, per-frame standard deviation of Cm.
    pub sigma_negative_threshold: f64,
    /// Refractory period, nanoseconds.
    pub refractory_period_ns: u64,
    /// Work on log intensity.
    pub use_log: bool,
    /// Epsilon added before the logarithm.
    pub log_eps: f64,
    /// Images rendered per frame interval for the event simulation (1: the frames only; more sample fast
    /// motion between frames).
    pub substeps: u32,
}

impl Default for Dvs {
    fn default() -> Self {
        Dvs {
            enabled: true,
            positive_threshold: 0.3,
            negative_threshold: 0.3,
            sigma_positive_threshold: 0.0,
            sigma_negative_threshold: 0.0,
            refractory_period_ns: 0,
            use_log: true,
            log_eps: 0.001,
            substeps: 1,
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
