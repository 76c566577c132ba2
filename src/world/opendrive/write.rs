//! OpenDRIVE 1.7 export of a built-in town (`pedsynth town export NAME --xodr FILE`): the generator's raw
//! records written as XML, so that CARLA, esmini, scenario tools and ASAM's checker read the same roads the
//! simulator drives on, and our importer reads them back to the same network.
//!
//! What is written: every road with its link (through roads to their junctions; connecting roads to their
//! incoming and outgoing roads with contact points), speed limit, plan view (line, arc, normalised
//! paramPoly3), lane offset and one lane section whose lanes carry widths, road marks (the markings the
//! camera paints: solid yellow between directions, dashed white between lanes of one direction, solid white
//! at the carriageway's edge), sidewalk heights (the curb) and, on connecting roads, lane links; crosswalks
//! as `<object type="crosswalk">` with their outline in road coordinates; buildings as
//! `<object type="building">` boxes on the nearest road; traffic lights as dynamic `<signal>`s (type 1000001,
//! as CARLA's maps) on their approach roads with one `<controller>` per junction phase, in sequence order;
//! junctions with their connections, lane links and controllers.
//! No date and no absolute path: the same town gives the same bytes. Floats are written in Rust's shortest
//! round-trip form, so a reading gives back the very numbers the generator produced.

use std::fmt::Write as _;

use glam::DVec2;

use super::build::{CrosswalkCorners, crosswalk_corners};
use super::geometry::{GeomKind, Poly3At};
use super::parse::ref_at;
use super::parse::{RawLane, RawNetwork, RawRoad};
use crate::util::xml::escape as xml_escape;
use crate::world::{LaneType, Obstacle, RoadLink, RoadNetwork, WorldError, builtin};

/// The OpenDRIVE revision written.
pub const XODR_REV: (u32, u32) = (1, 7);

/// The OpenDRIVE document of built-in town `name` (`None` for a name that is not a built-in town).
pub fn builtin_to_xodr(name: &str) -> Result<Option<String>, WorldError> {
    let Some((raw, buildings)) = builtin::raw(name) else {
        return Ok(None);
    };
    let Some(net) = RoadNetwork::builtin(name) else {
        return Ok(None);
    };
    let crosswalks = crosswalk_corners(&raw, name, "")?;
    Ok(Some(write(name, &raw, &buildings, &crosswalks, &net)))
}

