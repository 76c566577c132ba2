//! Signal plans: each signalised junction's fixed-time plan (its phases green one after the other, each
//! followed by amber and all red, as CARLA's traffic-light groups cycle), with an offset per junction and clip —
//! drawn from the clip's `sim/signals` stream, or set by the planner for the junction where it stages a
//! signalised crossing (`ClipScript::signal_offsets`).
//!
//! A light's state is a pure function of the clip's time: `state_at` needs no step history, so the planner, the
//! simulation, the tables and the renderer agree on every frame.

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::plan::seeds;
use crate::spec::types::Signals;
use crate::world::signals::junction_phases;
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

    /// These plans with the offsets the planner set (`ClipScript::signal_offsets`: junction, offset) in place of
    /// the drawn ones.
    pub fn with_offsets(mut self, offsets: &[(u32, f64)]) -> SignalPlans {
        for &(junction, offset_s) in offsets {
            if let Some(j) = self.junctions.get_mut(junction as usize) {
                j.1 = offset_s;
            }
        }
        self
    }

    /// The clip time at or after `time_s` when `signal`'s green next starts (`time_s` itself while green; never
    /// without phases).
    pub fn next_green_s(&self, signal: &Signal, time_s: f64) -> f64 {
        let (phases, offset) = self.plan_of(signal);
        if phases == 0 || self.state_at(signal, time_s) == LightState::Green {
            return time_s;
        }
        let slot = slot_s(&self.timing);
        let cycle = slot * f64::from(phases);
        let u = (time_s + offset).rem_euclid(cycle);
        let start = f64::from(signal.phase) * slot;
        time_s + (start - u).rem_euclid(cycle)
    }

    /// The offset into the cycle at which `signal`'s green ends (its amber starts) at clip time `time_s`.
    pub fn offset_ending_green_at(&self, signal: &Signal, time_s: f64) -> f64 {
        let (phases, _) = self.plan_of(signal);
        let slot = slot_s(&self.timing);
        let cycle = slot * f64::from(phases.max(1));
        (f64::from(signal.phase) * slot + self.timing.green_s.max(0.1) - time_s).rem_euclid(cycle)
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
}
