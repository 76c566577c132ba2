//! Rule tests of the simulation on a hand-built straight road (two driving lanes, a sidewalk on each side) with
//! hand-built clip scripts: gap acceptance waits and crosses, non-closing vehicles do not block, the lookahead
//! stops a crosser before a vehicle, groups cross together, patience expiry leads to a sudden crossing or to
//! abandoning, the ego brakes for a crosser, and nothing interpenetrates; cyclists make crossers wait like cars,
//! brake for walkers, and are overtaken with the clearance only when the oncoming lane is clear.

use glam::DVec2;
use pedsynth::plan::{
    Behaviour, ClipScript, CrosserSource, CrossingScript, CyclistScript, DrivingProfileKind, EgoScript, GroupRef,
    PedestrianScript, Role, RouteScript, SimParams, SpawnPlace, SpeedProfile, VehicleScript,
};
use pedsynth::sim::trace::{ClipTrace, Event, PedState, PedestrianId, VehicleId};
use pedsynth::sim::{self, PED_RADIUS_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M, ttc};
use pedsynth::spec::types::{Body, Spec, WeatherParams};
use pedsynth::world::{LaneType, RoadNetwork};

/// A straight 400 m road along +x from x = −50: lane −1 (y ∈ [−3.5, 0], towards +x), lane 1 (y ∈ [0, 3.5],
/// towards −x), sidewalks y ∈ [−6.5, −3.5] and [3.5, 6.5]; 30 km/h.
const STRAIGHT_ROAD: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="4" name="straight"/>
  <road name="r" length="400" id="1" junction="-1">
    <type s="0" type="town"><speed max="30" unit="km/h"/></type>
    <planView><geometry s="0" x="-50" y="0" hdg="0" length="400"><line/></geometry></planView>
    <lanes>
      <laneSection s="0">
        <left>
          <lane id="2" type="sidewalk" level="false"><width sOffset="0" a="3" b="0" c="0" d="0"/></lane>
          <lane id="1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
        </left>
        <center><lane id="0" type="none" level="false"/></center>
        <right>
          <lane id="-1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
          <lane id="-2" type="sidewalk" level="false"><width sOffset="0" a="3" b="0" c="0" d="0"/></lane>
        </right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>
"#;

fn road() -> RoadNetwork {
    RoadNetwork::from_xodr_str(STRAIGHT_ROAD, "straight.xodr").expect("valid road")
}

fn params() -> SimParams {
    SimParams::from_spec(&Spec::default())
}

fn lane_index(net: &RoadNetwork, lane_id: i32) -> u32 {
    net.lanes
        .iter()
        .position(|l| l.lane_id == lane_id && l.lane_type == LaneType::Driving)
        .expect("lane") as u32
}

/// A route along lane −1 (towards +x) starting at `x`, or lane 1 (towards −x).
fn route(net: &RoadNetwork, towards_plus_x: bool, x: f64) -> RouteScript {
    let lane = lane_index(net, if towards_plus_x { -1 } else { 1 });
    let (start, heading, s) = if towards_plus_x {
        (DVec2::new(x, -1.75), 0.0, x + 50.0)
    } else {
        (DVec2::new(x, 1.75), std::f64::consts::PI, 350.0 - x)
    };
    RouteScript {
        lanes: vec![lane],
        length_m: 400.0,
        start_s_m: s,
        start,
        start_heading_rad: heading,
    }
}

fn ego_at(net: &RoadNetwork, x: f64, speed_below_limit_pct: f64) -> EgoScript {
    EgoScript {
        route: route(net, true, x),
        speed_below_limit_pct,
        min_gap_m: 2.5,
        brake_ahead_m: 15.0,
        brake_lateral_m: 5.0,
        // No courtesy in the rule tests (its own tests switch it on): no easing off, no stopping short.
        courtesy_speed_mps: 100.0,
        courtesy_ahead_m: 35.0,
        courtesy_lateral_m: 10.0,
        courtesy_stop_short_m: 8.0,
        courtesy_patience_s: 0.0,
        courtesy_roll_up: false,
    }
}

fn vehicle(net: &RoadNetwork, id: u32, towards_plus_x: bool, x: f64, pct: f64, ignores_walkers: bool) -> VehicleScript {
    VehicleScript {
        id,
        profile: DrivingProfileKind::Normal,
        speed_difference_pct: pct,
        min_gap_m: 2.0,
        time_headway_s: 1.5,
        ignores_lights: false,
        ignores_walkers,
        route: route(net, towards_plus_x, x),
        emergency: None,
    }
}

/// `p` moved to its curb (where a planned crosser starts), facing the road.
fn at_curb(mut p: PedestrianScript) -> PedestrianScript {
    let c = p.crossing.as_ref().expect("a crosser");
    p.spawn = c.near_curb - c.direction * 0.3;
    p
}

/// A crosser standing on the south sidewalk at `x`, crossing north.
fn crosser(net: &RoadNetwork, id: u32, x: f64, behaviour: Behaviour, source: CrosserSource) -> PedestrianScript {
    let spawn = DVec2::new(x, -5.0);
    let c = net.crossing_at(spawn).expect("a crossing from the sidewalk");
    PedestrianScript {
        id,
        archetype: "casual_person".to_owned(),
        body: Body::Adult,
        base_speed_mps: 1.2,
        hesitation_s: 0.5,
        attention: 0.7,
        ttc_threshold_s: 4.0,
        safety_margin_s: 0.5,
        patience_s: 12.0,
        distracted_at_s: None,
        role: Role::Crosser,
        crosser_source: source,
        behaviour,
        group: None,
        speed_profile: SpeedProfile::Normal,
        spawn_place: SpawnPlace::Sidewalk,
        spawn,
        spawn_heading_rad: c.direction.to_angle(),
        ahead_of_ego_m: 0.0,
        crossing: Some(CrossingScript {
            near_curb: c.near_curb,
            far_curb: c.far_curb,
            end: c.end,
            direction: c.direction,
            carriageway_width_m: c.carriageway_width_m,
        }),
        in_view_before_crossing_s: None,
        step_out_ego_within_m: None,
        step_out_stopped_ego_within_m: None,
        curb_wait_s: None,
        identity: pedsynth::plan::identity::identities(1, id, "casual_person", Body::Adult, 0.0).0,
        child: None,
        red_light_violator: false,
    }
}

