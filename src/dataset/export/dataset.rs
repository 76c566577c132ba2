//! A finished dataset as the exporters see it: the manifest checked (every clip done, every table file's
//! blake3 as the manifest says), the resolved spec (camera, towns) and the tables an export needs, per clip.
//! Exporters read only this — never the simulator — so they work on any finished dataset.

use std::collections::BTreeMap;
use std::path::Path;

use arrow_array::Array;

use crate::dataset::read::tables;
use crate::dataset::write::{Layout, Manifest};
use crate::error::{Error, code};
use crate::spec::types::ExportBox;
use crate::spec::{LoadOptions, Spec};

/// One annotated pedestrian-frame.
#[derive(Clone, Debug)]
pub struct AnnotatedFrame {
    pub frame: u32,
    /// `[x_min, y_min, x_max, y_max]`, pixels: the tight box, or the annotator box where the spec's
    /// `annotations.export_box` says so.
    pub bbox_px: [f32; 4],
    /// Crossing label C.
    pub crossing: bool,
    pub state: String,
    /// Looks at the ego's camera (the table's `look`).
    pub look: bool,
    /// `walking` or `standing` (the table's `action`).
    pub action: String,
    /// `none`, `hand_ack`, `hand_yield` or `nod` (the table's `gesture`).
    pub gesture: String,
    /// `none`, `clear_path`, `speed_up` or `slow_down` (the table's `reaction`).
    pub reaction: String,
    pub occlusion: f32,
    /// Ground speed, m/s.
    pub speed_mps: f32,
    /// World ground position.
    pub x_m: f32,
    pub y_m: f32,
    /// Body yaw, radians.
    pub yaw_rad: f32,
    /// Ground distance from the ego, metres.
    pub distance_to_ego_m: f32,
    /// 3D box: centre (world) and length, width, height, metres.
    pub box3d_m: [f32; 6],
    /// Keypoints as written: 17 (COCO) or 18 (OpenPose) `u, v, flag` triplets.
    pub keypoints: Vec<f32>,
}

/// One pedestrian with its annotated frames (in frame order).
#[derive(Clone, Debug)]
pub struct Pedestrian {
    pub id: u32,
    pub age_group: String,
    pub gender: String,
    pub crosser: bool,
    pub intention_frame: Option<u32>,
    /// Crossing group within the clip.
    pub group_id: Option<u32>,
    /// Crossing behaviour (`normal`, `sudden`, ...).
    pub behaviour: String,
    /// First frame with C = 1, annotated or not.
    pub first_crossing_frame: Option<u32>,
    /// Body height, metres.
    pub height_m: f32,
    /// `adult`, `child` or `adult_with_child`.
    pub body: String,
    /// Wears a hat.
    pub headwear: bool,
    /// `trousers`, `skirt`, `dress` or `coat`.
    pub garment: String,
    /// `backpack`, `shoulder_bag`, or "" (nothing carried).
    pub carry: String,
    /// Holds an open umbrella.
    pub umbrella: bool,
    /// Wears a hood up.
    pub hood: bool,
    pub frames: Vec<AnnotatedFrame>,
}

/// One pedestrian in one frame (the `tracks` table: every frame, seen or not).
#[derive(Clone, Copy, Debug)]
pub struct TrackFrame {
    pub frame: u32,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub yaw_rad: f64,
}

/// The ego's state in one frame.
#[derive(Clone, Copy, Debug)]
pub struct EgoFrame {
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub yaw_rad: f64,
    /// Body pitch, nose up positive (the pitch wobble; 0 without it).
    pub pitch_rad: f64,
    pub speed_mps: f64,
    pub accel_mps2: f64,
}

/// One traffic vehicle in one frame.
#[derive(Clone, Debug)]
pub struct VehicleFrame {
    pub frame: u32,
    pub vehicle: u32,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub yaw_rad: f64,
    /// Speed along the heading, m/s.
    pub speed_mps: f64,
    /// `car`, `ambulance`, `fire_truck` or `police`.
    pub kind: String,
}

/// A cyclist in one frame: its pose, and its box of rider and bicycle where in view of the camera.
#[derive(Clone, Debug)]
pub struct CyclistFrame {
    pub frame: u32,
    pub cyclist: u32,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub yaw_rad: f64,
    /// Speed along the heading, m/s.
    pub speed_mps: f64,
    /// `[x1, y1, x2, y2]`, pixels.
    pub bbox: Option<[f64; 4]>,
    /// Share of the rider's sample points hidden from the camera; `None` when not in view.
    pub occlusion: Option<f32>,
    /// In view and passing the pedestrians' visibility gate (the table's `annotated`).
    pub annotated: bool,
    /// The rider's keypoints as written (`u, v, flag` triplets); empty when not in view.
    pub keypoints: Vec<f32>,
}

