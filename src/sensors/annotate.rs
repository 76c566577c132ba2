//! Annotation of a simulated clip: the visibility gate, tight 2D boxes of the projected body, COCO-17
//! keypoints with visibility flags (occluded: hidden by another object or by the body itself), occlusion by
//! vehicles, buildings, street lamps and other pedestrians, per-frame crossing
//! labels with temporal smoothing, sequence labels, time-to-event and intention onset.
//!
//! Crossing label (the paper's definition): C = 1 in a frame when the pedestrian is in a crossing-type state
//! *and* stands on a driving lane; C stays 1 for up to `crossing_label_smoothing_frames` frames after it
//! leaves the driving lane while still in a crossing-type state (shoulders, parking strips, lane seams).
//! Sequence label (JAAD/PIE): a crosser has C = 1 in at least one annotated frame. TTE counts the frames until
//! the first C = 1 (0 at that frame, null after it and for pedestrians that never cross).
//!
//! Behaviour labels in PIE's and JAAD's terms: `look` (the head's gaze within `look_cone_deg` of the direction
//! to the camera), `action` (walking from 0.3 m/s), the gesture and the reaction the trace records, and the
//! gaze direction itself.

use glam::{DVec2, DVec3};

use super::body::{self, BodyPose, CHILD_OFFSET_M, Capsule};
use super::cyclist;
use super::occlusion::{Occluder, hidden_by_own_body, may_block, occluded, static_occluders};
use super::scene::ClipScenery;
use crate::plan::{ClipScript, Figure};
use crate::sim::gate::{PED_OCCLUDER_RADIUS_PER_M, gate_box_size_px, min_box, too_small};
use crate::sim::rig::{Camera, CameraPose};
use crate::sim::trace::{ClipTrace, Event, Gesture, PedFrame, PedState, Reaction, WalkSignal};
use crate::spec::types::Annotations;
use crate::world::{LaneType, RoadNetwork};

/// Why a pedestrian-frame is not annotated (the first gate it fails).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rejections {
    /// Farther than the gate's distance.
    pub too_far: u64,
    /// Behind the camera.
    pub behind: u64,
    /// Box smaller than the gate's minimum.
    pub too_small: u64,
    /// Box not inside the image.
    pub outside_image: u64,
    /// Occluded beyond the threshold.
    pub occluded: u64,
}

/// One annotated pedestrian-frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnnotationRow {
    /// Frame index.
    pub frame: u32,
    /// Pedestrian id.
    pub pedestrian: u32,
    /// Tight 2D box `[x_min, y_min, x_max, y_max]`, pixels.
    pub bbox_px: [f32; 4],
    /// The annotator box ([`super::annotator`]), pixels.
    pub annotator_bbox_px: [f32; 4],
    /// Crossing label C.
    pub crossing: bool,
    /// Behaviour state.
    pub state: PedState,
    /// Ground distance from the ego vehicle, metres.
    pub distance_m: f32,
    /// Frames until the first C = 1 (None after it and for non-crossers).
    pub tte_frames: Option<i32>,
    /// Share of the body's sample points hidden by other objects.
    pub occlusion: f32,
    /// COCO-17 keypoints: `x, y, v` per joint (v: 0 outside the image, 1 occluded by another object or by the
    /// body itself, 2 visible).
    pub keypoints: [f32; 51],
    /// The 17 joints in the world, `x, y, z` per joint, metres.
    pub keypoints_3d: [f32; 51],
    /// Ground position, metres.
    pub pos_m: [f32; 3],
    /// Body yaw, radians.
    pub yaw_rad: f32,
    /// Ground velocity, m/s.
    pub velocity_mps: [f32; 2],
    /// Lane type under the pedestrian.
    pub lane_type: Option<LaneType>,
    /// Centre of the 3D box, metres.
    pub box3d_centre_m: [f32; 3],
    /// Extents of the 3D box (length, width, height), metres.
    pub box3d_size_m: [f32; 3],
    /// Whether the pedestrian looks at the ego's camera ([`looks_at`]).
    pub look: bool,
    /// Whether it walks (ground speed at least [`WALKING_MPS`]) rather than stands.
    pub walking: bool,
    /// The gesture it makes to the ego's driver.
    pub gesture: Option<Gesture>,
    /// Its reaction to a vehicle.
    pub reaction: Option<Reaction>,
    /// Whether it stands on a crosswalk.
    pub on_crosswalk: bool,
    /// The pedestrian signal of its signalised crosswalk, where lights run.
    pub walk_signal: Option<WalkSignal>,
    /// Whether it is crossing (a crossing state) while its signal shows "don't walk".
    pub against_signal: bool,
    /// The head's forward direction in the world (unit vector).
    pub gaze: [f32; 3],
}

