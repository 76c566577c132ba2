//! `pedsynth export jaad`: JAAD's layout (../shared/interfaces/jaad/README.md and its `example/`, the real
//! video_0207) so that JAAD's own `jaad_data.py` loads a pedsynth dataset unmodified: per video the five
//! annotation files (tracks with JAAD's behaviour labels, pedestrian attributes, appearance, traffic scene,
//! ego-vehicle actions), `split_ids/default/{train,val,test}.txt`, the images linked from `sensors/rgb`, and
//! `pedsynth_export.json` with the mapping. DATASET.md lists it.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use glam::DVec2;
use serde::Serialize;

use super::dataset::{Clip, ClipInfo, Dataset, EgoFrame, Pedestrian};
use super::pie::{Labels, Place, occlusion_class, place_at, wrap_pi, xml_escape};
use super::{LinkMode, RgbFiles, link_frames, write_file};
use crate::world::RoadNetwork;

/// Where a clip went.
#[derive(Clone, Debug, Serialize)]
pub struct VideoOf {
    pub clip_id: String,
    pub split: String,
    /// `video_NNNN`, numbered from 0001 over the clips sorted by id.
    pub video: String,
}

/// JAAD's id of a behaviour-annotated pedestrian: `0_<video number>_<pedestrian id>b` (as JAAD's
/// `0_207_1496b`; the `b` marks a pedestrian with behaviour labels, which the benchmark's `beh` samples keep).
pub fn track_id(v: &VideoOf, pedestrian: u32) -> String {
    format!(
        "0_{}_{pedestrian}b",
        v.video.trim_start_matches("video_").trim_start_matches('0')
    )
}

/// The videos of the clips (sorted by id).
pub fn assign_videos(clips: &[ClipInfo]) -> Vec<VideoOf> {
    clips
        .iter()
        .enumerate()
        .map(|(i, c)| VideoOf {
            clip_id: c.clip_id.clone(),
            split: c.split.clone(),
            video: format!("video_{:04}", i + 1),
        })
        .collect()
}

/// The ego's action in JAAD's words, from its speed and acceleration.
pub fn vehicle_action(e: &EgoFrame) -> &'static str {
    if e.speed_mps < 0.1 {
        "stopped"
    } else if e.accel_mps2 > 0.5 {
        "accelerating"
    } else if e.accel_mps2 < -0.5 {
        "decelerating"
    } else if e.speed_mps < 5.0 {
        "moving_slow"
    } else {
        "moving_fast"
    }
}

/// The side of a pedestrian the camera sees: JAAD's `pose_front/back/left/right` from the body's yaw and the
/// direction from the ego to the pedestrian.
fn facing(yaw_rad: f32, from_ego: DVec2) -> &'static str {
    let towards_camera = (-from_ego).to_angle();
    let rel = wrap_pi(towards_camera - f64::from(yaw_rad));
    if rel.abs() <= std::f64::consts::FRAC_PI_4 {
        "pose_front"
    } else if rel.abs() >= 3.0 * std::f64::consts::FRAC_PI_4 {
        "pose_back"
    } else if rel > 0.0 {
        // The camera is to the pedestrian's left.
        "pose_left"
    } else {
        "pose_right"
    }
}

const APPEARANCE: [&str; 24] = [
    "baby",
    "backpack",
    "bag_elbow",
    "bag_hand",
    "bag_left_side",
    "bag_right_side",
    "bag_shoulder",
    "bicycle_motorcycle",
    "cap",
    "clothes_below_knee",
    "clothes_lower_dark",
    "clothes_lower_light",
    "clothes_upper_dark",
    "clothes_upper_light",
    "hood",
    "object",
    "phone",
    "pose_back",
    "pose_front",
    "pose_left",
    "pose_right",
    "stroller_cart",
    "sunglasses",
    "umbrella",
];

/// Whether a pedestrian's figure shows JAAD's appearance label `label` (a hat is a `cap`; a shoulder bag hangs
/// on the left; a coat reaches below the knee; an open umbrella is `umbrella`, a hood up `hood`); the pose labels come from the
/// facing.
fn worn(p: &Pedestrian, label: &str) -> bool {
    match label {
        "backpack" => p.carry == "backpack",
        "bag_shoulder" | "bag_left_side" => p.carry == "shoulder_bag",
        "cap" => p.headwear,
        "clothes_below_knee" => p.garment == "coat",
        "umbrella" => p.umbrella,
        "hood" => p.hood,
        _ => false,
    }
}

/// A town's crosswalks as (outline, centre), worked out once per clip.
fn crosswalks(net: Option<&RoadNetwork>) -> Vec<(&[DVec2], DVec2)> {
    net.map_or_else(Vec::new, |net| {
        net.crosswalks
            .iter()
            .map(|c| {
                let centre = c.polygon.iter().copied().sum::<DVec2>() / c.polygon.len().max(1) as f64;
                (c.polygon.as_slice(), centre)
            })
            .collect()
    })
}

