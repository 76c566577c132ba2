//! A clip's other road users: traffic on lane walks ahead of and around the ego, the emergency vehicle of
//! `traffic.emergency`, and the cyclists of `traffic.cyclists` (every other one ahead of the ego in its
//! direction), each from streams of their own.

use super::*;

/// Minimum distance between vehicle spawns, metres.
pub(super) const VEHICLE_SPACING_M: f64 = 10.0;

pub(super) fn plan_vehicles(
    spec: &Spec,
    town: &TownContext,
    ego_route: &Route,
    peds: &[PedestrianScript],
    profiles: &[DrivingProfileKind],
    needed_m: f64,
    rng: &mut ChaCha20Rng,
) -> Result<Vec<VehicleScript>, String> {
    let net = &town.network;
    let ego_start = ego_route.points[0].pos;
    // Candidates within 150 m of the ego start, away from it and from pedestrians on the road.
    let candidates: Vec<&SpawnPoint> = town
        .spawn_points
        .iter()
        .filter(|sp| {
            let d = sp.pos.distance(ego_start);
            d > VEHICLE_SPACING_M && d < 150.0 && clear_of_road_pedestrians(sp, peds)
        })
        .collect();
    let mut out: Vec<VehicleScript> = Vec::with_capacity(profiles.len());
    let mut taken: Vec<DVec2> = vec![ego_start];
    for (i, &kind) in profiles.iter().enumerate() {
        let p = match kind {
            DrivingProfileKind::Aggressive => &spec.traffic.profiles.aggressive,
            DrivingProfileKind::Normal => &spec.traffic.profiles.normal,
            DrivingProfileKind::Cautious => &spec.traffic.profiles.cautious,
        };
        let draw = |rng: &mut ChaCha20Rng, r: crate::spec::types::Range| {
            if r.max() > r.min() {
                rng.random_range(r.min()..=r.max())
            } else {
                r.min()
            }
        };
        let mut placed = None;
        for _ in 0..PLACEMENT_ATTEMPTS {
            if candidates.is_empty() {
                break;
            }
            let sp = candidates[rng.random_range(0..candidates.len())];
            if taken.iter().any(|t| t.distance(sp.pos) < VEHICLE_SPACING_M) {
                continue;
            }
            let Some(script) = route_from_spawn(net, sp, needed_m, rng) else {
                continue;
            };
            placed = Some((script.start, script));
            break;
        }
        let Some((pos, route)) = placed else {
            return Err(format!(
                "cannot place vehicle {i} on a free driving lane within 150 m of the ego"
            ));
        };
        taken.push(pos);
        out.push(VehicleScript {
            id: i as u32,
            profile: kind,
            speed_difference_pct: draw(rng, p.speed_difference_pct),
            min_gap_m: draw(rng, p.min_gap_m),
            time_headway_s: draw(rng, p.time_headway_s),
            ignores_lights: rng.random_bool(p.ignore_lights_probability.clamp(0.0, 1.0)),
            ignores_walkers: rng.random_bool(p.ignore_walkers_probability.clamp(0.0, 1.0)),
            route,
            emergency: None,
        });
    }
    Ok(out)
}

/// Whether a vehicle may spawn at `sp`: no pedestrian starts on the road within 15 m of it.
pub(super) fn clear_of_road_pedestrians(sp: &SpawnPoint, peds: &[PedestrianScript]) -> bool {
    peds.iter()
        .all(|p| p.spawn_place != SpawnPlace::DrivingLane || p.spawn.distance(sp.pos) > 15.0)
}

/// A route from a spawn point: a lane walk of `needed_m` beyond it, not a polyline (the executor builds the
/// polyline, so planning 10k clips stays fast).
pub(super) fn route_from_spawn(
    net: &RoadNetwork,
    sp: &SpawnPoint,
    needed_m: f64,
    rng: &mut ChaCha20Rng,
) -> Option<RouteScript> {
    let lanes = net.lane_walk(sp.lane, needed_m + sp.lane_s_m, rng)?;
    let length_m = lanes.iter().map(|&l| net.lanes[l as usize].length_m).sum();
    Some(RouteScript {
        lanes,
        length_m,
        start_s_m: sp.lane_s_m,
        start: sp.pos,
        start_heading_rad: sp.heading_rad,
    })
}

