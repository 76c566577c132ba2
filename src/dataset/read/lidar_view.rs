//! The LiDAR's bird's-eye view for `pedsynth preview --stream lidar`: one frame's points seen from above in the
//! sensor's frame (forward up, right to the right, ±40 m), coloured by CARLA tag (by intensity for the seed's
//! `.bin` layout, which has no tags), with the annotated pedestrians' 3D boxes (red: crossing, green: not) and
//! the traffic's boxes (yellow) moved into the sensor frame with the `sensor_poses` table. Reads only the
//! written dataset.

use std::collections::{BTreeMap, BTreeSet};

use glam::{DAffine3, DMat3, DQuat, DVec2, DVec3};

use super::tables;
use crate::dataset::write::Layout;
use crate::error::{Error, code};
use crate::sensors::scene::tag;
use crate::sim::{VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};

/// Side of the view, pixels.
pub const VIEW_PX: usize = 640;
/// Half the side of the view, metres.
const HALF_M: f64 = 40.0;

/// A box seen from above: centre, size (length, width), yaw, colour; all in the world.
struct TopBox {
    centre: DVec2,
    size: DVec2,
    yaw_rad: f64,
    colour: [u8; 3],
}

/// What the views of some frames of a clip need, read once.
pub struct LidarFrames {
    /// Points by frame: sensor-frame x (forward), y (right), and a colour.
    points: BTreeMap<u32, Vec<(f32, f32, [u8; 3])>>,
    poses: BTreeMap<u32, DAffine3>,
    boxes: BTreeMap<u32, Vec<TopBox>>,
}

fn invalid(msg: String) -> Error {
    Error::new(code::DATASET_INVALID, msg)
}

/// The points of one frame in the seed's `.bin` layout (little-endian float32 `x y z intensity` per point,
/// CARLA's sensor frame); `None` when the file is absent.
pub(crate) fn read_bin(path: &std::path::Path) -> Result<Option<Vec<[f32; 4]>>, Error> {
    let Ok(bytes) = std::fs::read(path) else {
        return Ok(None);
    };
    if bytes.len() % 16 != 0 {
        return Err(invalid(format!(
            "{}: {} bytes is not a whole number of 16-byte points",
            path.display(),
            bytes.len()
        )));
    }
    let value = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
    Ok(Some(
        bytes
            .chunks_exact(16)
            .map(|p| [value(&p[0..4]), value(&p[4..8]), value(&p[8..12]), value(&p[12..16])])
            .collect(),
    ))
}

impl LidarFrames {
    /// Reads the points of `frames` of a clip, its LiDAR poses and its boxes.
    pub fn read(layout: &Layout, clip: &str, frames: &BTreeSet<u32>) -> Result<LidarFrames, Error> {
        let mut points: BTreeMap<u32, Vec<(f32, f32, [u8; 3])>> = BTreeMap::new();
        let parquet = layout.sensor_clip("lidar", clip, "parquet");
        if parquet.is_file() {
            for b in tables::read(&parquet, &["frame", "x", "y", "tag"])? {
                let (f, x, y, t) = (b.u32s("frame")?, b.f32s("x")?, b.f32s("y")?, b.u8s("tag")?);
                for i in (0..b.rows()).filter(|&i| frames.contains(&f.value(i))) {
                    let c = tag::PALETTE
                        .get(usize::from(t.value(i)))
                        .copied()
                        .unwrap_or([255, 255, 255]);
                    points.entry(f.value(i)).or_default().push((x.value(i), y.value(i), c));
                }
            }
        } else {
            for &f in frames {
                let Some(bin) = read_bin(&layout.sensor_frame("lidar", clip, f, "bin"))? else {
                    continue;
                };
                points.entry(f).or_default().extend(bin.iter().map(|p| {
                    let g = (60.0 + 195.0 * p[3].clamp(0.0, 1.0)) as u8;
                    (p[0], p[1], [g, g, g])
                }));
            }
        }
        if points.is_empty() {
            return Err(invalid(format!(
                "clip `{clip}` has no LiDAR points in {} (was `sensors.lidar` enabled? see manifest.json's `sensors`)",
                layout.root().display()
            )));
        }
        let mut poses = BTreeMap::new();
        let cols = ["frame", "sensor", "x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"];
        for b in tables::read(&layout.table("sensor_poses", clip), &cols)? {
            let (f, s) = (b.u32s("frame")?, b.strings("sensor")?);
            let c = [b.f64s("x_m")?, b.f64s("y_m")?, b.f64s("z_m")?];
            let q = [b.f64s("qw")?, b.f64s("qx")?, b.f64s("qy")?, b.f64s("qz")?];
            for i in (0..b.rows()).filter(|&i| s[i] == "lidar" && frames.contains(&f.value(i))) {
                let rot = DQuat::from_xyzw(q[1].value(i), q[2].value(i), q[3].value(i), q[0].value(i));
                let at = DVec3::new(c[0].value(i), c[1].value(i), c[2].value(i));
                poses.insert(f.value(i), DAffine3::from_rotation_translation(rot.normalize(), at));
            }
        }
        let mut boxes: BTreeMap<u32, Vec<TopBox>> = BTreeMap::new();
        let cols = [
            "frame",
            "crossing",
            "yaw_rad",
            "box3d_x_m",
            "box3d_y_m",
            "box3d_length_m",
            "box3d_width_m",
        ];
        for b in tables::read(&layout.table("annotations", clip), &cols)? {
            let (f, crossing, yaw) = (b.u32s("frame")?, b.bools("crossing")?, b.f32s("yaw_rad")?);
            let g = [
                b.f32s("box3d_x_m")?,
                b.f32s("box3d_y_m")?,
                b.f32s("box3d_length_m")?,
                b.f32s("box3d_width_m")?,
            ];
            for i in (0..b.rows()).filter(|&i| frames.contains(&f.value(i))) {
                let v = |k: usize| f64::from(g[k].value(i));
                boxes.entry(f.value(i)).or_default().push(TopBox {
                    centre: DVec2::new(v(0), v(1)),
                    size: DVec2::new(v(2), v(3)),
                    yaw_rad: f64::from(yaw.value(i)),
                    colour: if crossing.value(i) {
                        [235, 50, 40]
                    } else {
                        [60, 220, 90]
                    },
                });
            }
        }
        for b in tables::read(&layout.table("vehicles", clip), &["frame", "x_m", "y_m", "yaw_rad"])? {
            let (f, x, y, yaw) = (b.u32s("frame")?, b.f32s("x_m")?, b.f32s("y_m")?, b.f32s("yaw_rad")?);
            for i in (0..b.rows()).filter(|&i| frames.contains(&f.value(i))) {
                boxes.entry(f.value(i)).or_default().push(TopBox {
                    centre: DVec2::new(f64::from(x.value(i)), f64::from(y.value(i))),
                    size: DVec2::new(VEHICLE_LENGTH_M, VEHICLE_WIDTH_M),
                    yaw_rad: f64::from(yaw.value(i)),
                    colour: [250, 210, 40],
                });
            }
        }
        Ok(LidarFrames { points, poses, boxes })
    }