/// A clip's row of the `clips` table.
#[derive(Clone, Debug)]
pub struct ClipInfo {
    pub clip_id: String,
    pub town: String,
    pub weather: String,
    pub split: String,
    pub fps: u32,
    pub frame_count: u32,
    /// The clip's seed (what its per-clip camera mount is drawn from: `sim::rig::Camera::for_clip`).
    pub seed: u64,
    /// The clip's weather parameters (CARLA's units: degrees and percentages).
    pub sun_altitude_deg: f64,
    pub sun_azimuth_deg: f64,
    pub cloudiness_pct: f64,
    pub precipitation_pct: f64,
    pub fog_density_pct: f64,
    pub wetness_pct: f64,
    pub wind_intensity_pct: f64,
}

/// One clip's tables (its `clips` row through `Deref`).
#[derive(Clone, Debug)]
pub struct Clip {
    pub info: ClipInfo,
    /// Indexed by frame.
    pub ego: Vec<EgoFrame>,
    /// By pedestrian id.
    pub pedestrians: BTreeMap<u32, Pedestrian>,
    /// Sorted by (vehicle, frame).
    pub vehicles: Vec<VehicleFrame>,
    /// The cyclists in every frame, sorted by (cyclist, frame) (empty without cyclists, or for a dataset written
    /// before the `cyclists` table existed).
    pub cyclists: Vec<CyclistFrame>,
    /// Every pedestrian's track, by pedestrian id, in frame order (empty for a dataset written before the
    /// `tracks` table existed).
    pub tracks: BTreeMap<u32, Vec<TrackFrame>>,
    /// The `traffic_lights` rows, in (frame, light) order (empty without lights, or for a dataset written before
    /// the table existed).
    pub traffic_lights: Vec<LightFrame>,
    /// The `parked_cars` rows, by id (empty without parked cars, or for a dataset written before the table
    /// existed).
    pub parked_cars: Vec<ParkedCarRow>,
}

/// A row of the `parked_cars` table.
#[derive(Clone, Debug, PartialEq)]
pub struct ParkedCarRow {
    pub parked_car: u32,
    /// Centre of the ground footprint, world metres.
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub yaw_rad: f64,
    /// Length, width and height, metres.
    pub size_m: [f64; 3],
}

/// A row of the `traffic_lights` table.
#[derive(Clone, Debug, PartialEq)]
pub struct LightFrame {
    pub frame: u32,
    pub signal: String,
    /// `green`, `amber` or `red`.
    pub state: String,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub facing_rad: f64,
    pub faces_ego: bool,
}

impl std::ops::Deref for Clip {
    type Target = ClipInfo;

    fn deref(&self) -> &ClipInfo {
        &self.info
    }
}

/// A finished dataset: its clips' `clips` rows; the rest of a clip's tables is read when an exporter gets to
/// it ([`Dataset::load`]), so an export holds one clip at a time.
pub struct Dataset {
    pub layout: Layout,
    pub manifest: Manifest,
    pub spec: Spec,
    /// The clips, sorted by id.
    pub clips: Vec<ClipInfo>,
}

fn refuse(msg: String) -> Error {
    Error::new(code::DATASET_INVALID, msg)
}

/// Refuses a dataset that fails `verify`'s checks of its tables (everything but the sensor files' contents),
/// listing the problems.
pub fn refuse_unverified(dir: &Path) -> Result<(), Error> {
    let report = crate::dataset::verify::verify(dir, crate::dataset::verify::Depth::Tables)?;
    if report.problems.is_empty() {
        return Ok(());
    }
    let shown: Vec<String> = report.problems.iter().take(10).map(|p| format!("  {p}")).collect();
    let more = report.problems.len().saturating_sub(10);
    Err(refuse(format!(
        "{}: {} problem(s) (`pedsynth verify` lists them all):\n{}{}",
        dir.display(),
        report.problems.len(),
        shown.join("\n"),
        if more > 0 {
            format!("\n  ... and {more} more")
        } else {
            String::new()
        }
    )))
}

