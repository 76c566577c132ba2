//! The ego's sensor rig: the pinhole camera (mount, intrinsics, projection) and the LiDAR's mount, from the
//! spec.
//!
//! Frames: *world* (right-handed, x east, y north, z up), *vehicle* (x forward, y left, z up; origin on the
//! ground under the vehicle's centre), *sensor* (the vehicle frame moved and turned by the mount) and
//! *optical* (x right, y down, z forward, the usual image convention). Pixel (0, 0) is the top-left corner of
//! the top-left pixel; `u` grows to the right, `v` downwards.

use glam::{DAffine3, DMat3, DVec2, DVec3};

use rand::RngExt;

use crate::plan::seeds::clip_rng;
use crate::spec::types::{ExposureMode, Mount, Rgb, Sensors};
use crate::util::lens::Lens;

/// The sensors on the ego vehicle, placed and configured from the spec.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rig {
    /// The RGB camera (the annotations' camera: boxes and keypoints are in its image).
    pub camera: Camera,
    /// Pose of the LiDAR in the vehicle frame (x forward, y left, z up).
    pub lidar_vehicle_from_sensor: DAffine3,
}

impl Rig {
    /// The rig of a spec's sensors.
    pub fn from_spec(sensors: &Sensors) -> Rig {
        Rig {
            camera: Camera::from_spec(&sensors.rgb),
            lidar_vehicle_from_sensor: vehicle_from_mount(&sensors.lidar.mount),
        }
    }

    /// The rig of a spec's sensors on the clip seeded `clip_seed`: the camera's mount with the clip's offsets
    /// (`sensors.rgb.mount_spread`, [`clip_mount`]); the LiDAR's roof mount does not vary.
    pub fn for_clip(sensors: &Sensors, clip_seed: u64) -> Rig {
        Rig {
            camera: Camera::for_clip(&sensors.rgb, clip_seed),
            ..Rig::from_spec(sensors)
        }
    }

    /// The LiDAR's pose in the world (x forward, y left, z up) on a vehicle at `pos` heading `yaw_rad`, its body
    /// pitched `pitch_rad` (nose up positive).
    pub fn world_from_lidar(&self, vehicle_pos: DVec3, vehicle_yaw_rad: f64, vehicle_pitch_rad: f64) -> DAffine3 {
        world_from_vehicle(vehicle_pos, vehicle_yaw_rad, vehicle_pitch_rad) * self.lidar_vehicle_from_sensor
    }
}

/// Intrinsics and mount of a pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Image width, pixels.
    pub width_px: u32,
    /// Image height, pixels.
    pub height_px: u32,
    /// Focal length, pixels (square pixels).
    pub focal_px: f64,
    /// Pose of the sensor in the vehicle frame.
    pub vehicle_from_sensor: DAffine3,
    /// Lens distortion between the pinhole and the pixels ([`Lens::is_pinhole`] for none).
    pub lens: Lens,
    /// What the sensor does with the light: exposure, vignetting, noise.
    pub imaging: Imaging,
}

/// Shutter time per motion-blur render, seconds.
const BLUR_SAMPLE_SPACING_S: f64 = 0.002;

/// The camera's imaging of light into pixels (from `sensors.rgb`'s `exposure`, `vignetting`, `noise` and
/// `motion_blur`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Imaging {
    /// Auto-exposure's `(key, max_gain)`; `None` for a fixed gain of 1.
    pub auto_exposure: Option<(f32, f32)>,
    /// Share of the light lost at the image's corners.
    pub vignetting: f32,
    /// Shot noise's standard deviation at a linear signal of 1.
    pub shot_noise: f32,
    /// Read noise's standard deviation.
    pub read_noise: f32,
    /// Motion blur's shutter at a gain of 1, seconds (0: none).
    pub shutter_s: f64,
    /// Motion blur's longest shutter, seconds.
    pub max_shutter_s: f64,
    /// Motion blur's renders per frame at most.
    pub blur_samples: u32,
}

impl Imaging {
    /// The imaging of a spec's RGB camera.
    pub fn from_spec(rgb: &Rgb) -> Imaging {
        let e = &rgb.exposure;
        Imaging {
            auto_exposure: (e.mode == ExposureMode::Auto).then_some((e.key as f32, e.max_gain as f32)),
            vignetting: rgb.vignetting as f32,
            shot_noise: rgb.noise.shot as f32,
            read_noise: rgb.noise.read as f32,
            shutter_s: rgb.motion_blur.shutter_ms / 1000.0,
            max_shutter_s: rgb.motion_blur.max_shutter_ms / 1000.0,
            blur_samples: rgb.motion_blur.samples,
        }
    }

