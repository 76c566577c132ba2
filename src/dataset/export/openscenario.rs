//! `pedsynth export openscenario`: one ASAM OpenSCENARIO 1.2 file per clip (`<clip_id>.xosc`) that replays the
//! clip in esmini, CARLA's scenario_runner or any OpenSCENARIO player, with the towns beside them as OpenDRIVE
//! (`towns/<town>.xodr`: built-in towns exported by `town export`'s writer, imported towns copied).
//!
//! A file holds: the road network (a relative `LogicFile` path); the ego, every traffic vehicle, every cyclist
//! and every pedestrian as entities with their dimensions (vehicles 4.6 × 1.9 × 1.5 m, cyclists as vehicles of
//! category `bicycle` 1.75 × 0.65 × 1.7 m, pedestrians 0.6 m wide and their body height tall, mass from height
//! at BMI 22), and every parked car (`parked_cars`) as a vehicle of its row's size with the property
//! `parked`; in `Init`, the weather as an `EnvironmentAction` and each entity teleported to its first pose (a
//! parked car to its place, where it stays: it has no trajectory); in one act, each moving entity's whole trace (`frames` for the ego, `vehicles`, `cyclists`, `tracks` for pedestrians)
//! as a `FollowTrajectoryAction` with a timed polyline in absolute time.
//! Polylines keep only the vertices needed to reproduce every frame within 2 cm and 0.02 rad by linear
//! interpolation (a pedestrian who waits is two vertices, not one per frame); headings are unwrapped so that
//! interpolation never turns the long way round.
//!
//! Weather mapping (DATASET.md "Exports"): sun elevation = altitude; sun azimuth = 90° − our azimuth (ours is
//! counter-clockwise from east, OpenSCENARIO's clockwise from north); fog visual range = 3.912 / σ with the
//! renderer's extinction σ = 0.0002 + 0.05·(fog/100)² per metre; precipitation rain at 0.5 mm/h per percent
//! (100 % = 50 mm/h), dry at 0; cloud cover in oktas = round(cloudiness/100 × 8); road friction 1 − 0.3·wetness.
//! No date from the clock: the header's date is fixed (1970-01-01T00:00:00), so files are reproducible.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::dataset::{Clip, Dataset};
use super::{progress, write_file};
use crate::error::{Error, code};
use crate::sim::{
    BICYCLE_HEIGHT_M, BICYCLE_LENGTH_M, BICYCLE_WIDTH_M, VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M,
};
use crate::spec::types::TownRef;
use crate::util::xml::escape;

/// Largest position error of a simplified polyline at any frame, metres.
pub const TOLERANCE_M: f64 = 0.02;
/// Largest heading error of a simplified polyline at any frame, radians.
pub const TOLERANCE_RAD: f64 = 0.02;
/// Pedestrians' bounding-box width and length, metres.
const PEDESTRIAN_WIDTH_M: f64 = 0.6;

/// What an export wrote.
pub struct Summary {
    pub scenarios: usize,
    pub towns: usize,
    pub entities: usize,
    /// Of the entities, parked cars (no trajectory).
    pub parked: usize,
    pub vertices: usize,
    pub frames: usize,
}

/// One pose of an entity's trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub t_s: f64,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub h_rad: f64,
    /// Pitch, nose up positive: the ego's body pitch (`frames.ego_pitch_rad`), 0 for everyone else.
    pub p_rad: f64,
}

