//! The simulation engine: a deterministic fixed-step simulation of one clip script (the ego, traffic and the
//! pedestrians' 12-state behaviour machine), producing a [`ClipTrace`].
//!
//! # Step order
//!
//! The time step is `dt = 1 / fps`; simulated time is the only clock. Frame `f` records the state at time
//! `f · dt`; then step `f` advances it to `(f + 1) · dt`:
//!
//! 1. **record** frame `f` (every agent's pose, velocity, state, lane type);
//! 2. **perceive**: each pedestrian computes, from the state at the start of the step, its minimum TTC over all
//!    vehicles in range, the ego's distance and side, and (on the road) the lookahead conflict;
//! 3. **decide**: the behaviour machine of every single pedestrian and group leader takes at most one
//!    transition, in pedestrian order; then followers copy their leader's state (same frame);
//! 4. **move pedestrians**: AI mode on sidewalks, manual mode across the road; leaders before followers;
//! 5. **vehicles**: each vehicle's IDM acceleration towards its most constraining leader (vehicles and
//!    pedestrians in its path ahead, the ego's braking rule), all computed before any moves;
//! 6. **integrate** the vehicles along their paths;
//! 7. **contact check**: a pedestrian disc overlapping a vehicle footprint, or two overlapping footprints, is an
//!    [`Event::Contact`]; the vehicle is stopped (and moved back) so that nothing overlaps in the next frame;
//! 8. **gestures and heads**: each pedestrian's gesture advances, ends or starts (when the ego yields to it),
//!    then its head turns (to the ego while gesturing). Neither changes any motion.
//!
//! Events carry the first frame whose recorded state reflects them (a transition decided in step `f` is an
//! event of frame `f + 1`; a mid-road jaywalker's injection is a decision at frame 0).
//!
//! # Randomness
//!
//! Each pedestrian draws from its own stream, `clip_rng(seed, "sim/ped/{id}")`, in program order (constants at
//! set-up, then one draw per retreat conflict, patience expiry, scan or abandonment), so adding draws for one
//! pedestrian never shifts another's; its two gesture draws come from `clip_rng(seed, "sim/ped/{id}/gesture")`
//! at set-up, so gestures (which change no motion) shift no behaviour draw. Vehicles draw nothing. One clip runs on one thread; [`simulate_all`]
//! runs clips in parallel with rayon and returns them in plan order, identical for any thread count.

mod contacts;
mod cycling;
pub mod gate;
pub(crate) mod pedestrian;
pub mod rig;
pub mod signals;
pub mod trace;
pub mod ttc;
pub(crate) mod vehicle;
pub(crate) mod view;

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::plan::{ClipScript, Plan, SimParams, TownContext, seeds};
use crate::sim::trace::{ClipTrace, CyclistFrame, Event, PedFrame, SignalTrack, VehicleFrame, VehicleId};
use crate::world::RoadNetwork;
use contacts::Contacts;
use pedestrian::LeaderFacts;
use pedestrian::machine;
use pedestrian::params::{FOLLOWER_MAX_IN_VIEW_S, GROUP_LINE_MAX_WIDTH_DIFF, GROUP_LINE_MIN_COS};
use pedestrian::{Group, Ped, StepCtx, motion, perceive};
pub use pedestrian::{allowed_speed_range_mps, params as behaviour_params, profile_multiplier, state_speed_mps};
pub use vehicle::{BICYCLE_HEIGHT_M, BICYCLE_LENGTH_M, BICYCLE_WIDTH_M, EGO_TIME_HEADWAY_S};
use vehicle::{PedView, Vehicle};

/// Length of every vehicle's footprint box, metres.
pub const VEHICLE_LENGTH_M: f64 = 4.6;
/// Width of every vehicle's footprint box, metres.
pub const VEHICLE_WIDTH_M: f64 = 1.9;
/// Height of every vehicle's box, metres.
pub const VEHICLE_HEIGHT_M: f64 = 1.5;
/// Radius of a pedestrian's ground disc, metres.
pub const PED_RADIUS_M: f64 = 0.3;
/// Crank turns per metre ridden: a 2.1 m wheel circumference and a 2.6 gear ratio (a city bike's middle gear).
pub const CRANK_TURNS_PER_M: f64 = 1.0 / (2.1 * 2.6);