/// A pedestrian moving at least this fast walks (PIE's and JAAD's `action`), m/s.
pub const WALKING_MPS: f64 = 0.3;

/// Whether a head at `eyes` looking along the unit vector `gaze` looks at `target`: the angle between `gaze`
/// and the direction to `target` is at most `cone_deg`.
pub fn looks_at(gaze: DVec3, eyes: DVec3, target: DVec3, cone_deg: f64) -> bool {
    let to_target = (target - eyes).normalize_or_zero();
    to_target != DVec3::ZERO && gaze.dot(to_target) >= cone_deg.to_radians().cos()
}

/// Per-pedestrian results over the whole clip.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PedestrianLabels {
    /// Sequence label: C = 1 in at least one annotated frame.
    pub crosser: bool,
    /// First frame with C = 1 (in any frame, annotated or not).
    pub first_crossing_frame: Option<u32>,
    /// Frame of the decision to cross (intention onset).
    pub intention_frame: Option<u32>,
    /// Number of annotated frames.
    pub annotated_frames: u32,
}

/// The annotations of one clip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClipAnnotations {
    /// Annotated pedestrian-frames, ordered by (frame, pedestrian).
    pub rows: Vec<AnnotationRow>,
    /// Per pedestrian, indexed by id.
    pub pedestrians: Vec<PedestrianLabels>,
    /// Counts of pedestrian-frames that failed the visibility gate, by reason.
    pub rejections: Rejections,
    /// Crossing label C of every pedestrian (by id) in every frame, annotated or not.
    pub crossing: Vec<Vec<bool>>,
    /// Every cyclist-frame in front of the camera whose box reaches at least a pixel into the image, ordered by
    /// (frame, cyclist).
    pub cyclists: Vec<CyclistRow>,
    /// The clip's street lamps, furniture and parked cars: the scenery the occlusion labels test against and
    /// the sensors draw.
    pub scenery: ClipScenery,
}

/// A cyclist seen by the camera in one frame: the box of rider and bicycle, the rider's keypoints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CyclistRow {
    /// Frame index.
    pub frame: u32,
    /// Cyclist id.
    pub cyclist: u32,
    /// 2D box of the rider and the bicycle, `[x_min, y_min, x_max, y_max]`, pixels, clipped to the image.
    pub bbox_px: [f32; 4],
    /// Whether the box was cut by the image's border.
    pub truncated: bool,
    /// Ground distance from the ego vehicle, metres.
    pub distance_m: f32,
    /// Share of the rider's sample points (17 joints, 5 body samples) hidden from the camera.
    pub occlusion: f32,
    /// Whether it passes the pedestrians' visibility gate (distance, minimum box size, inside the image when
    /// required, occlusion).
    pub annotated: bool,
    /// The rider's COCO-17 keypoints `(u, v, flag)` (flag 2 visible, 1 occluded by another object or by the body
    /// itself, 0 outside the image).
    pub keypoints: [f32; 51],
    /// The rider's joints in the world, `(x, y, z)` metres.
    pub keypoints_3d: [f32; 51],
}

