//! The dataset's Parquet tables: schemas (keys first, Waymo-v2 style), Arrow record batches built from a
//! clip's script, trace and annotations, encoded as Parquet bytes (the writer stores them atomically).
//!
//! Layout: `tables/<table>/<clip_id>.parquet`, one file per clip and table, so that pyarrow, polars and DuckDB
//! read each table directory as one dataset. Every file carries `pedsynth.schema_version`, `pedsynth.version`,
//! `pedsynth.spec_hash` and `pedsynth.clip_id` in its key-value metadata. DATASET.md documents every column.

use std::sync::Arc;

use arrow_array::builder::{FixedSizeListBuilder, Float32Builder};
use arrow_array::{
    ArrayRef, BooleanArray, Float32Array, Float64Array, Int32Array, Int64Array, RecordBatch, StringArray, UInt32Array,
    UInt64Array,
};
use arrow_schema::{DataType, Field, Schema};
use parquet::arrow::ArrowWriter;
use parquet::basic::{Compression as ParquetCompression, ZstdLevel};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{WriterProperties, WriterPropertiesBuilder};

use crate::error::{Error, code};
use crate::plan::ClipScript;
use crate::sensors::annotate::ClipAnnotations;
use crate::sim::trace::{ClipTrace, Event, LightState, PedestrianId, VehicleId, WalkSignal};
use crate::spec::types::{Compression, Output, PoseFormat};
use crate::world::LaneType;

/// Version of the table schemas; bump on any change to a column.
pub const SCHEMA_VERSION: u32 = 9;

/// The tables, in the order they are written (`clips` last: its file marks the clip complete).
pub const TABLES: [&str; 11] = [
    "frames",
    "pedestrians",
    "annotations",
    "tracks",
    "vehicles",
    "cyclists",
    "events",
    "traffic_lights",
    "sensor_poses",
    "sensors",
    "clips",
];

/// Metadata every file carries.
#[derive(Clone, Debug)]
pub struct FileMeta {
    /// blake3 of the resolved spec.
    pub spec_hash: String,
}

fn lane_name(l: LaneType) -> &'static str {
    match l {
        LaneType::Driving => "driving",
        LaneType::Sidewalk => "sidewalk",
        LaneType::Shoulder => "shoulder",
        LaneType::Parking => "parking",
        LaneType::Median => "median",
        LaneType::Border => "border",
        LaneType::Biking => "biking",
        LaneType::Other => "other",
    }
}

fn snake<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_value(value)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

fn field(name: &str, data_type: DataType, nullable: bool) -> Field {
    Field::new(name, data_type, nullable)
}

fn utf8(n: usize, value: &str) -> ArrayRef {
    Arc::new(StringArray::from_iter_values(std::iter::repeat_n(value, n)))
}

fn batch(fields: Vec<Field>, columns: Vec<ArrayRef>) -> RecordBatch {
    RecordBatch::try_new(Arc::new(Schema::new(fields)), columns).expect("columns match their schema")
}

/// The `clips` table: one row describing the clip.
pub fn clips_batch(script: &ClipScript, trace: &ClipTrace, ann: &ClipAnnotations) -> RecordBatch {
    let w = &script.weather_params;
    let planned = script
        .pedestrians
        .iter()
        .filter(|p| p.role == crate::plan::Role::Crosser)
        .count() as u32;
    let crossers = ann.pedestrians.iter().filter(|p| p.crosser).count() as u32;
    let contacts = trace
        .events
        .iter()
        .filter(|e| matches!(e, Event::Contact { .. }))
        .count() as u32;
    let r = &ann.rejections;
    let f64s = [
        ("duration_s", script.duration_s()),
        ("sun_altitude_deg", w.sun_altitude_deg),
        ("sun_azimuth_deg", w.sun_azimuth_deg),
        ("cloudiness_pct", w.cloudiness_pct),
        ("precipitation_pct", w.precipitation_pct),
        ("fog_density_pct", w.fog_density_pct),
        ("wetness_pct", w.wetness_pct),
        ("wind_intensity_pct", w.wind_intensity_pct),
    ];
    let u32s = [
        ("fps", script.fps),
        ("frame_count", script.frame_count),
        ("pedestrians", script.pedestrians.len() as u32),
        ("planned_crossers", planned),
        ("crossers", crossers),
        ("vehicles", script.vehicles.len() as u32),
        ("contacts", contacts),
    ];
    let u64s = [
        ("seed", script.seed),
        ("annotated_samples", ann.rows.len() as u64),
        ("rejected_too_far", r.too_far),
        ("rejected_behind", r.behind),
        ("rejected_too_small", r.too_small),
        ("rejected_outside_image", r.outside_image),
        ("rejected_occluded", r.occluded),
    ];
    let mut fields = vec![
        field("clip_id", DataType::Utf8, false),
        field("town", DataType::Utf8, false),
        field("weather", DataType::Utf8, false),
        field("difficulty", DataType::Utf8, false),
        field("split", DataType::Utf8, false),
        field("emergency", DataType::Utf8, true),
    ];
    let mut columns: Vec<ArrayRef> = vec![
        utf8(1, &script.clip_id),
        utf8(1, &script.town),
        utf8(1, &script.weather),
        utf8(1, &snake(&w.difficulty)),
        utf8(1, &snake(&script.split)),
        Arc::new(StringArray::from(vec![
            script.vehicles.iter().find_map(|v| v.emergency).map(|k| k.name()),
        ])),
    ];
    for (name, v) in u64s {
        fields.push(field(name, DataType::UInt64, false));
        columns.push(Arc::new(UInt64Array::from(vec![v])));
    }
    for (name, v) in u32s {
        fields.push(field(name, DataType::UInt32, false));
        columns.push(Arc::new(UInt32Array::from(vec![v])));
    }
    for (name, v) in f64s {
        fields.push(field(name, DataType::Float64, false));
        columns.push(Arc::new(Float64Array::from(vec![v])));
    }
    batch(fields, columns)
}

