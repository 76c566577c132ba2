//! The LiDAR (issue 14): CARLA's ray-cast model on the scene the cameras render.
//!
//! - A ray at a wall at known distance returns it within 1 mm, with intensity `exp(−a·d)`.
//! - Rays per tick = `round(pps·dt/channels)·channels`; the general and intensity drop-offs keep what the model
//!   says within 3 sigma over a clip; consecutive ticks' azimuth ranges adjoin; every point lies in its tick's
//!   sweep.
//! - Through `generate` and the written files: every point tagged Pedestrian lies inside that pedestrian's 3D
//!   box (annotations table) grown by 5 cm, once moved into the world with the `sensor_poses` table; every
//!   annotated pedestrian within 30 m in clear line of sight of the sensor, inside the tick's sweep, gets
//!   points; the files are byte-identical across --jobs and a resumed run; `carla_bin` writes the seed's
//!   layout.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, DQuat, DVec3, Vec3};
use pedsynth::dataset::read::tables;
use pedsynth::dataset::write::Layout;
use pedsynth::sensors::lidar::{self, ScanScratch, TickPattern, TickStats, Tracer};
use pedsynth::sensors::scene::{
    self, FrameScene, Material, Prim, SceneTime, StaticScene, Tri, ego_at, pedestrian_instance, tag,
};
use pedsynth::sensors::{self, body};
use pedsynth::sim;
use pedsynth::sim::rig::Rig;
use pedsynth::spec::LoadOptions;
use pedsynth::spec::types::Lidar;

fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

