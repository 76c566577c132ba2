//! Where a clip's pedestrians start: on the sidewalk 10–55 m ahead on alternating sides; crossers and hard
//! negatives back along the sidewalk from their curb point by their approach; non-crossers optionally at a drawn
//! distance to the side; mid-road jaywalkers in a driving lane; group followers beside their leader; at the
//! first signalised crosswalk where lights run.

use super::*;

/// A crosser's sidewalk is at most this far to the side of the ego's route, metres: farther (across a junction,
/// beside a wide road) the ego's camera loses it before it crosses.
pub(super) const MAX_CROSSER_LATERAL_M: f64 = 12.0;

/// Mid-road jaywalkers start at most this far ahead of the ego, metres: they cross at once, and farther away
/// their whole crossing would be too small in the image to be annotated.
pub(super) const MIDROAD_MAX_AHEAD_M: f64 = 30.0;

/// A crosser placed at a signalised crosswalk stands this far before the route's entry into the junction
/// along the route, metres: the middle of the crosswalk at the road's mouth (0.5 to 3.5 m from its end).
pub(super) const SIGNALISED_CROSSWALK_BEFORE_ENTRY_M: f64 = 2.0;

/// How far from the curb a crosser starts, metres.
pub const CURB_STANDOFF_M: f64 = 0.3;

/// Minimum distance between two pedestrians' spawn and curb points, metres (beyond the avoidance radius, so that
/// two waiting pedestrians do not push each other away from their spots).
pub(super) const PED_SPACING_M: f64 = 1.2;

/// Attempts to place one pedestrian before the clip is declared infeasible.
pub(super) const PLACEMENT_ATTEMPTS: usize = 60;

