//! Lane graph, vehicle routes, the sidewalk walking graph, crossing vectors and sidewalk sampling.
//!
//! The lane graph links driving lanes end to start, in their direction of travel, where the centre line of
//! one ends within 0.5 m of where the next begins and the headings agree within 0.6 rad. Deriving the links
//! from geometry treats both sources alike and is robust to the link records of real files (which RoadRunner
//! writes per road and per junction connection, sometimes inconsistently); junction connecting lanes are
//! part of the graph like any other lane, so routes pass through junctions along them.

use std::collections::HashMap;

use glam::DVec2;
use rand::{Rng, RngExt};
use serde::Serialize;

use crate::world::{LaneType, RoadNetwork, TravelDirection};

const JOIN_M: f64 = 0.5;
const JOIN_HEADING_RAD: f64 = 0.6;
/// A bike lane counts as beside a driving lane across buffer lanes narrower than this, metres.
pub(super) const BIKE_LANE_BUFFER_MAX_M: f32 = 1.0;

/// Centre-line points of a lane, in its direction of travel (reference direction if undirected).
pub(crate) fn lane_centre_line(net: &RoadNetwork, lane: u32) -> Vec<DVec2> {
    lane_centre_points(net, lane).into_iter().map(|(p, _)| p).collect()
}

/// Centre-line points with the elevation of their piece.
fn lane_centre_points(net: &RoadNetwork, lane: u32) -> Vec<(DVec2, f64)> {
    let l = &net.lanes[lane as usize];
    let ps = &net.pieces[l.pieces.start as usize..l.pieces.end as usize];
    let mut out: Vec<(DVec2, f64)> = Vec::with_capacity(ps.len() + 1);
    for (i, p) in ps.iter().enumerate() {
        let c = p.centre();
        let z = p.z_m as f64;
        if i == 0 {
            out.push((c[0], z));
        }
        if (c[1] - out.last().map_or(c[0], |x| x.0)).length() > 1e-6 {
            out.push((c[1], z));
        }
    }
    if l.travel == TravelDirection::Backward {
        out.reverse();
    }
    out
}

fn heading(a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    d.y.atan2(d.x)
}

fn angle_diff(a: f64, b: f64) -> f64 {
    super::opendrive::geometry::wrap_angle(a - b).abs()
}

/// Successor links between driving lanes (compressed rows).
#[derive(Clone, Debug, Default)]
pub(crate) struct LaneGraph {
    start: Vec<u32>,
    succ: Vec<u32>,
}

impl LaneGraph {
    pub(crate) fn build(net: &RoadNetwork) -> LaneGraph {
        let n = net.lanes.len();
        // (entry point, entry heading, exit point, exit heading) per routable lane.
        let mut ends: Vec<Option<(DVec2, f64, DVec2, f64)>> = vec![None; n];
        let mut entries: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
        for (i, l) in net.lanes.iter().enumerate() {
            if l.lane_type != LaneType::Driving
                || !matches!(l.travel, TravelDirection::Forward | TravelDirection::Backward)
            {
                continue;
            }
            let c = lane_centre_line(net, i as u32);
            if c.len() < 2 || l.length_m < 0.1 {
                continue;
            }
            let e = (
                c[0],
                heading(c[0], c[1]),
                c[c.len() - 1],
                heading(c[c.len() - 2], c[c.len() - 1]),
            );
            ends[i] = Some(e);
            entries
                .entry(((e.0.x).floor() as i64, (e.0.y).floor() as i64))
                .or_default()
                .push(i as u32);
        }
        let mut start = Vec::with_capacity(n + 1);
        let mut succ = Vec::new();
        start.push(0);
        let mut found = Vec::new();
        for (i, e) in ends.iter().enumerate() {
            if let Some((_, _, exit, exit_h)) = *e {
                found.clear();
                let (cx, cy) = (exit.x.floor() as i64, exit.y.floor() as i64);
                for y in cy - 1..=cy + 1 {
                    for x in cx - 1..=cx + 1 {
                        for &j in entries.get(&(x, y)).map_or(&[][..], |v| v.as_slice()) {
                            if j as usize == i {
                                continue;
                            }
                            let (entry, entry_h, _, _) = ends[j as usize].expect("indexed lanes have ends");
                            if (entry - exit).length() <= JOIN_M && angle_diff(entry_h, exit_h) <= JOIN_HEADING_RAD {
                                found.push(j);
                            }
                        }
                    }
                }
                found.sort_unstable();
                found.dedup();
                succ.extend_from_slice(&found);
            }
            start.push(succ.len() as u32);
        }
        LaneGraph { start, succ }
    }

    pub(crate) fn successors(&self, lane: u32) -> &[u32] {
        let i = lane as usize;
        if i + 1 >= self.start.len() {
            return &[];
        }
        &self.succ[self.start[i] as usize..self.start[i + 1] as usize]
    }

