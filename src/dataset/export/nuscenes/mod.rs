//! `pedsynth export nuscenes`: nuScenes' layout, as `nuscenes-devkit`'s `NuScenes(version=..., dataroot=...)`
//! reads it, for 3D detection, tracking and prediction.
//!
//! One scene (and one log) per clip; keyframes (`sample`s) every `round(fps / keyframe_hz)` frames from frame 0
//! (2 Hz by default, as nuScenes); `CAM_FRONT` is every RGB frame (keyframes under `samples/`, the others under
//! `sweeps/`, linked from `sensors/rgb`); `LIDAR_TOP` is each keyframe's tick and the tick before it (a tick
//! covers 240° of azimuth at the defaults, so the devkit's `nsweeps=2` sees all around), as nuScenes'
//! `.pcd.bin` (float32 x, y, z, intensity, ring). Boxes (`sample_annotation`) at keyframes: the pedestrians the
//! dataset annotates (its camera visibility gate), and the traffic vehicles and cyclists within
//! [`ANNOTATION_RANGE_M`] of the ego. The global frame is the world's, shifted per town so that the town's map
//! mask (`maps/<town>.png`, 0.1 m a pixel) starts at (0, 0). DATASET.md ("`nuscenes`") documents every mapping.

mod lidar;
pub mod tables;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use glam::{DAffine3, DMat3, DQuat, DVec2, DVec3};

use super::dataset::{Clip, Dataset, SENSOR_FROM_OPTICAL};
use super::{LinkMode, link_file, write_file};
use crate::error::{Error, code};
use crate::sim::rig::world_from_vehicle;
#[cfg(feature = "rerun")]
pub(crate) use lidar::read_points as lidar_points_xyzi;
use lidar::{read_points, ring};
use tables::{CAM_FRONT, LIDAR_TOP, token};

/// The version name: the folder of the JSON tables (`NuScenes(version=VERSION, ...)`).
pub const VERSION: &str = "v1.0-pedsynth";
/// Traffic vehicles and cyclists are annotated within this plan-view distance of the ego, metres.
pub const ANNOTATION_RANGE_M: f64 = 100.0;
/// Map mask resolution (the devkit's default `map_resolution`), metres per pixel.
const MAP_M_PER_PX: f64 = 0.1;
/// Margin of the map mask around the town's bounds, metres.
const MAP_MARGIN_M: f64 = 50.0;
/// The largest map mask side, pixels (2 km at 0.1 m).
const MAP_MAX_SIDE_PX: usize = 20_000;
/// A cyclist's box height, metres (the occlusion box of the simulation).
const BICYCLE_HEIGHT_M: f64 = crate::sim::BICYCLE_HEIGHT_M;

/// What an export wrote.
#[derive(Debug, Default)]
pub struct NuscenesReport {
    pub scenes: usize,
    pub samples: usize,
    pub sample_data: usize,
    pub annotations: usize,
    pub instances: usize,
    pub images: usize,
    pub lidar_files: usize,
    pub maps: usize,
    /// Frames between keyframes.
    pub keyframe_step: u32,
    pub images_note: String,
}

fn refuse(msg: String) -> Error {
    Error::new(code::DATASET_INVALID, msg)
}

/// All records, in the order they are written.
#[derive(Default)]
struct Db {
    log: Vec<tables::Log>,
    scene: Vec<tables::Scene>,
    sample: Vec<tables::Sample>,
    sample_data: Vec<tables::SampleData>,
    ego_pose: Vec<tables::EgoPose>,
    calibrated_sensor: Vec<tables::CalibratedSensor>,
    instance: Vec<tables::Instance>,
    sample_annotation: Vec<tables::SampleAnnotation>,
}

/// A town's map: where the global frame's origin is in the world, and the mask's size.
struct TownMap {
    origin: DVec2,
    size_px: (usize, usize),
    logs: Vec<String>,
}

/// `[w, x, y, z]` of a rotation, with w ≥ 0.
fn quat(m: DMat3) -> [f64; 4] {
    let q = DQuat::from_mat3(&m).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    [q.w, q.x, q.y, q.z]
}

fn xyz(v: DVec3) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Frames between keyframes for a clip at `fps`.
pub fn keyframe_step(fps: u32, keyframe_hz: f64) -> u32 {
    ((f64::from(fps) / keyframe_hz).round() as u32).max(1)
}

