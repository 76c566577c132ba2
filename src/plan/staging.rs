//! Traffic lights in the plan: where lights run, the planner stages the clip's signalised crossing (the
//! junction whose crosswalk its first signalised crosser waits at gets the offset at which the ego's approach
//! turns amber just before the ego reaches its stop line, so that the ego waits at red while the crosser gets
//! "walk" in front of it), and it estimates when the ego reaches each point of its route, red-light waits
//! included, so that a clip lasts as long as its crossers' timelines need.
//!
//! Both are estimates from the ego's cruising speed; the simulation decides what happens. Pure: a function of
//! the clip's scripts, its seed and the town.

use rand::RngExt;

use super::script::{PedestrianScript, Role};
use super::seeds;
use super::signal_plans::{SignalPlans, WalkSignal};
use crate::world::signals::{STOP_LINE_SETBACK_M, crosswalk_signal, signalised_entries};
use crate::world::{RoadNetwork, Route};

/// The ego's approach turns amber this long before the ego, at its cruising speed, would reach the stop line,
/// seconds: at urban speeds (8–14 m/s) it is then 32–56 m away, room to stop comfortably, so it stops.
const STAGED_AMBER_LEAD_S: f64 = 4.0;
/// The staged moment varies by up to this much either way (seeded per clip), seconds.
const STAGED_JITTER_S: f64 = 1.5;
/// A crosser at a signalised crosswalk steps out at the earliest this long after reaching its curb point (it
/// looks, checks and hesitates), seconds.
pub(crate) const SIGNAL_CHECK_S: f64 = 3.0;
/// ... and only with at least this much "walk" left, seconds.
const WALK_LEFT_S: f64 = 2.0;
/// Horizon of the search for the next "walk", seconds (two cycles of a four-phase junction and more).
const WALK_SEARCH_S: f64 = 150.0;
/// Step of that search, seconds.
const WALK_SEARCH_STEP_S: f64 = 0.25;

/// The ego's drive as the planner estimates it: at its cruising speed, waiting at each red (or amber) light on
/// its route until green.
#[derive(Clone, Debug)]
pub(crate) struct EgoSchedule {
    cruise_mps: f64,
    /// (stop line's arc length along the route, metres; wait there, seconds), in route order.
    waits: Vec<(f64, f64)>,
}

impl EgoSchedule {
    /// Without lights: the ego cruises.
    pub(super) fn cruising(cruise_mps: f64) -> EgoSchedule {
        EgoSchedule {
            cruise_mps,
            waits: Vec::new(),
        }
    }

    /// With the clip's `plans`: the ego waits at each stop line of `route` whose light is not green when it
    /// gets there.
    pub(super) fn with_lights(cruise_mps: f64, net: &RoadNetwork, route: &Route, plans: &SignalPlans) -> EgoSchedule {
        let mut schedule = EgoSchedule::cruising(cruise_mps);
        for (s_entry_m, signal) in signalised_entries(net, route) {
            let Some(light) = net.signals.get(signal as usize) else {
                continue;
            };
            let s_m = (s_entry_m - STOP_LINE_SETBACK_M).max(0.0);
            let arrive_s = schedule.time_at(s_m);
            let wait_s = plans.next_green_s(light, arrive_s) - arrive_s;
            schedule.waits.push((s_m, wait_s));
        }
        schedule
    }

    /// When the ego reaches arc length `s_m` of its route (it starts at 0), seconds: the waits at stop lines
    /// before `s_m` count, one at `s_m` itself does not.
    pub(super) fn time_at(&self, s_m: f64) -> f64 {
        let waited: f64 = self.waits.iter().filter(|&&(s, _)| s < s_m).map(|&(_, w)| w).sum();
        s_m.max(0.0) / self.cruise_mps.max(0.1) + waited
    }
}

/// The signal (index into the town's signals) of the crosswalk a crosser's planned crossing runs along, if any
/// (the simulation asks the same: [`crosswalk_signal`] at the crossing's middle).
pub(crate) fn crossing_signal(net: &RoadNetwork, p: &PedestrianScript) -> Option<u32> {
    let c = p.crossing.as_ref()?;
    crosswalk_signal(net, c.near_curb + c.direction * (0.5 * c.carriageway_width_m))
}

/// The offset the planner sets for the junction of the first crosser (in pedestrian order) waiting at a
/// signalised crosswalk on the ego's approach (junction, offset into its cycle), or none: the ego's light there
/// turns amber [`STAGED_AMBER_LEAD_S`] (± [`STAGED_JITTER_S`], from the clip's `plan/signal_offsets` stream)
/// before the ego would reach its stop line. `drawn` are the clip's drawn plans and `schedule` the ego's drive
/// under them: the waits at earlier junctions count, the one being staged does not.
pub(crate) fn staged_offset(
    net: &RoadNetwork,
    clip_seed: u64,
    route: &Route,
    pedestrians: &[PedestrianScript],
    (drawn, schedule): (&SignalPlans, &EgoSchedule),
) -> Option<(u32, f64)> {
    let entries = signalised_entries(net, route);
    let (s_entry_m, light) = pedestrians
        .iter()
        .filter(|p| p.role == Role::Crosser && p.in_view_before_crossing_s.is_some() && !p.red_light_violator)
        .filter_map(|p| crossing_signal(net, p))
        .find_map(|signal| {
            let junction = net.signals.get(signal as usize)?.junction;
            entries
                .iter()
                .find(|&&(_, e)| net.signals.get(e as usize).is_some_and(|l| l.junction == junction))
                .and_then(|&(s, e)| Some((s, net.signals.get(e as usize)?)))
        })?;
    let stop_line_m = (s_entry_m - STOP_LINE_SETBACK_M).max(0.0);
    let jitter_s = seeds::clip_rng(clip_seed, "plan/signal_offsets").random_range(-STAGED_JITTER_S..=STAGED_JITTER_S);
    // `time_at` counts only the waits before this stop line.
    let amber_at_s = schedule.time_at(stop_line_m) - STAGED_AMBER_LEAD_S + jitter_s;
    Some((light.junction, drawn.offset_ending_green_at(light, amber_at_s)))
}

/// When a crosser at a signalised crosswalk can step out, seconds into the clip: the first moment from `ready_s`
/// on with "walk" and [`WALK_LEFT_S`] of it left (or `ready_s` when none comes within the search horizon).
pub(crate) fn walk_start_s(plans: &SignalPlans, net: &RoadNetwork, signal: u32, ready_s: f64) -> f64 {
    let Some(light) = net.signals.get(signal as usize) else {
        return ready_s;
    };
    let steps = (WALK_SEARCH_S / WALK_SEARCH_STEP_S) as u32;
    (0..steps)
        .map(|k| ready_s + f64::from(k) * WALK_SEARCH_STEP_S)
        .find(|&t| {
            plans.walk_at(light, t) == WalkSignal::Walk && plans.walk_at(light, t + WALK_LEFT_S) == WalkSignal::Walk
        })
        .unwrap_or(ready_s)
}
