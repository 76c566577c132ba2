//! The camera streams against the labels and against physics: instance masks agree with the annotated boxes
//! and keypoints frame by frame (one camera model), depth of a known plane, semantic ids of known surfaces,
//! weathers that differ measurably, golden images within a PSNR tolerance, and sensor files that are
//! byte-identical across job counts and resumption (a clip interrupted while rendering is rendered again).

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec2, Vec3};
use pedsynth::plan::{ClipScript, Garment, HairStyle, Plan, TownContext};
use pedsynth::sensors::camera::{CameraImages, Renderer, SKY_DEPTH_M, light::Lighting, luminance};
use pedsynth::sensors::scene::{
    self, CYCLIST_INSTANCE_BASE, Cluster, FrameScene, Material, Mesh, Prim, StaticScene, pedestrian_instance, tag,
};
use pedsynth::sensors::{self, annotate::ClipAnnotations};
use pedsynth::sim;
use pedsynth::sim::rig::{Camera, Rig};
use pedsynth::sim::trace::ClipTrace;
use pedsynth::spec::LoadOptions;
use pedsynth::spec::types::{Rgb, WeatherPreset};

pub(crate) fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

fn options(overrides: &[&str]) -> LoadOptions {
    LoadOptions {
        overrides: overrides.iter().map(|s| s.to_string()).collect(),
        allow_large: false,
        profile: None,
    }
}

pub(crate) struct Clip {
    pub(crate) plan: Plan,
    pub(crate) towns: BTreeMap<String, TownContext>,
    pub(crate) script: ClipScript,
    pub(crate) trace: ClipTrace,
    pub(crate) ann: ClipAnnotations,
    pub(crate) rig: Rig,
}

/// The first clip of a spec, simulated and annotated.
pub(crate) fn clip(spec_path: &Path, overrides: &[&str]) -> Clip {
    clip_at(spec_path, overrides, 0)
}

/// Clip `index` of a spec, simulated and annotated.
pub(crate) fn clip_at(spec_path: &Path, overrides: &[&str], index: usize) -> Clip {
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(spec_path, &options(overrides))
        .unwrap_or_else(|e| panic!("{}", e.render()));
    let script = plan.clips[index].clone();
    let net = &towns[&script.town].network;
    let trace = sim::simulate(&script, &plan.sim, net);
    let rig = Rig::from_spec(&plan.spec.sensors);
    let ann = sensors::observe(&script, &trace, &plan.spec, &rig, net).annotations;
    Clip {
        plan,
        towns,
        script,
        trace,
        ann,
        rig,
    }
}

impl Clip {
    pub(crate) fn render(&self, frame: u32) -> CameraImages {
        sensors::render_frame(
            &self.script,
            &self.trace,
            &self.rig,
            &self.towns[&self.script.town].network,
            frame,
        )
    }

    /// The frames with the most annotated pedestrians, `n` of them spread over the clip.
    pub(crate) fn busy_frames(&self, n: usize) -> Vec<u32> {
        let mut counts = vec![0usize; self.trace.frame_count as usize];
        for r in &self.ann.rows {
            counts[r.frame as usize] += 1;
        }
        let chunk = counts.len().div_ceil(n);
        counts
            .chunks(chunk)
            .enumerate()
            .filter_map(|(k, c)| {
                let (i, best) = c.iter().enumerate().max_by_key(|(i, v)| (**v, std::cmp::Reverse(*i)))?;
                (*best > 0).then_some((k * chunk + i) as u32)
            })
            .collect()
    }
}

/// What the mask/box comparison found over a clip.
#[derive(Default)]
pub(crate) struct MaskReport {
    pub(crate) rows: usize,
    pub(crate) keypoints: usize,
    pub(crate) keypoints_on_body: usize,
    pub(crate) worst_share: f64,
    pub(crate) worst_iou: f64,
    pub(crate) failures: Vec<String>,
    pub(crate) partly_hidden: usize,
    /// Pedestrians of the clip holding an umbrella, and the pixels tagged `Dynamic` (umbrellas) over every frame,
    /// and how many of those carry an instance id.
    pub(crate) umbrellas: usize,
    pub(crate) dynamic_px: usize,
    pub(crate) dynamic_px_with_instance: usize,
    /// Keypoints on their pedestrian's pixels, by flag (visible; occluded in a pedestrian no other object hides,
    /// that is by its own body), and how many of each have the rendered body nearer the camera than the joint by
    /// more than [`BODY_IN_FRONT_M`].
    pub(crate) visible_on_body: usize,
    pub(crate) visible_behind_body: usize,
    pub(crate) self_hidden_on_body: usize,
    pub(crate) self_hidden_behind_body: usize,
}

/// How much nearer than a joint the rendered body must be at its pixel for the joint to lie behind the body,
/// metres: more than a limb's or the head's radius (4–9 cm), less than the body's depth (20 cm and more).
const BODY_IN_FRONT_M: f32 = 0.12;

/// Whether `test` holds for a pixel within one pixel of the image point (`x`, `y`) (the label sample of pixel
/// (px, py) lies at (px + 0.25, py + 0.25)); `test` gets the pixel's index.
pub(crate) fn near_pixel(img: &CameraImages, x: f32, y: f32, test: impl Fn(usize) -> bool) -> bool {
    let (cx, cy) = ((x - 0.25).round() as i64, (y - 0.25).round() as i64);
    (-1..=1).any(|dy| {
        (-1..=1).any(|dx| {
            let (px, py) = (cx + dx, cy + dy);
            px >= 0
                && py >= 0
                && (px as usize) < img.width
                && (py as usize) < img.height
                && test(py as usize * img.width + px as usize)
        })
    })
}

/// Intersection over union of two boxes `[x_min, y_min, x_max, y_max]`.
fn box_iou(a: [f32; 4], b: [f32; 4]) -> f64 {
    let iw = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let ih = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = iw * ih;
    let union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter;
    f64::from(inter / union)
}