fn write(
    name: &str,
    raw: &RawNetwork,
    buildings: &[Obstacle],
    crosswalks: &[CrosswalkCorners],
    net: &RoadNetwork,
) -> String {
    let mut objects: Vec<Vec<String>> = vec![Vec::new(); raw.roads.len()];
    let mut object_id = 0u32;
    for (road, corners) in crosswalks {
        let (s_mid, _) = corners
            .iter()
            .fold((0.0, 0.0), |(a, b), &(s, t)| (a + s * 0.25, b + t * 0.25));
        let mut o = format!(
            "<object id=\"{object_id}\" name=\"crosswalk\" type=\"crosswalk\" s=\"{s_mid}\" t=\"0\" zOffset=\"0\" hdg=\"0\" orientation=\"none\">\n<outlines>\n<outline id=\"0\" closed=\"true\">\n"
        );
        for (k, (s, t)) in corners.iter().enumerate() {
            let _ = writeln!(o, "<cornerRoad id=\"{k}\" s=\"{s}\" t=\"{t}\" dz=\"0\" height=\"0\"/>");
        }
        o.push_str("</outline>\n</outlines>\n</object>\n");
        objects[*road as usize].push(o);
        object_id += 1;
    }
    for b in buildings {
        // The box's footprint is written as an outline in the object's own frame (u along `hdg`), so that a
        // building beyond the end of every road keeps its place.
        let Some((road, s, t, road_heading)) = nearest_road(raw, b.centre) else {
            continue;
        };
        let (origin, _) = ref_at(&raw.roads[road], s);
        let origin = origin + DVec2::from_angle(road_heading).perp() * t;
        let hdg = b.heading_rad - road_heading;
        let centre = DVec2::from_angle(-b.heading_rad).rotate(b.centre - origin);
        let half = b.half_extents_m;
        let mut o = format!(
            "<object id=\"{object_id}\" name=\"building\" type=\"building\" s=\"{s}\" t=\"{t}\" zOffset=\"{}\" hdg=\"{hdg}\" height=\"{}\" orientation=\"none\">\n<outlines>\n<outline id=\"0\" closed=\"true\" outer=\"true\">\n",
            b.base_z_m, b.height_m
        );
        for (k, (du, dv)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .into_iter()
            .enumerate()
        {
            let _ = writeln!(
                o,
                "<cornerLocal id=\"{k}\" u=\"{}\" v=\"{}\" z=\"0\" height=\"{}\"/>",
                centre.x + du * half.x,
                centre.y + dv * half.y,
                b.height_m
            );
        }
        o.push_str("</outline>\n</outlines>\n</object>\n");
        objects[road].push(o);
        object_id += 1;
    }

    // Traffic lights on their approach roads, as CARLA writes them: a dynamic three-light signal, valid for the
    // traffic entering the junction (`+` at the road's end, `-` at its start); one controller per phase of each
    // junction, in sequence order.
    let mut signals: Vec<Vec<String>> = vec![Vec::new(); raw.roads.len()];
    for g in &net.signals {
        let road = &raw.roads[g.road as usize];
        let (s, t) = road_coords(road, g.position.truncate());
        let z_offset = g.position.z - super::geometry::eval_piecewise(&road.elevations, s);
        signals[g.road as usize].push(format!(
            "<signal s=\"{s}\" t=\"{t}\" id=\"{}\" name=\"Signal_3Light_Post01\" dynamic=\"yes\" orientation=\"{}\" zOffset=\"{z_offset}\" country=\"OpenDRIVE\" type=\"1000001\" subtype=\"-1\" value=\"-1\" height=\"0.9\" width=\"0.34\" hOffset=\"0\" pitch=\"0\" roll=\"0\"/>\n",
            xml_escape(&g.id),
            if g.at_road_end { "+" } else { "-" }
        ));
    }
    let controller_id = |j: &str, phase: u32| format!("c{j}_{phase}");

    let (lo, hi) = net.bounds;
    let mut x = String::with_capacity(4 << 20);
    let _ = write!(
        x,
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<OpenDRIVE>\n<header revMajor=\"{}\" revMinor=\"{}\" name=\"{}\" version=\"1\" north=\"{}\" south=\"{}\" east=\"{}\" west=\"{}\" vendor=\"pedsynth\"/>\n",
        XODR_REV.0,
        XODR_REV.1,
        xml_escape(name),
        hi.y,
        lo.y,
        hi.x,
        lo.x
    );
    for (ri, road) in raw.roads.iter().enumerate() {
        write_road(&mut x, road, &objects[ri], &signals[ri]);
    }
    for (ji, j) in net.junctions.iter().enumerate() {
        for phase in 0..crate::world::signals::junction_phases(&net.signals, ji as u32) {
            let _ = writeln!(
                x,
                "<controller id=\"{}\" name=\"{}\" sequence=\"{phase}\">",
                xml_escape(&controller_id(&j.id, phase)),
                xml_escape(&format!("junction {} phase {phase}", j.id))
            );
            for g in net
                .signals
                .iter()
                .filter(|g| g.junction == ji as u32 && g.phase == phase)
            {
                let _ = writeln!(x, "<control signalId=\"{}\" type=\"0\"/>", xml_escape(&g.id));
            }
            x.push_str("</controller>\n");
        }
    }
    for j in &raw.junctions {
        let _ = writeln!(
            x,
            "<junction id=\"{}\" name=\"{}\">",
            xml_escape(&j.id),
            xml_escape(&j.name)
        );
        for (ci, c) in j.connections.iter().enumerate() {
            let _ = writeln!(
                x,
                "<connection id=\"{ci}\" incomingRoad=\"{}\" connectingRoad=\"{}\" contactPoint=\"{}\">",
                xml_escape(&c.incoming_road),
                xml_escape(&c.connecting_road),
                xml_escape(&c.contact_point)
            );
            for (from, to) in &c.lane_links {
                let _ = writeln!(x, "<laneLink from=\"{from}\" to=\"{to}\"/>");
            }
            x.push_str("</connection>\n");
        }
        if let Some(ji) = net.junctions.iter().position(|k| k.id == j.id) {
            for phase in 0..crate::world::signals::junction_phases(&net.signals, ji as u32) {
                let _ = writeln!(
                    x,
                    "<controller id=\"{}\" type=\"0\" sequence=\"{phase}\"/>",
                    xml_escape(&controller_id(&j.id, phase))
                );
            }
        }
        x.push_str("</junction>\n");
    }
    x.push_str("</OpenDRIVE>\n");
    x
}

fn write_link(x: &mut String, tag: &str, link: &RoadLink) {
    let _ = write!(
        x,
        "<{tag} elementType=\"{}\" elementId=\"{}\"",
        xml_escape(&link.element_type),
        xml_escape(&link.element_id)
    );
    if let Some(cp) = &link.contact_point {
        let _ = write!(x, " contactPoint=\"{}\"", xml_escape(cp));
    }
    x.push_str("/>\n");
}

fn poly(x: &mut String, tag: &str, s_attr: &str, p: &Poly3At) {
    let _ = writeln!(
        x,
        "<{tag} {s_attr}=\"{}\" a=\"{}\" b=\"{}\" c=\"{}\" d=\"{}\"/>",
        p.s, p.c[0], p.c[1], p.c[2], p.c[3]
    );
}

/// Road coordinates `(s, t)` of plan-view point `p` on `road`'s reference line: the nearest station (sampled
/// every 0.5 m, then refined by bisection) and the signed offset to the left.
fn road_coords(road: &RawRoad, p: DVec2) -> (f64, f64) {
    let d2 = |s: f64| ref_at(road, s).0.distance_squared(p);
    let n = (road.length / 0.5).ceil().max(1.0) as usize;
    let best = (0..=n)
        .map(|k| (k as f64 * 0.5).min(road.length))
        .min_by(|a, b| d2(*a).total_cmp(&d2(*b)))
        .unwrap_or(0.0);
    let (mut a, mut b) = ((best - 0.5).max(0.0), (best + 0.5).min(road.length));
    for _ in 0..40 {
        let (m1, m2) = (a + (b - a) / 3.0, b - (b - a) / 3.0);
        if d2(m1) <= d2(m2) {
            b = m2;
        } else {
            a = m1;
        }
    }
    let s = 0.5 * (a + b);
    let (q, h) = ref_at(road, s);
    (s, (p - q).dot(DVec2::from_angle(h).perp()))
}

fn write_road(x: &mut String, road: &RawRoad, objects: &[String], signals: &[String]) {
    let _ = writeln!(
        x,
        "<road name=\"{}\" length=\"{}\" id=\"{}\" junction=\"{}\" rule=\"{}\">",
        xml_escape(&road.name),
        road.length,
        xml_escape(&road.id),
        xml_escape(road.junction.as_deref().unwrap_or("-1")),
        if road.lht { "LHT" } else { "RHT" }
    );
    if road.predecessor.is_some() || road.successor.is_some() {
        x.push_str("<link>\n");
        if let Some(l) = &road.predecessor {
            write_link(x, "predecessor", l);
        }
        if let Some(l) = &road.successor {
            write_link(x, "successor", l);
        }
        x.push_str("</link>\n");
    }
    for &(s, speed_mps) in &road.speeds {
        let _ = writeln!(
            x,
            "<type s=\"{s}\" type=\"town\">\n<speed max=\"{speed_mps}\" unit=\"m/s\"/>\n</type>"
        );
    }
    x.push_str("<planView>\n");
    for g in &road.geometries {
        let _ = writeln!(
            x,
            "<geometry s=\"{}\" x=\"{}\" y=\"{}\" hdg=\"{}\" length=\"{}\">",
            g.s, g.x, g.y, g.hdg, g.length
        );
        match &g.kind {
            GeomKind::Line => x.push_str("<line/>\n"),
            GeomKind::Arc { curvature } => {
                let _ = writeln!(x, "<arc curvature=\"{curvature}\"/>");
            }
            GeomKind::Spiral { curv_start, curv_end } => {
                let _ = writeln!(x, "<spiral curvStart=\"{curv_start}\" curvEnd=\"{curv_end}\"/>");
            }
            GeomKind::Poly3 { a, b, c, d } => {
                let _ = writeln!(x, "<poly3 a=\"{a}\" b=\"{b}\" c=\"{c}\" d=\"{d}\"/>");
            }
            GeomKind::ParamPoly3 { u, v, normalized } => {
                let _ = writeln!(
                    x,
                    "<paramPoly3 aU=\"{}\" bU=\"{}\" cU=\"{}\" dU=\"{}\" aV=\"{}\" bV=\"{}\" cV=\"{}\" dV=\"{}\" pRange=\"{}\"/>",
                    u[0],
                    u[1],
                    u[2],
                    u[3],
                    v[0],
                    v[1],
                    v[2],
                    v[3],
                    if *normalized { "normalized" } else { "arcLength" }
                );
            }
        }
        x.push_str("</geometry>\n");
    }
    x.push_str("</planView>\n");
    if !road.elevations.is_empty() {
        x.push_str("<elevationProfile>\n");
        for e in &road.elevations {
            poly(x, "elevation", "s", e);
        }
        x.push_str("</elevationProfile>\n");
    }
    x.push_str("<lanes>\n");
    for o in &road.lane_offsets {
        poly(x, "laneOffset", "s", o);
    }
    for sec in &road.sections {
        let _ = writeln!(x, "<laneSection s=\"{}\">", sec.s);
        let driving = |id: i32| sec.lanes.iter().any(|l| l.id == id && l.lane_type == LaneType::Driving);
        let mut left: Vec<&RawLane> = sec.lanes.iter().filter(|l| l.id > 0).collect();
        let mut right: Vec<&RawLane> = sec.lanes.iter().filter(|l| l.id < 0).collect();
        left.sort_by_key(|l| -l.id);
        right.sort_by_key(|l| -l.id);
        let in_junction = road.junction.is_some();
        // The marking on each lane's outer border, as the camera paints it (src/sensors/scene/paint.rs).
        let mark = |l: &RawLane| -> Option<(&str, &str)> {
            if in_junction || l.lane_type != LaneType::Driving {
                return None;
            }
            let next = l.id + l.id.signum();
            Some(if driving(next) {
                ("broken", "white")
            } else {
                ("solid", "white")
            })
        };
        for (tag, lanes) in [("left", &left), ("center", &Vec::new()), ("right", &right)] {
            if tag == "center" {
                x.push_str("<center>\n<lane id=\"0\" type=\"none\" level=\"false\">\n");
                if !in_junction && driving(1) && driving(-1) {
                    road_mark(x, "solid", "yellow");
                }
                x.push_str("</lane>\n</center>\n");
                continue;
            }
            if lanes.is_empty() {
                continue;
            }
            let _ = writeln!(x, "<{tag}>");
            for l in lanes.iter() {
                write_lane(x, l, mark(l));
            }
            let _ = writeln!(x, "</{tag}>");
        }
        x.push_str("</laneSection>\n");
    }
    x.push_str("</lanes>\n");
    if !objects.is_empty() {
        x.push_str("<objects>\n");
        for o in objects {
            x.push_str(o);
        }
        x.push_str("</objects>\n");
    }
    if !signals.is_empty() {
        x.push_str("<signals>\n");
        for g in signals {
            x.push_str(g);
        }
        x.push_str("</signals>\n");
    }
    x.push_str("</road>\n");
}

fn road_mark(x: &mut String, kind: &str, colour: &str) {
    let lane_change = if kind == "broken" { "both" } else { "none" };
    let _ = writeln!(
        x,
        "<roadMark sOffset=\"0\" type=\"{kind}\" weight=\"standard\" color=\"{colour}\" width=\"0.15\" laneChange=\"{lane_change}\"/>"
    );
}

fn write_lane(x: &mut String, l: &RawLane, mark: Option<(&str, &str)>) {
    let _ = writeln!(
        x,
        "<lane id=\"{}\" type=\"{}\" level=\"false\">",
        l.id,
        lane_type_xodr(l.lane_type)
    );
    if l.links.0.is_some() || l.links.1.is_some() {
        x.push_str("<link>\n");
        if let Some(id) = l.links.0 {
            let _ = writeln!(x, "<predecessor id=\"{id}\"/>");
        }
        if let Some(id) = l.links.1 {
            let _ = writeln!(x, "<successor id=\"{id}\"/>");
        }
        x.push_str("</link>\n");
    }
    for w in &l.widths {
        poly(x, "width", "sOffset", w);
    }
    if let Some((kind, colour)) = mark {
        road_mark(x, kind, colour);
    }
    if let Some(v) = l.speed_mps {
        let _ = writeln!(x, "<speed sOffset=\"0\" max=\"{v}\" unit=\"m/s\"/>");
    }
    if l.lane_type == LaneType::Sidewalk {
        let h = crate::world::CURB_HEIGHT_M;
        let _ = writeln!(x, "<height sOffset=\"0\" inner=\"{h}\" outer=\"{h}\"/>");
    }
    x.push_str("</lane>\n");
}

fn lane_type_xodr(t: LaneType) -> &'static str {
    match t {
        LaneType::Driving => "driving",
        LaneType::Sidewalk => "sidewalk",
        LaneType::Shoulder => "shoulder",
        LaneType::Parking => "parking",
        LaneType::Median => "median",
        LaneType::Border => "border",
        LaneType::Biking => "biking",
        LaneType::Other => "none",
    }
}

