//! The camera streams against the labels and against physics: instance masks agree with the annotated boxes
//! and keypoints frame by frame (one camera model), depth of a known plane, semantic ids of known surfaces,
//! weathers that differ measurably, golden images within a PSNR tolerance, and sensor files that are
//! byte-identical across job counts and resumption (a clip interrupted while rendering is rendered again).

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec2, Vec3};
use pedsynth::commands::{self, GenerateArgs};
use pedsynth::dsl::LoadOptions;
use pedsynth::dsl::types::{Rgb, WeatherPreset};
use pedsynth::exec::observe::camera::{CameraImages, Renderer, SKY_DEPTH_M, light::Lighting, luminance};
use pedsynth::exec::observe::rig::{Camera, Rig};
use pedsynth::exec::observe::scene::{
    self, Cluster, FrameScene, Material, Prim, StaticScene, Tri, pedestrian_instance, tag,
};
use pedsynth::exec::observe::{self, annotate::ClipAnnotations};
use pedsynth::exec::simulate;
use pedsynth::exec::trace::ClipTrace;
use pedsynth::planner::{ClipScript, Plan, TownContext};

fn spec(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("specs").join(name)
}

fn options(overrides: &[&str]) -> LoadOptions {
    LoadOptions {
        overrides: overrides.iter().map(|s| s.to_string()).collect(),
        allow_large: false,
    }
}

struct Clip {
    plan: Plan,
    towns: BTreeMap<String, TownContext>,
    script: ClipScript,
    trace: ClipTrace,
    ann: ClipAnnotations,
    rig: Rig,
}