/// The `frames` table: one row per frame with the simulated time and the ego's state.
pub fn frames_batch(script: &ClipScript, trace: &ClipTrace) -> RecordBatch {
    let n = trace.ego.len();
    let ns_per_frame = 1_000_000_000i64 / i64::from(trace.fps.max(1));
    let rem = 1_000_000_000i64 % i64::from(trace.fps.max(1));
    let timestamps: Vec<i64> = (0..n as i64)
        .map(|f| f * ns_per_frame + f * rem / i64::from(trace.fps.max(1)))
        .collect();
    let col = |get: fn(&crate::sim::trace::VehicleFrame) -> f64| -> ArrayRef {
        Arc::new(Float64Array::from_iter_values(trace.ego.iter().map(get)))
    };
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("timestamp_ns", DataType::Int64, false),
            field("ego_x_m", DataType::Float64, false),
            field("ego_y_m", DataType::Float64, false),
            field("ego_z_m", DataType::Float64, false),
            field("ego_yaw_rad", DataType::Float64, false),
            field("ego_speed_mps", DataType::Float64, false),
            field("ego_accel_mps2", DataType::Float64, false),
            field("ego_yielding", DataType::Boolean, false),
            field("ego_light_state", DataType::Utf8, true),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(0..n as u32)),
            Arc::new(Int64Array::from(timestamps)),
            col(|f| f.pos.x),
            col(|f| f.pos.y),
            col(|f| f.pos.z),
            col(|f| f.yaw_rad),
            col(|f| f.speed_mps),
            col(|f| f.accel_mps2),
            Arc::new(BooleanArray::from_iter(trace.ego.iter().map(|f| Some(f.yielding)))),
            Arc::new(StringArray::from_iter(
                trace.ego.iter().map(|f| f.light.map(LightState::name)),
            )),
        ],
    )
}

/// Traffic lights within this distance of the ego (plan view) get a row in the `traffic_lights` table, metres.
pub const TRAFFIC_LIGHT_RANGE_M: f64 = 100.0;

/// The `traffic_lights` table: per frame, every traffic light within [`TRAFFIC_LIGHT_RANGE_M`] of the ego: its
/// id, junction, phase, state, head position and facing, distance to the ego, and whether it faces the ego
/// from ahead (its lamps turned within 30° of the ego, the ego within 45° of its heading to it). Empty where
/// lights do not run.
pub fn traffic_lights_batch(script: &ClipScript, trace: &ClipTrace) -> RecordBatch {
    let cos_30 = 30f64.to_radians().cos();
    let cos_45 = std::f64::consts::FRAC_1_SQRT_2;
    let mut rows: Vec<(u32, usize, f64, bool)> = Vec::new();
    for (f, ego) in trace.ego.iter().enumerate() {
        let e = ego.pos.truncate();
        for (k, g) in trace.signals.iter().enumerate() {
            let to_light = g.position.truncate() - e;
            let d = to_light.length();
            if d > TRAFFIC_LIGHT_RANGE_M {
                continue;
            }
            let dir = to_light / d.max(1e-9);
            let facing = glam::DVec2::from_angle(g.facing_rad).dot(-dir) >= cos_30
                && glam::DVec2::from_angle(ego.yaw_rad).dot(dir) >= cos_45;
            rows.push((f as u32, k, d, facing));
        }
    }
    let n = rows.len();
    let sig = |r: &(u32, usize, f64, bool)| &trace.signals[r.1];
    let state = |r: &(u32, usize, f64, bool)| sig(r).states.get(r.0 as usize).map_or("green", |s| s.name());
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("signal", DataType::Utf8, false),
            field("junction", DataType::Utf8, false),
            field("phase", DataType::UInt32, false),
            field("state", DataType::Utf8, false),
            field("x_m", DataType::Float32, false),
            field("y_m", DataType::Float32, false),
            field("z_m", DataType::Float32, false),
            field("facing_rad", DataType::Float32, false),
            field("distance_m", DataType::Float32, false),
            field("faces_ego", DataType::Boolean, false),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| sig(r).id.as_str()))),
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| sig(r).junction.as_str()),
            )),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| sig(r).phase))),
            Arc::new(StringArray::from_iter_values(rows.iter().map(state))),
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).position.x as f32),
            )),
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).position.y as f32),
            )),
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).position.z as f32),
            )),
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).facing_rad as f32),
            )),
            Arc::new(Float32Array::from_iter_values(rows.iter().map(|r| r.2 as f32))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.3)))),
        ],
    )
}

