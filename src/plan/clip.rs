//! One clip's script from its stratum's draws: the ego's route, its cruise speed, each crosser's time in view
//! before crossing (clips lengthened where the timeline needs it), then pedestrians, vehicles, emergency
//! vehicles and cyclists placed along the route.

use super::*;

/// The ego's planned cruise speed upper bound, for route length checks, m/s.
pub(super) const MAX_URBAN_SPEED_MPS: f64 = 14.0;

#[allow(clippy::too_many_arguments)]
pub(super) fn plan_clip(
    spec: &Spec,
    (town_ref, weather): (&TownRef, &WeatherRef),
    town: &TownContext,
    (clip_id, basics): (String, &ClipBasics),
    peds: &[PedAlloc],
    first_ped: usize,
    vehicle_profiles: &[DrivingProfileKind],
    archetype_names: &[&String],
) -> Result<ClipScript, String> {
    let mut rng = seeds::clip_rng(basics.seed, "plan");
    let net = &town.network;
    let fps = spec.dataset.fps;
    let duration_s = f64::from(basics.frame_count) / f64::from(fps);
    let l1 = &spec.crossing.layers.crosser_allocation;
    let ahead_max = l1.spawn_ahead_m.max().max(spec.annotations.visibility.max_distance_m);
    let needed_m = ahead_max + MAX_URBAN_SPEED_MPS * duration_s + spec.traffic.ego.route_margin_m;

    // The ego route, with room ahead for every pedestrian; a route along which the clip's pedestrians or
    // vehicles cannot be placed is replaced by another (a few tries), then the clip is infeasible.
    let ego_spec = &spec.traffic.ego;
    let mut last_error = String::new();
    let mut planned = None;
    for _ in 0..ROUTE_ATTEMPTS {
        let route = net
            .random_route(&mut rng, needed_m)
            .ok_or_else(|| format!("no route of {needed_m:.0} m in town `{}`", net.name))?;
        let ego = EgoScript {
            route: route_script(&route, 0.0),
            speed_below_limit_pct: rng
                .random_range(ego_spec.speed_below_limit_pct.min()..=ego_spec.speed_below_limit_pct.max()),
            min_gap_m: ego_spec.min_gap_m,
            brake_ahead_m: ego_spec.brake_ahead_m,
            brake_lateral_m: ego_spec.brake_lateral_m,
            courtesy_speed_mps: draw(&mut rng, ego_spec.courtesy_speed_mps),
            courtesy_ahead_m: ego_spec.courtesy_ahead_m,
            courtesy_lateral_m: ego_spec.courtesy_lateral_m,
            courtesy_stop_short_m: ego_spec.courtesy_stop_short_m,
            courtesy_patience_s: draw(&mut rng, ego_spec.courtesy_patience_s),
            courtesy_roll_up: ego_spec.courtesy_roll_up,
        };
        let placed = plan_pedestrians(
            spec,
            net,
            &route,
            peds,
            first_ped,
            archetype_names,
            duration_s,
            (
                basics.seed,
                identity::umbrella_share(weather.params().precipitation_pct),
            ),
            &mut rng,
        )
        .and_then(|pedestrians| {
            plan_vehicles(spec, town, &route, &pedestrians, vehicle_profiles, needed_m, &mut rng)
                .map(|v| (pedestrians, v))
        });
        match placed {
            Ok((pedestrians, vehicles)) => {
                planned = Some((route, ego, pedestrians, vehicles));
                break;
            }
            Err(e) => last_error = e,
        }
    }
    let Some((route, ego, pedestrians, mut vehicles)) = planned else {
        return Err(format!("{last_error} (tried {ROUTE_ATTEMPTS} ego routes)"));
    };
    if let Some(kind) = basics.emergency {
        vehicles.push(plan_emergency(
            spec,
            town,
            &ego.route,
            &pedestrians,
            &vehicles,
            kind,
            needed_m,
            basics.seed,
        )?);
    }
    let cyclists = plan_cyclists(spec, town, &ego.route, &pedestrians, &vehicles, needed_m, basics.seed);
    // Where lights run, the clip's signalised crossing is staged (the ego waits at red in front of it), and the
    // ego's red-light waits count in the crossers' timelines.
    let cruise_mps = ego_cruise_mps(net, &ego);
    let timing = &spec.traffic.signals;
    let lights = timing.enabled && !net.signals.is_empty();
    let (signal_offsets, plans) = if lights {
        let drawn = signal_plans::SignalPlans::new(net, timing, basics.seed);
        let schedule = staging::EgoSchedule::with_lights(cruise_mps, net, &route, &drawn);
        let offsets: Vec<(u32, f64)> =
            staging::staged_offset(net, basics.seed, &route, &pedestrians, (&drawn, &schedule))
                .into_iter()
                .collect();
        let plans = drawn.with_offsets(&offsets);
        (offsets, Some(plans))
    } else {
        (Vec::new(), None)
    };
    let schedule = match &plans {
        Some(plans) => staging::EgoSchedule::with_lights(cruise_mps, net, &route, plans),
        None => staging::EgoSchedule::cruising(cruise_mps),
    };
    // The clip lasts at least as long as its crossers' timelines, up to a cap.
    let needed_s = pedestrians
        .iter()
        .filter_map(|p| timeline_duration_s(p, &schedule, plans.as_ref().map(|plans| (plans, net))))
        .fold(0.0, f64::max);
    let frame_count = lengthened_frame_count(&spec.dataset, basics.frame_count, needed_s);
    let (weather_params, look) = super::look::randomise(&spec.domain_randomisation, weather.params(), basics.seed);

    Ok(ClipScript {
        clip_id,
        seed: basics.seed,
        town: town_ref.name().to_owned(),
        weather: weather.name().to_owned(),
        weather_params,
        split: split_of(spec, town_ref),
        fps,
        frame_count,
        ego,
        vehicles,
        pedestrians,
        cyclists,
        signal_offsets,
        timeline_extension_s: f64::from(frame_count - basics.frame_count) / f64::from(fps),
        labelled_crossers: basics.labelled_crossers,
        look,
        parked_car_share: spec.traffic.parked_cars.share,
    })
}