/// Microseconds of simulated time of `frame` (the tables' `timestamp_ns`, floored to µs).
fn timestamp_us(frame: u32, fps: u32) -> u64 {
    u64::from(frame) * 1_000_000_000 / u64::from(fps.max(1)) / 1000
}

/// Writes nuScenes' layout of `ds` into `out`.
pub fn export(ds: &Dataset, out: &Path, link: LinkMode, keyframe_hz: f64) -> Result<NuscenesReport, Error> {
    if !(keyframe_hz.is_finite() && keyframe_hz > 0.0) {
        return Err(Error::new(
            code::EXPORT_OPTIONS,
            format!("--keyframe-hz {keyframe_hz}: a rate above 0 Hz, such as 2 (nuScenes' own)"),
        ));
    }
    let frames = super::image_frames(ds, link, "nuScenes")?;
    let with_camera = frames.is_some();
    if with_camera && !ds.spec.sensors.rgb.distortion.is_zero() {
        return Err(refuse(format!(
            "{}: the camera has lens distortion (sensors.rgb.distortion), and nuScenes' CAM_FRONT is a pinhole \
             (camera_intrinsic only): the devkit would project boxes and points to the wrong pixels. Generate \
             with sensors.rgb.distortion unset for nuScenes",
            ds.layout.root().display()
        )));
    }
    let rendered = |s: &str| ds.manifest.sensors.get(s).is_some_and(|v| v.starts_with("rendered"));
    let with_lidar = rendered("lidar");
    if !with_camera && !with_lidar {
        return Err(refuse(format!(
            "{}: nuScenes samples need CAM_FRONT or LIDAR_TOP, and the dataset has neither an RGB stream nor a \
             LiDAR: generate it with sensors.rgb or sensors.lidar enabled",
            ds.layout.root().display()
        )));
    }
    let mut notes = Vec::new();
    let ext = match &frames {
        Some((ext, note)) => {
            notes.push(format!("CAM_FRONT {note}"));
            *ext
        }
        None => {
            notes.push("no CAM_FRONT (the dataset has no PNG or JPEG RGB stream)".to_owned());
            "png"
        }
    };
    if !with_lidar {
        notes.push("no LIDAR_TOP (the dataset has no LiDAR)".to_owned());
    }
    let mut warn = |_: String| {};
    let towns = super::towns(ds, &mut warn);
    let mut maps: BTreeMap<String, TownMap> = BTreeMap::new();
    for info in &ds.clips {
        if maps.contains_key(&info.town) {
            continue;
        }
        let town = towns.get(&info.town).ok_or_else(|| {
            refuse(format!(
                "town `{}` cannot be loaded (an OpenDRIVE map must be where the dataset's spec says, relative to \
                 {}): nuScenes needs each log's map",
                info.town,
                ds.layout.root().display()
            ))
        })?;
        let (lo, hi) = town.network.bounds;
        let origin = (lo - DVec2::splat(MAP_MARGIN_M)).floor();
        let ext = (hi + DVec2::splat(MAP_MARGIN_M) - origin) / MAP_M_PER_PX;
        let size_px = (ext.x.ceil().max(1.0) as usize, ext.y.ceil().max(1.0) as usize);
        if size_px.0 > MAP_MAX_SIDE_PX || size_px.1 > MAP_MAX_SIDE_PX {
            return Err(refuse(format!(
                "town `{}` spans {:.0} m × {:.0} m: its map mask at {MAP_M_PER_PX} m a pixel would exceed \
                 {MAP_MAX_SIDE_PX} pixels a side",
                info.town,
                hi.x - lo.x,
                hi.y - lo.y
            )));
        }
        maps.insert(
            info.town.clone(),
            TownMap {
                origin,
                size_px,
                logs: Vec::new(),
            },
        );
    }
    let camera = crate::sim::rig::Camera::from_spec(&ds.spec.sensors.rgb);
    let intrinsic = vec![
        [camera.focal_px, 0.0, f64::from(camera.width_px) * 0.5],
        [0.0, camera.focal_px, f64::from(camera.height_px) * 0.5],
        [0.0, 0.0, 1.0],
    ];
    let mut db = Db::default();
    let mut report = NuscenesReport::default();
    let mut splits: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let progress = super::progress(ds.clips.len());
    for info in &ds.clips {
        let clip = ds.load(info)?;
        let map = maps
            .get_mut(&clip.town)
            .expect("every clip's town has a map (checked above)");
        let step = keyframe_step(clip.fps, keyframe_hz);
        report.keyframe_step = step;
        let scene = ClipExport {
            ds,
            clip: &clip,
            origin: map.origin,
            step,
            out,
            link,
            ext,
        };
        let log_token = token(&["log", &clip.clip_id]);
        map.logs.push(log_token.clone());
        splits.entry(clip.split.clone()).or_default().push(clip.clip_id.clone());
        scene.write(&mut db, &mut report, (with_camera, with_lidar), &intrinsic)?;
        db.log.push(tables::Log {
            token: log_token,
            logfile: clip.clip_id.clone(),
            vehicle: "pedsynth-ego",
            date_captured: "1970-01-01",
            location: clip.town.clone(),
            weather: clip.weather.clone(),
        });
        progress.clip_done(&clip.clip_id, u64::from(clip.frame_count));
    }
    progress.finish();
    let mut map_records = Vec::new();
    for (town, map) in &maps {
        let png = towns[town]
            .network
            .surface_mask_png(map.origin, MAP_M_PER_PX, map.size_px);
        let filename = format!("maps/{town}.png");
        write_file(&out.join(&filename), &png)?;
        map_records.push(tables::Map {
            token: token(&["map", town]),
            log_tokens: map.logs.clone(),
            category: "semantic_prior",
            filename,
            world_origin_m: [map.origin.x, map.origin.y],
        });
    }
    report.maps = map_records.len();
    report.scenes = db.scene.len();
    report.samples = db.sample.len();
    report.sample_data = db.sample_data.len();
    report.annotations = db.sample_annotation.len();
    report.instances = db.instance.len();
    let dir = out.join(VERSION);
    let json = |name: &str, value: &dyn erased::Json| -> Result<(), Error> {
        let bytes = value.to_json().map_err(|e| refuse(format!("nuScenes JSON: {e}")))?;
        write_file(&dir.join(format!("{name}.json")), &bytes)
    };
    json("category", &tables::categories())?;
    json("attribute", &tables::attributes())?;
    json("visibility", &tables::visibilities())?;
    json("sensor", &tables::sensors())?;
    json("calibrated_sensor", &db.calibrated_sensor)?;
    json("ego_pose", &db.ego_pose)?;
    json("log", &db.log)?;
    json("scene", &db.scene)?;
    json("sample", &db.sample)?;
    json("sample_data", &db.sample_data)?;
    json("instance", &db.instance)?;
    json("sample_annotation", &db.sample_annotation)?;
    json("map", &map_records)?;
    json("splits", &splits)?;
    report.images_note = notes.join("; ");
    Ok(report)
}