/// Why a plan could not be simulated.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SimError {
    /// A clip names a town that was not passed in.
    #[error("clip {clip_id}: town `{town}` was not loaded")]
    UnknownTown {
        /// The clip.
        clip_id: String,
        /// The missing town.
        town: String,
    },
}

/// Simulates every clip of `plan` in parallel (rayon), returning the traces in plan order. The result does not
/// depend on the number of threads.
pub fn simulate_all(plan: &Plan, towns: &BTreeMap<String, TownContext>) -> Result<Vec<ClipTrace>, SimError> {
    for clip in &plan.clips {
        if !towns.contains_key(&clip.town) {
            return Err(SimError::UnknownTown {
                clip_id: clip.clip_id.clone(),
                town: clip.town.clone(),
            });
        }
    }
    Ok(plan
        .clips
        .par_iter()
        .map(|clip| simulate(clip, &plan.sim, &towns[&clip.town].network))
        .collect())
}

/// Simulates one clip, single-threaded and deterministically.
pub fn simulate(script: &ClipScript, params: &SimParams, town: &RoadNetwork) -> ClipTrace {
    let mut sim = Sim::new(script, params, town);
    sim.run();
    let mut trace = sim.trace;
    if let Some(wobble) = &params.ego_heading {
        wobble_heading(&mut trace, wobble, script.seed, script.fps);
    }
    if let Some(wobble) = &params.ego_pitch {
        let offsets_rad = wobble_offsets_rad(wobble, script.seed, "ego pitch", script.fps, trace.ego.len());
        for (frame, offset_rad) in trace.ego.iter_mut().zip(offsets_rad) {
            frame.pitch_rad = offset_rad;
        }
    }
    trace
}

/// Adds the ego's heading wobble to its recorded headings: a smooth Gauss–Markov offset (white noise through two
/// first-order lags of time constant `correlation_s`, autocorrelation `(1 + τ/T) e^{−τ/T}`) of stationary
/// deviation `sd_deg`, from the clip's `"ego heading"` stream (the same draws whatever else the spec changes).
/// A car's heading has a rate that changes smoothly (steering), so the offset is smooth too: a single lag
/// (AR(1)) would turn the camera by a fresh random rate every frame. The lags run for ten time constants before
/// the clip's first frame, so the offset starts from its stationary spread. The sensors point along the recorded
/// heading; the simulated path is unchanged.
fn wobble_heading(trace: &mut ClipTrace, wobble: &crate::spec::types::Wobble, clip_seed: u64, fps: u32) {
    let offsets_rad = wobble_offsets_rad(wobble, clip_seed, "ego heading", fps, trace.ego.len());
    for (frame, offset_rad) in trace.ego.iter_mut().zip(offsets_rad) {
        frame.yaw_rad += offset_rad;
    }
}

/// A wobble's offsets for `frames` frames (see [`wobble_heading`]) from the clip's stream `stream` (`"ego
/// heading"`, `"ego pitch"`), radians.
fn wobble_offsets_rad(
    wobble: &crate::spec::types::Wobble,
    clip_seed: u64,
    stream: &str,
    fps: u32,
    frames: usize,
) -> Vec<f64> {
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = crate::plan::seeds::clip_rng(clip_seed, stream);
    let sd_rad = wobble.sd_deg.to_radians();
    let frames_per_t = f64::from(fps.max(1)) * wobble.correlation_s.max(1e-3);
    let rho = (-1.0 / frames_per_t).exp();
    // Two AR(1) lags in cascade: `inner` = ρ inner + √(1 − ρ²) σ_in z, `offset` = ρ offset + (1 − ρ) inner, whose
    // stationary variance is σ_in² (1 + ρ²) / (1 + ρ)²; σ_in is chosen so that it is `sd_deg`².
    let sd_inner = sd_rad * (1.0 + rho) / (1.0 + rho * rho).sqrt();
    let innovation = sd_inner * (1.0 - rho * rho).sqrt();
    let (mut inner, mut offset_rad) = (0.0_f64, 0.0_f64);
    let warm_up = (10.0 * frames_per_t).ceil().min(100_000.0) as usize;
    let mut out = Vec::with_capacity(frames);
    for i in 0..warm_up + frames {
        let z: f64 = StandardNormal.sample(&mut rng);
        inner = rho * inner + innovation * z;
        offset_rad = rho * offset_rad + (1.0 - rho) * inner;
        if i >= warm_up {
            out.push(offset_rad);
        }
    }
    out
}

