//! Traffic lights in the simulation: each signalised junction's fixed-time plan (its phases green one after
//! the other, each followed by amber and all red, as CARLA's traffic-light groups cycle), with a seeded offset
//! per junction and clip, and the stop lines on a vehicle's path where a light applies to it.
//!
//! A light's state is a pure function of the clip's time: `state_at` needs no step history, so the tables
//! and the renderer can ask for any frame.

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::dsl::types::Signals;
use crate::planner::{RouteScript, seeds};
use crate::world::signals::{STOP_LINE_SETBACK_M, junction_phases, signalised_entries};
use crate::world::{RoadNetwork, Signal};

/// The state of a traffic light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LightState {
    /// Go.
    Green,
    /// Stop if you can stop safely.
    Amber,
    /// Stop.
    Red,
}

impl LightState {
    /// The state's name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            LightState::Green => "green",
            LightState::Amber => "amber",
            LightState::Red => "red",
        }
    }
}

/// The pedestrian signal of a crosswalk across an approach road: "walk" while another phase of the junction
/// is green (the approach's traffic has red), flashing while that phase's amber and all-red clear the junction,
/// "don't walk" during the approach's own phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WalkSignal {
    /// Cross.
    Walk,
    /// Finish crossing; do not start.
    Flashing,
    /// Do not cross.
    DontWalk,
}

impl WalkSignal {
    /// The state's name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            WalkSignal::Walk => "walk",
            WalkSignal::Flashing => "flashing",
            WalkSignal::DontWalk => "dont_walk",
        }
    }
}

/// The signal plans of one clip: per junction its number of phases and its offset into the cycle.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalPlans {
    timing: Signals,
    /// Per junction of the town: (phases, offset into the cycle in seconds); 0 phases: not signalised.
    junctions: Vec<(u32, f64)>,
}

impl SignalPlans {
    /// The plans of a clip of seed `clip_seed` in `net`: one offset per signalised junction, drawn uniformly
    /// over its cycle from the clip's own stream `sim/signals` (in junction order).
    pub fn new(net: &RoadNetwork, timing: &Signals, clip_seed: u64) -> SignalPlans {
        let mut rng = seeds::clip_rng(clip_seed, "sim/signals");
        let slot = slot_s(timing);
        let junctions = (0..net.junctions.len() as u32)
            .map(|j| {
                let phases = junction_phases(&net.signals, j);
                let cycle = f64::from(phases) * slot;
                let offset = if cycle > 0.0 { rng.random_range(0.0..cycle) } else { 0.0 };
                (phases, offset)
            })
            .collect();
        SignalPlans {
            timing: timing.clone(),
            junctions,
        }
    }

    /// The state of `signal` at clip time `time_s`.
    pub fn state_at(&self, signal: &Signal, time_s: f64) -> LightState {
        let (phases, offset) = self.plan_of(signal);
        phase_state(&self.timing, phases, signal.phase, time_s + offset)
    }

    /// The pedestrian signal of the crosswalk across `signal`'s approach road at clip time `time_s`.
    pub fn walk_at(&self, signal: &Signal, time_s: f64) -> WalkSignal {
        let (phases, offset) = self.plan_of(signal);
        match slot_at(&self.timing, phases, time_s + offset) {
            None => WalkSignal::Walk,
            Some((current, _)) if current == signal.phase => WalkSignal::DontWalk,
            Some((_, w)) if w < self.timing.green_s.max(0.1) => WalkSignal::Walk,
            Some(_) => WalkSignal::Flashing,
        }
    }

    /// (phases, offset) of `signal`'s junction.
    fn plan_of(&self, signal: &Signal) -> (u32, f64) {
        self.junctions
            .get(signal.junction as usize)
            .copied()
            .unwrap_or((0, 0.0))
    }
}

/// The phase whose slot cycle time `t_s` falls in and the time into that slot, for a plan of `phases` phases
/// (`None` without phases).
fn slot_at(timing: &Signals, phases: u32, t_s: f64) -> Option<(u32, f64)> {
    if phases == 0 {
        return None;
    }
    let slot = slot_s(timing);
    let u = t_s.rem_euclid(slot * f64::from(phases));
    let current = ((u / slot) as u32).min(phases - 1);
    Some((current, u - f64::from(current) * slot))
}