/// Occluder owner ids of cyclists' riders start here (pedestrians own their ids).
const RIDER_OWNER_BASE: u32 = 1 << 31;
/// Radius of the cylinder standing in for a cyclist when testing occlusion, metres.
const RIDER_OCCLUDER_RADIUS_M: f64 = 0.3;

/// Per-frame crossing labels of one pedestrian: raw (state ∧ driving lane), then smoothed.
pub fn crossing_labels(frames: &[PedFrame], smoothing_frames: u32) -> Vec<bool> {
    let mut out = Vec::with_capacity(frames.len());
    let mut since_on_road: Option<u32> = None;
    for f in frames {
        let raw = f.state.is_crossing() && f.lane_type == Some(LaneType::Driving);
        let label = if raw {
            since_on_road = Some(0);
            true
        } else if f.state.is_crossing() {
            let held = since_on_road.is_some_and(|n| n < smoothing_frames);
            since_on_road = since_on_road.map(|n| n + 1);
            held
        } else {
            since_on_road = None;
            false
        };
        out.push(label);
    }
    out
}

/// The image interval `[lo, hi]` covered by a sphere along one image axis, exactly (perspective included):
/// `lateral` and `depth` are the centre's optical coordinates along that axis and along the optical axis,
/// `r` its radius, `focal` and `principal` the intrinsics along the axis. The bounds are the planes through
/// the camera centre tangent to the sphere; the sphere must lie entirely in front of the camera.
fn sphere_interval(lateral: f64, depth: f64, r: f64, focal: f64, principal: f64) -> (f64, f64) {
    // A plane `lateral = k·depth` is tangent when (lateral − k·depth)² = r²(1 + k²).
    let a = depth * depth - r * r;
    let disc = (lateral * lateral + a).max(0.0).sqrt();
    let k_lo = (lateral * depth - r * disc) / a;
    let k_hi = (lateral * depth + r * disc) / a;
    (focal * k_lo + principal, focal * k_hi + principal)
}

/// The tight 2D box of a posed body: the exact extremes of the projected silhouette. A capsule is the convex
/// hull of its two end spheres, and a projection of a convex hull (in front of the camera) is the convex hull
/// of the projections, so the box is the union of the end spheres' exact image intervals.
/// Returns None if any part of the body is within 5 cm of the camera plane or behind it.
pub fn project_box(pose: &BodyPose, cam: &CameraPose) -> Option<[f64; 4]> {
    project_capsules_box(pose.parts(), cam)
}

/// [`project_box`] of any set of capsules (a cyclist: its rider and its bicycle).
pub fn project_capsules_box<'a>(capsules: impl IntoIterator<Item = &'a Capsule>, cam: &CameraPose) -> Option<[f64; 4]> {
    let c = &cam.camera;
    if !c.lens.is_pinhole() {
        return distorted_capsules_box(capsules, cam);
    }
    let (cx, cy) = (f64::from(c.width_px) * 0.5, f64::from(c.height_px) * 0.5);
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for cap in capsules {
        for centre in [cap.a, cap.b] {
            let p = cam.optical_from_world.transform_point3(centre);
            if p.z - cap.radius_m <= 0.05 {
                return None;
            }
            let (u0, u1) = sphere_interval(p.x, p.z, cap.radius_m, c.focal_px, cx);
            let (v0, v1) = sphere_interval(p.y, p.z, cap.radius_m, c.focal_px, cy);
            lo = lo.min(DVec2::new(u0, v0));
            hi = hi.max(DVec2::new(u1, v1));
        }
    }
    Some([lo.x, lo.y, hi.x, hi.y])
}

/// Spheres per capsule whose silhouettes bound its distorted image (the two ends and the points between).
const DISTORTED_SPHERES: usize = 5;
/// Points sampled on each sphere's silhouette.
const SILHOUETTE_POINTS: usize = 32;

