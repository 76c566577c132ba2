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
//!    [`Event::Contact`]; the vehicle is stopped (and moved back) so that nothing overlaps in the next frame.
//!
//! Events carry the first frame whose recorded state reflects them (a transition decided in step `f` is an
//! event of frame `f + 1`; a mid-road jaywalker's injection is a decision at frame 0).
//!
//! # Randomness
//!
//! Each pedestrian draws from its own stream, `clip_rng(seed, "sim/ped/{id}")`, in program order (constants at
//! set-up, then one draw per retreat conflict, patience expiry, scan or abandonment), so adding draws for one
//! pedestrian never shifts another's. Vehicles draw nothing. One clip runs on one thread; [`simulate_all`]
//! runs clips in parallel with rayon and returns them in plan order, identical for any thread count.

mod pedestrian;
pub mod ttc;
mod vehicle;

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::exec::trace::{ClipTrace, Event, PedFrame, PedState, VehicleFrame};
use crate::planner::{ClipScript, Plan, SimParams, TownContext, seeds};
use crate::world::RoadNetwork;
use pedestrian::{LeaderFacts, Ped, StepCtx};
pub use pedestrian::{allowed_speed_range_mps, profile_multiplier, state_speed_mps};
pub use vehicle::EGO_TIME_HEADWAY_S;
use vehicle::{HALF_LENGTH_M, HALF_WIDTH_M, PedView, Vehicle};

/// Length of every vehicle's footprint box, metres.
pub const VEHICLE_LENGTH_M: f64 = 4.6;
/// Width of every vehicle's footprint box, metres.
pub const VEHICLE_WIDTH_M: f64 = 1.9;
/// Height of every vehicle's box, metres.
pub const VEHICLE_HEIGHT_M: f64 = 1.5;
/// Radius of a pedestrian's ground disc, metres.
pub const PED_RADIUS_M: f64 = 0.3;

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
    sim.trace
}

/// The state of one clip's simulation.
struct Sim<'a> {
    params: &'a SimParams,
    net: &'a RoadNetwork,
    dt_s: f64,
    /// The ego first, then traffic in script order.
    vehicles: Vec<Vehicle>,
    peds: Vec<Ped>,
    /// Singles and leaders (decide and move first), then followers.
    order: Vec<usize>,
    trace: ClipTrace,
    // Scratch buffers, reused every step.
    probes: Vec<DVec2>,
    positions: Vec<DVec2>,
    views: Vec<PedView>,
    accels: Vec<f64>,
    leader_facts: Vec<Option<LeaderFacts>>,
    /// Where each vehicle's path crosses another's (found once at set-up).
    zones: Vec<Vec<vehicle::ConflictZone>>,
    ped_contact: Vec<bool>,
    vehicle_contact: Vec<bool>,
}

