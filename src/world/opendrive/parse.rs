//! OpenDRIVE XML → raw records with 1-based line numbers, via roxmltree.
//!
//! Lenient where real files deviate from the schema (CARLA's RoadRunner exports omit attributes and write
//! `type="-1"` objects): unknown elements are ignored, missing optional attributes take their schema
//! defaults. Strict where it matters: malformed XML, missing plan-view geometry, non-numeric, NaN/inf or
//! absurd numbers are errors naming the file and the element's line. Never panics.

use glam::DVec2;
use roxmltree::{Document, Node, ParsingOptions};

use super::geometry::{GeomKind, Geometry, Poly3At};
use super::{MAX_ABS_COORD_M, MAX_LENGTH_M, MAX_NODES, MAX_WIDTH_M};
use crate::world::{JunctionConnection, LaneType, RoadLink, TravelDirection, WorldError};

/// A whole document.
#[derive(Clone, Debug, Default)]
pub(crate) struct RawNetwork {
    pub roads: Vec<RawRoad>,
    pub junctions: Vec<RawJunction>,
    /// Top-level `<controller>` records: (controller id, the signal ids it controls).
    pub controllers: Vec<(String, Vec<String>)>,
}

#[derive(Clone, Debug)]
pub(crate) struct RawRoad {
    pub id: String,
    pub name: String,
    pub length: f64,
    pub junction: Option<String>,
    /// Left-hand traffic (`rule="LHT"`).
    pub lht: bool,
    /// Byte offset of the element in the source (converted to a line only for errors).
    pub pos: u32,
    pub predecessor: Option<RoadLink>,
    pub successor: Option<RoadLink>,
    /// (s, speed limit m/s) from `<type><speed>`.
    pub speeds: Vec<(f64, f64)>,
    pub geometries: Vec<Geometry>,
    pub elevations: Vec<Poly3At>,
    pub lane_offsets: Vec<Poly3At>,
    pub sections: Vec<RawSection>,
    pub objects: Vec<RawObject>,
    /// Dynamic vehicle signals (`<signal dynamic="yes">`, traffic lights) on this road.
    pub signals: Vec<RawSignal>,
    /// Ids of the signals this road's `<signalReference>`s name (a junction's connecting roads name the
    /// signal that controls them).
    pub signal_refs: Vec<String>,
}

/// A `<signal dynamic="yes">` (a traffic light) in road coordinates.
#[derive(Clone, Debug)]
pub(crate) struct RawSignal {
    pub id: String,
    pub s: f64,
    pub t: f64,
}

#[derive(Clone, Debug)]
pub(crate) struct RawSection {
    pub s: f64,
    /// Byte offset of the element in the source (converted to a line only for errors).
    pub pos: u32,
    pub lanes: Vec<RawLane>,
}

#[derive(Clone, Debug)]
pub(crate) struct RawLane {
    pub id: i32,
    pub lane_type: LaneType,
    /// Width records; `s` is the `sOffset` from the section start.
    pub widths: Vec<Poly3At>,
    pub speed_mps: Option<f64>,
    pub travel: Option<TravelDirection>,
    /// Ids of the predecessor and successor lanes (`<link>`), where given.
    pub links: (Option<i32>, Option<i32>),
    /// Byte offset of the element in the source (converted to a line only for errors).
    pub pos: u32,
}

#[derive(Clone, Debug)]
pub(crate) struct RawJunction {
    pub id: String,
    pub name: String,
    pub connections: Vec<JunctionConnection>,
    /// `<controller id sequence>` children: (controller id, sequence), the junction's signal phases in order.
    pub controllers: Vec<(String, u32)>,
}

/// An `<object>`; crosswalks and buildings are used.
#[derive(Clone, Debug)]
pub(crate) struct RawObject {
    pub kind: String,
    pub s: f64,
    pub t: f64,
    pub z_offset: f64,
    pub hdg: f64,
    pub length: f64,
    pub width: f64,
    pub height: f64,
    /// Outline corners: (s, t) road coordinates when `road` is true, else (u, v) relative to the object.
    pub outline: Vec<(f64, f64)>,
    pub outline_in_road_coords: bool,
}

struct Ctx<'a, 'i> {
    doc: &'a Document<'i>,
    path: &'a str,
}