/// `&dyn` JSON for the tables' different record types.
mod erased {
    pub(super) trait Json {
        fn to_json(&self) -> serde_json::Result<Vec<u8>>;
    }
    impl<T: serde::Serialize> Json for T {
        fn to_json(&self) -> serde_json::Result<Vec<u8>> {
            serde_json::to_vec(self)
        }
    }
}

/// One clip on its way to a scene.
struct ClipExport<'a> {
    ds: &'a Dataset,
    clip: &'a Clip,
    origin: DVec2,
    step: u32,
    out: &'a Path,
    link: LinkMode,
    ext: &'static str,
}

/// A 3D box at a keyframe, in the world.
struct Box3 {
    /// (kind order, id): pedestrians 0, vehicles 1, cyclists 2, parked cars 3.
    key: (u8, u32),
    centre: DVec3,
    /// Length (along the yaw), width, height, metres.
    size: DVec3,
    yaw_rad: f64,
    category: &'static str,
    attribute: &'static str,
    occlusion: Option<f32>,
    crossing: Option<bool>,
    state: Option<String>,
    tte_frames: Option<Option<u32>>,
}

impl Box3 {
    /// Whether a world point lies in the box (its faces included).
    fn contains(&self, p: DVec3) -> bool {
        let d = p - self.centre;
        let (s, c) = self.yaw_rad.sin_cos();
        let along = c * d.x + s * d.y;
        let across = -s * d.x + c * d.y;
        along.abs() <= 0.5 * self.size.x && across.abs() <= 0.5 * self.size.y && d.z.abs() <= 0.5 * self.size.z
    }
}