impl<'a> Sim<'a> {
    fn new(script: &ClipScript, params: &'a SimParams, net: &'a RoadNetwork) -> Sim<'a> {
        let fps = script.fps.max(1);
        let frames = script.frame_count as usize;
        let mut vehicles = Vec::with_capacity(script.vehicles.len() + 1);
        vehicles.push(Vehicle::ego(&script.ego, net));
        vehicles.extend(script.vehicles.iter().map(|v| Vehicle::traffic(v, net)));
        let mut peds: Vec<Ped> = script
            .pedestrians
            .iter()
            .map(|p| {
                Ped::new(
                    p,
                    params,
                    net,
                    seeds::clip_rng(script.seed, &format!("sim/ped/{}", p.id)),
                )
            })
            .collect();
        // A pedestrian's place along the ego's route is its planned distance ahead of the ego's start.
        for p in &mut peds {
            p.route_s_m += vehicles[0].s_m;
        }
        // Groups: followers point at their leader (by index), leaders list their followers.
        let index_of = |id: u32| script.pedestrians.iter().position(|p| p.id == id);
        for (i, s) in script.pedestrians.iter().enumerate() {
            if let Some(g) = s.group
                && g.leader != s.id
                && let Some(l) = index_of(g.leader)
                && peds[l].leader.is_none()
            {
                peds[i].leader = Some(l);
                peds[l].followers.push(i);
                // A follower sharing its leader's crossing line walks a parallel one through its own spawn.
                // So does one whose own line is not parallel to its leader's or much wider or narrower.
                if let (Some(fl), Some(ll)) = (peds[i].line, peds[l].line)
                    && (fl.near_curb.distance(ll.near_curb) < 1e-6
                        || fl.dir.dot(ll.dir) < 0.95
                        || (fl.width_m - ll.width_m).abs() > 0.15 * ll.width_m)
                {
                    peds[i].line = Some(ll);
                    let d = s.spawn - ll.near_curb;
                    let shift = d - ll.dir * d.dot(ll.dir);
                    let line = peds[i].line.as_mut().expect("checked");
                    line.near_curb += shift;
                    line.end += shift;
                }
            }
        }
        let mut order: Vec<usize> = (0..peds.len()).filter(|&i| peds[i].leader.is_none()).collect();
        order.extend((0..peds.len()).filter(|&i| peds[i].leader.is_some()));
        let mut events = Vec::new();
        for p in &peds {
            if p.decided {
                events.push(Event::CrossingDecision {
                    frame: 0,
                    pedestrian: p.id,
                });
            }
        }
        let np = peds.len();
        let nv = vehicles.len();
        for p in peds.iter_mut() {
            p.update_head(0.0, &vehicles);
        }
        let zones = vehicle::conflict_zones(&vehicles);
        let trace = ClipTrace {
            clip_id: script.clip_id.clone(),
            fps,
            frame_count: script.frame_count,
            ego: Vec::with_capacity(frames),
            vehicles: (0..script.vehicles.len()).map(|_| Vec::with_capacity(frames)).collect(),
            pedestrians: (0..np).map(|_| Vec::with_capacity(frames)).collect(),
            events,
        };
        Sim {
            params,
            net,
            dt_s: 1.0 / f64::from(fps),
            vehicles,
            peds,
            order,
            trace,
            probes: Vec::with_capacity(8),
            positions: Vec::with_capacity(np),
            views: Vec::with_capacity(np),
            accels: Vec::with_capacity(nv),
            leader_facts: vec![None; np],
            zones,
            ped_contact: vec![false; nv * np],
            vehicle_contact: vec![false; nv * nv],
        }
    }

    fn run(&mut self) {
        let frames = self.trace.frame_count;
        for f in 0..frames {
            self.record();
            if f + 1 < frames {
                self.step(f);
            }
        }
    }

    fn record(&mut self) {
        for (k, v) in self.vehicles.iter().enumerate() {
            let frame = VehicleFrame {
                pos: DVec3::new(v.pose.pos.x, v.pose.pos.y, v.pose.z_m),
                yaw_rad: v.pose.heading_rad,
                speed_mps: v.speed_mps,
                accel_mps2: v.accel_mps2,
            };
            if k == 0 {
                self.trace.ego.push(frame);
            } else {
                self.trace.vehicles[k - 1].push(frame);
            }
        }
        for (i, p) in self.peds.iter().enumerate() {
            self.trace.pedestrians[i].push(PedFrame {
                pos: DVec3::new(p.pos.x, p.pos.y, p.z_m),
                yaw_rad: p.yaw_rad,
                velocity: p.velocity,
                state: p.state,
                lane_type: p.lane_type,
                head_yaw_rad: p.head_yaw_rad,
                gait_phase: p.gait_phase,
                on_phone: p.on_phone,
            });
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
        for p in self.peds.iter_mut() {
            pedestrian::perceive(p, &self.vehicles, self.params, &mut self.probes);
        }

        // 3. Decide: singles and leaders, then followers.
        for k in 0..self.order.len() {
            let i = self.order[k];
            if let Some(l) = self.peds[i].leader {
                let facts = self.leader_facts[l].expect("leaders decide before followers");
                pedestrian::follow(&mut self.peds[i], &facts, &ctx, events);
                continue;
            }
            let p = &self.peds[i];
            let group_ready = p.followers.iter().all(|&j| self.peds[j].at_curb);
            let group_conflict = p
                .conflict_vehicle
                .or_else(|| p.followers.iter().find_map(|&j| self.peds[j].conflict_vehicle));
            let p = &mut self.peds[i];
            pedestrian::transition(p, &ctx, group_ready, group_conflict, events);
            if !p.followers.is_empty() {
                self.leader_facts[i] = Some(leader_facts(p, 0.0));
            }
        }

        // Group crossing speed: the slowest member's.
        let m = &self.params.speed_profiles.multipliers;
        for k in 0..self.order.len() {
            let i = self.order[k];
            if self.peds[i].followers.is_empty() {
                continue;
            }
            let state = self.peds[i].state;
            let profile = self.peds[i].profile;
            let speed = self.peds[i]
                .followers
                .iter()
                .map(|&j| &self.peds[j])
                .chain(std::iter::once(&self.peds[i]))
                .map(|q| pedestrian::state_speed_mps(state, q.base_speed_mps, profile, q.retreat_speed_mps, m))
                .fold(f64::INFINITY, f64::min);
            self.peds[i].group_speed_mps = if state.is_crossing() { speed } else { 0.0 };
        }

        // 4. Move pedestrians.
        self.positions.clear();
        self.positions.extend(self.peds.iter().map(|p| p.pos));
        for k in 0..self.order.len() {
            let i = self.order[k];
            let leader = self.peds[i].leader.and_then(|l| self.leader_facts[l]);
            pedestrian::move_ped(&mut self.peds[i], &ctx, &self.positions, i, leader.as_ref());
            if !self.peds[i].followers.is_empty() {
                let p = &self.peds[i];
                let fraction = p.line.map_or(0.0, |l| l.along_m(p.pos) / l.width_m);
                self.leader_facts[i] = Some(leader_facts(p, fraction));
            }
        }

        // 5. Vehicles: accelerations from the state after pedestrians moved, before any vehicle moves.
        self.views.clear();
        self.views.extend(self.peds.iter().map(|p| PedView {
            pos: p.pos,
            velocity: p.velocity,
            crossing: p.state.is_crossing() || p.state == PedState::Retreat,
        }));
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
        // 6. Integrate.
        for (v, &a) in self.vehicles.iter_mut().zip(&self.accels) {
            v.integrate(a, self.dt_s);
        }
        // 7. Contacts.
        self.contacts(f + 1);

        let time_s = f64::from(f + 1) * self.dt_s;
        for p in self.peds.iter_mut() {
            p.update_head(time_s, &self.vehicles);
        }
    }

    fn contacts(&mut self, frame: u32) {
        let np = self.peds.len();
        let nv = self.vehicles.len();
        for vi in 0..nv {
            for pi in 0..np {
                let v = &self.vehicles[vi];
                let p = &mut self.peds[pi];
                let touching = v.pose.pos.distance_squared(p.pos) < (HALF_LENGTH_M + PED_RADIUS_M + 0.5).powi(2)
                    && ttc::distance_to_box_m(p.pos, v.pose.pos, v.pose.heading_rad, HALF_LENGTH_M, HALF_WIDTH_M)
                        < PED_RADIUS_M;
                let flag = &mut self.ped_contact[vi * np + pi];
                if touching {
                    if !*flag {
                        self.trace.events.push(Event::Contact {
                            frame,
                            vehicle: v.id,
                            pedestrian: Some(p.id),
                            other_vehicle: None,
                        });
                    }
                    p.pos = push_out_of_box(p.pos, v.pose.pos, v.pose.heading_rad);
                    self.vehicles[vi].speed_mps = 0.0;
                }
                *flag = touching;
            }
        }
        for a in 0..nv {
            for b in a + 1..nv {
                let (va, vb) = (&self.vehicles[a], &self.vehicles[b]);
                let touching = va.pose.pos.distance_squared(vb.pose.pos) < (VEHICLE_LENGTH_M + 0.1).powi(2)
                    && boxes_overlap(va.pose.pos, va.pose.dir, vb.pose.pos, vb.pose.dir);
                let flag = &mut self.vehicle_contact[a * nv + b];
                if touching {
                    if !*flag {
                        self.trace.events.push(Event::Contact {
                            frame,
                            vehicle: va.id,
                            pedestrian: None,
                            other_vehicle: Some(vb.id),
                        });
                    }
                    // The one behind (the other is ahead along its heading) backs off and stops.
                    let a_behind = (vb.pose.pos - va.pose.pos).dot(va.pose.dir) > 0.0;
                    let (back, other) = if a_behind { (a, b) } else { (b, a) };
                    let (op, oh) = (self.vehicles[other].pose.pos, self.vehicles[other].pose.dir);
                    for _ in 0..40 {
                        let v = &mut self.vehicles[back];
                        v.back_off_and_stop(0.25);
                        if !boxes_overlap(v.pose.pos, v.pose.dir, op, oh) || v.s_m <= 0.0 {
                            break;
                        }
                    }
                }
                *flag = touching;
            }
        }
    }
}

