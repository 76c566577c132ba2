//! The built-in towns pass the same checks as the CARLA maps, match their golden summaries, and are
//! deterministic (built twice, identical geometry).

use crate::common;

use common::*;
use pedsynth::world::{BUILTIN_TOWN_NAMES, RoadNetwork};

fn check(name: &str) {
    let t = std::time::Instant::now();
    let net = RoadNetwork::builtin(name).expect("built-in town");
    eprintln!("{name}: built in {:?}", t.elapsed());
    insta::with_settings!({ snapshot_path => "../golden", prepend_module_to_snapshot => false }, {
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

#[test]
fn pedestrian_and_sensor_queries() {
    use glam::{DVec2, DVec3};
    use pedsynth::world::{LaneType, Side};
    use rand::SeedableRng;
    let net = RoadNetwork::builtin("town03_like").unwrap();
    // The sidewalk graph connects the whole town through crosswalks.
    let g = net.sidewalk_graph();
    assert!(g.nodes.len() > 100 && g.edge_count() > g.nodes.len());
    let a = g.nodes[0];
    let b = g.nodes[g.nodes.len() - 1];
    let path = net.sidewalk_path(a, b).expect("sidewalk path across town");
    assert!(path.len() > 2);
    for w in path.windows(2) {
        assert!((w[1] - w[0]).length() < 40.0);
    }
    // Sidewalk points ahead of a route, on both sides.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let route = net.random_route(&mut rng, 300.0).unwrap();
    for side in [Side::Left, Side::Right] {
        let pts = net.sidewalk_points_ahead(&route, 10.0, &[10.0, 20.0, 40.0, 80.0], side);
        let found = pts.iter().flatten().count();
        assert!(found >= 2, "{side:?}: {pts:?}");
        for s in pts.iter().flatten() {
            assert_eq!(net.lane_at(s.pos).unwrap().lane_type, LaneType::Sidewalk);
        }
    }
    // Nearest driving lane from a sidewalk point is close and has a travel heading.
    let sw = net
        .lanes
        .iter()
        .position(|l| l.lane_type == LaneType::Sidewalk && !l.in_junction)
        .unwrap();
    let p = net.lane_centre_line(sw as u32)[3];
    let hit = net.nearest_driving_lane(p, 30.0).unwrap();
    assert_eq!(hit.lane_type, LaneType::Driving);
    assert!(hit.distance_m > 0.0 && hit.distance_m < 10.0, "{hit:?}");
    // Spawn points lie on driving lanes.
    let spawns = net.driving_spawn_points(20.0);
    assert!(spawns.len() > 50);
    assert!(
        spawns
            .iter()
            .all(|s| { net.lane_at(s.pos).is_some_and(|h| h.lane_type == LaneType::Driving) })
    );
    // A ray along a street sees no building; a ray through a block does.
    let o = net.obstacles[0];
    let far = o.centre + DVec2::new(0.0, 500.0);
    assert!(net.ray_hits_obstacle(o.centre.extend(1.0) - DVec3::new(0.0, 200.0, 0.0), o.centre.extend(1.0)));
    assert!(!net.ray_hits_obstacle(far.extend(1.0), far.extend(1.0) + DVec3::new(0.0, 0.1, 0.0)));
    assert!(!net.ray_hits_obstacle(
        o.centre.extend(o.height_m + 1.0),
        o.centre.extend(o.height_m + 1.0) + DVec3::X
    ));
}