/// A clip on the straight road; pedestrians' distance ahead of the ego's start is measured along x (the ego
/// drives towards +x).
fn clip(
    ego: EgoScript,
    vehicles: Vec<VehicleScript>,
    mut pedestrians: Vec<PedestrianScript>,
    seconds: u32,
) -> ClipScript {
    for p in &mut pedestrians {
        p.ahead_of_ego_m = p.spawn.x - ego.route.start.x;
    }
    ClipScript {
        clip_id: "straight-clear_noon-0000".to_owned(),
        seed: 7,
        town: "straight".to_owned(),
        weather: "clear_noon".to_owned(),
        weather_params: WeatherParams::default(),
        split: pedsynth::spec::types::Split::Train,
        fps: 30,
        frame_count: seconds * 30,
        ego,
        vehicles,
        pedestrians,
        cyclists: Vec::new(),
        signal_offsets: Vec::new(),
        timeline_extension_s: 0.0,
        labelled_crossers: None,
        look: Default::default(),
        parked_car_share: 0.0,
    }
}

/// First frame where pedestrian `i` is on a driving lane in a crossing-type state.
fn first_in_road(trace: &ClipTrace, i: usize) -> Option<usize> {
    trace.pedestrians[i]
        .iter()
        .position(|f| f.state.is_crossing() && f.lane_type == Some(LaneType::Driving))
}

fn states(trace: &ClipTrace, i: usize) -> Vec<PedState> {
    let mut out: Vec<PedState> = Vec::new();
    for f in &trace.pedestrians[i] {
        if out.last() != Some(&f.state) {
            out.push(f.state);
        }
    }
    out
}

/// Every (pedestrian, frame) whose ground disc overlaps a vehicle footprint.
fn overlapping_frames(trace: &ClipTrace) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for (k, ped) in trace.pedestrians.iter().enumerate() {
        for (f, pf) in ped.iter().enumerate() {
            let overlaps = std::iter::once(&trace.ego).chain(trace.vehicles.iter()).any(|v| {
                let vf = &v[f];
                ttc::distance_to_box_m(
                    pf.pos.truncate(),
                    vf.pos.truncate(),
                    vf.yaw_rad,
                    VEHICLE_LENGTH_M / 2.0,
                    VEHICLE_WIDTH_M / 2.0,
                ) < PED_RADIUS_M - 1e-9
            });
            if overlaps {
                out.push((k, f));
            }
        }
    }
    out
}

/// No pedestrian disc overlaps a vehicle footprint in any frame, and there is no contact event.
fn assert_no_interpenetration(trace: &ClipTrace) {
    let overlaps = overlapping_frames(trace);
    assert!(
        overlaps.is_empty(),
        "(pedestrian, frame) overlapping a vehicle: {overlaps:?}"
    );
    assert!(
        !trace.events.iter().any(|e| matches!(e, Event::Contact { .. })),
        "contacts: {:?}",
        trace
            .events
            .iter()
            .filter(|e| matches!(e, Event::Contact { .. }))
            .collect::<Vec<_>>()
    );
}

/// The input that makes agents touch, and the proof that the overlap check can fail: a mid-road jaywalker
/// injected 2 m in front of a vehicle at 30 km/h that ignores walkers — it cannot stop in 2 m. Without the
/// contact step of the simulation (step 7: record, push the pedestrian out, stop the vehicle) the footprint
/// would cover the pedestrian; with it the collision is an event and no frame overlaps. The check itself is
/// shown to fail on the same trace with the pedestrian put back under the vehicle.
#[test]
fn a_collision_is_recorded_and_resolved_so_that_nothing_overlaps() {
    let net = road();
    let mut p = crosser(&net, 0, 100.0, Behaviour::MidroadJaywalker, CrosserSource::Allocated);
    let c = p.crossing.clone().expect("crossing");
    // In the south lane (towards +x), on the vehicle's path, 2 m ahead of its front bumper.
    p.spawn = c.near_curb + c.direction * 1.75;
    p.spawn_place = SpawnPlace::DrivingLane;
    p.base_speed_mps = 0.3;
    let front_x = p.spawn.x - 2.0 - VEHICLE_LENGTH_M / 2.0;
    let script = clip(
        ego_at(&net, -45.0, 0.0),
        vec![vehicle(&net, 0, true, front_x, 0.0, true)],
        vec![p],
        4,
    );
    let trace = sim::simulate(&script, &params(), &net);
    let contacts: Vec<&Event> = trace
        .events
        .iter()
        .filter(|e| {
            matches!(
                e,
                Event::Contact {
                    pedestrian: Some(_),
                    ..
                }
            )
        })
        .collect();
    assert!(
        !contacts.is_empty(),
        "the input must make the vehicle touch the pedestrian"
    );
    assert!(
        overlapping_frames(&trace).is_empty(),
        "{:?}",
        overlapping_frames(&trace)
    );
    // The check finds an overlap where there is one.
    let mut broken = trace.clone();
    let f = 10;
    broken.pedestrians[0][f].pos = broken.vehicles[0][f].pos;
    assert_eq!(overlapping_frames(&broken), vec![(0, f)]);
}

/// State-change events agree with the recorded states.
fn assert_events_match_trace(trace: &ClipTrace) {
    for e in &trace.events {
        if let Event::StateChange {
            frame,
            pedestrian,
            from,
            to,
        } = e
        {
            let p = &trace.pedestrians[pedestrian.index()];
            assert_eq!(p[*frame as usize].state, *to);
            assert_eq!(p[*frame as usize - 1].state, *from);
        }
    }
}

#[test]
fn a_closing_vehicle_below_the_threshold_makes_the_pedestrian_wait() {
    let net = road();
    // The ego has passed (so only the gap matters); a traffic vehicle 45 m away closing at ~8.3 m/s: TTC ≈ 5.4 s,
    // below the threshold 4 + 0.5 + 7 / 1.2 ≈ 10.3 s.
    let script = clip(
        ego_at(&net, 160.0, 0.0),
        vec![vehicle(&net, 0, false, 195.0, 0.0, false)],
        vec![crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated)],
        5,
    );
    let trace = sim::simulate(&script, &params(), &net);
    assert_events_match_trace(&trace);
    assert_eq!(first_in_road(&trace, 0), None, "states: {:?}", states(&trace, 0));
    assert!(
        trace.pedestrians[0]
            .iter()
            .any(|f| f.state == PedState::CheckingTraffic)
    );
    assert!(!trace.events.iter().any(|e| matches!(e, Event::CrossingDecision { .. })));
}