/// The `sensor_poses` table: per frame, the world pose of the camera (whose image the annotations are in) and,
/// when it is enabled, the LiDAR, as `world_from_sensor` with sensor axes x forward, y left, z up: position
/// and a unit quaternion (w, x, y, z).
pub fn sensor_poses_batch(
    script: &ClipScript,
    trace: &ClipTrace,
    rig: &crate::sim::rig::Rig,
    sensors: &crate::spec::types::Sensors,
) -> RecordBatch {
    let frames = trace.frame_count.min(trace.ego.len() as u32);
    let mut rows: Vec<(u32, &'static str, glam::DAffine3)> = Vec::new();
    for f in 0..frames {
        for (name, pose) in crate::sensors::sensor_poses(trace, rig, f) {
            if name == "camera" || sensors.lidar.enabled {
                rows.push((f, name, pose));
            }
        }
    }
    let n = rows.len();
    let quats: Vec<glam::DQuat> = rows.iter().map(|r| glam::DQuat::from_mat3(&r.2.matrix3)).collect();
    let f64c = |v: Vec<f64>| -> ArrayRef { Arc::new(Float64Array::from(v)) };
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("timestamp_ns", DataType::Int64, false),
            field("sensor", DataType::Utf8, false),
            field("x_m", DataType::Float64, false),
            field("y_m", DataType::Float64, false),
            field("z_m", DataType::Float64, false),
            field("qw", DataType::Float64, false),
            field("qx", DataType::Float64, false),
            field("qy", DataType::Float64, false),
            field("qz", DataType::Float64, false),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
            Arc::new(Int64Array::from_iter_values(
                rows.iter().map(|r| crate::sensors::frame_time_ns(r.0, trace.fps, 0, 1)),
            )),
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.1))),
            f64c(rows.iter().map(|r| r.2.translation.x).collect()),
            f64c(rows.iter().map(|r| r.2.translation.y).collect()),
            f64c(rows.iter().map(|r| r.2.translation.z).collect()),
            f64c(quats.iter().map(|q| q.w).collect()),
            f64c(quats.iter().map(|q| q.x).collect()),
            f64c(quats.iter().map(|q| q.y).collect()),
            f64c(quats.iter().map(|q| q.z).collect()),
        ],
    )
}

/// The `pedestrians` table: one row per pedestrian with its plan and its clip-level labels.
pub fn pedestrians_batch(script: &ClipScript, ann: &ClipAnnotations) -> RecordBatch {
    let peds = &script.pedestrians;
    let n = peds.len();
    let s = |f: &dyn Fn(&crate::plan::PedestrianScript) -> String| -> ArrayRef {
        Arc::new(StringArray::from_iter_values(peds.iter().map(f)))
    };
    let f32c = |f: &dyn Fn(&crate::plan::PedestrianScript) -> f64| -> ArrayRef {
        Arc::new(Float32Array::from_iter_values(peds.iter().map(|p| f(p) as f32)))
    };
    let label = |i: usize| ann.pedestrians.get(i).copied().unwrap_or_default();
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("pedestrian", DataType::UInt32, false),
            field("archetype", DataType::Utf8, false),
            field("body", DataType::Utf8, false),
            field("role", DataType::Utf8, false),
            field("crosser_source", DataType::Utf8, false),
            field("behaviour", DataType::Utf8, false),
            field("group_id", DataType::UInt32, true),
            field("group_leader", DataType::UInt32, true),
            field("speed_profile", DataType::Utf8, false),
            field("base_speed_mps", DataType::Float32, false),
            field("hesitation_s", DataType::Float32, false),
            field("attention", DataType::Float32, false),
            field("ttc_threshold_s", DataType::Float32, false),
            field("safety_margin_s", DataType::Float32, false),
            field("patience_s", DataType::Float32, false),
            field("height_m", DataType::Float32, false),
            field("age_group", DataType::Utf8, false),
            field("gender", DataType::Utf8, false),
            field("crosser", DataType::Boolean, false),
            field("first_crossing_frame", DataType::UInt32, true),
            field("intention_frame", DataType::UInt32, true),
            field("annotated_frames", DataType::UInt32, false),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(peds.iter().map(|p| p.id))),
            s(&|p| p.archetype.clone()),
            s(&|p| snake(&p.body)),
            s(&|p| snake(&p.role)),
            s(&|p| snake(&p.crosser_source)),
            s(&|p| snake(&p.behaviour)),
            Arc::new(UInt32Array::from_iter(peds.iter().map(|p| p.group.map(|g| g.group_id)))),
            Arc::new(UInt32Array::from_iter(peds.iter().map(|p| p.group.map(|g| g.leader)))),
            s(&|p| snake(&p.speed_profile)),
            f32c(&|p| p.base_speed_mps),
            f32c(&|p| p.hesitation_s),
            f32c(&|p| p.attention),
            f32c(&|p| p.ttc_threshold_s),
            f32c(&|p| p.safety_margin_s),
            f32c(&|p| p.patience_s),
            f32c(&|p| p.identity.height_m),
            s(&|p| p.identity.age.name().to_owned()),
            s(&|p| p.identity.gender.name().to_owned()),
            Arc::new(BooleanArray::from_iter((0..n).map(|i| Some(label(i).crosser)))),
            Arc::new(UInt32Array::from_iter((0..n).map(|i| label(i).first_crossing_frame))),
            Arc::new(UInt32Array::from_iter((0..n).map(|i| label(i).intention_frame))),
            Arc::new(UInt32Array::from_iter_values((0..n).map(|i| label(i).annotated_frames))),
        ],
    )
}