/// [`project_capsules_box`] through a distorting lens: a straight capsule's image is no longer the hull of its
/// end spheres' images, so the box bounds the distorted silhouettes (the circles where rays from the camera
/// graze each sphere) of spheres along each capsule, [`SILHOUETTE_POINTS`] points each. The sampled outline
/// lies within `R (1 − cos(π/32))` = 0.5 % of a sphere's image radius of the true one.
fn distorted_capsules_box<'a>(capsules: impl IntoIterator<Item = &'a Capsule>, cam: &CameraPose) -> Option<[f64; 4]> {
    let c = &cam.camera;
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for cap in capsules {
        let (a, b) = (
            cam.optical_from_world.transform_point3(cap.a),
            cam.optical_from_world.transform_point3(cap.b),
        );
        if a.z - cap.radius_m <= 0.05 || b.z - cap.radius_m <= 0.05 {
            return None;
        }
        for k in 0..DISTORTED_SPHERES {
            let p = a.lerp(b, k as f64 / (DISTORTED_SPHERES - 1) as f64);
            let (d2, r2) = (p.length_squared(), cap.radius_m * cap.radius_m);
            // The grazing circle: centre p (1 − r²/|p|²), radius r √(|p|² − r²) / |p|, facing the camera.
            let centre = p * (1.0 - r2 / d2);
            let radius = cap.radius_m * ((d2 - r2) / d2).sqrt();
            let (e1, e2) = (p / d2.sqrt()).any_orthonormal_pair();
            for i in 0..SILHOUETTE_POINTS {
                let (sin, cos) = (std::f64::consts::TAU * i as f64 / SILHOUETTE_POINTS as f64).sin_cos();
                let q = centre + radius * (cos * e1 + sin * e2);
                let px = c.pixel_of_normalised(q.x / q.z, q.y / q.z);
                lo = lo.min(px);
                hi = hi.max(px);
            }
        }
    }
    Some([lo.x, lo.y, hi.x, hi.y])
}