#[test]
fn a_gap_above_the_threshold_is_accepted() {
    let net = road();
    // The same vehicle crawling at ~1 m/s: TTC ≈ 45 s.
    let script = clip(
        ego_at(&net, 160.0, 0.0),
        vec![vehicle(&net, 0, false, 195.0, 88.0, false)],
        vec![crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated)],
        14,
    );
    let trace = sim::simulate(&script, &params(), &net);
    assert_events_match_trace(&trace);
    let entered = first_in_road(&trace, 0).expect("crosses");
    let s = states(&trace, 0);
    assert!(s.len() >= 6, "{s:?}");
    assert_eq!(
        &s[..6],
        &[
            PedState::WalkingSidewalk,
            PedState::LookingAround,
            PedState::CheckingTraffic,
            PedState::Hesitating,
            PedState::CrossingRoad,
            PedState::FinishedCrossing
        ],
        "{s:?}"
    );
    let decision = trace
        .events
        .iter()
        .find_map(|e| match e {
            Event::CrossingDecision { frame, .. } => Some(*frame as usize),
            _ => None,
        })
        .expect("decision");
    assert!(decision < entered);
    assert_no_interpenetration(&trace);
}

#[test]
fn a_vehicle_that_is_not_closing_does_not_block() {
    let net = road();
    // A vehicle 10 m past the pedestrian, driving away at 8.3 m/s (the ego too).
    let script = clip(
        ego_at(&net, 170.0, 0.0),
        vec![vehicle(&net, 0, true, 160.0, 0.0, false)],
        vec![crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated)],
        8,
    );
    let trace = sim::simulate(&script, &params(), &net);
    assert!(first_in_road(&trace, 0).is_some(), "states: {:?}", states(&trace, 0));
    assert_no_interpenetration(&trace);
}

#[test]
fn an_allocated_crosser_commits_when_the_ego_enters_the_decision_window() {
    let net = road();
    // The ego approaches at 8.3 m/s from 60 m. Outside the window the crosser waits (the ego's TTC is far
    // below the gap threshold); once the ego is inside the 10–40 m window it commits (the paper's rule) and the
    // ego brakes for it.
    let script = clip(
        ego_at(&net, 90.0, 0.0),
        vec![],
        vec![crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated)],
        14,
    );
    let trace = sim::simulate(&script, &params(), &net);
    assert_events_match_trace(&trace);
    let decision = trace
        .events
        .iter()
        .find_map(|e| {
            if let Event::CrossingDecision { frame, .. } = e {
                Some(*frame as usize)
            } else {
                None
            }
        })
        .expect("decides to cross");
    let gap = 150.0 - trace.ego[decision].pos.x;
    assert!((10.0..=40.5).contains(&gap), "decided with the ego {gap} m away");
    let entered = first_in_road(&trace, 0).expect("crosses");
    let ego_x = trace.ego[entered].pos.x;
    assert!(
        ego_x < 150.0,
        "entered the road in front of the ego (ego at x = {ego_x})"
    );
    assert!(
        trace.ego.iter().any(|f| f.accel_mps2 < -1.0),
        "the ego brakes for the crosser"
    );
    assert_no_interpenetration(&trace);
}

#[test]
fn a_crosser_facing_another_closing_vehicle_inside_the_window_waits_for_it() {
    let net = road();
    // The ego is inside the window, but a traffic vehicle in the far lane is 12 m away closing at ~8.3 m/s
    // (TTC ≈ 1.4 s): the crosser lets it pass before stepping out.
    let script = clip(
        ego_at(&net, 120.0, 60.0),
        vec![vehicle(&net, 0, false, 162.0, 0.0, false)],
        vec![at_curb(crosser(
            &net,
            0,
            150.0,
            Behaviour::Normal,
            CrosserSource::Allocated,
        ))],
        10,
    );
    let trace = sim::simulate(&script, &params(), &net);
    // Without the wait it would decide at once (it starts at the curb with the ego inside the window).
    let decision = trace
        .events
        .iter()
        .find_map(|e| {
            if let Event::CrossingDecision { frame, .. } = e {
                Some(*frame as usize)
            } else {
                None
            }
        })
        .expect("decides to cross");
    let other_x = trace.vehicles[0][decision].pos.x;
    assert!(
        other_x < 152.0,
        "decided only once the other vehicle was (nearly) past: it is at x = {other_x}"
    );
    let entered = first_in_road(&trace, 0).expect("crosses");
    assert!(
        trace.vehicles[0][entered].pos.x < 150.0,
        "stepped out after the other vehicle passed"
    );
    assert_no_interpenetration(&trace);
}

#[test]
fn the_lookahead_stops_a_crosser_before_a_vehicle_in_its_path() {
    let net = road();
    // A mid-road jaywalker in the south lane walking north; a vehicle that ignores walkers comes along the north
    // lane. The probes see it within 3 m and the pedestrian halts (pause or retreat) until it has passed.
    let mut p = crosser(&net, 0, 150.0, Behaviour::MidroadJaywalker, CrosserSource::Allocated);
    let c = p.crossing.clone().expect("crossing");
    p.spawn = c.near_curb + c.direction * 2.0;
    p.spawn_place = SpawnPlace::DrivingLane;
    let script = clip(
        ego_at(&net, -45.0, 0.0),
        vec![vehicle(&net, 0, false, 170.0, 0.0, true)],
        vec![p],
        8,
    );
    let trace = sim::simulate(&script, &params(), &net);
    assert_events_match_trace(&trace);
    let s = states(&trace, 0);
    assert_eq!(s[0], PedState::Jaywalking);
    assert!(
        s.contains(&PedState::PausingMidCross) || s.contains(&PedState::Retreat),
        "states: {s:?}"
    );
    assert!(trace.events.iter().any(|e| matches!(
        e,
        Event::Conflict {
            vehicle: VehicleId::Traffic(0),
            ..
        }
    )));
    assert!(matches!(
        trace.events[0],
        Event::CrossingDecision {
            frame: 0,
            pedestrian: PedestrianId(0)
        }
    ));
    assert_no_interpenetration(&trace);
}