    /// Motion blur at an exposure's gain: the shutter time, seconds, and the renders per frame (1: none).
    pub fn blur(&self, gain: f32) -> (f64, u32) {
        let shutter_s = (self.shutter_s * f64::from(gain.max(1.0))).min(self.max_shutter_s);
        let samples = (shutter_s / BLUR_SAMPLE_SPACING_S)
            .ceil()
            .clamp(1.0, f64::from(self.blur_samples.max(1)));
        (shutter_s, samples as u32)
    }

    /// Whether the sensor adds noise.
    pub fn noisy(&self) -> bool {
        self.shot_noise > 0.0 || self.read_noise > 0.0
    }
}

/// The rotation taking sensor axes (x forward, y left, z up) to optical axes (x right, y down, z forward).
const OPTICAL_FROM_SENSOR: DMat3 = DMat3::from_cols(
    DVec3::new(0.0, 0.0, 1.0),  // sensor x (forward) → optical z
    DVec3::new(-1.0, 0.0, 0.0), // sensor y (left) → optical −x
    DVec3::new(0.0, -1.0, 0.0), // sensor z (up) → optical −y
);

/// The camera mount of the clip seeded `clip_seed`: `rgb.mount` with its height and pitch offset by draws from
/// `rgb.mount_spread`'s ranges or pitch quantiles (the clip's `"camera mount"` stream). With the default spread (`[0, 0]`) it is
/// `rgb.mount` exactly.
pub fn clip_mount(rgb: &Rgb, clip_seed: u64) -> Mount {
    let spread = &rgb.mount_spread;
    let mut mount = rgb.mount.clone();
    if *spread == Default::default() {
        return mount;
    }
    let mut rng = clip_rng(clip_seed, "camera mount");
    let up = spread.up_m;
    mount.up_m += up.min() + (up.max() - up.min()) * rng.random::<f64>();
    mount.pitch_deg += spread.pitch_at(rng.random::<f64>());
    mount
}

/// The pose of a mount in the vehicle frame. Pitch is about the vehicle's y axis with negative values looking
/// down (CARLA's convention), yaw about z (positive turns left), roll about x.
pub fn vehicle_from_mount(mount: &Mount) -> DAffine3 {
    let yaw = DMat3::from_rotation_z(mount.yaw_deg.to_radians());
    let pitch = DMat3::from_rotation_y(-mount.pitch_deg.to_radians());
    let roll = DMat3::from_rotation_x(mount.roll_deg.to_radians());
    DAffine3::from_mat3_translation(
        yaw * pitch * roll,
        DVec3::new(mount.forward_m, mount.left_m, mount.up_m),
    )
}

/// The pose of a vehicle in the world: on the ground at `pos` (z is the ground height), heading `yaw_rad`, its
/// body pitched `pitch_rad` about the ground point (nose up positive, CARLA's convention; the ego's pitch
/// wobble, 0 for every other vehicle).
pub fn world_from_vehicle(pos: DVec3, yaw_rad: f64, pitch_rad: f64) -> DAffine3 {
    if pitch_rad == 0.0 {
        // Without pitch, exactly the matrix of earlier versions (bit for bit).
        return DAffine3::from_mat3_translation(DMat3::from_rotation_z(yaw_rad), pos);
    }
    DAffine3::from_mat3_translation(
        DMat3::from_rotation_z(yaw_rad) * DMat3::from_rotation_y(-pitch_rad),
        pos,
    )
}

/// A camera placed in the world for one frame: everything needed to project points.
#[derive(Clone, Copy, Debug)]
pub struct CameraPose {
    /// Intrinsics.
    pub camera: Camera,
    /// World → optical frame.
    pub optical_from_world: DAffine3,
    /// Camera centre in the world.
    pub centre: DVec3,
    /// Unit forward axis in the world.
    pub forward: DVec3,
    /// Unit right axis in the world (image +u).
    pub right: DVec3,
    /// Unit down axis in the world (image +v).
    pub down: DVec3,
}

/// A projected point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Pixel coordinates.
    pub px: DVec2,
    /// Depth along the optical axis, metres (≤ 0 behind the camera).
    pub depth_m: f64,
}

impl Camera {
    /// The RGB camera of a spec.
    pub fn from_spec(rgb: &Rgb) -> Self {
        let focal_px = f64::from(rgb.width_px) / (2.0 * (rgb.fov_deg.to_radians() / 2.0).tan());
        Camera {
            width_px: rgb.width_px,
            height_px: rgb.height_px,
            focal_px,
            vehicle_from_sensor: vehicle_from_mount(&rgb.mount),
            lens: Lens::new(rgb.distortion.coefficients()),
            imaging: Imaging::from_spec(rgb),
        }
    }

    /// The RGB camera of a spec on the clip seeded `clip_seed` (its mount: [`clip_mount`]).
    pub fn for_clip(rgb: &Rgb, clip_seed: u64) -> Self {
        Camera {
            vehicle_from_sensor: vehicle_from_mount(&clip_mount(rgb, clip_seed)),
            ..Camera::from_spec(rgb)
        }
    }

