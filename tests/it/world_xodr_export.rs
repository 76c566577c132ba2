//! `pedsynth town export NAME --xodr FILE`: every built-in town written as OpenDRIVE reads back through our
//! importer to the same network — lane counts per type, lane lengths (the issue asks for 1 %; the file keeps
//! the generator's numbers, so they agree to the micrometre), the lane graph, crosswalks, junctions and
//! buildings — and the export is byte-for-byte reproducible. ASAM's checker runs on the same files in CI
//! (`tests/asam_qc.py`, called by `.ci/run`).

use crate::common;

use std::collections::BTreeMap;
use std::process::Command;

use pedsynth::world::opendrive::write::builtin_to_xodr;
use pedsynth::world::{BUILTIN_TOWN_NAMES, LaneType, RoadNetwork};

fn lane_totals(net: &RoadNetwork) -> BTreeMap<String, (usize, f64)> {
    let mut out: BTreeMap<String, (usize, f64)> = BTreeMap::new();
    for l in &net.lanes {
        let e = out.entry(format!("{:?}", l.lane_type)).or_default();
        e.0 += 1;
        e.1 += l.length_m;
    }
    out
}

fn round_trip(name: &str) {
    let xml = builtin_to_xodr(name).expect("export").expect("a built-in town");
    assert_eq!(
        xml,
        builtin_to_xodr(name).unwrap().unwrap(),
        "{name}: two exports differ"
    );
    let original = RoadNetwork::builtin(name).unwrap();
    let back = RoadNetwork::from_xodr_str(&xml, &format!("{name}.xodr")).expect("our importer reads the export");

    let (a, b) = (lane_totals(&original), lane_totals(&back));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{name}: lane types"
    );
    for (kind, &(count, length_m)) in &a {
        let (count_back, length_back) = b[kind];
        assert_eq!(count, count_back, "{name}: number of {kind} lanes");
        assert!(
            (length_m - length_back).abs() <= 1e-6 * length_m.max(1.0),
            "{name}: {kind} lanes total {length_m} m, read back {length_back} m"
        );
    }
    assert!(
        a.contains_key(&format!("{:?}", LaneType::Driving)) && a.contains_key(&format!("{:?}", LaneType::Sidewalk))
    );

    // The same lane geometry and the same lane graph, lane for lane.
    assert_eq!(original.pieces.len(), back.pieces.len(), "{name}: lane pieces");
    for (p, q) in original.pieces.iter().zip(&back.pieces) {
        for (c, d) in p.corners.iter().zip(&q.corners) {
            assert!(c.distance(*d) < 1e-9, "{name}: lane piece corner {c} read back as {d}");
        }
        assert_eq!(p.lane, q.lane);
    }
    for lane in 0..original.lanes.len() as u32 {
        assert_eq!(
            original.lane_successors(lane),
            back.lane_successors(lane),
            "{name}: successors of lane {lane}"
        );
    }
    assert_eq!(
        original.sidewalk_graph(),
        back.sidewalk_graph(),
        "{name}: sidewalk graph"
    );

    // Junctions with their connections, now with correct lane links, and connecting roads linked both ways.
    assert_eq!(original.junctions.len(), back.junctions.len(), "{name}: junctions");
    for (j, k) in original.junctions.iter().zip(&back.junctions) {
        assert_eq!(j.id, k.id);
        assert_eq!(j.connections, k.connections, "{name}: connections of junction {}", j.id);
        assert!(j.centre.distance(k.centre) < 1e-9);
    }
    for road in back.roads.iter().filter(|r| r.junction.is_some()) {
        let driving = back.lanes[road.lanes.start as usize..road.lanes.end as usize]
            .iter()
            .any(|l| l.lane_type == LaneType::Driving);
        if driving {
            let (p, s) = (road.predecessor.as_ref(), road.successor.as_ref());
            assert!(
                p.is_some_and(|l| l.element_type == "road") && s.is_some_and(|l| l.element_type == "road"),
                "{name}: connecting road {} is not linked to its incoming and outgoing roads",
                road.id
            );
        }
    }

    // Crosswalks come back from the file's objects (no longer synthesised), at the same place.
    assert_eq!(original.crosswalks.len(), back.crosswalks.len(), "{name}: crosswalks");
    for (c, d) in original.crosswalks.iter().zip(&back.crosswalks) {
        assert!(c.synthesized && !d.synthesized);
        assert_eq!(c.road, d.road);
        assert_eq!(c.polygon.len(), d.polygon.len());
        for (p, q) in c.polygon.iter().zip(&d.polygon) {
            assert!(p.distance(*q) < 1e-9, "{name}: crosswalk corner {p} read back as {q}");
        }
    }
    // Traffic lights come back from the file's signals and controllers: same ids, junctions, approaches and
    // phases, at the same place, facing the same way.
    assert_eq!(original.signals.len(), back.signals.len(), "{name}: traffic lights");
    for (g, h) in original.signals.iter().zip(&back.signals) {
        assert!(g.synthesized && !h.synthesized);
        assert_eq!(
            (&g.id, g.junction, g.road, g.at_road_end, g.phase),
            (&h.id, h.junction, h.road, h.at_road_end, h.phase),
            "{name}: traffic light {}",
            g.id
        );
        assert!(
            g.position.distance(h.position) < 1e-3,
            "{name}: traffic light {} at {} read back at {}",
            g.id,
            g.position,
            h.position
        );
        assert!(
            (g.facing_rad - h.facing_rad).abs() < 1e-9,
            "{name}: traffic light {} facing",
            g.id
        );
    }
    // Buildings come back from the file's objects instead of being synthesised (grouped by the road they are
    // written on, so compared in a canonical order).
    assert_eq!(original.obstacles.len(), back.obstacles.len(), "{name}: buildings");
    let sorted = |net: &RoadNetwork| {
        let mut v = net.obstacles.clone();
        v.sort_by(|a, b| {
            (a.centre.x.round(), a.centre.y.round())
                .partial_cmp(&(b.centre.x.round(), b.centre.y.round()))
                .unwrap()
        });
        v
    };
    for (o, p) in sorted(&original).iter().zip(&sorted(&back)) {
        assert_eq!(o.kind, p.kind);
        assert!(
            o.centre.distance(p.centre) < 1e-6,
            "{name}: building at {} read back at {}",
            o.centre,
            p.centre
        );
        assert!((o.half_extents_m - p.half_extents_m).abs().max_element() < 1e-6);
        assert!((o.height_m - p.height_m).abs() < 1e-9 && (o.base_z_m - p.base_z_m).abs() < 1e-9);
        let turn = (o.heading_rad - p.heading_rad).rem_euclid(std::f64::consts::PI);
        assert!(turn.min(std::f64::consts::PI - turn) < 1e-9, "{name}: building heading");
    }
    assert_eq!(
        serde_json::to_value(original.summary()).unwrap()["bounds_m"],
        serde_json::to_value(back.summary()).unwrap()["bounds_m"]
    );
}