/// The state of one clip's simulation.
struct Sim<'a> {
    params: &'a SimParams,
    net: &'a RoadNetwork,
    /// Whether the clip has an emergency vehicle (only then does anyone yield to one).
    sirens: bool,
    /// The traffic lights' plans, where lights run.
    lights: Option<signals::SignalPlans>,
    dt_s: f64,
    /// The ego first (`VehicleId::Ego`), then traffic in script order, then the cyclists in script order.
    vehicles: Vec<Vehicle>,
    /// Cyclists' riding and overtaking parameters (where the clip has cyclists).
    cycling: Option<&'a crate::spec::types::Cyclists>,
    /// Which (cyclist, pedestrian, swerved) reactions have been recorded.
    cyclist_reactions: Vec<(u32, u32, bool)>,
    peds: Vec<Ped>,
    /// Singles and leaders (decide and move first), then followers.
    order: Vec<usize>,
    trace: ClipTrace,
    /// Where each vehicle's path crosses another's (found once at set-up).
    zones: Vec<Vec<vehicle::ConflictZone>>,
    contacts: Contacts,
    /// What the ego's camera sees (the pedestrians' timelines).
    view: view::ViewProxy,
    // Scratch buffers, reused every step.
    probes: Vec<DVec2>,
    positions: Vec<DVec2>,
    people: Vec<(DVec3, f64)>,
    views: Vec<PedView>,
    accels: Vec<f64>,
    leader_facts: Vec<Option<LeaderFacts>>,
}