/// Compares every unoccluded annotated pedestrian of one frame with its instance pixels; records a pedestrian
/// whose pixels leave its box or whose pixels' box differs from it.
pub(crate) fn check_masks(c: &Clip, frame: u32, img: &CameraImages, report: &mut MaskReport) {
    let w = img.width;
    for r in c.ann.rows.iter().filter(|r| r.frame == frame && r.occlusion == 0.0) {
        let id = pedestrian_instance(r.pedestrian);
        let (mut n, mut inside) = (0usize, 0usize);
        let (mut lo, mut hi) = ((f32::MAX, f32::MAX), (f32::MIN, f32::MIN));
        let b = r.bbox_px;
        for (i, _) in img.instance.iter().enumerate().filter(|(_, v)| **v == id) {
            // The label sample of pixel (x, y) lies at (x + 0.25, y + 0.25).
            let (x, y) = ((i % w) as f32 + 0.25, (i / w) as f32 + 0.25);
            n += 1;
            inside += usize::from(x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3]);
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        assert!(
            n > 0,
            "frame {frame}: pedestrian {} annotated but not drawn",
            r.pedestrian
        );
        // The annotation's occlusion samples 22 points of the body; a car, a lamp post or a bin can still hide a foot
        // or a hand, and a child walking beside its parent often covers a few percent of the parent's box. Such a
        // pedestrian is occluded in the image (another person, a vehicle or a pole nearer than the body inside
        // its box) and is not compared.
        let nearest_m = img
            .instance
            .iter()
            .zip(&img.depth_m)
            .filter(|(v, _)| **v == id)
            .map(|(_, d)| *d)
            .fold(f32::MAX, f32::min);
        let hidden = (b[1].max(0.0) as usize..(b[3].ceil() as usize).min(img.height)).any(|y| {
            (b[0].max(0.0) as usize..(b[2].ceil() as usize).min(w)).any(|x| {
                let i = y * w + x;
                let thing = img.instance[i] != 0 || [tag::POLE, tag::STATIC].contains(&img.semantic[i]);
                thing && img.instance[i] != id && img.depth_m[i] < nearest_m - 0.05
            })
        });
        if hidden {
            report.partly_hidden += 1;
            continue;
        }
        let share = inside as f64 / n as f64;
        // The pixels' box, with half a pixel around the outermost sample points.
        let pix = [lo.0 - 0.5, lo.1 - 0.5, hi.0 + 0.5, hi.1 + 0.5];
        let iou = box_iou(pix, b);
        if share < 0.95 || iou < 0.8 {
            report.failures.push(format!(
                "frame {frame}, pedestrian {}: {share:.3} of its pixels inside its box {b:?} ({:.1} x {:.1} px), IoU \
                 {iou:.3} with its pixels' box {pix:?}",
                r.pedestrian,
                b[2] - b[0],
                b[3] - b[1]
            ));
        }
        if report.rows == 0 || share < report.worst_share {
            report.worst_share = share;
        }
        if report.rows == 0 || iou < report.worst_iou {
            report.worst_iou = iou;
        }
        report.rows += 1;
        // Visible keypoints land on the pedestrian's pixels (within a pixel).
        for k in (0..17).filter(|k| r.keypoints[3 * k + 2] == 2.0) {
            let (x, y) = (r.keypoints[3 * k], r.keypoints[3 * k + 1]);
            report.keypoints += 1;
            report.keypoints_on_body += usize::from(near_pixel(img, x, y, |i| img.instance[i] == id));
        }
        // Where a keypoint's pixel shows its own pedestrian, the rendered body is not far in front of a visible
        // joint, and is in front of one its own body hides (nothing else hides this pedestrian: occlusion 0).
        // Clothes over the joints (a skirt, a coat, long hair, a hat) are drawn in front of them and do not hide
        // them: only pedestrians in trousers, bareheaded and without long hair are compared.
        let figure = &c.script.pedestrians[r.pedestrian as usize].identity.figure;
        if figure.garment != Garment::Trousers
            || figure.hair == HairStyle::Long
            || figure.headwear.is_some()
            || figure.hood
        {
            continue;
        }
        let ego = &c.trace.ego[frame as usize];
        let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
        for k in 0..17 {
            let flag = r.keypoints[3 * k + 2];
            let (x, y) = (r.keypoints[3 * k], r.keypoints[3 * k + 1]);
            let (px, py) = ((x - 0.25).round(), (y - 0.25).round());
            if flag == 0.0 || px < 0.0 || py < 0.0 || px as usize >= w || py as usize >= img.height {
                continue;
            }
            let i = py as usize * w + px as usize;
            if img.instance[i] != id {
                continue;
            }
            let joint = DVec3::from_array(std::array::from_fn(|a| f64::from(r.keypoints_3d[3 * k + a])));
            let joint_depth_m = (joint - cam.centre).dot(cam.forward) as f32;
            let behind = img.depth_m[i] < joint_depth_m - BODY_IN_FRONT_M;
            if flag == 2.0 {
                report.visible_on_body += 1;
                report.visible_behind_body += usize::from(behind);
            } else {
                report.self_hidden_on_body += 1;
                report.self_hidden_behind_body += usize::from(img.depth_m[i] < joint_depth_m - 0.03);
            }
        }
    }
}

#[test]
fn instance_masks_match_the_annotated_boxes_and_keypoints_in_every_frame() {
    // Every frame of a quickstart clip, as the pipeline hands it to the writer (half resolution for speed:
    // the annotations use the same camera).
    masks_match_boxes_and_keypoints(&[]);
}

/// Every frame of the first quickstart clip at 640 × 360 (with `overrides`), as the pipeline hands it to the
/// writer: each unoccluded annotated pedestrian's instance pixels lie in its box (≥ 95 %, IoU ≥ 0.8 with their
/// own box) and ≥ 99 % of visible keypoints lie on them; against the rendered depth, at most 2 % of visible
/// keypoints lie behind their own body and at least 90 % of those flagged hidden by it do.
pub(crate) fn masks_match_boxes_and_keypoints(overrides: &[&str]) -> MaskReport {
    let mut all = vec![
        "sensors.rgb.width_px=640",
        "sensors.rgb.height_px=360",
        "sensors.dvs.enabled=false",
    ];
    all.extend_from_slice(overrides);
    let c = clip(&spec("quickstart.yaml"), &all);
    let net = &c.towns[&c.script.town].network;
    let mut report = MaskReport {
        umbrellas: c
            .script
            .pedestrians
            .iter()
            .filter(|p| p.identity.figure.umbrella.is_some())
            .count(),
        ..MaskReport::default()
    };
    let mut frames = 0;
    let stat = StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
    sensors::render_cameras(&stat, &c.script, &c.trace, &c.plan.spec.sensors, &c.rig, |f| {
        check_masks(&c, f.frame, f.images, &mut report);
        for (&tag_id, &instance) in f.images.semantic.iter().zip(&f.images.instance) {
            if tag_id == tag::DYNAMIC {
                report.dynamic_px += 1;
                report.dynamic_px_with_instance += usize::from(instance != 0);
            }
        }
        frames += 1;
        Ok::<(), ()>(())
    })
    .expect("rendered");
    assert_eq!(frames, c.trace.frame_count);
    // Parked cars hide some pedestrian-frames (the heavy-rain quickstart clip: 591 checked without them, 245 with).
    assert!(
        report.rows >= 200,
        "only {} unoccluded pedestrian-frames checked",
        report.rows
    );
    let share = report.keypoints_on_body as f64 / report.keypoints as f64;
    eprintln!(
        "{} pedestrian-frames ({} more partly hidden in the image): worst in-box share {:.3}, worst IoU {:.3}; {} \
         of {} visible keypoints on the body",
        report.rows,
        report.partly_hidden,
        report.worst_share,
        report.worst_iou,
        report.keypoints_on_body,
        report.keypoints
    );
    // The image-based exclusion must not swallow the comparison (quickstart: 173 excluded, 784 compared).
    assert!(
        report.partly_hidden * 3 < report.rows,
        "{} partly hidden, {} compared",
        report.partly_hidden,
        report.rows
    );
    assert!(
        report.failures.is_empty(),
        "{} of {} pedestrian-frames fail:\n{}",
        report.failures.len(),
        report.rows,
        report.failures.join("\n")
    );
    assert!(
        share >= 0.99,
        "{} of {} visible keypoints on their pedestrian's pixels",
        report.keypoints_on_body,
        report.keypoints
    );
    // Visibility flags against the rendered depth: a visible joint is seldom behind its own body, a joint flagged
    // as hidden by its own body mostly is (the hand behind the back, the far shoulder in profile, the face seen
    // from behind).
    let visible_behind = report.visible_behind_body as f64 / report.visible_on_body as f64;
    let self_hidden_behind = report.self_hidden_behind_body as f64 / report.self_hidden_on_body.max(1) as f64;
    eprintln!(
        "{} of {} visible keypoints behind their own rendered body; {} of {} flagged hidden by it",
        report.visible_behind_body, report.visible_on_body, report.self_hidden_behind_body, report.self_hidden_on_body
    );
    assert!(
        visible_behind <= 0.02,
        "{} of {} visible keypoints lie more than {BODY_IN_FRONT_M} m behind their own rendered body",
        report.visible_behind_body,
        report.visible_on_body
    );
    assert!(
        report.self_hidden_on_body >= 100 && self_hidden_behind >= 0.9,
        "{} of {} keypoints hidden by their own body lie behind its rendered pixels",
        report.self_hidden_behind_body,
        report.self_hidden_on_body
    );
    report
}