fn keypoint_list(
    rows: &[crate::sensors::annotate::AnnotationRow],
    format: PoseFormat,
    flags: bool,
    get: fn(&crate::sensors::annotate::AnnotationRow) -> &[f32; 51],
) -> ArrayRef {
    let width = 3 * crate::sensors::body::joint_count(format);
    let mut values = Vec::with_capacity(rows.len() * width);
    for r in rows {
        crate::sensors::body::push_keypoints(get(r), format, flags, &mut values);
    }
    let mut builder =
        FixedSizeListBuilder::with_capacity(Float32Builder::with_capacity(values.len()), width as i32, rows.len())
            .with_field(Field::new("item", DataType::Float32, false));
    for chunk in values.chunks_exact(width) {
        builder.values().append_slice(chunk);
        builder.append(true);
    }
    Arc::new(builder.finish())
}

/// The `annotations` table: one row per annotated pedestrian-frame.
pub fn annotations_batch(script: &ClipScript, ann: &ClipAnnotations, format: PoseFormat) -> RecordBatch {
    let rows = &ann.rows;
    let n = rows.len();
    let f32c = |get: fn(&crate::sensors::annotate::AnnotationRow) -> f32| -> ArrayRef {
        Arc::new(Float32Array::from_iter_values(rows.iter().map(get)))
    };
    let width = 3 * crate::sensors::body::joint_count(format) as i32;
    let list = DataType::FixedSizeList(Arc::new(Field::new("item", DataType::Float32, false)), width);
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("pedestrian", DataType::UInt32, false),
            field("bbox_x_min", DataType::Float32, false),
            field("bbox_y_min", DataType::Float32, false),
            field("bbox_x_max", DataType::Float32, false),
            field("bbox_y_max", DataType::Float32, false),
            field("crossing", DataType::Boolean, false),
            field("state", DataType::Utf8, false),
            field("look", DataType::Boolean, false),
            field("action", DataType::Utf8, false),
            field("gesture", DataType::Utf8, false),
            field("reaction", DataType::Utf8, false),
            field("on_crosswalk", DataType::Boolean, false),
            field("walk_signal", DataType::Utf8, true),
            field("against_signal", DataType::Boolean, false),
            field("distance_to_ego_m", DataType::Float32, false),
            field("tte_frames", DataType::Int32, true),
            field("occlusion", DataType::Float32, false),
            field("keypoints", list.clone(), false),
            field("keypoints_3d", list, false),
            field("gaze_x", DataType::Float32, false),
            field("gaze_y", DataType::Float32, false),
            field("gaze_z", DataType::Float32, false),
            field("x_m", DataType::Float32, false),
            field("y_m", DataType::Float32, false),
            field("z_m", DataType::Float32, false),
            field("yaw_rad", DataType::Float32, false),
            field("vx_mps", DataType::Float32, false),
            field("vy_mps", DataType::Float32, false),
            field("lane_type", DataType::Utf8, true),
            field("box3d_x_m", DataType::Float32, false),
            field("box3d_y_m", DataType::Float32, false),
            field("box3d_z_m", DataType::Float32, false),
            field("box3d_length_m", DataType::Float32, false),
            field("box3d_width_m", DataType::Float32, false),
            field("box3d_height_m", DataType::Float32, false),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.frame))),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.pedestrian))),
            f32c(|r| r.bbox_px[0]),
            f32c(|r| r.bbox_px[1]),
            f32c(|r| r.bbox_px[2]),
            f32c(|r| r.bbox_px[3]),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.crossing)))),
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.state.name()))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.look)))),
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| if r.walking { "walking" } else { "standing" }),
            )),
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| r.gesture.map_or("none", |g| g.name())),
            )),
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| r.reaction.map_or("none", |g| g.name())),
            )),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.on_crosswalk)))),
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.walk_signal.map(WalkSignal::name)),
            )),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.against_signal)))),
            f32c(|r| r.distance_m),
            Arc::new(Int32Array::from_iter(rows.iter().map(|r| r.tte_frames))),
            f32c(|r| r.occlusion),
            keypoint_list(rows, format, true, |r| &r.keypoints),
            keypoint_list(rows, format, false, |r| &r.keypoints_3d),
            f32c(|r| r.gaze[0]),
            f32c(|r| r.gaze[1]),
            f32c(|r| r.gaze[2]),
            f32c(|r| r.pos_m[0]),
            f32c(|r| r.pos_m[1]),
            f32c(|r| r.pos_m[2]),
            f32c(|r| r.yaw_rad),
            f32c(|r| r.velocity_mps[0]),
            f32c(|r| r.velocity_mps[1]),
            Arc::new(StringArray::from_iter(rows.iter().map(|r| r.lane_type.map(lane_name)))),
            f32c(|r| r.box3d_centre_m[0]),
            f32c(|r| r.box3d_centre_m[1]),
            f32c(|r| r.box3d_centre_m[2]),
            f32c(|r| r.box3d_size_m[0]),
            f32c(|r| r.box3d_size_m[1]),
            f32c(|r| r.box3d_size_m[2]),
        ],
    )
}