#[test]
fn every_builtin_town_round_trips_through_opendrive() {
    for name in BUILTIN_TOWN_NAMES {
        round_trip(name);
    }
}

#[test]
fn the_export_carries_marks_heights_and_no_machine_specific_text() {
    let xml = builtin_to_xodr("town03_like").unwrap().unwrap();
    let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let header = doc.descendants().find(|n| n.has_tag_name("header")).unwrap();
    assert_eq!(
        (header.attribute("revMajor"), header.attribute("revMinor")),
        (Some("1"), Some("7"))
    );
    assert!(header.attribute("date").is_none(), "no wall-clock time in the file");
    let marks = |kind: &str, colour: &str| {
        doc.descendants()
            .filter(|n| {
                n.has_tag_name("roadMark") && n.attribute("type") == Some(kind) && n.attribute("color") == Some(colour)
            })
            .count()
    };
    // town03_like has two-way streets (yellow centre line), two-lane avenues (dashed between lanes) and edges.
    assert!(marks("solid", "yellow") > 0 && marks("broken", "white") > 0 && marks("solid", "white") > 0);
    let sidewalks = doc
        .descendants()
        .filter(|n| n.has_tag_name("lane") && n.attribute("type") == Some("sidewalk"))
        .collect::<Vec<_>>();
    assert!(!sidewalks.is_empty());
    assert!(sidewalks.iter().all(|l| {
        l.children()
            .any(|c| c.has_tag_name("height") && c.attribute("inner") == Some("0.15"))
    }));
    assert!(builtin_to_xodr("no_such_town").unwrap().is_none());
}

#[test]
fn cli_writes_the_file_and_refuses_unknown_towns() {
    let dir = common::Scratch::new("xodr-export");
    let path = dir.path().join("town02_like.xodr");
    let out = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .args(["town", "export", "town02_like", "--xodr"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("OpenDRIVE 1.7"));
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        builtin_to_xodr("town02_like").unwrap().unwrap()
    );
    let shown = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .args(["town", "show", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(shown.status.success());

    let bad = dir.path().join("nope.xodr");
    let out = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
        .args(["town", "export", "town04_like", "--xodr"])
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("town04_like"));
    assert!(!bad.exists(), "nothing written for an unknown town");
    let entries: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(entries.len(), 1, "no temporary file left behind: {entries:?}");
}

#[test]
fn an_exported_town_drives_a_spec_whose_plan_file_lives_elsewhere() {
    // A spec beside the exported town, a plan emitted into another directory: the plan records the spec's
    // directory relative to itself (no absolute path), and generating from it finds the map.
    let dir = common::Scratch::new("xodr-plan");
    let specs = dir.path().join("specs");
    std::fs::create_dir_all(&specs).unwrap();
    std::fs::write(
        specs.join("town.xodr"),
        builtin_to_xodr("town02_like").unwrap().unwrap(),
    )
    .unwrap();
    let quickstart =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml"))
            .unwrap();
    let spec = quickstart.replace(
        "towns: [town01_like]",
        "towns: [{name: exported, opendrive: town.xodr}]\n  splits: {exported: train}",
    );
    assert_ne!(spec, quickstart);
    std::fs::write(specs.join("spec.yaml"), spec).unwrap();
    let plan = dir.path().join("plans/p.json");
    std::fs::create_dir_all(plan.parent().unwrap()).unwrap();
    let run = |args: &[&std::ffi::OsStr]| {
        let o = Command::new(env!("CARGO_BIN_EXE_pedsynth"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    };
    // A plan takes no --set: plan it with the sensors off (fast), then generate from the plan alone.
    let mut plan_args: Vec<std::ffi::OsString> = vec![
        "plan".into(),
        specs.join("spec.yaml").into(),
        "--emit".into(),
        plan.clone().into(),
    ];
    for o in common::NO_SENSORS {
        plan_args.push("--set".into());
        plan_args.push(o.into());
    }
    run(&plan_args.iter().map(|a| a.as_os_str()).collect::<Vec<_>>());
    let text = std::fs::read_to_string(&plan).unwrap();
    assert!(
        !text.contains(dir.path().to_str().unwrap()),
        "the plan holds an absolute path"
    );
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["spec_dir"], "../specs");
    let out = dir.path().join("ds");
    run(&[
        "generate".as_ref(),
        plan.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
    ]);
    assert!(out.join("README.md").is_file());
}