#[test]
fn the_ego_brakes_for_a_pedestrian_crossing_in_its_path() {
    let net = road();
    let mut p = crosser(&net, 0, 60.0, Behaviour::MidroadJaywalker, CrosserSource::Allocated);
    let c = p.crossing.clone().expect("crossing");
    p.spawn = c.near_curb + c.direction * 1.5;
    p.spawn_place = SpawnPlace::DrivingLane;
    p.base_speed_mps = 0.6;
    let script = clip(ego_at(&net, 40.0, 0.0), vec![], vec![p], 8);
    let trace = sim::simulate(&script, &params(), &net);
    let min_speed = trace.ego.iter().map(|f| f.speed_mps).fold(f64::INFINITY, f64::min);
    assert!(min_speed < 2.0, "ego never slowed down: {min_speed}");
    assert!(trace.ego.iter().any(|f| f.accel_mps2 < -2.0));
    assert!(first_in_road(&trace, 0).is_some());
    assert_no_interpenetration(&trace);
}

#[test]
fn groups_cross_together() {
    let net = road();
    let mut leader = crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated);
    let mut follower = crosser(&net, 1, 151.8, Behaviour::Normal, CrosserSource::Allocated);
    follower.base_speed_mps = 1.0;
    follower.hesitation_s = 1.5;
    leader.group = Some(GroupRef { group_id: 0, leader: 0 });
    follower.group = Some(GroupRef { group_id: 0, leader: 0 });
    // The ego has already passed.
    let script = clip(ego_at(&net, 170.0, 0.0), vec![], vec![leader, follower], 12);
    let trace = sim::simulate(&script, &params(), &net);
    assert_events_match_trace(&trace);
    for f in 1..trace.frame_count as usize {
        assert_eq!(
            trace.pedestrians[0][f].state, trace.pedestrians[1][f].state,
            "states differ at frame {f}"
        );
    }
    let (a, b) = (
        first_in_road(&trace, 0).expect("leader crosses"),
        first_in_road(&trace, 1).expect("follower crosses"),
    );
    assert!(a.abs_diff(b) <= 3, "entered the road at frames {a} and {b}");
    // Same decision frame.
    let decisions: Vec<_> = trace
        .events
        .iter()
        .filter_map(|e| match e {
            Event::CrossingDecision { frame, .. } => Some(*frame),
            _ => None,
        })
        .collect();
    assert_eq!(decisions.len(), 2);
    assert_eq!(decisions[0], decisions[1]);
    // The follower never outruns its own speed by more than the width ratio allows.
    let max_follower_speed = trace.pedestrians[1]
        .iter()
        .filter(|f| f.state == PedState::CrossingRoad)
        .map(|f| f.velocity.length())
        .fold(0.0, f64::max);
    assert!(max_follower_speed <= 1.0 * 1.05, "{max_follower_speed}");
}

fn patience_clip(net: &RoadNetwork, sudden_probability: f64) -> (ClipTrace, ClipScript) {
    let mut p = crosser(net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated);
    p.patience_s = 2.0;
    p.ttc_threshold_s = 100.0;
    // A vehicle crawling towards the pedestrian keeps the TTC finite but below 100 s.
    let script = clip(
        ego_at(net, 160.0, 0.0),
        vec![vehicle(net, 0, false, 200.0, 88.0, false)],
        vec![p],
        10,
    );
    let mut params = params();
    params.patience.sudden_crossing_probability = sudden_probability;
    (sim::simulate(&script, &params, net), script)
}

#[test]
fn patience_expiry_leads_to_a_sudden_crossing() {
    let net = road();
    let (trace, _) = patience_clip(&net, 1.0);
    assert_events_match_trace(&trace);
    assert!(
        trace.events.iter().any(|e| matches!(
            e,
            Event::PatienceExpired {
                sudden_crossing: true,
                ..
            }
        )),
        "{:?}",
        states(&trace, 0)
    );
    let entered = first_in_road(&trace, 0).expect("crosses suddenly");
    assert_eq!(trace.pedestrians[0][entered].state, PedState::SuddenCrossing);
}

#[test]
fn patience_expiry_can_abandon_the_attempt() {
    let net = road();
    let (trace, _) = patience_clip(&net, 0.0);
    assert!(trace.events.iter().any(|e| matches!(
        e,
        Event::PatienceExpired {
            sudden_crossing: false,
            ..
        }
    )));
    assert_eq!(first_in_road(&trace, 0), None);
    assert!(
        trace.pedestrians[0]
            .iter()
            .all(|f| f.lane_type != Some(LaneType::Driving))
    );
    assert_eq!(
        trace.pedestrians[0].last().expect("frames").state,
        PedState::WalkingSidewalk
    );
}

#[test]
fn a_baseline_crosser_stops_and_checks_like_carla() {
    let net = road();
    // No decision window and no TTC threshold: it crosses once nothing is within 6 m or about to arrive, even
    // with the ego approaching 50 m away.
    let script = clip(
        ego_at(&net, 100.0, 50.0),
        vec![],
        vec![crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Baseline)],
        10,
    );
    let trace = sim::simulate(&script, &params(), &net);
    let entered = first_in_road(&trace, 0).expect("crosses");
    assert!(trace.ego[entered].pos.x < 150.0, "crossed in front of the ego");
    assert_no_interpenetration(&trace);
}

#[test]
fn non_crossers_stay_on_the_sidewalk_and_sudden_crossers_go_without_checking() {
    let net = road();
    let mut walker = crosser(&net, 0, 100.0, Behaviour::None, CrosserSource::None);
    walker.role = Role::NonCrosser;
    walker.crossing = None;
    walker.spawn_heading_rad = 0.0;
    let sudden = crosser(&net, 1, 150.0, Behaviour::Sudden, CrosserSource::Allocated);
    let script = clip(ego_at(&net, 80.0, 0.0), vec![], vec![walker, sudden], 10);
    let trace = sim::simulate(&script, &params(), &net);
    assert!(
        trace.pedestrians[0]
            .iter()
            .all(|f| f.lane_type == Some(LaneType::Sidewalk))
    );
    assert!(
        trace.pedestrians[0].last().expect("frames").pos.x > 105.0,
        "the walker walks"
    );
    let s = states(&trace, 1);
    assert_eq!(&s[..2], &[PedState::WalkingSidewalk, PedState::SuddenCrossing], "{s:?}");
    // Triggered by the ego entering the 40 m window.
    let decision = trace
        .events
        .iter()
        .find_map(|e| match e {
            Event::CrossingDecision {
                frame,
                pedestrian: PedestrianId(1),
            } => Some(*frame as usize),
            _ => None,
        })
        .expect("decision");
    let gap = 150.0 - trace.ego[decision].pos.x;
    assert!(gap <= 40.5 && gap > 30.0, "decided with the ego {gap} m away");
    assert_no_interpenetration(&trace);
}