    pub(crate) fn routable_lane_count(&self) -> usize {
        self.start.windows(2).filter(|w| w[1] > w[0]).count()
    }
}

/// One point of a [`Route`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RoutePoint {
    pub pos: DVec2,
    /// Direction of travel at this point.
    pub heading_rad: f64,
    /// Cumulative arc length from the route's start.
    pub s_m: f64,
    pub speed_limit_mps: f64,
    /// Index into [`RoadNetwork::lanes`].
    pub lane: u32,
    /// Elevation of the lane at this point.
    pub z_m: f64,
}

/// A vehicle route: a polyline along lane centre lines, through junctions, with cumulative arc length.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Route {
    pub points: Vec<RoutePoint>,
}

impl Route {
    pub fn length_m(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.s_m)
    }

    /// Interpolated pose at arc length `s_m` (clamped to the route).
    pub fn pose_at(&self, s_m: f64) -> RoutePoint {
        let pts = &self.points;
        let i = pts.partition_point(|p| p.s_m <= s_m).clamp(1, pts.len().max(2) - 1);
        if pts.len() < 2 {
            return pts[0];
        }
        let (a, b) = (&pts[i - 1], &pts[i]);
        let span = b.s_m - a.s_m;
        let t = if span > 0.0 {
            ((s_m - a.s_m) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        RoutePoint {
            pos: a.pos.lerp(b.pos, t),
            heading_rad: heading(a.pos, b.pos),
            s_m: a.s_m + span * t,
            speed_limit_mps: a.speed_limit_mps,
            lane: a.lane,
            z_m: a.z_m + (b.z_m - a.z_m) * t,
        }
    }
}

/// A place and direction where a vehicle can be spawned.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpawnPoint {
    pub pos: DVec2,
    pub heading_rad: f64,
    pub lane: u32,
    /// Distance along the lane's centre line (in its direction of travel) from the lane's start.
    pub lane_s_m: f64,
    pub speed_limit_mps: f64,
}

impl RoadNetwork {
    pub(super) fn class(&self, p: DVec2, z: f64) -> Option<LaneType> {
        self.index.lane_at(self, p, Some(z)).map(|h| h.lane_type)
    }

    /// Driving lanes that follow `lane` in its direction of travel.
    pub fn lane_successors(&self, lane: u32) -> &[u32] {
        self.lane_graph.successors(lane)
    }

    /// A route of at least `min_length_m` starting at a random lane outside junctions; tries up to 200 starts.
    pub fn random_route(&self, rng: &mut impl Rng, min_length_m: f64) -> Option<Route> {
        let starts: Vec<u32> = (0..self.lanes.len() as u32)
            .filter(|&l| !self.lanes[l as usize].in_junction && !self.lane_graph.successors(l).is_empty())
            .collect();
        if starts.is_empty() {
            return None;
        }
        for _ in 0..200 {
            let l = starts[rng.random_range(0..starts.len())];
            if let Some(r) = self.route_from(l, min_length_m, rng) {
                return Some(r);
            }
        }
        None
    }

    /// A route of at least `min_length_m` from the start of driving lane `lane`, choosing randomly among
    /// successors (preferring lanes not yet on the route). None at a dead end.
    pub fn route_from(&self, lane: u32, min_length_m: f64, rng: &mut impl Rng) -> Option<Route> {
        // Lane lengths slightly exceed the polyline's length (joins are merged), hence the small margin.
        let lanes = self.lane_walk(lane, min_length_m + 2.0 * JOIN_M, rng)?;
        let route = self.route_through(&lanes)?;
        (route.length_m() >= min_length_m).then_some(route)
    }

    /// The lanes of a random walk along the lane graph from driving lane `lane` whose lane lengths add up to
    /// at least `min_length_m`, preferring successors not yet visited. Cheap: builds no polyline (the planner
    /// stores walks; the executor turns them into routes with [`route_through`](Self::route_through)).
    pub fn lane_walk(&self, lane: u32, min_length_m: f64, rng: &mut impl Rng) -> Option<Vec<u32>> {
        let mut lanes: Vec<u32> = Vec::new();
        let mut cur = lane;
        let mut length = 0.0;
        for _ in 0..100_000 {
            let l = self.lanes.get(cur as usize)?;
            if l.lane_type != LaneType::Driving {
                return None;
            }
            lanes.push(cur);
            length += l.length_m;
            if length >= min_length_m {
                return Some(lanes);
            }
            let succ = self.lane_graph.successors(cur);
            if succ.is_empty() {
                return None;
            }
            let fresh = succ.iter().filter(|x| !lanes.contains(x)).count();
            cur = if fresh == 0 {
                succ[rng.random_range(0..succ.len())]
            } else {
                let k = rng.random_range(0..fresh);
                *succ.iter().filter(|x| !lanes.contains(x)).nth(k)?
            };
        }
        None
    }

