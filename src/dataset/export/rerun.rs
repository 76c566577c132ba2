//! `pedsynth export rerun DATASET --clip ID --out CLIP.rrd` (the `rerun` cargo feature): one clip as a Rerun
//! recording, written with Rerun's own Rust SDK, to look at with all its sensors in the Rerun viewer.
//!
//! Timelines `frame` (sequence) and `time` (simulated seconds). Entities (DATASET.md, "`rerun`"):
//!
//! - `world`: right-handed, z up (the world frame); `world/ego` the ego's pose per frame; `world/ego/camera`
//!   the camera's mount (optical axes) with its pinhole at `world/ego/camera/image`, under which `rgb` (the
//!   PNG or JPEG as is), `depth` (millimetres), `instance` (the instance ids), `boxes` (2D, red C = 1, green
//!   C = 0) and `keypoints/<pedestrian>` (COCO-17 with the person skeleton);
//! - `world/ego/lidar` the LiDAR's mount and `world/ego/lidar/points` its points per frame coloured by tag;
//! - `world/pedestrians`, `world/vehicles`, `world/cyclists`: 3D boxes per frame;
//! - `timeseries/pedestrian_<id>/state` (the state's index in the paper's order) and `.../tte_frames`, and
//!   `timeseries/ego/speed_mps`.

use std::collections::BTreeMap;
use std::path::Path;

use glam::{DAffine3, DMat3, DQuat, DVec3};
use rerun::datatypes::{AnnotationInfo, ClassDescription, KeypointPair};

use super::dataset::{Clip, Dataset, SENSOR_FROM_OPTICAL};
use crate::dataset::read::tables as read_tables;
use crate::error::{Error, code};
use crate::sensors::keypoints::COCO17;
use crate::sim::trace::PedState;

/// What an export wrote: entity path → rows (frames logged).
#[derive(Debug, Default)]
pub struct RerunReport {
    pub frames: u32,
    pub rows: BTreeMap<String, u64>,
}

fn failed(what: &str, e: impl std::fmt::Display) -> Error {
    Error::new(code::IO_WRITE, format!("Rerun recording: {what}: {e}"))
}

fn quaternion(m: DMat3) -> rerun::Quaternion {
    let q = DQuat::from_mat3(&m).normalize();
    rerun::Quaternion::from_xyzw([q.x as f32, q.y as f32, q.z as f32, q.w as f32])
}

fn transform(t: &DAffine3) -> rerun::Transform3D {
    let v = t.translation;
    rerun::Transform3D::from_translation_rotation([v.x as f32, v.y as f32, v.z as f32], quaternion(t.matrix3))
}

fn yaw_quaternion(yaw_rad: f64) -> rerun::Quaternion {
    quaternion(DMat3::from_rotation_z(yaw_rad))
}

/// Red for C = 1, green for C = 0 (as `preview`).
fn crossing_colour(crossing: bool) -> rerun::Color {
    if crossing {
        rerun::Color::from_rgb(235, 50, 40)
    } else {
        rerun::Color::from_rgb(60, 220, 90)
    }
}

/// Writes clip `clip_id` of `ds` to `out` (an `.rrd` file, written under a temporary name and renamed).
pub fn export(ds: &Dataset, clip_id: &str, out: &Path) -> Result<RerunReport, Error> {
    let info = ds.clips.iter().find(|c| c.clip_id == clip_id).ok_or_else(|| {
        Error::new(
            code::EXPORT_OPTIONS,
            format!("--clip {clip_id}: no such clip in {}", ds.layout.root().display()),
        )
    })?;
    let clip = ds.load(info)?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    }
    let tmp = crate::util::files::temporary_path(out);
    let rec = rerun::RecordingStreamBuilder::new("pedsynth")
        .recording_id(format!("pedsynth-{clip_id}"))
        .send_properties(false)
        .save(&tmp)
        .map_err(|e| failed("open", e))?;
    rec.set_log_time_enabled(false);
    let mut report = RerunReport::default();
    let result = Recorder {
        ds,
        clip: &clip,
        rec: &rec,
        report: &mut report,
    }
    .record();
    rec.flush_blocking().map_err(|e| failed("flush", e))?;
    drop(rec);
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, out).map_err(|e| Error::write(out, e))?;
    Ok(report)
}