impl Dataset {
    /// Opens a dataset, refusing an unfinished or altered one.
    pub fn open(dir: &Path) -> Result<Dataset, Error> {
        let layout = Layout::new(dir);
        let path = layout.manifest();
        let text = std::fs::read_to_string(&path).map_err(|e| {
            refuse(format!(
                "{}: {e} (is {} a pedsynth dataset?)",
                path.display(),
                dir.display()
            ))
        })?;
        let manifest = Manifest::parse(&text, &path.display().to_string())?;
        refuse_unverified(dir)?;
        let spec_path = layout.spec_resolved();
        let bytes = std::fs::read(&spec_path).map_err(|e| refuse(format!("{}: {e}", spec_path.display())))?;
        let options = LoadOptions {
            overrides: Vec::new(),
            allow_large: true,
            profile: None,
        };
        let spec = crate::spec::load_bytes(&bytes, &spec_path.display().to_string(), dir, &options)
            .map_err(|e| refuse(format!("{}: not a valid spec: {e}", spec_path.display())))?
            .spec;
        let mut clips = Vec::with_capacity(manifest.clips.len());
        for c in &manifest.clips {
            clips.push(read_info(&layout, &c.clip_id)?);
        }
        clips.sort_by(|a, b| a.clip_id.cmp(&b.clip_id));
        Ok(Dataset {
            layout,
            manifest,
            spec,
            clips,
        })
    }
}

/// Rotation taking a camera's optical axes (x right, y down, z forward) to its sensor axes (x forward, y left,
/// z up).
pub const SENSOR_FROM_OPTICAL: glam::DMat3 = glam::DMat3::from_cols(
    glam::DVec3::new(0.0, -1.0, 0.0), // optical x (right) → sensor −y
    glam::DVec3::new(0.0, 0.0, -1.0), // optical y (down) → sensor −z
    glam::DVec3::new(1.0, 0.0, 0.0),  // optical z (forward) → sensor x
);

impl Dataset {
    /// Each sensor's pose on the ego (`ego_from_sensor`, sensor axes x forward, y left, z up), by sensor name
    /// (`camera`, `lidar`), from the `sensor_poses` table at frame 0 and the ego's pose there (mounts are rigid:
    /// the ego only moves and turns).
    pub fn sensor_mounts(&self, clip: &Clip) -> Result<BTreeMap<String, glam::DAffine3>, Error> {
        use glam::{DAffine3, DQuat, DVec3};
        let e = clip
            .ego
            .first()
            .ok_or_else(|| refuse(format!("clip `{}`: no frames", clip.clip_id)))?;
        let ego_from_world =
            crate::sim::rig::world_from_vehicle(DVec3::new(e.x_m, e.y_m, e.z_m), e.yaw_rad, e.pitch_rad).inverse();
        let mut out = BTreeMap::new();
        let cols = ["frame", "sensor", "x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"];
        for b in tables::read(&self.layout.table("sensor_poses", &clip.clip_id), &cols)? {
            let (f, s) = (b.u32s("frame")?, b.strings("sensor")?);
            let c = [b.f64s("x_m")?, b.f64s("y_m")?, b.f64s("z_m")?];
            let q = [b.f64s("qw")?, b.f64s("qx")?, b.f64s("qy")?, b.f64s("qz")?];
            for i in (0..b.rows()).filter(|&i| f.value(i) == 0) {
                let rot = DQuat::from_xyzw(q[1].value(i), q[2].value(i), q[3].value(i), q[0].value(i)).normalize();
                let at = DVec3::new(c[0].value(i), c[1].value(i), c[2].value(i));
                out.insert(
                    s[i].to_owned(),
                    ego_from_world * DAffine3::from_rotation_translation(rot, at),
                );
            }
        }
        Ok(out)
    }

    /// A clip's tables, with the 2D box `annotations.export_box` chooses as `bbox_px`.
    pub fn load(&self, info: &ClipInfo) -> Result<Clip, Error> {
        read_clip(&self.layout, info.clone(), self.spec.annotations.export_box)
    }
}

