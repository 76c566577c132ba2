//! The clip-level tables: `clips` (one row per clip), `frames` (the ego per frame), `sensor_poses` and
//! `events` (state changes, decisions, conflicts, contacts, lights, overtakes).

use super::*;

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
    let mut table = Table::new()
        .column("clip_id", false, repeated_utf8(1, &script.clip_id))
        .column("town", false, repeated_utf8(1, &script.town))
        .column("weather", false, repeated_utf8(1, &script.weather))
        .column("difficulty", false, repeated_utf8(1, &snake(&w.difficulty)))
        .column("split", false, repeated_utf8(1, &snake(&script.split)))
        .column(
            "emergency",
            true,
            Arc::new(StringArray::from(vec![
                script.vehicles.iter().find_map(|v| v.emergency).map(|k| k.name()),
            ])),
        );
    for (name, v) in u64s {
        table = table.column(name, false, Arc::new(UInt64Array::from(vec![v])));
    }
    for (name, v) in u32s {
        table = table.column(name, false, Arc::new(UInt32Array::from(vec![v])));
    }
    for (name, v) in f64s {
        table = table.column(name, false, Arc::new(Float64Array::from(vec![v])));
    }
    table.finish()
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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column("frame", false, Arc::new(UInt32Array::from_iter_values(0..n as u32)))
        .column("timestamp_ns", false, Arc::new(Int64Array::from(timestamps)))
        .column("ego_x_m", false, col(|f| f.pos.x))
        .column("ego_y_m", false, col(|f| f.pos.y))
        .column("ego_z_m", false, col(|f| f.pos.z))
        .column("ego_yaw_rad", false, col(|f| f.yaw_rad))
        .column("ego_pitch_rad", false, col(|f| f.pitch_rad))
        .column("ego_speed_mps", false, col(|f| f.speed_mps))
        .column("ego_accel_mps2", false, col(|f| f.accel_mps2))
        .column(
            "ego_yielding",
            false,
            Arc::new(BooleanArray::from_iter(trace.ego.iter().map(|f| Some(f.yielding)))),
        )
        .column(
            "ego_light_state",
            true,
            Arc::new(StringArray::from_iter(
                trace.ego.iter().map(|f| f.light.map(LightState::name)),
            )),
        )
        .finish()
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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
        )
        .column(
            "timestamp_ns",
            false,
            Arc::new(Int64Array::from_iter_values(
                rows.iter().map(|r| crate::sensors::frame_time_ns(r.0, trace.fps, 0, 1)),
            )),
        )
        .column(
            "sensor",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.1))),
        )
        .column("x_m", false, f64c(rows.iter().map(|r| r.2.translation.x).collect()))
        .column("y_m", false, f64c(rows.iter().map(|r| r.2.translation.y).collect()))
        .column("z_m", false, f64c(rows.iter().map(|r| r.2.translation.z).collect()))
        .column("qw", false, f64c(quats.iter().map(|q| q.w).collect()))
        .column("qx", false, f64c(quats.iter().map(|q| q.x).collect()))
        .column("qy", false, f64c(quats.iter().map(|q| q.y).collect()))
        .column("qz", false, f64c(quats.iter().map(|q| q.z).collect()))
        .finish()
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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.frame))),
        )
        .column(
            "kind",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.kind))),
        )
        .column(
            "pedestrian",
            true,
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.pedestrian.map(|p| p.0)))),
        )
        .column(
            "vehicle",
            true,
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.vehicle))),
        )
        .column(
            "ego_involved",
            false,
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
        )
        .column(
            "from_state",
            true,
            Arc::new(StringArray::from_iter(rows.iter().map(|r| r.from))),
        )
        .column(
            "to_state",
            true,
            Arc::new(StringArray::from_iter(rows.iter().map(|r| r.to))),
        )
        .column(
            "in_retreat_window",
            true,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.in_window))),
        )
        .column(
            "retreated",
            true,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.retreated))),
        )
        .column(
            "sudden_crossing",
            true,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.sudden))),
        )
        .column(
            "other_vehicle",
            true,
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.other))),
        )
        .column(
            "signal",
            true,
            Arc::new(StringArray::from_iter(rows.iter().map(|r| {
                r.signal
                    .and_then(|k| trace.signals.get(k as usize))
                    .map(|g| g.id.as_str())
            }))),
        )
        .column(
            "unavoidable",
            true,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.unavoidable))),
        )
        .column(
            "cyclist",
            true,
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.cyclist))),
        )
        .column(
            "min_clearance_m",
            true,
            Arc::new(Float32Array::from_iter(rows.iter().map(|r| r.clearance))),
        )
        .column(
            "swerved",
            true,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| r.swerved))),
        )
        .finish()
}