#[test]
fn label_streams_agree_with_each_other_and_with_the_scene() {
    let c = clip(&spec("quickstart.yaml"), &[]);
    let frame = c.busy_frames(1)[0];
    let img = c.render(frame);
    let (w, h) = (img.width, img.height);
    for i in 0..w * h {
        let (inst, sem) = (img.instance[i], img.semantic[i]);
        match inst {
            0 => assert!(
                sem != tag::PEDESTRIAN && sem != tag::CAR,
                "pixel {i}: tag {sem} without an instance"
            ),
            i if i < scene::VEHICLE_INSTANCE_BASE => assert_eq!(sem, tag::PEDESTRIAN),
            // Traffic vehicles and parked cars.
            i if !(scene::CYCLIST_INSTANCE_BASE..scene::PARKED_INSTANCE_BASE).contains(&i) => {
                assert_eq!(sem, tag::CAR)
            }
            _ => assert!(
                sem == tag::RIDER || sem == tag::BICYCLE,
                "pixel {i}: cyclist instance, tag {sem}"
            ),
        }
        if sem == tag::SKY {
            assert_eq!(img.depth_m[i], SKY_DEPTH_M);
        } else {
            assert!(img.depth_m[i] > 0.0 && img.depth_m[i] < SKY_DEPTH_M);
        }
    }
    // The ego drives on a road: the bottom centre of the image is road or road paint, the top centre sky or
    // a building.
    let bottom = img.semantic[(h - 5) * w + w / 2];
    assert!(bottom == tag::ROAD || bottom == tag::ROAD_LINE, "{bottom}");
    let top = img.semantic[5 * w + w / 2];
    assert!(
        [tag::SKY, tag::BUILDING, tag::POLE, tag::VEGETATION].contains(&top),
        "{top}"
    );
    // Road, road lines, sidewalks and people all appear.
    for t in [tag::ROAD, tag::ROAD_LINE, tag::SIDEWALK, tag::PEDESTRIAN, tag::SKY] {
        assert!(img.semantic.contains(&t), "no pixel of tag {t}");
    }
}

/// A static scene of one mesh (one culling cluster), for physics tests.
pub(crate) fn static_scene(mesh: Mesh) -> StaticScene {
    let n = mesh.tris.len() as u32;
    StaticScene {
        origin: DVec3::ZERO,
        tris: mesh.tris,
        clusters: vec![Cluster {
            centre: Vec3::ZERO,
            radius_m: 5000.0,
            tris: 0..n,
        }],
        prims: mesh.prims,
        pieces: Vec::new(),
        crosswalks: Vec::new(),
        lamps: Vec::new(),
        signal_heads: Vec::new(),
        seed: 1,
        outfits: Vec::new(),
        riders: Vec::new(),
        car_paint: Vec::new(),
        texture_contrast: 1.0,
    }
}

/// A flat primitive.
pub(crate) fn flat(material: Material, tag_id: u8, instance: u16, normal: Vec3) -> Prim {
    Prim {
        material,
        tag: tag_id,
        instance,
        albedo: Vec3::splat(0.3),
        albedo2: Vec3::splat(0.3),
        normal,
        aux: 0,
    }
}

/// A static scene of one flat quad.
fn one_quad(q: [Vec3; 4], tag_id: u8, normal: Vec3) -> StaticScene {
    let mut mesh = Mesh::default();
    let id = mesh.prim(flat(Material::Roof, tag_id, 0, normal));
    mesh.quad(q, id);
    static_scene(mesh)
}

pub(crate) fn render_static(scene: &StaticScene, camera: &Camera, pos: DVec3, yaw: f64) -> CameraImages {
    let mut r = Renderer::new(camera, Lighting::from_weather(&WeatherPreset::ClearNoon.params()), 1);
    let mut img = CameraImages::default();
    r.render(scene, &FrameScene::default(), &camera.at(pos, yaw, 0.0), 1, &mut img);
    img
}

#[test]
fn depth_of_known_planes_reads_back_within_a_centimetre() {
    let rgb = Rgb {
        width_px: 320,
        height_px: 180,
        mount: pedsynth::spec::types::Mount {
            pitch_deg: 0.0,
            ..Default::default()
        },
        ..Rgb::default()
    };
    let camera = Camera::from_spec(&rgb);
    let pose = camera.at(DVec3::ZERO, 0.0, 0.0);
    // A wall facing the camera, 12.345 m ahead of it (the camera looks along +x).
    let x = (pose.centre.x + 12.345) as f32;
    let wall = one_quad(
        [
            Vec3::new(x, -100.0, -100.0),
            Vec3::new(x, 100.0, -100.0),
            Vec3::new(x, 100.0, 100.0),
            Vec3::new(x, -100.0, 100.0),
        ],
        tag::BUILDING,
        -Vec3::X,
    );
    let img = render_static(&wall, &camera, DVec3::ZERO, 0.0);
    for (i, d) in img.depth_m.iter().enumerate() {
        assert!((d - 12.345).abs() < 0.01, "pixel {i}: {d}");
        assert_eq!(img.semantic[i], tag::BUILDING);
    }
    // The ground plane z = 0 seen from 1.4 m with the default pitch: each pixel's depth is where its ray meets
    // the plane (by hand: depth along the optical axis = t · (ray · forward)).
    let camera = Camera::from_spec(&Rgb {
        width_px: 320,
        height_px: 180,
        ..Rgb::default()
    });
    let ground = one_quad(
        [
            Vec3::new(-500.0, -500.0, 0.0),
            Vec3::new(500.0, -500.0, 0.0),
            Vec3::new(500.0, 500.0, 0.0),
            Vec3::new(-500.0, 500.0, 0.0),
        ],
        tag::ROAD,
        Vec3::Z,
    );
    let img = render_static(&ground, &camera, DVec3::ZERO, 0.3);
    let pose = camera.at(DVec3::ZERO, 0.3, 0.0);
    let (mut checked, mut sky) = (0, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            let (u, v) = (x as f64 + 0.25, y as f64 + 0.25);
            let ray = pose.forward
                + pose.right * ((u - 160.0) / camera.focal_px)
                + pose.down * ((v - 90.0) / camera.focal_px);
            let i = y * img.width + x;
            if ray.z >= -1e-3 {
                sky += usize::from(img.semantic[i] == tag::SKY);
                continue;
            }
            let t = -pose.centre.z / ray.z;
            if t > 400.0 {
                continue; // grazing rays: a centimetre is below f32 depth precision there
            }
            let want = t * ray.dot(pose.forward);
            let got = f64::from(img.depth_m[i]);
            assert!((got - want).abs() < 0.01, "pixel ({x}, {y}): depth {got} vs {want}");
            assert_eq!(img.semantic[i], tag::ROAD);
            checked += 1;
        }
    }
    assert!(
        checked > 20_000 && sky > 5_000,
        "{checked} ground pixels, {sky} sky pixels"
    );
}

