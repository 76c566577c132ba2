//! `pedsynth export pie`: the PIE dataset's layout (../shared/interfaces/pie/annotations-README.md) so that
//! PIE's own `pie_data.py` loads a pedsynth dataset unmodified: per video an annotation XML (pedestrian tracks
//! with behaviour labels, traffic vehicle tracks with projected boxes), a pedestrian-attributes XML and an
//! ego-vehicle (OBD) XML, the images linked from `sensors/rgb`, and `pedsynth_export.json` with the mapping.
//! Every value comes from the dataset's tables, its resolved spec and its town; DATASET.md lists the mapping.

pub(crate) use crate::util::xml::escape as xml_escape;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Serialize;

use super::dataset::{Clip, ClipInfo, Dataset, Pedestrian};
use super::{LinkMode, RgbFiles, link_frames, write_file};
use crate::error::{Error, code};
use crate::sim::rig::Camera;
use crate::world::{LaneType, RoadNetwork, TravelDirection};

/// PIE's default split: the sets each of our splits goes to (`PIE._get_image_set_ids`).
pub const SETS: [(&str, &[&str]); 3] = [
    ("train", &["set01", "set02", "set04"]),
    ("val", &["set05", "set06"]),
    ("test", &["set03"]),
];

/// Where a clip went.
#[derive(Clone, Debug, Serialize)]
pub struct VideoOf {
    pub clip_id: String,
    pub split: String,
    /// `setNN`.
    pub set: String,
    /// `video_NNNN`.
    pub video: String,
}

/// Spreads the clips (sorted by id) over the sets of their split, round robin; videos are numbered from 1
/// within a set.
pub fn assign_videos(clips: &[ClipInfo]) -> Result<Vec<VideoOf>, Error> {
    let mut next_set: BTreeMap<&str, usize> = BTreeMap::new();
    let mut next_video: BTreeMap<&str, u32> = BTreeMap::new();
    let mut out = Vec::with_capacity(clips.len());
    for c in clips {
        let sets = SETS
            .iter()
            .find(|(split, _)| *split == c.split)
            .map(|(_, sets)| *sets)
            .ok_or_else(|| {
                Error::new(
                    code::DATASET_INVALID,
                    format!("clip {}: split `{}` is not train, val or test", c.clip_id, c.split),
                )
            })?;
        let k = next_set.entry(sets[0]).or_insert(0);
        let set = sets[*k % sets.len()];
        *k += 1;
        let v = next_video.entry(set).or_insert(0);
        *v += 1;
        out.push(VideoOf {
            clip_id: c.clip_id.clone(),
            split: c.split.clone(),
            set: set.to_owned(),
            video: format!("video_{v:04}"),
        });
    }
    Ok(out)
}

/// `<set number>_<video number>`, the prefix of PIE's object ids (`5_2` for set05, video_0002).
pub fn video_prefix(v: &VideoOf) -> String {
    let num = |s: &str| {
        s.trim_start_matches(|c: char| !c.is_ascii_digit())
            .trim_start_matches('0')
            .to_owned()
    };
    format!("{}_{}", num(&v.set), num(&v.video))
}

/// PIE's pedestrian id: `<set number>_<video number>_<our pedestrian id>` (as PIE's `5_2_1751`).
pub fn track_id(v: &VideoOf, pedestrian: u32) -> String {
    format!("{}_{pedestrian}", video_prefix(v))
}

/// PIE's occlusion class of an occluded fraction (< 25 % none, 25–75 % part, > 75 % full).
pub fn occlusion_class(fraction: f32) -> &'static str {
    if fraction < 0.25 {
        "none"
    } else if fraction <= 0.75 {
        "part"
    } else {
        "full"
    }
}