/// The `vehicles` table: one row per traffic vehicle and frame (the ego is in `frames`).
pub fn vehicles_batch(script: &ClipScript, trace: &ClipTrace) -> RecordBatch {
    let rows: Vec<(u32, u32, &crate::sim::trace::VehicleFrame)> = (0..trace.ego.len())
        .flat_map(|f| {
            trace
                .vehicles
                .iter()
                .enumerate()
                .filter_map(move |(v, frames)| frames.get(f).map(|x| (f as u32, v as u32, x)))
        })
        .collect();
    let n = rows.len();
    let f32c = |get: fn(&crate::sim::trace::VehicleFrame) -> f64| -> ArrayRef {
        Arc::new(Float32Array::from_iter_values(rows.iter().map(|r| get(r.2) as f32)))
    };
    let profile = |v: u32| {
        script
            .vehicles
            .get(v as usize)
            .map_or_else(String::new, |s| snake(&s.profile))
    };
    let emergency = |v: u32| script.vehicles.get(v as usize).and_then(|s| s.emergency);
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("vehicle", DataType::UInt32, false),
            field("x_m", DataType::Float32, false),
            field("y_m", DataType::Float32, false),
            field("z_m", DataType::Float32, false),
            field("yaw_rad", DataType::Float32, false),
            field("speed_mps", DataType::Float32, false),
            field("accel_mps2", DataType::Float32, false),
            field("profile", DataType::Utf8, false),
            field("kind", DataType::Utf8, false),
            field("siren", DataType::Boolean, false),
            field("yielding", DataType::Boolean, false),
            field("ignores_lights", DataType::Boolean, false),
            field("light_state", DataType::Utf8, true),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.1))),
            f32c(|f| f.pos.x),
            f32c(|f| f.pos.y),
            f32c(|f| f.pos.z),
            f32c(|f| f.yaw_rad),
            f32c(|f| f.speed_mps),
            f32c(|f| f.accel_mps2),
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| profile(r.1)))),
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| emergency(r.1).map_or("car", |k| k.name())),
            )),
            Arc::new(BooleanArray::from_iter(
                rows.iter().map(|r| Some(emergency(r.1).is_some())),
            )),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.2.yielding)))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| {
                Some(script.vehicles.get(r.1 as usize).is_some_and(|s| s.ignores_lights))
            }))),
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.2.light.map(LightState::name)),
            )),
        ],
    )
}

/// The `tracks` table: every pedestrian in every frame, seen by the camera or not (the full 3D state that
/// trajectory models and scenario replays need), ordered by (frame, pedestrian).
pub fn tracks_batch(script: &ClipScript, trace: &ClipTrace, ann: &ClipAnnotations) -> RecordBatch {
    let annotated: std::collections::BTreeSet<(u32, u32)> = ann.rows.iter().map(|r| (r.frame, r.pedestrian)).collect();
    let rows: Vec<(u32, u32, &crate::sim::trace::PedFrame)> = (0..trace.ego.len())
        .flat_map(|f| {
            trace
                .pedestrians
                .iter()
                .enumerate()
                .filter_map(move |(p, frames)| frames.get(f).map(|x| (f as u32, p as u32, x)))
        })
        .collect();
    let n = rows.len();
    let f32c = |get: fn(&crate::sim::trace::PedFrame) -> f64| -> ArrayRef {
        Arc::new(Float32Array::from_iter_values(rows.iter().map(|r| get(r.2) as f32)))
    };
    let crossing = |f: u32, p: u32| {
        ann.crossing
            .get(p as usize)
            .and_then(|c| c.get(f as usize))
            .copied()
            .unwrap_or(false)
    };
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("pedestrian", DataType::UInt32, false),
            field("x_m", DataType::Float32, false),
            field("y_m", DataType::Float32, false),
            field("z_m", DataType::Float32, false),
            field("yaw_rad", DataType::Float32, false),
            field("vx_mps", DataType::Float32, false),
            field("vy_mps", DataType::Float32, false),
            field("state", DataType::Utf8, false),
            field("crossing", DataType::Boolean, false),
            field("lane_type", DataType::Utf8, true),
            field("annotated", DataType::Boolean, false),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.1))),
            f32c(|f| f.pos.x),
            f32c(|f| f.pos.y),
            f32c(|f| f.pos.z),
            f32c(|f| f.yaw_rad),
            f32c(|f| f.velocity.x),
            f32c(|f| f.velocity.y),
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.2.state.name()))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(crossing(r.0, r.1))))),
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.2.lane_type.map(lane_name)),
            )),
            Arc::new(BooleanArray::from_iter(
                rows.iter().map(|r| Some(annotated.contains(&(r.0, r.1)))),
            )),
        ],
    )
}