impl<'a, 'i> Ctx<'a, 'i> {
    fn line(&self, n: Node) -> u32 {
        self.doc.text_pos_at(n.range().start).row
    }

    fn pos(&self, n: Node) -> u32 {
        n.range().start.min(u32::MAX as usize) as u32
    }

    fn invalid(&self, n: Node, message: impl Into<String>) -> WorldError {
        WorldError::XodrInvalid {
            path: self.path.to_string(),
            line: self.line(n),
            message: message.into(),
        }
    }

    /// An optional numeric attribute: absent → None; present but not a finite number → error.
    fn num(&self, n: Node, attr: &str) -> Result<Option<f64>, WorldError> {
        let Some(v) = n.attribute(attr) else {
            return Ok(None);
        };
        let v = v.trim();
        if v.is_empty() {
            return Ok(None);
        }
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(Some(x)),
            Ok(_) => Err(self.invalid(
                n,
                format!("<{}> attribute {attr}=\"{v}\" is not finite", n.tag_name().name()),
            )),
            Err(_) => Err(self.invalid(
                n,
                format!("<{}> attribute {attr}=\"{v}\" is not a number", n.tag_name().name()),
            )),
        }
    }

    fn num_or(&self, n: Node, attr: &str, default: f64) -> Result<f64, WorldError> {
        Ok(self.num(n, attr)?.unwrap_or(default))
    }

    fn req(&self, n: Node, attr: &str) -> Result<f64, WorldError> {
        self.num(n, attr)?.ok_or_else(|| {
            self.invalid(
                n,
                format!("<{}> is missing the required attribute {attr}", n.tag_name().name()),
            )
        })
    }

    fn bounded(&self, n: Node, attr: &str, v: f64, lo: f64, hi: f64) -> Result<f64, WorldError> {
        if v < lo || v > hi {
            return Err(self.invalid(
                n,
                format!("<{}> {attr}={v} is outside [{lo}, {hi}]", n.tag_name().name()),
            ));
        }
        Ok(v)
    }

    fn poly(&self, n: Node, s_attr: &str) -> Result<Poly3At, WorldError> {
        let s = self.num_or(n, s_attr, 0.0)?;
        self.bounded(n, s_attr, s, -1e-6, MAX_LENGTH_M)?;
        let mut c = [0.0; 4];
        for (i, a) in ["a", "b", "c", "d"].iter().enumerate() {
            c[i] = self.num_or(n, a, 0.0)?;
            self.bounded(n, a, c[i], -1e9, 1e9)?;
        }
        Ok(Poly3At {
            s: s.max(0.0),
            c,
            pos: self.pos(n),
        })
    }
}

fn children<'a, 'i>(n: Node<'a, 'i>, tag: &'a str) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    n.children()
        .filter(move |c| c.is_element() && c.tag_name().name().eq_ignore_ascii_case(tag))
}

fn child<'a, 'i>(n: Node<'a, 'i>, tag: &'a str) -> Option<Node<'a, 'i>> {
    children(n, tag).next()
}

/// Speed in m/s from a value and an OpenDRIVE unit (`m/s` default, `km/h`, `mph`).
fn speed_mps(v: f64, unit: Option<&str>) -> f64 {
    match unit.map(|u| u.trim().to_ascii_lowercase()) {
        Some(u) if u == "mph" => v * 0.44704,
        Some(u) if u == "km/h" || u == "kmh" => v / 3.6,
        _ => v,
    }
}