fn leader_facts(p: &Ped, fraction: f64) -> LeaderFacts {
    LeaderFacts {
        state: p.state,
        on_phone: p.on_phone,
        decided: p.decided,
        attempt_over: p.attempt_over,
        profile: p.profile,
        fraction,
        walker_heading: DVec2::from_angle(p.yaw_rad),
    }
}

/// Moves a pedestrian disc at `p` out of a vehicle footprint, to just beyond its radius.
fn push_out_of_box(p: DVec2, centre: DVec2, heading_rad: f64) -> DVec2 {
    let (s, c) = heading_rad.sin_cos();
    let d = p - centre;
    let local = DVec2::new(d.x * c + d.y * s, -d.x * s + d.y * c);
    let r = PED_RADIUS_M + 0.01;
    let clamped = DVec2::new(
        local.x.clamp(-HALF_LENGTH_M, HALF_LENGTH_M),
        local.y.clamp(-HALF_WIDTH_M, HALF_WIDTH_M),
    );
    let out = if clamped != local {
        // Outside the box but within the radius: push along the normal.
        clamped + (local - clamped).normalize_or(DVec2::Y) * r
    } else {
        // Inside: leave through the nearest side.
        let dx = HALF_LENGTH_M - local.x.abs();
        let dy = HALF_WIDTH_M - local.y.abs();
        if dy <= dx {
            DVec2::new(local.x, local.y.signum() * (HALF_WIDTH_M + r))
        } else {
            DVec2::new(local.x.signum() * (HALF_LENGTH_M + r), local.y)
        }
    };
    centre + DVec2::new(out.x * c - out.y * s, out.x * s + out.y * c)
}