/// Writes `towns/*.xodr` and one `.xosc` per clip under `out`.
pub fn export(ds: &Dataset, out: &Path) -> Result<Summary, Error> {
    let mut summary = Summary {
        scenarios: 0,
        towns: 0,
        entities: 0,
        parked: 0,
        vertices: 0,
        frames: 0,
    };
    for town in &ds.spec.dataset.towns {
        let path = out.join("towns").join(format!("{}.xodr", town.name()));
        let bytes = match town {
            TownRef::Builtin(t) => crate::world::opendrive::write::builtin_to_xodr(t.name())?
                .ok_or_else(|| Error::new(code::DATASET_INVALID, format!("unknown built-in town {}", t.name())))?
                .into_bytes(),
            TownRef::OpenDrive(t) => {
                let from = ds.layout.root().join(&t.opendrive);
                std::fs::read(&from).map_err(|e| {
                    Error::new(
                        code::DATASET_INVALID,
                        format!(
                            "{}: {e}: the scenarios need the town's OpenDRIVE file (the spec names it relative to the dataset)",
                            from.display()
                        ),
                    )
                })?
            }
        };
        write_file(&path, &bytes)?;
        summary.towns += 1;
    }
    let bar = progress(ds.clips.len());
    for info in &ds.clips {
        let clip = ds.load(info)?;
        let (xml, entities, vertices) = scenario(&clip);
        write_file(&out.join(format!("{}.xosc", clip.clip_id)), xml.as_bytes())?;
        let moving = entities - clip.parked_cars.len();
        summary.scenarios += 1;
        summary.entities += entities;
        summary.parked += clip.parked_cars.len();
        summary.vertices += vertices;
        summary.frames += moving * clip.frame_count as usize;
        bar.clip_done(&clip.clip_id, u64::from(clip.frame_count));
    }
    bar.finish();
    Ok(summary)
}

/// Keeps the vertices needed to reproduce every pose of `poses` within the tolerances by linear interpolation
/// in time (first and last always kept). Headings must be unwrapped.
pub fn simplify(poses: &[Pose]) -> Vec<Pose> {
    let n = poses.len();
    if n <= 2 {
        return poses.to_vec();
    }
    let fits = |i: usize, j: usize| {
        let (a, b) = (&poses[i], &poses[j]);
        let span = b.t_s - a.t_s;
        poses[i + 1..j].iter().all(|p| {
            let w = if span > 0.0 { (p.t_s - a.t_s) / span } else { 0.0 };
            let lerp = |u: f64, v: f64| u + (v - u) * w;
            let (dx, dy, dz) = (
                lerp(a.x_m, b.x_m) - p.x_m,
                lerp(a.y_m, b.y_m) - p.y_m,
                lerp(a.z_m, b.z_m) - p.z_m,
            );
            (dx * dx + dy * dy + dz * dz).sqrt() <= TOLERANCE_M
                && (lerp(a.h_rad, b.h_rad) - p.h_rad).abs() <= TOLERANCE_RAD
                && (lerp(a.p_rad, b.p_rad) - p.p_rad).abs() <= TOLERANCE_RAD
        })
    };
    let mut out = vec![poses[0]];
    let mut i = 0;
    while i < n - 1 {
        let mut j = i + 1;
        while j + 1 < n && fits(i, j + 1) {
            j += 1;
        }
        out.push(poses[j]);
        i = j;
    }
    out
}

/// Headings made continuous (no jump larger than π between consecutive poses).
fn unwrap(poses: &mut [Pose]) {
    for k in 1..poses.len() {
        let prev = poses[k - 1].h_rad;
        let mut h = poses[k].h_rad;
        while h - prev > std::f64::consts::PI {
            h -= std::f64::consts::TAU;
        }
        while h - prev < -std::f64::consts::PI {
            h += std::f64::consts::TAU;
        }
        poses[k].h_rad = h;
    }
}

struct Entity {
    name: String,
    kind: Kind,
    poses: Vec<Pose>,
}

enum Kind {
    Car,
    Pedestrian {
        height_m: f64,
    },
    Bicycle,
    /// A parked car: one pose, no trajectory; length, width and height in metres.
    Parked {
        size_m: [f64; 3],
    },
}

