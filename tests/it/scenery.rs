//! The scenery: domain randomisation's colours and texture contrast change the scenery and leave people and
//! every label stream alone, and the street furniture's traffic signs are drawn where `clip_furniture` puts
//! them (a plate tagged `TrafficSign` on a post tagged `Pole`), as are its bus shelters (on the sidewalk, tagged
//! `Static`).

use pedsynth::sensors::{self, camera::CameraImages, scene};

use crate::camera::{clip, clip_at, spec};

/// The pixels of a semantic class whose neighbours within two pixels have it too (away from outlines, where an
/// antialiased pixel mixes the colours on both sides).
fn inner_pixels(img: &CameraImages, class: u8) -> Vec<usize> {
    let (w, h) = (img.width, img.height);
    (2..h - 2)
        .flat_map(|y| (2..w - 2).map(move |x| (x, y)))
        .filter(|&(x, y)| (y - 2..=y + 2).all(|v| (x - 2..=x + 2).all(|u| img.semantic[v * w + u] == class)))
        .map(|(x, y)| y * w + x)
        .collect()
}

#[test]
fn scenery_colours_and_texture_contrast_change_the_scenery_and_leave_people_and_labels() {
    use pedsynth::sensors::scene::tag;
    // A fixed exposure: auto-exposure would meter the recoloured scenery and change every pixel's gain. At
    // 640 × 360, so that people have pixels away from their outlines.
    let overrides = [
        "sensors.rgb.exposure.mode=fixed",
        "sensors.rgb.width_px=640",
        "sensors.rgb.height_px=360",
    ];
    let mut c = clip(&spec("quickstart.yaml"), &overrides);
    assert!(c.script.look.is_identity());
    let frame = c.busy_frames(1)[0];
    let plain = c.render(frame);
    c.script.look.scenery_hue_deg = 120.0;
    c.script.look.scenery_saturation = 1.6;
    c.script.look.scenery_brightness = 0.8;
    let recoloured = c.render(frame);
    assert_eq!(plain.semantic, recoloured.semantic);
    assert_eq!(plain.instance, recoloured.instance);
    assert_eq!(plain.depth_m, recoloured.depth_m);
    let rgb = |img: &CameraImages, i: usize| [img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]];
    let people = inner_pixels(&plain, tag::PEDESTRIAN);
    assert!(
        people.len() > 20,
        "the frame shows people ({} inner pixels)",
        people.len()
    );
    let moved = people
        .iter()
        .filter(|&&i| rgb(&plain, i) != rgb(&recoloured, i))
        .count();
    assert_eq!(
        moved,
        0,
        "people keep their colours: {moved} of {} pixels changed",
        people.len()
    );
    let walls = inner_pixels(&plain, tag::BUILDING);
    let changed = walls.iter().filter(|&&i| rgb(&plain, i) != rgb(&recoloured, i)).count();
    // Every wall but its windows (dark glass, about a third of a facade, keeps its colour).
    assert!(
        changed * 5 > walls.len() * 3,
        "{changed} of {} wall pixels recoloured",
        walls.len()
    );
    // Texture contrast: 0 flattens the asphalt's mottling, 3 strengthens it (the spread of the road's levels).
    let spread = |img: &CameraImages| {
        let levels: Vec<f64> = inner_pixels(img, tag::ROAD)
            .iter()
            .map(|&i| f64::from(sensors::camera::luminance(&rgb(img, i))))
            .collect();
        let mean = levels.iter().sum::<f64>() / levels.len() as f64;
        (levels.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / levels.len() as f64).sqrt()
    };
    c.script.look = Default::default();
    c.script.look.texture_contrast = 0.0;
    let flat = c.render(frame);
    c.script.look.texture_contrast = 3.0;
    let rough = c.render(frame);
    assert_eq!(plain.semantic, flat.semantic);
    let (s_flat, s_plain, s_rough) = (spread(&flat), spread(&plain), spread(&rough));
    assert!(
        s_flat < s_plain && s_plain < s_rough,
        "road spread {s_flat} < {s_plain} < {s_rough}"
    );
}