/// Whether two vehicle footprints (centre, unit heading) overlap (separating axis test).
fn boxes_overlap(ca: DVec2, ua: DVec2, cb: DVec2, ub: DVec2) -> bool {
    let axes = [ua, ua.perp(), ub, ub.perp()];
    let d = cb - ca;
    axes.iter().all(|&ax| {
        let ra = HALF_LENGTH_M * ua.dot(ax).abs() + HALF_WIDTH_M * ua.perp().dot(ax).abs();
        let rb = HALF_LENGTH_M * ub.dot(ax).abs() + HALF_WIDTH_M * ub.perp().dot(ax).abs();
        d.dot(ax).abs() <= ra + rb
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_overlap_and_push_out() {
        assert!(boxes_overlap(DVec2::ZERO, DVec2::X, DVec2::new(4.0, 0.0), DVec2::X));
        assert!(!boxes_overlap(DVec2::ZERO, DVec2::X, DVec2::new(4.7, 0.0), DVec2::X));
        assert!(boxes_overlap(
            DVec2::ZERO,
            DVec2::X,
            DVec2::new(3.0, 0.0),
            DVec2::from_angle(std::f64::consts::FRAC_PI_2)
        ));
        let p = push_out_of_box(DVec2::new(1.0, 0.5), DVec2::ZERO, 0.0);
        assert!(ttc::distance_to_box_m(p, DVec2::ZERO, 0.0, HALF_LENGTH_M, HALF_WIDTH_M) >= PED_RADIUS_M);
        let p = push_out_of_box(DVec2::new(2.5, 0.0), DVec2::ZERO, 1.0);
        assert!(ttc::distance_to_box_m(p, DVec2::ZERO, 1.0, HALF_LENGTH_M, HALF_WIDTH_M) >= PED_RADIUS_M);
    }
}
