//! Road networks: the town model, its two sources (built-in procedural towns and OpenDRIVE import) and the
//! spatial queries the planner and the simulation use.
//!
//! # Coordinate convention
//!
//! All world coordinates are **right-handed, metres, z up**: x points east, y points north, and a heading
//! (`heading_rad`, `hdg`) is measured in radians counter-clockwise from +x. This is OpenDRIVE's own
//! inertial frame, so imported maps need no conversion. CARLA's world frame (Unreal) is left-handed; a point
//! `(x, y, z)` here is CARLA's `(x, -y, z)` and a heading `h` here is CARLA's yaw `-h` (in degrees:
//! `carla_yaw_deg = -h.to_degrees()`). [`to_carla`] and [`from_carla`] do the mapping.
//!
//! # Model
//!
//! A [`RoadNetwork`] holds [`Road`]s (OpenDRIVE roads: a reference line plus lane sections), [`Lane`]s (one per
//! road, lane section and lane id) and [`LanePiece`]s: each lane is discretised into quads between consecutive
//! stations of the reference line (0.25–2 m apart, denser on curves) with inner and outer borders in world
//! coordinates. The spatial index, the lane graph, the sidewalk graph and the obstacle BVH are derived from
//! these when the network is built and never change afterwards.
//!
//! Lateral offsets are measured along the road's `t` axis: positive to the left of the road's reference
//! direction (increasing `s`). The *carriageway* at a station is the span of lanes between the innermost
//! sidewalk on the left and the innermost sidewalk on the right (driving, parking, shoulder/curb, median,
//! biking and other lanes); `road_width_m` is its width. The model is 2-D for queries: elevation is kept per
//! piece (`z_m`) but `lane_at` ignores it (CARLA's bridges overlap roads below them in plan view).

pub(crate) mod builtin;
pub(crate) mod grid;
mod index;
mod obstacles;
pub mod opendrive;
mod render;
mod routes;
mod sidewalks;
pub mod signals;

use std::ops::Range;
use std::path::Path;

use glam::{DVec2, DVec3};
use serde::Serialize;

pub use routes::{Route, RoutePoint, SpawnPoint};
pub use sidewalks::{Crossing, Side, SidewalkGraph, SidewalkSample};
pub use signals::Signal;

/// Names of the built-in procedural towns, in the order `pedsynth town list` shows them. They are modelled on
/// the paper's CARLA towns but are not CARLA's maps, hence the `_like` suffix.
pub const BUILTIN_TOWN_NAMES: [&str; 4] = ["town01_like", "town02_like", "town03_like", "town05_like"];

/// Height of the curb: sidewalk surfaces stand this much above the reference line's elevation, so pedestrians
/// step down onto the road and sensors see the curb, metres (CARLA's towns: about 15 cm).
pub const CURB_HEIGHT_M: f64 = 0.15;

/// Projection of `p` on the segment `a`–`b` (plan view): `(t, squared distance, squared segment length)` with
/// `t` in [0, 1] the fraction along the segment of the nearest point (0 for a degenerate segment).
#[inline]
pub fn segment_projection(a: DVec2, b: DVec2, p: DVec2) -> (f64, f64, f64) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (t, (a + ab * t - p).length_squared(), len2)
}