/// Parses a document into raw records.
pub(crate) fn parse(xml: &str, path: &str) -> Result<RawNetwork, WorldError> {
    if xml.trim().is_empty() {
        return Err(WorldError::XodrSyntax {
            path: path.into(),
            line: 1,
            message: "the document is empty".into(),
        });
    }
    let opts = ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_NODES,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(xml, opts).map_err(|e| WorldError::XodrSyntax {
        path: path.into(),
        // roxmltree reports the end of a truncated document at 1:1; the end is the last line.
        line: match e {
            roxmltree::Error::UnexpectedEndOfStream => 1 + xml.bytes().filter(|&b| b == b'\n').count() as u32,
            // DTDs are refused (entity expansion attacks); roxmltree gives no position for that.
            roxmltree::Error::DtdDetected => {
                let at = xml.find("<!DOCTYPE").unwrap_or(0);
                1 + xml[..at].bytes().filter(|&b| b == b'\n').count() as u32
            }
            _ => e.pos().row,
        },
        message: e.to_string(),
    })?;
    let cx = Ctx { doc: &doc, path };
    let root = doc.root_element();
    if !root.tag_name().name().eq_ignore_ascii_case("OpenDRIVE") {
        return Err(cx.invalid(
            root,
            format!("root element is <{}>, expected <OpenDRIVE>", root.tag_name().name()),
        ));
    }
    let mut net = RawNetwork::default();
    for n in root.children().filter(|c| c.is_element()) {
        match n.tag_name().name() {
            "road" => net.roads.push(parse_road(&cx, n)?),
            "junction" => net.junctions.push(parse_junction(&cx, n)?),
            "controller" => net.controllers.push((
                n.attribute("id").unwrap_or("").to_string(),
                children(n, "control")
                    .filter_map(|c| c.attribute("signalId").map(str::to_string))
                    .collect(),
            )),
            _ => {}
        }
    }
    if net.roads.is_empty() {
        return Err(cx.invalid(root, "the document has no <road>"));
    }
    Ok(net)
}

fn parse_link(n: Node) -> Option<RoadLink> {
    let element_id = n.attribute("elementId")?.to_string();
    Some(RoadLink {
        element_type: n.attribute("elementType").unwrap_or("road").to_string(),
        element_id,
        contact_point: n.attribute("contactPoint").map(str::to_string),
    })
}

fn parse_road(cx: &Ctx, n: Node) -> Result<RawRoad, WorldError> {
    let pos = cx.pos(n);
    let id = n.attribute("id").unwrap_or("").to_string();
    let junction = n
        .attribute("junction")
        .map(str::trim)
        .filter(|j| !j.is_empty() && *j != "-1")
        .map(str::to_string);
    let mut road = RawRoad {
        id,
        name: n.attribute("name").unwrap_or("").to_string(),
        length: 0.0,
        junction,
        lht: n.attribute("rule").is_some_and(|r| r.eq_ignore_ascii_case("LHT")),
        pos,
        predecessor: None,
        successor: None,
        speeds: Vec::new(),
        geometries: Vec::new(),
        elevations: Vec::new(),
        lane_offsets: Vec::new(),
        sections: Vec::new(),
        objects: Vec::new(),
        signals: Vec::new(),
        signal_refs: Vec::new(),
    };
    if let Some(link) = child(n, "link") {
        road.predecessor = child(link, "predecessor").and_then(parse_link);
        road.successor = child(link, "successor").and_then(parse_link);
    }
    for t in children(n, "type") {
        let s = cx.num_or(t, "s", 0.0)?;
        if let Some(sp) = child(t, "speed")
            && let Some(v) = cx.num(sp, "max")?
        {
            let v = speed_mps(cx.bounded(sp, "max", v, 0.0, 1000.0)?, sp.attribute("unit"));
            road.speeds.push((s, v));
        }
    }
    let Some(pv) = child(n, "planView") else {
        return Err(cx.invalid(n, format!("road {:?} has no <planView>", road.id)));
    };
    let mut running_s = 0.0;
    for g in children(pv, "geometry") {
        let geom = parse_geometry(cx, g, running_s)?;
        running_s = geom.s + geom.length;
        road.geometries.push(geom);
    }
    if road.geometries.is_empty() {
        return Err(cx.invalid(pv, format!("road {:?} has no <geometry> in its <planView>", road.id)));
    }
    road.geometries.sort_by(|a, b| a.s.total_cmp(&b.s));
    let geom_end = road.geometries.iter().map(|g| g.s + g.length).fold(0.0, f64::max);
    road.length = match cx.num(n, "length")? {
        Some(l) => cx.bounded(n, "length", l, 0.0, MAX_LENGTH_M)?,
        None => geom_end,
    };
    if road.length <= 0.0 {
        road.length = geom_end;
    }
    if road.length <= 0.0 {
        return Err(cx.invalid(n, format!("road {:?} has zero length", road.id)));
    }
    if let Some(ep) = child(n, "elevationProfile") {
        for e in children(ep, "elevation") {
            road.elevations.push(cx.poly(e, "s")?);
        }
        road.elevations.sort_by(|a, b| a.s.total_cmp(&b.s));
    }
    if let Some(lanes) = child(n, "lanes") {
        for lo in children(lanes, "laneOffset") {
            road.lane_offsets.push(cx.poly(lo, "s")?);
        }
        road.lane_offsets.sort_by(|a, b| a.s.total_cmp(&b.s));
        for sec in children(lanes, "laneSection") {
            road.sections.push(parse_section(cx, sec, road.lht)?);
        }
        road.sections.sort_by(|a, b| a.s.total_cmp(&b.s));
    }
    if let Some(objs) = child(n, "objects") {
        for o in children(objs, "object") {
            road.objects.push(parse_object(cx, o)?);
        }
    }
    if let Some(sigs) = child(n, "signals") {
        for g in children(sigs, "signal") {
            // Traffic lights only: dynamic signals (static ones are signs).
            if !g
                .attribute("dynamic")
                .is_some_and(|d| d.trim().eq_ignore_ascii_case("yes"))
            {
                continue;
            }
            let s = cx.num_or(g, "s", 0.0)?;
            cx.bounded(g, "s", s, -1e-6, MAX_LENGTH_M)?;
            let t = cx.num_or(g, "t", 0.0)?;
            cx.bounded(g, "t", t, -1e4, 1e4)?;
            road.signals.push(RawSignal {
                id: g.attribute("id").unwrap_or("").to_string(),
                s: s.max(0.0),
                t,
            });
        }
        road.signal_refs
            .extend(children(sigs, "signalReference").filter_map(|r| r.attribute("id").map(str::to_string)));
    }
    Ok(road)
}