#[allow(clippy::too_many_arguments)]
pub(super) fn plan_pedestrians(
    spec: &Spec,
    net: &RoadNetwork,
    route: &Route,
    peds: &[PedAlloc],
    first_ped: usize,
    archetype_names: &[&String],
    duration_s: f64,
    (clip_seed, umbrella_share): (u64, f64),
    rng: &mut ChaCha20Rng,
) -> Result<Vec<PedestrianScript>, String> {
    let p = &spec.pedestrians;
    let c = &spec.crossing;
    let spawn_ahead = c.layers.crosser_allocation.spawn_ahead_m;
    let far_m = spec.annotations.visibility.max_distance_m.min(route.length_m() - 1.0);
    let mut scripts: Vec<PedestrianScript> = Vec::with_capacity(peds.len());
    let mut crosser_side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
    // Traffic lights: the route's signalised junction entries and a stream of their own for the draws (none when
    // lights do not run, so that turning them on shifts no other draw but the placements it changes).
    let mut signal_draws = spec.traffic.signals.enabled.then(|| {
        (
            seeds::clip_rng(clip_seed, "plan/signals"),
            crate::world::signals::signalised_entries(net, route),
        )
    });
    // Per-class scenario rules, drawn from a stream of their own (none while they are off, so that the paper's
    // set-up draws exactly what it drew before they existed).
    let scenario = &c.scenario;
    let mut scenario_rng = (!scenario.is_off()).then(|| seeds::clip_rng(clip_seed, "plan/scenario"));
    let walker_range = if scenario.walker_ahead_m.max() > 0.0 {
        (
            scenario.walker_ahead_m.min(),
            scenario.walker_ahead_m.max().min(route.length_m() - 1.0),
        )
    } else {
        (spawn_ahead.min(), far_m)
    };
    // Group ids are numbered by leader, in pedestrian order.
    let mut leaders: Vec<u32> = peds.iter().filter_map(|a| a.group).collect();
    leaders.sort_unstable();
    leaders.dedup();

    for (i, alloc) in peds.iter().enumerate() {
        let id = i as u32;
        let name = archetype_names
            .get(alloc.archetype as usize)
            .map_or("casual_person", |s| s.as_str());
        let a = p.archetypes.get(name).cloned().unwrap_or_default();
        let base_speed_mps = draw(rng, a.speed_mps);
        let hesitation_s = draw(rng, a.hesitation_s);
        let ttc_threshold_s = draw(rng, a.ttc_threshold_s);
        let safety_margin_s = draw(rng, c.gap_acceptance.safety_margin_s);
        let patience_s = draw(rng, a.patience_s);
        let distracted_at_s = if alloc.speed_profile == SpeedProfile::Distracted {
            Some(0.0)
        } else if rng.random_bool(a.distraction_probability.clamp(0.0, 1.0)) {
            Some(rng.random_range(0.0..duration_s.max(0.1)))
        } else {
            None
        };
        let group = alloc.group.map(|leader| GroupRef {
            group_id: leaders.iter().position(|&l| l == leader).unwrap_or(0) as u32,
            leader: (leader as usize - first_ped) as u32,
        });
        let role = if alloc.source == CrosserSource::None {
            Role::NonCrosser
        } else {
            Role::Crosser
        };

        // The timeline: crossers that start on a sidewalk are in view for a planned time before stepping out;
        // hard negatives wait at the curb for a planned time.
        let timeline = &c.timeline;
        let in_view_before_crossing_s = (role == Role::Crosser && alloc.behaviour != Behaviour::MidroadJaywalker)
            .then(|| draw(rng, timeline.in_view_before_crossing_s));
        let curb_wait_s =
            (alloc.behaviour == Behaviour::HardNegative).then(|| draw(rng, c.hard_negatives.wait_at_curb_s));

        // Placement.
        let leader = group
            .filter(|g| g.leader != id)
            .and_then(|g| scripts.get(g.leader as usize));
        let placed = if let Some(leader) = leader {
            place_follower(net, leader, &scripts, rng)
        } else {
            match (role, alloc.behaviour) {
                (Role::Crosser, Behaviour::MidroadJaywalker) => place_midroad(
                    net,
                    route,
                    crate::spec::types::Range(
                        spawn_ahead.min(),
                        spawn_ahead.max().min(MIDROAD_MAX_AHEAD_M).max(spawn_ahead.min()),
                    ),
                    c.layers.midroad_jaywalkers.lateral_offset_m,
                    &scripts,
                    rng,
                ),
                (Role::Crosser, _) | (_, Behaviour::HardNegative) => {
                    // Allocated and baseline crossers, and hard negatives, start within the spawn range ahead of
                    // the ego, far enough that the ego (easing off for them) cannot pass before their time in
                    // view is up.
                    let (lo, hi) = crosser_spawn_range(spec, route, in_view_before_crossing_s.unwrap_or(0.0));
                    let approach_m = draw(rng, timeline.approach_m);
                    // Where lights run, a share of them waits at a signalised crosswalk on the ego's route (the
                    // first one in range), across the ego's approach road at the junction's mouth.
                    let at_signal = signal_draws.as_mut().and_then(|(sig_rng, entries)| {
                        if !sig_rng.random_bool(spec.traffic.signals.crosswalk_share.clamp(0.0, 1.0)) {
                            return None;
                        }
                        let s = entries
                            .iter()
                            .map(|&(s, _)| s - SIGNALISED_CROSSWALK_BEFORE_ENTRY_M)
                            .find(|&s| s >= spawn_ahead.min() && s <= far_m)?;
                        place_crosser(net, route, s, s, crosser_side, approach_m, &scripts, rng)
                    });
                    let placed = at_signal
                        .or_else(|| place_crosser(net, route, lo, hi, crosser_side, approach_m, &scripts, rng));
                    crosser_side = if crosser_side == Side::Left {
                        Side::Right
                    } else {
                        Side::Left
                    };
                    placed
                }
                // Walkers too start within the spawn range, so that the camera sees them about as long as crossers
                // (the benchmark protocol counts a track only when it is long enough).
                // With a lateral rule, a walker starts on sidewalk at its drawn distance to the side: in the
                // walkers' range ahead, else anywhere in view ahead (side streets are few), else beside the route.
                (Role::NonCrosser, _) => scenario_rng
                    .as_mut()
                    .filter(|_| scenario.walker_lateral_m.max() > 0.0)
                    .map(|r| draw(r, scenario.walker_lateral_m))
                    .and_then(|lateral_m| {
                        let in_view = (spawn_ahead.min(), far_m);
                        place_aside(net, route, walker_range, lateral_m, &scripts, rng).or_else(|| {
                            (walker_range != in_view)
                                .then(|| place_aside(net, route, in_view, lateral_m, &scripts, rng))
                                .flatten()
                        })
                    })
                    .or_else(|| place_sidewalk(net, route, walker_range.0, walker_range.1, &scripts, rng)),
            }
        };
        let (spawn, heading, ahead, crossing, place) = placed.ok_or_else(|| {
            format!(
                "cannot place pedestrian {id} ({}, {}) on a {} near the ego's route",
                name,
                alloc.behaviour.name(),
                if alloc.behaviour == Behaviour::MidroadJaywalker {
                    "driving lane"
                } else {
                    "sidewalk"
                }
            )
        })?;
        let keeps_crossing = role == Role::Crosser || alloc.behaviour == Behaviour::HardNegative;
        let crossing = if keeps_crossing { crossing } else { None };
        if keeps_crossing && crossing.is_none() {
            return Err(format!("pedestrian {id} is a crosser but has no road to cross"));
        }
        let (identity, child) = identity::identities(clip_seed, id, name, a.body, umbrella_share);
        let step_out_ego_within_m = match scenario_rng.as_mut() {
            Some(r) if in_view_before_crossing_s.is_some() && scenario.crosser_ego_within_m.max() > 0.0 => {
                Some(draw(r, scenario.crosser_ego_within_m))
            }
            _ => None,
        };
        scripts.push(PedestrianScript {
            id,
            archetype: name.to_owned(),
            body: a.body,
            base_speed_mps,
            hesitation_s,
            attention: a.attention,
            ttc_threshold_s,
            safety_margin_s,
            patience_s,
            distracted_at_s,
            role,
            crosser_source: alloc.source,
            behaviour: alloc.behaviour,
            group,
            speed_profile: alloc.speed_profile,
            spawn_place: place,
            spawn,
            spawn_heading_rad: heading,
            ahead_of_ego_m: ahead,
            crossing,
            step_out_ego_within_m,
            step_out_stopped_ego_within_m: step_out_ego_within_m.and(stopped_ego_within(scenario)),
            in_view_before_crossing_s,
            curb_wait_s,
            identity,
            child,
            // A group crosses with its leader: followers share the leader's choice.
            red_light_violator: match leader {
                Some(l) => l.red_light_violator,
                None => signal_draws
                    .as_mut()
                    .is_some_and(|(sig_rng, _)| sig_rng.random_bool(a.red_light_violation_probability.clamp(0.0, 1.0))),
            },
        });
    }
    Ok(scripts)
}