/// The per-frame behaviour labels of PIE and JAAD, in their words, from the `annotations` table (DATASET.md
/// maps each to its definition in those datasets).
pub struct Labels {
    /// `looking` or `not-looking` (the table's `look`).
    pub look: &'static str,
    /// `walking` or `standing` (the table's `action`).
    pub action: &'static str,
    /// `crossing` when C = 1, `not-crossing` otherwise.
    pub cross: &'static str,
    /// PIE's `gesture`: the table's gesture (`hand_ack`, `hand_yield`, `nod`) or `__undefined__`.
    pub gesture: &'static str,
    /// JAAD's `hand_gesture`: `greet` for an acknowledging hand, `yield` for a wave-through, or `__undefined__`.
    pub hand_gesture: &'static str,
    /// JAAD's `nod`: `nodding` or `__undefined__`.
    pub nod: &'static str,
    /// JAAD's `reaction`: the table's reaction (`clear_path`, `speed_up`, `slow_down`) or `__undefined__`.
    pub reaction: &'static str,
}

impl Labels {
    /// The labels of an annotated frame.
    pub fn of(f: &super::dataset::AnnotatedFrame) -> Labels {
        let (gesture, hand_gesture, nod) = match f.gesture.as_str() {
            "hand_ack" => ("hand_ack", "greet", "__undefined__"),
            "hand_yield" => ("hand_yield", "yield", "__undefined__"),
            "nod" => ("nod", "__undefined__", "nodding"),
            _ => ("__undefined__", "__undefined__", "__undefined__"),
        };
        Labels {
            look: if f.look { "looking" } else { "not-looking" },
            action: if f.action == "walking" { "walking" } else { "standing" },
            cross: if f.crossing { "crossing" } else { "not-crossing" },
            gesture,
            hand_gesture,
            nod,
            reaction: match f.reaction.as_str() {
                "clear_path" => "clear_path",
                "speed_up" => "speed_up",
                "slow_down" => "slow_down",
                _ => "__undefined__",
            },
        }
    }
}

/// The track's event frame (PIE's `crossing_point`): the first annotated frame with C = 1 for a crosser, the
/// last annotated frame otherwise — always an annotated frame.
pub fn crossing_point(p: &Pedestrian) -> Option<u32> {
    let first_crossing = p.frames.iter().find(|f| f.crossing).map(|f| f.frame);
    if p.crosser { first_crossing } else { None }.or_else(|| p.frames.last().map(|f| f.frame))
}

/// What the map says about where a pedestrian crosses (or would cross).
#[derive(Clone, Debug, PartialEq)]
pub struct Place {
    pub intersection: &'static str,
    pub num_lanes: u32,
    pub signalized: &'static str,
    pub traffic_direction: &'static str,
    /// Whether the point lies on a crosswalk.
    pub on_crosswalk: bool,
}

impl Place {
    /// Unknown (no town to ask): PIE's `n/a`-like values, `num_lanes` 0.
    pub const UNKNOWN: Place = Place {
        intersection: "midblock",
        num_lanes: 0,
        signalized: "n/a",
        traffic_direction: "TW",
        on_crosswalk: false,
    };
}

/// The road at a point: its driving lanes in the lane section there, their directions, a junction, a
/// crosswalk and (where traffic lights ran, `lights_run`) whether that crosswalk is signalised.
pub fn place_at(net: &RoadNetwork, x_m: f64, y_m: f64, lights_run: bool) -> Place {
    let p = glam::DVec2::new(x_m, y_m);
    let hit = net
        .lane_at(p)
        .filter(|h| h.lane_type == LaneType::Driving)
        .or_else(|| net.nearest_driving_lane(p, 30.0));
    let Some(hit) = hit else {
        return Place::UNKNOWN;
    };
    let lane = &net.lanes[hit.lane as usize];
    let road = &net.roads[hit.road as usize];
    let driving: Vec<&crate::world::Lane> = net.lanes[road.lanes.start as usize..road.lanes.end as usize]
        .iter()
        .filter(|l| l.section == lane.section && l.lane_type == LaneType::Driving)
        .collect();
    let forward = driving
        .iter()
        .any(|l| matches!(l.travel, TravelDirection::Forward | TravelDirection::Both));
    let backward = driving
        .iter()
        .any(|l| matches!(l.travel, TravelDirection::Backward | TravelDirection::Both));
    let intersection = match &road.junction {
        Some(id) => {
            let arms: std::collections::BTreeSet<&str> = net
                .junctions
                .iter()
                .filter(|j| &j.id == id)
                .flat_map(|j| j.connections.iter().map(|c| c.incoming_road.as_str()))
                .collect();
            if arms.len() == 3 { "T" } else { "four-way" }
        }
        None => "midblock",
    };
    let on_crosswalk = net
        .crosswalks
        .iter()
        .any(|c| crate::world::point_in_polygon(&c.polygon, p));
    Place {
        intersection,
        num_lanes: driving.len() as u32,
        // PIE's values: `C` a crosswalk, `CS` a crosswalk with a pedestrian signal.
        signalized: match (
            on_crosswalk,
            lights_run && crate::world::signals::crosswalk_signal(net, p).is_some(),
        ) {
            (true, true) => "CS",
            (true, false) => "C",
            (false, _) => "n/a",
        },
        traffic_direction: if forward && backward { "TW" } else { "OW" },
        on_crosswalk,
    }
}

