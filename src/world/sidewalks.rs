//! The sidewalk walking graph (shortest walks between sidewalk points), crossing vectors (where a pedestrian at
//! a curb point would cross, and to which curb), and sidewalk sampling beside a route.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use super::routes::*;
use super::*;

/// Which side of a route.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    Left,
    Right,
}

/// A sidewalk point found beside a route.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SidewalkSample {
    /// Middle of the sidewalk, on the perpendicular through the route point.
    pub pos: DVec2,
    /// Arc length of the route point it was found beside.
    pub route_s_m: f64,
    /// Distance from the route's centre line.
    pub lateral_m: f64,
}

/// A crossing vector: perpendicular across the carriageway from a sidewalk point to the far sidewalk.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Crossing {
    /// The sidewalk point the crossing starts from.
    pub start: DVec2,
    /// Where the walker leaves the near sidewalk.
    pub near_curb: DVec2,
    /// Where the walker reaches the far sidewalk.
    pub far_curb: DVec2,
    /// A point on the far sidewalk (as deep into it as `start` is into the near one, within its width).
    pub end: DVec2,
    /// Unit direction of the crossing.
    pub direction: DVec2,
    /// `|far_curb - near_curb|`.
    pub carriageway_width_m: f64,
}

/// One edge of the sidewalk graph.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SidewalkEdge {
    pub to: u32,
    pub length_m: f64,
    /// True for edges across a crosswalk.
    pub crosswalk: bool,
}

/// Pedestrian walking graph: nodes on sidewalk centre lines (≥ 2 m apart), edges along sidewalks, between
/// sidewalks whose ends meet, and across crosswalks.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SidewalkGraph {
    pub nodes: Vec<DVec2>,
    edge_start: Vec<u32>,
    edges: Vec<SidewalkEdge>,
}

impl SidewalkGraph {
    pub(crate) fn build(net: &RoadNetwork) -> SidewalkGraph {
        let mut nodes: Vec<DVec2> = Vec::new();
        let mut node_lane: Vec<u32> = Vec::new();
        let mut pairs: Vec<(u32, u32, bool)> = Vec::new();
        let mut endpoints: Vec<u32> = Vec::new();
        for (li, l) in net.lanes.iter().enumerate() {
            if l.lane_type != LaneType::Sidewalk || l.length_m < 0.5 {
                continue;
            }
            let pieces = &net.pieces[l.pieces.start as usize..l.pieces.end as usize];
            if pieces.iter().all(|p| p.width_m[0].max(p.width_m[1]) < 0.3) {
                continue;
            }
            let c = lane_centre_line(net, li as u32);
            let first = nodes.len() as u32;
            for (k, &p) in c.iter().enumerate() {
                let last = k + 1 == c.len();
                if k > 0 && !last && (p - nodes[nodes.len() - 1]).length() < 2.0 {
                    continue;
                }
                if nodes.len() as u32 > first {
                    pairs.push((nodes.len() as u32 - 1, nodes.len() as u32, false));
                }
                nodes.push(p);
                node_lane.push(li as u32);
            }
            endpoints.push(first);
            endpoints.push(nodes.len() as u32 - 1);
        }
        let mut grid: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
        let cell = |p: DVec2| ((p.x / 2.0).floor() as i64, (p.y / 2.0).floor() as i64);
        for (i, &p) in nodes.iter().enumerate() {
            grid.entry(cell(p)).or_default().push(i as u32);
        }
        let near = |p: DVec2, r: f64, out: &mut Vec<(f64, u32)>| {
            out.clear();
            let (cx, cy) = cell(p);
            let k = (r / 2.0).ceil() as i64;
            for y in cy - k..=cy + k {
                for x in cx - k..=cx + k {
                    for &j in grid.get(&(x, y)).map_or(&[][..], |v| v.as_slice()) {
                        let d = (nodes[j as usize] - p).length();
                        if d <= r {
                            out.push((d, j));
                        }
                    }
                }
            }
            out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        };
        let mut buf = Vec::new();
        for &e in &endpoints {
            near(nodes[e as usize], 1.5, &mut buf);
            let mut seen_lanes: Vec<u32> = Vec::new();
            for &(_, j) in &buf {
                let lj = node_lane[j as usize];
                if lj == node_lane[e as usize] || seen_lanes.contains(&lj) {
                    continue;
                }
                seen_lanes.push(lj);
                pairs.push((e, j, false));
            }
        }
        for cw in &net.crosswalks {
            let Some((a, b)) = crosswalk_ends(&cw.polygon) else {
                continue;
            };
            near(a, 5.0, &mut buf);
            let na = buf.first().map(|x| x.1);
            near(b, 5.0, &mut buf);
            let nb = buf.first().map(|x| x.1);
            if let (Some(na), Some(nb)) = (na, nb)
                && na != nb
            {
                pairs.push((na, nb, true));
            }
        }
        let mut directed: Vec<(u32, u32, bool)> = Vec::with_capacity(pairs.len() * 2);
        for (a, b, c) in pairs {
            if a != b {
                directed.push((a, b, c));
                directed.push((b, a, c));
            }
        }
        directed.sort_unstable();
        directed.dedup_by(|x, y| x.0 == y.0 && x.1 == y.1);
        let mut edge_start = vec![0u32; nodes.len() + 1];
        for &(a, _, _) in &directed {
            edge_start[a as usize + 1] += 1;
        }
        for i in 0..nodes.len() {
            edge_start[i + 1] += edge_start[i];
        }
        let edges = directed
            .iter()
            .map(|&(a, b, c)| SidewalkEdge {
                to: b,
                length_m: (nodes[a as usize] - nodes[b as usize]).length(),
                crosswalk: c,
            })
            .collect();
        SidewalkGraph {
            nodes,
            edge_start,
            edges,
        }
    }