#[test]
fn vehicles_follow_without_passing_through_each_other() {
    let net = road();
    // A slow vehicle ahead of the ego in the same lane.
    let script = clip(
        ego_at(&net, 0.0, 0.0),
        vec![vehicle(&net, 0, true, 25.0, 70.0, false)],
        vec![],
        15,
    );
    let trace = sim::simulate(&script, &params(), &net);
    for f in 0..trace.frame_count as usize {
        let gap = trace.vehicles[0][f].pos.x - trace.ego[f].pos.x - VEHICLE_LENGTH_M;
        assert!(gap > 1.0, "gap {gap} at frame {f}");
    }
    assert!(!trace.events.iter().any(|e| matches!(
        e,
        Event::Contact {
            vehicle: VehicleId::Ego,
            ..
        }
    )));
    // It ends up following at about the leader's speed.
    let last = trace.ego.last().expect("frames");
    assert!((last.speed_mps - trace.vehicles[0].last().expect("frames").speed_mps).abs() < 0.5);
}

/// The first annotated frame of pedestrian `id` (it passes the visibility gate of the default camera).
fn first_annotated(script: &ClipScript, trace: &ClipTrace, net: &RoadNetwork) -> Option<usize> {
    let spec = Spec::default();
    let camera = pedsynth::sim::rig::Camera::from_spec(&spec.sensors.rgb);
    let obs = pedsynth::sensors::annotate::annotate(script, trace, &spec.annotations, &camera, net);
    obs.rows.iter().find(|r| r.pedestrian == 0).map(|r| r.frame as usize)
}

/// A crosser at its curb with the ego 40 m away and slow (1.7 m/s): without a timeline it decides at once;
/// with `in_view_before_crossing_s` = 4 s it steps out only after the camera has seen it for 4 s (measured
/// with the annotation's visibility gate, which the simulation's view estimate approximates).
#[test]
fn a_crosser_steps_out_only_after_the_camera_has_seen_it_for_its_planned_time() {
    let net = road();
    let run = |in_view_s: Option<f64>| {
        let mut p = at_curb(crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated));
        p.in_view_before_crossing_s = in_view_s;
        let script = clip(ego_at(&net, 110.0, 80.0), vec![], vec![p], 12);
        let trace = sim::simulate(&script, &params(), &net);
        assert_no_interpenetration(&trace);
        let seen = first_annotated(&script, &trace, &net).expect("the camera sees it");
        let entered = first_in_road(&trace, 0).expect("crosses");
        (entered as f64 - seen as f64) / 30.0
    };
    let without = run(None);
    let with = run(Some(4.0));
    assert!(
        without < 2.5,
        "without a timeline it steps out {without:.2} s after it is first seen"
    );
    assert!(
        (3.8..6.0).contains(&with),
        "with a 4 s timeline it steps out {with:.2} s after it is first seen"
    );
}

/// A hard negative walks to its curb, stops and checks traffic for its planned wait, and walks on without
/// ever stepping onto the road.
#[test]
fn a_hard_negative_waits_at_the_curb_and_walks_on_without_crossing() {
    let net = road();
    let mut p = crosser(&net, 0, 150.0, Behaviour::HardNegative, CrosserSource::None);
    p.role = Role::NonCrosser;
    p.curb_wait_s = Some(5.0);
    let script = clip(ego_at(&net, 0.0, 0.0), vec![], vec![p], 15);
    let trace = sim::simulate(&script, &params(), &net);
    assert!(
        trace.pedestrians[0]
            .iter()
            .all(|f| f.lane_type != Some(LaneType::Driving)),
        "it never steps onto the road"
    );
    let s = states(&trace, 0);
    assert!(s.contains(&PedState::CheckingTraffic), "{s:?}");
    assert_eq!(s.last(), Some(&PedState::WalkingSidewalk), "{s:?}");
    let checking_s = trace.pedestrians[0]
        .iter()
        .filter(|f| f.state == PedState::CheckingTraffic)
        .count() as f64
        / 30.0;
    assert!(
        (4.9..5.5).contains(&checking_s),
        "checked traffic for {checking_s:.2} s"
    );
    let near_curb = trace.pedestrians[0].iter().map(|f| f.pos.y).fold(f64::MIN, f64::max);
    assert!(near_curb > -3.9, "it reached the curb (y = {near_curb:.2})");
}

/// The ego eases off for a pedestrian waiting at the curb ahead, stops short of it, and drives on once it has
/// yielded for its patience (counted from when the waiting pedestrian enters its courtesy zone); without
/// courtesy it keeps its speed.
#[test]
fn the_ego_eases_off_and_stops_short_for_a_pedestrian_waiting_at_the_curb() {
    let net = road();
    let run = |courtesy: bool| {
        let mut p = at_curb(crosser(&net, 0, 150.0, Behaviour::HardNegative, CrosserSource::None));
        p.role = Role::NonCrosser;
        p.curb_wait_s = Some(30.0);
        let mut ego = ego_at(&net, 60.0, 0.0);
        if courtesy {
            ego.courtesy_speed_mps = 2.5;
            ego.courtesy_patience_s = 12.0;
        }
        let script = clip(ego, vec![], vec![p], 30);
        sim::simulate(&script, &params(), &net)
    };
    let plain = run(false);
    let slowest = |t: &ClipTrace| {
        t.ego
            .iter()
            .filter(|f| f.pos.x < 150.0)
            .map(|f| f.speed_mps)
            .fold(f64::MAX, f64::min)
    };
    assert!(
        slowest(&plain) > 7.0,
        "without courtesy: slowest {:.2} m/s",
        slowest(&plain)
    );
    let kind = run(true);
    // It eases off from the moment the waiting pedestrian is 35 m ahead (its centre's distance), with a 1.5 s
    // response: 5 s later it is within 0.3 m/s of its courtesy speed, until it has passed the pedestrian.
    let zone = kind.ego.iter().position(|f| f.pos.x >= 115.0).expect("zone");
    let eased: Vec<f64> = kind.ego[zone + 150..]
        .iter()
        .take_while(|f| f.pos.x < 150.0)
        .map(|f| f.speed_mps)
        .collect();
    assert!(eased.len() > 30);
    let fastest = eased.iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(fastest <= 2.5 + 0.3, "eased to only {fastest:.2} m/s");
    // It stops short of the pedestrian, about 8 m before.
    let stop = kind.ego.iter().position(|f| f.speed_mps < 0.1).expect("it stops");
    let gap_m = 150.0 - (kind.ego[stop].pos.x + VEHICLE_LENGTH_M / 2.0);
    assert!((5.0..12.0).contains(&gap_m), "stopped {gap_m:.1} m short");
    // Then, its patience spent (12 s after the pedestrian entered the zone), it drives on past the pedestrian,
    // which still waits.
    let moves_on = stop
        + kind.ego[stop..]
            .iter()
            .position(|f| f.speed_mps > 0.5)
            .expect("drives on");
    let yielded_s = (moves_on - zone) as f64 / 30.0;
    assert!((11.5..13.5).contains(&yielded_s), "yielded for {yielded_s:.2} s");
    assert!(kind.ego.last().expect("frames").pos.x > 155.0, "drives on");
    assert_eq!(kind.pedestrians[0][moves_on].state, PedState::CheckingTraffic);
    assert_no_interpenetration(&kind);
}