/// Length of one phase's slot (green, amber, all red), seconds.
fn slot_s(t: &Signals) -> f64 {
    t.green_s.max(0.1) + t.amber_s.max(0.0) + t.all_red_s.max(0.0)
}

/// The state of phase `phase` of a plan of `phases` phases at cycle time `t_s` (green without phases).
pub fn phase_state(timing: &Signals, phases: u32, phase: u32, t_s: f64) -> LightState {
    match slot_at(timing, phases, t_s) {
        None => LightState::Green,
        Some((current, _)) if current != phase => LightState::Red,
        Some((_, w)) if w < timing.green_s.max(0.1) => LightState::Green,
        Some((_, w)) if w < timing.green_s.max(0.1) + timing.amber_s.max(0.0) => LightState::Amber,
        Some(_) => LightState::Red,
    }
}

/// A vehicle at rest before a red light with its front bumper within this distance of the stop line has stopped
/// for the light (it aims 1 m short of the line plus its minimum gap), metres.
pub const STOPPED_AT_LINE_M: f64 = 8.0;

/// Where a light applies on a vehicle's path: its stop line at arc length `s_m`, and the signal (index into
/// [`RoadNetwork::signals`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StopLine {
    pub s_m: f64,
    pub signal: u32,
}

/// The stop lines along `route`: wherever it enters a signalised junction from an approach road with a light,
/// [`STOP_LINE_SETBACK_M`] before the junction, in path order. The path's arc length is the route polyline's
/// (the vehicle path resamples the same polyline).
pub(crate) fn stop_lines(route: &RouteScript, net: &RoadNetwork) -> Vec<StopLine> {
    if net.signals.is_empty() {
        return Vec::new();
    }
    let Some(r) = net.route_through(&route.lanes_in(net)) else {
        return Vec::new();
    };
    signalised_entries(net, &r)
        .into_iter()
        .map(|(s_m, signal)| StopLine {
            s_m: (s_m - STOP_LINE_SETBACK_M).max(0.0),
            signal,
        })
        .collect()
}

/// Whether a vehicle `gap_m` before its stop line at `speed_mps` can still stop there braking at
/// `decel_mps2`.
pub(crate) fn can_stop(gap_m: f64, speed_mps: f64, decel_mps2: f64) -> bool {
    gap_m >= speed_mps * speed_mps / (2.0 * decel_mps2.max(0.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_are_green_in_turn_with_amber_and_all_red_between() {
        let t = Signals {
            enabled: true,
            green_s: 10.0,
            amber_s: 3.0,
            all_red_s: 2.0,
            crosswalk_share: 0.5,
        };
        // Three phases: a 45 s cycle; phase 1's slot is 15..30 s.
        let at = |phase, s| phase_state(&t, 3, phase, s);
        assert_eq!(at(0, 0.0), LightState::Green);
        assert_eq!(at(0, 9.99), LightState::Green);
        assert_eq!(at(0, 10.0), LightState::Amber);
        assert_eq!(at(0, 13.0), LightState::Red);
        assert_eq!(at(1, 14.9), LightState::Red);
        assert_eq!(at(1, 15.0), LightState::Green);
        assert_eq!(at(1, 26.0), LightState::Amber);
        assert_eq!(at(2, 31.0), LightState::Green);
        assert_eq!(at(0, 45.5), LightState::Green, "the cycle repeats");
        assert_eq!(at(0, -1.0), LightState::Red, "negative times wrap (phase 2's all red)");
        // Never two phases green at once, and every phase green for its share of the cycle.
        let mut green = [0u32; 3];
        for k in 0..4500 {
            let s = f64::from(k) * 0.01;
            let g: Vec<u32> = (0..3).filter(|&p| at(p, s) == LightState::Green).collect();
            assert!(g.len() <= 1, "{s} s: {g:?} green together");
            for p in g {
                green[p as usize] += 1;
            }
        }
        assert_eq!(green, [1000, 1000, 1000]);
    }

    #[test]
    fn can_stop_is_the_kinematic_stopping_distance() {
        assert!(can_stop(16.7, 10.0, 3.0));
        assert!(!can_stop(16.6, 10.0, 3.0));
        assert!(can_stop(0.0, 0.0, 3.0));
    }
}
