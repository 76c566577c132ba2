//! Cyclists (`traffic.cyclists`): turning them on adds them without shifting any other planned draw; a dataset
//! with cyclists (and traffic lights) is byte-identical for `--jobs 1` and `--jobs 2`; its `cyclists` table has
//! every cyclist in every frame, boxes that hold the rider's visible keypoints, and the events record overtakes
//! with the spec's clearance, cyclists yielding to pedestrians and pedestrians' conflicts with cyclists, with no
//! contact; `pedsynth stats` counts them as the tables do.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use arrow_array::Array;
use pedsynth::dataset::read::{stats, tables};
use pedsynth::dataset::write::Layout;
use pedsynth::spec::LoadOptions;

const SPEC: &str = "specs/pedsynth_pp.yaml";
const CYCLISTS: [&str; 2] = ["traffic.cyclists.per_clip=[2, 4]", "dataset.clips.count=4"];

fn plan(overrides: &[&str]) -> pedsynth::plan::Plan {
    common::plan_spec(SPEC, overrides).1
}

#[test]
fn cyclists_are_added_without_changing_any_other_planned_draw() {
    let with = plan(&CYCLISTS);
    let without = plan(&CYCLISTS[1..]);
    assert!(without.sim.cyclists.is_none() && with.sim.cyclists.is_some());
    assert_eq!(with.clips.len(), without.clips.len());
    let spec = &with.spec.traffic.cyclists;
    let (mut total, mut short, mut ignoring) = (0usize, 0usize, 0usize);
    for (a, b) in with.clips.iter().zip(&without.clips) {
        assert!(b.cyclists.is_empty());
        assert_eq!(a.pedestrians, b.pedestrians, "{}: pedestrians changed", a.clip_id);
        assert_eq!(a.ego, b.ego, "{}: the ego changed", a.clip_id);
        assert_eq!(a.vehicles, b.vehicles, "{}: the traffic changed", a.clip_id);
        assert!(a.cyclists.len() <= 4, "{}: {} cyclists", a.clip_id, a.cyclists.len());
        short += usize::from(a.cyclists.len() < 2);
        total += a.cyclists.len();
        for (k, c) in a.cyclists.iter().enumerate() {
            assert_eq!(c.id as usize, k);
            assert!((spec.speed_mps.min()..=spec.speed_mps.max()).contains(&c.speed_mps));
            assert!(c.route.start.distance(a.ego.route.start) >= 15.0);
            ignoring += usize::from(c.ignores_lights);
        }
    }
    // A cyclist is left out only where no free lane is near the ego: rarely.
    assert!(
        short * 20 <= with.clips.len(),
        "{short} of {} clips short of cyclists",
        with.clips.len()
    );
    assert!(total >= 2 * with.clips.len());
    // 7 % ride through red lights: within 4 standard errors.
    let p = spec.ignore_lights_probability;
    let sd = (p * (1.0 - p) * total as f64).sqrt();
    assert!(
        (ignoring as f64 - p * total as f64).abs() <= 4.0 * sd,
        "{ignoring} of {total} ignore lights"
    );
}