/// A crosser that waits at its curb for the ego to come within 6 m (`crossing.scenario.crosser_ego_within_m`)
/// and an ego that yields to it, stopping 8 m short. Once the ego has stopped within 12 m
/// (`crossing.scenario.crosser_stopped_ego_within_m`) the crosser goes in front of it (before that rule neither moved until the ego's patience ran out: 2,121 of 3,933 planned crossers
/// of PedSynth++ with the JAAD profile never crossed). With `traffic.ego.courtesy_roll_up` the ego rolls up near
/// enough instead, and the crosser steps out within its distance, in front of the still-moving ego.
#[test]
fn a_yielding_ego_rolls_up_to_a_crosser_that_waits_for_it_to_come_near() {
    let net = road();
    let run = |roll_up: bool, stopped_ego_within_m: Option<f64>| {
        let mut p = at_curb(crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated));
        p.step_out_ego_within_m = Some(6.0);
        p.step_out_stopped_ego_within_m = stopped_ego_within_m;
        let mut ego = ego_at(&net, 60.0, 0.0);
        ego.courtesy_speed_mps = 2.5;
        ego.courtesy_patience_s = 30.0;
        ego.courtesy_roll_up = roll_up;
        let script = clip(ego, vec![], vec![p], 30);
        let trace = sim::simulate(&script, &params(), &net);
        assert_no_interpenetration(&trace);
        trace
    };
    // Without the roll-up (`traffic.ego.courtesy_roll_up`, off by default) the ego stops short and, without the
    // stopped-ego rule, the two wait for each other.
    let waits = run(false, None);
    let stop = waits.ego.iter().position(|f| f.speed_mps < 0.1).expect("it stops");
    let gap_m = 150.0 - (waits.ego[stop].pos.x + VEHICLE_LENGTH_M / 2.0);
    assert!(
        (5.0..12.0).contains(&gap_m),
        "without the roll-up it stops {gap_m:.1} m short"
    );
    assert_eq!(first_in_road(&waits, 0), None, "without either rule the crosser waits");
    // With the stopped-ego rule the crosser goes in front of the stopped ego.
    let goes = run(false, Some(12.0));
    let stop = goes.ego.iter().position(|f| f.speed_mps < 0.1).expect("it stops");
    let entered = first_in_road(&goes, 0).expect("the crosser crosses once the ego has stopped");
    assert!(entered > stop, "it steps out only after the ego has stopped");
    let dist_m = (goes.ego[entered].pos - goes.pedestrians[0][entered].pos)
        .truncate()
        .length();
    assert!(
        dist_m > 6.0 + 0.5 && dist_m <= 12.0,
        "the stopped ego is beyond the crosser's 6 m and within 12 m: {dist_m:.1} m"
    );
    assert!(
        goes.ego[stop..=entered].iter().all(|f| f.speed_mps < 0.3),
        "the ego stays stopped until the crosser steps out"
    );
    let entered_s = entered as f64 / 30.0;
    assert!(
        entered_s < 25.0,
        "it stepped out at {entered_s:.1} s, before the ego's patience ran out"
    );
    // Beyond the rule's distance the stopped ego does not release it.
    assert_eq!(
        first_in_road(&run(false, Some(dist_m - 2.0)), 0),
        None,
        "a stopped ego too far away"
    );

    let near = run(true, None);
    let entered = first_in_road(&near, 0).expect("the crosser crosses in front of the ego");
    let ego = &near.ego[entered];
    let dist_m = (ego.pos - near.pedestrians[0][entered].pos).truncate().length();
    assert!(dist_m <= 6.0 + 0.5, "it stepped out with the ego {dist_m:.1} m away");
    assert!(
        ego.pos.x + VEHICLE_LENGTH_M / 2.0 < 150.0 - 1.0,
        "the ego is still short of it"
    );
    let entered_s = entered as f64 / 30.0;
    assert!(
        entered_s < 25.0,
        "it stepped out at {entered_s:.1} s, before the ego's patience ran out"
    );
}

fn emergency(net: &RoadNetwork, id: u32, towards_plus_x: bool, x: f64) -> VehicleScript {
    VehicleScript {
        emergency: Some(pedsynth::plan::EmergencyKind::Ambulance),
        ..vehicle(net, id, towards_plus_x, x, -30.0, false)
    }
}

