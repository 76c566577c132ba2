//! The camera's sensor (`sensors.rgb.exposure`, `vignetting`, `noise`, `motion_blur`): auto-exposure brightens a
//! night clip within its gain and leaves noon as it was, vignetting dims the corners and not the centre, noise is
//! seeded (the same frame twice is the same bytes), motion blur smears only the RGB, and the label streams and
//! the DVS's events stay exactly what a noise-free, fixed-exposure camera gives.

use pedsynth::sensors::{self, camera::CameraImages, scene::StaticScene};

use crate::camera::{Clip, clip, mean_luminance, spec};

const SMALL: [&str; 2] = ["sensors.rgb.width_px=320", "sensors.rgb.height_px=180"];

fn quickstart(weather: &str, more: &[&str]) -> Clip {
    let weather = format!("dataset.weathers=[{weather}]");
    let mut overrides: Vec<&str> = SMALL.to_vec();
    overrides.push(&weather);
    overrides.extend_from_slice(more);
    clip(&spec("quickstart.yaml"), &overrides)
}

fn busy(weather: &str, more: &[&str]) -> CameraImages {
    let c = quickstart(weather, more);
    c.render(c.busy_frames(1)[0])
}

/// The mean luminance of the pixels within `share` of the image's half-diagonal from its centre, and of those
/// beyond `1 − share` (the corners).
fn centre_and_corners(img: &CameraImages, share: f64) -> (f64, f64) {
    let (w, h) = (img.width as f64, img.height as f64);
    let corner = 0.5 * (w * w + h * h).sqrt();
    let (mut centre, mut corners) = ((0.0, 0usize), (0.0, 0usize));
    for (i, px) in img.rgb.chunks_exact(3).enumerate() {
        let (x, y) = (
            (i % img.width) as f64 + 0.5 - 0.5 * w,
            (i / img.width) as f64 + 0.5 - 0.5 * h,
        );
        let r = (x * x + y * y).sqrt() / corner;
        let l = f64::from(sensors::camera::luminance(px));
        if r <= share {
            centre = (centre.0 + l, centre.1 + 1);
        } else if r >= 1.0 - share {
            corners = (corners.0 + l, corners.1 + 1);
        }
    }
    (centre.0 / centre.1 as f64, corners.0 / corners.1 as f64)
}

#[test]
fn auto_exposure_brightens_the_night_within_its_gain_and_leaves_noon_as_it_was() {
    // Noon meters brighter than the key: a gain of 1, the same bytes as a fixed exposure.
    assert_eq!(
        busy("clear_noon", &[]).rgb,
        busy("clear_noon", &["sensors.rgb.exposure.mode=fixed"]).rgb
    );
    // Night: brighter with more gain allowed, and every step of gain brightens it.
    let fixed = mean_luminance(&busy("night_clear", &["sensors.rgb.exposure.mode=fixed"]));
    let low = mean_luminance(&busy("night_clear", &["sensors.rgb.exposure.max_gain=2"]));
    let auto = mean_luminance(&busy("night_clear", &[]));
    assert!(
        fixed < low && low < auto,
        "night luminance: fixed {fixed:.1}, gain ≤ 2 {low:.1}, auto {auto:.1}"
    );
    let noon = mean_luminance(&busy("clear_noon", &[]));
    // The default key brings the night to a daylight-like level (not beyond noon's by far).
    assert!(
        auto > 0.6 * noon && auto < 1.3 * noon,
        "night {auto:.1} against noon {noon:.1}"
    );
    eprintln!("mean luminance: night fixed {fixed:.1}, gain ≤ 2 {low:.1}, auto {auto:.1}; noon {noon:.1}");
}

#[test]
fn the_clip_renderer_meters_a_gain_between_one_and_its_bound() {
    for (weather, max_gain, want_above_one) in [("clear_noon", 16.0f32, false), ("night_clear", 16.0, true)] {
        let c = quickstart(weather, &[]);
        let net = &c.towns[&c.script.town].network;
        let stat = StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
        let gain = sensors::clip_renderer(&stat, &c.script, &c.trace, &c.rig).gain();
        assert!((1.0..=max_gain).contains(&gain), "{weather}: gain {gain}");
        assert_eq!(gain > 1.0, want_above_one, "{weather}: gain {gain}");
    }
}