/// Whether the segment `from + t·d`, t ∈ (1e-6, `t_max`), passes through a box turned about z: centre `centre`,
/// `yaw.sin_cos()` as `sin_cos`, half extents `half` (along its heading, across, up). A slab test.
#[inline]
pub fn segment_hits_box(from: DVec3, d: DVec3, t_max: f64, centre: DVec3, sin_cos: (f64, f64), half: DVec3) -> bool {
    let (s, c) = sin_cos;
    let rel = from - centre;
    let o = DVec3::new(c * rel.x + s * rel.y, -s * rel.x + c * rel.y, rel.z);
    let v = DVec3::new(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
    let (mut t0, mut t1): (f64, f64) = (1e-6, t_max);
    for k in 0..3 {
        if v[k].abs() < 1e-12 {
            if o[k].abs() > half[k] {
                return false;
            }
        } else {
            let a = (-half[k] - o[k]) / v[k];
            let b = (half[k] - o[k]) / v[k];
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// Whether the segment `from + t·d`, t ∈ (1e-6, `t_max`), passes through the upright cylinder of `radius_m` and
/// `height_m` standing at `ground`.
#[inline]
pub fn segment_hits_cylinder(from: DVec3, d: DVec3, t_max: f64, ground: DVec3, radius_m: f64, height_m: f64) -> bool {
    let o = (from - ground).truncate();
    let v = d.truncate();
    let a = v.length_squared();
    if a < 1e-12 {
        return false;
    }
    let b = o.dot(v);
    let c = o.length_squared() - radius_m * radius_m;
    let disc = b * b - a * c;
    if disc < 0.0 {
        return false;
    }
    let sq = disc.sqrt();
    let (lo, hi) = (((-b - sq) / a).max(1e-6), ((-b + sq) / a).min(t_max));
    if lo > hi {
        return false;
    }
    // Inside the cylinder's height anywhere on [lo, hi] (z is linear in t).
    let z0 = from.z + d.z * lo - ground.z;
    let z1 = from.z + d.z * hi - ground.z;
    z0.min(z1) <= height_m && z0.max(z1) >= 0.0
}

/// Whether `p` lies inside the polygon `poly` (plan view, even-odd rule; either winding, not closed).
pub fn point_in_polygon(poly: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The axis-aligned bounding box `(lo, hi)` of `points`, or `None` when there are none.
pub fn bounding_box(points: impl IntoIterator<Item = DVec2>) -> Option<(DVec2, DVec2)> {
    let mut points = points.into_iter();
    let first = points.next()?;
    Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
}

/// Converts a point from this crate's right-handed frame to CARLA's left-handed world frame.
pub fn to_carla(p: DVec3) -> DVec3 {
    DVec3::new(p.x, -p.y, p.z)
}

/// Converts a point from CARLA's left-handed world frame to this crate's right-handed frame.
pub fn from_carla(p: DVec3) -> DVec3 {
    DVec3::new(p.x, -p.y, p.z)
}

/// Errors from loading a road network. Every variant carries the file (or built-in name) it concerns; XML
/// errors also carry the 1-based line of the offending element.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum WorldError {
    /// The file is not well-formed XML.
    #[error("{path}:{line}: malformed OpenDRIVE XML: {message}")]
    #[diagnostic(
        code(pedsynth::world::xodr_syntax),
        help("the file must be a well-formed OpenDRIVE 1.4-1.7 document")
    )]
    XodrSyntax { path: String, line: u32, message: String },
    /// The XML is well-formed but its content is unusable (missing geometry, NaN, absurd values, ...).
    #[error("{path}:{line}: invalid OpenDRIVE: {message}")]
    #[diagnostic(code(pedsynth::world::xodr_invalid))]
    XodrInvalid { path: String, line: u32, message: String },
    /// The file (or the network it describes) exceeds the size caps that protect us from hostile input.
    #[error("{path}:{line}: OpenDRIVE input too large: {message}")]
    #[diagnostic(code(pedsynth::world::xodr_too_large))]
    XodrTooLarge { path: String, line: u32, message: String },
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    #[diagnostic(code(pedsynth::world::io))]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The town name is neither a built-in town nor a path ending in `.xodr`.
    #[error("unknown town {name:?}")]
    #[diagnostic(
        code(pedsynth::world::unknown_town),
        help("built-in towns: town01_like, town02_like, town03_like, town05_like; or give a path to an .xodr file")
    )]
    UnknownTown { name: String },
}