/// Annotates a simulated clip.
pub fn annotate(
    script: &ClipScript,
    trace: &ClipTrace,
    annotations: &Annotations,
    camera: &Camera,
    town: &RoadNetwork,
) -> ClipAnnotations {
    let gate = &annotations.visibility;
    let n_peds = trace.pedestrians.len();
    let heights: Vec<(f64, Option<f64>)> = script
        .pedestrians
        .iter()
        .map(|p| (p.identity.height_m, p.child.map(|c| c.height_m)))
        .chain(std::iter::repeat((1.75, None)))
        .take(n_peds)
        .collect();
    let figures: Vec<Figure> = (0..n_peds)
        .map(|k| script.pedestrians.get(k).map_or(Figure::PLAIN, |p| p.identity.figure))
        .collect();
    let rider_heights: Vec<f64> = (0..trace.cyclists.len())
        .map(|k| script.cyclists.get(k).map_or(1.75, |c| c.rider.height_m))
        .collect();
    let rider_figures: Vec<Figure> = (0..trace.cyclists.len())
        .map(|k| script.cyclists.get(k).map_or(Figure::PLAIN, |c| c.rider.figure))
        .collect();
    let labels: Vec<Vec<bool>> = trace
        .pedestrians
        .iter()
        .map(|f| crossing_labels(f, annotations.crossing_label_smoothing_frames))
        .collect();
    let first_crossing: Vec<Option<u32>> = labels
        .iter()
        .map(|l| l.iter().position(|c| *c).map(|f| f as u32))
        .collect();
    let scenery = ClipScenery::new(script, trace, town);
    let statics = static_occluders(&scenery);
    let mut out = ClipAnnotations {
        rows: Vec::new(),
        pedestrians: vec![PedestrianLabels::default(); n_peds],
        rejections: Rejections::default(),
        crossing: Vec::new(),
        cyclists: Vec::new(),
        scenery,
    };
    for (i, p) in out.pedestrians.iter_mut().enumerate() {
        p.first_crossing_frame = first_crossing[i];
    }
    for e in &trace.events {
        if let Event::CrossingDecision { frame, pedestrian } = e
            && let Some(p) = out.pedestrians.get_mut(pedestrian.index())
            && p.intention_frame.is_none()
        {
            p.intention_frame = Some(*frame);
        }
    }

    let mut occluders: Vec<Occluder> = Vec::with_capacity(statics.len() + trace.vehicles.len() + 2 * n_peds);
    let mut near: Vec<Occluder> = Vec::with_capacity(occluders.capacity());
    let (width, height) = (f64::from(camera.width_px), f64::from(camera.height_px));
    for frame in 0..trace.frame_count as usize {
        let Some(ego) = trace.ego.get(frame) else { break };
        let cam = camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
        occluders.clear();
        occluders.extend_from_slice(&statics);
        for v in &trace.vehicles {
            if let Some(f) = v.get(frame) {
                occluders.push(Occluder::Vehicle {
                    centre: f.pos,
                    sin_cos: f.yaw_rad.sin_cos(),
                });
            }
        }
        for (id, ped) in trace.pedestrians.iter().enumerate() {
            let f = &ped[frame];
            let (h, child) = heights[id];
            occluders.push(Occluder::Person {
                ground: f.pos,
                radius_m: PED_OCCLUDER_RADIUS_PER_M * h,
                height_m: h,
                owner: id as u32,
            });
            if let Some(hc) = child {
                let offset = glam::DMat3::from_rotation_z(f.yaw_rad) * CHILD_OFFSET_M;
                occluders.push(Occluder::Person {
                    ground: f.pos + offset,
                    radius_m: PED_OCCLUDER_RADIUS_PER_M * hc,
                    height_m: hc,
                    owner: u32::MAX,
                });
            }
        }
        for (ci, frames) in trace.cyclists.iter().enumerate() {
            if let Some(f) = frames.get(frame) {
                occluders.push(Occluder::Person {
                    ground: f.pos,
                    radius_m: RIDER_OCCLUDER_RADIUS_M,
                    height_m: rider_heights[ci],
                    owner: RIDER_OWNER_BASE + ci as u32,
                });
            }
        }
        for (ci, frames) in trace.cyclists.iter().enumerate() {
            let Some(f) = frames.get(frame) else { continue };
            let distance = (f.pos - ego.pos).truncate().length();
            if (f.pos - cam.centre).dot(cam.forward) <= 0.0 {
                continue;
            }
            let rider = cyclist::rider_pose(f, rider_heights[ci], &rider_figures[ci]);
            let bike = cyclist::bicycle(f, rider_heights[ci]);
            let Some(bbox) = project_capsules_box(rider.parts().chain(&bike), &cam) else {
                continue;
            };
            let clipped = [
                bbox[0].clamp(0.0, width),
                bbox[1].clamp(0.0, height),
                bbox[2].clamp(0.0, width),
                bbox[3].clamp(0.0, height),
            ];
            // In view: at least a pixel of the box inside the image.
            if clipped[2] - clipped[0] < 1.0 || clipped[3] - clipped[1] < 1.0 {
                continue;
            }
            let truncated = clipped != bbox;
            let ground = f.pos.truncate();
            near.clear();
            near.extend(occluders.iter().filter(|occ| {
                !matches!(occ, Occluder::Person { owner, .. } if *owner == RIDER_OWNER_BASE + ci as u32)
                    && may_block(occ, cam.centre.truncate(), ground, 1.5)
            }));
            let samples = rider.occlusion_samples();
            let mut keypoints = [0f32; 51];
            let mut keypoints_3d = [0f32; 51];
            let mut hidden = 0u32;
            for (k, joint) in rider.joints.iter().enumerate() {
                let p = cam.project(*joint);
                let flag = if p.depth_m <= 0.05 || !cam.in_image(p.px) {
                    0.0
                } else if occluded(town, &near, cam.centre, *joint) {
                    hidden += 1;
                    1.0
                } else if hidden_by_own_body(&rider, k, cam.centre) {
                    1.0
                } else {
                    2.0
                };
                set_keypoint((&mut keypoints, &mut keypoints_3d), k, p.px, flag, *joint);
            }
            for sample in samples {
                hidden += u32::from(occluded(town, &near, cam.centre, sample));
            }
            let occlusion = f64::from(hidden) / (rider.joints.len() + samples.len()) as f64;
            let min = min_box(gate, distance);
            let annotated = distance <= gate.max_distance_m
                && !too_small(bbox[2] - bbox[0], bbox[3] - bbox[1], min)
                && !(gate.require_inside_image && truncated)
                && occlusion <= gate.max_occlusion;
            out.cyclists.push(CyclistRow {
                frame: frame as u32,
                cyclist: ci as u32,
                bbox_px: clipped.map(|x| x as f32),
                truncated,
                distance_m: distance as f32,
                occlusion: occlusion as f32,
                annotated,
                keypoints,
                keypoints_3d,
            });
        }
        for (id, ped) in trace.pedestrians.iter().enumerate() {
            let f = &ped[frame];
            let distance = (f.pos - ego.pos).truncate().length();
            if distance > gate.max_distance_m {
                out.rejections.too_far += 1;
                continue;
            }
            if gate.require_in_front && (f.pos - cam.centre).dot(cam.forward) <= 0.0 {
                out.rejections.behind += 1;
                continue;
            }
            let pose = body::pose(f, heights[id].0, &figures[id], DVec3::ZERO);
            let Some(bbox) = project_box(&pose, &cam) else {
                out.rejections.behind += 1;
                continue;
            };
            let min = min_box(gate, distance);
            let Some((w, hgt)) = gate_box_size_px(&cam, f.pos, f.yaw_rad, heights[id].0) else {
                out.rejections.behind += 1;
                continue;
            };
            if too_small(w, hgt, min) {
                out.rejections.too_small += 1;
                continue;
            }
            if gate.require_inside_image && (bbox[0] < 0.0 || bbox[1] < 0.0 || bbox[2] > width || bbox[3] > height) {
                out.rejections.outside_image += 1;
                continue;
            }
            // Keypoints and occlusion: the 17 joints plus torso and head samples.
            let samples = pose.occlusion_samples();
            let projected = pose.joints.map(|j| cam.project(j));
            let inside = projected.map(|p| p.depth_m > 0.05 && cam.in_image(p.px));
            let seen = inside.iter().map(|&i| u32::from(i)).sum::<u32>() + samples.len() as u32;
            // Only the occluders near the lines of sight to this body take part in the ray tests.
            let ground = f.pos.truncate();
            let reach = pose
                .joints
                .iter()
                .chain(&samples)
                .map(|q| q.truncate().distance(ground))
                .fold(0.0, f64::max);
            near.clear();
            near.extend(occluders.iter().filter(|occ| {
                !matches!(occ, Occluder::Person { owner, .. } if *owner == id as u32)
                    && may_block(occ, cam.centre.truncate(), ground, reach)
            }));
            // Stop casting rays once the body is hidden beyond the threshold (hidden only grows).
            let too_hidden = |hidden: u32| f64::from(hidden) / f64::from(seen) > gate.max_occlusion;
            let mut keypoints = [0f32; 51];
            let mut keypoints_3d = [0f32; 51];
            let mut hidden = 0u32;
            for (k, joint) in pose.joints.iter().enumerate() {
                if too_hidden(hidden) {
                    break;
                }
                let p = projected[k];
                // Hidden by the body itself: labelled occluded, but not occlusion by something else.
                let flag = if !inside[k] {
                    0.0
                } else if occluded(town, &near, cam.centre, *joint) {
                    hidden += 1;
                    1.0
                } else if hidden_by_own_body(&pose, k, cam.centre) {
                    1.0
                } else {
                    2.0
                };
                set_keypoint((&mut keypoints, &mut keypoints_3d), k, p.px, flag, *joint);
            }
            let mut rejected = too_hidden(hidden);
            for sample in samples {
                if rejected {
                    break;
                }
                hidden += u32::from(occluded(town, &near, cam.centre, sample));
                rejected = too_hidden(hidden);
            }
            if rejected {
                out.rejections.occluded += 1;
                continue;
            }
            let occlusion = f64::from(hidden) / f64::from(seen);
            let crossing = labels[id][frame];
            let tte = first_crossing[id].and_then(|fc| (frame as u32 <= fc).then(|| (fc - frame as u32) as i32));
            let (box_centre, box_size) = pose.box3d();
            out.pedestrians[id].annotated_frames += 1;
            out.pedestrians[id].crosser |= crossing;
            out.rows.push(AnnotationRow {
                frame: frame as u32,
                pedestrian: id as u32,
                bbox_px: bbox.map(|x| x as f32),
                annotator_bbox_px: super::annotator::annotator_box(
                    bbox,
                    &annotations.annotator_box,
                    (script.seed, id as u32, frame as u32),
                    (camera.width_px, camera.height_px),
                )
                .map(|x| x as f32),
                crossing,
                state: f.state,
                distance_m: distance as f32,
                tte_frames: tte,
                occlusion: occlusion as f32,
                keypoints,
                keypoints_3d,
                pos_m: [f.pos.x as f32, f.pos.y as f32, f.pos.z as f32],
                yaw_rad: f.yaw_rad as f32,
                velocity_mps: [f.velocity.x as f32, f.velocity.y as f32],
                lane_type: f.lane_type,
                box3d_centre_m: [box_centre.x as f32, box_centre.y as f32, box_centre.z as f32],
                box3d_size_m: [box_size.x as f32, box_size.y as f32, box_size.z as f32],
                look: looks_at(
                    pose.gaze,
                    (pose.joints[1] + pose.joints[2]) * 0.5,
                    cam.centre,
                    annotations.look_cone_deg,
                ),
                walking: f.velocity.length() >= WALKING_MPS,
                gesture: f.gesture.map(|g| g.0),
                reaction: f.reaction,
                on_crosswalk: f.on_crosswalk,
                walk_signal: f.walk_signal,
                against_signal: f.walk_signal == Some(WalkSignal::DontWalk) && f.state.is_crossing(),
                gaze: pose.gaze.to_array().map(|x| x as f32),
            });
        }
    }
    if annotations.annotator_box.keyframe_every != crate::spec::types::CountRange(1, 1) {
        redraw_at_keyframes(&mut out.rows, annotations, script.seed, camera);
    }
    out.crossing = labels;
    out
}