    /// The pixel at which the camera sees the normalised image point `(x, y) = (X/Z, Y/Z)` of its optical frame:
    /// through the lens, then the intrinsics (principal point at the image centre).
    pub fn pixel_of_normalised(&self, x: f64, y: f64) -> DVec2 {
        let (x, y) = if self.lens.is_pinhole() {
            (x, y)
        } else {
            self.lens.distort(x, y)
        };
        DVec2::new(
            self.focal_px * x + f64::from(self.width_px) * 0.5,
            self.focal_px * y + f64::from(self.height_px) * 0.5,
        )
    }

    /// The camera's pose in the world (x forward, y left, z up) on a vehicle at `pos` heading `yaw_rad`, pitched
    /// `pitch_rad` ([`world_from_vehicle`]).
    pub fn world_from_sensor(&self, vehicle_pos: DVec3, vehicle_yaw_rad: f64, vehicle_pitch_rad: f64) -> DAffine3 {
        world_from_vehicle(vehicle_pos, vehicle_yaw_rad, vehicle_pitch_rad) * self.vehicle_from_sensor
    }

    /// The camera on a vehicle at `pos` heading `yaw_rad`, pitched `pitch_rad` ([`world_from_vehicle`]).
    pub fn at(&self, vehicle_pos: DVec3, vehicle_yaw_rad: f64, vehicle_pitch_rad: f64) -> CameraPose {
        let world_from_sensor = self.world_from_sensor(vehicle_pos, vehicle_yaw_rad, vehicle_pitch_rad);
        let sensor_from_world = world_from_sensor.inverse();
        let optical_from_world = DAffine3::from_mat3(OPTICAL_FROM_SENSOR) * sensor_from_world;
        let rot = world_from_sensor.matrix3;
        CameraPose {
            camera: *self,
            optical_from_world,
            centre: world_from_sensor.translation,
            forward: rot.x_axis,
            right: -rot.y_axis,
            down: -rot.z_axis,
        }
    }
}

impl CameraPose {
    /// Projects a world point.
    pub fn project(&self, world: DVec3) -> Projection {
        let p = self.optical_from_world.transform_point3(world);
        let c = &self.camera;
        let depth = p.z;
        let inv = if depth.abs() > 1e-9 { 1.0 / depth } else { 1e9 };
        let px = if c.lens.is_pinhole() {
            // (f·x)/z, in this order: the pinhole's pixels are bit for bit those of earlier versions.
            DVec2::new(
                c.focal_px * p.x * inv + f64::from(c.width_px) * 0.5,
                c.focal_px * p.y * inv + f64::from(c.height_px) * 0.5,
            )
        } else {
            c.pixel_of_normalised(p.x * inv, p.y * inv)
        };
        Projection { px, depth_m: depth }
    }