pub(super) type Placement = (DVec2, f64, f64, Option<CrossingScript>, SpawnPlace);

/// Where along the ego's route (arc length from its start, metres) a crosser starting on a sidewalk is placed:
/// within layer 1's spawn range and the visibility gate's distance, and far enough that the ego, easing off for
/// it, cannot pass before its `in_view_s` is up.
pub(super) fn crosser_spawn_range(spec: &Spec, route: &Route, in_view_s: f64) -> (f64, f64) {
    let c = &spec.crossing;
    let spawn_ahead = c.layers.crosser_allocation.spawn_ahead_m;
    let far_m = spec.annotations.visibility.max_distance_m.min(route.length_m() - 1.0);
    let (lo, hi) = (spawn_ahead.min(), spawn_ahead.max().min(far_m));
    let lo =
        (c.decision_window_m.min() + EGO_BRAKING_ESTIMATE_M + COURTESY_SPEED_ESTIMATE_MPS * in_view_s).clamp(lo, hi);
    (lo, hi)
}

pub(super) fn draw(rng: &mut ChaCha20Rng, r: crate::spec::types::Range) -> f64 {
    if r.max() > r.min() {
        rng.random_range(r.min()..=r.max())
    } else {
        r.min()
    }
}

/// Whether `p` is at least [`PED_SPACING_M`] from every earlier pedestrian's spawn point and curb point (two
/// pedestrians bound for the same spot would block each other there).
pub(super) fn far_from_others(p: DVec2, scripts: &[PedestrianScript]) -> bool {
    scripts.iter().all(|s| {
        s.spawn.distance(p) >= PED_SPACING_M
            && s.crossing
                .as_ref()
                .is_none_or(|c| (c.near_curb - c.direction * CURB_STANDOFF_M).distance(p) >= PED_SPACING_M)
    })
}