/// The entities of a clip with their traces (headings unwrapped), in a fixed order: ego, vehicles by id,
/// cyclists by id, pedestrians by id, parked cars by id (one pose each).
fn collect(clip: &Clip) -> Vec<Entity> {
    let fps = f64::from(clip.fps.max(1));
    let mut out = Vec::new();
    let ego = clip
        .ego
        .iter()
        .enumerate()
        .map(|(f, e)| Pose {
            t_s: f as f64 / fps,
            x_m: e.x_m,
            y_m: e.y_m,
            z_m: e.z_m,
            h_rad: e.yaw_rad,
            p_rad: e.pitch_rad,
        })
        .collect();
    out.push(Entity {
        name: "ego".into(),
        kind: Kind::Car,
        poses: ego,
    });
    let mut vehicles: BTreeMap<u32, Vec<Pose>> = BTreeMap::new();
    for v in &clip.vehicles {
        vehicles.entry(v.vehicle).or_default().push(Pose {
            t_s: f64::from(v.frame) / fps,
            x_m: v.x_m,
            y_m: v.y_m,
            z_m: v.z_m,
            h_rad: v.yaw_rad,
            p_rad: 0.0,
        });
    }
    for (id, poses) in vehicles {
        out.push(Entity {
            name: format!("vehicle_{id}"),
            kind: Kind::Car,
            poses,
        });
    }
    for track in clip.cyclists.chunk_by(|a, b| a.cyclist == b.cyclist) {
        out.push(Entity {
            name: format!("cyclist_{}", track[0].cyclist),
            kind: Kind::Bicycle,
            poses: track
                .iter()
                .map(|c| Pose {
                    t_s: f64::from(c.frame) / fps,
                    x_m: c.x_m,
                    y_m: c.y_m,
                    z_m: c.z_m,
                    h_rad: c.yaw_rad,
                    p_rad: 0.0,
                })
                .collect(),
        });
    }
    for (id, track) in &clip.tracks {
        let height_m = clip.pedestrians.get(id).map_or(1.75, |p| f64::from(p.height_m));
        out.push(Entity {
            name: format!("pedestrian_{id}"),
            kind: Kind::Pedestrian { height_m },
            poses: track
                .iter()
                .map(|f| Pose {
                    t_s: f64::from(f.frame) / fps,
                    x_m: f.x_m,
                    y_m: f.y_m,
                    z_m: f.z_m,
                    h_rad: f.yaw_rad,
                    p_rad: 0.0,
                })
                .collect(),
        });
    }
    for car in &clip.parked_cars {
        out.push(Entity {
            name: format!("parked_car_{}", car.parked_car),
            kind: Kind::Parked { size_m: car.size_m },
            poses: vec![Pose {
                t_s: 0.0,
                x_m: car.x_m,
                y_m: car.y_m,
                z_m: car.z_m,
                h_rad: car.yaw_rad,
                p_rad: 0.0,
            }],
        });
    }
    out.retain(|e| !e.poses.is_empty());
    for e in &mut out {
        unwrap(&mut e.poses);
    }
    out
}

/// A `Vehicle` of category car: length, width and height in metres, its `Properties` element as given.
fn car(x: &mut String, name: &str, [length_m, width_m, height_m]: [f64; 3], properties: &str) {
    let _ = write!(
        x,
        "<Vehicle name=\"{name}\" vehicleCategory=\"car\" mass=\"1500\">\n<BoundingBox><Center x=\"0\" y=\"0\" z=\"{}\"/><Dimensions width=\"{width_m}\" length=\"{length_m}\" height=\"{height_m}\"/></BoundingBox>\n<Performance maxSpeed=\"50\" maxAcceleration=\"10\" maxDeceleration=\"10\"/>\n<Axles>\n<FrontAxle maxSteering=\"0.6\" wheelDiameter=\"0.65\" trackWidth=\"1.6\" positionX=\"1.4\" positionZ=\"0.325\"/>\n<RearAxle maxSteering=\"0\" wheelDiameter=\"0.65\" trackWidth=\"1.6\" positionX=\"-1.4\" positionZ=\"0.325\"/>\n</Axles>\n{properties}\n</Vehicle>\n",
        0.5 * height_m
    );
}