impl<'a> Sim<'a> {
    fn new(script: &ClipScript, params: &'a SimParams, net: &'a RoadNetwork) -> Sim<'a> {
        let fps = script.fps.max(1);
        let frames = script.frame_count as usize;
        let mut vehicles = Vec::with_capacity(script.vehicles.len() + 1);
        vehicles.push(Vehicle::ego(&script.ego, net));
        vehicles.extend(script.vehicles.iter().map(|v| Vehicle::traffic(v, net)));
        vehicles.extend(script.cyclists.iter().map(|c| Vehicle::cyclist(c, net)));
        let ego_start_s_m = vehicles[0].s_m;
        let mut peds: Vec<Ped> = script
            .pedestrians
            .iter()
            .map(|p| {
                let rng = seeds::clip_rng(script.seed, &format!("sim/ped/{}", p.id));
                let gesture_rng = seeds::clip_rng(script.seed, &format!("sim/ped/{}/gesture", p.id));
                Ped::new(p, params, net, rng, gesture_rng)
            })
            .collect();
        // A pedestrian's place along the ego's route is its planned distance ahead of the ego's start.
        for p in &mut peds {
            p.traits.route_s_m += ego_start_s_m;
        }
        form_groups(script, &mut peds);
        let mut order: Vec<usize> = (0..peds.len()).filter(|&i| peds[i].leader().is_none()).collect();
        order.extend((0..peds.len()).filter(|&i| peds[i].leader().is_some()));
        let events: Vec<Event> = peds
            .iter()
            .filter(|p| p.attempt.decided())
            .map(|p| Event::CrossingDecision {
                frame: 0,
                pedestrian: p.traits.id,
            })
            .collect();
        let np = peds.len();
        let nv = vehicles.len();
        for p in peds.iter_mut() {
            p.update_head(0.0, &vehicles);
        }
        let zones = vehicle::conflict_zones(&vehicles);
        let sirens = vehicles.iter().any(|v| v.emergency.is_some());
        let lights = params
            .signals
            .as_ref()
            .filter(|_| !net.signals.is_empty())
            .map(|t| signals::SignalPlans::new(net, t, script.seed).with_offsets(&script.signal_offsets));
        if lights.is_some() {
            // A pedestrian whose crossing runs along a signalised crosswalk heeds its signal.
            for p in &mut peds {
                p.traits.signal = p.traits.line.and_then(|l| {
                    crate::world::signals::crosswalk_signal(net, l.near_curb + l.dir * (0.5 * l.width_m))
                });
            }
            // A group crosses on its leader's signal.
            for i in 0..peds.len() {
                if let Some(l) = peds[i].leader() {
                    peds[i].traits.signal = peds[l].traits.signal;
                }
            }
            vehicles[0].set_stop_lines(signals::stop_lines(&script.ego.route, net));
            let routes = script.vehicles.iter().map(|v| &v.route);
            for (v, route) in vehicles[1..]
                .iter_mut()
                .zip(routes.chain(script.cyclists.iter().map(|c| &c.route)))
            {
                v.set_stop_lines(signals::stop_lines(route, net));
            }
        }
        let signal_tracks = if lights.is_some() {
            net.signals
                .iter()
                .map(|g| SignalTrack {
                    id: g.id.clone(),
                    junction: net.junctions[g.junction as usize].id.clone(),
                    phase: g.phase,
                    position: g.position,
                    facing_rad: g.facing_rad,
                    states: Vec::with_capacity(frames),
                })
                .collect()
        } else {
            Vec::new()
        };
        let trace = ClipTrace {
            clip_id: script.clip_id.clone(),
            fps,
            frame_count: script.frame_count,
            ego: Vec::with_capacity(frames),
            vehicles: (0..script.vehicles.len()).map(|_| Vec::with_capacity(frames)).collect(),
            pedestrians: (0..np).map(|_| Vec::with_capacity(frames)).collect(),
            cyclists: (0..script.cyclists.len()).map(|_| Vec::with_capacity(frames)).collect(),
            events,
            signals: signal_tracks,
        };
        let cycling = params.cyclists.as_ref().filter(|_| !script.cyclists.is_empty());
        Sim {
            params,
            net,
            cycling,
            cyclist_reactions: Vec::new(),
            sirens,
            lights,
            dt_s: 1.0 / f64::from(fps),
            vehicles,
            peds,
            order,
            trace,
            zones,
            contacts: Contacts::new(nv, np),
            view: view::ViewProxy::new(params, script.seed),
            probes: Vec::with_capacity(8),
            positions: Vec::with_capacity(np),
            people: Vec::with_capacity(np),
            views: Vec::with_capacity(np),
            accels: Vec::with_capacity(nv),
            leader_facts: vec![None; np],
        }
    }

    fn run(&mut self) {
        let frames = self.trace.frame_count;
        for f in 0..frames {
            self.see_lights(f);
            self.record();
            if f + 1 < frames {
                self.step(f);
            }
        }
    }

    fn record(&mut self) {
        for v in &self.vehicles {
            let VehicleId::Cyclist(n) = v.id else { continue };
            self.trace.cyclists[n as usize].push(CyclistFrame {
                pos: DVec3::new(v.pose.pos.x, v.pose.pos.y, v.pose.z_m),
                yaw_rad: v.pose.heading_rad,
                speed_mps: v.speed_mps,
                accel_mps2: v.accel_mps2,
                crank_phase: (v.odometer_m * CRANK_TURNS_PER_M).fract(),
                ridden_m: v.odometer_m,
                swerving: v.swerving_for.is_some(),
                in_bike_lane: v.in_bike_lane,
                light: v.light_ahead.map(|(_, state)| state),
            });
        }
        for (k, v) in self.vehicles.iter().enumerate() {
            if v.is_cyclist() {
                continue;
            }
            let frame = VehicleFrame {
                pos: DVec3::new(v.pose.pos.x, v.pose.pos.y, v.pose.z_m),
                yaw_rad: v.pose.heading_rad,
                pitch_rad: 0.0,
                speed_mps: v.speed_mps,
                accel_mps2: v.accel_mps2,
                yielding: v.yielding,
                light: v.light_ahead.map(|(_, state)| state),
            };
            if k == 0 {
                self.trace.ego.push(frame);
            } else {
                self.trace.vehicles[k - 1].push(frame);
            }
        }
        for (i, p) in self.peds.iter().enumerate() {
            let b = &p.body;
            self.trace.pedestrians[i].push(PedFrame {
                pos: DVec3::new(b.pos.x, b.pos.y, b.z_m),
                yaw_rad: b.yaw_rad,
                velocity: b.velocity,
                state: p.state(),
                lane_type: b.lane_type,
                head_yaw_rad: b.head_yaw_rad,
                gait_phase: b.gait_phase,
                on_phone: p.on_phone(),
                gesture: p.gesture,
                reaction: p.reaction(),
                walk_signal: p.percept.walk,
                on_crosswalk: on_crosswalk(self.net, b.pos),
            });
        }
    }

    /// The lights' states at frame `f` (recorded), and each vehicle's next light within range.
    fn see_lights(&mut self, f: u32) {
        let Some(plans) = &self.lights else { return };
        let time_s = f64::from(f) * self.dt_s;
        for (track, g) in self.trace.signals.iter_mut().zip(&self.net.signals) {
            track.states.push(plans.state_at(g, time_s));
        }
        let idm = &self.params.idm;
        for p in &mut self.peds {
            p.percept.walk = p
                .traits
                .signal
                .map(|k| plans.walk_at(&self.net.signals[k as usize], time_s));
        }
        for v in &mut self.vehicles {
            v.light_ahead = v.stop_lines.get(v.next_stop).and_then(|l| {
                let gap = l.s_m - (v.s_m + v.half_length_m);
                (gap <= vehicle::LIGHT_RANGE_M)
                    .then(|| (gap, plans.state_at(&self.net.signals[l.signal as usize], time_s)))
            });
            // The dilemma zone: a light that turns amber (or is red when first seen) too close to stop for, at a
            // comfortable rate for amber and the hardest for red, is driven through.
            if let Some((gap, state)) = v.light_ahead
                && v.bound_by_light()
            {
                let stoppable = match state {
                    signals::LightState::Green => true,
                    signals::LightState::Amber => signals::can_stop(gap, v.speed_mps, idm.comfortable_decel_mps2),
                    signals::LightState::Red => signals::can_stop(gap, v.speed_mps, idm.max_decel_mps2),
                };
                if !stoppable {
                    v.committed = Some(v.next_stop);
                }
            }
        }
    }

    /// After the vehicles moved in the step to frame `frame`: a front bumper past its next stop line while that
    /// light was red ran it; a vehicle standing at a red line (its front within [`signals::STOPPED_AT_LINE_M`]
    /// of it) has stopped for it (once per line; those queued behind it are not counted).
    fn pass_stop_lines(&mut self, frame: u32) {
        if self.lights.is_none() {
            return;
        }
        for v in &mut self.vehicles {
            let Some(line) = v.stop_lines.get(v.next_stop).copied() else {
                continue;
            };
            let red = matches!(v.light_ahead, Some((_, signals::LightState::Red)));
            if v.s_m + v.half_length_m >= line.s_m {
                if red {
                    self.trace.events.push(Event::RedLight {
                        frame,
                        vehicle: v.id,
                        signal: line.signal,
                        ran: true,
                        unavoidable: v.committed == Some(v.next_stop),
                    });
                }
                v.next_stop += 1;
            } else if red
                && v.bound_by_light()
                && v.speed_mps < 0.1
                && line.s_m - (v.s_m + v.half_length_m) < signals::STOPPED_AT_LINE_M
                && v.stopped_at != Some(v.next_stop)
            {
                v.stopped_at = Some(v.next_stop);
                self.trace.events.push(Event::RedLight {
                    frame,
                    vehicle: v.id,
                    signal: line.signal,
                    ran: false,
                    unavoidable: false,
                });
            }
        }
    }

    fn step(&mut self, f: u32) {
        let ctx = StepCtx {
            params: self.params,
            net: self.net,
            dt_s: self.dt_s,
            time_s: f64::from(f) * self.dt_s,
            next_frame: f + 1,
        };
        let events = &mut self.trace.events;

        // 2. Perceive.
        let camera = self.view.camera_at(&self.vehicles[0]);
        self.people.clear();
        self.people.extend(
            self.peds
                .iter()
                .map(|p| (DVec3::new(p.body.pos.x, p.body.pos.y, p.body.z_m), p.traits.height_m)),
        );
        for (me, p) in self.peds.iter_mut().enumerate() {
            let around = perceive::Surroundings {
                params: self.params,
                net: self.net,
                view: &self.view,
                camera: &camera,
                people: &self.people,
                me,
                dt_s: self.dt_s,
            };
            perceive::perceive(p, &self.vehicles, &around, &mut self.probes);
        }

        // 3. Decide: singles and leaders, then followers.
        for k in 0..self.order.len() {
            let i = self.order[k];
            if let Some(l) = self.peds[i].leader() {
                let facts = self.leader_facts[l].expect("leaders decide before followers");
                machine::follow(&mut self.peds[i], &facts, &ctx, events);
                continue;
            }
            let p = &self.peds[i];
            let group_ready = p.followers().iter().all(|&j| self.peds[j].attempt.at_curb());
            let followers_seen = p.followers().iter().all(|&j| {
                let f = &self.peds[j];
                f.in_view_s
                    >= f.traits
                        .in_view_before_crossing_s
                        .unwrap_or(0.0)
                        .min(FOLLOWER_MAX_IN_VIEW_S)
            });
            let group_conflict = p.percept.conflict_vehicle.or_else(|| {
                p.followers()
                    .iter()
                    .find_map(|&j| self.peds[j].percept.conflict_vehicle)
            });
            let p = &mut self.peds[i];
            p.followers_seen = followers_seen;
            machine::transition(p, &ctx, group_ready, group_conflict, events);
            if !p.followers().is_empty() {
                self.leader_facts[i] = Some(LeaderFacts::of(p, 0.0));
            }
        }

        // Group crossing speed: the slowest member's.
        let m = &self.params.speed_profiles.multipliers;
        for k in 0..self.order.len() {
            let i = self.order[k];
            let leader = &self.peds[i];
            if leader.followers().is_empty() {
                continue;
            }
            let (state, profile) = (leader.state(), leader.profile);
            let speed = leader
                .followers()
                .iter()
                .map(|&j| &self.peds[j])
                .chain(std::iter::once(leader))
                .map(|q| state_speed_mps(state, q.traits.base_speed_mps, profile, q.traits.retreat_speed_mps, m))
                .fold(f64::INFINITY, f64::min);
            self.peds[i].group_speed_mps = if state.is_crossing() { speed } else { 0.0 };
        }

        // 4. Move pedestrians.
        self.positions.clear();
        self.positions.extend(self.peds.iter().map(|p| p.body.pos));
        for k in 0..self.order.len() {
            let i = self.order[k];
            let leader = self.peds[i].leader().and_then(|l| self.leader_facts[l]);
            motion::move_ped(&mut self.peds[i], &ctx, &self.positions, i, leader.as_ref());
            let p = &self.peds[i];
            if !p.followers().is_empty() {
                let fraction = p.traits.line.map_or(0.0, |l| l.along_m(p.body.pos) / l.width_m);
                self.leader_facts[i] = Some(LeaderFacts::of(p, fraction));
            }
        }

        // 5. Vehicles: accelerations from the state after pedestrians moved, before any vehicle moves.
        self.views.clear();
        self.views.extend(self.peds.iter().map(|p| PedView {
            pos: p.body.pos,
            velocity: p.body.velocity,
            crossing: p.activity.crossing_motion(),
            approaching_curb: p.heading_for_curb(),
            waiting_at_curb: p.waiting_at_curb(),
            steps_out_ego_within_m: p.traits.step_out_ego_within_m,
        }));
        // Vehicles closing in on an emergency vehicle stop for it.
        if self.sirens {
            for i in 0..self.vehicles.len() {
                let yielding = self.vehicles.iter().any(|e| self.vehicles[i].yields_to(e));
                self.vehicles[i].yielding = yielding;
            }
        }
        if let Some(c) = self.cycling {
            cycling::decide(&mut self.vehicles, &self.views, c, &self.params.idm);
        }
        self.accels.clear();
        for i in 0..self.vehicles.len() {
            self.accels.push(vehicle::accel_for(
                i,
                &self.vehicles,
                &self.zones[i],
                &self.views,
                &self.params.idm,
            ));
        }
        // 6. Integrate (and count the ego's time yielding to waiting pedestrians).
        let yielding = self.vehicles[0].sees_waiting_pedestrian(&self.views);
        self.vehicles[0].count_yield(yielding, self.dt_s);
        for (v, &a) in self.vehicles.iter_mut().zip(&self.accels) {
            v.integrate(a, self.dt_s);
        }
        self.pass_stop_lines(f + 1);
        if self.cycling.is_some() {
            cycling::record(
                f + 1,
                &mut self.vehicles,
                &self.accels,
                &self.views,
                &mut self.cyclist_reactions,
                &mut self.trace.events,
            );
        }
        // 7. Contacts.
        self.contacts
            .resolve(f + 1, &mut self.vehicles, &mut self.peds, &mut self.trace.events);

        let time_s = f64::from(f + 1) * self.dt_s;
        for p in self.peds.iter_mut() {
            p.update_gesture(self.dt_s, &self.vehicles[0], &self.params.gestures);
            p.update_head(time_s, &self.vehicles);
        }
    }
}

