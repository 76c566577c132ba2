//! Built-in procedural towns: a deterministic, parameterised grid generator that emits the same raw
//! OpenDRIVE records as the importer (roads with lane sections, junctions with connecting roads, corner
//! sidewalks) plus building blocks, so both sources share one builder.
//!
//! A town is a grid of junctions with jittered spacing. Grid edges are roads; some are removed to make
//! T-junctions and corners. Each road has, per side from the centre: an optional half median, driving lanes,
//! a curb (shoulder) and a sidewalk. Junction boxes hold connecting roads for every straight, right and left
//! movement (arcs where the geometry allows, paramPoly3 Hermite curves otherwise) and sidewalks around their
//! corners (arcs) or along their closed sides (lines). Crosswalks are derived by the builder at every
//! junction mouth. All randomness comes from a ChaCha8 generator with a fixed seed per town.

use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;

use glam::DVec2;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::opendrive::build::build_with;
use super::opendrive::geometry::{GeomKind, Geometry, Poly3At};
use super::opendrive::parse::{RawJunction, RawLane, RawNetwork, RawRoad, RawSection};
use crate::world::{JunctionConnection, LaneType, Obstacle, ObstacleKind, RoadLink, RoadNetwork, TownSource};

const MPH: f64 = 0.44704;
/// Radius of the inner edge of corner sidewalks (the building corner is inside it).
const CORNER_INNER_M: f64 = 3.0;
/// Gap between sidewalk and buildings.
const SETBACK_M: f64 = 2.0;

#[derive(Clone, Copy)]
struct Class {
    lanes_per_dir: usize,
    lane_w: f64,
    median_w: f64,
    curb_w: f64,
    speed_mps: f64,
}

impl Class {
    fn half(&self) -> f64 {
        0.5 * self.median_w + self.lanes_per_dir as f64 * self.lane_w + self.curb_w
    }
    fn lane_offset(&self, i: usize) -> f64 {
        0.5 * self.median_w + (i as f64 + 0.5) * self.lane_w
    }
}

struct Params {
    name: &'static str,
    description: &'static str,
    seed: u64,
    nx: usize,
    ny: usize,
    spacing_m: (f64, f64),
    sidewalk_w: f64,
    street: Class,
    avenue: Class,
    avenue_x_lines: &'static [usize],
    avenue_y_lines: &'static [usize],
    /// Remove interior edges until no 4-way junction is left (Town01-like) ...
    only_t_junctions: bool,
    /// ... or remove this many random edges.
    removals: usize,
    height_m: (f64, f64),
}

const STREET_4M: Class = Class {
    lanes_per_dir: 1,
    lane_w: 4.0,
    median_w: 0.0,
    curb_w: 0.3,
    speed_mps: 25.0 * MPH,
};
const STREET_35: Class = Class {
    lanes_per_dir: 1,
    lane_w: 3.5,
    median_w: 0.0,
    curb_w: 0.5,
    speed_mps: 25.0 * MPH,
};

fn params(name: &str) -> Option<Params> {
    Some(match name {
        "town01_like" => Params {
            name: "town01_like",
            description: "small two-lane town with T-junctions (like CARLA Town01)",
            seed: 0x7_0001,
            nx: 4,
            ny: 3,
            spacing_m: (100.0, 135.0),
            sidewalk_w: 3.7,
            street: STREET_4M,
            avenue: STREET_4M,
            avenue_x_lines: &[],
            avenue_y_lines: &[],
            only_t_junctions: true,
            removals: 0,
            height_m: (6.0, 20.0),
        },
        "town02_like" => Params {
            name: "town02_like",
            description: "compact two-lane town, short blocks (like CARLA Town02)",
            seed: 0x7_0002,
            nx: 4,
            ny: 3,
            spacing_m: (48.0, 70.0),
            sidewalk_w: 3.7,
            street: STREET_4M,
            avenue: STREET_4M,
            avenue_x_lines: &[],
            avenue_y_lines: &[],
            only_t_junctions: false,
            removals: 2,
            height_m: (6.0, 15.0),
        },
        "town03_like" => Params {
            name: "town03_like",
            description: "multi-lane town with medians and varied junctions (like CARLA Town03)",
            seed: 0x7_0003,
            nx: 5,
            ny: 4,
            spacing_m: (75.0, 110.0),
            sidewalk_w: 3.0,
            street: STREET_35,
            avenue: Class {
                lanes_per_dir: 2,
                lane_w: 3.5,
                median_w: 2.0,
                curb_w: 0.5,
                speed_mps: 30.0 * MPH,
            },
            avenue_x_lines: &[2],
            avenue_y_lines: &[1],
            only_t_junctions: false,
            removals: 3,
            height_m: (8.0, 40.0),
        },
        "town05_like" => Params {
            name: "town05_like",
            description: "grid with multi-lane avenues (like CARLA Town05)",
            seed: 0x7_0005,
            nx: 6,
            ny: 5,
            spacing_m: (68.0, 92.0),
            sidewalk_w: 3.0,
            street: STREET_35,
            avenue: Class {
                lanes_per_dir: 3,
                lane_w: 3.5,
                median_w: 1.0,
                curb_w: 0.5,
                speed_mps: 35.0 * MPH,
            },
            avenue_x_lines: &[1, 4],
            avenue_y_lines: &[2],
            only_t_junctions: false,
            removals: 2,
            height_m: (10.0, 60.0),
        },
        _ => return None,
    })
}