    /// The route polyline along `lanes` (consecutive lanes should be successors), with cumulative arc length.
    /// None if a lane index is out of range or the route has fewer than two points.
    pub fn route_through(&self, lanes: &[u32]) -> Option<Route> {
        let mut points: Vec<RoutePoint> = Vec::new();
        let mut s = 0.0;
        for &lane in lanes {
            let l = self.lanes.get(lane as usize)?;
            let c = lane_centre_points(self, lane);
            for (k, &(p, z)) in c.iter().enumerate() {
                if let Some(last) = points.last() {
                    let d = (p - last.pos).length();
                    if d < 1e-6 || (k == 0 && d < JOIN_M * 2.0) {
                        continue;
                    }
                    s += d;
                }
                points.push(RoutePoint {
                    pos: p,
                    heading_rad: 0.0,
                    s_m: s,
                    speed_limit_mps: l.speed_limit_mps,
                    lane,
                    z_m: z,
                });
            }
        }
        if points.len() < 2 {
            return None;
        }
        for i in 0..points.len() {
            let (a, b) = if i + 1 < points.len() { (i, i + 1) } else { (i - 1, i) };
            points[i].heading_rad = heading(points[a].pos, points[b].pos);
        }
        Some(Route { points })
    }

    /// The bike lane beside a driving lane on the right of its travel (OpenDRIVE lane type `biking`), in the same
    /// lane section: the next lane outwards, or the first beyond narrow buffer lanes (border, shoulder or other,
    /// less than [`BIKE_LANE_BUFFER_MAX_M`] wide).
    pub fn bike_lane_beside(&self, lane: u32) -> Option<u32> {
        let l = self.lanes.get(lane as usize)?;
        let step = match (l.travel, l.lane_id.signum()) {
            (TravelDirection::Forward, -1) => -1,
            (TravelDirection::Backward, 1) => 1,
            _ => return None,
        };
        let road = self.roads.get(l.road as usize)?;
        let find = |id: i32| {
            (road.lanes.start..road.lanes.end)
                .find(|&k| self.lanes[k as usize].section == l.section && self.lanes[k as usize].lane_id == id)
        };
        let mut id = l.lane_id + step;
        while let Some(k) = find(id) {
            let next = &self.lanes[k as usize];
            match next.lane_type {
                LaneType::Biking => return Some(k),
                LaneType::Border | LaneType::Shoulder | LaneType::Other
                    if self.pieces[next.pieces.start as usize..next.pieces.end as usize]
                        .iter()
                        .all(|p| p.width_m[0].max(p.width_m[1]) < BIKE_LANE_BUFFER_MAX_M) => {}
                _ => return None,
            }
            id += step;
        }
        None
    }

    /// Where a route along `lanes` (as [`RoadNetwork::route_through`] joins them) runs beside a bike lane: at
    /// each route point, its arc length and the distance from the point to the centre line of the bike lane
    /// beside its lane ([`RoadNetwork::bike_lane_beside`]), or `None` where there is none. Empty where the
    /// route has no bike lane at all.
    pub fn bike_lane_offsets(&self, lanes: &[u32]) -> Vec<(f64, Option<f64>)> {
        let beside: HashMap<u32, (u32, Vec<DVec2>)> = lanes
            .iter()
            .filter_map(|&l| self.bike_lane_beside(l).map(|b| (l, (b, lane_centre_line(self, b)))))
            .collect();
        if beside.is_empty() {
            return Vec::new();
        }
        let Some(route) = self.route_through(lanes) else {
            return Vec::new();
        };
        route
            .points
            .iter()
            .map(|q| {
                let offset = beside.get(&q.lane).map(|(_, line)| {
                    line.windows(2)
                        .map(|w| crate::world::segment_projection(w[0], w[1], q.pos).1)
                        .fold(f64::INFINITY, f64::min)
                        .sqrt()
                });
                (q.s_m, offset)
            })
            .collect()
    }

    /// Spawn points every `spacing_m` along the centre lines of routable driving lanes outside junctions.
    pub fn driving_spawn_points(&self, spacing_m: f64) -> Vec<SpawnPoint> {
        let spacing = spacing_m.max(1.0);
        let mut out = Vec::new();
        for (i, l) in self.lanes.iter().enumerate() {
            if l.in_junction || self.lane_graph.successors(i as u32).is_empty() {
                continue;
            }
            let c = lane_centre_line(self, i as u32);
            let mut next = 0.5 * spacing;
            let mut s = 0.0;
            for w in c.windows(2) {
                let d = (w[1] - w[0]).length();
                while next <= s + d && d > 0.0 {
                    let t = (next - s) / d;
                    out.push(SpawnPoint {
                        pos: w[0].lerp(w[1], t),
                        heading_rad: heading(w[0], w[1]),
                        lane: i as u32,
                        lane_s_m: next,
                        speed_limit_mps: l.speed_limit_mps,
                    });
                    next += spacing;
                }
                s += d;
            }
        }
        out
    }
}
