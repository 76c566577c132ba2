//! The pedestrians' tables: `pedestrians` (one row per person), `annotations` (one row per annotated
//! pedestrian-frame: boxes, keypoints, labels, 3D state) and `tracks` (every pedestrian-frame's 3D state).

use super::*;

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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "pedestrian",
            false,
            Arc::new(UInt32Array::from_iter_values(peds.iter().map(|p| p.id))),
        )
        .column("archetype", false, s(&|p| p.archetype.clone()))
        .column("body", false, s(&|p| snake(&p.body)))
        .column("role", false, s(&|p| snake(&p.role)))
        .column("crosser_source", false, s(&|p| snake(&p.crosser_source)))
        .column("behaviour", false, s(&|p| snake(&p.behaviour)))
        .column(
            "group_id",
            true,
            Arc::new(UInt32Array::from_iter(peds.iter().map(|p| p.group.map(|g| g.group_id)))),
        )
        .column(
            "group_leader",
            true,
            Arc::new(UInt32Array::from_iter(peds.iter().map(|p| p.group.map(|g| g.leader)))),
        )
        .column("speed_profile", false, s(&|p| snake(&p.speed_profile)))
        .column("base_speed_mps", false, f32c(&|p| p.base_speed_mps))
        .column("hesitation_s", false, f32c(&|p| p.hesitation_s))
        .column("attention", false, f32c(&|p| p.attention))
        .column("ttc_threshold_s", false, f32c(&|p| p.ttc_threshold_s))
        .column("safety_margin_s", false, f32c(&|p| p.safety_margin_s))
        .column("patience_s", false, f32c(&|p| p.patience_s))
        .column("height_m", false, f32c(&|p| p.identity.height_m))
        .column("age_group", false, s(&|p| p.identity.age.name().to_owned()))
        .column("gender", false, s(&|p| p.identity.gender.name().to_owned()))
        .column("build", false, f32c(&|p| p.identity.figure.build))
        .column("hair", false, s(&|p| p.identity.figure.hair.name().to_owned()))
        .column(
            "headwear",
            false,
            Arc::new(BooleanArray::from_iter(
                peds.iter().map(|p| Some(p.identity.figure.headwear.is_some())),
            )),
        )
        .column("garment", false, s(&|p| p.identity.figure.garment.name().to_owned()))
        .column(
            "carry",
            true,
            Arc::new(StringArray::from_iter(
                peds.iter().map(|p| p.identity.figure.carry.map(|c| c.0.name())),
            )),
        )
        .column(
            "umbrella",
            false,
            Arc::new(BooleanArray::from_iter(
                peds.iter().map(|p| Some(p.identity.figure.umbrella.is_some())),
            )),
        )
        .column(
            "hood",
            false,
            Arc::new(BooleanArray::from_iter(
                peds.iter().map(|p| Some(p.identity.figure.hood)),
            )),
        )
        .column(
            "pattern",
            true,
            Arc::new(StringArray::from_iter(
                peds.iter().map(|p| p.identity.figure.pattern.map(|c| c.0.name())),
            )),
        )
        .column(
            "crosser",
            false,
            Arc::new(BooleanArray::from_iter((0..n).map(|i| Some(label(i).crosser)))),
        )
        .column(
            "first_crossing_frame",
            true,
            Arc::new(UInt32Array::from_iter((0..n).map(|i| label(i).first_crossing_frame))),
        )
        .column(
            "intention_frame",
            true,
            Arc::new(UInt32Array::from_iter((0..n).map(|i| label(i).intention_frame))),
        )
        .column(
            "annotated_frames",
            false,
            Arc::new(UInt32Array::from_iter_values((0..n).map(|i| label(i).annotated_frames))),
        )
        .finish()
}