/// A static scene of one primitive: the given triangles.
fn scene_of(tris: Vec<Tri>) -> StaticScene {
    StaticScene {
        origin: DVec3::ZERO,
        tris,
        clusters: Vec::new(),
        prims: vec![Prim {
            material: Material::Wall,
            tag: tag::BUILDING,
            instance: 0,
            albedo: Vec3::ONE,
            albedo2: Vec3::ONE,
            normal: -Vec3::X,
            aux: 0,
        }],
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

#[test]
fn a_wall_at_a_known_distance_is_returned_within_a_millimetre() {
    let wall_x = 20.0f32;
    let (y, z) = (200.0f32, 100.0f32);
    let q = [
        Vec3::new(wall_x, -y, -z),
        Vec3::new(wall_x, y, -z),
        Vec3::new(wall_x, y, z),
        Vec3::new(wall_x, -y, z),
    ];
    let stat = scene_of(vec![
        Tri {
            v: [q[0], q[1], q[2]],
            prim: 0,
            closed: false,
        },
        Tri {
            v: [q[0], q[2], q[3]],
            prim: 0,
            closed: false,
        },
    ]);
    let l = Lidar {
        channels: 5,
        upper_fov_deg: 10.0,
        lower_fov_deg: -10.0,
        points_per_second: 30 * 5 * 360,
        dropoff_general_rate: 0.0,
        dropoff_intensity_limit: 0.0,
        noise_stddev_m: 0.0,
        ..Lidar::default()
    };
    // The sensor 1.5 m up, turned 10° left: the wall is still ahead.
    let yaw = 10f32.to_radians();
    let pose = Affine3A::from_rotation_translation(glam::Quat::from_rotation_z(yaw), Vec3::new(0.0, 0.0, 1.5));
    let mut tracer = Tracer::new(&stat);
    tracer.set_agents(&FrameScene::default(), &pose);
    let scan = |l: &Lidar| {
        let mut points = Vec::new();
        let prim = |id: u32| &stat.prims[id as usize];
        let stats = lidar::scan(
            l,
            30,
            0,
            7,
            &pose,
            &tracer,
            prim,
            &mut ScanScratch::default(),
            &mut points,
        );
        (stats, points)
    };
    let (stats, points) = scan(&l);
    assert_eq!(stats.rays, 5 * 360);
    assert!(points.len() > 300, "{} points", points.len());
    for p in &points {
        // Back into the scene: CARLA's y is right, the pose's y left.
        let world = pose.transform_point3(Vec3::new(p.x_m, -p.y_m, p.z_m));
        assert!((world.x - wall_x).abs() < 1e-3, "{world:?}");
        let d = (p.x_m * p.x_m + p.y_m * p.y_m + p.z_m * p.z_m).sqrt();
        assert!((p.intensity - (-0.004 * d).exp()).abs() < 1e-6);
        assert_eq!(p.tag, tag::BUILDING);
        // Known distance along the ray: 20 m over the cosine between the ray and the wall's normal.
        let expected = (wall_x / p.cos_incidence).min(1000.0);
        assert!((d - expected).abs() < 1e-3, "{d} vs {expected}");
    }
    // The ray straight ahead (azimuth 0, elevation 0) is at 20 / cos(10°).
    let ahead = points
        .iter()
        .min_by(|a, b| (a.y_m.abs() + a.z_m.abs()).total_cmp(&(b.y_m.abs() + b.z_m.abs())))
        .expect("a point");
    assert!((ahead.x_m - wall_x / yaw.cos()).abs() < 1e-3, "{ahead:?}");

    // Noise moves points along their rays only.
    let noisy = Lidar {
        noise_stddev_m: 0.05,
        ..l.clone()
    };
    let (_, moved) = scan(&noisy);
    assert_eq!(moved.len(), points.len());
    let mut spread = 0.0f64;
    for (a, b) in points.iter().zip(&moved) {
        let (da, db) = (Vec3::new(a.x_m, a.y_m, a.z_m), Vec3::new(b.x_m, b.y_m, b.z_m));
        assert!(
            da.normalize().dot(db.normalize()) > 1.0 - 1e-6,
            "noise stays on the ray"
        );
        spread += f64::from(db.length() - da.length()).powi(2);
    }
    let sd = (spread / points.len() as f64).sqrt();
    assert!((sd - 0.05).abs() < 0.01, "range noise sd {sd}");
}

struct Clip {
    script: pedsynth::plan::ClipScript,
    trace: pedsynth::sim::trace::ClipTrace,
    rig: Rig,
    stat: StaticScene,
    lidar: Lidar,
    annotations: pedsynth::sensors::annotate::ClipAnnotations,
    net: pedsynth::world::RoadNetwork,
}

fn quickstart_clip() -> Clip {
    clip_of(&spec("quickstart.yaml"))
}

/// The first clip of a spec, simulated, annotated and with its static scene.
fn clip_of(spec_path: &Path) -> Clip {
    let options = LoadOptions {
        overrides: Vec::new(),
        allow_large: false,
        profile: None,
    };
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(spec_path, &options).expect("plans");
    let script = plan.clips[0].clone();
    let net = towns[&script.town].network.clone();
    let trace = sim::simulate(&script, &plan.sim, &net);
    let rig = Rig::from_spec(&plan.spec.sensors);
    let annotations = sensors::observe(&script, &trace, &plan.spec, &rig, &net).annotations;
    let stat = StaticScene::build(&script, &trace, &net, &annotations.scenery);
    Clip {
        lidar: plan.spec.sensors.lidar.clone(),
        script,
        trace,
        rig,
        stat,
        annotations,
        net,
    }
}

/// Möller–Trumbore, written out here independently of the tracer: the distance along the unit ray.
fn brute_force_hit(t: &Tri, o: Vec3, d: Vec3) -> Option<f32> {
    let (e1, e2) = (t.v[1] - t.v[0], t.v[2] - t.v[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = o - t.v[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let dist = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dist > 1e-4).then_some(dist)
}

#[test]
fn the_static_acceleration_structures_return_the_nearest_triangle() {
    // A built-in town: rays from sensor-like positions along the ego's path, in every direction the sensor
    // casts, against every static triangle by brute force.
    tracer_equals_brute_force(&spec("quickstart.yaml"));
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn the_static_acceleration_structures_return_the_nearest_triangle_on_a_carla_map() {
    // The real CARLA Town01 (OpenDRIVE heights).
    common::carla_map("Town01");
    tracer_equals_brute_force(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/specs/carla_town01.yaml"));
}

fn tracer_equals_brute_force(spec_path: &Path) {
    {
        let c = clip_of(spec_path);
        let tracer = Tracer::new(&c.stat);
        let mut rng = 0x5eed_u64;
        let mut next = move || {
            rng = pedsynth::util::mix::splitmix64(rng);
            (rng >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut rays, mut hits) = (0, 0);
        for f in (0..c.trace.ego.len() as u32).step_by(7) {
            let (pos, yaw, pitch) = ego_at(&c.trace, SceneTime::at(f));
            let pose = sensors::scene_from(&c.stat, &c.rig.world_from_lidar(pos, yaw, pitch));
            let o: Vec3 = pose.translation.into();
            for _ in 0..60 {
                let azimuth = next() * std::f32::consts::TAU;
                let elevation = (next() * 40.0 - 25.0).to_radians();
                let d = Vec3::new(
                    elevation.cos() * azimuth.cos(),
                    elevation.cos() * azimuth.sin(),
                    elevation.sin(),
                );
                let expected = c
                    .stat
                    .tris
                    .iter()
                    .filter_map(|t| brute_force_hit(t, o, d))
                    .filter(|&t| t < 100.0)
                    .fold(None, |best: Option<f32>, t| Some(best.map_or(t, |b| b.min(t))));
                let mut hint = u32::MAX;
                let got = tracer.cast_static(o, d, 100.0, &mut hint).map(|h| h.distance_m);
                match (got, expected) {
                    (Some(g), Some(e)) => {
                        assert!((g - e).abs() < 1e-3, "{}: frame {f}: {g} vs {e}", spec_path.display())
                    }
                    (g, e) => assert_eq!(g, e, "{}: frame {f}, ray {d}", spec_path.display()),
                }
                rays += 1;
                hits += usize::from(expected.is_some());
            }
        }
        assert!(hits * 2 > rays, "{}: {hits} of {rays} rays hit", spec_path.display());
    }
}

/// Whether an azimuth (degrees, CARLA's: 0 forward, positive right, in [−180, 180)) lies in a tick's sweep,
/// `margin` degrees inside its ends.
fn in_sweep(l: &Lidar, p: &TickPattern, azimuth_deg: f64, margin: f64) -> bool {
    let sweep = p.step_deg * f64::from(p.rays_per_channel);
    let mut from_start = (azimuth_deg + l.horizontal_fov_deg / 2.0 - p.start_deg).rem_euclid(360.0);
    if from_start > 180.0 + sweep / 2.0 {
        from_start -= 360.0; // just before the start
    }
    from_start >= margin && from_start <= sweep - p.step_deg - margin
}

#[test]
fn ticks_follow_the_ray_pattern_the_drop_off_model_and_the_sweep() {
    let c = quickstart_clip();
    let l = &c.lidar;
    let fps = c.script.fps;
    let per_tick = (f64::from(l.points_per_second) / f64::from(fps) / f64::from(l.channels)).round() as u64
        * u64::from(l.channels);
    let mut total = TickStats::default();
    let mut ticks = 0u32;
    let mut previous_end: Option<f64> = None;
    sensors::scan_lidar(&c.stat, &c.script, &c.trace, l, &c.rig, |t| {
        assert_eq!(t.stats.rays, per_tick, "rays of tick {}", t.frame);
        assert_eq!(t.stats.kept, t.points.len() as u64);
        let p = TickPattern::of(l, fps, t.frame);
        // Adjoining sweeps: this tick starts where the previous one ended, modulo the field of view.
        if let Some(end) = previous_end {
            let gap = (p.start_deg - end).rem_euclid(360.0);
            assert!(gap < 1e-6 || (360.0 - gap) < 1e-6, "tick {}: gap {gap}°", t.frame);
        }
        previous_end = Some(p.start_deg + p.step_deg * f64::from(p.rays_per_channel));
        for q in t.points {
            let az = f64::from(q.y_m).atan2(f64::from(q.x_m)).to_degrees();
            assert!(
                in_sweep(l, &p, az, -0.01),
                "tick {}: azimuth {az}° outside its sweep",
                t.frame
            );
        }
        total += t.stats;
        ticks += 1;
        Ok::<(), ()>(())
    })
    .expect("scan");
    assert_eq!(ticks, c.trace.frame_count);
    // General drop-off: binomial over every ray.
    let g = l.dropoff_general_rate;
    let n = total.rays as f64;
    let sigma = (n * g * (1.0 - g)).sqrt();
    let traced = total.traced as f64;
    assert!(
        (traced - n * (1.0 - g)).abs() < 3.0 * sigma,
        "traced {traced} of {n}: expected {} ± {}",
        n * (1.0 - g),
        3.0 * sigma
    );
    // Intensity drop-off: a sum of Bernoulli draws with the model's probabilities.
    let kept = total.kept as f64;
    let sd = total.kept_variance.sqrt();
    assert!(
        total.kept_variance > 0.0 && (kept - total.expected_kept).abs() < 3.0 * sd,
        "kept {kept}: expected {} ± {}",
        total.expected_kept,
        3.0 * sd
    );
    eprintln!(
        "rays {n}, traced {traced} (expected {:.0} ± {:.0}), kept {kept} of {} hits (expected {:.0} ± {:.0})",
        n * (1.0 - g),
        3.0 * sigma,
        total.hits,
        total.expected_kept,
        3.0 * sd
    );
    assert!(total.hits as f64 > 0.5 * traced, "most rays hit something in a town");
}

#[test]
fn pedestrians_in_clear_view_get_points_and_every_pedestrian_point_is_in_its_box() {
    let mut c = quickstart_clip();
    // Without the general drop-off (random by design), and within 30 m the intensity drop-off keeps every
    // return, so a pedestrian in clear view inside the sweep must get points.
    c.lidar.dropoff_general_rate = 0.0;
    assert!((-c.lidar.atmosphere_attenuation_per_m * 30.0).exp() > c.lidar.dropoff_intensity_limit);
    let l = &c.lidar;
    // Each body of the clip by instance id: (pedestrian index, child?).
    let mut bodies: BTreeMap<u16, (usize, bool)> = BTreeMap::new();
    for (i, p) in c.script.pedestrians.iter().enumerate() {
        bodies.insert(pedestrian_instance(p.id), (i, false));
        if p.child.is_some() {
            bodies.insert(scene::CHILD_INSTANCE_BASE + p.id as u16, (i, true));
        }
    }
    let mut inside = 0u64;
    let mut by_frame: BTreeMap<u32, Vec<(u32, u32)>> = BTreeMap::new(); // frame → (actor, points)
    sensors::scan_lidar(&c.stat, &c.script, &c.trace, l, &c.rig, |t| {
        let mut counts: BTreeMap<u32, u32> = BTreeMap::new();
        let (pos, yaw, pitch) = ego_at(&c.trace, SceneTime::at(t.frame));
        let world_from_lidar = c.rig.world_from_lidar(pos, yaw, pitch);
        for p in t.points.iter().filter(|p| p.tag == tag::PEDESTRIAN) {
            *counts.entry(u32::from(p.instance)).or_default() += 1;
            // Every pedestrian point, annotated or not, adult or child, lies in its own body's 3D box + 5 cm.
            let (pi, child) = bodies[&p.instance];
            let ps = &c.script.pedestrians[pi];
            let frame = &c.trace.pedestrians[pi][t.frame as usize];
            let pose = match (&ps.child, child) {
                (Some(k), true) => body::pose(frame, k.height_m, &k.figure, body::CHILD_OFFSET_M),
                _ => body::pose(frame, ps.identity.height_m, &ps.identity.figure, DVec3::ZERO),
            };
            let (centre, size) = pose.box3d();
            let world =
                world_from_lidar.transform_point3(DVec3::new(f64::from(p.x_m), -f64::from(p.y_m), f64::from(p.z_m)));
            let local = glam::DMat3::from_rotation_z(-pose.yaw_rad) * (world - centre);
            let half = size * 0.5 + DVec3::splat(0.05);
            assert!(
                local.abs().cmple(half).all(),
                "frame {}: a point of body {} is {local:?} from its box centre (half {half:?})",
                t.frame,
                p.instance
            );
            inside += 1;
        }
        by_frame.insert(t.frame, counts.into_iter().collect());
        Ok::<(), ()>(())
    })
    .expect("scan");
    let mut tracer = Tracer::new(&c.stat);
    let mut frame_scene = FrameScene::default();
    let (mut checked, mut blocked) = (0, 0);
    for row in &c.annotations.rows {
        let t = SceneTime::at(row.frame);
        let (pos, yaw, pitch) = ego_at(&c.trace, t);
        let world_from_lidar = c.rig.world_from_lidar(pos, yaw, pitch);
        let target = DVec3::new(
            f64::from(row.box3d_centre_m[0]),
            f64::from(row.box3d_centre_m[1]),
            f64::from(row.box3d_centre_m[2]),
        );
        let in_sensor = world_from_lidar.inverse().transform_point3(target);
        if in_sensor.length() > 30.0 {
            continue;
        }
        let p = TickPattern::of(l, c.script.fps, row.frame);
        let azimuth = (-in_sensor.y).atan2(in_sensor.x).to_degrees();
        let elevation = in_sensor.z.atan2(in_sensor.truncate().length()).to_degrees();
        if !in_sweep(l, &p, azimuth, 2.0) || elevation > l.upper_fov_deg || elevation < l.lower_fov_deg {
            continue;
        }
        // Clear line of sight from the sensor to the body's centre: the first surface is this pedestrian.
        frame_scene.build(&c.stat, &c.script, &c.trace, t);
        let pose = sensors::scene_from(&c.stat, &world_from_lidar);
        tracer.set_agents(&frame_scene, &pose);
        let o: Vec3 = pose.translation.into();
        let to = (target - c.stat.origin).as_vec3();
        let Some(hit) = tracer.cast(o, (to - o).normalize(), 200.0) else {
            continue;
        };
        let instance = pedestrian_instance(c.script.pedestrians[row.pedestrian as usize].id);
        if frame_scene.prim(&c.stat, hit.prim).instance != instance {
            blocked += 1;
            continue;
        }
        checked += 1;
        let got = by_frame[&row.frame]
            .iter()
            .find(|(i, _)| *i == u32::from(instance))
            .map_or(0, |x| x.1);
        assert!(
            got > 0,
            "frame {}: pedestrian {} at {:.1} m in clear view got no point",
            row.frame,
            row.pedestrian,
            in_sensor.length()
        );
    }
    eprintln!(
        "pedestrian-frames in clear view within 30 m checked: {checked} ({blocked} blocked); {inside} pedestrian \
         points inside their bodies' boxes"
    );
    assert!(inside >= 1000, "{inside} pedestrian points");
    assert!(checked >= 20, "{checked} pedestrian-frames checked ({blocked} blocked)");
    let _ = &c.net;
}

fn generate(overrides: &[&str], out: &Path, jobs: usize) {
    let (code, _, stderr) = common::generate(&spec("quickstart.yaml"), overrides, out, Some(jobs));
    assert_eq!(code, 0, "{stderr}");
}

#[test]
#[ignore = "slow (20 s in a debug build: the quickstart's LiDAR written twice): cargo test -- --include-ignored"]
fn written_points_lie_in_their_pedestrians_boxes_and_files_are_reproducible() {
    let tmp = std::env::temp_dir().join(format!("pedsynth-lidar-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    // A LiDAR-only dataset of short clips.
    let lidar_only: Vec<&str> = common::NO_CAMERAS
        .into_iter()
        .chain(["dataset.clip_duration_s=[4, 5]"])
        .collect();
    let one = tmp.join("one");
    let files = common::generate_with_jobs_1_and_2(&spec("quickstart.yaml"), &lidar_only, &tmp);
    let layout = Layout::new(&one);
    let manifest: serde_json::Value = serde_json::from_slice(&files["manifest.json"]).expect("manifest");
    assert!(
        manifest["sensors"]["lidar"]
            .as_str()
            .is_some_and(|s| s.starts_with("rendered"))
    );
    let (mut inside, mut unannotated) = (0u64, 0u64);
    for clip in manifest["clips"].as_array().expect("clips") {
        let id = clip["clip_id"].as_str().expect("id");
        // Poses: frame → world_from_lidar.
        let mut poses: BTreeMap<u32, glam::DAffine3> = BTreeMap::new();
        for b in tables::read(
            &layout.table("sensor_poses", id),
            &["frame", "sensor", "x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"],
        )
        .expect("poses")
        {
            let (f, s) = (b.u32s("frame").unwrap(), b.strings("sensor").unwrap());
            let c = |n: &str| b.f64s(n).unwrap().clone();
            let (x, y, z, qw, qx, qy, qz) = (c("x_m"), c("y_m"), c("z_m"), c("qw"), c("qx"), c("qy"), c("qz"));
            for (i, sensor) in s.iter().enumerate() {
                if *sensor == "lidar" {
                    let q = DQuat::from_xyzw(qx.value(i), qy.value(i), qz.value(i), qw.value(i));
                    poses.insert(
                        f.value(i),
                        glam::DAffine3::from_rotation_translation(q, DVec3::new(x.value(i), y.value(i), z.value(i))),
                    );
                }
            }
        }
        // Boxes: (frame, pedestrian) → (centre, size, yaw).
        let mut boxes: BTreeMap<(u32, u32), (DVec3, DVec3, f64)> = BTreeMap::new();
        let cols = [
            "frame",
            "pedestrian",
            "yaw_rad",
            "box3d_x_m",
            "box3d_y_m",
            "box3d_z_m",
            "box3d_length_m",
            "box3d_width_m",
            "box3d_height_m",
        ];
        for b in tables::read(&layout.table("annotations", id), &cols).expect("annotations") {
            let (f, p) = (b.u32s("frame").unwrap(), b.u32s("pedestrian").unwrap());
            let g = |n: &str| b.f32s(n).unwrap().clone();
            let (yaw, x, y, z, bl, bw, bh) = (
                g("yaw_rad"),
                g("box3d_x_m"),
                g("box3d_y_m"),
                g("box3d_z_m"),
                g("box3d_length_m"),
                g("box3d_width_m"),
                g("box3d_height_m"),
            );
            for i in 0..b.rows() {
                let v = |a: &arrow_array::Float32Array| f64::from(a.value(i));
                boxes.insert(
                    (f.value(i), p.value(i)),
                    (
                        DVec3::new(v(&x), v(&y), v(&z)),
                        DVec3::new(v(&bl), v(&bw), v(&bh)),
                        v(&yaw),
                    ),
                );
            }
        }
        let path = layout.sensor_clip("lidar", id, "parquet");
        for b in tables::read(&path, &["frame", "x", "y", "z", "tag", "instance", "actor_id"]).expect("points") {
            let (f, tg, inst) = (
                b.u32s("frame").unwrap(),
                b.u8s("tag").unwrap(),
                b.u16s("instance").unwrap(),
            );
            let (x, y, z) = (b.f32s("x").unwrap(), b.f32s("y").unwrap(), b.f32s("z").unwrap());
            let actor = b.u32s("actor_id").unwrap();
            for i in 0..b.rows() {
                if tg.value(i) != tag::PEDESTRIAN || inst.value(i) >= scene::CHILD_INSTANCE_BASE {
                    continue;
                }
                let Some(&(centre, size, yaw)) = boxes.get(&(f.value(i), actor.value(i))) else {
                    unannotated += 1;
                    continue;
                };
                let sensor = DVec3::new(f64::from(x.value(i)), -f64::from(y.value(i)), f64::from(z.value(i)));
                let world = poses[&f.value(i)].transform_point3(sensor);
                let local = glam::DMat3::from_rotation_z(-yaw) * (world - centre);
                let half = size * 0.5 + DVec3::splat(0.05);
                assert!(
                    local.x.abs() <= half.x && local.y.abs() <= half.y && local.z.abs() <= half.z,
                    "clip {id} frame {}: pedestrian {}'s point {world:?} is {local:?} from its box centre (half {half:?})",
                    f.value(i),
                    actor.value(i)
                );
                inside += 1;
            }
        }
    }
    eprintln!("pedestrian points inside their boxes: {inside} ({unannotated} of unannotated pedestrians)");
    assert!(
        inside >= 200,
        "{inside} pedestrian points checked ({unannotated} of unannotated pedestrians)"
    );

    // Interrupted half-way: the clip's completion marker and its LiDAR file are gone and a temporary file is
    // left; the resumed run writes the clip again, byte-identical.
    let clip0 = manifest["clips"][0]["clip_id"].as_str().expect("id").to_owned();
    common::assert_resume_rewrites_clip(
        &one,
        &clip0,
        &[format!("sensors/lidar/{clip0}.parquet")],
        &format!("sensors/lidar/.{clip0}.parquet.tmp-99999"),
        &files,
        || generate(&lidar_only, &one, 2),
    );

    // The seed's layout: one .bin per frame with the same points' x y z intensity.
    let bin_dir = tmp.join("bin");
    let mut overrides = lidar_only.clone();
    overrides.push("sensors.lidar.format=carla_bin");
    generate(&overrides, &bin_dir, 2);
    let bins = common::all_files(&bin_dir);
    let first = bins
        .iter()
        .find(|(k, _)| k.starts_with(&format!("sensors/lidar/{clip0}/")) && k.ends_with("000010.bin"))
        .expect("frame 10's .bin")
        .1;
    let mut expected = Vec::new();
    for b in tables::read(
        &layout.sensor_clip("lidar", &clip0, "parquet"),
        &["frame", "x", "y", "z", "intensity"],
    )
    .expect("points")
    {
        let f = b.u32s("frame").unwrap();
        let cols = ["x", "y", "z", "intensity"].map(|n| b.f32s(n).unwrap().clone());
        for i in (0..b.rows()).filter(|&i| f.value(i) == 10) {
            for c in &cols {
                expected.extend(c.value(i).to_le_bytes());
            }
        }
    }
    assert!(!expected.is_empty());
    assert!(*first == expected, "the .bin holds the Parquet's points of the frame");
    std::fs::remove_dir_all(&tmp).ok();
}