/// One-line description of a built-in town.
pub(crate) fn description(name: &str) -> Option<&'static str> {
    params(name).map(|p| p.description)
}

/// The raw OpenDRIVE records and the building blocks of a built-in town (what [`build`] builds from).
pub(crate) fn raw(name: &str) -> Option<(RawNetwork, Vec<Obstacle>)> {
    params(name).map(|p| generate(&p))
}

pub(crate) fn build(name: &str) -> Option<RoadNetwork> {
    let p = params(name)?;
    let (raw, obstacles) = generate(&p);
    let net = build_with(
        raw,
        p.name.to_string(),
        TownSource::Builtin,
        p.name,
        "",
        Some(obstacles),
        true,
    )
    .expect("built-in towns are valid OpenDRIVE (covered by tests/it/world_builtin.rs)");
    Some(net)
}

fn width(w: f64) -> Vec<Poly3At> {
    vec![Poly3At {
        s: 0.0,
        c: [w, 0.0, 0.0, 0.0],
        pos: 0,
    }]
}

fn lane(id: i32, lane_type: LaneType, w: f64) -> RawLane {
    RawLane {
        id,
        lane_type,
        widths: width(w),
        speed_mps: None,
        travel: None,
        links: (None, None),
        pos: 0,
    }
}

fn geom(p: DVec2, hdg: f64, length: f64, kind: GeomKind) -> Geometry {
    Geometry {
        s: 0.0,
        x: p.x,
        y: p.y,
        hdg,
        length,
        kind,
        pos: 0,
    }
}

fn angle(v: DVec2) -> f64 {
    v.y.atan2(v.x)
}

fn left_n(u: DVec2) -> DVec2 {
    DVec2::new(-u.y, u.x)
}

fn junction_link(id: usize) -> Option<RoadLink> {
    Some(RoadLink {
        element_type: "junction".into(),
        element_id: id.to_string(),
        contact_point: None,
    })
}

/// Arms E and N of a junction are the start of their through road, W and S its end.
fn arm_starts_road(arm: usize) -> bool {
    arm < 2
}

/// Id of driving lane `k` (0 = nearest the centre) on arm `arm` of a junction, for traffic coming into the
/// junction (`incoming`) or leaving it. Right-hand traffic: on a road that starts at the junction, incoming
/// traffic drives against the reference direction, on the left (positive ids).
fn arm_lane_id(arm: usize, class: &Class, k: usize, incoming: bool) -> i32 {
    let magnitude = (k + 1 + usize::from(class.median_w > 0.0)) as i32;
    if arm_starts_road(arm) == incoming {
        magnitude
    } else {
        -magnitude
    }
}

/// Link from a connecting road to the through road on arm `arm`, at the end that touches the junction.
fn road_link(road_id: &str, arm: usize) -> RoadLink {
    RoadLink {
        element_type: "road".into(),
        element_id: road_id.into(),
        contact_point: Some(if arm_starts_road(arm) { "start" } else { "end" }.into()),
    }
}

struct Gen {
    roads: Vec<RawRoad>,
}