impl crate::error::Report for WorldError {
    fn code(&self) -> &'static str {
        use crate::error::code;
        match self {
            WorldError::XodrSyntax { .. } => code::XODR_SYNTAX,
            WorldError::XodrInvalid { .. } => code::XODR_INVALID,
            WorldError::XodrTooLarge { .. } => code::XODR_TOO_LARGE,
            WorldError::Io { .. } => code::WORLD_IO,
            WorldError::UnknownTown { .. } => code::UNKNOWN_TOWN,
        }
    }

    fn summary(&self) -> String {
        self.to_string()
    }

    fn render(&self) -> String {
        crate::error::render_diagnostic(self)
    }
}

impl From<WorldError> for crate::error::Error {
    fn from(e: WorldError) -> Self {
        crate::error::Error::report(e)
    }
}

/// What a lane is for. Unknown OpenDRIVE types map to `Other`; `curb` maps to `Border`; the driving-like types
/// (`entry`, `exit`, `onRamp`, `offRamp`, `connectingRamp`, `bidirectional`, `stop`) map to `Driving`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LaneType {
    Driving,
    Sidewalk,
    Shoulder,
    Parking,
    Median,
    Border,
    Biking,
    Other,
}

impl LaneType {
    /// Parses an OpenDRIVE lane type attribute (case-insensitive, lenient).
    pub fn from_xodr(s: &str) -> LaneType {
        match s.to_ascii_lowercase().as_str() {
            "driving" | "entry" | "exit" | "onramp" | "offramp" | "connectingramp" | "bidirectional" | "stop" => {
                LaneType::Driving
            }
            "sidewalk" | "walking" => LaneType::Sidewalk,
            "shoulder" => LaneType::Shoulder,
            "parking" => LaneType::Parking,
            "median" => LaneType::Median,
            "border" | "curb" => LaneType::Border,
            "biking" => LaneType::Biking,
            _ => LaneType::Other,
        }
    }
}

/// Direction of travel on a lane, relative to the road's reference direction (increasing `s`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TravelDirection {
    /// Traffic moves towards increasing `s`.
    Forward,
    /// Traffic moves towards decreasing `s`.
    Backward,
    /// Both directions (e.g. OpenDRIVE `bidirectional`).
    Both,
    /// No vehicle traffic (sidewalks, shoulders, ...).
    Undirected,
}

/// One OpenDRIVE road: a reference line carrying lane sections.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Road {
    /// The road's id as written in the file (built-in towns number them).
    pub id: String,
    pub name: String,
    /// Id of the junction this road belongs to, for connecting roads inside junctions.
    pub junction: Option<String>,
    pub length_m: f64,
    /// Indices into [`RoadNetwork::lanes`].
    pub lanes: Range<u32>,
    pub predecessor: Option<RoadLink>,
    pub successor: Option<RoadLink>,
}

/// A road's link to its predecessor or successor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RoadLink {
    /// `road` or `junction`.
    pub element_type: String,
    pub element_id: String,
    /// `start` or `end` for links to roads.
    pub contact_point: Option<String>,
}

/// One lane of one lane section of one road.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Lane {
    /// Index into [`RoadNetwork::roads`].
    pub road: u32,
    /// Index of the lane section within its road.
    pub section: u32,
    /// OpenDRIVE lane id: > 0 left of the reference line, < 0 right of it.
    pub lane_id: i32,
    pub lane_type: LaneType,
    pub travel: TravelDirection,
    pub speed_limit_mps: f64,
    /// Indices into [`RoadNetwork::pieces`], ordered by increasing `s`.
    pub pieces: Range<u32>,
    /// Length of the lane's centre line.
    pub length_m: f64,
    /// Whether the lane belongs to a connecting road inside a junction.
    pub in_junction: bool,
}