#[test]
fn vignetting_dims_the_corners_and_not_the_centre() {
    // A fixed exposure: auto-exposure meters the dimmed corners and brightens the whole frame a little (2 % at
    // the centre of this frame), which is not vignetting's doing.
    let plain = busy("clear_noon", &["sensors.rgb.exposure.mode=fixed"]);
    let dimmed = busy(
        "clear_noon",
        &["sensors.rgb.exposure.mode=fixed", "sensors.rgb.vignetting=0.5"],
    );
    let (c0, k0) = centre_and_corners(&plain, 0.1);
    let (c1, k1) = centre_and_corners(&dimmed, 0.1);
    assert!((c1 - c0).abs() < 0.02 * c0, "centre {c0:.1} → {c1:.1}");
    // Half the light at the very corner, a bit less just inside it; through the tone curve that is less
    // than half the level.
    assert!(k1 < 0.9 * k0 && k1 > 0.4 * k0, "corners {k0:.1} → {k1:.1}");
}

#[test]
fn noise_is_seeded_and_labels_stay_exact() {
    let sensor = [
        "sensors.rgb.noise.shot=0.02",
        "sensors.rgb.noise.read=0.001",
        "sensors.rgb.vignetting=0.3",
    ];
    let c = quickstart("night_rainy", &sensor);
    let frame = c.busy_frames(1)[0];
    let (a, b) = (c.render(frame), c.render(frame));
    assert_eq!(a, b, "the same frame renders the same bytes");
    let clean = busy("night_rainy", &["sensors.rgb.exposure.mode=fixed"]);
    assert_eq!(a.depth_m, clean.depth_m);
    assert_eq!(a.semantic, clean.semantic);
    assert_eq!(a.instance, clean.instance);
    // Noise: most pixels differ from the noise-free image at the same exposure and vignetting.
    let quiet = busy("night_rainy", &["sensors.rgb.vignetting=0.3"]);
    let differ = a.rgb.iter().zip(&quiet.rgb).filter(|(x, y)| x != y).count();
    assert!(differ > a.rgb.len() / 2, "{differ} of {} values differ", a.rgb.len());
}

#[test]
fn the_dvs_sees_the_clean_image() {
    // Events of a short stretch of a rainy night clip, with and without sensor noise: the same events.
    let events = |noise: &str| {
        let mut overrides: Vec<&str> = SMALL.to_vec();
        overrides.extend([
            "dataset.weathers=[night_rainy]",
            "dataset.clip_duration_s=[1, 1]",
            noise,
        ]);
        let c = clip(&spec("quickstart.yaml"), &overrides);
        let net = &c.towns[&c.script.town].network;
        let stat = StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
        let mut all = Vec::new();
        let mut rgb = Vec::new();
        sensors::render_cameras::<()>(&stat, &c.script, &c.trace, &c.plan.spec.sensors, &c.rig, |f| {
            all.extend(f.events.iter().map(|e| format!("{e:?}")));
            rgb.push(f.images.rgb.clone());
            Ok(())
        })
        .expect("render");
        (all, rgb)
    };
    let (quiet, quiet_rgb) = events("sensors.rgb.noise.shot=0");
    let (noisy, noisy_rgb) = events("sensors.rgb.noise.shot=0.02");
    assert!(!quiet.is_empty(), "the DVS fires");
    assert_eq!(quiet, noisy);
    assert_ne!(quiet_rgb, noisy_rgb, "the RGB stream is noisy");
}

