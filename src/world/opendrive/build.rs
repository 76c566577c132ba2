//! Raw OpenDRIVE records → the road-network model: samples every lane section at stations along the
//! reference line (≤ 2 m apart, closer on curves so that the chord error stays ≤ 2 cm), turns each lane into
//! a run of [`LanePiece`] quads, resolves travel directions and speed limits, places crosswalks (from
//! `<object type="crosswalk">`, or synthesised at junction mouths when a file has none), takes buildings from
//! `<object type="building">` (or synthesises them beside the sidewalks when a file has none) and then derives
//! the query structures. Used by both sources: the built-in generator emits the same raw records.

use glam::DVec2;

use super::geometry::{Poly3At, eval_piecewise};
use super::parse::{RawNetwork, RawRoad, RawSection, ref_at};
use super::{MAX_LANE_OFFSET_M, MAX_PIECES, MAX_WIDTH_M};
use crate::world::{
    Crosswalk, Junction, Lane, LanePiece, LaneType, Obstacle, ObstacleKind, Road, RoadNetwork, TownSource,
    TravelDirection, WorldError, index, obstacles, routes, sidewalks,
};

/// Per station: reference point, left normal, elevation, carriageway width, per-lane (inner t, outer t, width).
type Station = (DVec2, DVec2, f64, f64, Vec<(f64, f64, f64)>);

/// Default speed limit when a file gives none: 50 km/h.
const DEFAULT_SPEED_MPS: f64 = 50.0 / 3.6;

/// 1-based line of byte offset `pos` in `xml` (1 when `xml` is empty, as for built-in towns).
pub(crate) fn line_of(xml: &str, pos: u32) -> u32 {
    let end = (pos as usize).min(xml.len());
    1 + xml.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count() as u32
}

fn left_normal(h: f64) -> DVec2 {
    let (sn, cs) = h.sin_cos();
    DVec2::new(-sn, cs)
}

/// Borders of the lanes of a section at `s`: for each lane (in section order) `(inner_t, outer_t)`.
struct Borders {
    /// Per lane of the section: (inner t, outer t, width).
    lanes: Vec<(f64, f64, f64)>,
    carriageway_m: f64,
}

/// Order of lanes inside a section: left lanes by increasing id, then right lanes by decreasing id.
fn section_order(sec: &RawSection) -> Vec<usize> {
    let mut left: Vec<usize> = (0..sec.lanes.len()).filter(|&i| sec.lanes[i].id > 0).collect();
    let mut right: Vec<usize> = (0..sec.lanes.len()).filter(|&i| sec.lanes[i].id < 0).collect();
    left.sort_by_key(|&i| sec.lanes[i].id);
    right.sort_by_key(|&i| -sec.lanes[i].id);
    left.extend(right);
    left
}

fn width_at(widths: &[Poly3At], ds: f64) -> f64 {
    if widths.is_empty() {
        return 0.0;
    }
    eval_piecewise(widths, ds).max(0.0)
}

