//! The other road users' tables: `vehicles`, `cyclists` (with the rider's box and keypoints where seen),
//! `parked_cars` and `traffic_lights` near the ego.

use super::*;

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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
        )
        .column(
            "signal",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| sig(r).id.as_str()))),
        )
        .column(
            "junction",
            false,
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| sig(r).junction.as_str()),
            )),
        )
        .column(
            "phase",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| sig(r).phase))),
        )
        .column(
            "state",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(state))),
        )
        .column(
            "x_m",
            false,
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).position.x as f32),
            )),
        )
        .column(
            "y_m",
            false,
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).position.y as f32),
            )),
        )
        .column(
            "z_m",
            false,
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).position.z as f32),
            )),
        )
        .column(
            "facing_rad",
            false,
            Arc::new(Float32Array::from_iter_values(
                rows.iter().map(|r| sig(r).facing_rad as f32),
            )),
        )
        .column(
            "distance_m",
            false,
            Arc::new(Float32Array::from_iter_values(rows.iter().map(|r| r.2 as f32))),
        )
        .column(
            "faces_ego",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.3)))),
        )
        .finish()
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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
        )
        .column(
            "vehicle",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.1))),
        )
        .column("x_m", false, f32c(|f| f.pos.x))
        .column("y_m", false, f32c(|f| f.pos.y))
        .column("z_m", false, f32c(|f| f.pos.z))
        .column("yaw_rad", false, f32c(|f| f.yaw_rad))
        .column("speed_mps", false, f32c(|f| f.speed_mps))
        .column("accel_mps2", false, f32c(|f| f.accel_mps2))
        .column(
            "profile",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| profile(r.1)))),
        )
        .column(
            "kind",
            false,
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| emergency(r.1).map_or("car", |k| k.name())),
            )),
        )
        .column(
            "siren",
            false,
            Arc::new(BooleanArray::from_iter(
                rows.iter().map(|r| Some(emergency(r.1).is_some())),
            )),
        )
        .column(
            "yielding",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.2.yielding)))),
        )
        .column(
            "ignores_lights",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| {
                Some(script.vehicles.get(r.1 as usize).is_some_and(|s| s.ignores_lights))
            }))),
        )
        .column(
            "light_state",
            true,
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.2.light.map(LightState::name)),
            )),
        )
        .finish()
}

/// The `parked_cars` table: one row per parked car of the clip (scenery: it stands still for the whole clip),
/// with its id, its instance in the `instance` stream, its footprint's centre, heading and size, and whether it
/// stands with two wheels up on the curb.
pub fn parked_cars_batch(script: &ClipScript, ann: &ClipAnnotations) -> RecordBatch {
    use crate::sim::{VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
    let cars = &ann.scenery.parked_cars;
    let n = cars.len();
    let f32c = |get: &dyn Fn(&crate::sensors::scene::ParkedCar) -> f64| -> ArrayRef {
        Arc::new(Float32Array::from_iter_values(cars.iter().map(|c| get(c) as f32)))
    };
    let size = |v: f64| -> ArrayRef { Arc::new(Float32Array::from_iter_values((0..n).map(|_| v as f32))) };
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "parked_car",
            false,
            Arc::new(UInt32Array::from_iter_values(0..n as u32)),
        )
        .column(
            "instance",
            false,
            Arc::new(UInt32Array::from_iter_values(
                (0..n as u32).map(|id| u32::from(crate::sensors::scene::parked_instance(id))),
            )),
        )
        .column("x_m", false, f32c(&|c| c.centre.x))
        .column("y_m", false, f32c(&|c| c.centre.y))
        .column("z_m", false, f32c(&|c| c.centre.z))
        .column("yaw_rad", false, f32c(&|c| c.yaw_rad))
        .column("length_m", false, size(VEHICLE_LENGTH_M))
        .column("width_m", false, size(VEHICLE_WIDTH_M))
        .column("height_m", false, size(VEHICLE_HEIGHT_M))
        .column(
            "on_curb",
            false,
            Arc::new(BooleanArray::from_iter(cars.iter().map(|c| Some(c.on_curb)))),
        )
        .finish()
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
    let width = 3 * crate::sensors::keypoints::joint_count(format);
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
                    crate::sensors::keypoints::push_keypoints(src, format, !three_d, &mut buf);
                }
                None => buf.resize(width, 0.0),
            }
            builder.values().append_slice(&buf);
            builder.append(s.is_some());
        }
        Arc::new(builder.finish())
    };
    let kp_type = DataType::FixedSizeList(Arc::new(Field::new("item", DataType::Float32, false)), width as i32);
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
        )
        .column(
            "cyclist",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.1))),
        )
        .column("class", false, repeated_utf8(n, "cyclist"))
        .column("x_m", false, f32c(|f| f.pos.x))
        .column("y_m", false, f32c(|f| f.pos.y))
        .column("z_m", false, f32c(|f| f.pos.z))
        .column("yaw_rad", false, f32c(|f| f.yaw_rad))
        .column("speed_mps", false, f32c(|f| f.speed_mps))
        .column("accel_mps2", false, f32c(|f| f.accel_mps2))
        .column("crank_phase", false, f32c(|f| f.crank_phase))
        .column(
            "swerving",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.2.swerving)))),
        )
        .column(
            "in_bike_lane",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.2.in_bike_lane)))),
        )
        .column(
            "ignores_lights",
            false,
            Arc::new(BooleanArray::from_iter(
                rows.iter()
                    .map(|r| Some(script_of(r.1).is_some_and(|c| c.ignores_lights))),
            )),
        )
        .column(
            "light_state",
            true,
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.2.light.map(LightState::name)),
            )),
        )
        .column(
            "rider_height_m",
            false,
            Arc::new(Float32Array::from_iter_values(
                rows.iter()
                    .map(|r| script_of(r.1).map_or(0.0, |c| c.rider.height_m) as f32),
            )),
        )
        .column(
            "in_view",
            false,
            Arc::new(BooleanArray::from_iter(seen.iter().map(|s| Some(s.is_some())))),
        )
        .column(
            "annotated",
            false,
            Arc::new(BooleanArray::from_iter(
                seen.iter().map(|s| Some(s.is_some_and(|s| s.annotated))),
            )),
        )
        .column("x1", true, boxc(0))
        .column("y1", true, boxc(1))
        .column("x2", true, boxc(2))
        .column("y2", true, boxc(3))
        .column(
            "truncated",
            true,
            Arc::new(BooleanArray::from_iter(seen.iter().map(|s| s.map(|s| s.truncated)))),
        )
        .column(
            "distance_m",
            true,
            Arc::new(Float32Array::from_iter(seen.iter().map(|s| s.map(|s| s.distance_m)))),
        )
        .column(
            "occlusion",
            true,
            Arc::new(Float32Array::from_iter(seen.iter().map(|s| s.map(|s| s.occlusion)))),
        )
        .column_of_type("keypoints", kp_type.clone(), true, keypoints(false))
        .column_of_type("keypoints_3d", kp_type, true, keypoints(true))
        .finish()
}