/// Appends a PIE vehicle `<box>` (its `id` and `type` attributes) to a track.
fn vehicle_box_xml(boxes: &mut String, frame: u32, b: [f64; 4], id: &str, kind: &str) {
    let _ = writeln!(
        boxes,
        "    <box frame=\"{frame}\" keyframe=\"1\" occluded=\"0\" outside=\"0\" xtl=\"{:.2}\" ytl=\"{:.2}\" \
         xbr=\"{:.2}\" ybr=\"{:.2}\">\n      <attribute name=\"id\">{id}</attribute>\n      \
         <attribute name=\"type\">{kind}</attribute>\n    </box>",
        b[0], b[1], b[2], b[3],
    );
}

/// A vehicle's projected box in a frame: the 8 corners of its 3D box, all in front of the camera, the box
/// clipped to the image; `None` when nothing of it is in the image.
fn vehicle_box(cam: &crate::sim::rig::CameraPose, pos: DVec3, yaw_rad: f64) -> Option<[f64; 4]> {
    use crate::sim::{VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
    let (s, c) = yaw_rad.sin_cos();
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for (fx, fy, z) in [
        (0.5, 0.5, 0.0),
        (0.5, -0.5, 0.0),
        (-0.5, 0.5, 0.0),
        (-0.5, -0.5, 0.0),
        (0.5, 0.5, 1.0),
        (0.5, -0.5, 1.0),
        (-0.5, 0.5, 1.0),
        (-0.5, -0.5, 1.0),
    ] {
        let (lx, ly) = (fx * VEHICLE_LENGTH_M, fy * VEHICLE_WIDTH_M);
        let w = pos + DVec3::new(c * lx - s * ly, s * lx + c * ly, z * VEHICLE_HEIGHT_M);
        let p = cam.project(w);
        if p.depth_m < 0.5 || p.depth_m > 80.0 {
            return None;
        }
        (lo, hi) = (lo.min(p.px), hi.max(p.px));
    }
    let (w, h) = (f64::from(cam.camera.width_px), f64::from(cam.camera.height_px));
    let b = [lo.x.max(0.0), lo.y.max(0.0), hi.x.min(w), hi.y.min(h)];
    (b[2] - b[0] >= 2.0 && b[3] - b[1] >= 2.0).then_some(b)
}

/// A traffic light's projected box in a frame: the 8 corners of its housing around the head's centre `pos`,
/// all 0.5–80 m in front of the camera, the box clipped to the image; `None` when nothing of it is in the image.
fn light_box(cam: &crate::sim::rig::CameraPose, pos: DVec3, facing_rad: f64) -> Option<[f64; 4]> {
    let (s, c) = facing_rad.sin_cos();
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for (fx, fy, fz) in [
        (1.0, 1.0, 1.0),
        (1.0, -1.0, 1.0),
        (-1.0, 1.0, 1.0),
        (-1.0, -1.0, 1.0),
        (1.0, 1.0, -1.0),
        (1.0, -1.0, -1.0),
        (-1.0, 1.0, -1.0),
        (-1.0, -1.0, -1.0),
    ] {
        let (lx, ly) = (
            fx * crate::sensors::scene::SIGNAL_HOUSING_HALF_DEPTH_M as f64,
            fy * crate::sensors::scene::SIGNAL_HOUSING_HALF_WIDTH_M as f64,
        );
        let z = fz * crate::sensors::scene::SIGNAL_HOUSING_HALF_HEIGHT_M as f64;
        let p = cam.project(pos + DVec3::new(c * lx - s * ly, s * lx + c * ly, z));
        if p.depth_m < 0.5 || p.depth_m > 80.0 {
            return None;
        }
        (lo, hi) = (lo.min(p.px), hi.max(p.px));
    }
    let (w, h) = (f64::from(cam.camera.width_px), f64::from(cam.camera.height_px));
    let b = [lo.x.max(0.0), lo.y.max(0.0), hi.x.min(w), hi.y.min(h)];
    (b[2] - b[0] >= 1.0 && b[3] - b[1] >= 1.0).then_some(b)
}

/// A ground polygon's projected box in a frame: every corner 0.5–80 m in front of the camera, the box clipped to
/// the image; `None` when nothing of it is in the image.
fn ground_box(cam: &crate::sim::rig::CameraPose, polygon: &[glam::DVec2], z_m: f64) -> Option<[f64; 4]> {
    let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    for c in polygon {
        let p = cam.project(DVec3::new(c.x, c.y, z_m));
        if p.depth_m < 0.5 || p.depth_m > 80.0 {
            return None;
        }
        (lo, hi) = (lo.min(p.px), hi.max(p.px));
    }
    let (w, h) = (f64::from(cam.camera.width_px), f64::from(cam.camera.height_px));
    let b = [lo.x.max(0.0), lo.y.max(0.0), hi.x.min(w), hi.y.min(h)];
    (b[2] - b[0] >= 2.0 && b[3] - b[1] >= 2.0).then_some(b)
}

/// Writes one clip's three XML files; returns the number of pedestrian tracks and vehicle tracks.
fn write_video(
    out: &Path,
    clip: &Clip,
    v: &VideoOf,
    camera: &Camera,
    net: Option<&RoadNetwork>,
) -> Result<(usize, usize), Error> {
    let mut x = String::new();
    let _ = write!(
        x,
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<annotations>\n  <version>1.1</version>\n  <meta>\n    <task>\n      \
         <name>{}</name>\n      <size>{}</size>\n      <original_size>\n        <width>{}</width>\n        \
         <height>{}</height>\n      </original_size>\n    </task>\n  </meta>\n",
        xml_escape(&clip.clip_id),
        clip.frame_count,
        camera.width_px,
        camera.height_px
    );
    let mut tracks = 0;
    for p in clip.pedestrians.values().filter(|p| !p.frames.is_empty()) {
        tracks += 1;
        let id = track_id(v, p.id);
        let _ = writeln!(x, "  <track label=\"pedestrian\">");
        for f in &p.frames {
            let b = f.bbox_px;
            let Labels {
                look,
                action,
                cross,
                gesture,
                ..
            } = Labels::of(f);
            let _ = writeln!(
                x,
                "    <box frame=\"{}\" keyframe=\"1\" occluded=\"{}\" outside=\"0\" xtl=\"{:.2}\" ytl=\"{:.2}\" \
                 xbr=\"{:.2}\" ybr=\"{:.2}\">\n      <attribute name=\"id\">{id}</attribute>\n      \
                 <attribute name=\"occlusion\">{}</attribute>\n      <attribute name=\"action\">{action}</attribute>\n      \
                 <attribute name=\"gesture\">{gesture}</attribute>\n      <attribute name=\"look\">{look}</attribute>\n      \
                 <attribute name=\"cross\">{cross}</attribute>\n    </box>",
                f.frame,
                u8::from(f.occlusion >= 0.25),
                b[0],
                b[1],
                b[2],
                b[3],
                occlusion_class(f.occlusion),
            );
        }
        let _ = writeln!(x, "  </track>");
    }
    let mut vehicle_tracks = 0;
    let prefix = video_prefix(v);
    // The annotations' camera in each frame, placed once.
    let cameras: Vec<_> = clip
        .ego
        .iter()
        .map(|e| camera.at(DVec3::new(e.x_m, e.y_m, e.z_m), e.yaw_rad, e.pitch_rad))
        .collect();
    let mut i = 0;
    while i < clip.vehicles.len() {
        let vid = clip.vehicles[i].vehicle;
        let mut boxes = String::new();
        while i < clip.vehicles.len() && clip.vehicles[i].vehicle == vid {
            let vf = &clip.vehicles[i];
            i += 1;
            let Some(cam) = cameras.get(vf.frame as usize) else {
                continue;
            };
            if let Some(b) = vehicle_box(cam, DVec3::new(vf.x_m, vf.y_m, vf.z_m), vf.yaw_rad) {
                vehicle_box_xml(&mut boxes, vf.frame, b, &format!("{prefix}_{vid}v"), "car");
            }
        }
        if !boxes.is_empty() {
            vehicle_tracks += 1;
            let _ = write!(x, "  <track label=\"vehicle\">\n{boxes}  </track>\n");
        }
    }
    // Cyclists as PIE vehicles of type `bicycle`, with the `cyclists` table's box of rider and bicycle.
    for track in clip.cyclists.chunk_by(|a, b| a.cyclist == b.cyclist) {
        let cid = track[0].cyclist;
        let mut boxes = String::new();
        for c in track {
            if let Some(b) = c.bbox {
                vehicle_box_xml(&mut boxes, c.frame, b, &format!("{prefix}_{cid}b"), "bicycle");
            }
        }
        if !boxes.is_empty() {
            vehicle_tracks += 1;
            let _ = write!(x, "  <track label=\"vehicle\">\n{boxes}  </track>\n");
        }
    }
    // Crosswalks of the town near the ego's path, projected like the vehicles: the polygon on the ground.
    if let Some(net) = net {
        for (k, cw) in net.crosswalks.iter().enumerate() {
            let Some((lo, hi)) = crate::world::bounding_box(cw.polygon.iter().copied()) else {
                continue;
            };
            let centre = (lo + hi) * 0.5;
            if !clip
                .ego
                .iter()
                .any(|e| centre.distance(glam::DVec2::new(e.x_m, e.y_m)) < 80.0)
            {
                continue;
            }
            let z_m = net.lane_at(centre).map_or(0.0, |h| h.z_m);
            let mut boxes = String::new();
            for (frame, cam) in cameras.iter().enumerate() {
                if let Some(b) = ground_box(cam, &cw.polygon, z_m) {
                    let _ = writeln!(
                        boxes,
                        "    <box frame=\"{frame}\" keyframe=\"1\" occluded=\"0\" outside=\"0\" xtl=\"{:.2}\" ytl=\"{:.2}\" \
                         xbr=\"{:.2}\" ybr=\"{:.2}\">\n      <attribute name=\"id\">{prefix}_{k}cw</attribute>\n    </box>",
                        b[0], b[1], b[2], b[3],
                    );
                }
            }
            if !boxes.is_empty() {
                let _ = write!(x, "  <track label=\"crosswalk\">\n{boxes}  </track>\n");
            }
        }
    }
    // Traffic lights facing the ego: PIE's `traffic_light` tracks (type `regular`, state red / yellow / green),
    // the head's housing projected like the vehicles. Ids number the clip's lights in id order.
    let mut light_ids: Vec<&str> = clip.traffic_lights.iter().map(|l| l.signal.as_str()).collect();
    light_ids.sort_unstable();
    light_ids.dedup();
    for (k, id) in light_ids.iter().enumerate() {
        let mut boxes = String::new();
        for l in clip.traffic_lights.iter().filter(|l| l.signal == *id && l.faces_ego) {
            let Some(cam) = cameras.get(l.frame as usize) else {
                continue;
            };
            let Some(b) = light_box(cam, DVec3::new(l.x_m, l.y_m, l.z_m), l.facing_rad) else {
                continue;
            };
            let state = match l.state.as_str() {
                "amber" => "yellow",
                s => s,
            };
            let _ = writeln!(
                boxes,
                "    <box frame=\"{}\" keyframe=\"1\" occluded=\"0\" outside=\"0\" xtl=\"{:.2}\" ytl=\"{:.2}\" \
                 xbr=\"{:.2}\" ybr=\"{:.2}\">\n      <attribute name=\"id\">{prefix}_{k}tl</attribute>\n      \
                 <attribute name=\"type\">regular</attribute>\n      <attribute name=\"state\">{state}</attribute>\n    </box>",
                l.frame, b[0], b[1], b[2], b[3],
            );
        }
        if !boxes.is_empty() {
            let _ = write!(x, "  <track label=\"traffic_light\">\n{boxes}  </track>\n");
        }
    }
    x.push_str("</annotations>\n");
    write_file(
        &out.join("annotations")
            .join(&v.set)
            .join(format!("{}_annt.xml", v.video)),
        x.as_bytes(),
    )?;

    // Attributes: one <pedestrian> per track.
    let mut a = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<ped_attributes>\n");
    for p in clip.pedestrians.values().filter(|p| !p.frames.is_empty()) {
        let event = crossing_point(p).unwrap_or(0);
        let event_idx = p.frames.iter().position(|f| f.frame == event).unwrap_or(0);
        let critical = p.frames[event_idx.saturating_sub(1)].frame;
        let at = &p.frames[event_idx];
        let lights_run = !clip.traffic_lights.is_empty();
        let place = net.map_or(Place::UNKNOWN, |n| {
            place_at(n, f64::from(at.x_m), f64::from(at.y_m), lights_run)
        });
        let _ = writeln!(
            a,
            "  <pedestrian age=\"{}\" critical_point=\"{critical}\" crossing=\"{}\" crossing_point=\"{event}\" \
             exp_start_point=\"{}\" gender=\"{}\" id=\"{}\" intention_prob=\"{}\" intersection=\"{}\" num_lanes=\"{}\" \
             signalized=\"{}\" traffic_direction=\"{}\" />",
            xml_escape(&p.age_group),
            u8::from(p.crosser),
            p.frames[0].frame,
            xml_escape(&p.gender),
            track_id(v, p.id),
            if p.intention_frame.is_some() { 1 } else { 0 },
            place.intersection,
            place.num_lanes,
            place.signalized,
            place.traffic_direction,
        );
    }
    a.push_str("</ped_attributes>\n");
    write_file(
        &out.join("annotations_attributes")
            .join(&v.set)
            .join(format!("{}_attributes.xml", v.video)),
        a.as_bytes(),
    )?;

    // Ego vehicle: one <frame> per frame.
    let mut o = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<vehicle_info>\n");
    let dt = 1.0 / f64::from(clip.fps.max(1));
    let n = clip.ego.len();
    for (i, e) in clip.ego.iter().enumerate() {
        let (a, b) = (&clip.ego[i.saturating_sub(1)], &clip.ego[(i + 1).min(n - 1)]);
        let span = ((i + 1).min(n - 1) - i.saturating_sub(1)) as f64 * dt;
        let yaw_rate = if span > 0.0 {
            wrap_pi(b.yaw_rad - a.yaw_rad) / span
        } else {
            0.0
        };
        let (lat, lon) = local_lat_lon(e.x_m, e.y_m);
        let kmh = e.speed_mps * 3.6;
        let _ = writeln!(
            o,
            "  <frame id=\"{i}\" GPS_speed=\"{kmh:.4}\" OBD_speed=\"{kmh:.4}\" accX=\"{:.5}\" accY=\"{:.5}\" \
             accZ=\"9.80665\" gyroX=\"0\" gyroY=\"0\" gyroZ=\"{:.5}\" heading_angle=\"{:.4}\" latitude=\"{lat:.9}\" \
             longitude=\"{lon:.9}\" pitch=\"{}\" roll=\"0\" yaw=\"{:.4}\" />",
            e.accel_mps2,
            e.speed_mps * yaw_rate,
            yaw_rate.to_degrees(),
            compass_heading_deg(e.yaw_rad),
            // "0" on a level car, as before the pitch wobble.
            if e.pitch_rad == 0.0 {
                "0".to_owned()
            } else {
                format!("{:.4}", e.pitch_rad.to_degrees())
            },
            e.yaw_rad.to_degrees(),
        );
    }
    o.push_str("</vehicle_info>\n");
    write_file(
        &out.join("annotations_vehicle")
            .join(&v.set)
            .join(format!("{}_obd.xml", v.video)),
        o.as_bytes(),
    )?;
    Ok((tracks, vehicle_tracks))
}

pub(crate) fn wrap_pi(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

/// Compass heading, degrees clockwise from north (world +y), in [0, 360).
pub fn compass_heading_deg(yaw_rad: f64) -> f64 {
    (90.0 - yaw_rad.to_degrees()).rem_euclid(360.0)
}

/// The documented local projection for latitude and longitude (no geoReference is used): an equirectangular
/// projection about (0°, 0°) on the WGS84 equatorial radius, world +y north and +x east.
pub fn local_lat_lon(x_m: f64, y_m: f64) -> (f64, f64) {
    const R: f64 = 6_378_137.0;
    ((y_m / R).to_degrees(), (x_m / R).to_degrees())
}

/// `pedsynth_export.json`.
#[derive(Serialize)]
struct ExportRecord<'a> {
    format: &'a str,
    dataset: &'a str,
    spec_hash: &'a str,
    sets: BTreeMap<&'a str, &'a [&'a str]>,
    pedestrian_id: &'a str,
    images: &'a str,
    videos: &'a [VideoOf],
}

/// What an export did.
#[derive(Debug, Default)]
pub struct PieReport {
    pub videos: usize,
    pub pedestrian_tracks: usize,
    pub vehicle_tracks: usize,
    pub images: usize,
    pub videos_linked: usize,
    pub images_note: String,
}

/// Writes the PIE layout of `ds` into `out`.
pub fn export(ds: &Dataset, out: &Path, link: LinkMode, warn: &mut dyn FnMut(String)) -> Result<PieReport, Error> {
    let videos = assign_videos(&ds.clips)?;
    let towns = super::towns(ds, warn);
    for (_, sets) in SETS {
        for set in sets {
            for folder in ["annotations", "annotations_attributes", "annotations_vehicle"] {
                let d = out.join(folder).join(set);
                std::fs::create_dir_all(&d).map_err(|e| Error::write(&d, e))?;
            }
        }
    }
    let mut report = PieReport {
        videos: videos.len(),
        ..PieReport::default()
    };
    let (rgb_files, note) = super::images_note(ds, link);
    report.images_note = note;
    let progress = super::progress(ds.clips.len());
    for (info, v) in ds.clips.iter().zip(&videos) {
        let clip = &ds.load(info)?;
        let net = towns.get(&clip.town).map(|t| &t.network);
        let camera = Camera::for_clip(&ds.spec.sensors.rgb, clip.info.seed);
        let (peds, vehicles) = write_video(out, clip, v, &camera, net)?;
        report.pedestrian_tracks += peds;
        report.vehicle_tracks += vehicles;
        match rgb_files {
            RgbFiles::Png => {
                report.images += link_frames(ds, clip, &out.join("images").join(&v.set).join(&v.video), 5, link)?;
            }
            RgbFiles::Mp4 => {
                let to = out.join("PIE_clips").join(&v.set).join(format!("{}.mp4", v.video));
                report.videos_linked += usize::from(super::link_video(ds, clip, &to, link)?);
            }
            RgbFiles::None => {}
        }
        progress.clip_done(&clip.clip_id, u64::from(clip.frame_count));
    }
    progress.finish();
    let sets: BTreeMap<&str, &[&str]> = SETS.iter().copied().collect();
    let record = ExportRecord {
        format: "pie",
        dataset: &ds.manifest.dataset,
        spec_hash: &ds.manifest.spec_hash,
        sets,
        pedestrian_id: "<set number>_<video number>_<pedestrian id in the tables>",
        images: &report.images_note,
        videos: &videos,
    };
    let json = crate::error::to_json(&record, true)? + "\n";
    write_file(&out.join("pedsynth_export.json"), json.as_bytes())?;
    Ok(report)
}

/// The video directory of a clip in an export (for tests and the poses).
pub fn image_dir(out: &Path, v: &VideoOf) -> PathBuf {
    out.join("images").join(&v.set).join(&v.video)
}