fn parse_geometry(cx: &Ctx, g: Node, running_s: f64) -> Result<Geometry, WorldError> {
    let s = cx.num_or(g, "s", running_s)?;
    cx.bounded(g, "s", s, -1e-6, MAX_LENGTH_M)?;
    let x = cx.req(g, "x")?;
    let y = cx.req(g, "y")?;
    cx.bounded(g, "x", x, -MAX_ABS_COORD_M, MAX_ABS_COORD_M)?;
    cx.bounded(g, "y", y, -MAX_ABS_COORD_M, MAX_ABS_COORD_M)?;
    let hdg = cx.req(g, "hdg")?;
    cx.bounded(g, "hdg", hdg, -1e4, 1e4)?;
    let length = cx.req(g, "length")?;
    cx.bounded(g, "length", length, 0.0, MAX_LENGTH_M)?;
    let Some(shape) = g.children().find(|c| c.is_element()) else {
        return Err(cx.invalid(g, "<geometry> has no shape (line, arc, spiral, poly3 or paramPoly3)"));
    };
    let curv = |attr: &str| -> Result<f64, WorldError> {
        let k = cx.num_or(shape, attr, 0.0)?;
        cx.bounded(shape, attr, k, -100.0, 100.0)
    };
    let coef = |attr: &str| -> Result<f64, WorldError> {
        let k = cx.num_or(shape, attr, 0.0)?;
        cx.bounded(shape, attr, k, -1e9, 1e9)
    };
    let kind = match shape.tag_name().name() {
        "line" => GeomKind::Line,
        "arc" => GeomKind::Arc {
            curvature: curv("curvature")?,
        },
        "spiral" => GeomKind::Spiral {
            curv_start: curv("curvStart")?,
            curv_end: curv("curvEnd")?,
        },
        "poly3" => GeomKind::Poly3 {
            a: coef("a")?,
            b: coef("b")?,
            c: coef("c")?,
            d: coef("d")?,
        },
        "paramPoly3" => {
            let normalized = !shape
                .attribute("pRange")
                .is_some_and(|r| r.eq_ignore_ascii_case("arcLength"));
            GeomKind::ParamPoly3 {
                u: [coef("aU")?, coef("bU")?, coef("cU")?, coef("dU")?],
                v: [coef("aV")?, coef("bV")?, coef("cV")?, coef("dV")?],
                normalized,
            }
        }
        other => return Err(cx.invalid(shape, format!("unknown geometry shape <{other}>"))),
    };
    let geometry = Geometry {
        s: s.max(0.0),
        x,
        y,
        hdg,
        length,
        kind,
        pos: cx.pos(g),
    };
    // A record's `length` is its curve's arc length. A polynomial whose curve runs far longer (a coefficient of
    // 10^8 in a 20 m record) would put lanes kilometres long between the stations sampled along `length`, and
    // everything built along them (spawn points every few metres) would not fit in memory.
    let traced = geometry.traced_length(TRACE_STEPS);
    if traced.is_nan() || traced > MAX_TRACED_RATIO * length + 1.0 {
        return Err(cx.invalid(
            shape,
            format!(
                "<{}> traces a curve of {traced:.1} m, but the geometry's length is {length} m (coefficients in the wrong unit?)",
                shape.tag_name().name()
            ),
        ));
    }
    Ok(geometry)
}