/// The non-junction road whose reference line passes nearest to `p`: (road index, s, t, heading at s), with
/// `s` clamped to the road and `t` the offset across it at `s`.
fn nearest_road(raw: &RawNetwork, p: DVec2) -> Option<(usize, f64, f64, f64)> {
    let mut best: Option<(f64, usize, f64)> = None;
    for (ri, road) in raw.roads.iter().enumerate() {
        if road.junction.is_some() || road.geometries.is_empty() {
            continue;
        }
        let steps = road.length.ceil().max(1.0) as usize;
        for k in 0..=steps {
            let s = road.length * k as f64 / steps as f64;
            let d = ref_at(road, s).0.distance_squared(p);
            if best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, ri, s));
            }
        }
    }
    let (_, ri, mut s) = best?;
    let road = &raw.roads[ri];
    // Refine: move s by the offset's component along the tangent until it no longer changes.
    for _ in 0..20 {
        let (q, h) = ref_at(road, s);
        let next = (s + (p - q).dot(DVec2::from_angle(h))).clamp(0.0, road.length);
        if (next - s).abs() < 1e-12 {
            break;
        }
        s = next;
    }
    let (q, h) = ref_at(road, s);
    Some((ri, s, (p - q).dot(DVec2::from_angle(h).perp()), h))
}