fn world_position(x: &mut String, p: &Pose) {
    let _ = write!(
        x,
        "<Position><WorldPosition x=\"{:.3}\" y=\"{:.3}\" z=\"{:.3}\" h=\"{:.4}\" p=\"",
        p.x_m, p.y_m, p.z_m, p.h_rad
    );
    // OpenSCENARIO's pitch is about the left-pointing y axis, positive nose down (ISO 8855): the negative of
    // ours. "0" when level, as before the pitch wobble.
    if p.p_rad == 0.0 {
        x.push('0');
    } else {
        let _ = write!(x, "{:.4}", -p.p_rad);
    }
    x.push_str("\" r=\"0\"/></Position>");
}

fn start_trigger(x: &mut String, tag: &str, name: &str, time_s: f64, rule: &str, edge: &str) {
    let _ = write!(
        x,
        "<{tag}>\n<ConditionGroup>\n<Condition name=\"{name}\" delay=\"0\" conditionEdge=\"{edge}\">\n<ByValueCondition>\n<SimulationTimeCondition value=\"{time_s}\" rule=\"{rule}\"/>\n</ByValueCondition>\n</Condition>\n</ConditionGroup>\n</{tag}>\n"
    );
}

/// The OpenSCENARIO document of a clip, with the number of entities and of polyline vertices.
pub fn scenario(clip: &Clip) -> (String, usize, usize) {
    let entities = collect(clip);
    let duration_s = f64::from(clip.frame_count.saturating_sub(1)) / f64::from(clip.fps.max(1));
    let mut x = String::with_capacity(256 << 10);
    let _ = write!(
        x,
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<OpenSCENARIO>\n<FileHeader revMajor=\"1\" revMinor=\"2\" date=\"1970-01-01T00:00:00\" description=\"pedsynth clip {} ({}, {}, {} split): replay of its traces\" author=\"pedsynth\"/>\n<ParameterDeclarations/>\n<CatalogLocations/>\n<RoadNetwork>\n<LogicFile filepath=\"towns/{}.xodr\"/>\n</RoadNetwork>\n<Entities>\n",
        escape(&clip.clip_id),
        escape(&clip.town),
        escape(&clip.weather),
        escape(&clip.split),
        escape(&clip.town)
    );
    for e in &entities {
        let _ = writeln!(x, "<ScenarioObject name=\"{}\">", e.name);
        match e.kind {
            Kind::Car => car(
                &mut x,
                &e.name,
                [VEHICLE_LENGTH_M, VEHICLE_WIDTH_M, VEHICLE_HEIGHT_M],
                "<Properties/>",
            ),
            Kind::Bicycle => {
                let _ = write!(
                    x,
                    "<Vehicle name=\"{}\" vehicleCategory=\"bicycle\" mass=\"90\">\n<BoundingBox><Center x=\"0\" y=\"0\" z=\"{}\"/><Dimensions width=\"{BICYCLE_WIDTH_M}\" length=\"{BICYCLE_LENGTH_M}\" height=\"{BICYCLE_HEIGHT_M}\"/></BoundingBox>\n<Performance maxSpeed=\"15\" maxAcceleration=\"3\" maxDeceleration=\"8\"/>\n<Axles>\n<FrontAxle maxSteering=\"0.8\" wheelDiameter=\"0.68\" trackWidth=\"0\" positionX=\"0.525\" positionZ=\"0.34\"/>\n<RearAxle maxSteering=\"0\" wheelDiameter=\"0.68\" trackWidth=\"0\" positionX=\"-0.525\" positionZ=\"0.34\"/>\n</Axles>\n<Properties/>\n</Vehicle>\n",
                    e.name,
                    0.5 * BICYCLE_HEIGHT_M
                );
            }
            Kind::Parked { size_m } => car(
                &mut x,
                &e.name,
                size_m,
                "<Properties>\n<Property name=\"parked\" value=\"true\"/>\n</Properties>",
            ),
            Kind::Pedestrian { height_m } => {
                let _ = write!(
                    x,
                    "<Pedestrian name=\"{}\" mass=\"{:.1}\" pedestrianCategory=\"pedestrian\">\n<BoundingBox><Center x=\"0\" y=\"0\" z=\"{:.3}\"/><Dimensions width=\"{PEDESTRIAN_WIDTH_M}\" length=\"{PEDESTRIAN_WIDTH_M}\" height=\"{:.3}\"/></BoundingBox>\n<Properties/>\n</Pedestrian>\n",
                    e.name,
                    22.0 * height_m * height_m,
                    0.5 * height_m,
                    height_m
                );
            }
        }
        x.push_str("</ScenarioObject>\n");
    }
    x.push_str("</Entities>\n<Storyboard>\n<Init>\n<Actions>\n");
    environment(&mut x, clip);
    for e in &entities {
        let _ = write!(
            x,
            "<Private entityRef=\"{}\">\n<PrivateAction>\n<TeleportAction>",
            e.name
        );
        world_position(&mut x, &e.poses[0]);
        x.push_str("</TeleportAction>\n</PrivateAction>\n</Private>\n");
    }
    x.push_str("</Actions>\n</Init>\n<Story name=\"replay\">\n<Act name=\"replay\">\n");
    let mut vertices = 0;
    for e in entities.iter().filter(|e| !matches!(e.kind, Kind::Parked { .. })) {
        let kept = simplify(&e.poses);
        vertices += kept.len();
        let n = &e.name;
        let _ = write!(
            x,
            "<ManeuverGroup name=\"{n}\" maximumExecutionCount=\"1\">\n<Actors selectTriggeringEntities=\"false\">\n<EntityRef entityRef=\"{n}\"/>\n</Actors>\n<Maneuver name=\"{n}\">\n<Event name=\"{n}\" priority=\"override\" maximumExecutionCount=\"1\">\n<Action name=\"{n}\">\n<PrivateAction>\n<RoutingAction>\n<FollowTrajectoryAction>\n<TrajectoryRef>\n<Trajectory name=\"{n}\" closed=\"false\">\n<Shape>\n<Polyline>\n"
        );
        for p in &kept {
            let _ = write!(x, "<Vertex time=\"{:.4}\">", p.t_s);
            world_position(&mut x, p);
            x.push_str("</Vertex>\n");
        }
        x.push_str("</Polyline>\n</Shape>\n</Trajectory>\n</TrajectoryRef>\n<TimeReference>\n<Timing domainAbsoluteRelative=\"absolute\" scale=\"1\" offset=\"0\"/>\n</TimeReference>\n<TrajectoryFollowingMode followingMode=\"position\"/>\n</FollowTrajectoryAction>\n</RoutingAction>\n</PrivateAction>\n</Action>\n");
        start_trigger(&mut x, "StartTrigger", "start", 0.0, "greaterOrEqual", "none");
        x.push_str("</Event>\n</Maneuver>\n</ManeuverGroup>\n");
    }
    start_trigger(&mut x, "StartTrigger", "act_start", 0.0, "greaterOrEqual", "none");
    x.push_str("</Act>\n</Story>\n");
    start_trigger(
        &mut x,
        "StopTrigger",
        "end_of_clip",
        duration_s,
        "greaterThan",
        "rising",
    );
    x.push_str("</Storyboard>\n</OpenSCENARIO>\n");
    (x, entities.len(), vertices)
}