    /// Whether a pixel lies inside the image.
    pub fn in_image(&self, px: DVec2) -> bool {
        px.x >= 0.0
            && px.y >= 0.0
            && px.x <= f64::from(self.camera.width_px)
            && px.y <= f64::from(self.camera.height_px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::types::Rgb;

    #[test]
    fn intrinsics_and_axes_follow_the_spec() {
        let cam = Camera::from_spec(&Rgb::default());
        assert!((cam.focal_px - 640.0).abs() < 1e-9, "f = W / (2 tan(45°)) = 640");
        let pose = cam.at(DVec3::ZERO, 0.0, 0.0);
        assert!((pose.centre - DVec3::new(0.8, 0.3, 1.4)).length() < 1e-12);
        // Pitch −8° looks down: the forward axis has a negative z component.
        assert!((pose.forward.z - (-8f64.to_radians()).sin()).abs() < 1e-12);
        // A point straight ahead along the optical axis lands on the principal point.
        let ahead = pose.centre + pose.forward * 20.0;
        let p = pose.project(ahead);
        assert!((p.px - DVec2::new(640.0, 360.0)).length() < 1e-9 && (p.depth_m - 20.0).abs() < 1e-9);
        // Left of the camera is left in the image; above is up.
        assert!(pose.project(ahead + DVec3::Y).px.x < 640.0);
        assert!(pose.project(ahead + DVec3::Z).px.y < 360.0);
        // Behind the camera: negative depth.
        assert!(pose.project(pose.centre - pose.forward).depth_m < 0.0);
    }

    #[test]
    fn the_camera_turns_with_the_vehicle() {
        let cam = Camera::from_spec(&Rgb::default());
        let pose = cam.at(DVec3::new(10.0, 5.0, 0.0), std::f64::consts::FRAC_PI_2, 0.0);
        assert!(
            (pose.forward.truncate().normalize() - DVec2::Y).length() < 1e-9,
            "heading north looks north"
        );
        assert!(
            (pose.right - DVec3::X).length() < 1e-9 || pose.right.x > 0.99,
            "north-facing: right is east"
        );
    }

    #[test]
    fn a_nose_up_body_pitch_moves_the_scene_down_the_image_by_f_tan_pitch() {
        let cam = Camera::from_spec(&Rgb {
            mount: Mount {
                pitch_deg: 0.0,
                ..Rgb::default().mount
            },
            ..Rgb::default()
        });
        let level = cam.at(DVec3::ZERO, 0.3, 0.0);
        assert_eq!(
            level.optical_from_world,
            cam.at(DVec3::ZERO, 0.3, -0.0).optical_from_world
        );
        // A point far ahead, at the camera's height: on the principal point when level.
        let far = level.centre + level.forward * 1e6;
        assert!((level.project(far).px - DVec2::new(640.0, 360.0)).length() < 1e-6);
        let pitch_rad = 0.5f64.to_radians();
        let nodded = cam.at(DVec3::ZERO, 0.3, pitch_rad);
        let px = nodded.project(far).px;
        assert!(
            (px.x - 640.0).abs() < 1e-6 && (px.y - (360.0 + 640.0 * pitch_rad.tan())).abs() < 1e-3,
            "{px}"
        );
        // The LiDAR pitches with the body.
        let rig = Rig::from_spec(&crate::spec::types::Sensors::default());
        let (a, b) = (
            rig.world_from_lidar(DVec3::ZERO, 0.0, 0.0),
            rig.world_from_lidar(DVec3::ZERO, 0.0, pitch_rad),
        );
        assert!((b.matrix3.x_axis.z - pitch_rad.sin()).abs() < 1e-12 && a.matrix3.x_axis.z.abs() < 1e-12);
    }

    #[test]
    fn pitch_quantiles_give_the_measured_distribution_in_place_of_the_uniform_range() {
        let mut rgb = Rgb::default();
        rgb.mount_spread.pitch_quantiles_deg = vec![-6.0, -1.0, 0.0, 1.0, 4.0];
        // Linear between the quantiles at 0, ¼, ½, ¾ and 1.
        let s = &rgb.mount_spread;
        assert_eq!((s.pitch_at(0.0), s.pitch_at(0.125), s.pitch_at(0.5)), (-6.0, -3.5, 0.0));
        assert!((s.pitch_at(0.999_999_999) - 4.0).abs() < 1e-6 && s.pitch_at(1.0) == 4.0);
        let pitches: Vec<f64> = (0..2000)
            .map(|seed| clip_mount(&rgb, seed).pitch_deg - rgb.mount.pitch_deg)
            .collect();
        assert!(pitches.iter().all(|p| (-6.0..=4.0).contains(p)));
        // Half the clips between the quartiles −1° and 1°, where a uniform draw over [−6, 4] would put a fifth.
        let inner = pitches.iter().filter(|p| (-1.0..=1.0).contains(*p)).count() as f64 / 2000.0;
        assert!((inner - 0.5).abs() < 0.04, "{inner}");
    }

    #[test]
    fn clip_mounts_vary_within_the_spread_and_are_the_spec_mount_without_it() {
        let mut rgb = Rgb::default();
        for seed in [0, 1, u64::MAX] {
            assert_eq!(clip_mount(&rgb, seed), rgb.mount, "no spread: the spec's mount exactly");
            assert_eq!(Camera::for_clip(&rgb, seed), Camera::from_spec(&rgb));
        }
        rgb.mount_spread.up_m = crate::spec::types::Range(-0.3, 0.2);
        rgb.mount_spread.pitch_deg = crate::spec::types::Range(-5.0, 5.0);
        let mounts: Vec<Mount> = (0..200).map(|seed| clip_mount(&rgb, seed)).collect();
        for m in &mounts {
            assert!(
                (1.1..=1.6).contains(&m.up_m) && (-13.0..=-3.0).contains(&m.pitch_deg),
                "{m:?}"
            );
            let untouched = (m.forward_m, m.left_m, m.yaw_deg, m.roll_deg);
            assert_eq!(untouched, (0.8, 0.3, 0.0, 0.0));
        }
        let spread = |f: fn(&Mount) -> f64| {
            let xs: Vec<f64> = mounts.iter().map(f).collect();
            xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min)
        };
        assert!(
            spread(|m| m.up_m) > 0.4 && spread(|m| m.pitch_deg) > 8.0,
            "draws cover the ranges"
        );
        assert_eq!(clip_mount(&rgb, 7), clip_mount(&rgb, 7), "a pure function of the seed");
        let rig = Rig::for_clip(&Sensors::default(), 7);
        assert_eq!(rig, Rig::from_spec(&Sensors::default()));
    }
}