    /// Edges leaving node `n`.
    pub fn edges(&self, n: u32) -> &[SidewalkEdge] {
        let i = n as usize;
        if i + 1 >= self.edge_start.len() {
            return &[];
        }
        &self.edges[self.edge_start[i] as usize..self.edge_start[i + 1] as usize]
    }

    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The node nearest to `p` (linear scan; not for hot paths).
    pub fn nearest_node(&self, p: DVec2) -> Option<u32> {
        self.nodes
            .iter()
            .enumerate()
            .min_by(|a, b| (*a.1 - p).length_squared().total_cmp(&(*b.1 - p).length_squared()))
            .map(|(i, _)| i as u32)
    }

    /// Shortest walking path between the nodes nearest to `from` and `to` (Dijkstra), as points from `from`
    /// to `to`; None if they are not connected.
    pub fn path(&self, from: DVec2, to: DVec2) -> Option<Vec<DVec2>> {
        let a = self.nearest_node(from)?;
        let b = self.nearest_node(to)?;
        let n = self.nodes.len();
        let mut dist = vec![f64::INFINITY; n];
        let mut prev = vec![u32::MAX; n];
        let mut heap = BinaryHeap::new();
        dist[a as usize] = 0.0;
        heap.push(Reverse((0u64, a)));
        while let Some(Reverse((dbits, u))) = heap.pop() {
            let d = f64::from_bits(dbits);
            if d > dist[u as usize] {
                continue;
            }
            if u == b {
                break;
            }
            for e in self.edges(u) {
                let nd = d + e.length_m;
                if nd < dist[e.to as usize] {
                    dist[e.to as usize] = nd;
                    prev[e.to as usize] = u;
                    heap.push(Reverse((nd.to_bits(), e.to)));
                }
            }
        }
        if !dist[b as usize].is_finite() {
            return None;
        }
        let mut path = vec![to];
        let mut cur = b;
        while cur != u32::MAX {
            path.push(self.nodes[cur as usize]);
            cur = prev[cur as usize];
        }
        path.push(from);
        path.reverse();
        Some(path)
    }
}

/// The two ends of a crosswalk's long axis: midpoints of the shorter opposite sides of a quad, else the two
/// vertices farthest apart.
fn crosswalk_ends(poly: &[DVec2]) -> Option<(DVec2, DVec2)> {
    if poly.len() == 4 {
        let m = |i: usize, j: usize| (poly[i] + poly[j]) * 0.5;
        let (a0, a1) = (m(0, 1), m(2, 3));
        let (b0, b1) = (m(1, 2), m(3, 0));
        return Some(if (a1 - a0).length() > (b1 - b0).length() {
            (a0, a1)
        } else {
            (b0, b1)
        });
    }
    let mut best = None;
    let mut bd = 0.0;
    for (i, &p) in poly.iter().enumerate() {
        for &q in &poly[i + 1..] {
            let d = (p - q).length();
            if d > bd {
                bd = d;
                best = Some((p, q));
            }
        }
    }
    best
}

impl RoadNetwork {
    /// The sidewalk walking graph.
    pub fn sidewalk_graph(&self) -> &SidewalkGraph {
        &self.sidewalk_graph
    }

    /// Shortest sidewalk path (crosswalks included) between two points; see [`SidewalkGraph::path`].
    pub fn sidewalk_path(&self, from: DVec2, to: DVec2) -> Option<Vec<DVec2>> {
        self.sidewalk_graph.path(from, to)
    }

    /// The crossing vector at a sidewalk point: perpendicular to the sidewalk, across the carriageway, to the
    /// far sidewalk. None if `p` is not on a sidewalk, or no far sidewalk is found within 60 m across at least
    /// one driving lane (with no gap of more than 4 m off every lane).
    pub fn crossing_at(&self, p: DVec2) -> Option<Crossing> {
        self.crossing_at_3d(DVec3::new(p.x, p.y, f64::NAN))
    }