#[test]
fn a_point_projects_to_the_same_pixel_in_the_renderer_and_the_annotations() {
    // A small marker cube 15 m ahead and to the left; its centre's projection (the annotation code's camera
    // model) is the centre of the rendered cube's pixels.
    let camera = Camera::from_spec(&Rgb {
        width_px: 640,
        height_px: 360,
        ..Rgb::default()
    });
    let pose = camera.at(DVec3::new(3.0, -2.0, 0.0), 0.4, 0.0);
    let centre = pose.centre + pose.forward * 15.0 + pose.right * -3.0 + pose.down * 1.0;
    let project = pose.project(centre).px;
    // A 0.5 m upright cube (a box of instance 7) centred on the point.
    let c = centre.as_vec3();
    let mut mesh = Mesh::default();
    let face = flat(Material::Metal, tag::POLE, 7, Vec3::Z);
    mesh.upright_box(
        c.truncate(),
        0.0,
        Vec2::splat(0.25),
        [c.z - 0.25, c.z + 0.25],
        face,
        face,
    );
    // ... and its bottom face, which the upright box leaves open.
    let id = mesh.prim(flat(Material::Metal, tag::POLE, 7, -Vec3::Z));
    mesh.quad(
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(a, b): (f32, f32)| c + Vec3::new(a, b, -1.0) * 0.25),
        id,
    );
    let scene = static_scene(mesh);
    let img = render_static(&scene, &camera, DVec3::new(3.0, -2.0, 0.0), 0.4);
    let (mut sum, mut count) = (Vec2::ZERO, 0.0);
    for (i, &inst) in img.instance.iter().enumerate() {
        if inst == 7 {
            sum += Vec2::new((i % img.width) as f32 + 0.25, (i / img.width) as f32 + 0.25);
            count += 1.0;
        }
    }
    assert!(count > 50.0, "{count} pixels");
    let centroid = sum / count;
    // A cube seen in perspective: its pixels' centroid is within a pixel of its centre's projection.
    let d = (centroid.as_dvec2() - project).length();
    assert!(d < 1.0, "centroid {centroid} vs projection {project} ({d:.2} px apart)");
}

pub(crate) fn mean_luminance(img: &CameraImages) -> f64 {
    img.rgb.chunks_exact(3).map(|p| f64::from(luminance(p))).sum::<f64>() / (img.width * img.height) as f64
}

/// RMS contrast (standard deviation of luminance) of the pixels whose depth is within `range`.
fn contrast(img: &CameraImages, range: std::ops::Range<f32>) -> f64 {
    let l: Vec<f64> = img
        .rgb
        .chunks_exact(3)
        .zip(&img.depth_m)
        .filter(|&(_, &d)| range.contains(&d))
        .map(|(p, _)| f64::from(luminance(p)))
        .collect();
    let m = l.iter().sum::<f64>() / l.len() as f64;
    (l.iter().map(|x| (x - m).powi(2)).sum::<f64>() / l.len() as f64).sqrt()
}

/// Streak energy: how much more luminance varies across rows than down columns (rain streaks are thin,
/// near-vertical lines; the scene's edges run every way).
fn streak_energy(img: &CameraImages) -> f64 {
    let w = img.width;
    let l = |x: usize, y: usize| f64::from(luminance(&img.rgb[(y * w + x) * 3..]));
    let (mut across, mut down) = (0.0, 0.0);
    for y in 0..img.height - 1 {
        for x in 0..w - 1 {
            across += (l(x, y) - l(x + 1, y)).abs();
            down += (l(x, y) - l(x, y + 1)).abs();
        }
    }
    across / down
}

#[test]
fn weathers_look_measurably_different() {
    // The light itself, at a fixed exposure (auto-exposure would brighten the night: tests/it/imaging.rs).
    let mut c = clip(
        &spec("quickstart.yaml"),
        &[
            "sensors.rgb.width_px=640",
            "sensors.rgb.height_px=360",
            "sensors.rgb.exposure.mode=fixed",
        ],
    );
    let frame = c.busy_frames(1)[0];
    let mut render = |p: WeatherPreset, tweak: &dyn Fn(&mut pedsynth::spec::types::WeatherParams)| {
        c.script.weather_params = p.params();
        tweak(&mut c.script.weather_params);
        c.render(frame)
    };
    let noon = render(WeatherPreset::ClearNoon, &|_| {});
    let sunset = render(WeatherPreset::ClearSunset, &|_| {});
    let night = render(WeatherPreset::NightClear, &|_| {});
    let (ln, ls, lt) = (mean_luminance(&noon), mean_luminance(&sunset), mean_luminance(&night));
    assert!(
        lt < ls && ls < ln,
        "mean luminance: night {lt:.1} < sunset {ls:.1} < noon {ln:.1}"
    );
    // Fog lowers contrast with distance: far pixels lose more of their contrast than near ones.
    let foggy = render(WeatherPreset::FoggyNoon, &|_| {});
    let ratio = |img: &CameraImages| contrast(img, 40.0..300.0) / contrast(img, 0.0..15.0);
    let (clear_ratio, fog_ratio) = (ratio(&noon), ratio(&foggy));
    assert!(
        fog_ratio < 0.6 * clear_ratio,
        "far/near contrast: fog {fog_ratio:.3} vs clear {clear_ratio:.3}"
    );
    // Rain adds streak energy; the same weather without precipitation has less.
    let rain = render(WeatherPreset::HeavyRain, &|_| {});
    let dry = render(WeatherPreset::HeavyRain, &|w| w.precipitation_pct = 0.0);
    let (er, ed) = (streak_energy(&rain), streak_energy(&dry));
    assert!(er > 1.15 * ed, "streak energy: rain {er:.3} vs dry {ed:.3}");
    // All 12 presets differ from each other: the mean absolute difference of their pixels' luminance.
    let images: Vec<(WeatherPreset, Vec<f32>)> = WeatherPreset::ALL
        .iter()
        .map(|p| (*p, render(*p, &|_| {}).rgb.chunks_exact(3).map(luminance).collect()))
        .collect();
    let mut closest = f64::MAX;
    for (i, (pa, a)) in images.iter().enumerate() {
        for (pb, b) in &images[i + 1..] {
            let d = a.iter().zip(b).map(|(x, y)| f64::from((x - y).abs())).sum::<f64>() / a.len() as f64;
            assert!(
                d > 3.0,
                "{pa:?} and {pb:?} look alike: mean luminance difference {d:.2}"
            );
            closest = closest.min(d);
        }
    }
    eprintln!(
        "luminance night {lt:.1} < sunset {ls:.1} < noon {ln:.1}; far/near contrast fog {fog_ratio:.3} vs clear \
         {clear_ratio:.3}; streaks {er:.3} vs {ed:.3}; the closest presets differ by {closest:.2} levels"
    );
}

fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(x, y)| (f64::from(*x) - f64::from(*y)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    }
}

#[test]
fn golden_images_match_within_40_db() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/camera");
    let update = std::env::var("INSTA_UPDATE").is_ok_and(|v| v == "always");
    for (weather, name) in [("clear_noon", "clear_noon"), ("night_rainy", "night_rainy")] {
        let c = clip(
            &spec("quickstart.yaml"),
            &[
                "sensors.rgb.width_px=320",
                "sensors.rgb.height_px=180",
                &format!("dataset.weathers=[{weather}]"),
            ],
        );
        let frame = c.busy_frames(1)[0];
        let img = c.render(frame);
        let path = dir.join(format!("{name}.png"));
        let bytes = pedsynth::dataset::write::sensors::rgb_png(&img).expect("png");
        if update {
            std::fs::create_dir_all(&dir).expect("mkdir");
            std::fs::write(&path, bytes).expect("write golden");
            continue;
        }
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&path)
                .unwrap_or_else(|e| panic!("{}: {e} (INSTA_UPDATE=always writes it)", path.display())),
        ));
        let mut reader = decoder.read_info().expect("golden PNG");
        let mut buf = vec![0; reader.output_buffer_size().expect("size")];
        let info = reader.next_frame(&mut buf).expect("golden frame");
        assert_eq!((info.width as usize, info.height as usize), (img.width, img.height));
        let p = psnr(&buf[..info.buffer_size()], &img.rgb);
        assert!(p >= 40.0, "{name}: PSNR {p:.1} dB against {}", path.display());
    }
}

fn generate(overrides: &[&str], out: &Path, jobs: usize) {
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), overrides, out, Some(jobs));
    assert_eq!(code, 0, "{stderr}");
}

#[test]
#[ignore = "slow (29 s in a debug build: four generations of every camera stream): cargo test -- --include-ignored"]
fn sensor_files_are_identical_across_jobs_and_resumption_and_indexed() {
    let tmp = std::env::temp_dir().join(format!("pedsynth-camera-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let small = [
        "sensors.rgb.width_px=160",
        "sensors.rgb.height_px=90",
        "dataset.clip_duration_s=[3, 4]",
        "sensors.dvs.substeps=2",
    ];
    let one = tmp.join("one");
    let a = common::generate_with_jobs_1_and_2(&spec("quickstart.yaml"), &small, &tmp);
    for stream in ["rgb", "depth", "semantic", "instance"] {
        assert!(
            a.keys()
                .any(|k| k.starts_with(&format!("sensors/{stream}/")) && k.ends_with("000000.png")),
            "no {stream} frame 0"
        );
    }
    assert!(
        a.keys()
            .any(|k| k.starts_with("sensors/dvs/") && k.ends_with(".parquet"))
    );

    // The index lists every sensor file with its size and SHA-256.
    let manifest: serde_json::Value = serde_json::from_slice(&a["manifest.json"]).expect("manifest");
    assert!(
        manifest["sensors"]["rgb"]
            .as_str()
            .is_some_and(|s| s.starts_with("rendered"))
    );
    let mut indexed = 0;
    for clip in manifest["clips"].as_array().expect("clips") {
        let id = clip["clip_id"].as_str().expect("id");
        let file = std::fs::File::open(one.join(format!("tables/sensors/{id}.parquet"))).expect("index");
        let reader = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
            .expect("parquet")
            .build()
            .expect("reader");
        for batch in reader {
            let batch = batch.expect("batch");
            use arrow_array::cast::AsArray;
            let paths = batch.column_by_name("path").expect("path").as_string::<i32>();
            let sums = batch.column_by_name("sha256").expect("sha256").as_string::<i32>();
            let bytes = batch
                .column_by_name("bytes")
                .expect("bytes")
                .as_primitive::<arrow_array::types::UInt64Type>();
            for i in 0..batch.num_rows() {
                let data = &a[paths.value(i)];
                assert_eq!(data.len() as u64, bytes.value(i));
                use sha2::Digest;
                let hex: String = sha2::Sha256::digest(data).iter().map(|b| format!("{b:02x}")).collect();
                assert_eq!(hex, sums.value(i), "{}", paths.value(i));
                indexed += 1;
            }
        }
    }
    let sensor_files = a.keys().filter(|k| k.starts_with("sensors/")).count();
    assert_eq!(indexed, sensor_files, "every sensor file is indexed, once");

    // Interrupt a clip half-way through writing: its completion marker and one of its images are gone and a
    // temporary file is left; the resumed run renders the clip again and ends byte-identical.
    let clip0 = manifest["clips"][0]["clip_id"].as_str().expect("id").to_owned();
    common::assert_resume_rewrites_clip(
        &one,
        &clip0,
        &[format!("sensors/rgb/{clip0}/000003.png")],
        &format!("sensors/depth/{clip0}/.000004.png.tmp-99999"),
        &a,
        || generate(&small, &one, 2),
    );
    std::fs::remove_dir_all(&tmp).ok();
}

/// `output.rgb_encoding: h264`: one MP4 per clip with a sample per frame, byte-identical across `--jobs` and
/// a resumed run, indexed, decoding to the frames a PNG run of the same spec writes (PSNR), and odd image
/// sizes refused by the spec check.
#[test]
fn h264_videos_hold_every_frame_deterministically_and_decode_to_the_png_frames() {
    let tmp = std::env::temp_dir().join(format!("pedsynth-camera-h264-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let rgb_only = [
        "sensors.rgb.width_px=160",
        "sensors.rgb.height_px=90",
        "dataset.clip_duration_s=[3, 4]",
        "sensors.depth.enabled=false",
        "sensors.semantic.enabled=false",
        "sensors.instance.enabled=false",
        "sensors.dvs.enabled=false",
        "sensors.lidar.enabled=false",
    ];
    let h264: Vec<&str> = rgb_only.iter().copied().chain(["output.rgb_encoding=h264"]).collect();
    let a = common::generate_with_jobs_1_and_2(&spec("quickstart.yaml"), &h264, &tmp);
    let png_dir = tmp.join("png");
    generate(&rgb_only, &png_dir, 2);
    let png = common::all_files(&png_dir);
    let manifest: serde_json::Value = serde_json::from_slice(&a["manifest.json"]).expect("manifest");
    assert!(manifest["sensors"]["rgb"].as_str().is_some_and(|s| s.contains(".mp4")));
    let sensor_files: Vec<&String> = a.keys().filter(|k| k.starts_with("sensors/")).collect();
    let clips = manifest["clips"].as_array().expect("clips");
    assert_eq!(sensor_files.len(), clips.len(), "one file per clip: {sensor_files:?}");
    let mut frames_checked = 0;
    for clip in clips {
        let id = clip["clip_id"].as_str().expect("id");
        let mp4 = tmp.join(format!("one/sensors/rgb/{id}.mp4"));
        let png_frames: Vec<&String> = png
            .keys()
            .filter(|k| k.starts_with(&format!("sensors/rgb/{id}/")))
            .collect();
        assert!(png_frames.len() > 60, "{id}: {} PNG frames", png_frames.len());
        let wanted = (0..png_frames.len() as u32).collect();
        let video = pedsynth::dataset::write::video::read_frames(&mp4, &wanted).expect("decode");
        assert_eq!(
            video.sample_count as usize,
            png_frames.len(),
            "{id}: a sample per frame"
        );
        assert_eq!((video.width, video.height), (160, 90));
        for (frame, rgb) in &video.frames {
            let want = &png[&format!("sensors/rgb/{id}/{frame:06}.png")];
            let mut reader = png::Decoder::new(std::io::Cursor::new(want.as_slice()))
                .read_info()
                .expect("png");
            let mut buf = vec![0; reader.output_buffer_size().expect("size")];
            reader.next_frame(&mut buf).expect("frame");
            let psnr = psnr(&buf, rgb);
            assert!(psnr >= 30.0, "{id} frame {frame}: PSNR {psnr:.1} dB against the PNG");
            frames_checked += 1;
        }
    }
    assert!(frames_checked > 120);

    // `output.rgb_encoding: jpeg`: one `.jpg` per frame where the PNG run has a `.png`, each a baseline JPEG of
    // the frame's size, and the index names them.
    let jpeg: Vec<&str> = rgb_only.iter().copied().chain(["output.rgb_encoding=jpeg"]).collect();
    let jpeg_dir = tmp.join("jpeg");
    generate(&jpeg, &jpeg_dir, 2);
    let jpg = common::all_files(&jpeg_dir);
    let png_names: Vec<String> = png.keys().filter(|k| k.starts_with("sensors/rgb/")).cloned().collect();
    let jpg_names: Vec<String> = jpg.keys().filter(|k| k.starts_with("sensors/rgb/")).cloned().collect();
    let want: Vec<String> = png_names.iter().map(|k| k.replace(".png", ".jpg")).collect();
    assert!(
        jpg_names == want,
        "{} RGB files, {} expected; first: {:?} vs {:?}",
        jpg_names.len(),
        want.len(),
        jpg_names.first(),
        want.first()
    );
    for name in &jpg_names {
        let bytes = &jpg[name];
        assert!(
            bytes.starts_with(&[0xff, 0xd8, 0xff]) && bytes.ends_with(&[0xff, 0xd9]),
            "{name}: not a JPEG"
        );
        let sof = bytes
            .windows(2)
            .position(|w| w == [0xff, 0xc0])
            .expect("baseline SOF0 marker");
        let size = |at: usize| u16::from_be_bytes([bytes[at], bytes[at + 1]]);
        assert_eq!((size(sof + 7), size(sof + 5)), (160, 90), "{name}: width, height");
    }
    let verify = std::process::Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .arg("verify")
        .arg(&jpeg_dir)
        .output()
        .expect("run verify");
    assert!(
        verify.status.success(),
        "verify: {}",
        String::from_utf8_lossy(&verify.stderr)
    );

    // A clip interrupted while its video was being written: no completion marker, a temporary video left.
    let one = tmp.join("one");
    let clip0 = clips[0]["clip_id"].as_str().expect("id");
    common::assert_resume_rewrites_clip(
        &one,
        clip0,
        &[format!("sensors/rgb/{clip0}.mp4")],
        &format!("sensors/rgb/.{clip0}.mp4.tmp-99999"),
        &a,
        || generate(&h264, &one, 2),
    );

    // 4:2:0 needs even sizes: an odd width is refused before anything is written, with the value located.
    let odd: Vec<&str> = h264.iter().copied().chain(["sensors.rgb.width_px=161"]).collect();
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), &odd, &tmp.join("odd"), Some(1));
    assert_ne!(code, 0);
    assert!(
        stderr.contains("must be even") && stderr.contains("sensors.rgb.width_px"),
        "{stderr}"
    );
    assert!(!tmp.join("odd/manifest.json").exists());
    std::fs::remove_dir_all(&tmp).ok();
}