#[test]
fn vehicles_pull_over_and_stop_for_an_oncoming_emergency_vehicle_which_drives_above_the_limit() {
    let net = road();
    // The ego (towards +x) and a car behind it meet an ambulance coming the other way at 1.3 × the limit.
    let script = clip(
        ego_at(&net, 0.0, 0.0),
        vec![
            vehicle(&net, 0, true, -20.0, 0.0, false),
            emergency(&net, 1, false, 150.0),
        ],
        vec![],
        14,
    );
    let trace = sim::simulate(&script, &params(), &net);
    let limit = 30.0 / 3.6;
    let ev = &trace.vehicles[1];
    let ev_speed = ev.iter().map(|f| f.speed_mps).fold(0.0, f64::max);
    assert!((ev_speed - 1.3 * limit).abs() < 0.1, "ambulance at {ev_speed} m/s");
    assert!(ev.iter().all(|f| !f.yielding), "the ambulance yields to nobody");
    // Where they pass each other, the ego and the car behind it stand (or nearly); before the ambulance came
    // near they drove at the limit, and after it passed they drive on.
    let pass = (0..trace.ego.len())
        .find(|&f| ev[f].pos.x < trace.ego[f].pos.x)
        .expect("the ambulance passes the ego");
    for (name, frames) in [("ego", &trace.ego), ("car behind", &trace.vehicles[0])] {
        assert!(frames[0].speed_mps > 0.95 * limit, "{name} starts at the limit");
        assert!(
            frames[pass].speed_mps < 0.5,
            "{name} at {} m/s when passed",
            frames[pass].speed_mps
        );
        assert!(frames[pass].yielding, "{name} yields when passed");
        let after = frames.len() - 1;
        assert!(
            !frames[after].yielding && frames[after].speed_mps > 2.0,
            "{name} drives on"
        );
        // It pulled over to the right (its lane's centre is y = −1.75), and back after.
        assert!(
            frames[pass].pos.y < -1.75 - 0.3,
            "{name} at y {} when passed",
            frames[pass].pos.y
        );
        assert!(
            (frames[after].pos.y + 1.75).abs() < 0.05,
            "{name} back at y {}",
            frames[after].pos.y
        );
        // It began to yield only once the ambulance was within 70 m and closing.
        let first = frames.iter().position(|f| f.yielding).expect("yields");
        let d = (ev[first - 1].pos - frames[first - 1].pos).truncate().length();
        assert!(d < 70.0 + 1.0 && d > 60.0, "{name} began to yield {d:.1} m away");
    }
    assert_no_interpenetration(&trace);
}

#[test]
fn pedestrians_hold_at_the_curb_for_a_siren_and_cross_after_it_passes() {
    let net = road();
    // The ego has passed the crosser; a vehicle comes along the far lane towards it. With a small TTC threshold
    // the gap would be accepted at once; a siren holds the crosser until the vehicle has passed.
    let run = |siren: bool| {
        let mut c = crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated);
        c.ttc_threshold_s = 0.5;
        c.safety_margin_s = 0.0;
        let v = if siren {
            emergency(&net, 0, false, 240.0)
        } else {
            vehicle(&net, 0, false, 240.0, -30.0, false)
        };
        let script = clip(ego_at(&net, 160.0, 0.0), vec![v], vec![c], 20);
        sim::simulate(&script, &params(), &net)
    };
    let decision = |t: &ClipTrace| {
        t.events.iter().find_map(|e| match e {
            Event::CrossingDecision { frame, .. } => Some(*frame as usize),
            _ => None,
        })
    };
    let (plain, with_siren) = (run(false), run(true));
    let early = decision(&plain).expect("crosses without a siren");
    let held = decision(&with_siren).expect("crosses after the siren");
    let v = &with_siren.vehicles[0];
    let passed = (0..v.len())
        .find(|&f| v[f].pos.x < 150.0)
        .expect("the ambulance passes the crossing");
    assert!(
        early < passed,
        "without a siren it goes first (frame {early}, vehicle past at {passed})"
    );
    assert!(
        held >= passed,
        "with a siren it waits until it has passed: decided at {held}, passed at {passed}"
    );
    assert_no_interpenetration(&with_siren);
}

/// Simulation parameters with cyclists on (`traffic.cyclists.per_clip` above 0).
fn cycling_params() -> SimParams {
    let mut spec = Spec::default();
    spec.traffic.cyclists.per_clip = pedsynth::spec::types::CountRange(1, 1);
    SimParams::from_spec(&spec)
}

fn cyclist(net: &RoadNetwork, id: u32, towards_plus_x: bool, x: f64, speed_mps: f64) -> CyclistScript {
    CyclistScript {
        id,
        route: route(net, towards_plus_x, x),
        speed_mps,
        edge_offset_m: 0.8,
        ignores_lights: false,
        rider: pedsynth::plan::identity::rider_identity(1, id),
        bike_rgb: [200, 30, 30],
    }
}

/// The distance between two footprints (centre, yaw, half extents), metres: the nearest points include a
/// corner of one of the boxes.
fn footprint_gap_m(a: (DVec2, f64, DVec2), b: (DVec2, f64, DVec2)) -> f64 {
    let corners = |(c, yaw, h): (DVec2, f64, DVec2)| {
        let (f, l) = (DVec2::from_angle(yaw) * h.x, DVec2::from_angle(yaw).perp() * h.y);
        [c + f + l, c + f - l, c - f + l, c - f - l]
    };
    let to = |p: DVec2, (c, yaw, h): (DVec2, f64, DVec2)| ttc::distance_to_box_m(p, c, yaw, h.x, h.y);
    let ab = corners(a).into_iter().map(|p| to(p, b)).fold(f64::INFINITY, f64::min);
    let ba = corners(b).into_iter().map(|p| to(p, a)).fold(f64::INFINITY, f64::min);
    ab.min(ba)
}

const CAR_HALF: DVec2 = DVec2::new(VEHICLE_LENGTH_M / 2.0, VEHICLE_WIDTH_M / 2.0);
const BIKE_HALF: DVec2 = DVec2::new(0.875, 0.325);