    /// Like [`crossing_at`](Self::crossing_at) for a point at elevation `p.z` (on a bridge, say).
    pub fn crossing_at_3d(&self, p3: DVec3) -> Option<Crossing> {
        // Coarse steps with bisection at the curbs: lanes narrower than a step (curbs, borders) may be stepped
        // over, which does not matter here; sidewalks and driving lanes are much wider.
        const STEP: f64 = 0.8;
        let p = p3.truncate();
        let hit = if p3.z.is_nan() {
            self.lane_at(p)?
        } else {
            self.lane_at_3d(p3)?
        };
        if hit.lane_type != LaneType::Sidewalk {
            return None;
        }
        let c = &self.pieces[hit.piece as usize].corners;
        let dir = (((c[0] + c[1]) - (c[2] + c[3])) * 0.5).normalize_or_zero();
        if dir == DVec2::ZERO {
            return None;
        }
        let z = hit.z_m;
        let is_sw = |t: f64| self.class(p + dir * t, z) == Some(LaneType::Sidewalk);
        // Bisect the boundary between `lo` (state a) and `hi` (state b).
        let bisect = |mut lo: f64, mut hi: f64, want_sidewalk_at_hi: bool| {
            for _ in 0..7 {
                let mid = 0.5 * (lo + hi);
                if is_sw(mid) == want_sidewalk_at_hi {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            hi
        };
        let mut t = 0.0;
        while is_sw(t) {
            t += STEP;
            if t > 15.0 {
                return None;
            }
        }
        let near_t = bisect(t - STEP, t, false);
        let mut crossed_driving = false;
        let mut gap = 0.0;
        let far_t = loop {
            t += STEP;
            if t > near_t + 60.0 {
                return None;
            }
            match self.class(p + dir * t, z) {
                Some(LaneType::Sidewalk) => break bisect(t - STEP, t, true),
                Some(LaneType::Driving) => {
                    crossed_driving = true;
                    gap = 0.0;
                }
                Some(_) => gap = 0.0,
                None => {
                    gap += STEP;
                    if gap > 4.0 {
                        return None;
                    }
                }
            }
        };
        if !crossed_driving {
            return None;
        }
        let far_w = self
            .index
            .lane_at(self, p + dir * (far_t + 0.05), Some(z))
            .map_or(0.4, |h| h.lane_width_m);
        let depth = near_t.clamp(0.1, (0.5 * far_w).max(0.1));
        let mut end = p + dir * (far_t + depth);
        if !is_sw(far_t + depth) {
            end = p + dir * (far_t + 0.05);
        }
        Some(Crossing {
            start: p,
            near_curb: p + dir * near_t,
            far_curb: p + dir * far_t,
            end,
            direction: dir,
            carriageway_width_m: far_t - near_t,
        })
    }

    /// The middle of the first sidewalk beside the route at arc length `s_m`, on `side`, within 40 m.
    pub fn sidewalk_beside(&self, route: &Route, s_m: f64, side: Side) -> Option<SidewalkSample> {
        if route.points.len() < 2 || s_m < 0.0 || s_m > route.length_m() {
            return None;
        }
        let pose = route.pose_at(s_m);
        let (sn, cs) = pose.heading_rad.sin_cos();
        let left = DVec2::new(-sn, cs);
        let n = if side == Side::Left { left } else { -left };
        // Step outwards to the first sidewalk, then bisect its near and far edges (a few `lane_at` calls
        // instead of one per 10 cm: this is the planner's hottest query).
        const STEP: f64 = 1.0;
        let is_sw = |t: f64| self.class(pose.pos + n * t, pose.z_m) == Some(LaneType::Sidewalk);
        let bisect = |mut inside: f64, mut outside: f64| {
            for _ in 0..6 {
                let mid = 0.5 * (inside + outside);
                if is_sw(mid) {
                    inside = mid;
                } else {
                    outside = mid;
                }
            }
            inside
        };
        let mut t = 0.5;
        while !is_sw(t) {
            t += STEP;
            if t > 40.0 {
                return None;
            }
        }
        let t0 = if t > 0.5 { bisect(t, t - STEP) } else { t };
        let mut t1 = t;
        while is_sw(t1 + STEP) && t1 < t0 + 8.0 {
            t1 += STEP;
        }
        let t1 = bisect(t1, t1 + STEP);
        let mid = 0.5 * (t0 + t1);
        Some(SidewalkSample {
            pos: pose.pos + n * mid,
            route_s_m: s_m,
            lateral_m: mid,
        })
    }

    /// Sidewalk points beside `route` at each of `distances_m` ahead of `s_m`, on `side` (None where the
    /// route ends first or there is no sidewalk).
    pub fn sidewalk_points_ahead(
        &self,
        route: &Route,
        s_m: f64,
        distances_m: &[f64],
        side: Side,
    ) -> Vec<Option<SidewalkSample>> {
        distances_m
            .iter()
            .map(|d| self.sidewalk_beside(route, s_m + d, side))
            .collect()
    }
}