pub(super) fn crossing_script(c: &crate::world::Crossing) -> CrossingScript {
    CrossingScript {
        near_curb: c.near_curb,
        far_curb: c.far_curb,
        end: c.end,
        direction: c.direction,
        carriageway_width_m: c.carriageway_width_m,
    }
}

pub(super) fn is_lane(net: &RoadNetwork, p: DVec2, kind: LaneType) -> bool {
    net.lane_at(p).is_some_and(|h| h.lane_type == kind)
}

#[allow(clippy::too_many_arguments)]
pub(super) fn place_crosser(
    net: &RoadNetwork,
    route: &Route,
    lo: f64,
    hi: f64,
    side: Side,
    approach_m: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for attempt in 0..PLACEMENT_ATTEMPTS {
        let s = if hi > lo { rng.random_range(lo..hi) } else { lo };
        let side = if attempt % 2 == 0 {
            side
        } else if side == Side::Left {
            Side::Right
        } else {
            Side::Left
        };
        let Some(sample) = net.sidewalk_beside(route, s, side) else {
            continue;
        };
        if !far_from_others(sample.pos, scripts)
            || !is_lane(net, sample.pos, LaneType::Sidewalk)
            || sample.pos.distance(route.pose_at(s).pos) > MAX_CROSSER_LATERAL_M
        {
            continue;
        }
        let Some(crossing) = net.crossing_at(sample.pos) else {
            continue;
        };
        if crossing.carriageway_width_m < 2.0 {
            continue;
        }
        // The curb point, facing the road (if that spot is free sidewalk); the pedestrian starts up to
        // `approach_m` along the curb from it and walks there.
        let heading = crossing.direction.to_angle();
        let at_curb = crossing.near_curb - crossing.direction * CURB_STANDOFF_M;
        let free = is_lane(net, at_curb, LaneType::Sidewalk) && far_from_others(at_curb, scripts);
        if !free {
            return Some((
                sample.pos,
                heading,
                s,
                Some(crossing_script(&crossing)),
                SpawnPlace::Sidewalk,
            ));
        }
        let first = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let (spawn, spawn_heading) =
            approach_start(net, at_curb, crossing.direction.perp(), approach_m, first, scripts)
                .unwrap_or((at_curb, heading));
        return Some((
            spawn,
            spawn_heading,
            s,
            Some(crossing_script(&crossing)),
            SpawnPlace::Sidewalk,
        ));
    }
    None
}

/// Where a pedestrian bound for `curb` starts when it walks `approach_m` along the curb (direction `along`,
/// trying `first` then the other way, then half the distance): the start and its heading, if the whole walk is
/// on free sidewalk.
pub(super) fn approach_start(
    net: &RoadNetwork,
    curb: DVec2,
    along: DVec2,
    approach_m: f64,
    first: f64,
    scripts: &[PedestrianScript],
) -> Option<(DVec2, f64)> {
    if approach_m < 0.5 {
        return None;
    }
    for distance in [approach_m, 0.5 * approach_m] {
        for sign in [first, -first] {
            let start = curb + along * (sign * distance);
            let steps = distance.ceil() as usize;
            let on_sidewalk = (1..=steps).all(|k| {
                let p = curb + along * (sign * distance * k as f64 / steps as f64);
                is_lane(net, p, LaneType::Sidewalk)
            });
            if on_sidewalk && far_from_others(start, scripts) {
                return Some((start, (curb - start).to_angle()));
            }
        }
    }
    None
}