impl Gen {
    #[allow(clippy::too_many_arguments)]
    fn road(
        &mut self,
        g: Geometry,
        lanes: Vec<RawLane>,
        lane_offset: f64,
        junction: Option<usize>,
        speed: f64,
        pred: Option<RoadLink>,
        succ: Option<RoadLink>,
    ) -> String {
        let id = (self.roads.len() + 1).to_string();
        self.roads.push(RawRoad {
            id: id.clone(),
            name: String::new(),
            length: g.length,
            junction: junction.map(|j| j.to_string()),
            lht: false,
            pos: 0,
            predecessor: pred,
            successor: succ,
            speeds: vec![(0.0, speed)],
            geometries: vec![g],
            elevations: Vec::new(),
            lane_offsets: vec![Poly3At {
                s: 0.0,
                c: [lane_offset, 0.0, 0.0, 0.0],
                pos: 0,
            }],
            sections: vec![RawSection { s: 0.0, pos: 0, lanes }],
            objects: Vec::new(),
            signals: Vec::new(),
            signal_refs: Vec::new(),
        });
        id
    }
}

/// Lanes of a through road: per side, half median, driving lanes, curb, sidewalk.
fn arm_lanes(c: &Class, sidewalk_w: f64) -> Vec<RawLane> {
    let mut out = Vec::new();
    for side in [1i32, -1] {
        let mut k = 1;
        if c.median_w > 0.0 {
            out.push(lane(side * k, LaneType::Median, 0.5 * c.median_w));
            k += 1;
        }
        for _ in 0..c.lanes_per_dir {
            out.push(lane(side * k, LaneType::Driving, c.lane_w));
            k += 1;
        }
        out.push(lane(side * k, LaneType::Shoulder, c.curb_w));
        out.push(lane(side * (k + 1), LaneType::Sidewalk, sidewalk_w));
    }
    out
}

/// Hermite curve from `a` (heading `ha`) to `b` (heading `hb`) as a normalised paramPoly3, with its length.
fn hermite(a: DVec2, ha: f64, b: DVec2, hb: f64) -> Geometry {
    let (s, c) = ha.sin_cos();
    let d = b - a;
    let local = DVec2::new(c * d.x + s * d.y, -s * d.x + c * d.y);
    let l = 1.657 * 0.5 * (local.x.abs() + local.y.abs());
    let t0 = DVec2::new(l, 0.0);
    let dh = hb - ha;
    let t1 = DVec2::new(dh.cos(), dh.sin()) * l;
    let p1 = local;
    let c2 = p1 * 3.0 - t0 * 2.0 - t1;
    let c3 = -p1 * 2.0 + t0 + t1;
    let u = [0.0, t0.x, c2.x, c3.x];
    let v = [0.0, t0.y, c2.y, c3.y];
    let eval = |t: f64| {
        DVec2::new(
            u[1] * t + u[2] * t * t + u[3] * t * t * t,
            v[1] * t + v[2] * t * t + v[3] * t * t * t,
        )
    };
    let mut len = 0.0;
    let mut prev = eval(0.0);
    for i in 1..=256 {
        let q = eval(i as f64 / 256.0);
        len += (q - prev).length();
        prev = q;
    }
    geom(a, ha, len, GeomKind::ParamPoly3 { u, v, normalized: true })
}

/// Path for a vehicle from `a` (heading `ha`) to `b` (heading `hb`): a line, an exact quarter arc, or a
/// Hermite paramPoly3.
fn connector(a: DVec2, ha: f64, b: DVec2, hb: f64) -> Geometry {
    let (s, c) = ha.sin_cos();
    let d = b - a;
    let local = DVec2::new(c * d.x + s * d.y, -s * d.x + c * d.y);
    if local.y.abs() < 1e-6 {
        return geom(a, ha, local.x, GeomKind::Line);
    }
    if (local.x - local.y.abs()).abs() < 1e-6 {
        let r = local.x;
        return geom(
            a,
            ha,
            r * FRAC_PI_2,
            GeomKind::Arc {
                curvature: local.y.signum() / r,
            },
        );
    }
    hermite(a, ha, b, hb)
}