/// The first clip of a spec, simulated and annotated.
fn clip(spec_path: &Path, overrides: &[&str]) -> Clip {
    let (_, towns, plan) =
        commands::plan_spec_file(spec_path, &options(overrides)).unwrap_or_else(|e| panic!("{}", e.render()));
    let script = plan.clips[0].clone();
    let net = &towns[&script.town].network;
    let trace = simulate::simulate(&script, &plan.sim, net);
    let rig = Rig::from_spec(&plan.spec.sensors);
    let ann = observe::observe(&script, &trace, &plan.spec, &rig, net).annotations;
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
    fn render(&self, frame: u32) -> CameraImages {
        observe::render_frame(
            &self.script,
            &self.trace,
            &self.rig,
            &self.towns[&self.script.town].network,
            frame,
        )
    }

    /// The frames with the most annotated pedestrians, `n` of them spread over the clip.
    fn busy_frames(&self, n: usize) -> Vec<u32> {
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

#[test]
fn instance_masks_match_the_annotated_boxes_and_keypoints_frame_exactly() {
    let c = clip(&spec("quickstart.yaml"), &[]);
    let (mut rows_checked, mut kp_total, mut kp_on) = (0, 0, 0);
    for frame in c.busy_frames(12) {
        let img = c.render(frame);
        let w = img.width;
        for r in c.ann.rows.iter().filter(|r| r.frame == frame && r.occlusion == 0.0) {
            let id = pedestrian_instance(r.pedestrian);
            let (mut n, mut inside) = (0usize, 0usize);
            let (mut lo, mut hi) = ((f32::MAX, f32::MAX), (f32::MIN, f32::MIN));
            for (i, &v) in img.instance.iter().enumerate() {
                if v != id {
                    continue;
                }
                // The label sample of pixel (x, y) lies at (x + 0.25, y + 0.25).
                let (x, y) = ((i % w) as f32 + 0.25, (i / w) as f32 + 0.25);
                n += 1;
                let b = r.bbox_px;
                if x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3] {
                    inside += 1;
                }
                lo = (lo.0.min(x), lo.1.min(y));
                hi = (hi.0.max(x), hi.1.max(y));
            }
            assert!(
                n > 0,
                "frame {frame}: pedestrian {} annotated but not drawn",
                r.pedestrian
            );
            let share = inside as f64 / n as f64;
            assert!(
                share >= 0.95,
                "frame {frame}, pedestrian {}: {:.3} of its pixels inside its box",
                r.pedestrian,
                share
            );
            // The pixels' box, with half a pixel around the outermost sample points.
            let pix = [lo.0 - 0.5, lo.1 - 0.5, hi.0 + 0.5, hi.1 + 0.5];
            let b = r.bbox_px;
            let iw = (pix[2].min(b[2]) - pix[0].max(b[0])).max(0.0);
            let ih = (pix[3].min(b[3]) - pix[1].max(b[1])).max(0.0);
            let inter = iw * ih;
            let union = (pix[2] - pix[0]) * (pix[3] - pix[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter;
            let iou = inter / union;
            assert!(
                iou >= 0.8,
                "frame {frame}, pedestrian {}: IoU {iou:.3} between its pixels' box {pix:?} and its annotated box {b:?}",
                r.pedestrian
            );
            rows_checked += 1;
            // Visible keypoints land on the pedestrian's pixels (within a pixel).
            for k in 0..17 {
                if r.keypoints[3 * k + 2] != 2.0 {
                    continue;
                }
                let (x, y) = (r.keypoints[3 * k], r.keypoints[3 * k + 1]);
                kp_total += 1;
                let hit = (-1i32..=1).any(|dy| {
                    (-1i32..=1).any(|dx| {
                        let (px, py) = ((x - 0.25).round() as i32 + dx, (y - 0.25).round() as i32 + dy);
                        px >= 0
                            && py >= 0
                            && (px as usize) < w
                            && (py as usize) < img.height
                            && img.instance[py as usize * w + px as usize] == id
                    })
                });
                kp_on += usize::from(hit);
            }
        }
    }
    assert!(
        rows_checked >= 20,
        "only {rows_checked} unoccluded pedestrian-frames checked"
    );
    let share = kp_on as f64 / kp_total as f64;
    assert!(
        share >= 0.97,
        "{kp_on} of {kp_total} visible keypoints on their pedestrian's pixels"
    );
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
            _ => assert_eq!(sem, tag::CAR),
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

/// A static scene of one flat quad (tag and albedo given), for physics tests.
fn one_quad(q: [Vec3; 4], tag_id: u8, normal: Vec3) -> StaticScene {
    let prim = Prim {
        material: Material::Roof,
        tag: tag_id,
        instance: 0,
        albedo: Vec3::splat(0.3),
        albedo2: Vec3::splat(0.3),
        normal,
        aux: 0,
    };
    StaticScene {
        origin: DVec3::ZERO,
        tris: vec![
            Tri {
                v: [q[0], q[1], q[2]],
                prim: 0,
            },
            Tri {
                v: [q[0], q[2], q[3]],
                prim: 0,
            },
        ],
        clusters: vec![Cluster {
            centre: Vec3::ZERO,
            radius_m: 5000.0,
            tris: 0..2,
        }],
        prims: vec![prim],
        pieces: Vec::new(),
        crosswalks: Vec::new(),
        lamps: Vec::new(),
        seed: 1,
    }
}

fn render_static(scene: &StaticScene, camera: &Camera, pos: DVec3, yaw: f64) -> CameraImages {
    let mut frame = FrameScene::default();
    frame.prims.extend_from_slice(&scene.prims);
    let mut r = Renderer::new(camera, Lighting::from_weather(&WeatherPreset::ClearNoon.params()), 1);
    let mut img = CameraImages::default();
    r.render(scene, &frame, &camera.at(pos, yaw), 1, &mut img);
    img
}

#[test]
fn depth_of_known_planes_reads_back_within_a_centimetre() {
    let rgb = Rgb {
        width_px: 320,
        height_px: 180,
        mount: pedsynth::dsl::types::Mount {
            pitch_deg: 0.0,
            ..Default::default()
        },
        ..Rgb::default()
    };
    let camera = Camera::from_spec(&rgb);
    let pose = camera.at(DVec3::ZERO, 0.0);
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
    let pose = camera.at(DVec3::ZERO, 0.3);
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
    let pose = camera.at(DVec3::new(3.0, -2.0, 0.0), 0.4);
    let centre = pose.centre + pose.forward * 15.0 + pose.right * -3.0 + pose.down * 1.0;
    let project = pose.project(centre).px;
    let half = 0.25f32;
    let c = centre.as_vec3();
    let mut tris = Vec::new();
    let mut prims = Vec::new();
    let face = Prim {
        material: Material::Metal,
        tag: tag::POLE,
        instance: 7,
        albedo: Vec3::ONE,
        albedo2: Vec3::ONE,
        normal: Vec3::Z,
        aux: 0,
    };
    // Six faces of the cube, axis-aligned.
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|k| if k == axis { sign } else { 0.0 }));
            let (u, v) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
            let q = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(a, b): (f32, f32)| c + (n + u * a + v * b) * half);
            prims.push(Prim { normal: n, ..face });
            let id = prims.len() as u32 - 1;
            tris.push(Tri {
                v: [q[0], q[1], q[2]],
                prim: id,
            });
            tris.push(Tri {
                v: [q[0], q[2], q[3]],
                prim: id,
            });
        }
    }
    let n = tris.len() as u32;
    let scene = StaticScene {
        origin: DVec3::ZERO,
        tris,
        clusters: vec![Cluster {
            centre: c,
            radius_m: 1.0,
            tris: 0..n,
        }],
        prims,
        pieces: Vec::new(),
        crosswalks: Vec::new(),
        lamps: Vec::new(),
        seed: 1,
    };
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