#[test]
fn static_scenes_give_no_dvs_events_and_motion_gives_some() {
    let c = clip(
        &spec("quickstart.yaml"),
        &["sensors.rgb.width_px=160", "sensors.rgb.height_px=90"],
    );
    let net = &c.towns[&c.script.town].network;
    let mut per_frame = Vec::new();
    let sensors = c.plan.spec.sensors.clone();
    let stat = StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
    sensors::render_cameras(&stat, &c.script, &c.trace, &sensors, &c.rig, |f| {
        per_frame.push((
            f.frame,
            f.events.len(),
            f.events.windows(2).all(|w| w[0].t_ns <= w[1].t_ns),
        ));
        if f.frame >= 40 { Err(()) } else { Ok(()) }
    })
    .ok();
    assert_eq!(per_frame[0].1, 0, "the first image sets the reference");
    assert!(per_frame.iter().all(|f| f.2), "events sorted by time");
    assert!(
        per_frame.iter().map(|f| f.1).sum::<usize>() > 100,
        "a moving camera sees events"
    );
    // The same image twice: no events (a static scene).
    let img = c.render(10);
    let mut esim = pedsynth::sensors::camera::dvs::Esim::new(&sensors.dvs, img.width, img.height);
    let mut ev = Vec::new();
    esim.step(&img.rgb, 0, 1, &mut ev);
    esim.step(&img.rgb, 33_333_333, 2, &mut ev);
    assert!(ev.is_empty());
}

#[test]
fn a_street_lamp_between_the_camera_and_a_pedestrian_hides_the_keypoints_it_covers() {
    // A pedestrian moved 3 m behind a lamp pole, on the camera's line of sight through the pole: the
    // annotation flags the joints the pole covers as occluded (v = 1), and the rendered frame shows the pole
    // there; the joints it flags visible are on the pedestrian's pixels.
    let mut c = clip(
        &spec("quickstart.yaml"),
        &["sensors.rgb.width_px=640", "sensors.rgb.height_px=360"],
    );
    let net = &c.towns[&c.script.town].network;
    let mut checked = 0;
    for frame in (0..c.trace.frame_count as usize).step_by(10) {
        let ego = c.trace.ego[frame];
        let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
        let eye = cam.centre.truncate();
        let posts = scene::clip_lamp_posts(&c.trace, net);
        let Some(post) = posts.iter().find(|p| {
            let pole = cam.project(p.foot.extend(p.base_z_m + 1.0));
            let d = p.foot.distance(eye);
            (6.0..20.0).contains(&d) && pole.depth_m > 0.0 && cam.in_image(pole.px)
        }) else {
            continue;
        };
        let behind = eye + (post.foot - eye) * (1.0 + 3.0 / post.foot.distance(eye));
        let saved = c.trace.pedestrians[0][frame];
        c.trace.pedestrians[0][frame].pos = behind.extend(post.base_z_m);
        // The pole must still stand (no pedestrian of the clip walks through it).
        if !scene::clip_lamp_posts(&c.trace, net).contains(post) {
            c.trace.pedestrians[0][frame] = saved;
            continue;
        }
        let ann = sensors::observe(&c.script, &c.trace, &c.plan.spec, &c.rig, net).annotations;
        let Some(row) = ann.rows.iter().find(|r| r.frame as usize == frame && r.pedestrian == 0) else {
            c.trace.pedestrians[0][frame] = saved;
            continue;
        };
        let img = sensors::render_frame(&c.script, &c.trace, &c.rig, net, frame as u32);
        let id = pedestrian_instance(0);
        let keypoint = |k: usize| (row.keypoints[3 * k], row.keypoints[3 * k + 1]);
        let hidden: Vec<usize> = (0..17).filter(|&k| row.keypoints[3 * k + 2] == 1.0).collect();
        assert!(
            row.occlusion > 0.0 && !hidden.is_empty(),
            "frame {frame}: the pole hides nothing: {row:?}"
        );
        let on_pole = hidden
            .iter()
            .filter(|&&k| {
                let (x, y) = keypoint(k);
                near_pixel(&img, x, y, |i| img.semantic[i] == tag::POLE)
            })
            .count();
        assert!(
            on_pole * 2 >= hidden.len(),
            "frame {frame}: {on_pole} of {} occluded keypoints on the pole's pixels",
            hidden.len()
        );
        for k in (0..17).filter(|&k| row.keypoints[3 * k + 2] == 2.0) {
            let (x, y) = keypoint(k);
            assert!(
                near_pixel(&img, x, y, |i| img.instance[i] == id),
                "frame {frame}: visible keypoint {k} not on the pedestrian"
            );
        }
        checked += 1;
        c.trace.pedestrians[0][frame] = saved;
    }
    assert!(
        checked >= 3,
        "only {checked} frames with a pole in front of a pedestrian"
    );
}

