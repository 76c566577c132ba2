//! The built-in towns pass the same checks as the CARLA maps, match their golden summaries, and are
//! deterministic (built twice, identical geometry).

mod world_common;

use pedsynth::world::{BUILTIN_TOWN_NAMES, RoadNetwork};
use world_common::*;

fn check(name: &str) {
    let t = std::time::Instant::now();
    let net = RoadNetwork::builtin(name).expect("built-in town");
    eprintln!("{name}: built in {:?}", t.elapsed());
    insta::with_settings!({ snapshot_path => "golden", prepend_module_to_snapshot => false }, {
        insta::assert_json_snapshot!(format!("builtin_{name}"), net.summary());
    });
    assert_queries(&net);
    assert!(!net.obstacles.is_empty() && !net.crosswalks.is_empty());
    let again = RoadNetwork::builtin(name).expect("built-in town");
    assert_eq!(
        net.pieces, again.pieces,
        "{name}: lane geometry differs between two builds"
    );
    assert_eq!(net.lanes, again.lanes);
    assert_eq!(net.obstacles, again.obstacles);
    assert_eq!(net.crosswalks, again.crosswalks);
    assert_eq!(net.sidewalk_graph(), again.sidewalk_graph());
}

#[test]
fn town01_like() {
    check("town01_like");
}

#[test]
fn town02_like() {
    check("town02_like");
}

#[test]
fn town03_like() {
    check("town03_like");
}

#[test]
fn town05_like() {
    check("town05_like");
}

#[test]
fn every_builtin_name_builds_and_unknown_names_do_not() {
    for name in BUILTIN_TOWN_NAMES {
        assert!(RoadNetwork::builtin(name).is_some(), "{name}");
    }
    assert!(RoadNetwork::builtin("Town01").is_none());
    assert!(matches!(
        RoadNetwork::load("no_such_town"),
        Err(pedsynth::world::WorldError::UnknownTown { .. })
    ));
}

#[test]
fn builtin_towns_have_realistic_lane_widths() {
    use pedsynth::world::LaneType;
    for name in BUILTIN_TOWN_NAMES {
        let net = RoadNetwork::builtin(name).unwrap();
        for l in net.lanes.iter().filter(|l| !l.in_junction) {
            let w = net.pieces[l.pieces.start as usize].width_m[0];
            match l.lane_type {
                LaneType::Driving => {
                    assert!((3.5..=4.0).contains(&w), "{name}: driving lane {w} m")
                }
                LaneType::Sidewalk => assert!((2.0..=4.0).contains(&w), "{name}: sidewalk {w} m"),
                _ => {}
            }
        }
    }
}
