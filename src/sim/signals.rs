//! Traffic lights in the simulation: the stop lines on a vehicle's path where a light applies to it, and the
//! kinematics of stopping there. The lights' states come from the clip's signal plans
//! ([`crate::plan::signal_plans`], re-exported here), a pure function of the clip's time.

use crate::plan::RouteScript;
pub use crate::plan::signal_plans::{LightState, SignalPlans, WalkSignal, phase_state};
use crate::world::RoadNetwork;
use crate::world::signals::{STOP_LINE_SETBACK_M, signalised_entries};

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
    fn can_stop_is_the_kinematic_stopping_distance() {
        assert!(can_stop(16.7, 10.0, 3.0));
        assert!(!can_stop(16.6, 10.0, 3.0));
        assert!(can_stop(0.0, 0.0, 3.0));
    }
}