/// Generates the raw network and the building blocks of a town.
fn generate(p: &Params) -> (RawNetwork, Vec<Obstacle>) {
    let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
    let mut xs = vec![0.0];
    for _ in 1..p.nx {
        let last = xs[xs.len() - 1];
        xs.push(last + rng.random_range(p.spacing_m.0..p.spacing_m.1));
    }
    let mut ys = vec![0.0];
    for _ in 1..p.ny {
        let last = ys[ys.len() - 1];
        ys.push(last + rng.random_range(p.spacing_m.0..p.spacing_m.1));
    }
    let vclass = |i: usize| {
        if p.avenue_x_lines.contains(&i) {
            p.avenue
        } else {
            p.street
        }
    };
    let hclass = |j: usize| {
        if p.avenue_y_lines.contains(&j) {
            p.avenue
        } else {
            p.street
        }
    };
    let (nx, ny) = (p.nx, p.ny);
    // Edges: h[i][j] joins (i,j)-(i+1,j); v[i][j] joins (i,j)-(i,j+1).
    let mut h = vec![vec![true; ny]; nx - 1];
    let mut v = vec![vec![true; ny - 1]; nx];
    let degree = |h: &Vec<Vec<bool>>, v: &Vec<Vec<bool>>, i: usize, j: usize| {
        let mut d = 0;
        if i + 1 < nx && h[i][j] {
            d += 1;
        }
        if i > 0 && h[i - 1][j] {
            d += 1;
        }
        if j + 1 < ny && v[i][j] {
            d += 1;
        }
        if j > 0 && v[i][j - 1] {
            d += 1;
        }
        d
    };
    let connected = |h: &Vec<Vec<bool>>, v: &Vec<Vec<bool>>| {
        let mut seen = vec![false; nx * ny];
        let mut stack = vec![(0usize, 0usize)];
        seen[0] = true;
        let mut count = 1;
        while let Some((i, j)) = stack.pop() {
            let mut nb = Vec::new();
            if i + 1 < nx && h[i][j] {
                nb.push((i + 1, j));
            }
            if i > 0 && h[i - 1][j] {
                nb.push((i - 1, j));
            }
            if j + 1 < ny && v[i][j] {
                nb.push((i, j + 1));
            }
            if j > 0 && v[i][j - 1] {
                nb.push((i, j - 1));
            }
            for (a, b) in nb {
                if !seen[b * nx + a] {
                    seen[b * nx + a] = true;
                    count += 1;
                    stack.push((a, b));
                }
            }
        }
        count == nx * ny
    };
    // Candidate interior edges (never on the boundary, never on an avenue), in a fixed order.
    let mut cands: Vec<(bool, usize, usize)> = Vec::new();
    for j in 1..ny - 1 {
        for i in 0..nx - 1 {
            if !p.avenue_y_lines.contains(&j) {
                cands.push((true, i, j));
            }
        }
    }
    for i in 1..nx - 1 {
        for j in 0..ny - 1 {
            if !p.avenue_x_lines.contains(&i) {
                cands.push((false, i, j));
            }
        }
    }
    let mut removed = 0;
    for _ in 0..200 {
        if cands.is_empty() {
            break;
        }
        if !p.only_t_junctions && removed >= p.removals {
            break;
        }
        if p.only_t_junctions && (0..nx).all(|i| (0..ny).all(|j| degree(&h, &v, i, j) < 4)) {
            break;
        }
        let k = rng.random_range(0..cands.len());
        let (horiz, i, j) = cands.swap_remove(k);
        let (a, b) = if horiz {
            ((i, j), (i + 1, j))
        } else {
            ((i, j), (i, j + 1))
        };
        if p.only_t_junctions && degree(&h, &v, a.0, a.1) < 4 && degree(&h, &v, b.0, b.1) < 4 {
            continue;
        }
        if degree(&h, &v, a.0, a.1) < 3 || degree(&h, &v, b.0, b.1) < 3 {
            continue;
        }
        if horiz {
            h[i][j] = false;
        } else {
            v[i][j] = false;
        }
        if connected(&h, &v) {
            removed += 1;
        } else if horiz {
            h[i][j] = true;
        } else {
            v[i][j] = true;
        }
    }

    let r = p.sidewalk_w + CORNER_INNER_M;
    let jx = |i: usize| vclass(i).half() + r;
    let jy = |j: usize| hclass(j).half() + r;
    let node_id = |i: usize, j: usize| j * nx + i + 1;
    let mut g = Gen { roads: Vec::new() };
    // (node i, node j, arm index E=0 N=1 W=2 S=3) → id of the through road on that arm.
    let mut arm_road: BTreeMap<(usize, usize, usize), String> = BTreeMap::new();
    // Through roads.
    for j in 0..ny {
        for i in 0..nx - 1 {
            if h[i][j] {
                let a = DVec2::new(xs[i] + jx(i), ys[j]);
                let b = DVec2::new(xs[i + 1] - jx(i + 1), ys[j]);
                let c = hclass(j);
                let id = g.road(
                    geom(a, 0.0, b.x - a.x, GeomKind::Line),
                    arm_lanes(&c, p.sidewalk_w),
                    0.0,
                    None,
                    c.speed_mps,
                    junction_link(node_id(i, j)),
                    junction_link(node_id(i + 1, j)),
                );
                arm_road.insert((i, j, 0), id.clone());
                arm_road.insert((i + 1, j, 2), id);
            }
        }
    }
    for i in 0..nx {
        for j in 0..ny - 1 {
            if v[i][j] {
                let a = DVec2::new(xs[i], ys[j] + jy(j));
                let b = DVec2::new(xs[i], ys[j + 1] - jy(j + 1));
                let c = vclass(i);
                let id = g.road(
                    geom(a, FRAC_PI_2, b.y - a.y, GeomKind::Line),
                    arm_lanes(&c, p.sidewalk_w),
                    0.0,
                    None,
                    c.speed_mps,
                    junction_link(node_id(i, j)),
                    junction_link(node_id(i, j + 1)),
                );
                arm_road.insert((i, j, 1), id.clone());
                arm_road.insert((i, j + 1, 3), id);
            }
        }
    }
    // Junctions.
    let mut junctions = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let jid = node_id(i, j);
            let node = DVec2::new(xs[i], ys[j]);
            // Arms counter-clockwise: E, N, W, S: (direction, present, class, box half-size along it).
            let arms = [
                (DVec2::X, i + 1 < nx && h[i][j], hclass(j), jx(i)),
                (DVec2::Y, j + 1 < ny && v[i][j], vclass(i), jy(j)),
                (-DVec2::X, i > 0 && h[i - 1][j], hclass(j), jx(i)),
                (-DVec2::Y, j > 0 && v[i][j - 1], vclass(i), jy(j)),
            ];
            let mut connections = Vec::new();
            for (ka, (ua, pa, ca, ja)) in arms.into_iter().enumerate() {
                if !pa {
                    continue;
                }
                for (kb, (ub, pb, cb, jb)) in arms.into_iter().enumerate() {
                    if !pb || ub == ua {
                        continue;
                    }
                    let turn = (-ua).perp_dot(ub);
                    let pairs: Vec<(usize, usize)> = if turn.abs() < 0.5 {
                        (0..ca.lanes_per_dir.min(cb.lanes_per_dir)).map(|k| (k, k)).collect()
                    } else if turn < 0.0 {
                        vec![(ca.lanes_per_dir - 1, cb.lanes_per_dir - 1)]
                    } else {
                        vec![(0, 0)]
                    };
                    for (la, lb) in pairs {
                        let a = node + ua * ja + left_n(ua) * ca.lane_offset(la);
                        let b = node + ub * jb - left_n(ub) * cb.lane_offset(lb);
                        let ga = connector(a, angle(-ua), b, angle(ub));
                        let w = ca.lane_w;
                        let incoming = arm_road.get(&(i, j, ka)).cloned().unwrap_or_default();
                        let outgoing = arm_road.get(&(i, j, kb)).cloned().unwrap_or_default();
                        let (from_lane, to_lane) = (arm_lane_id(ka, &ca, la, true), arm_lane_id(kb, &cb, lb, false));
                        let mut connector_lane = lane(-1, LaneType::Driving, w);
                        connector_lane.links = (Some(from_lane), Some(to_lane));
                        let id = g.road(
                            ga,
                            vec![connector_lane],
                            0.5 * w,
                            Some(jid),
                            ca.speed_mps.min(cb.speed_mps),
                            Some(road_link(&incoming, ka)),
                            Some(road_link(&outgoing, kb)),
                        );
                        connections.push(JunctionConnection {
                            incoming_road: incoming,
                            connecting_road: id,
                            contact_point: "start".into(),
                            lane_links: vec![(from_lane, -1)],
                        });
                    }
                }
            }
            // Corner sidewalks (arcs) and sidewalks along closed sides (lines).
            for k in 0..4 {
                let (ua, pa, ca, ja) = arms[k];
                let (ub, pb, _, jb) = arms[(k + 1) % 4];
                if pa && pb {
                    let start = node + ua * ja + ub * ca.half();
                    let rr = jb - ca.half();
                    g.road(
                        geom(
                            start,
                            angle(-ua),
                            rr * FRAC_PI_2,
                            GeomKind::Arc { curvature: -1.0 / rr },
                        ),
                        vec![lane(-1, LaneType::Sidewalk, p.sidewalk_w)],
                        0.0,
                        Some(jid),
                        STREET_35.speed_mps,
                        None,
                        None,
                    );
                }
            }
            for k in 0..4 {
                let (um, pm, _, _) = arms[k];
                if pm {
                    continue;
                }
                let hdir = left_n(um);
                // The arm on the -hdir side and the one on the +hdir side.
                let extent = |d: DVec2| {
                    let (_, pd, _, jd) = arms
                        .iter()
                        .copied()
                        .find(|a| (a.0 - d).length() < 1e-9)
                        .expect("four arms");
                    // The band of a missing arm in direction d sits at the half width of the line across d.
                    let across = arms
                        .iter()
                        .copied()
                        .find(|a| (a.0 - um).length() < 1e-9)
                        .map(|a| a.2)
                        .expect("arm");
                    if pd { jd } else { across.half() + p.sidewalk_w }
                };
                let a_ext = extent(-hdir);
                let b_ext = extent(hdir);
                let perp_half = arms
                    .iter()
                    .copied()
                    .find(|a| (a.0 - hdir).length() < 1e-9)
                    .map(|a| a.2.half())
                    .expect("arm");
                let start = node + um * perp_half - hdir * a_ext;
                g.road(
                    geom(start, angle(hdir), a_ext + b_ext, GeomKind::Line),
                    vec![lane(-1, LaneType::Sidewalk, p.sidewalk_w)],
                    0.0,
                    Some(jid),
                    STREET_35.speed_mps,
                    None,
                    None,
                );
            }
            junctions.push(RawJunction {
                id: jid.to_string(),
                name: format!("junction {i},{j}"),
                connections,
                controllers: Vec::new(),
            });
        }
    }
    // Buildings: lots in every block, and a band of blocks around the outside of the grid.
    let mut obstacles = Vec::new();
    let band = 30.0;
    let line_x = |i: isize| -> (f64, f64) {
        if i < 0 {
            (xs[0] - band - vclass(0).half() - p.sidewalk_w, 0.0)
        } else if i as usize >= nx {
            (xs[nx - 1] + band + vclass(nx - 1).half() + p.sidewalk_w, 0.0)
        } else {
            (xs[i as usize], vclass(i as usize).half() + p.sidewalk_w + SETBACK_M)
        }
    };
    let line_y = |j: isize| -> (f64, f64) {
        if j < 0 {
            (ys[0] - band - hclass(0).half() - p.sidewalk_w, 0.0)
        } else if j as usize >= ny {
            (ys[ny - 1] + band + hclass(ny - 1).half() + p.sidewalk_w, 0.0)
        } else {
            (ys[j as usize], hclass(j as usize).half() + p.sidewalk_w + SETBACK_M)
        }
    };
    for bj in -1..ny as isize {
        for bi in -1..nx as isize {
            let (x0, ox0) = line_x(bi);
            let (x1, ox1) = line_x(bi + 1);
            let (y0, oy0) = line_y(bj);
            let (y1, oy1) = line_y(bj + 1);
            let (lo, hi) = (DVec2::new(x0 + ox0, y0 + oy0), DVec2::new(x1 - ox1, y1 - oy1));
            let ext = hi - lo;
            if ext.x < 8.0 || ext.y < 8.0 {
                continue;
            }
            let lots_x = ((ext.x / 30.0).round() as usize).max(1);
            let lots_y = ((ext.y / 30.0).round() as usize).max(1);
            let lot = DVec2::new(ext.x / lots_x as f64, ext.y / lots_y as f64);
            for ly in 0..lots_y {
                for lx in 0..lots_x {
                    let interior = lx > 0 && ly > 0 && lx + 1 < lots_x && ly + 1 < lots_y;
                    let empty = rng.random_range(0.0..1.0) < 0.12;
                    let height = rng.random_range(p.height_m.0..p.height_m.1);
                    if interior || empty {
                        continue;
                    }
                    let centre = lo + DVec2::new((lx as f64 + 0.5) * lot.x, (ly as f64 + 0.5) * lot.y);
                    obstacles.push(Obstacle {
                        kind: ObstacleKind::Building,
                        centre,
                        half_extents_m: (lot * 0.5 - DVec2::splat(1.5)).max(DVec2::splat(1.0)),
                        heading_rad: 0.0,
                        base_z_m: 0.0,
                        height_m: height,
                    });
                }
            }
        }
    }
    (
        RawNetwork {
            roads: g.roads,
            junctions,
            controllers: Vec::new(),
        },
        obstacles,
    )
}