pub(super) fn place_sidewalk(
    net: &RoadNetwork,
    route: &Route,
    lo: f64,
    hi: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for _ in 0..PLACEMENT_ATTEMPTS {
        let s = if hi > lo { rng.random_range(lo..hi) } else { lo };
        let side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
        let Some(sample) = net.sidewalk_beside(route, s, side) else {
            continue;
        };
        if !far_from_others(sample.pos, scripts) || !is_lane(net, sample.pos, LaneType::Sidewalk) {
            continue;
        }
        let heading = either_way(route.pose_at(s).heading_rad, rng);
        // Non-crossers never cross: no crossing vector (the costliest query) is computed for them.
        let crossing = None;
        return Some((sample.pos, heading, s, crossing, SpawnPlace::Sidewalk));
    }
    None
}

/// A walker's heading: along the route's `heading_rad` or against it, even odds.
fn either_way(heading_rad: f64, rng: &mut ChaCha20Rng) -> f64 {
    if rng.random_bool(0.5) {
        heading_rad
    } else {
        wrap_angle(heading_rad + PI)
    }
}

/// A non-crosser on free sidewalk `lateral_m` to the side of the ego's route (either side), somewhere in
/// `ahead_m` (arc length along it, `[lo, hi]` metres): beside a wide road, along a side street or across a
/// junction. `None` where the route has no such sidewalk within [`PLACEMENT_ATTEMPTS`] draws.
pub(super) fn place_aside(
    net: &RoadNetwork,
    route: &Route,
    (lo, hi): (f64, f64),
    lateral_m: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for _ in 0..PLACEMENT_ATTEMPTS {
        let s = if hi > lo { rng.random_range(lo..hi) } else { lo };
        let pose = route.pose_at(s);
        let left = DVec2::from_angle(pose.heading_rad).perp();
        let n = if rng.random_bool(0.5) { left } else { -left };
        let p = pose.pos + n * lateral_m;
        if !is_lane(net, p, LaneType::Sidewalk) || !far_from_others(p, scripts) {
            continue;
        }
        return Some((p, either_way(pose.heading_rad, rng), s, None, SpawnPlace::Sidewalk));
    }
    None
}

pub(super) fn place_midroad(
    net: &RoadNetwork,
    route: &Route,
    ahead: crate::spec::types::Range,
    lateral_m: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for _ in 0..PLACEMENT_ATTEMPTS {
        let s = rng.random_range(ahead.min()..=ahead.max()).min(route.length_m() - 1.0);
        let origin_side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
        let Some(sample) = net.sidewalk_beside(route, s, origin_side) else {
            continue;
        };
        let Some(crossing) = net.crossing_at(sample.pos) else {
            continue;
        };
        if crossing.carriageway_width_m < 2.0 {
            continue;
        }
        // Spawn in a driving lane at the ego lane's centre ± the lateral offset, on the crossing line.
        let pose = route.pose_at(s);
        let target = pose.pos + crossing.direction * rng.random_range(-lateral_m..=lateral_m);
        let t = (target - crossing.near_curb)
            .dot(crossing.direction)
            .clamp(0.5, crossing.carriageway_width_m - 0.5);
        let spawn = crossing.near_curb + crossing.direction * t;
        if !is_lane(net, spawn, LaneType::Driving) || !far_from_others(spawn, scripts) {
            continue;
        }
        return Some((
            spawn,
            crossing.direction.to_angle(),
            s,
            Some(crossing_script(&crossing)),
            SpawnPlace::DrivingLane,
        ));
    }
    None
}