/// A quad of one lane between two consecutive stations of its road's reference line.
///
/// `corners` are `[inner(s0), inner(s1), outer(s1), outer(s0)]`, where *inner* is the border nearer the
/// reference line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LanePiece {
    pub corners: [DVec2; 4],
    /// Index into [`RoadNetwork::lanes`].
    pub lane: u32,
    /// Station range along the road's reference line.
    pub s_m: [f64; 2],
    /// Lane width at the two stations.
    pub width_m: [f32; 2],
    /// Carriageway width at the two stations (see the module doc).
    pub road_width_m: [f32; 2],
    /// Mean elevation of the piece.
    pub z_m: f32,
}

impl LanePiece {
    /// Centre-line points at the two stations.
    pub fn centre(&self) -> [DVec2; 2] {
        [
            (self.corners[0] + self.corners[3]) * 0.5,
            (self.corners[1] + self.corners[2]) * 0.5,
        ]
    }
}

/// A junction and its connections as given by the source.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Junction {
    pub id: String,
    pub name: String,
    /// Mean of the connecting roads' mid points (the junction's rough centre).
    pub centre: DVec2,
    pub connections: Vec<JunctionConnection>,
}

/// One `<connection>` of a junction.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct JunctionConnection {
    pub incoming_road: String,
    pub connecting_road: String,
    pub contact_point: String,
    /// (from lane id on the incoming road, to lane id on the connecting road).
    pub lane_links: Vec<(i32, i32)>,
}

/// A pedestrian crossing: a polygon on the carriageway.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Crosswalk {
    /// Outline in world coordinates (counter-clockwise or clockwise, not closed).
    pub polygon: Vec<DVec2>,
    /// Index into [`RoadNetwork::roads`] of the road it lies on.
    pub road: u32,
    /// True when the crosswalk was derived (at a junction mouth with sidewalks on both sides) rather than
    /// read from a `<object type="crosswalk">`.
    pub synthesized: bool,
}

/// Kind of a static obstacle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ObstacleKind {
    Building,
    Pole,
    Tree,
}

/// A static obstacle: an oriented box standing on the ground (z from `base_z_m` to `base_z_m + height_m`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Obstacle {
    pub kind: ObstacleKind,
    pub centre: DVec2,
    pub half_extents_m: DVec2,
    pub heading_rad: f64,
    pub base_z_m: f64,
    pub height_m: f64,
}

impl Obstacle {
    /// The footprint's four corners, counter-clockwise.
    pub fn footprint(&self) -> [DVec2; 4] {
        let (s, c) = self.heading_rad.sin_cos();
        let ax = DVec2::new(c, s) * self.half_extents_m.x;
        let ay = DVec2::new(-s, c) * self.half_extents_m.y;
        [
            self.centre - ax - ay,
            self.centre + ax - ay,
            self.centre + ax + ay,
            self.centre - ax + ay,
        ]
    }

    /// The axis-aligned bounding box `(lo, hi)` of the footprint.
    pub fn footprint_box(&self) -> (DVec2, DVec2) {
        bounding_box(self.footprint()).expect("four corners")
    }
}

/// Where a network came from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TownSource {
    Builtin,
    Xodr { path: String },
}

/// Result of [`RoadNetwork::lane_at`] and [`RoadNetwork::nearest_driving_lane`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaneHit {
    pub lane_type: LaneType,
    /// Index into [`RoadNetwork::roads`].
    pub road: u32,
    /// Index into [`RoadNetwork::lanes`].
    pub lane: u32,
    /// OpenDRIVE lane id.
    pub lane_id: i32,
    /// Index into [`RoadNetwork::pieces`].
    pub piece: u32,
    /// Station of the query point's projection on the reference line.
    pub s_m: f64,
    /// Signed distance from the lane's centre line, positive to the left of the road's reference direction.
    pub lateral_offset_m: f64,
    /// Width of the lane at the query station.
    pub lane_width_m: f64,
    /// Width of the carriageway at the query station.
    pub road_width_m: f64,
    /// Direction of travel (the reference direction for lanes without a travel direction).
    pub heading_rad: f64,
    pub travel: TravelDirection,
    pub speed_limit_mps: f64,
    /// Distance from the query point to the lane piece (0 when inside).
    pub distance_m: f64,
    /// Elevation of the lane piece.
    pub z_m: f64,
}

