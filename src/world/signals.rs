//! Traffic signals: the traffic lights of a town, one head per junction approach (the traffic entering a
//! junction from one road), each in one phase of its junction's signal plan.
//!
//! OpenDRIVE maps give theirs: `<signal dynamic="yes">` records on the approach roads (CARLA's maps carry
//! `type="1000001"`, a three-light head), tied to a junction by the `<signalReference>`s of its connecting
//! roads (or, without any, by the road end that meets a junction), and to a phase by the junction's
//! `<controller sequence>` records (CARLA turns a junction's controllers green one after another, in sequence
//! order). Built-in towns get a head at every approach of every junction with three or more approaches,
//! phased by axis (opposite approaches share a phase: two phases at a crossroads). A file without signals has
//! none: no signal is invented for an OpenDRIVE map.
//!
//! Where a vehicle stops is not the head's position but the approach's stop line, [`STOP_LINE_SETBACK_M`]
//! before the road end (behind the crosswalk across the road's mouth).

use glam::{DVec2, DVec3};
use serde::Serialize;

use super::opendrive::parse::{RawNetwork, ref_at};
use super::{LaneType, RoadNetwork, Route, point_in_polygon};

/// A vehicle stops this far before the end of its approach road: the crosswalks at junction mouths span 0.5 to
/// 3.5 m from the road end, so the stop line is 1 m behind them, metres.
pub const STOP_LINE_SETBACK_M: f64 = 4.5;
/// Height of a signal head's centre above the ground it stands on, metres (CARLA's `Signal_3Light_Post01`:
/// a post of about 3 m with the head at its top).
pub const SIGNAL_HEAD_HEIGHT_M: f64 = 2.8;
/// A synthesised head stands this far into the sidewalk from the curb, metres.
const POLE_FROM_CURB_M: f64 = 0.6;
/// Built-in towns signalise junctions with at least this many approaches.
const MIN_SIGNALISED_APPROACHES: usize = 3;

/// A traffic light head: it controls the traffic that enters junction `junction` from road `road`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Signal {
    /// The signal's id: the file's, or `j{junction id}_r{road id}_{start|end}` for synthesised ones.
    pub id: String,
    /// Index into [`RoadNetwork::junctions`].
    pub junction: u32,
    /// Index into [`RoadNetwork::roads`] of the approach road (outside the junction).
    pub road: u32,
    /// Whether the approach leaves the road at its end (`s = length`) rather than at its start.
    pub at_road_end: bool,
    /// The phase of the junction's signal plan in which it is green, `0..phases`.
    pub phase: u32,
    /// Centre of the head, world metres.
    pub position: DVec3,
    /// The direction the lamps face (towards the approaching traffic), radians.
    pub facing_rad: f64,
    /// True for heads placed by pedsynth (built-in towns) rather than read from the map.
    pub synthesized: bool,
}

/// The number of phases of junction `junction`'s signal plan (0: not signalised).
pub fn junction_phases(signals: &[Signal], junction: u32) -> u32 {
    signals
        .iter()
        .filter(|s| s.junction == junction)
        .map(|s| s.phase + 1)
        .max()
        .unwrap_or(0)
}

/// Where `route` enters a signalised junction from an approach road with a light: the arc length of the first
/// route point inside the junction and the light (index into [`RoadNetwork::signals`]), in route order.
pub fn signalised_entries(net: &RoadNetwork, route: &Route) -> Vec<(f64, u32)> {
    let mut out = Vec::new();
    if net.signals.is_empty() {
        return out;
    }
    for w in route.points.windows(2) {
        let (Some(from), Some(to)) = (net.lanes.get(w[0].lane as usize), net.lanes.get(w[1].lane as usize)) else {
            continue;
        };
        if from.in_junction || !to.in_junction {
            continue;
        }
        let Some(junction_id) = net.roads[to.road as usize].junction.as_deref() else {
            continue;
        };
        if let Some(signal) = net
            .signals
            .iter()
            .position(|g| g.road == from.road && net.junctions[g.junction as usize].id == junction_id)
        {
            out.push((w[1].s_m, signal as u32));
        }
    }
    out
}

/// The light of the signalised crosswalk under `p`: a crosswalk across an approach road with a light, the
/// light of that road's end nearest the crosswalk (index into [`RoadNetwork::signals`]).
pub fn crosswalk_signal(net: &RoadNetwork, p: DVec2) -> Option<u32> {
    let cw = net.crosswalks.iter().find(|c| point_in_polygon(&c.polygon, p))?;
    let centre = cw.polygon.iter().copied().sum::<DVec2>() / cw.polygon.len().max(1) as f64;
    net.signals
        .iter()
        .enumerate()
        .filter(|(_, g)| g.road == cw.road)
        .min_by(|a, b| {
            let d = |g: &Signal| g.position.truncate().distance_squared(centre);
            d(a.1).total_cmp(&d(b.1))
        })
        .map(|(k, _)| k as u32)
}