/// The `events` table: state changes, crossing decisions, conflicts and retreats, patience expiry, contacts.
pub fn events_batch(script: &ClipScript, trace: &ClipTrace) -> RecordBatch {
    #[derive(Default)]
    struct Row {
        frame: u32,
        kind: &'static str,
        pedestrian: Option<PedestrianId>,
        vehicle: Option<u32>,
        from: Option<&'static str>,
        to: Option<&'static str>,
        in_window: Option<bool>,
        retreated: Option<bool>,
        sudden: Option<bool>,
        other: Option<u32>,
        signal: Option<u32>,
        unavoidable: Option<bool>,
        cyclist: Option<u32>,
        clearance: Option<f32>,
        swerved: Option<bool>,
    }
    let rows: Vec<Row> = trace
        .events
        .iter()
        .map(|e| match *e {
            Event::StateChange {
                frame,
                pedestrian,
                from,
                to,
            } => Row {
                frame,
                kind: "state_change",
                pedestrian: Some(pedestrian),
                from: Some(from.name()),
                to: Some(to.name()),
                ..Row::default()
            },
            Event::CrossingDecision { frame, pedestrian } => Row {
                frame,
                kind: "crossing_decision",
                pedestrian: Some(pedestrian),
                ..Row::default()
            },
            Event::Conflict {
                frame,
                pedestrian,
                vehicle,
                in_retreat_window,
                retreated,
            } => Row {
                frame,
                kind: "conflict",
                pedestrian: Some(pedestrian),
                vehicle: vehicle.traffic(),
                cyclist: vehicle.cyclist(),
                in_window: Some(in_retreat_window),
                retreated: Some(retreated),
                ..Row::default()
            },
            Event::PatienceExpired {
                frame,
                pedestrian,
                sudden_crossing,
            } => Row {
                frame,
                kind: "patience_expired",
                pedestrian: Some(pedestrian),
                sudden: Some(sudden_crossing),
                ..Row::default()
            },
            Event::Contact {
                frame,
                vehicle,
                pedestrian,
                other_vehicle,
            } => Row {
                frame,
                kind: "contact",
                pedestrian,
                vehicle: vehicle.traffic(),
                other: other_vehicle.and_then(VehicleId::traffic),
                cyclist: vehicle.cyclist().or(other_vehicle.and_then(VehicleId::cyclist)),
                ..Row::default()
            },
            Event::RedLight {
                frame,
                vehicle,
                signal,
                ran,
                unavoidable,
            } => Row {
                frame,
                kind: if ran { "ran_red_light" } else { "stopped_at_red_light" },
                vehicle: vehicle.traffic(),
                signal: Some(signal),
                unavoidable: ran.then_some(unavoidable),
                cyclist: vehicle.cyclist(),
                ..Row::default()
            },
            Event::OvertookCyclist {
                frame,
                vehicle,
                cyclist,
                min_clearance_m,
            } => Row {
                frame,
                kind: "overtook_cyclist",
                vehicle: vehicle.traffic(),
                cyclist: Some(cyclist),
                clearance: Some(min_clearance_m as f32),
                ..Row::default()
            },
            Event::CyclistYielded {
                frame,
                cyclist,
                pedestrian,
                swerved,
            } => Row {
                frame,
                kind: "cyclist_yielded",
                pedestrian: Some(pedestrian),
                cyclist: Some(cyclist),
                swerved: Some(swerved),
                ..Row::default()
            },
        })
        .collect();
    let n = rows.len();
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("kind", DataType::Utf8, false),
            field("pedestrian", DataType::UInt32, true),
            field("vehicle", DataType::UInt32, true),
            field("ego_involved", DataType::Boolean, false),
            field("from_state", DataType::Utf8, true),
            field("to_state", DataType::Utf8, true),
            field("in_retreat_window", DataType::Boolean, true),
            field("retreated", DataType::Boolean, true),
            field("sudden_crossing", DataType::Boolean, true),
            field("other_vehicle", DataType::UInt32, true),
            field("signal", DataType::Utf8, true),
            field("unavoidable", DataType::Boolean, true),
            field("cyclist", DataType::UInt32, true),
            field("min_clearance_m", DataType::Float32, true),
            field("swerved", DataType::Boolean, true),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.frame))),
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.kind))),
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.pedestrian.map(|p| p.0)))),
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.vehicle))),
            Arc::new(BooleanArray::from_iter(trace.events.iter().map(|e| {
                Some(matches!(
                    e,
                    Event::Conflict {
                        vehicle: VehicleId::Ego,
                        ..
                    } | Event::Contact {
                        vehicle: VehicleId::Ego,
                        ..
                    } | Event::Contact {
                        other_vehicle: Some(VehicleId::Ego),
                        ..
                    } | Event::RedLight {
                        vehicle: VehicleId::Ego,
                        ..
                    } | Event::OvertookCyclist {
                        vehicle: VehicleId::Ego,
                        ..
                    }
                ))
            }))),
            Arc::new(StringArray::from_iter(rows.iter().map(|r| r.from))),
            Arc::new(StringArray::from_iter(rows.iter().map(|r| r.to))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.in_window))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.retreated))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.sudden))),
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.other))),
            Arc::new(StringArray::from_iter(rows.iter().map(|r| {
                r.signal
                    .and_then(|k| trace.signals.get(k as usize))
                    .map(|g| g.id.as_str())
            }))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.unavoidable))),
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.cyclist))),
            Arc::new(Float32Array::from_iter(rows.iter().map(|r| r.clearance))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.swerved))),
        ],
    )
}