struct Recorder<'a> {
    ds: &'a Dataset,
    clip: &'a Clip,
    rec: &'a rerun::RecordingStream,
    report: &'a mut RerunReport,
}

impl Recorder<'_> {
    fn log<A: ?Sized + rerun::AsComponents>(&mut self, path: &str, what: &A) -> Result<(), Error> {
        self.rec.log(path, what).map_err(|e| failed(path, e))?;
        *self.report.rows.entry(path.to_owned()).or_default() += 1;
        Ok(())
    }

    fn log_static<A: ?Sized + rerun::AsComponents>(&mut self, path: &str, what: &A) -> Result<(), Error> {
        self.rec.log_static(path, what).map_err(|e| failed(path, e))
    }

    fn record(mut self) -> Result<(), Error> {
        let (ds, clip) = (self.ds, self.clip);
        self.log_static("world", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
        let mounts = ds.sensor_mounts(clip)?;
        let rendered = |s: &str| ds.manifest.sensors.get(s).is_some_and(|v| v.starts_with("rendered"));
        // PNG or JPEG frames go in as they are; an H.264 dataset's recording has no camera image (its depth,
        // masks, boxes and LiDAR still do).
        let rgb_ext = super::image_frames(ds, super::LinkMode::Hard, "Rerun")
            .ok()
            .flatten()
            .map(|(ext, _)| ext);
        let depth_mm =
            rendered("depth") && ds.spec.output.depth_encoding == crate::spec::types::DepthEncoding::MillimetresU16;
        let (w, h) = (ds.spec.sensors.rgb.width_px, ds.spec.sensors.rgb.height_px);
        if let Some(camera) = mounts.get("camera") {
            let ego_from_optical =
                DAffine3::from_mat3_translation(camera.matrix3 * SENSOR_FROM_OPTICAL, camera.translation);
            self.log_static("world/ego/camera", &transform(&ego_from_optical))?;
            let focal = crate::sim::rig::Camera::from_spec(&ds.spec.sensors.rgb).focal_px as f32;
            self.log_static(
                "world/ego/camera/image",
                &rerun::Pinhole::from_focal_length_and_resolution([focal, focal], [w as f32, h as f32]),
            )?;
            let person = ClassDescription {
                info: AnnotationInfo::from((1, "person")),
                keypoint_annotations: COCO17
                    .iter()
                    .enumerate()
                    .map(|(k, name)| AnnotationInfo::from((k as u16, *name)))
                    .collect(),
                keypoint_connections: super::coco::SKELETON
                    .iter()
                    .map(|&[a, b]| KeypointPair::from((u16::from(a) - 1, u16::from(b) - 1)))
                    .collect(),
            };
            self.log_static(
                "world/ego/camera/image/keypoints",
                &rerun::AnnotationContext::new([person]),
            )?;
        }
        let lidar = mounts.get("lidar").copied();
        if let Some(l) = &lidar {
            self.log_static("world/ego/lidar", &transform(l))?;
        }
        let mut points = if lidar.is_some() {
            lidar_points(ds, &clip.clip_id)?
        } else {
            BTreeMap::new()
        };
        // Annotations by frame.
        // The traffic by frame (ground point, yaw, label), grouped once.
        let mut vehicles: BTreeMap<u32, Vec<(DVec3, f64, String)>> = BTreeMap::new();
        for v in &clip.vehicles {
            vehicles.entry(v.frame).or_default().push((
                DVec3::new(v.x_m, v.y_m, v.z_m),
                v.yaw_rad,
                format!("{} {}", v.kind, v.vehicle),
            ));
        }
        let mut cyclists: BTreeMap<u32, Vec<(DVec3, f64, String)>> = BTreeMap::new();
        for c in &clip.cyclists {
            cyclists.entry(c.frame).or_default().push((
                DVec3::new(c.x_m, c.y_m, c.z_m),
                c.yaw_rad,
                format!("cyclist {}", c.cyclist),
            ));
        }
        let mut by_frame: BTreeMap<u32, Vec<(u32, &super::dataset::AnnotatedFrame)>> = BTreeMap::new();
        for p in clip.pedestrians.values() {
            for a in &p.frames {
                by_frame.entry(a.frame).or_default().push((p.id, a));
            }
        }
        let frames = u32::try_from(clip.ego.len()).unwrap_or(0).min(clip.frame_count);
        for f in 0..frames {
            self.rec.set_time_sequence("frame", i64::from(f));
            self.rec
                .set_duration_secs("time", f64::from(f) / f64::from(clip.fps.max(1)));
            let e = &clip.ego[f as usize];
            let world_from_ego =
                crate::sim::rig::world_from_vehicle(DVec3::new(e.x_m, e.y_m, e.z_m), e.yaw_rad, e.pitch_rad);
            self.log("world/ego", &transform(&world_from_ego))?;
            self.log("timeseries/ego/speed_mps", &rerun::Scalars::new([e.speed_mps]))?;
            if let Some(ext) = rgb_ext {
                let path = ds.layout.sensor_frame("rgb", &clip.clip_id, f, ext);
                if let Ok(bytes) = std::fs::read(&path) {
                    self.log(
                        "world/ego/camera/image/rgb",
                        &rerun::EncodedImage::from_file_contents(bytes),
                    )?;
                }
            }
            if depth_mm {
                let path = ds.layout.sensor_frame("depth", &clip.clip_id, f, "png");
                if let Ok(bytes) = std::fs::read(&path) {
                    self.log(
                        "world/ego/camera/image/depth",
                        &rerun::EncodedDepthImage::from_file_contents(bytes).with_meter(1000.0),
                    )?;
                }
            }
            if rendered("instance") {
                let path = ds.layout.sensor_frame("instance", &clip.clip_id, f, "png");
                if path.is_file() {
                    let (iw, ih, ids) = crate::dataset::read::preview::read_u16_png(&path)?;
                    let bytes: Vec<u8> = ids.iter().flat_map(|v| v.to_le_bytes()).collect();
                    let format = rerun::ImageFormat::segmentation([iw as u32, ih as u32], rerun::ChannelDatatype::U16);
                    self.log(
                        "world/ego/camera/image/instance",
                        &rerun::SegmentationImage::new(bytes, format),
                    )?;
                }
            }
            let anns = by_frame.remove(&f).unwrap_or_default();
            if !anns.is_empty() {
                self.pedestrians(f, &anns)?;
            }
            let vehicles = vehicles.remove(&f).unwrap_or_default();
            let size = (
                crate::sim::VEHICLE_LENGTH_M,
                crate::sim::VEHICLE_WIDTH_M,
                crate::sim::VEHICLE_HEIGHT_M,
            );
            self.traffic("world/vehicles", &vehicles, size, rerun::Color::from_rgb(250, 210, 40))?;
            let cyclists = cyclists.remove(&f).unwrap_or_default();
            let size = (
                crate::sim::BICYCLE_LENGTH_M,
                crate::sim::BICYCLE_WIDTH_M,
                crate::sim::BICYCLE_HEIGHT_M,
            );
            self.traffic("world/cyclists", &cyclists, size, rerun::Color::from_rgb(80, 160, 250))?;
            if let Some(pts) = points.remove(&f) {
                let positions: Vec<[f32; 3]> = pts.iter().map(|p| [p.0[0], -p.0[1], p.0[2]]).collect();
                let colours: Vec<rerun::Color> = pts
                    .iter()
                    .map(|p| {
                        let [r, g, b] = crate::sensors::scene::tag::PALETTE
                            .get(usize::from(p.1))
                            .copied()
                            .unwrap_or([255, 255, 255]);
                        rerun::Color::from_rgb(r, g, b)
                    })
                    .collect();
                self.log(
                    "world/ego/lidar/points",
                    &rerun::Points3D::new(positions).with_colors(colours).with_radii([0.03]),
                )?;
            }
        }
        self.report.frames = frames;
        Ok(())
    }

    /// The annotated pedestrians of frame `f`: 2D boxes, keypoints, 3D boxes, states and TTE.
    fn pedestrians(&mut self, f: u32, anns: &[(u32, &super::dataset::AnnotatedFrame)]) -> Result<(), Error> {
        let colours: Vec<rerun::Color> = anns.iter().map(|(_, a)| crossing_colour(a.crossing)).collect();
        let labels: Vec<String> = anns.iter().map(|(id, a)| format!("{id} {}", a.state)).collect();
        let boxes = rerun::Boxes2D::from_mins_and_sizes(
            anns.iter().map(|(_, a)| (a.bbox_px[0], a.bbox_px[1])),
            anns.iter()
                .map(|(_, a)| (a.bbox_px[2] - a.bbox_px[0], a.bbox_px[3] - a.bbox_px[1])),
        )
        .with_colors(colours.clone())
        .with_labels(labels.clone());
        self.log("world/ego/camera/image/boxes", &boxes)?;
        for (id, a) in anns {
            let (mut positions, mut ids) = (Vec::new(), Vec::new());
            let (coco, _) = super::coco::coco_keypoints(&a.keypoints);
            for (k, kp) in coco.chunks_exact(3).enumerate() {
                if kp[2] >= 1.0 {
                    positions.push([kp[0], kp[1]]);
                    ids.push(k as u16);
                }
            }
            let n = ids.len();
            self.log(
                &format!("world/ego/camera/image/keypoints/{id}"),
                &rerun::Points2D::new(positions)
                    .with_keypoint_ids(ids)
                    .with_class_ids(std::iter::repeat_n(1u16, n))
                    .with_radii([2.0]),
            )?;
            let state = PedState::ALL.iter().position(|s| s.name() == a.state).unwrap_or(0);
            self.log(
                &format!("timeseries/pedestrian_{id}/state"),
                &rerun::Scalars::new([state as f64]),
            )?;
            let p = &self.clip.pedestrians[id];
            if let Some(tte) = p.first_crossing_frame.and_then(|c| c.checked_sub(f)) {
                self.log(
                    &format!("timeseries/pedestrian_{id}/tte_frames"),
                    &rerun::Scalars::new([f64::from(tte)]),
                )?;
            }
        }
        let boxes3d = rerun::Boxes3D::from_centers_and_sizes(
            anns.iter().map(|(_, a)| (a.box3d_m[0], a.box3d_m[1], a.box3d_m[2])),
            anns.iter().map(|(_, a)| (a.box3d_m[3], a.box3d_m[4], a.box3d_m[5])),
        )
        .with_quaternions(anns.iter().map(|(_, a)| yaw_quaternion(f64::from(a.yaw_rad))))
        .with_colors(colours)
        .with_labels(labels);
        self.log("world/pedestrians", &boxes3d)
    }

    /// Boxes of one kind of traffic in one frame: ground points, yaws and labels, all of one size and colour.
    fn traffic(
        &mut self,
        path: &str,
        items: &[(DVec3, f64, String)],
        (l, w, h): (f64, f64, f64),
        colour: rerun::Color,
    ) -> Result<(), Error> {
        if items.is_empty() {
            return Ok(());
        }
        let boxes = rerun::Boxes3D::from_centers_and_sizes(
            items
                .iter()
                .map(|(g, _, _)| (g.x as f32, g.y as f32, (g.z + 0.5 * h) as f32)),
            items.iter().map(|_| (l as f32, w as f32, h as f32)),
        )
        .with_quaternions(items.iter().map(|&(_, yaw, _)| yaw_quaternion(yaw)))
        .with_colors([colour])
        .with_labels(items.iter().map(|(_, _, label)| label.clone()));
        self.log(path, &boxes)
    }
}