/// One approach of a junction: road `road` meeting junction `junction` at its end or its start.
#[derive(Clone, Copy, Debug)]
struct Approach {
    junction: u32,
    road: u32,
    at_road_end: bool,
    /// Heading of the traffic entering the junction, radians.
    heading_rad: f64,
}

/// The approaches of every junction: roads outside junctions whose predecessor or successor is the junction.
fn approaches(raw: &RawNetwork, net: &RoadNetwork) -> Vec<Approach> {
    let mut out = Vec::new();
    for (ri, road) in raw.roads.iter().enumerate() {
        if road.junction.is_some() {
            continue;
        }
        for (at_road_end, link) in [(false, &road.predecessor), (true, &road.successor)] {
            let Some(link) = link.as_ref().filter(|l| l.element_type == "junction") else {
                continue;
            };
            let Some(j) = net.junctions.iter().position(|j| j.id == link.element_id) else {
                continue;
            };
            let heading_rad = if at_road_end {
                ref_at(road, road.length).1
            } else {
                ref_at(road, 0.0).1 + std::f64::consts::PI
            };
            out.push(Approach {
                junction: j as u32,
                road: ri as u32,
                at_road_end,
                heading_rad,
            });
        }
    }
    out
}

/// Phase by axis: approaches within 45° of the junction's first approach's axis (either way) are phase 0, the
/// others phase 1.
fn axis_phase(first_heading_rad: f64, heading_rad: f64) -> u32 {
    if (heading_rad - first_heading_rad).cos().abs() >= std::f64::consts::FRAC_1_SQRT_2 {
        0
    } else {
        1
    }
}

/// The town's signals: the file's traffic lights, or (built-in towns, `synthesize`) one per approach of every
/// junction with [`MIN_SIGNALISED_APPROACHES`] or more. Sorted by junction, then road, then id.
pub(crate) fn derive(raw: &RawNetwork, net: &RoadNetwork, synthesize: bool) -> Vec<Signal> {
    let approaches = approaches(raw, net);
    let mut signals = if synthesize {
        synthesized(raw, net, &approaches)
    } else {
        from_file(raw, net, &approaches)
    };
    signals.sort_by(|a, b| (a.junction, a.road, &a.id).cmp(&(b.junction, b.road, &b.id)));
    signals
}

/// A head at every approach of junctions with enough approaches: on the sidewalk to the right of the entering
/// traffic, just before the stop line, phased by axis.
fn synthesized(raw: &RawNetwork, net: &RoadNetwork, approaches: &[Approach]) -> Vec<Signal> {
    let mut out = Vec::new();
    for (j, junction) in net.junctions.iter().enumerate() {
        let mine: Vec<&Approach> = approaches.iter().filter(|a| a.junction == j as u32).collect();
        if mine.len() < MIN_SIGNALISED_APPROACHES {
            continue;
        }
        let first = mine[0].heading_rad;
        for a in mine {
            let road = &raw.roads[a.road as usize];
            let s = if a.at_road_end {
                (road.length - STOP_LINE_SETBACK_M).max(0.0)
            } else {
                STOP_LINE_SETBACK_M.min(road.length)
            };
            let (p, _) = ref_at(road, s);
            let d = DVec2::from_angle(a.heading_rad);
            let position = roadside(net, a.road, p, DVec2::new(d.y, -d.x));
            out.push(Signal {
                id: format!(
                    "j{}_r{}_{}",
                    junction.id,
                    road.id,
                    if a.at_road_end { "end" } else { "start" }
                ),
                junction: j as u32,
                road: a.road,
                at_road_end: a.at_road_end,
                phase: axis_phase(first, a.heading_rad),
                position,
                facing_rad: a.heading_rad + std::f64::consts::PI,
                synthesized: true,
            });
        }
    }
    out
}

/// Where a head stands beside road `road` at reference point `p`, to the side `side` (unit): [`POLE_FROM_CURB_M`]
/// into the first sidewalk of the road that way, or just beyond its last lane; the head's centre
/// [`SIGNAL_HEAD_HEIGHT_M`] above that ground.
fn roadside(net: &RoadNetwork, road: u32, p: DVec2, side: DVec2) -> DVec3 {
    let mut last_on_road = (0.0, 0.0);
    for k in 0..=120 {
        let t = f64::from(k) * 0.25;
        let Some(hit) = net.lane_at(p + side * t).filter(|h| h.road == road) else {
            continue;
        };
        if hit.lane_type == LaneType::Sidewalk {
            let q = p + side * (t + POLE_FROM_CURB_M);
            return DVec3::new(q.x, q.y, hit.z_m + SIGNAL_HEAD_HEIGHT_M);
        }
        last_on_road = (t, hit.z_m);
    }
    let q = p + side * (last_on_road.0 + POLE_FROM_CURB_M);
    DVec3::new(q.x, q.y, last_on_road.1 + SIGNAL_HEAD_HEIGHT_M)
}