const KIND_NAMES: [&str; 4] = ["pedestrian", "vehicle", "cyclist", "parked_car"];

impl ClipExport<'_> {
    fn id(&self) -> &str {
        &self.clip.clip_id
    }

    fn world_from_ego(&self, frame: u32) -> DAffine3 {
        let e = &self.clip.ego[frame as usize];
        world_from_vehicle(DVec3::new(e.x_m, e.y_m, e.z_m), e.yaw_rad, e.pitch_rad)
    }

    fn to_global(&self, world: DVec3) -> DVec3 {
        world - self.origin.extend(0.0)
    }

    fn write(
        &self,
        db: &mut Db,
        report: &mut NuscenesReport,
        (with_camera, with_lidar): (bool, bool),
        intrinsic: &[[f64; 3]],
    ) -> Result<(), Error> {
        let clip = self.clip;
        let n = u32::try_from(clip.ego.len()).unwrap_or(0).min(clip.frame_count);
        if n == 0 {
            return Err(refuse(format!("clip `{}`: no frames", self.id())));
        }
        let keyframes: Vec<u32> = (0..n).step_by(self.step as usize).collect();
        let sample_token = |f: u32| token(&["sample", self.id(), &f.to_string()]);
        let scene_token = token(&["scene", self.id()]);
        for (k, &f) in keyframes.iter().enumerate() {
            db.sample.push(tables::Sample {
                token: sample_token(f),
                timestamp: timestamp_us(f, clip.fps),
                prev: if k > 0 {
                    sample_token(keyframes[k - 1])
                } else {
                    String::new()
                },
                next: keyframes.get(k + 1).map(|&g| sample_token(g)).unwrap_or_default(),
                scene_token: scene_token.clone(),
            });
        }
        db.scene.push(tables::Scene {
            token: scene_token,
            log_token: token(&["log", self.id()]),
            nbr_samples: keyframes.len(),
            first_sample_token: sample_token(keyframes[0]),
            last_sample_token: sample_token(*keyframes.last().expect("frame 0 is a keyframe")),
            name: self.id().to_owned(),
            description: format!("{}, {}, {} split", clip.town, clip.weather, clip.split),
        });
        // The sample a sweep belongs to: the latest keyframe at or before it.
        let sample_of = |f: u32| sample_token(f - f % self.step);
        let mounts = self.ds.sensor_mounts(self.clip)?;
        if with_camera {
            let ego_from_sensor = *mounts.get("camera").ok_or_else(|| self.no_pose("camera"))?;
            let ego_from_optical = ego_from_sensor.matrix3 * SENSOR_FROM_OPTICAL;
            let calibrated = self.calibrated(db, CAM_FRONT, ego_from_sensor.translation, ego_from_optical, intrinsic);
            let mut frames = Vec::new();
            for f in 0..n {
                let from = self.ds.layout.sensor_frame("rgb", self.id(), f, self.ext);
                if !from.exists() {
                    continue;
                }
                let filename = self.filename(f, CAM_FRONT, self.ext, f % self.step == 0);
                let to = self.out.join(&filename);
                if let Some(dir) = to.parent() {
                    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
                }
                link_file(&from, &to, self.link)?;
                report.images += 1;
                frames.push((f, filename));
            }
            let (w, h) = (self.ds.spec.sensors.rgb.width_px, self.ds.spec.sensors.rgb.height_px);
            self.sample_data(db, CAM_FRONT, &calibrated, &frames, (self.ext, w, h), &sample_of);
        }
        let boxes: BTreeMap<u32, Vec<Box3>> = keyframes.iter().map(|&f| (f, self.boxes(f))).collect();
        let mut lidar_counts: BTreeMap<(u32, usize), u32> = BTreeMap::new();
        if with_lidar {
            let ego_from_lidar = *mounts.get("lidar").ok_or_else(|| self.no_pose("lidar"))?;
            let calibrated = self.calibrated(db, LIDAR_TOP, ego_from_lidar.translation, ego_from_lidar.matrix3, &[]);
            let mut wanted = BTreeSet::new();
            for &k in &keyframes {
                if k > 0 {
                    wanted.insert(k - 1);
                }
                wanted.insert(k);
            }
            let points = read_points(self.ds, self.id(), &wanted)?;
            let lidar = &self.ds.spec.sensors.lidar;
            let mut frames = Vec::new();
            for &f in &wanted {
                let pts = points.get(&f).map_or(&[][..], Vec::as_slice);
                let key = f % self.step == 0;
                let filename = self.filename(f, LIDAR_TOP, "pcd.bin", key);
                let mut bytes = Vec::with_capacity(pts.len() * 20);
                for p in pts {
                    let ring = ring(lidar, p[0], -p[1], p[2]);
                    for v in [p[0], -p[1], p[2], p[3], ring] {
                        bytes.extend_from_slice(&v.to_le_bytes());
                    }
                }
                write_file(&self.out.join(&filename), &bytes)?;
                report.lidar_files += 1;
                if key {
                    // Each point into the world once, then counted against every box of the keyframe.
                    let world_from_lidar = self.world_from_ego(f) * ego_from_lidar;
                    let world: Vec<DVec3> = pts
                        .iter()
                        .map(|p| {
                            let local = DVec3::new(f64::from(p[0]), -f64::from(p[1]), f64::from(p[2]));
                            world_from_lidar.transform_point3(local)
                        })
                        .collect();
                    for (b, bx) in boxes[&f].iter().enumerate() {
                        let count = world.iter().filter(|&&w| bx.contains(w)).count();
                        lidar_counts.insert((f, b), count as u32);
                    }
                }
                frames.push((f, filename));
            }
            self.sample_data(db, LIDAR_TOP, &calibrated, &frames, ("pcd", 0, 0), &sample_of);
        }
        self.annotations(db, &boxes, &lidar_counts, &sample_token);
        Ok(())
    }

    fn no_pose(&self, sensor: &str) -> Error {
        refuse(format!(
            "clip `{}`: the sensor_poses table has no `{sensor}` row at frame 0",
            self.id()
        ))
    }

    /// `samples/<channel>/<clip>__<channel>__<µs>.<ext>` for a keyframe, `sweeps/...` otherwise.
    fn filename(&self, frame: u32, channel: &str, ext: &str, key: bool) -> String {
        format!(
            "{}/{channel}/{}__{channel}__{:016}.{ext}",
            if key { "samples" } else { "sweeps" },
            self.id(),
            timestamp_us(frame, self.clip.fps)
        )
    }

    fn calibrated(
        &self,
        db: &mut Db,
        channel: &str,
        translation: DVec3,
        rotation: DMat3,
        intrinsic: &[[f64; 3]],
    ) -> String {
        let t = token(&["calibrated_sensor", self.id(), channel]);
        db.calibrated_sensor.push(tables::CalibratedSensor {
            token: t.clone(),
            sensor_token: token(&["sensor", channel]),
            translation: xyz(translation),
            rotation: quat(rotation),
            camera_intrinsic: intrinsic.to_vec(),
        });
        t
    }

    /// A channel's `sample_data` (and `ego_pose`) records for `frames` (in time order, with their files).
    fn sample_data(
        &self,
        db: &mut Db,
        channel: &str,
        calibrated: &str,
        frames: &[(u32, String)],
        (fileformat, width, height): (&'static str, u32, u32),
        sample_of: &dyn Fn(u32) -> String,
    ) {
        let sd_token = |f: u32| token(&["sample_data", self.id(), channel, &f.to_string()]);
        for (k, (f, filename)) in frames.iter().enumerate() {
            let (f, t) = (*f, sd_token(*f));
            let timestamp = timestamp_us(f, self.clip.fps);
            let world_from_ego = self.world_from_ego(f);
            db.ego_pose.push(tables::EgoPose {
                token: t.clone(),
                timestamp,
                rotation: quat(world_from_ego.matrix3),
                translation: xyz(self.to_global(world_from_ego.translation)),
            });
            db.sample_data.push(tables::SampleData {
                token: t.clone(),
                sample_token: sample_of(f),
                ego_pose_token: t,
                calibrated_sensor_token: calibrated.to_owned(),
                timestamp,
                fileformat,
                is_key_frame: f % self.step == 0,
                height,
                width,
                filename: filename.clone(),
                prev: if k > 0 {
                    sd_token(frames[k - 1].0)
                } else {
                    String::new()
                },
                next: frames.get(k + 1).map(|(g, _)| sd_token(*g)).unwrap_or_default(),
            });
        }
    }

    /// The boxes at keyframe `f`: the annotated pedestrians, then the vehicles, the parked cars and the cyclists
    /// within [`ANNOTATION_RANGE_M`] of the ego, each by id.
    fn boxes(&self, f: u32) -> Vec<Box3> {
        let clip = self.clip;
        let e = &clip.ego[f as usize];
        let near = |x: f64, y: f64| (x - e.x_m).hypot(y - e.y_m) <= ANNOTATION_RANGE_M;
        let mut out = Vec::new();
        for p in clip.pedestrians.values() {
            let Ok(i) = p.frames.binary_search_by_key(&f, |a| a.frame) else {
                continue;
            };
            let a = &p.frames[i];
            let b = a.box3d_m.map(f64::from);
            out.push(Box3 {
                key: (0, p.id),
                centre: DVec3::new(b[0], b[1], b[2]),
                size: DVec3::new(b[3], b[4], b[5]),
                yaw_rad: f64::from(a.yaw_rad),
                category: if p.body == "child" {
                    "human.pedestrian.child"
                } else {
                    "human.pedestrian.adult"
                },
                attribute: if a.action == "walking" {
                    "pedestrian.moving"
                } else {
                    "pedestrian.standing"
                },
                occlusion: Some(a.occlusion),
                crossing: Some(a.crossing),
                state: Some(a.state.clone()),
                tte_frames: Some(p.first_crossing_frame.and_then(|c| c.checked_sub(f))),
            });
        }
        for v in clip.vehicles.iter().filter(|v| v.frame == f && near(v.x_m, v.y_m)) {
            out.push(Box3 {
                key: (1, v.vehicle),
                centre: DVec3::new(v.x_m, v.y_m, v.z_m + 0.5 * crate::sim::VEHICLE_HEIGHT_M),
                size: DVec3::new(
                    crate::sim::VEHICLE_LENGTH_M,
                    crate::sim::VEHICLE_WIDTH_M,
                    crate::sim::VEHICLE_HEIGHT_M,
                ),
                yaw_rad: v.yaw_rad,
                category: match v.kind.as_str() {
                    "ambulance" => "vehicle.emergency.ambulance",
                    "police" => "vehicle.emergency.police",
                    "fire_truck" => "vehicle.truck",
                    _ => "vehicle.car",
                },
                attribute: if v.speed_mps.abs() >= 0.3 {
                    "vehicle.moving"
                } else {
                    "vehicle.stopped"
                },
                occlusion: None,
                crossing: None,
                state: None,
                tte_frames: None,
            });
        }
        for c in clip.parked_cars.iter().filter(|c| near(c.x_m, c.y_m)) {
            out.push(Box3 {
                key: (3, c.parked_car),
                centre: DVec3::new(c.x_m, c.y_m, c.z_m + 0.5 * c.size_m[2]),
                size: DVec3::from_array(c.size_m),
                yaw_rad: c.yaw_rad,
                category: "vehicle.car",
                attribute: "vehicle.parked",
                occlusion: None,
                crossing: None,
                state: None,
                tte_frames: None,
            });
        }
        for c in clip.cyclists.iter().filter(|c| c.frame == f && near(c.x_m, c.y_m)) {
            out.push(Box3 {
                key: (2, c.cyclist),
                centre: DVec3::new(c.x_m, c.y_m, c.z_m + 0.5 * BICYCLE_HEIGHT_M),
                size: DVec3::new(
                    crate::sim::BICYCLE_LENGTH_M,
                    crate::sim::BICYCLE_WIDTH_M,
                    BICYCLE_HEIGHT_M,
                ),
                yaw_rad: c.yaw_rad,
                category: "vehicle.bicycle",
                attribute: "cycle.with_rider",
                occlusion: c.occlusion,
                crossing: None,
                state: None,
                tte_frames: None,
            });
        }
        out
    }

    /// The `sample_annotation` and `instance` records of the clip's boxes, each instance's annotations linked
    /// in time order.
    fn annotations(
        &self,
        db: &mut Db,
        boxes: &BTreeMap<u32, Vec<Box3>>,
        lidar_counts: &BTreeMap<(u32, usize), u32>,
        sample_token: &dyn Fn(u32) -> String,
    ) {
        let instance_token =
            |key: (u8, u32)| token(&["instance", self.id(), KIND_NAMES[key.0 as usize], &key.1.to_string()]);
        let ann_token = |f: u32, key: (u8, u32)| {
            token(&[
                "sample_annotation",
                self.id(),
                KIND_NAMES[key.0 as usize],
                &key.1.to_string(),
                &f.to_string(),
            ])
        };
        let mut by_instance: BTreeMap<(u8, u32), Vec<u32>> = BTreeMap::new();
        for (&f, list) in boxes {
            for b in list {
                by_instance.entry(b.key).or_default().push(f);
            }
        }
        for (&f, list) in boxes {
            for (i, b) in list.iter().enumerate() {
                let frames = &by_instance[&b.key];
                let k = frames.binary_search(&f).expect("the box's own frame");
                db.sample_annotation.push(tables::SampleAnnotation {
                    token: ann_token(f, b.key),
                    sample_token: sample_token(f),
                    instance_token: instance_token(b.key),
                    visibility_token: tables::visibility_token(b.occlusion),
                    attribute_tokens: vec![token(&["attribute", b.attribute])],
                    translation: xyz(self.to_global(b.centre)),
                    size: [b.size.y, b.size.x, b.size.z],
                    rotation: quat(DMat3::from_rotation_z(b.yaw_rad)),
                    prev: if k > 0 {
                        ann_token(frames[k - 1], b.key)
                    } else {
                        String::new()
                    },
                    next: frames.get(k + 1).map(|&g| ann_token(g, b.key)).unwrap_or_default(),
                    num_lidar_pts: lidar_counts.get(&(f, i)).copied().unwrap_or(0),
                    num_radar_pts: 0,
                    crossing: b.crossing,
                    behaviour_state: b.state.clone(),
                    tte_frames: b.tte_frames,
                });
            }
        }
        for (key, frames) in &by_instance {
            let category = boxes[&frames[0]]
                .iter()
                .find(|b| b.key == *key)
                .map_or("vehicle.car", |b| b.category);
            db.instance.push(tables::Instance {
                token: instance_token(*key),
                category_token: token(&["category", category]),
                nbr_annotations: frames.len(),
                first_annotation_token: ann_token(frames[0], *key),
                last_annotation_token: ann_token(*frames.last().expect("an instance has an annotation"), *key),
                clip_id: self.id().to_owned(),
                kind: KIND_NAMES[key.0 as usize],
                id: key.1,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyframes_are_two_hertz_at_thirty_fps_and_every_frame_at_most() {
        assert_eq!(keyframe_step(30, 2.0), 15);
        assert_eq!(keyframe_step(20, 2.0), 10);
        assert_eq!(keyframe_step(30, 60.0), 1);
        assert_eq!(timestamp_us(15, 30), 500_000);
        assert_eq!(timestamp_us(1, 30), 33_333);
    }

    #[test]
    fn the_optical_frame_looks_along_the_sensors_x_with_its_y_down() {
        let m = SENSOR_FROM_OPTICAL;
        assert_eq!(m * DVec3::Z, DVec3::X);
        assert_eq!(m * DVec3::Y, -DVec3::Z);
        assert_eq!(m * DVec3::X, -DVec3::Y);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn boxes_contain_their_faces_and_not_beyond() {
        let b = Box3 {
            key: (0, 0),
            centre: DVec3::new(10.0, 5.0, 1.0),
            size: DVec3::new(0.8, 0.5, 1.8),
            yaw_rad: std::f64::consts::FRAC_PI_2,
            category: "human.pedestrian.adult",
            attribute: "pedestrian.moving",
            occlusion: None,
            crossing: None,
            state: None,
            tte_frames: None,
        };
        // Yaw 90°: the length runs along y.
        assert!(b.contains(DVec3::new(10.0, 5.39, 1.0)));
        assert!(!b.contains(DVec3::new(10.0, 5.41, 1.0)));
        assert!(b.contains(DVec3::new(10.24, 5.0, 1.89)));
        assert!(!b.contains(DVec3::new(10.26, 5.0, 1.0)));
        assert!(!b.contains(DVec3::new(10.0, 5.0, 1.91)));
    }
}