/// Whether `p` lies on a crosswalk's carriageway part.
fn on_crosswalk(net: &RoadNetwork, p: DVec2) -> bool {
    net.crosswalks
        .iter()
        .any(|c| crate::world::point_in_polygon(&c.polygon, p))
}

/// Groups: followers point at their leader (by index), leaders list their followers. A follower whose own
/// crossing line is its leader's, or not parallel to it, or much wider or narrower, walks a line parallel to its
/// leader's through its own spawn point.
fn form_groups(script: &ClipScript, peds: &mut [Ped]) {
    let index_of = |id: u32| script.pedestrians.iter().position(|p| p.id == id);
    for (i, s) in script.pedestrians.iter().enumerate() {
        let Some(g) = s.group else { continue };
        if g.leader == s.id {
            continue;
        }
        let Some(l) = index_of(g.leader) else { continue };
        if peds[l].leader().is_some() {
            continue;
        }
        peds[i].group = Group::Follower(l);
        match &mut peds[l].group {
            Group::Leader(followers) => followers.push(i),
            group => *group = Group::Leader(vec![i]),
        }
        if let (Some(fl), Some(ll)) = (peds[i].traits.line, peds[l].traits.line)
            && (fl.near_curb.distance(ll.near_curb) < 1e-6
                || fl.dir.dot(ll.dir) < GROUP_LINE_MIN_COS
                || (fl.width_m - ll.width_m).abs() > GROUP_LINE_MAX_WIDTH_DIFF * ll.width_m)
        {
            let d = s.spawn - ll.near_curb;
            let shift = d - ll.dir * d.dot(ll.dir);
            let mut line = ll;
            line.near_curb += shift;
            line.end += shift;
            peds[i].traits.line = Some(line);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::wobble_offsets_rad;
    use crate::spec::types::Wobble;

    /// The standard deviation of `xs` about their mean.
    fn sd(xs: &[f64]) -> f64 {
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64).sqrt()
    }

    #[test]
    fn the_heading_wobble_is_smooth_with_the_asked_spread_and_change_over_half_a_second() {
        let wobble = Wobble {
            sd_deg: 2.0,
            correlation_s: 1.0,
        };
        // Many clips' offsets (each from its own seed), degrees.
        let clips: Vec<Vec<f64>> = (0..400_u64)
            .map(|seed| {
                wobble_offsets_rad(&wobble, seed, "ego heading", 30, 450)
                    .iter()
                    .map(|r| r.to_degrees())
                    .collect()
            })
            .collect();
        let all: Vec<f64> = clips.iter().flatten().copied().collect();
        let first: Vec<f64> = clips.iter().map(|c| c[0]).collect();
        // Stationary from the first frame: the spread of frame 0 across clips and of every frame is `sd_deg`.
        assert!((sd(&all) - 2.0).abs() < 0.1, "sd {}", sd(&all));
        assert!((sd(&first) - 2.0).abs() < 0.25, "first-frame sd {}", sd(&first));
        // Its change over 0.5 s is σ √(2 (1 − 1.5 e^{−0.5})) = 0.849° (what `calibrate` inverts) ...
        let lag: Vec<f64> = clips.iter().flat_map(|c| c.windows(16).map(|w| w[15] - w[0])).collect();
        assert!((sd(&lag) - 0.849).abs() < 0.05, "0.5 s change sd {}", sd(&lag));
        // ... and it turns at a smooth rate: the change of the per-frame change is about a third of the per-frame
        // change (σ/T = 2°/s is 0.067° a frame), where an AR(1)'s would be √2 times it.
        let steps: Vec<f64> = clips.iter().flat_map(|c| c.windows(2).map(|w| w[1] - w[0])).collect();
        let bends: Vec<f64> = clips
            .iter()
            .flat_map(|c| c.windows(3).map(|w| w[2] - 2.0 * w[1] + w[0]))
            .collect();
        assert!((sd(&steps) - 0.067).abs() < 0.006, "per-frame change sd {}", sd(&steps));
        assert!(
            sd(&bends) < 0.45 * sd(&steps),
            "bend sd {} against step sd {}",
            sd(&bends),
            sd(&steps)
        );
        assert_eq!(
            wobble_offsets_rad(&wobble, 9, "ego heading", 30, 100),
            wobble_offsets_rad(&wobble, 9, "ego heading", 30, 100)
        );
        // The pitch draws from its own stream: the two wobbles of a clip are independent.
        assert_ne!(
            wobble_offsets_rad(&wobble, 9, "ego heading", 30, 100),
            wobble_offsets_rad(&wobble, 9, "ego pitch", 30, 100)
        );
    }
}