    /// The view of one frame as RGB pixels, [`VIEW_PX`] square.
    pub fn view(&self, frame: u32) -> Vec<u8> {
        let n = VIEW_PX;
        let mut px = vec![12u8; n * n * 3];
        let scale = n as f64 / (2.0 * HALF_M);
        // Sensor frame (x forward, y right) → pixel: forward is up.
        let to_px =
            |x: f64, y_right: f64| -> (f64, f64) { (n as f64 / 2.0 + y_right * scale, n as f64 / 2.0 - x * scale) };
        let mut put = |u: f64, v: f64, c: [u8; 3]| {
            if u >= 0.0 && v >= 0.0 && (u as usize) < n && (v as usize) < n {
                let o = ((v as usize) * n + u as usize) * 3;
                px[o..o + 3].copy_from_slice(&c);
            }
        };
        // Range rings every 10 m.
        for r in [10.0, 20.0, 30.0, 40.0] {
            for k in 0..720 {
                let a = f64::from(k) * std::f64::consts::TAU / 720.0;
                let (u, v) = to_px(r * a.cos(), r * a.sin());
                put(u, v, [45, 45, 55]);
            }
        }
        for &(x, y, c) in self.points.get(&frame).map_or(&[][..], Vec::as_slice) {
            let (u, v) = to_px(f64::from(x), f64::from(y));
            put(u, v, c);
        }
        if let Some(pose) = self.poses.get(&frame) {
            let sensor_from_world = pose.inverse();
            for b in self.boxes.get(&frame).map_or(&[][..], Vec::as_slice) {
                let rot = DMat3::from_rotation_z(b.yaw_rad);
                let corners = [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)].map(|(sx, sy)| {
                    let w = b.centre.extend(0.0) + rot * DVec3::new(sx * b.size.x / 2.0, sy * b.size.y / 2.0, 0.0);
                    let s = sensor_from_world.transform_point3(w);
                    to_px(s.x, -s.y) // the pose's y is left; the view's right is CARLA's y
                });
                for k in 0..4 {
                    let (a, c) = (corners[k], corners[(k + 1) % 4]);
                    let steps = ((c.0 - a.0).abs().max((c.1 - a.1).abs()).ceil() as usize).clamp(1, 4 * n);
                    for s in 0..=steps {
                        let t = s as f64 / steps as f64;
                        put(a.0 + (c.0 - a.0) * t, a.1 + (c.1 - a.1) * t, b.colour);
                    }
                }
            }
        }
        // The sensor.
        for d in -3i32..=3 {
            put(n as f64 / 2.0 + f64::from(d), n as f64 / 2.0, [255, 255, 255]);
            put(n as f64 / 2.0, n as f64 / 2.0 + f64::from(d), [255, 255, 255]);
        }
        px
    }
}