/// Summary figures of a town, rounded so that golden files are stable.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TownSummary {
    pub name: String,
    pub source: TownSource,
    pub road_count: usize,
    pub lane_count: usize,
    pub junction_count: usize,
    pub crosswalk_count: usize,
    pub obstacle_count: usize,
    /// Traffic light heads (one per signalised junction approach).
    pub signal_count: usize,
    /// Junctions with traffic lights.
    pub signalised_junction_count: usize,
    /// Signal controllers: the phases of all signalised junctions' plans together.
    pub signal_controller_count: usize,
    /// Total centre-line length of driving lanes (junction connecting lanes included), km, 2 decimals.
    pub driving_lane_km: f64,
    /// Total centre-line length of sidewalk lanes, km, 2 decimals.
    pub sidewalk_km: f64,
    /// Total centre-line length of bike lanes (OpenDRIVE `biking`), km, 2 decimals.
    pub bike_lane_km: f64,
    /// Number of driving lanes in the lane graph that have at least one successor.
    pub routable_lane_count: usize,
    /// `[min_x, min_y, max_x, max_y]` of all lane pieces, metres, 1 decimal.
    pub bounds_m: [f64; 4],
}

/// A town: roads, lanes, junctions, crosswalks, obstacles and the derived query structures.
#[derive(Clone, Debug)]
pub struct RoadNetwork {
    pub name: String,
    pub source: TownSource,
    pub roads: Vec<Road>,
    pub lanes: Vec<Lane>,
    pub pieces: Vec<LanePiece>,
    pub junctions: Vec<Junction>,
    pub crosswalks: Vec<Crosswalk>,
    pub obstacles: Vec<Obstacle>,
    /// Traffic light heads, sorted by junction and approach road ([`signals`]).
    pub signals: Vec<Signal>,
    /// `(min, max)` corners of the axis-aligned bounds of all lane pieces.
    pub bounds: (DVec2, DVec2),
    index: index::LaneIndex,
    lane_graph: routes::LaneGraph,
    sidewalk_graph: sidewalks::SidewalkGraph,
    obstacle_index: obstacles::ObstacleIndex,
}

impl RoadNetwork {
    /// Builds a built-in procedural town by name (one of [`BUILTIN_TOWN_NAMES`]). Deterministic.
    pub fn builtin(name: &str) -> Option<RoadNetwork> {
        builtin::build(name)
    }