/// LiDAR points by frame: CARLA's sensor frame (x forward, y right, z up) and the tag.
type TaggedPoints = BTreeMap<u32, Vec<([f32; 3], u8)>>;

/// A clip's LiDAR points (the seed's `.bin` layout has no tags: 0).
fn lidar_points(ds: &Dataset, clip: &str) -> Result<TaggedPoints, Error> {
    let mut out = TaggedPoints::new();
    let parquet = ds.layout.sensor_clip("lidar", clip, "parquet");
    if parquet.is_file() {
        for b in read_tables::read(&parquet, &["frame", "x", "y", "z", "tag"])? {
            let (f, t) = (b.u32s("frame")?, b.u8s("tag")?);
            let (x, y, z) = (b.f32s("x")?, b.f32s("y")?, b.f32s("z")?);
            for r in 0..b.rows() {
                out.entry(f.value(r))
                    .or_default()
                    .push(([x.value(r), y.value(r), z.value(r)], t.value(r)));
            }
        }
    } else {
        let frames: std::collections::BTreeSet<u32> =
            (0..ds.clips.iter().find(|c| c.clip_id == clip).map_or(0, |c| c.frame_count)).collect();
        for (f, pts) in super::nuscenes::lidar_points_xyzi(ds, clip, &frames)? {
            out.insert(f, pts.into_iter().map(|p| ([p[0], p[1], p[2]], 0)).collect());
        }
    }
    Ok(out)
}