#[test]
fn a_litter_bin_between_the_camera_and_a_pedestrian_hides_its_feet() {
    // A pedestrian moved 2.5 m behind a bin of the clip's street furniture, on the camera's line of sight through
    // the bin: the annotation flags the ankles as occluded (the same box the renderer draws stands in the way),
    // the rendered frame shows furniture (semantic `Static`) there, and no visible keypoint is on it.
    let mut c = clip(
        &spec("quickstart.yaml"),
        &["sensors.rgb.width_px=640", "sensors.rgb.height_px=360"],
    );
    let net = &c.towns[&c.script.town].network;
    let posts = scene::clip_lamp_posts(&c.trace, net);
    let bins: Vec<scene::Furniture> = scene::clip_furniture(&c.trace, net, c.script.seed, &posts)
        .into_iter()
        .filter(|f| f.kind == scene::FurnitureKind::Bin)
        .collect();
    let mut checked = 0;
    for frame in (0..c.trace.frame_count as usize).step_by(10) {
        let ego = c.trace.ego[frame];
        let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
        let eye = cam.centre.truncate();
        let Some(bin) = bins.iter().find(|b| {
            let at = cam.project(b.centre());
            (6.0..14.0).contains(&b.foot.distance(eye)) && at.depth_m > 0.0 && cam.in_image(at.px)
        }) else {
            continue;
        };
        let behind = eye + (bin.foot - eye) * (1.0 + 2.5 / bin.foot.distance(eye));
        let saved = c.trace.pedestrians[0][frame];
        c.trace.pedestrians[0][frame].pos = behind.extend(bin.base_z_m);
        let still = scene::clip_furniture(&c.trace, net, c.script.seed, &posts);
        let ann = sensors::observe(&c.script, &c.trace, &c.plan.spec, &c.rig, net).annotations;
        let row = ann.rows.iter().find(|r| r.frame as usize == frame && r.pedestrian == 0);
        let (true, Some(row)) = (still.contains(bin), row) else {
            c.trace.pedestrians[0][frame] = saved;
            continue;
        };
        let img = sensors::render_frame(&c.script, &c.trace, &c.rig, net, frame as u32);
        // COCO's ankles are keypoints 15 and 16.
        for k in [15, 16] {
            let (x, y) = (row.keypoints[3 * k], row.keypoints[3 * k + 1]);
            assert_eq!(
                row.keypoints[3 * k + 2],
                1.0,
                "frame {frame}: ankle {k} not occluded: {row:?}"
            );
            assert!(
                near_pixel(&img, x, y, |i| img.semantic[i] == tag::STATIC),
                "frame {frame}: occluded ankle {k} not on the bin's pixels"
            );
        }
        for k in (0..17).filter(|&k| row.keypoints[3 * k + 2] == 2.0) {
            let (x, y) = (row.keypoints[3 * k], row.keypoints[3 * k + 1]);
            assert!(
                near_pixel(&img, x, y, |i| img.instance[i] == pedestrian_instance(0)),
                "frame {frame}: visible keypoint {k} not on the pedestrian"
            );
        }
        checked += 1;
        c.trace.pedestrians[0][frame] = saved;
    }
    assert!(
        checked >= 2,
        "only {checked} frames with a bin in front of a pedestrian"
    );
}

/// Cyclists are drawn where the `cyclists` table puts them: for every annotated cyclist (every frame of
/// the first quickstart clip with cyclists near the ego) that nothing nearer covers, its instance pixels (rider
/// and bicycle) lie in its box and their box has IoU ≥ 0.8 with it, they carry CARLA's `Rider` and `Bicycle`
/// tags, and the rider's visible keypoints fall on its pixels.
#[test]
fn cyclists_are_drawn_in_their_boxes_as_rider_and_bicycle() {
    let overrides = [
        "sensors.rgb.width_px=640",
        "sensors.rgb.height_px=360",
        "sensors.dvs.enabled=false",
        "traffic.cyclists.per_clip=[3, 3]",
    ];
    let candidates = |c: &Clip| {
        c.ann
            .cyclists
            .iter()
            .filter(|r| r.annotated && !r.truncated && r.occlusion == 0.0)
            .count()
    };
    let c = (0..2)
        .map(|k| clip_at(&spec("quickstart.yaml"), &overrides, k))
        .find(|c| candidates(c) >= 20)
        .expect("a quickstart clip with cyclists near the ego");
    let (mut compared, mut hidden, mut keypoints, mut on_body) = (0usize, 0usize, 0usize, 0usize);
    let (mut worst_share, mut worst_iou) = (1.0f64, 1.0f64);
    let mut tags = std::collections::BTreeSet::new();
    for frame in 0..c.trace.frame_count {
        let rows: Vec<_> = c
            .ann
            .cyclists
            .iter()
            .filter(|r| r.frame == frame && r.annotated && !r.truncated && r.occlusion == 0.0)
            .collect();
        if rows.is_empty() {
            continue;
        }
        let img = c.render(frame);
        let w = img.width;
        for r in rows {
            let id = CYCLIST_INSTANCE_BASE + r.cyclist as u16;
            let b = r.bbox_px;
            let pixels: Vec<usize> = (0..img.instance.len()).filter(|&i| img.instance[i] == id).collect();
            assert!(!pixels.is_empty(), "frame {frame}: cyclist {} not drawn", r.cyclist);
            let nearest_m = pixels.iter().map(|&i| img.depth_m[i]).fold(f32::MAX, f32::min);
            let covered = (b[1] as usize..(b[3].ceil() as usize).min(img.height)).any(|y| {
                (b[0] as usize..(b[2].ceil() as usize).min(w)).any(|x| {
                    let i = y * w + x;
                    (img.instance[i] != 0 || img.semantic[i] == tag::POLE)
                        && img.instance[i] != id
                        && img.depth_m[i] < nearest_m - 0.05
                })
            });
            if covered {
                hidden += 1;
                continue;
            }
            let (mut inside, mut lo, mut hi) = (0usize, (f32::MAX, f32::MAX), (f32::MIN, f32::MIN));
            for &i in &pixels {
                let (x, y) = ((i % w) as f32 + 0.25, (i / w) as f32 + 0.25);
                inside += usize::from(x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3]);
                lo = (lo.0.min(x), lo.1.min(y));
                hi = (hi.0.max(x), hi.1.max(y));
                tags.insert(img.semantic[i]);
            }
            let share = inside as f64 / pixels.len() as f64;
            let pix = [lo.0 - 0.5, lo.1 - 0.5, hi.0 + 0.5, hi.1 + 0.5];
            let iou = box_iou(pix, b);
            assert!(
                share >= 0.95 && iou >= 0.8,
                "frame {frame}, cyclist {}: {share:.3} of its pixels in its box {b:?}, IoU {iou:.3} with {pix:?}",
                r.cyclist
            );
            worst_share = worst_share.min(share);
            worst_iou = worst_iou.min(iou);
            compared += 1;
            for k in (0..17).filter(|k| r.keypoints[3 * k + 2] == 2.0) {
                keypoints += 1;
                on_body += usize::from(near_pixel(&img, r.keypoints[3 * k], r.keypoints[3 * k + 1], |i| {
                    img.instance[i] == id
                }));
            }
        }
    }
    eprintln!(
        "{compared} cyclist-frames compared ({hidden} covered): worst in-box share {worst_share:.3}, worst IoU \
         {worst_iou:.3}; {on_body} of {keypoints} visible keypoints on the cyclist; tags {tags:?}"
    );
    assert!(compared >= 20, "only {compared} cyclist-frames compared");
    assert_eq!(
        tags,
        [tag::RIDER, tag::BICYCLE].into_iter().collect(),
        "a cyclist's pixels are Rider and Bicycle"
    );
    assert!(
        on_body as f64 >= 0.95 * keypoints as f64,
        "{on_body} of {keypoints} keypoints on the cyclist"
    );
}