/// Steps of the polyline that checks a geometry record's length ([`Geometry::traced_length`]).
const TRACE_STEPS: usize = 32;
/// How much longer than its declared length a record's traced curve may be (plus a metre).
const MAX_TRACED_RATIO: f64 = 1.5;

fn parse_section(cx: &Ctx, sec: Node, lht: bool) -> Result<RawSection, WorldError> {
    let s = cx.num_or(sec, "s", 0.0)?;
    cx.bounded(sec, "s", s, -1e-6, MAX_LENGTH_M)?;
    let mut lanes = Vec::new();
    for side in ["left", "right"] {
        let Some(side_node) = child(sec, side) else {
            continue;
        };
        for l in children(side_node, "lane") {
            let pos = cx.pos(l);
            let id_raw = l.attribute("id").unwrap_or("");
            let Ok(id) = id_raw.trim().parse::<i32>() else {
                return Err(cx.invalid(l, format!("<lane> id=\"{id_raw}\" is not an integer")));
            };
            if id == 0 || id.unsigned_abs() > 1000 {
                return Err(cx.invalid(l, format!("<lane> id={id} is not a valid {side} lane id")));
            }
            let lane_type = LaneType::from_xodr(l.attribute("type").unwrap_or("none"));
            let mut widths = Vec::new();
            for w in children(l, "width") {
                let p = cx.poly(w, "sOffset")?;
                if p.c[0] > MAX_WIDTH_M || p.c[0] < -MAX_WIDTH_M {
                    return Err(cx.invalid(w, format!("lane width a={} is absurd (cap {MAX_WIDTH_M} m)", p.c[0])));
                }
                widths.push(p);
            }
            widths.sort_by(|a, b| a.s.total_cmp(&b.s));
            let mut speed = None;
            if let Some(sp) = child(l, "speed")
                && let Some(v) = cx.num(sp, "max")?
            {
                speed = Some(speed_mps(cx.bounded(sp, "max", v, 0.0, 1000.0)?, sp.attribute("unit")));
            }
            // Travel direction: OpenDRIVE 1.7 `direction`, RoadRunner's `vectorLane travelDir`, else the rule.
            let mut travel = match l.attribute("direction") {
                Some("reversed") => Some(if (id < 0) != lht {
                    TravelDirection::Backward
                } else {
                    TravelDirection::Forward
                }),
                Some("both") => Some(TravelDirection::Both),
                _ => None,
            };
            if travel.is_none()
                && let Some(ud) = child(l, "userData")
                && let Some(vl) = child(ud, "vectorLane")
            {
                travel = match vl.attribute("travelDir") {
                    Some("forward") => Some(TravelDirection::Forward),
                    Some("backward") => Some(TravelDirection::Backward),
                    Some("bidirectional") => Some(TravelDirection::Both),
                    Some("undirected") => Some(TravelDirection::Undirected),
                    _ => None,
                };
            }
            if l.attribute("type")
                .is_some_and(|t| t.eq_ignore_ascii_case("bidirectional"))
            {
                travel = Some(TravelDirection::Both);
            }
            let link_id = |tag: &str| {
                child(l, "link")
                    .and_then(|k| child(k, tag))
                    .and_then(|e| e.attribute("id"))
                    .and_then(|v| v.trim().parse::<i32>().ok())
            };
            lanes.push(RawLane {
                id,
                lane_type,
                widths,
                speed_mps: speed,
                travel,
                links: (link_id("predecessor"), link_id("successor")),
                pos,
            });
        }
    }
    Ok(RawSection {
        s: s.max(0.0),
        pos: cx.pos(sec),
        lanes,
    })
}