/// Fog extinction of the renderer (src/sensors/camera/light.rs), 1/m.
fn fog_per_m(fog_density_pct: f64) -> f64 {
    let f = (fog_density_pct / 100.0).clamp(0.0, 1.0);
    0.0002 + 0.05 * f * f
}

fn environment(x: &mut String, c: &Clip) {
    let azimuth_deg = (90.0 - c.sun_azimuth_deg).rem_euclid(360.0);
    let oktas = ((c.cloudiness_pct / 100.0).clamp(0.0, 1.0) * 8.0).round() as u32;
    let oktas = ["zero", "one", "two", "three", "four", "five", "six", "seven", "eight"][oktas as usize];
    let rain_mm_h = 0.5 * c.precipitation_pct.clamp(0.0, 100.0);
    let kind = if rain_mm_h > 0.0 { "rain" } else { "dry" };
    let hour = if c.sun_altitude_deg >= 0.0 { 12 } else { 0 };
    let _ = write!(
        x,
        "<GlobalAction>\n<EnvironmentAction>\n<Environment name=\"{}\">\n<TimeOfDay animation=\"false\" dateTime=\"1970-06-21T{hour:02}:00:00\"/>\n<Weather fractionalCloudCover=\"{oktas}Oktas\">\n<Sun azimuth=\"{:.4}\" elevation=\"{:.4}\" illuminance=\"{:.0}\"/>\n<Fog visualRange=\"{:.1}\"/>\n<Precipitation precipitationType=\"{kind}\" precipitationIntensity=\"{rain_mm_h}\"/>\n<Wind direction=\"0\" speed=\"{:.2}\"/>\n</Weather>\n<RoadCondition frictionScaleFactor=\"{:.3}\"/>\n</Environment>\n</EnvironmentAction>\n</GlobalAction>\n",
        escape(&c.weather),
        azimuth_deg.to_radians(),
        c.sun_altitude_deg.to_radians(),
        if c.sun_altitude_deg > 0.0 {
            100_000.0 * c.sun_altitude_deg.to_radians().sin() * (1.0 - 0.75 * c.cloudiness_pct / 100.0)
        } else {
            0.0
        },
        3.912 / fog_per_m(c.fog_density_pct),
        0.1 * c.wind_intensity_pct.clamp(0.0, 100.0),
        1.0 - 0.3 * (c.wetness_pct / 100.0).clamp(0.0, 1.0)
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(t: f64, x: f64, h: f64) -> Pose {
        Pose {
            t_s: t,
            x_m: x,
            y_m: 0.0,
            z_m: 0.0,
            h_rad: h,
            p_rad: 0.0,
        }
    }

    #[test]
    fn simplify_keeps_ends_and_corners_and_drops_straight_runs() {
        let mut poses: Vec<Pose> = (0..100).map(|k| pose(k as f64 * 0.1, k as f64 * 0.1, 0.0)).collect();
        assert_eq!(simplify(&poses).len(), 2, "a uniform straight walk is two vertices");
        // Stop for a second at k = 50: the corner vertices appear.
        for (k, p) in poses.iter_mut().enumerate().skip(50) {
            p.x_m = 5.0 + (k as f64 - 50.0).max(0.0) * 0.0;
        }
        let kept = simplify(&poses);
        assert!(
            kept.len() >= 3 && kept.iter().any(|p| (p.t_s - 5.0).abs() < 0.15),
            "{kept:?}"
        );
        assert_eq!(kept.first(), poses.first());
        assert_eq!(kept.last(), poses.last());
    }

    #[test]
    fn a_nodding_ego_keeps_the_vertices_of_its_pitch_and_writes_it_nose_down_positive() {
        // Straight and level except a nod of 0.05 rad in the middle: the straight run would collapse to its ends.
        let mut poses: Vec<Pose> = (0..5).map(|i| pose(f64::from(i), f64::from(i), 0.0)).collect();
        assert_eq!(simplify(&poses).len(), 2);
        poses[2].p_rad = 0.05;
        let kept = simplify(&poses);
        assert!(kept.iter().any(|p| p.p_rad == 0.05), "{} vertices", kept.len());
        let mut x = String::new();
        world_position(&mut x, &poses[2]);
        assert!(x.contains("p=\"-0.0500\""), "{x}");
        x.clear();
        world_position(&mut x, &poses[0]);
        assert!(x.contains("p=\"0\" r=\"0\""), "level: {x}");
    }

    #[test]
    fn unwrap_makes_headings_continuous() {
        let mut poses = vec![pose(0.0, 0.0, 3.1), pose(0.1, 0.0, -3.1), pose(0.2, 0.0, -3.0)];
        unwrap(&mut poses);
        assert!((poses[1].h_rad - (-3.1 + std::f64::consts::TAU)).abs() < 1e-12);
        assert!((poses[2].h_rad - (-3.0 + std::f64::consts::TAU)).abs() < 1e-12);
    }
}