/// A lane's shading does not depend on the other points in its vector: `LANES` points of one primitive shaded
/// together give, lane by lane, the bits each gives shaded alone (in every lane), for every primitive of a
/// quickstart clip's busiest frame (ground with road paint, walls with windows, bodies with their capsules'
/// normals) and the sky, by day with shadows and at night in rain with lamps, headlights and wet reflections. Runs of
/// pixels and edge samples are grouped differently, so this is what keeps an image independent of grouping.
#[test]
fn a_lanes_shading_does_not_depend_on_the_other_lanes() {
    use pedsynth::sensors::camera::lanes::{LANES, V3, lanes_from};
    use pedsynth::sensors::camera::shade::{self, ActiveLights, Noise, Points, ShadeContext};
    use rand::{RngExt, SeedableRng};

    for weather in ["clear_noon", "night_rainy"] {
        let c = clip(&spec("quickstart.yaml"), &[&format!("dataset.weathers=[{weather}]")]);
        let net = &c.towns[&c.script.town].network;
        let stat = StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
        let frame_no = c.busy_frames(1)[0];
        let mut frame = FrameScene::default();
        frame.build(&stat, &c.script, &c.trace, scene::SceneTime::at(frame_no));
        let light = Lighting::from_weather(&c.script.weather_params);
        let noise = Noise::new(c.script.seed);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        // Every primitive's triangles, static and of the frame.
        let mut tris: BTreeMap<u32, Vec<[Vec3; 3]>> = BTreeMap::new();
        for t in stat.tris.iter().chain(&frame.mesh.tris) {
            tris.entry(t.prim).or_default().push(t.v);
        }
        let (mut checked, mut painted) = (0, 0);
        for (&id, prim_tris) in &tris {
            let prim = frame.prim(&stat, id);
            // Points on the primitive's triangles, seen from 1.6 m above a point 12 m away.
            let pts: [Vec3; LANES] = std::array::from_fn(|_| {
                let v = prim_tris[rng.random_range(0..prim_tris.len())];
                let (a, b): (f32, f32) = (rng.random(), rng.random());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b
            });
            let cam = pts[0] + Vec3::new(-12.0, 3.0, 1.6);
            let mut lamps: Vec<Vec3> = stat.lamps.iter().map(|l| l.pos).collect();
            lamps.sort_by(|a, b| a.distance(pts[0]).total_cmp(&b.distance(pts[0])));
            lamps.truncate(16);
            let lights = ActiveLights {
                lamps,
                heads: vec![
                    (cam - Vec3::Z * 0.7, Vec3::X),
                    (pts[3] - Vec3::new(9.0, 0.0, 0.6), Vec3::X),
                ],
            };
            let ctx = ShadeContext {
                scene: &stat,
                frame: &frame,
                light: &light,
                noise: &noise,
                lamps: &lights.lamps,
                heads: &lights.heads,
            };
            let shadow: [f32; LANES] = std::array::from_fn(|i| [0.0, 1.0, 0.25][i % 3]);
            let points = |lane: Option<usize>| {
                let at = |i: usize| lane.unwrap_or(i);
                let p = V3::from_lanes(std::array::from_fn(|i| pts[at(i)]));
                let ray = V3::from_lanes(std::array::from_fn(|i| pts[at(i)] - cam));
                Points {
                    p,
                    ray,
                    ray_len: ray.length_squared().sqrt(),
                    shadow: lanes_from(|i| shadow[at(i)]),
                    depth_m: ray.length_squared().sqrt(),
                }
            };
            let shaded = |pts: &Points| {
                let (colour, tags) = shade::surface(&ctx, prim, pts);
                let fogged = shade::fog(&light, colour, pts.ray_len * 7.0);
                (fogged.lanes(), tags)
            };
            let (together, together_tags) = shaded(&points(None));
            for lane in 0..LANES {
                let (alone, alone_tags) = shaded(&points(Some(lane)));
                assert_eq!(
                    together[lane].to_array().map(f32::to_bits),
                    alone[0].to_array().map(f32::to_bits),
                    "{weather}: prim {id} ({:?}) lane {lane}",
                    prim.material
                );
                assert_eq!(together_tags[lane], alone_tags[0], "{weather}: prim {id} lane {lane}");
                painted += usize::from(alone_tags[0] == tag::ROAD_LINE);
            }
            checked += 1;
        }
        assert!(
            checked > 500 && painted > 0,
            "{weather}: {checked} primitives, {painted} painted points"
        );
        // The sky (its sun glow and the ground below the horizon are added only where a lane needs them):
        // directions at the sun, near it, across the sky and below the horizon.
        for _ in 0..200 {
            let dirs: [Vec3; LANES] = std::array::from_fn(|i| match i % 4 {
                0 => light.sun_dir,
                1 => (light.sun_dir + Vec3::new(rng.random_range(-0.3..0.3), rng.random_range(-0.3..0.3), 0.0))
                    .normalize(),
                2 => Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random()).normalize(),
                _ => Vec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    -rng.random::<f32>(),
                )
                .normalize(),
            });
            let together = light.sky(V3::from_lanes(dirs)).lanes();
            for lane in 0..LANES {
                let alone = light.sky(V3::from_lanes([dirs[lane]; LANES])).lanes();
                assert_eq!(
                    together[lane].to_array().map(f32::to_bits),
                    alone[0].to_array().map(f32::to_bits),
                    "{weather}: sky {:?}",
                    dirs[lane]
                );
            }
        }
    }
}
