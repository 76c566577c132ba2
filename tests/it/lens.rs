//! Lens distortion (`sensors.rgb.distortion`, Brown–Conrady): a projected grid lands on the distorted image's
//! pixels, every visible keypoint lands on its pedestrian and the instance masks stay in the boxes, the pinhole
//! stays bit for bit what it was, and a lens that folds over inside the image is refused with its location.

use glam::{DVec3, Vec2};
use pedsynth::sensors::scene::{Material, Mesh, tag};
use pedsynth::sim::rig::Camera;
use pedsynth::spec::types::{Distortion, Mount, Rgb};

use crate::camera::{flat, masks_match_boxes_and_keypoints, render_static, static_scene};
use crate::common;

/// A strong barrel lens with tangential terms (a wide dashcam lens is about half as strong).
const LENS: Distortion = Distortion {
    k1: -0.3,
    k2: 0.08,
    p1: 0.002,
    p2: -0.0015,
    k3: 0.0,
};

#[test]
fn a_projected_grid_lands_on_the_distorted_image_within_a_pixel() {
    let rgb = Rgb {
        width_px: 640,
        height_px: 360,
        mount: Mount {
            pitch_deg: 0.0,
            ..Mount::default()
        },
        distortion: LENS,
        ..Rgb::default()
    };
    let camera = Camera::from_spec(&rgb);
    let pinhole = Camera::from_spec(&Rgb {
        distortion: Distortion::default(),
        ..rgb.clone()
    });
    let (pos, yaw) = (DVec3::new(3.0, -2.0, 0.0), 0.4);
    let pose = camera.at(pos, yaw, 0.0);
    // A grid of 0.3 m squares facing the camera, 8 m ahead, over the whole field of view (normalised image
    // coordinates −1.1…1.1 by −0.6…0.6: the lens shows more than the pinhole's ±1 × ±0.56), each its own
    // instance.
    let mut mesh = Mesh::default();
    let mut points = Vec::new();
    for j in -3..=3 {
        for i in -5..=5 {
            let (x, y) = (0.22 * f64::from(i), 0.2 * f64::from(j));
            let centre = pose.centre + (pose.forward + pose.right * x + pose.down * y) * 8.0;
            let instance = 1 + points.len() as u16;
            let id = mesh.prim(flat(Material::Metal, tag::POLE, instance, -pose.forward.as_vec3()));
            let (r, d) = (pose.right.as_vec3() * 0.15, pose.down.as_vec3() * 0.15);
            let c = centre.as_vec3();
            mesh.quad([c - r - d, c + r - d, c + r + d, c - r + d], id);
            points.push((instance, centre));
        }
    }
    let img = render_static(&static_scene(mesh), &camera, pos, yaw);
    assert_eq!((img.width, img.height), (640, 360));
    let (mut checked, mut worst, mut pinhole_off) = (0, 0.0f64, 0.0f64);
    for (instance, centre) in points {
        let want = pose.project(centre).px;
        let (mut sum, mut n) = (Vec2::ZERO, 0.0f32);
        for (i, &v) in img.instance.iter().enumerate() {
            if v == instance {
                sum += Vec2::new((i % img.width) as f32 + 0.25, (i / img.width) as f32 + 0.25);
                n += 1.0;
            }
        }
        let inside = want.x > 8.0 && want.y > 8.0 && want.x < 632.0 && want.y < 352.0;
        if !inside {
            continue;
        }
        assert!(n > 40.0, "square {instance} at {want}: {n} pixels");
        let centroid = (sum / n).as_dvec2();
        let d = (centroid - want).length();
        worst = worst.max(d);
        assert!(
            d < 1.0,
            "square {instance}: pixels centred at {centroid}, projected to {want} ({d:.2} px)"
        );
        pinhole_off = pinhole_off.max((pinhole.at(pos, yaw, 0.0).project(centre).px - want).length());
        checked += 1;
    }
    eprintln!(
        "{checked} grid squares within {worst:.2} px of their projections; the pinhole is up to {pinhole_off:.0} px off"
    );
    assert!(checked >= 60, "{checked} squares checked");
    assert!(
        pinhole_off > 40.0,
        "the lens moves the grid's outer squares: {pinhole_off} px"
    );
}

#[test]
fn keypoints_and_masks_stay_on_the_distorted_pixels() {
    let r = masks_match_boxes_and_keypoints(&[
        "sensors.rgb.distortion.k1=-0.3",
        "sensors.rgb.distortion.k2=0.08",
        "sensors.rgb.distortion.p1=0.002",
        "sensors.rgb.distortion.p2=-0.0015",
    ]);
    assert!(r.keypoints > 1000, "{} keypoints", r.keypoints);
}

#[test]
fn keypoints_and_masks_stay_on_the_pixels_of_a_nodding_car() {
    // A body pitch four times JAAD's (2°, 0.35 s) moves the image by up to ~25 px at 640 × 360: the annotations'
    // camera and the renderer's must pitch together.
    let r = masks_match_boxes_and_keypoints(&[
        "traffic.ego.pitch_wobble.sd_deg=2",
        "traffic.ego.pitch_wobble.correlation_s=0.35",
    ]);
    assert!(r.keypoints > 1000, "{} keypoints", r.keypoints);
}

#[test]
fn a_lens_that_folds_inside_the_image_is_refused_at_its_key() {
    let spec = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let args = [
        "plan".as_ref(),
        spec.as_os_str(),
        "--set".as_ref(),
        "sensors.rgb.distortion={k1: -0.9}".as_ref(),
    ];
    let (code, _, err) = common::pedsynth(&args);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("folds over inside the image"), "{err}");
    assert!(err.contains("sensors.rgb.distortion"), "{err}");
}

#[test]
fn a_pinhole_is_unchanged_by_the_lens_code() {
    // Distortion zero: the projection is the pinhole's formula bit for bit.
    let camera = Camera::from_spec(&Rgb::default());
    assert!(camera.lens.is_pinhole());
    let pose = camera.at(DVec3::new(1.0, 2.0, 0.0), 0.3, 0.0);
    let p = pose.centre + pose.forward * 9.0 + pose.right * 2.5 - pose.down * 0.7;
    let o = pose.optical_from_world.transform_point3(p);
    let want = (
        camera.focal_px * o.x * (1.0 / o.z) + 640.0,
        camera.focal_px * o.y * (1.0 / o.z) + 360.0,
    );
    let got = pose.project(p).px;
    assert_eq!((got.x.to_bits(), got.y.to_bits()), (want.0.to_bits(), want.1.to_bits()));
}