/// Whether a crosswalk lies ahead of the ego within 40 m, or under it (JAAD's per-frame `ped_crossing`).
fn crosswalk_ahead(crosswalks: &[(&[DVec2], DVec2)], e: &EgoFrame) -> bool {
    let (p, fwd) = (DVec2::new(e.x_m, e.y_m), DVec2::from_angle(e.yaw_rad));
    crosswalks.iter().any(|&(polygon, centre)| {
        let d = centre - p;
        crate::world::point_in_polygon(polygon, p) || (d.length() < 40.0 && d.dot(fwd) > 0.7 * d.length())
    })
}

fn write_video(
    out: &Path,
    clip: &Clip,
    v: &VideoOf,
    size: (u32, u32),
    net: Option<&RoadNetwork>,
) -> Result<usize, crate::error::Error> {
    let peds: Vec<_> = clip.pedestrians.values().filter(|p| !p.frames.is_empty()).collect();
    let mut x = String::new();
    let _ = write!(
        x,
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<annotations><version>1.1</version><meta><task><name>{}</name>\
         <size>{}</size><original_size><width>{}</width><height>{}</height></original_size></task></meta>\n",
        v.video, clip.frame_count, size.0, size.1
    );
    for p in &peds {
        let id = track_id(v, p.id);
        x.push_str("<track label=\"pedestrian\">\n");
        for f in &p.frames {
            let b = f.bbox_px;
            let Labels {
                look,
                action,
                cross,
                hand_gesture,
                nod,
                reaction,
                ..
            } = Labels::of(f);
            let _ = writeln!(
                x,
                "<box frame=\"{}\" keyframe=\"1\" occluded=\"{}\" outside=\"0\" xbr=\"{:.2}\" xtl=\"{:.2}\" ybr=\"{:.2}\" \
                 ytl=\"{:.2}\"><attribute name=\"id\">{id}</attribute><attribute name=\"old_id\">pedestrian</attribute>\
                 <attribute name=\"look\">{look}</attribute><attribute name=\"reaction\">{reaction}</attribute>\
                 <attribute name=\"action\">{action}</attribute><attribute name=\"cross\">{cross}</attribute>\
                 <attribute name=\"hand_gesture\">{hand_gesture}</attribute><attribute name=\"occlusion\">{}</attribute>\
                 <attribute name=\"nod\">{nod}</attribute></box>",
                f.frame,
                u8::from(f.occlusion >= 0.25),
                b[2],
                b[0],
                b[3],
                b[1],
                occlusion_class(f.occlusion)
            );
        }
        x.push_str("</track>\n");
    }
    x.push_str("</annotations>\n");
    write_file(&out.join("annotations").join(format!("{}.xml", v.video)), x.as_bytes())?;

    let mut groups: BTreeMap<u32, usize> = BTreeMap::new();
    for p in clip.pedestrians.values() {
        if let Some(g) = p.group_id {
            *groups.entry(g).or_default() += 1;
        }
    }
    let mut a = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<ped_attributes>\n");
    for p in &peds {
        let first_c = p.frames.iter().find(|f| f.crossing).map(|f| f.frame);
        let crossing_point = if p.crosser { first_c } else { None };
        let at = crossing_point
            .and_then(|c| p.frames.iter().find(|f| f.frame == c))
            .unwrap_or(&p.frames[p.frames.len() - 1]);
        let lights_run = !clip.traffic_lights.is_empty();
        let place = net.map_or(Place::UNKNOWN, |n| {
            place_at(n, f64::from(at.x_m), f64::from(at.y_m), lights_run)
        });
        let on_crosswalk = place.on_crosswalk;
        let _ = writeln!(
            a,
            "<pedestrian age=\"{}\" crossing=\"{}\" crossing_point=\"{}\" decision_point=\"{}\" designated=\"{}\" \
             gender=\"{}\" group_size=\"{}\" id=\"{}\" intersection=\"{}\" motion_direction=\"{}\" num_lanes=\"{}\" \
             old_id=\"pedestrian\" signalized=\"{}\" traffic_direction=\"{}\" />",
            xml_escape(&p.age_group),
            u8::from(p.crosser),
            crossing_point.map_or(-1, i64::from),
            p.intention_frame.map_or(-1, i64::from),
            if on_crosswalk { "D" } else { "ND" },
            xml_escape(&p.gender),
            p.group_id.and_then(|g| groups.get(&g)).copied().unwrap_or(1),
            track_id(v, p.id),
            if place.intersection == "midblock" { "no" } else { "yes" },
            if p.crosser { "LAT" } else { "n/a" },
            place.num_lanes,
            if on_crosswalk { "NS" } else { "n/a" },
            place.traffic_direction,
        );
    }
    a.push_str("</ped_attributes>\n");
    write_file(
        &out.join("annotations_attributes")
            .join(format!("{}_attributes.xml", v.video)),
        a.as_bytes(),
    )?;

    let mut ap = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<pedestrian_appearance>\n");
    for p in &peds {
        let _ = writeln!(
            ap,
            "<track id=\"{}\" label=\"pedestrian\" old_id=\"pedestrian\">",
            track_id(v, p.id)
        );
        for f in &p.frames {
            let e = &clip.ego[(f.frame as usize).min(clip.ego.len() - 1)];
            let side = facing(
                f.yaw_rad,
                DVec2::new(f64::from(f.x_m) - e.x_m, f64::from(f.y_m) - e.y_m),
            );
            ap.push_str("<box");
            for label in APPEARANCE {
                let _ = write!(ap, " {label}=\"{}\"", u8::from(label == side || worn(p, label)));
            }
            let _ = writeln!(ap, " frame=\"{}\" />", f.frame);
        }
        ap.push_str("</track>\n");
    }
    ap.push_str("</pedestrian_appearance>\n");
    write_file(
        &out.join("annotations_appearance")
            .join(format!("{}_appearance.xml", v.video)),
        ap.as_bytes(),
    )?;

    let mut t =
        String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<traffic_scene><road_type>street</road_type>\n");
    let mut veh = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<vehicle_info>\n");
    let crosswalks = crosswalks(net);
    for (i, e) in clip.ego.iter().enumerate() {
        let _ = writeln!(
            t,
            "<frame id=\"{i}\" ped_crossing=\"{}\" ped_sign=\"0\" stop_sign=\"0\" traffic_light=\"n/a\" />",
            u8::from(crosswalk_ahead(&crosswalks, e))
        );
        let _ = writeln!(veh, "<frame action=\"{}\" id=\"{i}\" />", vehicle_action(e));
    }
    t.push_str("</traffic_scene>\n");
    veh.push_str("</vehicle_info>\n");
    write_file(
        &out.join("annotations_traffic").join(format!("{}_traffic.xml", v.video)),
        t.as_bytes(),
    )?;
    write_file(
        &out.join("annotations_vehicle").join(format!("{}_vehicle.xml", v.video)),
        veh.as_bytes(),
    )?;
    Ok(peds.len())
}