/// The frames of a clip drawn with `drawn_frames` whose crossers' timelines need `needed_s` seconds: as many as
/// they need, up to `clip_duration_s`'s maximum plus `max_extension_s` (never fewer than drawn).
pub(super) fn lengthened_frame_count(d: &crate::spec::types::Dataset, drawn_frames: u32, needed_s: f64) -> u32 {
    let fps = f64::from(d.fps);
    let cap = ((d.clip_duration_s.max() + d.max_extension_s) * fps).floor() as u32;
    let needed = (needed_s * fps).ceil().min(f64::from(u32::MAX)) as u32;
    needed.min(cap).max(drawn_frames)
}

/// Distance at which the planner estimates that the ego's camera starts to see a pedestrian, metres (the
/// visibility gate admits an adult within about 30–35 m; the simulation decides the real moment).
pub(super) const VIEW_DISTANCE_ESTIMATE_M: f64 = 30.0;

/// Time after a crossing for the crosser to reach the far sidewalk in view, seconds.
pub(super) const CROSSING_MARGIN_S: f64 = 1.5;

/// The ego's cruising speed at its start, m/s.
pub(super) fn ego_cruise_mps(net: &RoadNetwork, ego: &EgoScript) -> f64 {
    let limit = ego
        .route
        .lanes
        .first()
        .and_then(|&l| net.lanes.get(l as usize))
        .map_or(30.0 / 3.6, |l| {
            if l.speed_limit_mps > 0.5 {
                l.speed_limit_mps
            } else {
                30.0 / 3.6
            }
        });
    (limit * (1.0 - ego.speed_below_limit_pct / 100.0)).max(1.0)
}

/// The time a crosser's timeline needs from the clip's start, seconds: until it is in view (the ego, waiting at
/// red lights on the way, comes within view, or it walks to its curb), its time in view, and the crossing. At a
/// signalised crosswalk (where `lights` run) "walk" sets the moment instead: the first after it has reached its
/// curb and checked.
pub(super) fn timeline_duration_s(
    p: &PedestrianScript,
    schedule: &staging::EgoSchedule,
    lights: Option<(&signal_plans::SignalPlans, &RoadNetwork)>,
) -> Option<f64> {
    let in_view_s = p.in_view_before_crossing_s?;
    let crossing = p.crossing.as_ref()?;
    let speed = p.base_speed_mps.max(0.3);
    let curb = crossing.near_curb - crossing.direction * CURB_STANDOFF_M;
    let approach_s = p.spawn.distance(curb) / speed;
    let into_view_s = schedule.time_at(p.ahead_of_ego_m - VIEW_DISTANCE_ESTIMATE_M);
    let signal = lights
        .filter(|_| !p.red_light_violator)
        .and_then(|(plans, net)| Some((plans, net, staging::crossing_signal(net, p)?)));
    let start_s = match signal {
        Some((plans, net, signal)) => staging::walk_start_s(plans, net, signal, approach_s + staging::SIGNAL_CHECK_S),
        None => approach_s.max(into_view_s) + in_view_s,
    };
    Some(start_s + crossing.carriageway_width_m / speed + CROSSING_MARGIN_S)
}

pub(super) fn route_script(route: &Route, start_s_m: f64) -> RouteScript {
    let mut lanes: Vec<u32> = Vec::new();
    for p in &route.points {
        if lanes.last() != Some(&p.lane) {
            lanes.push(p.lane);
        }
    }
    let pose = route.pose_at(start_s_m);
    RouteScript {
        lanes,
        length_m: route.length_m(),
        start_s_m,
        start: pose.pos,
        start_heading_rad: pose.heading_rad,
    }
}

/// The ego's speed while easing off for a waiting pedestrian, as the planner estimates it when placing crossers,
/// m/s (within the default courtesy speeds; the simulation decides the real speed).
pub(super) const COURTESY_SPEED_ESTIMATE_MPS: f64 = 2.5;

/// The distance the ego covers while easing off from its cruising speed, as the planner estimates it, metres.
pub(super) const EGO_BRAKING_ESTIMATE_M: f64 = 10.0;

/// Ego routes tried before a clip is declared infeasible.
pub(super) const ROUTE_ATTEMPTS: usize = 8;