#[test]
fn domain_randomisation_draws_a_look_per_clip_and_the_images_follow_it() {
    let dr = [
        "domain_randomisation.light_intensity=[0.5, 2]",
        "domain_randomisation.white_balance=[0.6, 1.6]",
        "domain_randomisation.sun_azimuth_offset_deg=[-90, 90]",
        "sensors.rgb.exposure.mode=fixed",
    ];
    let mut overrides: Vec<&str> = SMALL.to_vec();
    overrides.extend(dr);
    let mut a = clip(&spec("quickstart.yaml"), &overrides);
    let b = crate::camera::clip_at(&spec("quickstart.yaml"), &overrides, 1);
    assert!(!a.script.look.is_identity() && !b.script.look.is_identity());
    assert_ne!(a.script.look, b.script.look, "each clip draws its own look");
    // The same clip without domain randomisation: the weather as the preset has it, the identity look.
    let mut plain: Vec<&str> = SMALL.to_vec();
    plain.push("sensors.rgb.exposure.mode=fixed");
    let p = clip(&spec("quickstart.yaml"), &plain);
    assert!(p.script.look.is_identity());
    assert_ne!(
        a.script.weather_params.sun_azimuth_deg,
        p.script.weather_params.sun_azimuth_deg
    );
    // The colour balance shows: the channel with the larger gain gains on the other (in the mean level).
    let frame = a.busy_frames(1)[0];
    let tinted = a.render(frame);
    let wb = a.script.look.white_balance;
    a.script.look.white_balance = [1.0; 3];
    let untinted = a.render(frame);
    let means = |img: &CameraImages| -> [f64; 3] {
        let n = (img.rgb.len() / 3) as f64;
        std::array::from_fn(|c| img.rgb.iter().skip(c).step_by(3).map(|&v| f64::from(v)).sum::<f64>() / n)
    };
    let (t, u) = (means(&tinted), means(&untinted));
    for (i, j) in [(0, 1), (1, 2), (0, 2)] {
        let (gain_ratio, level_ratio) = (wb[i] / wb[j], (t[i] / t[j]) / (u[i] / u[j]));
        assert_eq!(
            gain_ratio > 1.0,
            level_ratio > 1.0,
            "channels {i}/{j}: gains {wb:?}, means {t:?} vs {u:?}"
        );
    }
}

#[test]
fn motion_blur_smears_the_rgb_of_its_frame_and_leaves_the_labels() {
    let blur = ["sensors.rgb.motion_blur.shutter_ms=2"];
    // By day a 2 ms shutter is one render: the same bytes as no blur.
    assert_eq!(busy("clear_noon", &blur).rgb, busy("clear_noon", &[]).rgb);
    // At night auto-exposure opens it by its gain: the RGB is smeared, the labels and depth are the frame's.
    let c = quickstart("night_clear", &blur);
    let frame = c.busy_frames(1)[0];
    let blurred = c.render(frame);
    let sharp = busy("night_clear", &[]);
    assert_eq!(blurred.depth_m, sharp.depth_m);
    assert_eq!(blurred.semantic, sharp.semantic);
    assert_eq!(blurred.instance, sharp.instance);
    let differ = blurred.rgb.iter().zip(&sharp.rgb).filter(|(x, y)| x != y).count();
    assert!(
        differ > blurred.rgb.len() / 50,
        "{differ} of {} values differ",
        blurred.rgb.len()
    );
    let (b, s) = (mean_luminance(&blurred), mean_luminance(&sharp));
    assert!(
        (b - s).abs() < 0.03 * s,
        "a blur keeps the light: {b:.2} against {s:.2}"
    );
    // The clip's frame equals the single frame rendered alone (every frame a pure function of the clip).
    let mut overrides: Vec<&str> = SMALL.to_vec();
    overrides.extend([
        "dataset.weathers=[night_clear]",
        "dataset.clip_duration_s=[1, 1]",
        blur[0],
    ]);
    let c = clip(&spec("quickstart.yaml"), &overrides);
    let net = &c.towns[&c.script.town].network;
    let stat = StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
    let mut frames = Vec::new();
    sensors::render_cameras::<()>(&stat, &c.script, &c.trace, &c.plan.spec.sensors, &c.rig, |f| {
        frames.push(f.images.rgb.clone());
        Ok(())
    })
    .expect("render");
    for frame in [0u32, 7] {
        assert_eq!(frames[frame as usize], c.render(frame).rgb, "frame {frame}");
    }
}