pub(super) fn place_follower(
    net: &RoadNetwork,
    leader: &PedestrianScript,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    // Beside the leader along the curb (the leader's crossing line, shifted), walking with it.
    let along = leader
        .crossing
        .as_ref()
        .map_or(DVec2::from_angle(leader.spawn_heading_rad).perp(), |c| {
            c.direction.perp()
        });
    for _ in 0..PLACEMENT_ATTEMPTS {
        let offset = rng.random_range(PED_SPACING_M..2.5) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let shift = along * offset;
        let p = leader.spawn + shift;
        let kind = if leader.spawn_place == SpawnPlace::DrivingLane {
            LaneType::Driving
        } else {
            LaneType::Sidewalk
        };
        if !is_lane(net, p, kind) || !far_from_others(p, scripts) {
            continue;
        }
        let crossing = leader.crossing.clone().map(|c| CrossingScript {
            near_curb: c.near_curb + shift,
            far_curb: c.far_curb + shift,
            end: c.end + shift,
            ..c
        });
        if crossing.as_ref().is_none_or(|c| {
            kind == LaneType::Sidewalk
                && !(is_lane(net, c.near_curb - c.direction * CURB_STANDOFF_M, LaneType::Sidewalk)
                    && is_lane(net, c.end, LaneType::Sidewalk))
        }) {
            continue;
        }
        return Some((
            p,
            leader.spawn_heading_rad,
            leader.ahead_of_ego_m,
            crossing,
            leader.spawn_place,
        ));
    }
    None
}

/// The distance within which a stopped ego lets a crosser that waits for it step out
/// (`crossing.scenario.crosser_stopped_ego_within_m`), where that rule is on.
pub(super) fn stopped_ego_within(scenario: &crate::spec::types::Scenario) -> Option<f64> {
    Some(scenario.crosser_stopped_ego_within_m).filter(|&d| d > 0.0)
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    /// Walkers placed aside stand on free sidewalk exactly their drawn distance to the side of the route, at
    /// every distance a town has sidewalk; where it has none in reach, there is no placement (the planner then
    /// falls back to the sidewalk beside the route).
    #[test]
    fn walkers_aside_stand_on_sidewalk_at_their_distance_from_the_route() {
        let net = RoadNetwork::builtin("town01_like").expect("a built-in town");
        let mut rng = ChaCha20Rng::seed_from_u64(7);
        let mut placed_by_distance = BTreeMap::new();
        for _ in 0..40 {
            let route = net.random_route(&mut rng, 150.0).expect("a route");
            for lateral_m in [4.0, 9.0, 12.0, 18.0, 30.0] {
                let Some((spawn, _, ahead_m, crossing, place)) =
                    place_aside(&net, &route, (10.0, 120.0), lateral_m, &[], &mut rng)
                else {
                    continue;
                };
                *placed_by_distance.entry(lateral_m as u32).or_insert(0) += 1;
                assert!((10.0..=120.0).contains(&ahead_m));
                assert!(crossing.is_none() && place == SpawnPlace::Sidewalk);
                assert!(is_lane(&net, spawn, LaneType::Sidewalk));
                let pose = route.pose_at(ahead_m);
                let offset = spawn - pose.pos;
                let along = DVec2::from_angle(pose.heading_rad);
                assert!(offset.dot(along).abs() < 1e-9, "straight out to the side");
                assert!((offset.length() - lateral_m).abs() < 1e-9);
            }
        }
        // Sidewalk beside the route (4-9 m in town01_like) is found on every route; side streets and the far
        // sides of junctions (12-30 m) on some (24, 16 and 12 of 40 when this was written).
        for (lateral_m, least) in [(4, 40), (9, 40), (12, 10), (18, 8), (30, 5)] {
            let got = placed_by_distance.get(&lateral_m).copied().unwrap_or(0);
            assert!(
                got >= least,
                "{got} of 40 routes have sidewalk {lateral_m} m aside: {placed_by_distance:?}"
            );
        }
        let route = net.random_route(&mut rng, 150.0).expect("a route");
        assert!(
            place_aside(&net, &route, (10.0, 60.0), 400.0, &[], &mut rng).is_none(),
            "beyond the town"
        );
    }
}