fn borders_at(
    xml: &str,
    road: &RawRoad,
    sec: &RawSection,
    order: &[usize],
    s: f64,
    path: &str,
    out: &mut Borders,
) -> Result<(), WorldError> {
    let lo = eval_piecewise(&road.lane_offsets, s);
    if lo.abs() > MAX_LANE_OFFSET_M || !lo.is_finite() {
        return Err(WorldError::XodrInvalid {
            path: path.into(),
            line: line_of(xml, road.pos),
            message: format!(
                "the lane offset of road {:?} is {lo:.1} m at s={s:.2} (cap {MAX_LANE_OFFSET_M} m)",
                road.id
            ),
        });
    }
    out.lanes.clear();
    out.lanes.resize(sec.lanes.len(), (0.0, 0.0, 0.0));
    let (mut tl, mut tr) = (lo, lo);
    let (mut cw_l, mut cw_r) = (0.0, 0.0);
    let (mut open_l, mut open_r) = (true, true);
    for &i in order {
        let lane = &sec.lanes[i];
        let w = width_at(&lane.widths, s - sec.s);
        if w > MAX_WIDTH_M || !w.is_finite() {
            return Err(WorldError::XodrInvalid {
                path: path.into(),
                line: line_of(xml, lane.pos),
                message: format!(
                    "lane {} of road {:?} is {w:.1} m wide at s={s:.2} (cap {MAX_WIDTH_M} m)",
                    lane.id, road.id
                ),
            });
        }
        if lane.id > 0 {
            out.lanes[i] = (tl, tl + w, w);
            tl += w;
            if lane.lane_type == LaneType::Sidewalk && w > 0.01 {
                open_l = false;
            }
            if open_l {
                cw_l += w;
            }
        } else {
            out.lanes[i] = (tr, tr - w, w);
            tr -= w;
            if lane.lane_type == LaneType::Sidewalk && w > 0.01 {
                open_r = false;
            }
            if open_r {
                cw_r += w;
            }
        }
    }
    out.carriageway_m = cw_l + cw_r;
    Ok(())
}