/// `pedsynth_export.json`.
#[derive(Serialize)]
struct ExportRecord<'a> {
    format: &'a str,
    dataset: &'a str,
    spec_hash: &'a str,
    pedestrian_id: &'a str,
    images: &'a str,
    videos: &'a [VideoOf],
}

/// What an export did.
#[derive(Debug, Default)]
pub struct JaadReport {
    pub videos: usize,
    pub pedestrian_tracks: usize,
    pub images: usize,
    pub videos_linked: usize,
    pub images_note: String,
}

/// Writes the JAAD layout of `ds` into `out`.
pub fn export(
    ds: &Dataset,
    out: &Path,
    link: LinkMode,
    warn: &mut dyn FnMut(String),
) -> Result<JaadReport, crate::error::Error> {
    let videos = assign_videos(&ds.clips);
    let rgb = &ds.spec.sensors.rgb;
    let towns = super::towns(ds, warn);
    let (rgb_files, images_note) = super::images_note(ds, link);
    let mut report = JaadReport {
        videos: videos.len(),
        images_note,
        ..JaadReport::default()
    };
    let mut splits: BTreeMap<&str, Vec<&str>> = ["train", "val", "test"].into_iter().map(|s| (s, Vec::new())).collect();
    let progress = super::progress(ds.clips.len());
    for (info, v) in ds.clips.iter().zip(&videos) {
        let clip = &ds.load(info)?;
        let net = towns.get(&clip.town).map(|t| &t.network);
        report.pedestrian_tracks += write_video(out, clip, v, (rgb.width_px, rgb.height_px), net)?;
        splits.entry(v.split.as_str()).or_default().push(v.video.as_str());
        match rgb_files {
            RgbFiles::Png => report.images += link_frames(ds, clip, &out.join("images").join(&v.video), 5, link)?,
            RgbFiles::Mp4 => {
                let to = out.join("JAAD_clips").join(format!("{}.mp4", v.video));
                report.videos_linked += usize::from(super::link_video(ds, clip, &to, link)?);
            }
            RgbFiles::None => {}
        }
        progress.clip_done(&clip.clip_id, u64::from(clip.frame_count));
    }
    progress.finish();
    for (split, list) in &splits {
        if list.is_empty() {
            warn(format!(
                "warning: split `{split}` has no clips: split_ids/default/{split}.txt is empty, and JAAD's \
                 generate_data_trajectory_sequence('{split}') fails on an empty split"
            ));
        }
        let text: String = list.iter().map(|v| format!("{v}\n")).collect();
        write_file(
            &out.join("split_ids").join("default").join(format!("{split}.txt")),
            text.as_bytes(),
        )?;
    }
    let record = ExportRecord {
        format: "jaad",
        dataset: &ds.manifest.dataset,
        spec_hash: &ds.manifest.spec_hash,
        pedestrian_id: "0_<video number>_<pedestrian id in the tables>b",
        images: &report.images_note,
        videos: &videos,
    };
    let json = crate::error::to_json(&record, true)? + "\n";
    write_file(&out.join("pedsynth_export.json"), json.as_bytes())?;
    Ok(report)
}