fn read_info(layout: &Layout, clip_id: &str) -> Result<ClipInfo, Error> {
    let file = layout.table("clips", clip_id);
    let mut clip = None;
    const WEATHER: [&str; 7] = [
        "sun_altitude_deg",
        "sun_azimuth_deg",
        "cloudiness_pct",
        "precipitation_pct",
        "fog_density_pct",
        "wetness_pct",
        "wind_intensity_pct",
    ];
    let mut cols = vec!["town", "weather", "split", "fps", "frame_count", "seed"];
    cols.extend(WEATHER);
    for b in tables::read(&file, &cols)? {
        let (town, weather, split) = (b.strings("town")?, b.strings("weather")?, b.strings("split")?);
        let (fps, frames, seed) = (b.u32s("fps")?, b.u32s("frame_count")?, b.u64s("seed")?);
        let w: Vec<_> = WEATHER.iter().map(|c| b.f64s(c)).collect::<Result<_, _>>()?;
        if b.rows() > 0 {
            clip = Some(ClipInfo {
                clip_id: clip_id.to_owned(),
                town: town[0].to_owned(),
                weather: weather[0].to_owned(),
                split: split[0].to_owned(),
                fps: fps.value(0),
                frame_count: frames.value(0),
                seed: seed.value(0),
                sun_altitude_deg: w[0].value(0),
                sun_azimuth_deg: w[1].value(0),
                cloudiness_pct: w[2].value(0),
                precipitation_pct: w[3].value(0),
                fog_density_pct: w[4].value(0),
                wetness_pct: w[5].value(0),
                wind_intensity_pct: w[6].value(0),
            });
        }
    }
    clip.ok_or_else(|| refuse(format!("{}: no row", file.display())))
}