/// A number column of a batch as f64, whatever its Arrow type (f32 or u32).
fn column_f64(b: &tables::Batch, name: &str) -> Vec<Option<f64>> {
    if let Ok(c) = b.f32s(name) {
        return (0..c.len())
            .map(|i| c.is_valid(i).then(|| f64::from(c.value(i))))
            .collect();
    }
    let c = b.u32s(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    (0..c.len())
        .map(|i| c.is_valid(i).then(|| f64::from(c.value(i))))
        .collect()
}

#[test]
#[ignore = "slow (13 s in a debug build: PedSynth++ with cyclists generated with one and two jobs): cargo test -- --include-ignored"]
fn a_dataset_with_cyclists_is_deterministic_and_its_tables_hold_together() {
    let scratch = common::Scratch::new("cyclists");
    let mut overrides: Vec<&str> = common::NO_SENSORS.to_vec();
    overrides.extend([
        "traffic.cyclists.per_clip=[3, 5]",
        "dataset.clips.count=2",
        "traffic.signals.enabled=true",
    ]);
    common::generate_with_jobs_1_and_2(Path::new(SPEC), &overrides, scratch.path());
    let dir = scratch.path().join("one");
    let layout = Layout::new(&dir);
    let plan = plan(&overrides);
    let clearance = plan.spec.traffic.cyclists.overtaking_clearance_m;
    let (width, height) = (
        f64::from(plan.spec.sensors.rgb.width_px),
        f64::from(plan.spec.sensors.rgb.height_px),
    );

    let (mut cyclists, mut in_view, mut checked_keypoints) = (0usize, 0usize, 0usize);
    let mut kinds: BTreeMap<String, usize> = BTreeMap::new();
    for clip in &plan.clips {
        // Every cyclist in every frame, once.
        let mut rows: BTreeSet<(u32, u32)> = BTreeSet::new();
        let cols = [
            "frame",
            "cyclist",
            "class",
            "in_view",
            "annotated",
            "x1",
            "y1",
            "x2",
            "y2",
            "keypoints",
        ];
        for b in tables::read(&layout.table("cyclists", &clip.clip_id), &cols).expect("cyclists") {
            let (frame, id) = (column_f64(&b, "frame"), column_f64(&b, "cyclist"));
            let boxes: Vec<Vec<Option<f64>>> = ["x1", "y1", "x2", "y2"].iter().map(|c| column_f64(&b, c)).collect();
            let (seen, annotated) = (b.bools("in_view").unwrap(), b.bools("annotated").unwrap());
            let (keypoints, kw) = b.f32_lists("keypoints").unwrap();
            assert!(b.strings("class").unwrap().iter().all(|c| *c == "cyclist"));
            for i in 0..b.rows() {
                assert!(rows.insert((frame[i].unwrap() as u32, id[i].unwrap() as u32)));
                assert!(!annotated.value(i) || seen.value(i), "annotated but not in view");
                let bx: Vec<Option<f64>> = boxes.iter().map(|c| c[i]).collect();
                if !seen.value(i) {
                    assert!(bx.iter().all(Option::is_none));
                    continue;
                }
                in_view += 1;
                let [x1, y1, x2, y2] = [bx[0].unwrap(), bx[1].unwrap(), bx[2].unwrap(), bx[3].unwrap()];
                assert!(0.0 <= x1 && x1 < x2 && x2 <= width && 0.0 <= y1 && y1 < y2 && y2 <= height);
                // The rider's visible keypoints lie in the box of rider and bicycle.
                for k in keypoints[i * kw..(i + 1) * kw].chunks_exact(3) {
                    if k[2] == 2.0 {
                        let (u, v) = (f64::from(k[0]), f64::from(k[1]));
                        assert!(
                            u >= x1 - 0.5 && u <= x2 + 0.5 && v >= y1 - 0.5 && v <= y2 + 0.5,
                            "{}: keypoint ({u}, {v}) outside [{x1}, {y1}, {x2}, {y2}]",
                            clip.clip_id
                        );
                        checked_keypoints += 1;
                    }
                }
            }
        }
        assert_eq!(
            rows.len(),
            clip.cyclists.len() * clip.frame_count as usize,
            "{}",
            clip.clip_id
        );
        cyclists += clip.cyclists.len();

        for b in tables::read(
            &layout.table("events", &clip.clip_id),
            &["kind", "cyclist", "min_clearance_m", "swerved", "pedestrian"],
        )
        .expect("events")
        {
            let kind = b.strings("kind").unwrap();
            let (cyc, clear) = (column_f64(&b, "cyclist"), column_f64(&b, "min_clearance_m"));
            for i in 0..b.rows() {
                let by_cyclist = cyc[i].is_some();
                match kind[i] {
                    "overtook_cyclist" => {
                        let c = clear[i].expect("a clearance");
                        assert!(c >= clearance - 1e-3, "{}: overtaken at {c} m", clip.clip_id);
                        *kinds.entry("overtake".into()).or_default() += 1;
                    }
                    "cyclist_yielded" => *kinds.entry("cyclist_yielded".into()).or_default() += 1,
                    "conflict" if by_cyclist => *kinds.entry("pedestrian_conflict".into()).or_default() += 1,
                    "contact" if by_cyclist => panic!("{}: a contact with a cyclist", clip.clip_id),
                    "stopped_at_red_light" if by_cyclist => *kinds.entry("stopped_at_red".into()).or_default() += 1,
                    _ => {}
                }
            }
        }
    }
    // Interactions of every kind happen (measured: see the closing note / BENCHMARKS for the figures).
    for kind in ["overtake", "cyclist_yielded", "pedestrian_conflict", "stopped_at_red"] {
        assert!(kinds.get(kind).copied().unwrap_or(0) > 0, "no {kind}: {kinds:?}");
    }
    assert!(in_view > 0 && checked_keypoints > 0);

    let s = stats::compute(&dir).expect("stats");
    assert_eq!(s.cyclists as usize, cyclists);
    assert_eq!(s.cyclist_frames_in_view as usize, in_view);
    assert_eq!(s.cyclist_overtakes as usize, kinds["overtake"]);
    assert_eq!(
        (s.cyclist_swerves + s.cyclist_brakes_for_pedestrians) as usize,
        kinds["cyclist_yielded"]
    );
    assert_eq!(s.pedestrian_cyclist_conflicts as usize, kinds["pedestrian_conflict"]);
    assert_eq!(s.cyclist_contacts, 0);
    assert!(s.min_overtaking_clearance_m.is_some_and(|c| c >= clearance - 1e-3));
}

/// CARLA's Town01 with every 0.3 m shoulder of a road outside junctions turned into a 1.5 m bike lane
/// (OpenDRIVE lane type `biking`) beside the driving lane: the map's text changed in memory and written to
/// `dir`, never into the repository.
fn town01_with_bike_lanes(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(common::carla_map("Town01")).expect("read Town01");
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(start) = rest.find("<road ") {
        out.push_str(&rest[..start]);
        let end = rest[start..].find("</road>").expect("road closes") + start;
        let road = &rest[start..end];
        if road[..road.find('>').expect("tag")].contains("junction=\"-1\"") {
            let mut r = road;
            while let Some(k) = r.find("type=\"shoulder\"") {
                let close = r[k..].find("</lane>").expect("lane closes") + k;
                out.push_str(&r[..k]);
                out.push_str(
                    &r[k..close]
                        .replacen("type=\"shoulder\"", "type=\"biking\"", 1)
                        .replace("a=\"2.9999999999999982e-1\"", "a=\"1.5\""),
                );
                r = &r[close..];
            }
            out.push_str(r);
        } else {
            out.push_str(road);
        }
        rest = &rest[end..];
    }
    out.push_str(rest);
    let path = dir.join("bike_town.xodr");
    std::fs::write(&path, out).expect("write the map");
    path
}

/// The traces of a small dataset with four cyclists per clip on `town` (an OpenDRIVE file in `dir`).
fn bike_traces(dir: &Path, town: &str) -> (pedsynth::world::RoadNetwork, Vec<pedsynth::sim::trace::ClipTrace>) {
    let spec = dir.join(format!("{town}.yaml"));
    std::fs::write(
        &spec,
        format!(
            "version: 1\ndataset:\n  name: bike_lanes\n  seed: 5\n  towns: [{{name: {town}, opendrive: {town}.xodr}}]\n  \
             weathers: [clear_noon]\n  clips: {{count: 8, per: weather}}\n  clip_duration_s: [15, 15]\n\
             traffic:\n  cyclists: {{per_clip: [4, 4]}}\n"
        ),
    )
    .expect("write the spec");
    let options = LoadOptions {
        overrides: common::NO_SENSORS.iter().map(|s| (*s).to_owned()).collect(),
        allow_large: false,
        profile: None,
    };
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(&spec, &options).unwrap_or_else(|e| panic!("{e}"));
    let net = towns.values().next().expect("one town").network.clone();
    let traces = plan
        .clips
        .iter()
        .map(|clip| pedsynth::sim::simulate(clip, &plan.sim, &net))
        .collect();
    (net, traces)
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn cyclists_ride_in_the_bike_lanes_of_a_map_that_has_them() {
    let scratch = common::Scratch::new("bike-lanes");
    let map = town01_with_bike_lanes(scratch.path());
    let summary = pedsynth::world::RoadNetwork::load(map.to_str().expect("utf-8 path"))
        .expect("the map loads")
        .summary();
    assert!(summary.bike_lane_km > 1.0, "{summary:?}");
    std::fs::copy(common::carla_map("Town01"), scratch.path().join("plain_town.xodr")).expect("copy");

    let (net, traces) = bike_traces(scratch.path(), "bike_town");
    let (mut frames, mut in_lane, mut settled, mut settled_on_bike_lane) = (0usize, 0usize, 0usize, 0usize);
    let mut passes_in_lane = 0usize;
    for trace in &traces {
        for cyclist in &trace.cyclists {
            for (f, c) in cyclist.iter().enumerate() {
                frames += 1;
                in_lane += usize::from(c.in_bike_lane);
                // A cyclist moves over 0.3 m per metre ridden: two seconds after it entered the bike lane it rides
                // on it.
                if f >= 60 && cyclist[f - 60..=f].iter().all(|x| x.in_bike_lane) {
                    settled += 1;
                    let hit = net.lane_at(c.pos.truncate());
                    settled_on_bike_lane +=
                        usize::from(hit.is_some_and(|h| h.lane_type == pedsynth::world::LaneType::Biking));
                }
            }
        }
        for e in &trace.events {
            if let pedsynth::sim::trace::Event::OvertookCyclist { frame, cyclist, .. } = e {
                passes_in_lane += usize::from(trace.cyclists[*cyclist as usize][*frame as usize].in_bike_lane);
            }
            assert!(
                !matches!(
                    e,
                    pedsynth::sim::trace::Event::Contact {
                        vehicle: pedsynth::sim::trace::VehicleId::Cyclist(_),
                        ..
                    }
                ),
                "{}: {e:?}",
                trace.clip_id
            );
        }
    }
    eprintln!(
        "bike lanes: {in_lane} of {frames} cyclist frames in a bike lane; {settled_on_bike_lane} of {settled} settled \
         ones on a biking lane; {passes_in_lane} overtakes of a cyclist in a bike lane"
    );
    assert!(
        frames > 0 && in_lane * 2 > frames,
        "{in_lane} of {frames} cyclist frames in a bike lane"
    );
    assert!(
        settled > 0 && settled_on_bike_lane * 100 >= settled * 99,
        "{settled_on_bike_lane} of {settled} settled frames on a biking lane"
    );
    // Vehicles pass a cyclist in its own lane without moving out.
    assert_eq!(
        passes_in_lane, 0,
        "vehicles moved out to overtake cyclists in bike lanes"
    );

    // The same map without bike lanes: cyclists ride by the edge of the driving lane.
    let (_, plain) = bike_traces(scratch.path(), "plain_town");
    assert!(
        plain
            .iter()
            .flat_map(|t| &t.cyclists)
            .flatten()
            .all(|c| !c.in_bike_lane)
    );
    let overtakes = |traces: &[pedsynth::sim::trace::ClipTrace]| {
        traces
            .iter()
            .flat_map(|t| &t.events)
            .filter(|e| matches!(e, pedsynth::sim::trace::Event::OvertookCyclist { .. }))
            .count()
    };
    let (with, without) = (overtakes(&traces), overtakes(&plain));
    eprintln!("overtakes with bike lanes {with}, without {without}");
    // Without bike lanes vehicles do move out for these cyclists, so the zero above is not for want of traffic.
    assert!(
        without > 0 && with < without,
        "overtakes with bike lanes {with}, without {without}"
    );
}