/// A pedestrian checks a cyclist as it checks a car: one closing at 5.5 m/s from 35 m (TTC ≈ 6.4 s, below the
/// threshold of ≈ 10.3 s) keeps it at the curb; it crosses once the cyclist has passed. Without the cyclist the
/// same crosser steps out seconds earlier.
#[test]
fn a_crosser_waits_for_a_closing_cyclist_as_for_a_car() {
    let net = road();
    let base = clip(
        ego_at(&net, 160.0, 0.0),
        Vec::new(),
        vec![crosser(&net, 0, 150.0, Behaviour::Normal, CrosserSource::Allocated)],
        20,
    );
    let alone = sim::simulate(&base, &cycling_params(), &net);
    let entered_alone = first_in_road(&alone, 0).expect("crosses without the cyclist");
    let mut script = base.clone();
    script.cyclists = vec![cyclist(&net, 0, false, 185.0, 5.5)];
    let trace = sim::simulate(&script, &cycling_params(), &net);
    assert_events_match_trace(&trace);
    let entered = first_in_road(&trace, 0).expect("crosses after the cyclist");
    let passed = trace.cyclists[0]
        .iter()
        .position(|f| f.pos.x < 150.0 - 0.3)
        .expect("the cyclist passes the crossing");
    assert!(
        entered > passed && entered > entered_alone + 30,
        "entered at frame {entered} (alone: {entered_alone}); the cyclist passed at frame {passed}"
    );
    let min_gap = trace.pedestrians[0]
        .iter()
        .zip(&trace.cyclists[0])
        .map(|(p, c)| ttc::distance_to_box_m(p.pos.truncate(), c.pos.truncate(), c.yaw_rad, 0.875, 0.325))
        .fold(f64::INFINITY, f64::min);
    assert!(min_gap > PED_RADIUS_M, "the two kept apart: {min_gap} m");
}

/// A cyclist rides near its lane's right edge at its own speed, and brakes for a pedestrian stepping into its
/// path without touching it (and the braking is recorded).
#[test]
fn a_cyclist_rides_at_the_lane_edge_and_brakes_for_a_sudden_crosser() {
    let net = road();
    let mut script = clip(
        ego_at(&net, 200.0, 0.0),
        Vec::new(),
        vec![crosser(&net, 0, 150.0, Behaviour::Sudden, CrosserSource::Allocated)],
        12,
    );
    script.cyclists = vec![cyclist(&net, 0, true, 138.0, 5.0)];
    let trace = sim::simulate(&script, &cycling_params(), &net);
    assert_events_match_trace(&trace);
    let first = trace.cyclists[0][0];
    // Lane −1 spans y ∈ [−3.5, 0]; 0.8 m from its right edge is y = −2.7.
    assert!(
        (first.pos.y + 2.7).abs() < 1e-6 && (first.speed_mps - 5.0).abs() < 1e-9,
        "{first:?}"
    );
    assert!(first_in_road(&trace, 0).is_some(), "the crosser crosses");
    let slowest = trace.cyclists[0]
        .iter()
        .map(|f| f.speed_mps)
        .fold(f64::INFINITY, f64::min);
    assert!(slowest < 2.5, "the cyclist slowed to {slowest} m/s for the crosser");
    assert!(
        trace.events.iter().any(|e| matches!(
            e,
            Event::CyclistYielded {
                cyclist: 0,
                pedestrian: PedestrianId(0),
                swerved: false,
                ..
            }
        )),
        "{:?}",
        trace.events
    );
    assert!(!trace.events.iter().any(|e| matches!(e, Event::Contact { .. })));
}

/// The ego catches up with a slower cyclist: with the oncoming lane clear it moves out and passes with the
/// spec's clearance (1.5 m side to side, measured on the trace's footprints); with a car coming the other way
/// it stays behind the cyclist until that car has passed.
#[test]
fn vehicles_overtake_a_cyclist_with_clearance_only_when_the_oncoming_lane_is_clear() {
    let net = road();
    let clearance = Spec::default().traffic.cyclists.overtaking_clearance_m;
    let mut script = clip(ego_at(&net, 0.0, 0.0), Vec::new(), Vec::new(), 20);
    script.cyclists = vec![cyclist(&net, 0, true, 30.0, 3.0)];
    let trace = sim::simulate(&script, &cycling_params(), &net);
    let gap = |f: usize| {
        let (e, c) = (&trace.ego[f], &trace.cyclists[0][f]);
        footprint_gap_m(
            (e.pos.truncate(), e.yaw_rad, CAR_HALF),
            (c.pos.truncate(), c.yaw_rad, BIKE_HALF),
        )
    };
    let passed = (0..trace.ego.len())
        .find(|&f| trace.ego[f].pos.x - VEHICLE_LENGTH_M / 2.0 > trace.cyclists[0][f].pos.x + 0.875)
        .expect("the ego passes the cyclist");
    let min_gap = (0..trace.ego.len()).map(gap).fold(f64::INFINITY, f64::min);
    assert!(min_gap >= clearance - 1e-6, "closest approach {min_gap} m");
    let overtakes: Vec<f64> = trace
        .events
        .iter()
        .filter_map(|e| match e {
            Event::OvertookCyclist {
                vehicle: VehicleId::Ego,
                cyclist: 0,
                min_clearance_m,
                ..
            } => Some(*min_clearance_m),
            _ => None,
        })
        .collect();
    assert_eq!(overtakes.len(), 1, "{:?}", trace.events);
    assert!(
        (overtakes[0] - clearance).abs() < 0.05,
        "recorded clearance {}",
        overtakes[0]
    );
    // The ego is back in its lane's centre (y = −1.75) some seconds after passing.
    let end = trace.ego.last().expect("frames");
    assert!(
        (end.pos.y + 1.75).abs() < 0.05 && passed < trace.ego.len() - 60,
        "{end:?}"
    );

    // The same with a car coming the other way: the ego stays in its lane until that car has passed it.
    let mut script = clip(
        ego_at(&net, 0.0, 0.0),
        vec![vehicle(&net, 0, false, 110.0, 0.0, false)],
        Vec::new(),
        20,
    );
    script.cyclists = vec![cyclist(&net, 0, true, 30.0, 3.0)];
    let trace = sim::simulate(&script, &cycling_params(), &net);
    let moved_out = (0..trace.ego.len())
        .find(|&f| trace.ego[f].pos.y > -1.75 + 0.05)
        .expect("the ego overtakes after the car has passed");
    assert!(
        trace.vehicles[0][moved_out].pos.x < trace.ego[moved_out].pos.x,
        "moved out at frame {moved_out} before the oncoming car passed"
    );
    let min_gap = (0..trace.ego.len())
        .map(|f| {
            let (e, c) = (&trace.ego[f], &trace.cyclists[0][f]);
            footprint_gap_m(
                (e.pos.truncate(), e.yaw_rad, CAR_HALF),
                (c.pos.truncate(), c.yaw_rad, BIKE_HALF),
            )
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        min_gap > 1.0,
        "the ego kept its distance behind the cyclist: {min_gap} m"
    );
    assert!(!trace.events.iter().any(|e| matches!(e, Event::Contact { .. })));
}