fn read_clip(layout: &Layout, info: ClipInfo, export_box: ExportBox) -> Result<Clip, Error> {
    let boxes = match export_box {
        ExportBox::Tight => ["bbox_x_min", "bbox_y_min", "bbox_x_max", "bbox_y_max"],
        ExportBox::Annotator => [
            "annotator_x_min",
            "annotator_y_min",
            "annotator_x_max",
            "annotator_y_max",
        ],
    };
    let file = |t: &str| layout.table(t, &info.clip_id);
    let mut clip = Clip {
        info: info.clone(),
        ego: Vec::new(),
        pedestrians: BTreeMap::new(),
        vehicles: Vec::new(),
        cyclists: Vec::new(),
        tracks: BTreeMap::new(),
        traffic_lights: Vec::new(),
        parked_cars: Vec::new(),
    };
    let cols = [
        "frame",
        "ego_x_m",
        "ego_y_m",
        "ego_z_m",
        "ego_yaw_rad",
        "ego_pitch_rad",
        "ego_speed_mps",
        "ego_accel_mps2",
    ];
    for b in tables::read(&file("frames"), &cols)? {
        let f = b.u32s("frame")?;
        let v: Vec<_> = cols[1..].iter().map(|c| b.f64s(c)).collect::<Result<_, _>>()?;
        for i in 0..b.rows() {
            if f.value(i) as usize != clip.ego.len() {
                return Err(refuse(format!("{}: frames out of order", file("frames").display())));
            }
            clip.ego.push(EgoFrame {
                x_m: v[0].value(i),
                y_m: v[1].value(i),
                z_m: v[2].value(i),
                yaw_rad: v[3].value(i),
                pitch_rad: v[4].value(i),
                speed_mps: v[5].value(i),
                accel_mps2: v[6].value(i),
            });
        }
    }
    let cols = [
        "pedestrian",
        "age_group",
        "gender",
        "crosser",
        "intention_frame",
        "group_id",
        "behaviour",
        "first_crossing_frame",
        "height_m",
        "body",
        "headwear",
        "garment",
        "carry",
        "umbrella",
        "hood",
    ];
    for b in tables::read(&file("pedestrians"), &cols)? {
        let (id, age, gender) = (b.u32s("pedestrian")?, b.strings("age_group")?, b.strings("gender")?);
        let (crosser, intention, group) = (b.bools("crosser")?, b.u32s("intention_frame")?, b.u32s("group_id")?);
        let (behaviour, first_c) = (b.strings("behaviour")?, b.u32s("first_crossing_frame")?);
        let (height, body) = (b.f32s("height_m")?, b.strings("body")?);
        let (headwear, garment, carry) = (b.bools("headwear")?, b.strings("garment")?, b.strings("carry")?);
        let (umbrella, hood) = (b.bools("umbrella")?, b.bools("hood")?);
        for i in 0..b.rows() {
            clip.pedestrians.insert(
                id.value(i),
                Pedestrian {
                    id: id.value(i),
                    age_group: age[i].to_owned(),
                    gender: gender[i].to_owned(),
                    crosser: crosser.value(i),
                    intention_frame: (!intention.is_null(i)).then(|| intention.value(i)),
                    group_id: (!group.is_null(i)).then(|| group.value(i)),
                    behaviour: behaviour[i].to_owned(),
                    first_crossing_frame: (!first_c.is_null(i)).then(|| first_c.value(i)),
                    height_m: height.value(i),
                    body: body[i].to_owned(),
                    headwear: headwear.value(i),
                    garment: garment[i].to_owned(),
                    carry: carry[i].to_owned(),
                    umbrella: umbrella.value(i),
                    hood: hood.value(i),
                    frames: Vec::new(),
                },
            );
        }
    }
    let cols = [
        "frame",
        "pedestrian",
        boxes[0],
        boxes[1],
        boxes[2],
        boxes[3],
        "crossing",
        "state",
        "occlusion",
        "vx_mps",
        "vy_mps",
        "x_m",
        "y_m",
        "yaw_rad",
        "distance_to_ego_m",
        "box3d_x_m",
        "box3d_y_m",
        "box3d_z_m",
        "box3d_length_m",
        "box3d_width_m",
        "box3d_height_m",
        "keypoints",
        "look",
        "action",
        "gesture",
        "reaction",
    ];
    for b in tables::read(&file("annotations"), &cols)? {
        let (frame, ped) = (b.u32s("frame")?, b.u32s("pedestrian")?);
        let bbox: Vec<_> = cols[2..6].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
        let (crossing, state, occlusion) = (b.bools("crossing")?, b.strings("state")?, b.f32s("occlusion")?);
        let (vx, vy, x, y) = (b.f32s("vx_mps")?, b.f32s("vy_mps")?, b.f32s("x_m")?, b.f32s("y_m")?);
        let (yaw, distance) = (b.f32s("yaw_rad")?, b.f32s("distance_to_ego_m")?);
        let box3d: Vec<_> = cols[15..21].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
        let (kp, width) = b.f32_lists("keypoints")?;
        let (look, action) = (b.bools("look")?, b.strings("action")?);
        let (gesture, reaction) = (b.strings("gesture")?, b.strings("reaction")?);
        for i in 0..b.rows() {
            let p = clip.pedestrians.get_mut(&ped.value(i)).ok_or_else(|| {
                refuse(format!(
                    "{}: pedestrian {} is not in the pedestrians table",
                    file("annotations").display(),
                    ped.value(i)
                ))
            })?;
            p.frames.push(AnnotatedFrame {
                frame: frame.value(i),
                bbox_px: [bbox[0].value(i), bbox[1].value(i), bbox[2].value(i), bbox[3].value(i)],
                crossing: crossing.value(i),
                state: state[i].to_owned(),
                look: look.value(i),
                action: action[i].to_owned(),
                gesture: gesture[i].to_owned(),
                reaction: reaction[i].to_owned(),
                occlusion: occlusion.value(i),
                speed_mps: vx.value(i).hypot(vy.value(i)),
                x_m: x.value(i),
                y_m: y.value(i),
                yaw_rad: yaw.value(i),
                distance_to_ego_m: distance.value(i),
                box3d_m: std::array::from_fn(|k| box3d[k].value(i)),
                keypoints: kp[i * width..(i + 1) * width].to_vec(),
            });
        }
    }
    for p in clip.pedestrians.values_mut() {
        p.frames.sort_by_key(|f| f.frame);
    }
    let cols = ["frame", "vehicle", "x_m", "y_m", "z_m", "yaw_rad", "speed_mps", "kind"];
    for b in tables::read(&file("vehicles"), &cols)? {
        let (frame, vehicle, kind) = (b.u32s("frame")?, b.u32s("vehicle")?, b.strings("kind")?);
        let v: Vec<_> = cols[2..7].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
        for (i, kind) in kind.iter().enumerate() {
            clip.vehicles.push(VehicleFrame {
                frame: frame.value(i),
                vehicle: vehicle.value(i),
                x_m: f64::from(v[0].value(i)),
                y_m: f64::from(v[1].value(i)),
                z_m: f64::from(v[2].value(i)),
                yaw_rad: f64::from(v[3].value(i)),
                speed_mps: f64::from(v[4].value(i)),
                kind: (*kind).to_owned(),
            });
        }
    }
    clip.vehicles.sort_by_key(|v| (v.vehicle, v.frame));
    let parked = file("parked_cars");
    if parked.is_file() {
        let cols = [
            "parked_car",
            "x_m",
            "y_m",
            "z_m",
            "yaw_rad",
            "length_m",
            "width_m",
            "height_m",
        ];
        for b in tables::read(&parked, &cols)? {
            let id = b.u32s("parked_car")?;
            let v: Vec<_> = cols[1..].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
            for i in 0..b.rows() {
                let at = |k: usize| f64::from(v[k].value(i));
                clip.parked_cars.push(ParkedCarRow {
                    parked_car: id.value(i),
                    x_m: at(0),
                    y_m: at(1),
                    z_m: at(2),
                    yaw_rad: at(3),
                    size_m: [at(4), at(5), at(6)],
                });
            }
        }
        clip.parked_cars.sort_by_key(|c| c.parked_car);
    }
    let cyclists = file("cyclists");
    if cyclists.is_file() {
        let cols = [
            "frame",
            "cyclist",
            "in_view",
            "x_m",
            "y_m",
            "z_m",
            "yaw_rad",
            "x1",
            "y1",
            "x2",
            "y2",
            "speed_mps",
            "occlusion",
            "annotated",
            "keypoints",
        ];
        for b in tables::read(&cyclists, &cols)? {
            let (frame, cyclist, in_view) = (b.u32s("frame")?, b.u32s("cyclist")?, b.bools("in_view")?);
            let v: Vec<_> = cols[3..13].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
            let (annotated, (kp, width)) = (b.bools("annotated")?, b.f32_lists("keypoints")?);
            for i in 0..b.rows() {
                let keypoints = if in_view.value(i) {
                    kp[i * width..(i + 1) * width].to_vec()
                } else {
                    Vec::new()
                };
                clip.cyclists.push(CyclistFrame {
                    frame: frame.value(i),
                    cyclist: cyclist.value(i),
                    x_m: f64::from(v[0].value(i)),
                    y_m: f64::from(v[1].value(i)),
                    z_m: f64::from(v[2].value(i)),
                    yaw_rad: f64::from(v[3].value(i)),
                    speed_mps: f64::from(v[8].value(i)),
                    bbox: in_view
                        .value(i)
                        .then(|| std::array::from_fn(|k| f64::from(v[4 + k].value(i)))),
                    occlusion: (in_view.value(i) && !v[9].is_null(i)).then(|| v[9].value(i)),
                    annotated: annotated.value(i),
                    keypoints,
                });
            }
        }
        clip.cyclists.sort_by_key(|c| (c.cyclist, c.frame));
    }
    let tracks = file("tracks");
    if tracks.is_file() {
        let cols = ["frame", "pedestrian", "x_m", "y_m", "z_m", "yaw_rad"];
        for b in tables::read(&tracks, &cols)? {
            let (frame, ped) = (b.u32s("frame")?, b.u32s("pedestrian")?);
            let v: Vec<_> = cols[2..].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
            for i in 0..b.rows() {
                clip.tracks.entry(ped.value(i)).or_default().push(TrackFrame {
                    frame: frame.value(i),
                    x_m: f64::from(v[0].value(i)),
                    y_m: f64::from(v[1].value(i)),
                    z_m: f64::from(v[2].value(i)),
                    yaw_rad: f64::from(v[3].value(i)),
                });
            }
        }
        for t in clip.tracks.values_mut() {
            t.sort_by_key(|f| f.frame);
        }
    }
    let lights = file("traffic_lights");
    if lights.is_file() {
        let cols = [
            "frame",
            "signal",
            "state",
            "x_m",
            "y_m",
            "z_m",
            "facing_rad",
            "faces_ego",
        ];
        for b in tables::read(&lights, &cols)? {
            let (frame, signal, state, faces) = (
                b.u32s("frame")?,
                b.strings("signal")?,
                b.strings("state")?,
                b.bools("faces_ego")?,
            );
            let v: Vec<_> = cols[3..7].iter().map(|c| b.f32s(c)).collect::<Result<_, _>>()?;
            for i in 0..b.rows() {
                clip.traffic_lights.push(LightFrame {
                    frame: frame.value(i),
                    signal: signal[i].to_owned(),
                    state: state[i].to_owned(),
                    x_m: f64::from(v[0].value(i)),
                    y_m: f64::from(v[1].value(i)),
                    z_m: f64::from(v[2].value(i)),
                    facing_rad: f64::from(v[3].value(i)),
                    faces_ego: faces.value(i),
                });
            }
        }
    }
    Ok(clip)
}