/// The file's traffic lights, each tied to the approach it controls. Signals that no approach takes (a light
/// on a road that meets no junction) are left out.
fn from_file(raw: &RawNetwork, net: &RoadNetwork, approaches: &[Approach]) -> Vec<Signal> {
    // Signal id -> junctions whose connecting roads reference it.
    let mut referenced: Vec<(&str, &str)> = Vec::new();
    for road in &raw.roads {
        if let Some(j) = road.junction.as_deref() {
            referenced.extend(road.signal_refs.iter().map(|id| (id.as_str(), j)));
        }
    }
    // Signal id -> controller id, controller id -> (junction, sequence).
    let controller_of = |signal: &str| {
        raw.controllers
            .iter()
            .find(|(_, ids)| ids.iter().any(|i| i == signal))
            .map(|(c, _)| c.as_str())
    };
    let sequence_of = |junction: &str, controller: &str| {
        raw.junctions
            .iter()
            .find(|j| j.id == junction)
            .and_then(|j| j.controllers.iter().find(|(c, _)| c == controller))
            .map(|&(_, seq)| seq)
    };

    let mut out = Vec::new();
    for (ri, road) in raw.roads.iter().enumerate() {
        for sig in &road.signals {
            // The approach road: this road, or the incoming road of the connecting road the light stands on.
            let approach_road = match road.junction {
                None => Some(ri),
                Some(_) => road
                    .predecessor
                    .as_ref()
                    .filter(|l| l.element_type == "road")
                    .and_then(|l| raw.roads.iter().position(|r| r.id == l.element_id)),
            };
            let Some(approach_road) = approach_road else { continue };
            let candidates: Vec<&Approach> = approaches.iter().filter(|a| a.road as usize == approach_road).collect();
            let by_reference = candidates.iter().find(|a| {
                referenced
                    .iter()
                    .any(|&(id, j)| id == sig.id && net.junctions[a.junction as usize].id == j)
            });
            let nearer_end = candidates.iter().min_by(|a, b| {
                let len = raw.roads[approach_road].length;
                let d = |x: &Approach| if x.at_road_end { (len - sig.s).abs() } else { sig.s };
                d(a).total_cmp(&d(b))
            });
            let Some(a) = by_reference.or(nearer_end).copied().copied() else {
                continue;
            };
            let (p, h) = ref_at(road, sig.s);
            let q = p + DVec2::new(-h.sin(), h.cos()) * sig.t;
            let ground = net.lane_at(q).map_or_else(
                || super::opendrive::geometry::eval_piecewise(&road.elevations, sig.s),
                |hit| hit.z_m,
            );
            let junction_id = &net.junctions[a.junction as usize].id;
            let phase = controller_of(&sig.id).and_then(|c| sequence_of(junction_id, c));
            out.push((
                Signal {
                    id: sig.id.clone(),
                    junction: a.junction,
                    road: a.road,
                    at_road_end: a.at_road_end,
                    phase: 0,
                    position: DVec3::new(q.x, q.y, ground + SIGNAL_HEAD_HEIGHT_M),
                    facing_rad: a.heading_rad + std::f64::consts::PI,
                    synthesized: false,
                },
                phase,
                a.heading_rad,
            ));
        }
    }
    // Phases: the rank of the controller's sequence among the junction's sequences; by axis where the file ties
    // a junction's lights to no controller.
    let mut signals = Vec::with_capacity(out.len());
    for j in 0..net.junctions.len() as u32 {
        let mine: Vec<&(Signal, Option<u32>, f64)> = out.iter().filter(|(s, _, _)| s.junction == j).collect();
        let Some(first_heading) = mine.first().map(|m| m.2) else {
            continue;
        };
        let mut sequences: Vec<u32> = mine.iter().filter_map(|(_, seq, _)| *seq).collect();
        sequences.sort_unstable();
        sequences.dedup();
        for (s, seq, heading) in mine {
            let mut s = s.clone();
            s.phase = match seq {
                Some(q) if sequences.len() > 1 => sequences.iter().position(|x| x == q).unwrap_or(0) as u32,
                _ => axis_phase(first_heading, *heading),
            };
            signals.push(s);
        }
    }
    signals
}