/// Stations in `[a, b]`: geometry boundaries plus steps sized by curvature.
fn stations(road: &RawRoad, a: f64, b: f64, out: &mut Vec<f64>) {
    out.clear();
    let mut cuts: Vec<f64> = vec![a, b];
    for g in &road.geometries {
        for c in [g.s, g.s + g.length] {
            if c > a + 1e-3 && c < b - 1e-3 {
                cuts.push(c);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|x, y| (*x - *y).abs() < 1e-3);
    for w in cuts.windows(2) {
        let (s0, s1) = (w[0], w[1]);
        let mid = 0.5 * (s0 + s1);
        let gi = road.geometries.partition_point(|g| g.s <= mid).saturating_sub(1);
        let k = road.geometries[gi].max_curvature();
        let step = if k > 1e-9 {
            (0.16 / k).sqrt().clamp(0.25, 2.0)
        } else {
            2.0
        };
        let n = ((s1 - s0) / step).ceil().max(1.0) as usize;
        for i in 0..n {
            out.push(s0 + (s1 - s0) * i as f64 / n as f64);
        }
    }
    out.push(b);
}

/// Builds the model from raw records. Buildings come from the file's `<object type="building">` records, or
/// are synthesised beside the sidewalks when it has none.
pub(crate) fn build(
    raw: RawNetwork,
    name: String,
    source: TownSource,
    path: &str,
    xml: &str,
) -> Result<RoadNetwork, WorldError> {
    build_with(raw, name, source, path, xml, None, false)
}

pub(crate) fn build_with(
    raw: RawNetwork,
    name: String,
    source: TownSource,
    path: &str,
    xml: &str,
    given_obstacles: Option<Vec<Obstacle>>,
    synthesize_signals: bool,
) -> Result<RoadNetwork, WorldError> {
    let mut roads = Vec::with_capacity(raw.roads.len());
    let mut lanes: Vec<Lane> = Vec::new();
    let mut pieces: Vec<LanePiece> = Vec::new();
    let mut st = Vec::new();
    let mut borders = Borders {
        lanes: Vec::new(),
        carriageway_m: 0.0,
    };
    let mut file_crosswalks = Vec::new();
    let mut file_buildings = Vec::new();
    for (ri, road) in raw.roads.iter().enumerate() {
        let lane_start = lanes.len() as u32;
        for (si, sec) in road.sections.iter().enumerate() {
            let a = sec.s.min(road.length);
            let b = road.sections.get(si + 1).map_or(road.length, |n| n.s.min(road.length));
            if b - a < 1e-3 {
                continue;
            }
            stations(road, a, b, &mut st);
            if pieces.len() + st.len() * sec.lanes.len() > MAX_PIECES {
                return Err(WorldError::XodrTooLarge {
                    path: path.into(),
                    line: line_of(xml, sec.pos),
                    message: format!("more than {MAX_PIECES} lane pieces"),
                });
            }
            let order = section_order(sec);
            // Per station: reference point, normal, z, per-lane borders.
            let mut per_station: Vec<Station> = Vec::with_capacity(st.len());
            for &s in &st {
                let (p, h) = ref_at(road, s);
                borders_at(xml, road, sec, &order, s, path, &mut borders)?;
                let z = eval_piecewise(&road.elevations, s);
                per_station.push((p, left_normal(h), z, borders.carriageway_m, borders.lanes.clone()));
            }
            let speed_road = road
                .speeds
                .iter()
                .rev()
                .find(|(s, _)| *s <= a + 1e-6)
                .or(road.speeds.first())
                .map_or(DEFAULT_SPEED_MPS, |x| x.1);
            for &li in &order {
                let rl = &sec.lanes[li];
                let travel = match (rl.lane_type, rl.travel) {
                    (
                        LaneType::Driving,
                        Some(t @ (TravelDirection::Forward | TravelDirection::Backward | TravelDirection::Both)),
                    ) => t,
                    (LaneType::Driving, _) => {
                        if (rl.id < 0) != road.lht {
                            TravelDirection::Forward
                        } else {
                            TravelDirection::Backward
                        }
                    }
                    _ => TravelDirection::Undirected,
                };
                let first_piece = pieces.len() as u32;
                let mut length = 0.0;
                // Sidewalks are raised by a curb (CARLA's are; OpenDRIVE's lane <height> is not read).
                let curb = if rl.lane_type == LaneType::Sidewalk {
                    crate::world::CURB_HEIGHT_M
                } else {
                    0.0
                };
                for k in 0..per_station.len() - 1 {
                    let (p0, n0, z0, cw0, ref b0) = per_station[k];
                    let (p1, n1, z1, cw1, ref b1) = per_station[k + 1];
                    let (i0, o0, w0) = b0[li];
                    let (i1, o1, w1) = b1[li];
                    let corners = [p0 + n0 * i0, p1 + n1 * i1, p1 + n1 * o1, p0 + n0 * o0];
                    let c0 = (corners[0] + corners[3]) * 0.5;
                    let c1 = (corners[1] + corners[2]) * 0.5;
                    length += (c1 - c0).length();
                    pieces.push(LanePiece {
                        corners,
                        lane: lanes.len() as u32,
                        s_m: [st[k], st[k + 1]],
                        width_m: [w0 as f32, w1 as f32],
                        road_width_m: [cw0 as f32, cw1 as f32],
                        z_m: (0.5 * (z0 + z1) + curb) as f32,
                    });
                }
                lanes.push(Lane {
                    road: ri as u32,
                    section: si as u32,
                    lane_id: rl.id,
                    lane_type: rl.lane_type,
                    travel,
                    speed_limit_mps: rl.speed_mps.unwrap_or(speed_road),
                    pieces: first_piece..pieces.len() as u32,
                    length_m: length,
                    in_junction: road.junction.is_some(),
                });
            }
        }
        for o in &road.objects {
            if o.kind.eq_ignore_ascii_case("crosswalk") {
                file_crosswalks.push(object_polygon(road, ri as u32, o));
            } else if o.kind.eq_ignore_ascii_case("building")
                && let Some(b) = building(road, o)
            {
                file_buildings.push(b);
            }
        }
        roads.push(Road {
            id: road.id.clone(),
            name: road.name.clone(),
            junction: road.junction.clone(),
            length_m: road.length,
            lanes: lane_start..lanes.len() as u32,
            predecessor: road.predecessor.clone(),
            successor: road.successor.clone(),
        });
    }
    let live = pieces.iter().filter(|p| p.width_m[0].max(p.width_m[1]) > 0.01);
    let Some((lo, hi)) =
        crate::world::bounding_box(live.flat_map(|p| p.corners)).filter(|(lo, hi)| lo.is_finite() && hi.is_finite())
    else {
        return Err(WorldError::XodrInvalid {
            path: path.into(),
            line: raw.roads.first().map_or(1, |r| line_of(xml, r.pos)),
            message: "no lane of any road has a positive width".into(),
        });
    };
    let mut junctions: Vec<Junction> = raw
        .junctions
        .iter()
        .map(|j| Junction {
            id: j.id.clone(),
            name: j.name.clone(),
            centre: DVec2::ZERO,
            connections: j.connections.clone(),
        })
        .collect();
    for j in &mut junctions {
        let mids: Vec<DVec2> = raw
            .roads
            .iter()
            .filter(|r| r.junction.as_deref() == Some(j.id.as_str()))
            .map(|r| ref_at(r, 0.5 * r.length).0)
            .collect();
        if !mids.is_empty() {
            j.centre = mids.iter().copied().sum::<DVec2>() / mids.len() as f64;
        }
    }
    let crosswalks = if file_crosswalks.is_empty() {
        synthesize_crosswalks(&raw, path, xml)?
    } else {
        file_crosswalks
    };

    let mut net = RoadNetwork {
        name,
        source,
        roads,
        lanes,
        pieces,
        junctions,
        crosswalks,
        obstacles: Vec::new(),
        signals: Vec::new(),
        bounds: (lo, hi),
        index: index::LaneIndex::default(),
        lane_graph: routes::LaneGraph::default(),
        sidewalk_graph: sidewalks::SidewalkGraph::default(),
        obstacle_index: obstacles::ObstacleIndex::default(),
    };
    net.index = index::LaneIndex::build(&net);
    net.obstacles = match given_obstacles {
        Some(o) => o,
        None if !file_buildings.is_empty() => file_buildings,
        None => obstacles::synthesize_buildings(&net),
    };
    net.obstacle_index = obstacles::ObstacleIndex::build(&net.obstacles);
    net.lane_graph = routes::LaneGraph::build(&net);
    net.sidewalk_graph = sidewalks::SidewalkGraph::build(&net);
    net.signals = crate::world::signals::derive(&raw, &net, synthesize_signals);
    Ok(net)
}

/// A `<object type="building">` as a box: its outline in the object's frame (the bounding box of the corners)
/// or its length and width around its origin; `None` without a footprint or a height.
fn building(road: &RawRoad, o: &super::parse::RawObject) -> Option<Obstacle> {
    let (p, h) = ref_at(road, o.s.clamp(0.0, road.length));
    let origin = p + left_normal(h) * o.t;
    let heading_rad = h + o.hdg;
    let (centre_local, half) = if o.outline.len() >= 3 && !o.outline_in_road_coords {
        let (lo, hi) = crate::world::bounding_box(o.outline.iter().map(|&(u, v)| DVec2::new(u, v)))?;
        ((lo + hi) * 0.5, (hi - lo) * 0.5)
    } else {
        (DVec2::ZERO, DVec2::new(0.5 * o.length, 0.5 * o.width))
    };
    if half.x <= 0.0 || half.y <= 0.0 || o.height <= 0.0 {
        return None;
    }
    Some(Obstacle {
        kind: ObstacleKind::Building,
        centre: origin + DVec2::from_angle(heading_rad).rotate(centre_local),
        half_extents_m: half,
        heading_rad,
        base_z_m: eval_piecewise(&road.elevations, o.s) + o.z_offset,
        height_m: o.height,
    })
}

fn object_polygon(road: &RawRoad, ri: u32, o: &super::parse::RawObject) -> Crosswalk {
    let (p, h) = ref_at(road, o.s);
    let origin = p + left_normal(h) * o.t;
    let heading = h + o.hdg;
    let (sn, cs) = heading.sin_cos();
    let local = |u: f64, v: f64| origin + DVec2::new(cs * u - sn * v, sn * u + cs * v);
    let polygon = if o.outline.len() >= 3 {
        if o.outline_in_road_coords {
            o.outline
                .iter()
                .map(|&(s, t)| {
                    let (q, hq) = ref_at(road, s.clamp(0.0, road.length));
                    q + left_normal(hq) * t
                })
                .collect()
        } else {
            o.outline.iter().map(|&(u, v)| local(u, v)).collect()
        }
    } else {
        let (l, w) = (o.length.max(0.5) * 0.5, o.width.max(0.5) * 0.5);
        vec![local(-l, -w), local(l, -w), local(l, w), local(-l, w)]
    };
    Crosswalk {
        polygon,
        road: ri,
        synthesized: false,
    }
}

/// Crosswalks across every non-junction road end that meets a junction and has sidewalks on both sides:
/// 3 m deep, starting 0.5 m from the road end, spanning between the inner sidewalk borders.
fn synthesize_crosswalks(raw: &RawNetwork, path: &str, xml: &str) -> Result<Vec<Crosswalk>, WorldError> {
    Ok(crosswalk_corners(raw, path, xml)?
        .into_iter()
        .map(|(ri, corners)| {
            let road = &raw.roads[ri as usize];
            Crosswalk {
                polygon: corners
                    .iter()
                    .map(|&(s, t)| {
                        let (p, h) = ref_at(road, s);
                        p + left_normal(h) * t
                    })
                    .collect(),
                road: ri,
                synthesized: true,
            }
        })
        .collect())
}

/// A crosswalk on road `.0` with corners `(s, t)` in road coordinates.
pub(crate) type CrosswalkCorners = (u32, [(f64, f64); 4]);

/// The crosswalks [`synthesize_crosswalks`] places, as (road index, corners in road coordinates `(s, t)`).
pub(crate) fn crosswalk_corners(raw: &RawNetwork, path: &str, xml: &str) -> Result<Vec<CrosswalkCorners>, WorldError> {
    let mut out = Vec::new();
    let mut b = Borders {
        lanes: Vec::new(),
        carriageway_m: 0.0,
    };
    for (ri, road) in raw.roads.iter().enumerate() {
        if road.junction.is_some() || road.length < 10.0 || road.sections.is_empty() {
            continue;
        }
        let at_junction = |l: &Option<crate::world::RoadLink>| l.as_ref().is_some_and(|l| l.element_type == "junction");
        for (is_start, linked) in [
            (true, at_junction(&road.predecessor)),
            (false, at_junction(&road.successor)),
        ] {
            if !linked {
                continue;
            }
            let (s0, s1) = if is_start {
                (0.5, 3.5)
            } else {
                (road.length - 3.5, road.length - 0.5)
            };
            let mut ts = [(0.0, 0.0); 2];
            let mut ok = true;
            for (k, s) in [s0, s1].into_iter().enumerate() {
                let si = road.sections.partition_point(|x| x.s <= s).saturating_sub(1);
                let sec = &road.sections[si];
                let order = section_order(sec);
                borders_at(xml, road, sec, &order, s, path, &mut b)?;
                let inner = |left: bool| {
                    order
                        .iter()
                        .filter(|&&i| (sec.lanes[i].id > 0) == left)
                        .find(|&&i| sec.lanes[i].lane_type == LaneType::Sidewalk && b.lanes[i].2 > 0.5)
                        .map(|&i| b.lanes[i].0)
                };
                match (inner(false), inner(true)) {
                    (Some(r), Some(l)) => ts[k] = (r, l),
                    _ => ok = false,
                }
            }
            if !ok {
                continue;
            }
            out.push((ri as u32, [(s0, ts[0].0), (s1, ts[1].0), (s1, ts[1].1), (s0, ts[0].1)]));
        }
    }
    Ok(out)
}
