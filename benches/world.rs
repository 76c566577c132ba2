//! World benchmarks: loading the CARLA maps, lane-at-point queries, obstacle rays.
//! Run with `cargo bench --bench world`.

use divan::counter::ItemsCount;
use glam::{DVec2, DVec3};
use pedsynth::world::RoadNetwork;
use rand::{RngExt, SeedableRng};

fn main() {
    divan::main();
}

fn carla(town: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/maps/carla")).join(format!("{town}.xodr"))
}

#[divan::bench(args = ["Town01", "Town02", "Town03", "Town05"], sample_count = 20)]
fn load_carla_map(town: &str) -> RoadNetwork {
    RoadNetwork::from_xodr_file(&carla(town)).unwrap()
}

#[divan::bench(args = ["town01_like", "town05_like"], sample_count = 20)]
fn build_builtin_town(name: &str) -> RoadNetwork {
    RoadNetwork::builtin(name).unwrap()
}

const N: usize = 100_000;

/// Points: half on lane pieces (centre of a random piece), half uniform over the bounds.
fn points(net: &RoadNetwork) -> Vec<DVec2> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let (lo, hi) = net.bounds;
    (0..N)
        .map(|i| {
            if i % 2 == 0 {
                let p = &net.pieces[rng.random_range(0..net.pieces.len())];
                (p.corners[0] + p.corners[1] + p.corners[2] + p.corners[3]) * 0.25
            } else {
                DVec2::new(rng.random_range(lo.x..hi.x), rng.random_range(lo.y..hi.y))
            }
        })
        .collect()
}

#[divan::bench(args = ["Town03", "Town05", "town05_like"])]
fn lane_at(bencher: divan::Bencher, town: &str) {
    let net = if town.starts_with("Town") {
        RoadNetwork::from_xodr_file(&carla(town)).unwrap()
    } else {
        RoadNetwork::builtin(town).unwrap()
    };
    let pts = points(&net);
    bencher.counter(ItemsCount::new(N)).bench_local(|| {
        let mut hits = 0usize;
        for &p in &pts {
            hits += net.lane_at(divan::black_box(p)).is_some() as usize;
        }
        hits
    });
}

#[divan::bench(args = ["town05_like"])]
fn obstacle_rays(bencher: divan::Bencher, town: &str) {
    let net = RoadNetwork::builtin(town).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let (lo, hi) = net.bounds;
    let rays: Vec<(DVec3, DVec3)> = (0..10_000)
        .map(|_| {
            let a = DVec3::new(rng.random_range(lo.x..hi.x), rng.random_range(lo.y..hi.y), 1.5);
            let b = a + DVec3::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0), 0.0);
            (a, b)
        })
        .collect();
    bencher
        .counter(ItemsCount::new(rays.len()))
        .bench_local(|| rays.iter().filter(|(a, b)| net.ray_hits_obstacle(*a, *b)).count());
}