    /// A fingerprint of the town's geometry and topology (blake3 of the JSON of its roads, lanes, pieces,
    /// junctions, crosswalks, obstacles and traffic lights; not its name or source path): a plan records it for every town, so
    /// that a plan made for another version of a map is refused instead of indexing the wrong lanes.
    pub fn fingerprint(&self) -> String {
        #[derive(Serialize)]
        struct Geometry<'a> {
            roads: &'a [Road],
            lanes: &'a [Lane],
            pieces: &'a [LanePiece],
            junctions: &'a [Junction],
            crosswalks: &'a [Crosswalk],
            obstacles: &'a [Obstacle],
            #[serde(skip_serializing_if = "<[_]>::is_empty")]
            signals: &'a [Signal],
        }
        let geometry = Geometry {
            roads: &self.roads,
            lanes: &self.lanes,
            pieces: &self.pieces,
            junctions: &self.junctions,
            crosswalks: &self.crosswalks,
            obstacles: &self.obstacles,
            signals: &self.signals,
        };
        let mut hasher = blake3::Hasher::new();
        // Serialising plain data into a hasher cannot fail; were it to, the fingerprint would still differ
        // from any real town's.
        serde_json::to_writer(&mut hasher, &geometry).ok();
        hasher.finalize().to_hex().to_string()
    }

    /// Loads an OpenDRIVE file. This is the only function of the world module that does IO.
    pub fn from_xodr_file(path: &Path) -> Result<RoadNetwork, WorldError> {
        let shown = path.display().to_string();
        // Capped while reading: a FIFO or a device reports no size, a growing file a wrong one.
        let bytes = crate::util::files::read_capped(path, opendrive::MAX_FILE_BYTES).map_err(|source| {
            if source.kind() == std::io::ErrorKind::FileTooLarge {
                WorldError::XodrTooLarge {
                    path: shown.clone(),
                    line: 1,
                    message: format!("the file is larger than the cap of {} bytes", opendrive::MAX_FILE_BYTES),
                }
            } else {
                WorldError::Io {
                    path: shown.clone(),
                    source,
                }
            }
        })?;
        let xml = String::from_utf8(bytes).map_err(|e| WorldError::XodrSyntax {
            path: shown.clone(),
            line: 1 + bytecount_lines(&e.as_bytes()[..e.utf8_error().valid_up_to()]),
            message: "file is not valid UTF-8".into(),
        })?;
        Self::from_xodr_str(&xml, &shown)
    }

    /// Parses an OpenDRIVE document held in memory; `source` names it in errors and in the summary.
    pub fn from_xodr_str(xml: &str, source: &str) -> Result<RoadNetwork, WorldError> {
        let raw = opendrive::parse::parse(xml, source)?;
        let name = Path::new(source)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| source.to_string());
        opendrive::build::build(
            raw,
            name,
            TownSource::Xodr {
                path: source.to_string(),
            },
            source,
            xml,
        )
    }

    /// Loads a built-in town by name or an OpenDRIVE file by path (anything ending in `.xodr`).
    pub fn load(name_or_path: &str) -> Result<RoadNetwork, WorldError> {
        if let Some(net) = Self::builtin(name_or_path) {
            return Ok(net);
        }
        if name_or_path.to_ascii_lowercase().ends_with(".xodr") {
            return Self::from_xodr_file(Path::new(name_or_path));
        }
        Err(WorldError::UnknownTown {
            name: name_or_path.to_string(),
        })
    }

    /// The lane piece containing `p` in plan view. Where pieces overlap (junctions), the one whose centre line
    /// is nearest relative to its half width wins; lanes of type `Other` lose against typed lanes; where
    /// pieces on different levels overlap (a bridge over a road), the lowest wins. Allocation-free.
    pub fn lane_at(&self, p: DVec2) -> Option<LaneHit> {
        self.index.lane_at(self, p, None)
    }

    /// Like [`lane_at`](Self::lane_at), but only lane pieces within 3 m of the elevation `p.z` count (to
    /// query a bridge deck rather than the road below).
    pub fn lane_at_3d(&self, p: DVec3) -> Option<LaneHit> {
        self.index.lane_at(self, p.truncate(), Some(p.z))
    }

    /// The nearest driving lane with a travel direction within `max_distance_m` of `p`.
    pub fn nearest_driving_lane(&self, p: DVec2, max_distance_m: f64) -> Option<LaneHit> {
        self.index.nearest(self, p, max_distance_m, |l| {
            l.lane_type == LaneType::Driving && matches!(l.travel, TravelDirection::Forward | TravelDirection::Backward)
        })
    }

    /// Builds a [`LaneHit`] for `p` against one piece (used by the index and by callers holding a piece index).
    pub fn hit_on_piece(&self, piece: u32, p: DVec2) -> LaneHit {
        index::hit_on_piece(self, piece, p)
    }

    /// Summary figures for `town show --json` and golden tests.
    pub fn summary(&self) -> TownSummary {
        let km = |t: LaneType| {
            let m: f64 = self.lanes.iter().filter(|l| l.lane_type == t).map(|l| l.length_m).sum();
            // `+ 0.0`: an empty sum is −0.0.
            (m / 10.0).round() / 100.0 + 0.0
        };
        let r1 = |v: f64| (v * 10.0).round() / 10.0;
        TownSummary {
            name: self.name.clone(),
            source: self.source.clone(),
            road_count: self.roads.len(),
            lane_count: self.lanes.len(),
            junction_count: self.junctions.len(),
            crosswalk_count: self.crosswalks.len(),
            obstacle_count: self.obstacles.len(),
            signal_count: self.signals.len(),
            signalised_junction_count: (0..self.junctions.len() as u32)
                .filter(|&j| signals::junction_phases(&self.signals, j) > 0)
                .count(),
            signal_controller_count: (0..self.junctions.len() as u32)
                .map(|j| signals::junction_phases(&self.signals, j) as usize)
                .sum(),
            driving_lane_km: km(LaneType::Driving),
            sidewalk_km: km(LaneType::Sidewalk),
            bike_lane_km: km(LaneType::Biking),
            routable_lane_count: self.lane_graph.routable_lane_count(),
            bounds_m: [
                r1(self.bounds.0.x),
                r1(self.bounds.0.y),
                r1(self.bounds.1.x),
                r1(self.bounds.1.y),
            ],
        }
    }

    /// Renders a top-down PNG (north up) at `px_per_m`, shrunk if needed so that neither side exceeds
    /// `max_side_px`. Returns the PNG bytes.
    pub fn render_png(&self, px_per_m: f64, max_side_px: u32) -> Vec<u8> {
        render::render_png(self, px_per_m, max_side_px)
    }

    /// The surface mask of nuScenes' map: a grey PNG of `size_px` (width, height) at `m_per_px` whose bottom-left
    /// corner is `origin` (north up), 255 where a lane of any type covers a pixel's centre, 0 elsewhere.
    pub fn surface_mask_png(&self, origin: DVec2, m_per_px: f64, size_px: (usize, usize)) -> Vec<u8> {
        render::surface_mask_png(self, origin, m_per_px, size_px)
    }

    /// Centre-line points of a lane in the direction of travel (reference direction if undirected).
    pub fn lane_centre_line(&self, lane: u32) -> Vec<DVec2> {
        routes::lane_centre_line(self, lane)
    }

    /// Distance along the segment `from → to` to the first static obstacle it hits, if any.
    pub fn first_obstacle_hit(&self, from: DVec3, to: DVec3) -> Option<f64> {
        self.obstacle_index.first_hit(&self.obstacles, from, to)
    }

    /// Whether the segment `from → to` hits a static obstacle (line-of-sight test).
    pub fn ray_hits_obstacle(&self, from: DVec3, to: DVec3) -> bool {
        self.first_obstacle_hit(from, to).is_some()
    }
}

/// Number of newlines in `b`.
fn bytecount_lines(b: &[u8]) -> u32 {
    b.iter().filter(|&&c| c == b'\n').count() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_town_names_match_the_spec_language() {
        let names: Vec<&str> = crate::spec::types::BuiltinTown::ALL.iter().map(|t| t.name()).collect();
        assert_eq!(names, BUILTIN_TOWN_NAMES);
    }

    #[test]
    fn carla_frame_round_trip() {
        let p = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(to_carla(p), DVec3::new(1.0, -2.0, 3.0));
        assert_eq!(from_carla(to_carla(p)), p);
    }

    #[test]
    fn lane_types_parse_leniently() {
        assert_eq!(LaneType::from_xodr("Driving"), LaneType::Driving);
        assert_eq!(LaneType::from_xodr("sidewalk"), LaneType::Sidewalk);
        assert_eq!(LaneType::from_xodr("curb"), LaneType::Border);
        assert_eq!(LaneType::from_xodr("-1"), LaneType::Other);
    }
}