/// The `cyclists` table: one row per cyclist and frame (the 3D state), with the box of rider and bicycle and
/// the rider's keypoints where the camera sees it (null otherwise).
pub fn cyclists_batch(
    script: &ClipScript,
    trace: &ClipTrace,
    ann: &ClipAnnotations,
    format: PoseFormat,
) -> RecordBatch {
    let rows: Vec<(u32, u32, &crate::sim::trace::CyclistFrame)> = (0..trace.ego.len())
        .flat_map(|f| {
            trace
                .cyclists
                .iter()
                .enumerate()
                .filter_map(move |(c, frames)| frames.get(f).map(|x| (f as u32, c as u32, x)))
        })
        .collect();
    // Both ordered by (frame, cyclist): walk the seen rows alongside.
    let mut seen_iter = ann.cyclists.iter().peekable();
    let seen: Vec<Option<&crate::sensors::annotate::CyclistRow>> = rows
        .iter()
        .map(|r| {
            while seen_iter.peek().is_some_and(|s| (s.frame, s.cyclist) < (r.0, r.1)) {
                seen_iter.next();
            }
            seen_iter.next_if(|s| (s.frame, s.cyclist) == (r.0, r.1))
        })
        .collect();
    let n = rows.len();
    let f32c = |get: fn(&crate::sim::trace::CyclistFrame) -> f64| -> ArrayRef {
        Arc::new(Float32Array::from_iter_values(rows.iter().map(|r| get(r.2) as f32)))
    };
    let boxc =
        |k: usize| -> ArrayRef { Arc::new(Float32Array::from_iter(seen.iter().map(|s| s.map(|s| s.bbox_px[k])))) };
    let script_of = |c: u32| script.cyclists.get(c as usize);
    let width = 3 * crate::sensors::body::joint_count(format);
    let keypoints = |three_d: bool| -> ArrayRef {
        let mut builder =
            FixedSizeListBuilder::with_capacity(Float32Builder::with_capacity(n * width), width as i32, n)
                .with_field(Field::new("item", DataType::Float32, false));
        let mut buf = Vec::with_capacity(width);
        for s in &seen {
            buf.clear();
            match s {
                Some(s) => {
                    let src = if three_d { &s.keypoints_3d } else { &s.keypoints };
                    crate::sensors::body::push_keypoints(src, format, !three_d, &mut buf);
                }
                None => buf.resize(width, 0.0),
            }
            builder.values().append_slice(&buf);
            builder.append(s.is_some());
        }
        Arc::new(builder.finish())
    };
    let kp_type = DataType::FixedSizeList(Arc::new(Field::new("item", DataType::Float32, false)), width as i32);
    batch(
        vec![
            field("clip_id", DataType::Utf8, false),
            field("frame", DataType::UInt32, false),
            field("cyclist", DataType::UInt32, false),
            field("class", DataType::Utf8, false),
            field("x_m", DataType::Float32, false),
            field("y_m", DataType::Float32, false),
            field("z_m", DataType::Float32, false),
            field("yaw_rad", DataType::Float32, false),
            field("speed_mps", DataType::Float32, false),
            field("accel_mps2", DataType::Float32, false),
            field("crank_phase", DataType::Float32, false),
            field("swerving", DataType::Boolean, false),
            field("in_bike_lane", DataType::Boolean, false),
            field("ignores_lights", DataType::Boolean, false),
            field("light_state", DataType::Utf8, true),
            field("rider_height_m", DataType::Float32, false),
            field("in_view", DataType::Boolean, false),
            field("annotated", DataType::Boolean, false),
            field("x1", DataType::Float32, true),
            field("y1", DataType::Float32, true),
            field("x2", DataType::Float32, true),
            field("y2", DataType::Float32, true),
            field("truncated", DataType::Boolean, true),
            field("distance_m", DataType::Float32, true),
            field("occlusion", DataType::Float32, true),
            field("keypoints", kp_type.clone(), true),
            field("keypoints_3d", kp_type, true),
        ],
        vec![
            utf8(n, &script.clip_id),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.1))),
            utf8(n, "cyclist"),
            f32c(|f| f.pos.x),
            f32c(|f| f.pos.y),
            f32c(|f| f.pos.z),
            f32c(|f| f.yaw_rad),
            f32c(|f| f.speed_mps),
            f32c(|f| f.accel_mps2),
            f32c(|f| f.crank_phase),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.2.swerving)))),
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.2.in_bike_lane)))),
            Arc::new(BooleanArray::from_iter(
                rows.iter()
                    .map(|r| Some(script_of(r.1).is_some_and(|c| c.ignores_lights))),
            )),
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.2.light.map(LightState::name)),
            )),
            Arc::new(Float32Array::from_iter_values(
                rows.iter()
                    .map(|r| script_of(r.1).map_or(0.0, |c| c.rider.height_m) as f32),
            )),
            Arc::new(BooleanArray::from_iter(seen.iter().map(|s| Some(s.is_some())))),
            Arc::new(BooleanArray::from_iter(
                seen.iter().map(|s| Some(s.is_some_and(|s| s.annotated))),
            )),
            boxc(0),
            boxc(1),
            boxc(2),
            boxc(3),
            Arc::new(BooleanArray::from_iter(seen.iter().map(|s| s.map(|s| s.truncated)))),
            Arc::new(Float32Array::from_iter(seen.iter().map(|s| s.map(|s| s.distance_m)))),
            Arc::new(Float32Array::from_iter(seen.iter().map(|s| s.map(|s| s.occlusion)))),
            keypoints(false),
            keypoints(true),
        ],
    )
}

