//! The real CARLA maps (MIT, read from `$PEDSYNTH_CARLA_MAPS` or ../shared/maps/carla, never copied into the
//! repository): each loads,
//! its summary matches the golden file, sampled points classify correctly, long routes exist and crossing
//! vectors land on the far sidewalk.

use crate::common;

use common::*;
use pedsynth::world::RoadNetwork;

fn load(town: &str) -> RoadNetwork {
    let path = carla_map(town);
    let t = std::time::Instant::now();
    let net = RoadNetwork::from_xodr_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    eprintln!("{town}: loaded in {:?}", t.elapsed());
    net
}

fn check(town: &str) {
    let net = load(town);
    let mut s = net.summary();
    s.source = pedsynth::world::TownSource::Xodr {
        path: format!("../shared/maps/carla/{town}.xodr"),
    };
    insta::with_settings!({ snapshot_path => "../golden", prepend_module_to_snapshot => false }, {
        insta::assert_json_snapshot!(format!("carla_{}", town.to_lowercase()), s);
    });
    assert_queries(&net);
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn town01() {
    check("Town01");
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn town02() {
    check("Town02");
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn town03() {
    check("Town03");
}

#[test]
#[ignore = "reads CARLA's maps (../shared/maps/carla): cargo test -- --include-ignored"]
fn town05() {
    check("Town05");
}