#[test]
fn traffic_signs_stand_where_the_furniture_list_puts_them() {
    use scene::{FurnitureKind, tag};
    let overrides = ["sensors.rgb.width_px=640", "sensors.rgb.height_px=360"];
    let mut plates_seen = 0;
    for index in 0..2 {
        let c = clip_at(&spec("quickstart.yaml"), &overrides, index);
        let net = &c.towns[&c.script.town].network;
        let posts = scene::clip_lamp_posts(&c.trace, net);
        let furniture = scene::clip_furniture(&c.trace, net, c.script.seed, &posts);
        // Every plate is mounted on a face of the post listed just before it (touching it, not through it), its
        // bottom 1.8 m above the post's foot.
        for (k, plate) in furniture
            .iter()
            .enumerate()
            .filter(|(_, f)| f.kind == FurnitureKind::SignPlate)
        {
            let post = &furniture[k - 1];
            assert_eq!(post.kind, FurnitureKind::SignPost);
            let gap = (plate.foot - post.foot).abs() - (plate.half_m + post.half_m).truncate();
            assert!(
                gap.max_element() > 0.0 && gap.max_element() < 0.01,
                "plate {plate:?} on post {post:?}"
            );
            assert!((plate.base_z_m - post.base_z_m - 1.8).abs() < 1e-9);
            assert!(plate.base_z_m + 2.0 * plate.half_m.z <= post.base_z_m + 2.0 * post.half_m.z + 1e-9);
        }
        // In frames where a plate is 5–25 m ahead and in the image, its centre's pixel is a sign's and the
        // middle of its post a pole's (unless something nearer covers them: then the depth says so).
        for frame in (0..c.trace.frame_count as usize).step_by(15) {
            let ego = c.trace.ego[frame];
            let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
            let eye = cam.centre.truncate();
            let img = c.render(frame as u32);
            for (k, plate) in furniture
                .iter()
                .enumerate()
                .filter(|(_, f)| f.kind == FurnitureKind::SignPlate)
            {
                let post = &furniture[k - 1];
                let post_mid = post.foot.extend(post.base_z_m + 1.0);
                for (point, want) in [(plate.centre(), tag::TRAFFIC_SIGN), (post_mid, tag::POLE)] {
                    let at = cam.project(point);
                    let distance_m = plate.foot.distance(eye);
                    if !(5.0..25.0).contains(&distance_m) || at.depth_m <= 0.0 || !cam.in_image(at.px) {
                        continue;
                    }
                    let i = at.px.y as usize * img.width + at.px.x as usize;
                    if img.depth_m[i] < at.depth_m as f32 - 0.3 {
                        continue;
                    }
                    assert_eq!(
                        img.semantic[i], want,
                        "clip {index} frame {frame}: {point} at {:?}",
                        at.px
                    );
                    if want == tag::TRAFFIC_SIGN {
                        plates_seen += 1;
                    }
                }
            }
        }
    }
    assert!(plates_seen >= 3, "only {plates_seen} sign plates checked in view");
}