/// Redraws every pedestrian's annotator boxes from keyframes ([`super::annotator::keyframe_track`]).
fn redraw_at_keyframes(rows: &mut [AnnotationRow], annotations: &Annotations, clip_seed: u64, camera: &Camera) {
    let mut by_pedestrian: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for (i, r) in rows.iter().enumerate() {
        by_pedestrian.entry(r.pedestrian).or_default().push(i);
    }
    for (pedestrian, mut idx) in by_pedestrian {
        idx.sort_by_key(|&i| rows[i].frame);
        let frames: Vec<u32> = idx.iter().map(|&i| rows[i].frame).collect();
        let tight: Vec<[f64; 4]> = idx.iter().map(|&i| rows[i].bbox_px.map(f64::from)).collect();
        let boxes = super::annotator::keyframe_track(
            &frames,
            &tight,
            &annotations.annotator_box,
            (clip_seed, pedestrian),
            (camera.width_px, camera.height_px),
        );
        for (&i, b) in idx.iter().zip(boxes) {
            rows[i].annotator_bbox_px = b.map(|x| x as f32);
        }
    }
}

/// Writes joint `k` into a row's keypoint arrays: its pixel `px` with visibility `flag` (COCO's 0 / 1 / 2), and
/// its world position.
fn set_keypoint(
    (keypoints, keypoints_3d): (&mut [f32; 51], &mut [f32; 51]),
    k: usize,
    px: DVec2,
    flag: f32,
    joint: DVec3,
) {
    keypoints[3 * k..3 * k + 3].copy_from_slice(&[px.x as f32, px.y as f32, flag]);
    keypoints_3d[3 * k..3 * k + 3].copy_from_slice(&[joint.x as f32, joint.y as f32, joint.z as f32]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::types::BoxSize;

    #[test]
    fn looks_at_is_a_cone_around_the_gaze() {
        let eyes = DVec3::new(0.0, 0.0, 1.6);
        let x = DVec3::X;
        assert!(looks_at(x, eyes, DVec3::new(10.0, 0.0, 1.6), 30.0));
        // 29° and 31° to the left, and 29° above.
        let at = |deg: f64| DVec3::new(10.0 * deg.to_radians().cos(), 10.0 * deg.to_radians().sin(), 1.6);
        assert!(looks_at(x, eyes, at(29.0), 30.0));
        assert!(!looks_at(x, eyes, at(31.0), 30.0));
        let up = DVec3::new(10.0, 0.0, 1.6 + 10.0 * 29f64.to_radians().tan());
        assert!(looks_at(x, eyes, up, 30.0));
        assert!(!looks_at(x, eyes, DVec3::new(-10.0, 0.0, 1.6), 90.0), "behind the head");
        assert!(!looks_at(x, eyes, eyes, 30.0), "no direction to oneself");
    }

    fn frame(state: PedState, lane: Option<LaneType>) -> PedFrame {
        PedFrame {
            state,
            lane_type: lane,
            ..PedFrame::STILL
        }
    }

    #[test]
    fn crossing_label_needs_state_and_driving_lane_and_is_smoothed() {
        use LaneType::*;
        use PedState::*;
        let frames = [
            frame(CheckingTraffic, Some(Sidewalk)),
            frame(CrossingRoad, Some(Sidewalk)),
            frame(CrossingRoad, Some(Driving)),
            frame(CrossingRoad, Some(Shoulder)),
            frame(CrossingRoad, Some(Shoulder)),
            frame(CrossingRoad, Some(Shoulder)),
            frame(CrossingRoad, Some(Driving)),
            frame(FinishedCrossing, Some(Driving)),
        ];
        assert_eq!(
            crossing_labels(&frames, 2),
            vec![false, false, true, true, true, false, true, false]
        );
        assert_eq!(
            crossing_labels(&frames, 0),
            vec![false, false, true, false, false, false, true, false]
        );
    }

    #[test]
    fn the_size_gate_compares_width_with_width_and_height_with_height() {
        let tall = BoxSize::new(15.0, 30.0);
        let wide = BoxSize::new(30.0, 15.0);
        assert!(!too_small(20.0, 40.0, tall));
        assert!(too_small(20.0, 40.0, wide), "20 px wide is narrower than 30");
        assert!(too_small(40.0, 20.0, tall), "20 px high is lower than 30");
        assert!(!too_small(40.0, 20.0, wide));
    }

    #[test]
    fn sphere_bounds_are_exact_under_perspective() {
        // Spheres near the axis, off-axis (wide angle) and close: the interval contains every projected
        // surface point and is attained by one.
        let (f, c) = (640.0, 640.0);
        for (x, z, r) in [(0.0, 10.0, 0.2), (9.0, 10.0, 0.15), (-3.0, 2.0, 0.3), (1.5, 0.5, 0.2)] {
            let (lo, hi) = sphere_interval(x, z, r, f, c);
            let (mut dlo, mut dhi) = (f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..100_000 {
                let t = std::f64::consts::TAU * f64::from(k) / 100_000.0;
                let (px, pz) = (x + r * t.cos(), z + r * t.sin());
                let u = f * px / pz + c;
                dlo = dlo.min(u);
                dhi = dhi.max(u);
            }
            assert!(
                (lo - dlo).abs() < 1e-3 && (hi - dhi).abs() < 1e-3,
                "{x} {z} {r}: {lo} {hi} vs {dlo} {dhi}"
            );
        }
    }
}