/// The clip's emergency vehicle: on a driving lane 40–150 m ahead of the ego's start heading towards it
/// (oncoming) where the town has one, else anywhere 20–150 m away; clear of the other vehicles and of
/// pedestrians on the road; from its own stream.
#[allow(clippy::too_many_arguments)]
pub(super) fn plan_emergency(
    spec: &Spec,
    town: &TownContext,
    ego_route: &RouteScript,
    peds: &[PedestrianScript],
    vehicles: &[VehicleScript],
    kind: EmergencyKind,
    needed_m: f64,
    clip_seed: u64,
) -> Result<VehicleScript, String> {
    let net = &town.network;
    let mut rng = seeds::clip_rng(clip_seed, "emergency");
    let ego_start = ego_route.start;
    let ego_dir = DVec2::from_angle(ego_route.start_heading_rad);
    let free = |sp: &&SpawnPoint| {
        clear_of_road_pedestrians(sp, peds)
            && vehicles
                .iter()
                .all(|v| v.route.start.distance(sp.pos) >= VEHICLE_SPACING_M)
    };
    let oncoming: Vec<&SpawnPoint> = town
        .spawn_points
        .iter()
        .filter(|sp| {
            let d = sp.pos - ego_start;
            (40.0..150.0).contains(&d.length())
                && d.dot(ego_dir) > 0.7 * d.length()
                && DVec2::from_angle(sp.heading_rad).dot(ego_dir) < -0.7
        })
        .filter(free)
        .collect();
    let any: Vec<&SpawnPoint> = town
        .spawn_points
        .iter()
        .filter(|sp| (20.0..150.0).contains(&sp.pos.distance(ego_start)))
        .filter(free)
        .collect();
    for candidates in [oncoming, any] {
        for _ in 0..PLACEMENT_ATTEMPTS.min(candidates.len().max(1) * 2) {
            if candidates.is_empty() {
                break;
            }
            let sp = candidates[rng.random_range(0..candidates.len())];
            let Some(route) = route_from_spawn(net, sp, needed_m, &mut rng) else {
                continue;
            };
            return Ok(VehicleScript {
                id: vehicles.len() as u32,
                profile: DrivingProfileKind::Aggressive,
                speed_difference_pct: -spec.traffic.emergency.speed_above_limit_pct,
                min_gap_m: 2.0,
                time_headway_s: 1.0,
                ignores_lights: true,
                ignores_walkers: false,
                route,
                emergency: Some(kind),
            });
        }
    }
    Err("cannot place the emergency vehicle on a free driving lane within 150 m of the ego".to_owned())
}

/// Bicycle frame colours (sRGB).
pub(super) const BIKE_COLOURS: [[u8; 3]; 8] = [
    [200, 30, 30],
    [20, 20, 22],
    [230, 230, 225],
    [30, 80, 170],
    [40, 130, 60],
    [240, 170, 20],
    [120, 120, 125],
    [0, 150, 160],
];

/// Cyclists start at least this far from the ego and from every vehicle's start, metres.
pub(super) const CYCLIST_SPACING_M: f64 = 8.0;

/// A vehicle starting within this distance behind a cyclist in its lane could not stop for it, metres (from
/// 60 km/h at 8 m/s² with a second's reaction, plus the lengths).
pub(super) const CYCLIST_CLEAR_BEHIND_M: f64 = 40.0;