fn mean_luminance(img: &CameraImages) -> f64 {
    img.rgb.chunks_exact(3).map(|p| f64::from(luminance(p))).sum::<f64>() / (img.width * img.height) as f64
}

/// RMS contrast (standard deviation of luminance) of the pixels whose depth is within `range`.
fn contrast(img: &CameraImages, range: std::ops::Range<f32>) -> f64 {
    let l: Vec<f64> = img
        .rgb
        .chunks_exact(3)
        .zip(&img.depth_m)
        .filter(|(_, d)| range.contains(d))
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
    let mut c = clip(
        &spec("quickstart.yaml"),
        &["sensors.rgb.width_px=640", "sensors.rgb.height_px=360"],
    );
    let frame = c.busy_frames(1)[0];
    let mut render = |p: WeatherPreset, tweak: &dyn Fn(&mut pedsynth::dsl::types::WeatherParams)| {
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
    // All 12 presets differ from each other.
    let means: Vec<(WeatherPreset, f64)> = WeatherPreset::ALL
        .iter()
        .map(|p| (*p, mean_luminance(&render(*p, &|_| {}))))
        .collect();
    for (i, a) in means.iter().enumerate() {
        for b in &means[i + 1..] {
            assert!(
                (a.1 - b.1).abs() > 0.5,
                "{:?} and {:?} look alike: {:.2} vs {:.2}",
                a.0,
                b.0,
                a.1,
                b.1
            );
        }
    }
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
        let bytes = pedsynth::exec::write::sensors::png_bytes(
            img.width,
            img.height,
            png::ColorType::Rgb,
            png::BitDepth::Eight,
            &img.rgb,
            None,
        )
        .expect("png");
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

/// Every file under `dir`, by relative path.
fn all_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).expect("read dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                let rel = path.strip_prefix(root).expect("prefix").to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&path).expect("read"));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn generate(overrides: &[&str], out: &Path, jobs: usize) {
    let args = GenerateArgs {
        out: out.to_path_buf(),
        jobs: Some(jobs),
        only: None,
        quiet: true,
    };
    let (mut o, mut e) = (Vec::new(), Vec::new());
    let code = commands::finish(
        commands::generate(&spec("quickstart.yaml"), &options(overrides), &args, &mut o),
        &mut e,
    );
    assert_eq!(code, 0, "{}", String::from_utf8_lossy(&e));
}

#[test]
fn sensor_files_are_identical_across_jobs_and_resumption_and_indexed() {
    let tmp = std::env::temp_dir().join(format!("pedsynth-camera-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let small = [
        "sensors.rgb.width_px=160",
        "sensors.rgb.height_px=90",
        "dataset.clip_duration_s=[3, 4]",
        "sensors.dvs.substeps=2",
    ];
    let (one, two) = (tmp.join("one"), tmp.join("two"));
    generate(&small, &one, 1);
    generate(&small, &two, 2);
    let a = all_files(&one);
    assert!(a == all_files(&two), "--jobs 1 and --jobs 2 wrote different files");
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
    std::fs::remove_file(one.join(format!("tables/clips/{clip0}.parquet"))).expect("rm");
    std::fs::remove_file(one.join(format!("sensors/rgb/{clip0}/000003.png"))).expect("rm");
    std::fs::write(
        one.join(format!("sensors/depth/{clip0}/.000004.png.tmp-99999")),
        b"half",
    )
    .expect("tmp");
    generate(&small, &one, 2);
    assert!(all_files(&one) == a, "a resumed run differs from an uninterrupted one");
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
    observe::render_cameras(&c.script, &c.trace, &sensors, &c.rig, net, |f| {
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
    let mut esim = pedsynth::exec::observe::camera::dvs::Esim::new(&sensors.dvs, img.width, img.height);
    let mut ev = Vec::new();
    esim.step(&img.rgb, 0, 1, &mut ev);
    esim.step(&img.rgb, 33_333_333, 2, &mut ev);
    assert!(ev.is_empty());
}