fn keypoint_list(
    rows: &[crate::sensors::annotate::AnnotationRow],
    format: PoseFormat,
    flags: bool,
    get: fn(&crate::sensors::annotate::AnnotationRow) -> &[f32; 51],
) -> ArrayRef {
    let width = 3 * crate::sensors::keypoints::joint_count(format);
    let mut values = Vec::with_capacity(rows.len() * width);
    for r in rows {
        crate::sensors::keypoints::push_keypoints(get(r), format, flags, &mut values);
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
    let width = 3 * crate::sensors::keypoints::joint_count(format) as i32;
    let list = DataType::FixedSizeList(Arc::new(Field::new("item", DataType::Float32, false)), width);
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.frame))),
        )
        .column(
            "pedestrian",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.pedestrian))),
        )
        .column("bbox_x_min", false, f32c(|r| r.bbox_px[0]))
        .column("bbox_y_min", false, f32c(|r| r.bbox_px[1]))
        .column("bbox_x_max", false, f32c(|r| r.bbox_px[2]))
        .column("bbox_y_max", false, f32c(|r| r.bbox_px[3]))
        .column("annotator_x_min", false, f32c(|r| r.annotator_bbox_px[0]))
        .column("annotator_y_min", false, f32c(|r| r.annotator_bbox_px[1]))
        .column("annotator_x_max", false, f32c(|r| r.annotator_bbox_px[2]))
        .column("annotator_y_max", false, f32c(|r| r.annotator_bbox_px[3]))
        .column(
            "crossing",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.crossing)))),
        )
        .column(
            "state",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.state.name()))),
        )
        .column(
            "look",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.look)))),
        )
        .column(
            "action",
            false,
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| if r.walking { "walking" } else { "standing" }),
            )),
        )
        .column(
            "gesture",
            false,
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| r.gesture.map_or("none", |g| g.name())),
            )),
        )
        .column(
            "reaction",
            false,
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|r| r.reaction.map_or("none", |g| g.name())),
            )),
        )
        .column(
            "on_crosswalk",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.on_crosswalk)))),
        )
        .column(
            "walk_signal",
            true,
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.walk_signal.map(WalkSignal::name)),
            )),
        )
        .column(
            "against_signal",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(r.against_signal)))),
        )
        .column("distance_to_ego_m", false, f32c(|r| r.distance_m))
        .column(
            "tte_frames",
            true,
            Arc::new(Int32Array::from_iter(rows.iter().map(|r| r.tte_frames))),
        )
        .column("occlusion", false, f32c(|r| r.occlusion))
        .column_of_type(
            "keypoints",
            list.clone(),
            false,
            keypoint_list(rows, format, true, |r| &r.keypoints),
        )
        .column_of_type(
            "keypoints_3d",
            list,
            false,
            keypoint_list(rows, format, false, |r| &r.keypoints_3d),
        )
        .column("gaze_x", false, f32c(|r| r.gaze[0]))
        .column("gaze_y", false, f32c(|r| r.gaze[1]))
        .column("gaze_z", false, f32c(|r| r.gaze[2]))
        .column("x_m", false, f32c(|r| r.pos_m[0]))
        .column("y_m", false, f32c(|r| r.pos_m[1]))
        .column("z_m", false, f32c(|r| r.pos_m[2]))
        .column("yaw_rad", false, f32c(|r| r.yaw_rad))
        .column("vx_mps", false, f32c(|r| r.velocity_mps[0]))
        .column("vy_mps", false, f32c(|r| r.velocity_mps[1]))
        .column(
            "lane_type",
            true,
            Arc::new(StringArray::from_iter(rows.iter().map(|r| r.lane_type.map(lane_name)))),
        )
        .column("box3d_x_m", false, f32c(|r| r.box3d_centre_m[0]))
        .column("box3d_y_m", false, f32c(|r| r.box3d_centre_m[1]))
        .column("box3d_z_m", false, f32c(|r| r.box3d_centre_m[2]))
        .column("box3d_length_m", false, f32c(|r| r.box3d_size_m[0]))
        .column("box3d_width_m", false, f32c(|r| r.box3d_size_m[1]))
        .column("box3d_height_m", false, f32c(|r| r.box3d_size_m[2]))
        .finish()
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
    Table::new()
        .column("clip_id", false, repeated_utf8(n, &script.clip_id))
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.0))),
        )
        .column(
            "pedestrian",
            false,
            Arc::new(UInt32Array::from_iter_values(rows.iter().map(|r| r.1))),
        )
        .column("x_m", false, f32c(|f| f.pos.x))
        .column("y_m", false, f32c(|f| f.pos.y))
        .column("z_m", false, f32c(|f| f.pos.z))
        .column("yaw_rad", false, f32c(|f| f.yaw_rad))
        .column("vx_mps", false, f32c(|f| f.velocity.x))
        .column("vy_mps", false, f32c(|f| f.velocity.y))
        .column(
            "state",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.2.state.name()))),
        )
        .column(
            "crossing",
            false,
            Arc::new(BooleanArray::from_iter(rows.iter().map(|r| Some(crossing(r.0, r.1))))),
        )
        .column(
            "lane_type",
            true,
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.2.lane_type.map(lane_name)),
            )),
        )
        .column(
            "annotated",
            false,
            Arc::new(BooleanArray::from_iter(
                rows.iter().map(|r| Some(annotated.contains(&(r.0, r.1)))),
            )),
        )
        .finish()
}