fn parse_junction(cx: &Ctx, n: Node) -> Result<RawJunction, WorldError> {
    let mut connections = Vec::new();
    for c in children(n, "connection") {
        let mut lane_links = Vec::new();
        for ll in children(c, "laneLink") {
            let from = ll.attribute("from").and_then(|v| v.trim().parse::<i32>().ok());
            let to = ll.attribute("to").and_then(|v| v.trim().parse::<i32>().ok());
            match (from, to) {
                (Some(f), Some(t)) => lane_links.push((f, t)),
                _ => return Err(cx.invalid(ll, "<laneLink> needs integer from and to attributes")),
            }
        }
        connections.push(JunctionConnection {
            incoming_road: c.attribute("incomingRoad").unwrap_or("").to_string(),
            connecting_road: c.attribute("connectingRoad").unwrap_or("").to_string(),
            contact_point: c.attribute("contactPoint").unwrap_or("start").to_string(),
            lane_links,
        });
    }
    let controllers = children(n, "controller")
        .filter_map(|c| {
            let seq = c
                .attribute("sequence")
                .and_then(|v| v.trim().parse::<u32>().ok())
                .unwrap_or(0);
            Some((c.attribute("id")?.to_string(), seq))
        })
        .collect();
    Ok(RawJunction {
        id: n.attribute("id").unwrap_or("").to_string(),
        name: n.attribute("name").unwrap_or("").to_string(),
        connections,
        controllers,
    })
}

fn parse_object(cx: &Ctx, o: Node) -> Result<RawObject, WorldError> {
    let kind = o.attribute("type").unwrap_or("").to_string();
    let s = cx.num_or(o, "s", 0.0)?;
    cx.bounded(o, "s", s, -1e-6, MAX_LENGTH_M)?;
    let t = cx.num_or(o, "t", 0.0)?;
    cx.bounded(o, "t", t, -1e4, 1e4)?;
    let hdg = cx.num_or(o, "hdg", 0.0)?;
    let length = cx.num_or(o, "length", 0.0)?;
    let width = cx.num_or(o, "width", 0.0)?;
    let height = cx.num_or(o, "height", 0.0)?;
    let z_offset = cx.num_or(o, "zOffset", 0.0)?;
    cx.bounded(o, "length", length, 0.0, 1e4)?;
    cx.bounded(o, "width", width, 0.0, 1e4)?;
    cx.bounded(o, "height", height, 0.0, 1e4)?;
    cx.bounded(o, "zOffset", z_offset, -1e4, 1e4)?;
    let mut outline = Vec::new();
    let mut road_coords = false;
    let outline_node = child(o, "outline").or_else(|| child(o, "outlines").and_then(|os| child(os, "outline")));
    if let Some(ol) = outline_node {
        for c in ol.children().filter(|c| c.is_element()) {
            match c.tag_name().name() {
                "cornerRoad" => {
                    road_coords = true;
                    outline.push((cx.req(c, "s")?, cx.req(c, "t")?));
                }
                "cornerLocal" => outline.push((cx.req(c, "u")?, cx.req(c, "v")?)),
                _ => {}
            }
            if outline.len() > 1000 {
                return Err(cx.invalid(c, "object outline has more than 1000 corners"));
            }
        }
    }
    for &(a, b) in &outline {
        if a.abs() > MAX_LENGTH_M || b.abs() > MAX_LENGTH_M {
            return Err(cx.invalid(o, "object outline corner is out of range"));
        }
    }
    Ok(RawObject {
        kind,
        s,
        t,
        z_offset,
        hdg,
        length,
        width,
        height,
        outline,
        outline_in_road_coords: road_coords,
    })
}

/// Reference-line position and heading at `s`.
pub(crate) fn ref_at(road: &RawRoad, s: f64) -> (DVec2, f64) {
    let gi = road.geometries.partition_point(|g| g.s <= s + 1e-9).saturating_sub(1);
    let g = &road.geometries[gi];
    g.eval(s - g.s)
}