#[test]
fn bus_shelters_stand_on_the_sidewalk_and_are_drawn_where_listed() {
    use scene::{FurnitureKind, tag};
    let overrides = [
        "sensors.rgb.width_px=640",
        "sensors.rgb.height_px=360",
        "dataset.clips={count: 4, per: weather}",
    ];
    let is_shelter = |f: &&scene::Furniture| {
        matches!(
            f.kind,
            FurnitureKind::ShelterFrame | FurnitureKind::ShelterGlass | FurnitureKind::ShelterPoster
        )
    };
    let (mut shelters, mut seen) = (0, 0);
    for index in 0..4 {
        let c = clip_at(&spec("quickstart.yaml"), &overrides, index);
        let net = &c.towns[&c.script.town].network;
        let posts = scene::clip_lamp_posts(&c.trace, net);
        let furniture = scene::clip_furniture(&c.trace, net, c.script.seed, &posts);
        let walls: Vec<&scene::Furniture> = furniture
            .iter()
            .filter(|f| f.kind == FurnitureKind::ShelterGlass)
            .collect();
        shelters += walls.len();
        // Six parts per shelter (roof, two posts, glass, bench, poster), each within 2 m (plan view) of its
        // wall and standing on the sidewalk's surface or above it, none higher than the roof's top at 2.4 m.
        assert_eq!(furniture.iter().filter(is_shelter).count(), 6 * walls.len());
        for part in furniture.iter().filter(is_shelter) {
            let wall = walls
                .iter()
                .min_by(|a, b| a.foot.distance(part.foot).total_cmp(&b.foot.distance(part.foot)))
                .expect("a wall");
            assert!(part.foot.distance(wall.foot) < 2.0, "{part:?} away from {wall:?}");
            assert!(part.base_z_m >= wall.base_z_m - 0.1 - 1e-9);
            assert!(part.base_z_m + 2.0 * part.half_m.z <= wall.base_z_m - 0.1 + 2.4 + 1e-9);
            // Nothing of a shelter stands on the road: its footprint's corners lie on a sidewalk.
            for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                let corner = part.foot + glam::DVec2::new(sx * part.half_m.x, sy * part.half_m.y) * 0.99;
                let lane = net.lane_at(corner).map(|hit| hit.lane_type);
                assert_eq!(
                    lane,
                    Some(pedsynth::world::LaneType::Sidewalk),
                    "{part:?}: corner {corner} on {lane:?}"
                );
            }
        }
        // Where a point of a wall (its middle, and 1.3 m to each side at the same height) or a poster's centre is
        // 3–25 m ahead and in the image, its pixel is Static unless something more than 2 m nearer covers it
        // (seen along the road, a shelter's own poster end and posts may come first); some points are seen
        // directly. (In these clips the camera meets the shelters mostly from their poster's end, so the direct
        // hits are posters and the walls' points are checked where the poster does not cover them.)
        let posters: Vec<&scene::Furniture> = furniture
            .iter()
            .filter(|f| f.kind == FurnitureKind::ShelterPoster)
            .collect();
        let mut probes = Vec::new();
        for wall in &walls {
            let side = if wall.half_m.x > wall.half_m.y {
                glam::DVec3::X
            } else {
                glam::DVec3::Y
            };
            probes.extend([-1.3, 0.0, 1.3].map(|offset_m| (wall.centre() + side * offset_m, wall.foot)));
        }
        probes.extend(posters.iter().map(|p| (p.centre(), p.foot)));
        // Each wall seen square-on from the road, 6 m in front of it (the static scene alone, clear noon): its
        // centre's pixel is the glass, tagged Static, at its depth.
        let stat = scene::StaticScene::build(&c.script, &c.trace, net, &c.ann.scenery);
        for (k, wall) in furniture
            .iter()
            .enumerate()
            .filter(|(_, f)| f.kind == FurnitureKind::ShelterGlass)
        {
            let roof = &furniture[k - 3];
            assert_eq!(roof.kind, FurnitureKind::ShelterFrame);
            let out = (roof.foot - wall.foot).normalize();
            let pos = (wall.foot + out * 6.0).extend(wall.base_z_m - 0.1);
            let yaw = (-out.y).atan2(-out.x);
            let cam = c.rig.camera.at(pos, yaw, 0.0);
            let img = crate::camera::render_static(&stat, &c.rig.camera, pos, yaw);
            let at = cam.project(wall.centre());
            assert!(cam.in_image(at.px), "wall {wall:?} not in view");
            let i = at.px.y as usize * img.width + at.px.x as usize;
            assert_eq!(img.semantic[i], tag::STATIC, "clip {index}: wall {wall:?}");
            assert!(
                (img.depth_m[i] - at.depth_m as f32).abs() < 0.1,
                "{} against {}",
                img.depth_m[i],
                at.depth_m
            );
        }
        for frame in (0..c.trace.frame_count as usize).step_by(5) {
            let ego = c.trace.ego[frame];
            let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
            let eye = cam.centre.truncate();
            let img = c.render(frame as u32);
            for &(point, foot) in &probes {
                let at = cam.project(point);
                if !(3.0..25.0).contains(&foot.distance(eye)) || at.depth_m <= 0.0 || !cam.in_image(at.px) {
                    continue;
                }
                let i = at.px.y as usize * img.width + at.px.x as usize;
                let nearer_m = at.depth_m as f32 - img.depth_m[i];
                if nearer_m > 2.0 {
                    continue;
                }
                assert_eq!(
                    img.semantic[i],
                    tag::STATIC,
                    "clip {index} frame {frame}: {point} at {:?}",
                    at.px
                );
                seen += usize::from(nearer_m.abs() < 0.1);
            }
        }
    }
    eprintln!("{shelters} shelters, {seen} of their points seen directly");
    assert!(
        shelters >= 2 && seen >= 3,
        "{shelters} shelters, {seen} of their points seen directly"
    );
}