/// The Parquet writer settings of a dataset file: the spec's codec (zstd by default) and the file's key-value
/// metadata.
pub fn writer_properties(output: &Output, meta: &FileMeta, table: &str, clip_id: &str) -> WriterProperties {
    properties_builder(output, meta, table, clip_id).build()
}

/// [`writer_properties`] for the DVS events: millions of rows of mostly distinct values, where dictionary pages
/// cost time (interning every value) and zstd alone packs tighter (quickstart: 81.7 MB instead of 89.0 MB;
/// the LiDAR's quantised columns are the other way round, 158 MB with dictionaries and 205 MB without).
pub fn events_writer_properties(output: &Output, meta: &FileMeta, table: &str, clip_id: &str) -> WriterProperties {
    properties_builder(output, meta, table, clip_id)
        .set_dictionary_enabled(false)
        .build()
}

fn properties_builder(output: &Output, meta: &FileMeta, table: &str, clip_id: &str) -> WriterPropertiesBuilder {
    let compression = match output.compression {
        Compression::Zstd => ParquetCompression::ZSTD(ZstdLevel::try_new(output.zstd_level as i32).unwrap_or_default()),
        Compression::Snappy => ParquetCompression::SNAPPY,
        Compression::None => ParquetCompression::UNCOMPRESSED,
    };
    let kv = |k: &str, v: String| KeyValue::new(k.to_owned(), v);
    WriterProperties::builder()
        .set_compression(compression)
        .set_created_by(format!("pedsynth {}", env!("CARGO_PKG_VERSION")))
        .set_key_value_metadata(Some(vec![
            kv("pedsynth.schema_version", SCHEMA_VERSION.to_string()),
            kv("pedsynth.version", env!("CARGO_PKG_VERSION").to_owned()),
            kv("pedsynth.spec_hash", meta.spec_hash.clone()),
            kv("pedsynth.table", table.to_owned()),
            kv("pedsynth.clip_id", clip_id.to_owned()),
        ]))
}

/// The error of a file that cannot be encoded as Parquet.
pub fn parquet_error(table: &str, clip_id: &str, e: &parquet::errors::ParquetError) -> Error {
    Error::new(
        code::INTERNAL_SERIALIZE,
        format!("cannot encode table `{table}` of clip {clip_id} as Parquet: {e}"),
    )
}

/// The Parquet bytes of a record batch, with [`writer_properties`].
pub fn parquet_bytes(
    batch: &RecordBatch,
    output: &Output,
    meta: &FileMeta,
    table: &str,
    clip_id: &str,
) -> Result<Vec<u8>, Error> {
    let props = writer_properties(output, meta, table, clip_id);
    let encode = || -> Result<Vec<u8>, parquet::errors::ParquetError> {
        let mut writer = ArrowWriter::try_new(Vec::new(), batch.schema(), Some(props))?;
        writer.write(batch)?;
        writer.into_inner()
    };
    encode().map_err(|e| parquet_error(table, clip_id, &e))
}