/// Whether a vehicle starting at `route`'s start would come up behind a cyclist starting at `sp` in the same
/// lane within [`CYCLIST_CLEAR_BEHIND_M`].
pub(super) fn closing_from_behind(route: &RouteScript, sp: &SpawnPoint) -> bool {
    let dir = DVec2::from_angle(route.start_heading_rad);
    let d = sp.pos - route.start;
    let along = d.dot(dir);
    along > 0.0
        && along < CYCLIST_CLEAR_BEHIND_M
        && d.dot(dir.perp()).abs() < 2.5
        && DVec2::from_angle(sp.heading_rad).dot(dir) > 0.7
}

/// The clip's cyclists (`traffic.cyclists.per_clip`), all from the stream `cyclists` (and their riders' looks
/// from `cyclist/<id>/identity`), so that adding cyclists changes no other draw of the plan. Every other one
/// starts ahead of the ego in its direction (15–80 m: the ego catches up and overtakes it), the others anywhere
/// 15–120 m away; clear of the vehicles' starts and of pedestrians on the road. A cyclist that finds no free
/// lane is left out (cyclists are optional scenery; `pedsynth stats` counts those placed).
pub(super) fn plan_cyclists(
    spec: &Spec,
    town: &TownContext,
    ego_route: &RouteScript,
    peds: &[PedestrianScript],
    vehicles: &[VehicleScript],
    needed_m: f64,
    clip_seed: u64,
) -> Vec<CyclistScript> {
    let c = &spec.traffic.cyclists;
    if c.per_clip.max() == 0 {
        return Vec::new();
    }
    let net = &town.network;
    let mut rng = seeds::clip_rng(clip_seed, "cyclists");
    let count = rng.random_range(c.per_clip.min()..=c.per_clip.max().max(c.per_clip.min()));
    let ego_start = ego_route.start;
    let ego_dir = DVec2::from_angle(ego_route.start_heading_rad);
    let mut taken: Vec<DVec2> = vehicles.iter().map(|v| v.route.start).collect();
    taken.push(ego_start);
    let mut out = Vec::with_capacity(count as usize);
    for k in 0..count {
        let candidates_for = |same_way: bool, taken: &[DVec2]| -> Vec<&SpawnPoint> {
            town.spawn_points
                .iter()
                .filter(|sp| {
                    let d = sp.pos - ego_start;
                    let ahead =
                        d.dot(ego_dir) > 0.7 * d.length() && DVec2::from_angle(sp.heading_rad).dot(ego_dir) > 0.7;
                    let range = if same_way { 15.0..80.0 } else { 15.0..120.0 };
                    range.contains(&d.length())
                        && (!same_way || ahead)
                        && clear_of_road_pedestrians(sp, peds)
                        && taken.iter().all(|t| t.distance(sp.pos) >= CYCLIST_SPACING_M)
                        && !vehicles.iter().any(|v| closing_from_behind(&v.route, sp))
                })
                .collect()
        };
        let mut candidates = if k % 2 == 0 {
            candidates_for(true, &taken)
        } else {
            Vec::new()
        };
        if candidates.is_empty() {
            candidates = candidates_for(false, &taken);
        }
        for _ in 0..PLACEMENT_ATTEMPTS.min(candidates.len() * 2) {
            let sp = candidates[rng.random_range(0..candidates.len())];
            let Some(route) = route_from_spawn(net, sp, needed_m, &mut rng) else {
                continue;
            };
            taken.push(sp.pos);
            let id = out.len() as u32;
            out.push(CyclistScript {
                id,
                route,
                speed_mps: draw(&mut rng, c.speed_mps),
                edge_offset_m: c.edge_offset_m,
                ignores_lights: rng.random_bool(c.ignore_lights_probability.clamp(0.0, 1.0)),
                rider: identity::rider_identity(clip_seed, id),
                bike_rgb: BIKE_COLOURS[rng.random_range(0..BIKE_COLOURS.len())],
            });
            break;
        }
    }
    out
}

pub(super) fn wrap_angle(a: f64) -> f64 {
    let mut a = a % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a <= -PI {
        a += 2.0 * PI;
    }
    a
}
