//! The renderable scene of a clip: triangles with a primitive table (material, CARLA semantic tag, instance
//! id, albedo, normal), built from the town (once per clip) and from the trace (once per frame). One source for
//! every camera stream and, later, for LiDAR: what a camera draws is what a ray would hit.
//!
//! - Static part ([`StaticScene`]): the lane pieces near the ego's path (roads at their elevation, sidewalks
//!   raised by the world's curb, curb faces), a terrain plane, buildings (walls and roofs), trees, poles and
//!   street lamps (synthesised along sidewalks; towns and maps rarely carry them). Lane markings and crosswalk
//!   stripes are not geometry: they are painted by the surface functions ([`road_paint`]) from the lane
//!   piece a road pixel belongs to, so the label streams and the image agree exactly.
//! - Dynamic part ([`FrameScene`]): traffic vehicles (body, cabin, wheels, lamps) and pedestrians (the
//!   capsules of [`super::body::pose`], the very body the keypoints come from) at a frame, or at a time between
//!   two frames for the DVS's sub-frame renders.
//!
//! Positions are `f32` metres relative to the clip's [`StaticScene::origin`] (a world point near the ego's
//! path), which keeps single precision at the millimetre over a town.

use std::collections::BTreeMap;
use std::ops::Range;

use glam::{DVec2, DVec3, Vec2, Vec3};

use super::body::{self, CAPSULES, CHILD_OFFSET_M};
use super::cyclist;
use crate::plan::{ClipScript, EmergencyKind, Identity};
use crate::sim::trace::{ClipTrace, LightState, PedFrame, VehicleFrame};
use crate::sim::{VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::util::mix::splitmix64;
use crate::world::{CURB_HEIGHT_M, LaneType, ObstacleKind, RoadNetwork, TravelDirection};

/// CARLA's semantic tags (CARLA 0.9.14+, `carla.CityObjectLabel`), as written in the `semantic` stream.
pub mod tag {
    /// Nothing (never drawn: every pixel is something).
    pub const UNLABELED: u8 = 0;
    /// Road surface.
    pub const ROAD: u8 = 1;
    /// Sidewalk surface and curb.
    pub const SIDEWALK: u8 = 2;
    /// Buildings.
    pub const BUILDING: u8 = 3;
    /// Poles and street lamps.
    pub const POLE: u8 = 6;
    /// Traffic light heads.
    pub const TRAFFIC_LIGHT: u8 = 7;
    /// Trees.
    pub const VEGETATION: u8 = 9;
    /// Grass and soil beside the roads.
    pub const TERRAIN: u8 = 10;
    /// Sky.
    pub const SKY: u8 = 11;
    /// Pedestrians.
    pub const PEDESTRIAN: u8 = 12;
    /// A cyclist's rider.
    pub const RIDER: u8 = 13;
    /// Bicycles.
    pub const BICYCLE: u8 = 19;
    /// Cars.
    pub const CAR: u8 = 14;
    /// Lane markings and crosswalk stripes.
    pub const ROAD_LINE: u8 = 24;
    /// Paved ground that is neither road nor sidewalk (medians, borders, shoulders).
    pub const GROUND: u8 = 25;
    /// Names of the tags, indexed by id (CARLA's spelling).
    pub const NAMES: [&str; 29] = [
        "Unlabeled",
        "Road",
        "Sidewalk",
        "Building",
        "Wall",
        "Fence",
        "Pole",
        "TrafficLight",
        "TrafficSign",
        "Vegetation",
        "Terrain",
        "Sky",
        "Pedestrian",
        "Rider",
        "Car",
        "Truck",
        "Bus",
        "Train",
        "Motorcycle",
        "Bicycle",
        "Static",
        "Dynamic",
        "Other",
        "Water",
        "RoadLine",
        "Ground",
        "Bridge",
        "RailTrack",
        "GuardRail",
    ];
    /// CARLA's palette for the tags (the CityScapes colours), indexed by id.
    pub const PALETTE: [[u8; 3]; 29] = [
        [0, 0, 0],
        [128, 64, 128],
        [244, 35, 232],
        [70, 70, 70],
        [102, 102, 156],
        [190, 153, 153],
        [153, 153, 153],
        [250, 170, 30],
        [220, 220, 0],
        [107, 142, 35],
        [152, 251, 152],
        [70, 130, 180],
        [220, 20, 60],
        [255, 0, 0],
        [0, 0, 142],
        [0, 0, 70],
        [0, 60, 100],
        [0, 80, 100],
        [0, 0, 230],
        [119, 11, 32],
        [110, 190, 160],
        [170, 120, 50],
        [55, 90, 80],
        [45, 60, 150],
        [157, 234, 50],
        [81, 0, 81],
        [150, 100, 100],
        [230, 150, 140],
        [180, 165, 180],
    ];
}

/// Instance ids of the `instance` stream (16-bit): 0 for static scenery and sky, `1 + pedestrian` for a
/// pedestrian (its id in the tables), [`CHILD_INSTANCE_BASE`]` + parent` for the child walking beside a parent,
/// [`VEHICLE_INSTANCE_BASE`]` + vehicle` for a traffic vehicle (its id in the `vehicles` table),
/// [`CYCLIST_INSTANCE_BASE`]` + cyclist` for a cyclist.
pub const CHILD_INSTANCE_BASE: u16 = 16_384;
/// See [`CHILD_INSTANCE_BASE`].
pub const VEHICLE_INSTANCE_BASE: u16 = 32_768;
/// [`CYCLIST_INSTANCE_BASE`]` + cyclist` for a cyclist (rider and bicycle; its id in the `cyclists` table).
pub const CYCLIST_INSTANCE_BASE: u16 = 49_152;

/// The instance id of pedestrian `id`.
pub fn pedestrian_instance(id: u32) -> u16 {
    (1 + id).min(u32::from(CHILD_INSTANCE_BASE) - 1) as u16
}

/// The actor an instance id belongs to, as the tables number it: the pedestrian id (for a pedestrian and the
/// child walking with it), the vehicle id or the cyclist id; `None` for the static scene. Undoes
/// [`pedestrian_instance`], [`CHILD_INSTANCE_BASE`], [`VEHICLE_INSTANCE_BASE`] and [`CYCLIST_INSTANCE_BASE`].
pub fn actor_of_instance(instance: u16) -> Option<u32> {
    match instance {
        0 => None,
        i if i >= CYCLIST_INSTANCE_BASE => Some(u32::from(i - CYCLIST_INSTANCE_BASE)),
        i if i >= VEHICLE_INSTANCE_BASE => Some(u32::from(i - VEHICLE_INSTANCE_BASE)),
        i if i >= CHILD_INSTANCE_BASE => Some(u32::from(i - CHILD_INSTANCE_BASE)),
        i => Some(u32::from(i) - 1),
    }
}

/// How a primitive's surface is shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Material {
    /// Asphalt with lane markings and crosswalks; `aux` is the lane piece's [`PieceSurface`] index.
    Road,
    /// Sidewalk tiles.
    Sidewalk,
    /// Curb stone faces.
    Curb,
    /// Grass and soil.
    Terrain,
    /// A building wall with windows; `aux` is the building's index (window lighting seed).
    Wall,
    /// A flat roof.
    Roof,
    /// Painted metal (poles, lamp arms).
    Metal,
    /// A street lamp's head (emissive at night).
    LampHead,
    /// Tree bark.
    Trunk,
    /// Tree foliage.
    Foliage,
    /// Car paint.
    CarPaint,
    /// Car windows.
    CarGlass,
    /// Tyres.
    Tyre,
    /// Headlamps (emissive at night).
    HeadLamp,
    /// Tail lamps (emissive at night).
    TailLamp,
    /// An emergency vehicle's flashing light (emits its albedo, by day too).
    Beacon,
    /// Skin or clothing of a body part; `aux` is the capsule's index in [`FrameScene::capsules`] (smooth
    /// normals).
    Body,
    /// A head: skin in front, hair on top and at the back (`albedo2`); `aux` as for [`Material::Body`],
    /// `normal` is the body's forward axis.
    Head,
}

/// One primitive: everything the shading and the label streams need of a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prim {
    /// Shading model.
    pub material: Material,
    /// CARLA semantic tag.
    pub tag: u8,
    /// Instance id (0 for scenery).
    pub instance: u16,
    /// Base colour, linear RGB.
    pub albedo: Vec3,
    /// Second colour (hair for heads), linear RGB.
    pub albedo2: Vec3,
    /// Unit normal for flat surfaces (see [`Material::Head`] for heads).
    pub normal: Vec3,
    /// Material-specific index (see [`Material`]).
    pub aux: u32,
}

/// A triangle of the scene: three vertices (metres, relative to the scene origin) and its primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tri {
    /// Vertices.
    pub v: [Vec3; 3],
    /// Index into the primitive table.
    pub prim: u32,
}

/// A spatially coherent run of static triangles with its bounding sphere, for culling.
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// Bounding sphere centre.
    pub centre: Vec3,
    /// Bounding sphere radius.
    pub radius_m: f32,
    /// Triangles (indices into [`StaticScene::tris`]).
    pub tris: Range<u32>,
}

/// A lane marking along one border of a lane piece.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// None.
    None,
    /// Solid white (the carriageway's edge).
    Solid,
    /// Dashed white (between lanes of one direction).
    Dashed,
    /// Solid yellow (between the two directions, at the reference line).
    Centre,
}

/// What the road paint of a lane piece needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PieceSurface {
    /// Inner border (nearer the reference line), start and end, relative to the origin.
    pub inner: [Vec2; 2],
    /// Outer border, start and end.
    pub outer: [Vec2; 2],
    /// Stations of the two ends along the road, metres.
    pub s_m: [f32; 2],
    /// Marking on the inner and the outer border.
    pub marks: [Mark; 2],
    /// The crosswalk over this piece (index into [`StaticScene::crosswalks`]).
    pub crosswalk: Option<u32>,
}

/// A street lamp's light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lamp {
    /// Position of the light, relative to the origin.
    pub pos: Vec3,
}

/// Height of a street lamp's light above the sidewalk, metres.
pub const LAMP_HEIGHT_M: f32 = 6.5;
/// Distance between street lamps along a sidewalk, metres.
const LAMP_SPACING_M: f64 = 30.0;
/// How far around the ego's path the town is included, metres.
const SCENE_MARGIN_M: f64 = 160.0;
/// Width of a lane marking, metres.
pub const MARK_WIDTH_M: f32 = 0.15;
/// Dashes: painted length and period along the road, metres.
const DASH_M: (f32, f32) = (3.0, 9.0);

/// The static part of a clip's scene.
#[derive(Clone, Debug)]
pub struct StaticScene {
    /// World position of the scene's origin.
    pub origin: DVec3,
    /// Triangles, grouped by cluster.
    pub tris: Vec<Tri>,
    /// Clusters for culling.
    pub clusters: Vec<Cluster>,
    /// Primitive table of the static triangles (a frame's agents number theirs after these: see
    /// [`FrameScene::prim`]).
    pub prims: Vec<Prim>,
    /// Road paint of each road primitive (indexed by [`Prim::aux`]).
    pub pieces: Vec<PieceSurface>,
    /// Crosswalk outlines, relative to the origin.
    pub crosswalks: Vec<Vec<Vec2>>,
    /// Street lamps.
    pub lamps: Vec<Lamp>,
    /// The traffic lights drawn (indices into the trace's `signals`: those within the scene).
    pub signal_heads: Vec<usize>,
    /// The clip's seed (textures, colours).
    pub seed: u64,
    /// What each pedestrian (and the child beside it) wears, by pedestrian index: worked out once per clip.
    pub outfits: Vec<(Outfit, Option<Outfit>)>,
    /// Per cyclist: its rider's outfit and its bicycle's frame colour (linear RGB).
    pub riders: Vec<(Outfit, Vec3)>,
    /// Each traffic vehicle's paint (linear RGB), by vehicle index.
    pub car_paint: Vec<Vec3>,
}

/// What a body wears: the material and colour of each capsule (see [`body::pose`]'s order), and its hair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outfit {
    /// Per capsule: shading model and linear colour.
    pub parts: [(Material, Vec3); CAPSULES],
    /// Hair colour, linear RGB.
    pub hair: Vec3,
}

impl Outfit {
    /// The outfit of an identity; `key` seeds sleeve and leg length.
    pub fn of(identity: &Identity, seed: u64, key: u64) -> Outfit {
        let h = splitmix64(seed ^ 0xb0d1 ^ splitmix64(key));
        let short_sleeves = h & 3 == 0;
        let shorts = (h >> 2) & 7 == 0;
        let (skin, top, bottom) = (
            linear(identity.skin_rgb),
            linear(identity.top_rgb),
            linear(identity.bottom_rgb),
        );
        let shoes = linear(identity.shoes_rgb);
        Outfit {
            parts: WEAR.map(|w| match w {
                Wear::Top => (Material::Body, top),
                Wear::Bottom => (Material::Body, bottom),
                Wear::Skin => (Material::Body, skin),
                Wear::Shoes => (Material::Body, shoes),
                Wear::Head => (Material::Head, skin),
                Wear::Sleeve if short_sleeves => (Material::Body, skin),
                Wear::Sleeve => (Material::Body, top),
                Wear::Leg if shorts => (Material::Body, skin),
                Wear::Leg => (Material::Body, bottom),
            }),
            hair: linear(identity.hair_rgb),
        }
    }
}

/// An sRGB colour (0–255) in linear RGB.
pub fn linear(c: [u8; 3]) -> Vec3 {
    let f = |v: u8| {
        let x = f32::from(v) / 255.0;
        if x <= 0.04045 {
            x / 12.92
        } else {
            ((x + 0.055) / 1.055).powf(2.4)
        }
    };
    Vec3::new(f(c[0]), f(c[1]), f(c[2]))
}

/// Triangles and their primitives under construction. Primitive ids start at `base`: a frame's agents
/// ([`FrameScene`]) number theirs after the static scene's, which are not copied per frame.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Triangles.
    pub tris: Vec<Tri>,
    /// Primitives; `prims[i]` has id `base + i`.
    pub prims: Vec<Prim>,
    /// Id of the first primitive.
    pub base: u32,
}

impl Mesh {
    /// Empties the mesh; new primitives are numbered from `base`.
    pub fn clear(&mut self, base: u32) {
        self.tris.clear();
        self.prims.clear();
        self.base = base;
    }

    /// Adds a primitive; returns its id.
    pub fn prim(&mut self, prim: Prim) -> u32 {
        self.prims.push(prim);
        self.base + (self.prims.len() - 1) as u32
    }

    /// Adds a quad (corners in order) as two triangles.
    pub fn quad(&mut self, q: [Vec3; 4], prim: u32) {
        self.tris.push(Tri {
            v: [q[0], q[1], q[2]],
            prim,
        });
        self.tris.push(Tri {
            v: [q[0], q[2], q[3]],
            prim,
        });
    }

    /// Adds an upright box (footprint centre, heading, half extents along and across, z range): four sides of
    /// `side` and a top of `top`, each face its own primitive with its flat normal.
    pub fn upright_box(&mut self, centre: Vec2, heading_rad: f32, half: Vec2, z: [f32; 2], side: Prim, top: Prim) {
        let (s, c) = heading_rad.sin_cos();
        let ax = Vec2::new(c, s) * half.x;
        let ay = Vec2::new(-s, c) * half.y;
        let corners = [centre - ax - ay, centre + ax - ay, centre + ax + ay, centre - ax + ay];
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let n = -(b - a).perp().normalize_or_zero();
            let id = self.prim(Prim {
                normal: Vec3::new(n.x, n.y, 0.0),
                ..side
            });
            self.quad(
                [
                    Vec3::new(a.x, a.y, z[0]),
                    Vec3::new(b.x, b.y, z[0]),
                    Vec3::new(b.x, b.y, z[1]),
                    Vec3::new(a.x, a.y, z[1]),
                ],
                id,
            );
        }
        let id = self.prim(Prim { normal: Vec3::Z, ..top });
        self.quad(corners.map(|c| Vec3::new(c.x, c.y, z[1])), id);
    }

    /// Adds a capsule as a closed polyhedron (8 sides, two rings per cap) of one primitive.
    pub fn capsule(&mut self, c: &SceneCapsule, prim: u32) {
        const N: usize = 8;
        // Vertices sit slightly outside the surface so the polygon's silhouette matches the capsule's on average.
        let r = c.radius_m * 1.04;
        let d = c.b - c.a;
        let axis = if d.length_squared() > 1e-10 {
            d.normalize()
        } else {
            Vec3::Z
        };
        let u = axis.any_orthonormal_vector();
        let v = axis.cross(u);
        let ring = |centre: Vec3, radius: f32| -> [Vec3; N] {
            std::array::from_fn(|k| {
                let (s, co) = (k as f32 * std::f32::consts::TAU / N as f32).sin_cos();
                centre + (u * co + v * s) * radius
            })
        };
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let rings = [
            ring(c.a - axis * r * h, r * h),
            ring(c.a, r),
            ring(c.b, r),
            ring(c.b + axis * r * h, r * h),
        ];
        let poles = [c.a - axis * r, c.b + axis * r];
        for k in 0..N {
            let k1 = (k + 1) % N;
            self.tris.push(Tri {
                v: [poles[0], rings[0][k1], rings[0][k]],
                prim,
            });
            self.tris.push(Tri {
                v: [poles[1], rings[3][k], rings[3][k1]],
                prim,
            });
            for r2 in 0..3 {
                let (p, q) = (&rings[r2], &rings[r2 + 1]);
                self.quad([p[k], p[k1], q[k1], q[k]], prim);
            }
        }
    }
}

struct Builder {
    origin: DVec3,
    mesh: Mesh,
}

impl Builder {
    fn rel(&self, p: DVec3) -> Vec3 {
        (p - self.origin).as_vec3()
    }
}

fn flat(material: Material, tag: u8, albedo: Vec3, normal: Vec3, aux: u32) -> Prim {
    Prim {
        material,
        tag,
        instance: 0,
        albedo,
        albedo2: albedo,
        normal,
        aux,
    }
}

/// The markings of each lane's inner and outer border.
fn lane_marks(town: &RoadNetwork) -> Vec<[Mark; 2]> {
    let by_id: BTreeMap<(u32, u32, i32), usize> = town
        .lanes
        .iter()
        .enumerate()
        .map(|(i, l)| ((l.road, l.section, l.lane_id), i))
        .collect();
    let driving = |road: u32, section: u32, id: i32| {
        by_id
            .get(&(road, section, id))
            .map(|&i| &town.lanes[i])
            .filter(|l| l.lane_type == LaneType::Driving)
    };
    town.lanes
        .iter()
        .map(|l| {
            if l.lane_type != LaneType::Driving || l.in_junction {
                return [Mark::None, Mark::None];
            }
            let sign = l.lane_id.signum();
            let inner = if l.lane_id.abs() == 1 {
                let other_side = driving(l.road, l.section, -sign).is_some();
                if other_side && l.travel != TravelDirection::Both {
                    Mark::Centre
                } else {
                    Mark::None
                }
            } else {
                Mark::None // painted by the inner neighbour's outer border
            };
            let outer = match driving(l.road, l.section, l.lane_id + sign) {
                Some(n) if n.travel == l.travel => Mark::Dashed,
                Some(_) => Mark::Centre,
                None => Mark::Solid,
            };
            [inner, outer]
        })
        .collect()
}

/// The plan-view box of a clip's scene: the ego's path and [`SCENE_MARGIN_M`] around it.
pub fn scene_bounds(trace: &ClipTrace) -> (DVec2, DVec2) {
    let (lo, hi) =
        crate::world::bounding_box(trace.ego.iter().map(|e| e.pos.truncate())).unwrap_or((DVec2::ZERO, DVec2::ZERO));
    (lo - DVec2::splat(SCENE_MARGIN_M), hi + DVec2::splat(SCENE_MARGIN_M))
}

/// Where a street lamp stands: the foot of its pole, the sidewalk's height there and the direction of its arm
/// (toward the road).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LampPost {
    /// Foot of the pole, world plan view, metres.
    pub foot: DVec2,
    /// Height of the ground at the foot, metres.
    pub base_z_m: f64,
    /// Unit direction of the arm, toward the road.
    pub to_road: DVec2,
}

/// Half the width of a (square) lamp pole, metres.
pub const LAMP_POLE_HALF_WIDTH_M: f32 = 0.07;
/// How far the pole rises above the light, metres.
pub const LAMP_POLE_ABOVE_LIGHT_M: f32 = 0.2;

/// The street lamps of `town` whose foot satisfies `near`: one every [`LAMP_SPACING_M`] along each sidewalk
/// outside junctions, at the curb (a pure function of the town, so the renderer draws and the annotations
/// test occlusion against the same poles).
pub fn street_lamp_posts(town: &RoadNetwork, near: impl Fn(DVec2) -> bool) -> Vec<LampPost> {
    let mut posts = Vec::new();
    for lane in &town.lanes {
        if lane.lane_type != LaneType::Sidewalk || lane.in_junction {
            continue;
        }
        let mut next_m = LAMP_SPACING_M * 0.5;
        let mut along = 0.0;
        for piece in &town.pieces[lane.pieces.start as usize..lane.pieces.end as usize] {
            let [c0, c1] = piece.centre();
            let len = c0.distance(c1);
            while along + len >= next_m && len > 1e-6 {
                let t = (next_m - along) / len;
                let inner = piece.corners[0].lerp(piece.corners[1], t);
                let centre = c0.lerp(c1, t);
                let to_road = (inner - centre).normalize_or_zero();
                let width = f64::from(piece.width_m[0]);
                let foot = inner - to_road * (0.35f64).min(0.4 * width);
                next_m += LAMP_SPACING_M;
                if !near(foot) || width < 1.0 {
                    continue;
                }
                posts.push(LampPost {
                    foot,
                    base_z_m: f64::from(piece.z_m),
                    to_road,
                });
            }
            along += len;
        }
    }
    posts
}

/// Clearance between a lamp pole and the path of any pedestrian of the clip (the body's radius, a child
/// walking beside it, the pole), metres.
const LAMP_CLEARANCE_M: f64 = 1.0;

/// The street lamps of a clip's scene: [`street_lamp_posts`] within [`scene_bounds`], leaving out any that a
/// pedestrian of the clip would walk through (the simulation does not steer around poles, and a pole inside a
/// body makes neither a sensible image nor a sensible occlusion label). The renderer draws these and the
/// annotations test occlusion against these.
pub fn clip_lamp_posts(trace: &ClipTrace, town: &RoadNetwork) -> Vec<LampPost> {
    let (lo, hi) = scene_bounds(trace);
    let near = |p: DVec2| p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y;
    let mut posts = street_lamp_posts(town, near);
    let clear2 = LAMP_CLEARANCE_M * LAMP_CLEARANCE_M;
    posts.retain(|post| {
        trace
            .pedestrians
            .iter()
            .flatten()
            .all(|f| f.pos.truncate().distance_squared(post.foot) > clear2)
    });
    posts
}

/// Half the width of a traffic light's post, metres.
const SIGNAL_POST_HALF_WIDTH_M: f32 = 0.06;
/// Half the height of a traffic light's housing (three lamps above each other), metres.
pub const SIGNAL_HOUSING_HALF_HEIGHT_M: f32 = 0.45;
/// Half the width of a traffic light's housing, metres.
pub const SIGNAL_HOUSING_HALF_WIDTH_M: f32 = 0.17;
/// Half the depth of a traffic light's housing (along its facing), metres.
pub const SIGNAL_HOUSING_HALF_DEPTH_M: f32 = 0.12;
/// Half the side of a traffic light's lamp, metres.
const SIGNAL_LAMP_HALF_M: f32 = 0.11;

/// `p` relative to the scene origin, f32.
fn stat_rel(origin: DVec3, p: DVec3) -> Vec3 {
    (p - origin).as_vec3()
}

impl StaticScene {
    /// Builds the static scene of a clip: the town within [`SCENE_MARGIN_M`] of the ego's path.
    pub fn build(script: &ClipScript, trace: &ClipTrace, town: &RoadNetwork) -> StaticScene {
        let (lo, hi) = scene_bounds(trace);
        let z0 = trace.ego.first().map_or(0.0, |e| e.pos.z);
        let origin = DVec3::new(((lo.x + hi.x) * 0.5).round(), ((lo.y + hi.y) * 0.5).round(), z0.round());
        let near = |p: DVec2| p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y;
        let seed = script.seed;
        let mut b = Builder {
            origin,
            mesh: Mesh::default(),
        };
        let mut clusters = Vec::new();
        let mut cluster_start = 0u32;
        let close_cluster = |b: &Builder, clusters: &mut Vec<Cluster>, start: &mut u32| {
            let end = b.mesh.tris.len() as u32;
            if end == *start {
                return;
            }
            let tris = &b.mesh.tris[*start as usize..end as usize];
            let (mut mn, mut mx) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for t in tris {
                for v in t.v {
                    mn = mn.min(v);
                    mx = mx.max(v);
                }
            }
            let centre = (mn + mx) * 0.5;
            let radius_m = tris
                .iter()
                .flat_map(|t| t.v)
                .map(|v| v.distance(centre))
                .fold(0.0f32, f32::max);
            clusters.push(Cluster {
                centre,
                radius_m,
                tris: *start..end,
            });
            *start = end;
        };

        // Terrain: one large plane just under the lowest surface.
        let min_z = town
            .pieces
            .iter()
            .filter(|p| near(p.centre()[0]))
            .map(|p| f64::from(p.z_m))
            .fold(z0, f64::min);
        let terrain = b
            .mesh
            .prim(flat(Material::Terrain, tag::TERRAIN, linear([86, 104, 58]), Vec3::Z, 0));
        let tz = (min_z - 0.03 - origin.z) as f32;
        let e = 1500.0f32;
        b.mesh.quad(
            [
                Vec3::new(-e, -e, tz),
                Vec3::new(e, -e, tz),
                Vec3::new(e, e, tz),
                Vec3::new(-e, e, tz),
            ],
            terrain,
        );
        close_cluster(&b, &mut clusters, &mut cluster_start);

        // Road surfaces: one primitive per lane piece (road paint needs the piece), clusters of 24 pieces.
        let marks = lane_marks(town);
        let crosswalks: Vec<Vec<Vec2>> = town
            .crosswalks
            .iter()
            .map(|c| c.polygon.iter().map(|p| (*p - origin.truncate()).as_vec2()).collect())
            .collect();
        let cw_boxes: Vec<(Vec2, Vec2)> = crosswalks
            .iter()
            .map(|poly| {
                poly.iter().fold(
                    (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
                    |(a, b), p| (a.min(*p), b.max(*p)),
                )
            })
            .collect();
        let mut pieces = Vec::new();
        let asphalt = linear([62, 62, 66]);
        let pavement = linear([150, 146, 138]);
        let ground = linear([112, 110, 100]);
        let mut in_cluster = 0;
        for (lane_idx, lane) in town.lanes.iter().enumerate() {
            let lane_pieces = &town.pieces[lane.pieces.start as usize..lane.pieces.end as usize];
            for piece in lane_pieces {
                if !piece.corners.iter().any(|c| near(*c)) {
                    continue;
                }
                let z = f64::from(piece.z_m);
                let q: [Vec3; 4] = piece.corners.map(|c| b.rel(DVec3::new(c.x, c.y, z)));
                let (material, tag, albedo) = match lane.lane_type {
                    LaneType::Driving | LaneType::Parking => (Material::Road, tag::ROAD, asphalt),
                    // Red-coloured asphalt, as many cities surface their bike lanes (CARLA has no tag for them).
                    LaneType::Biking => (Material::Road, tag::ROAD, asphalt * Vec3::new(1.45, 0.8, 0.75)),
                    LaneType::Sidewalk => (Material::Sidewalk, tag::SIDEWALK, pavement),
                    LaneType::Shoulder | LaneType::Border => (Material::Road, tag::ROAD, asphalt * 1.1),
                    LaneType::Median | LaneType::Other => (Material::Sidewalk, tag::GROUND, ground),
                };
                let aux = if material == Material::Road {
                    let qb = q.map(|v| v.truncate());
                    let (pmin, pmax) = qb.iter().fold(
                        (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
                        |(a, b), p| (a.min(*p), b.max(*p)),
                    );
                    let crosswalk = cw_boxes
                        .iter()
                        .position(|(a, b2)| a.x <= pmax.x && a.y <= pmax.y && b2.x >= pmin.x && b2.y >= pmin.y)
                        .map(|i| i as u32);
                    pieces.push(PieceSurface {
                        inner: [qb[0], qb[1]],
                        outer: [qb[3], qb[2]],
                        s_m: [piece.s_m[0] as f32, piece.s_m[1] as f32],
                        marks: if lane.lane_type == LaneType::Driving {
                            marks[lane_idx]
                        } else {
                            [Mark::None, Mark::None]
                        },
                        crosswalk,
                    });
                    (pieces.len() - 1) as u32
                } else {
                    0
                };
                let id = b.mesh.prim(flat(material, tag, albedo, Vec3::Z, aux));
                b.mesh.quad(q, id);
                // Curb faces: a sidewalk's borders drop to the road (or the terrain) below.
                if lane.lane_type == LaneType::Sidewalk {
                    let low = (z - CURB_HEIGHT_M - origin.z) as f32;
                    for (a, c) in [(q[0], q[1]), (q[2], q[3])] {
                        let n2 = (c - a).truncate().perp().normalize_or_zero();
                        let curb = b.mesh.prim(flat(
                            Material::Curb,
                            tag::SIDEWALK,
                            linear([170, 168, 160]),
                            Vec3::new(n2.x, n2.y, 0.0),
                            0,
                        ));
                        b.mesh.quad(
                            [
                                Vec3::new(a.x, a.y, low),
                                Vec3::new(c.x, c.y, low),
                                Vec3::new(c.x, c.y, c.z),
                                Vec3::new(a.x, a.y, a.z),
                            ],
                            curb,
                        );
                    }
                }
                in_cluster += 1;
                if in_cluster == 24 {
                    close_cluster(&b, &mut clusters, &mut cluster_start);
                    in_cluster = 0;
                }
            }
            close_cluster(&b, &mut clusters, &mut cluster_start);
            in_cluster = 0;
        }

        // Buildings, trees and poles of the town.
        const FACADES: [[u8; 3]; 7] = [
            [150, 84, 64],
            [196, 178, 150],
            [140, 140, 136],
            [214, 208, 196],
            [120, 96, 78],
            [176, 150, 120],
            [104, 112, 120],
        ];
        for (i, o) in town.obstacles.iter().enumerate() {
            if !o.footprint().iter().any(|c| near(*c)) {
                continue;
            }
            let c = (o.centre - origin.truncate()).as_vec2();
            let z = [
                (o.base_z_m - origin.z) as f32,
                (o.base_z_m + o.height_m - origin.z) as f32,
            ];
            let h = splitmix64(seed ^ splitmix64(i as u64 + 1));
            match o.kind {
                ObstacleKind::Building => {
                    let colour = linear(FACADES[(h % FACADES.len() as u64) as usize]);
                    let wall = flat(Material::Wall, tag::BUILDING, colour, Vec3::Z, i as u32);
                    let roof = flat(Material::Roof, tag::BUILDING, linear([84, 80, 78]), Vec3::Z, i as u32);
                    b.mesh
                        .upright_box(c, o.heading_rad as f32, o.half_extents_m.as_vec2(), z, wall, roof);
                }
                ObstacleKind::Pole => {
                    let metal = flat(Material::Metal, tag::POLE, linear([90, 92, 96]), Vec3::Z, 0);
                    b.mesh
                        .upright_box(c, o.heading_rad as f32, o.half_extents_m.as_vec2(), z, metal, metal);
                }
                ObstacleKind::Tree => {
                    let bark = flat(Material::Trunk, tag::VEGETATION, linear([92, 70, 50]), Vec3::Z, 0);
                    let leaves = flat(Material::Foliage, tag::VEGETATION, linear([60, 100, 44]), Vec3::Z, 0);
                    let trunk_top = z[0] + 0.45 * (z[1] - z[0]);
                    b.mesh
                        .upright_box(c, 0.0, Vec2::splat(0.15), [z[0], trunk_top], bark, bark);
                    b.mesh.upright_box(
                        c,
                        o.heading_rad as f32,
                        o.half_extents_m.as_vec2(),
                        [trunk_top, z[1]],
                        leaves,
                        leaves,
                    );
                }
            }
            close_cluster(&b, &mut clusters, &mut cluster_start);
        }

        // Street lamps along the sidewalks (outside junctions), at the curb, the arm over the road.
        let mut lamps = Vec::new();
        let metal = flat(Material::Metal, tag::POLE, linear([70, 74, 78]), Vec3::Z, 0);
        let head = flat(Material::LampHead, tag::POLE, linear([230, 220, 190]), -Vec3::Z, 0);
        for post in clip_lamp_posts(trace, town) {
            let base = (post.base_z_m - origin.z) as f32;
            let f = (post.foot - origin.truncate()).as_vec2();
            let dir = post.to_road.as_vec2();
            let top = base + LAMP_HEIGHT_M;
            b.mesh.upright_box(
                f,
                0.0,
                Vec2::splat(LAMP_POLE_HALF_WIDTH_M),
                [base, top + LAMP_POLE_ABOVE_LIGHT_M],
                metal,
                metal,
            );
            let arm_end = f + dir * 1.4;
            b.mesh.upright_box(
                (f + arm_end) * 0.5,
                dir.y.atan2(dir.x),
                Vec2::new(0.7, 0.05),
                [top + 0.1, top + 0.2],
                metal,
                metal,
            );
            b.mesh.upright_box(
                arm_end,
                dir.y.atan2(dir.x),
                Vec2::new(0.3, 0.15),
                [top - 0.05, top + 0.1],
                head,
                metal,
            );
            lamps.push(Lamp {
                pos: Vec3::new(arm_end.x, arm_end.y, top - 0.15),
            });
            close_cluster(&b, &mut clusters, &mut cluster_start);
        }

        // Traffic lights (where they run): a post and a dark housing; the lamps are lit per frame.
        let post = flat(Material::Metal, tag::POLE, linear([60, 62, 64]), Vec3::Z, 0);
        let housing = flat(Material::Metal, tag::TRAFFIC_LIGHT, linear([28, 30, 26]), Vec3::Z, 0);
        let mut signal_heads = Vec::new();
        for (k, g) in trace.signals.iter().enumerate() {
            let p = g.position.truncate();
            if p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
                continue;
            }
            signal_heads.push(k);
            let head = stat_rel(origin, g.position);
            let yaw = g.facing_rad as f32;
            let ground = head.z - crate::world::signals::SIGNAL_HEAD_HEIGHT_M as f32;
            b.mesh.upright_box(
                head.truncate(),
                yaw,
                Vec2::splat(SIGNAL_POST_HALF_WIDTH_M),
                [ground, head.z - SIGNAL_HOUSING_HALF_HEIGHT_M],
                post,
                post,
            );
            b.mesh.upright_box(
                head.truncate(),
                yaw,
                Vec2::new(SIGNAL_HOUSING_HALF_DEPTH_M, SIGNAL_HOUSING_HALF_WIDTH_M),
                [
                    head.z - SIGNAL_HOUSING_HALF_HEIGHT_M,
                    head.z + SIGNAL_HOUSING_HALF_HEIGHT_M,
                ],
                housing,
                housing,
            );
            close_cluster(&b, &mut clusters, &mut cluster_start);
        }
        close_cluster(&b, &mut clusters, &mut cluster_start);

        StaticScene {
            origin,
            tris: b.mesh.tris,
            clusters,
            prims: b.mesh.prims,
            pieces,
            crosswalks,
            lamps,
            signal_heads,
            seed,
            riders: script
                .cyclists
                .iter()
                .map(|c| {
                    (
                        Outfit::of(&c.rider, seed, u64::from(c.id) | 1 << 41),
                        linear(c.bike_rgb),
                    )
                })
                .collect(),
            outfits: script
                .pedestrians
                .iter()
                .map(|p| {
                    (
                        Outfit::of(&p.identity, seed, u64::from(p.id)),
                        p.child.as_ref().map(|c| Outfit::of(c, seed, u64::from(p.id) | 1 << 40)),
                    )
                })
                .collect(),
            car_paint: (0..trace.vehicles.len())
                .map(|vi| {
                    let id = script.vehicles.get(vi).map_or(vi as u32, |v| v.id);
                    let h = splitmix64(seed ^ 0x5eed_ca75 ^ splitmix64(u64::from(id)));
                    match script.vehicles.get(vi).and_then(|v| v.emergency) {
                        Some(EmergencyKind::Ambulance) => linear([235, 235, 228]),
                        Some(EmergencyKind::FireTruck) => linear([190, 20, 18]),
                        Some(EmergencyKind::Police) => linear([22, 30, 70]),
                        None => linear(CAR_COLOURS[(h % CAR_COLOURS.len() as u64) as usize]),
                    }
                })
                .collect(),
        }
    }

    /// The scene-relative position of a world point.
    pub fn rel(&self, p: DVec3) -> Vec3 {
        (p - self.origin).as_vec3()
    }
}

/// Whether [`road_paint`] can find paint anywhere in the box `lo..=hi` (scene-relative): `false` where the
/// box misses the piece's crosswalk and every marking's bounding box grown by the mark's half width, so that
/// a run of points can skip the per-point test. Inlined: shading calls it once per run of road pixels, and a
/// call there spills every vector register of the shading around it.
#[inline(always)]
pub fn road_paint_near(scene: &StaticScene, piece: &PieceSurface, lo: Vec2, hi: Vec2) -> bool {
    let overlaps = |a: Vec2, b: Vec2| lo.x <= b.x && hi.x >= a.x && lo.y <= b.y && hi.y >= a.y;
    if let Some(cw) = piece.crosswalk {
        let poly = &scene.crosswalks[cw as usize];
        let (a, b) = poly.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(a, b), &q| (a.min(q), b.max(q)),
        );
        if overlaps(a, b) {
            return true;
        }
    }
    [(piece.inner, piece.marks[0]), (piece.outer, piece.marks[1])]
        .into_iter()
        .any(|([a, b], mark)| {
            // As in `road_paint`: the mark's half width and a millimetre.
            let reach = match mark {
                Mark::None => return false,
                Mark::Centre => MARK_WIDTH_M * 0.5,
                _ => MARK_WIDTH_M,
            } + 1e-3;
            overlaps(a.min(b) - reach, a.max(b) + reach)
        })
}

/// The paint of a road point: `Some((colour, tag))` for a marking or a crosswalk stripe, `None` for bare
/// asphalt. `p` is scene-relative.
pub fn road_paint(scene: &StaticScene, piece: &PieceSurface, p: Vec2) -> Option<(Vec3, u8)> {
    if let Some(cw) = piece.crosswalk {
        let poly = &scene.crosswalks[cw as usize];
        if point_in_polygon(poly, p) {
            // Stripes 0.5 m wide every 1 m, parallel to the road.
            let k = p.dot(crosswalk_across(piece));
            return (k - k.floor() < 0.5).then_some((CROSSWALK_PAINT, tag::ROAD_LINE));
        }
    }
    road_marking(piece, p)
}

/// The colour of a crosswalk's stripes (tagged [`tag::ROAD_LINE`]).
pub const CROSSWALK_PAINT: Vec3 = Vec3::splat(0.62);

/// The unit vector across a piece's road: a point `p` of its crosswalk is on a stripe where
/// `k = p · across` has `k − ⌊k⌋ < 0.5`.
#[inline]
pub fn crosswalk_across(piece: &PieceSurface) -> Vec2 {
    (piece.inner[1] - piece.inner[0]).normalize_or_zero().perp()
}

/// [`road_paint`] off the crosswalk: the lane marking at a road point, if any.
pub fn road_marking(piece: &PieceSurface, p: Vec2) -> Option<(Vec3, u8)> {
    if piece.marks == [Mark::None, Mark::None] {
        return None;
    }
    let edge = |a: Vec2, b: Vec2| {
        let d = b - a;
        let len2 = d.length_squared().max(1e-9);
        let t = ((p - a).dot(d) / len2).clamp(0.0, 1.0);
        ((a + d * t).distance(p), t)
    };
    for (k, (a, b)) in [(piece.inner[0], piece.inner[1]), (piece.outer[0], piece.outer[1])]
        .into_iter()
        .enumerate()
    {
        let mark = piece.marks[k];
        if mark == Mark::None {
            continue;
        }
        let half = if mark == Mark::Centre {
            MARK_WIDTH_M * 0.5
        } else {
            MARK_WIDTH_M
        };
        // Far outside the edge's bounding box grown by the mark's half width (a millimetre more than rounding
        // could take off the distance): farther than `half` from the edge, without working the distance out.
        let reach = half + 1e-3;
        if p.x < a.x.min(b.x) - reach
            || p.x > a.x.max(b.x) + reach
            || p.y < a.y.min(b.y) - reach
            || p.y > a.y.max(b.y) + reach
        {
            continue;
        }
        let (dist, t) = edge(a, b);
        if dist > half {
            continue;
        }
        let s = piece.s_m[0] + t * (piece.s_m[1] - piece.s_m[0]);
        match mark {
            Mark::Dashed if (s.rem_euclid(DASH_M.1)) > DASH_M.0 => continue,
            Mark::Centre => return Some((Vec3::new(0.75, 0.55, 0.08), tag::ROAD_LINE)),
            _ => return Some((Vec3::splat(0.7), tag::ROAD_LINE)),
        }
    }
    None
}

/// Even-odd point-in-polygon test.
pub fn point_in_polygon(poly: &[Vec2], p: Vec2) -> bool {
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

/// A capsule of a body in the frame: ends, radius (scene-relative).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneCapsule {
    /// One end.
    pub a: Vec3,
    /// Other end.
    pub b: Vec3,
    /// Radius, metres.
    pub radius_m: f32,
}

impl SceneCapsule {
    /// The outward unit normal at a surface point `p`.
    pub fn normal(&self, p: Vec3) -> Vec3 {
        let d = self.b - self.a;
        let t = ((p - self.a).dot(d) / d.length_squared().max(1e-12)).clamp(0.0, 1.0);
        (p - (self.a + d * t)).normalize_or(Vec3::Z)
    }
}

/// The dynamic part of a frame's scene (traffic and pedestrians); its primitive ids follow the static
/// scene's.
#[derive(Clone, Debug, Default)]
pub struct FrameScene {
    /// Triangles and primitives of the frame's agents.
    pub mesh: Mesh,
    /// Body capsules (for [`Material::Body`] normals).
    pub capsules: Vec<SceneCapsule>,
    /// Vehicle head lamps (position, forward axis), for lighting.
    pub head_lamps: Vec<(Vec3, Vec3)>,
}

/// Linear interpolation of two vehicle frames (the DVS's sub-frame renders).
fn lerp_vehicle(a: &VehicleFrame, b: &VehicleFrame, t: f64) -> (DVec3, f64) {
    lerp_pose(a.pos, a.yaw_rad, b.pos, b.yaw_rad, t)
}

/// Linear interpolation of two poses (position, yaw the short way round).
fn lerp_pose(a: DVec3, a_yaw: f64, b: DVec3, b_yaw: f64, t: f64) -> (DVec3, f64) {
    let dyaw = (b_yaw - a_yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    (a.lerp(b, t), a_yaw + dyaw * t)
}

/// Linear interpolation of two pedestrian frames (state and flags of the nearer one).
fn lerp_ped(a: &PedFrame, b: &PedFrame, t: f64) -> PedFrame {
    let wrap = |d: f64| (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    let mut out = if t < 0.5 { *a } else { *b };
    out.pos = a.pos.lerp(b.pos, t);
    out.yaw_rad = a.yaw_rad + wrap(b.yaw_rad - a.yaw_rad) * t;
    out.head_yaw_rad = a.head_yaw_rad + wrap(b.head_yaw_rad - a.head_yaw_rad) * t;
    out.velocity = a.velocity.lerp(b.velocity, t);
    let mut dp = b.gait_phase - a.gait_phase;
    dp -= dp.round();
    out.gait_phase = (a.gait_phase + dp * t).rem_euclid(1.0);
    if let (Some((ga, ta)), Some((gb, tb))) = (a.gesture, b.gesture)
        && ga == gb
    {
        out.gesture = Some((ga, ta + (tb - ta) * t));
    }
    out
}

/// A time within a clip: frame `frame` plus `alpha` ∈ [0, 1) of the way to the next frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneTime {
    /// Frame index.
    pub frame: u32,
    /// Fraction of a frame after it.
    pub alpha: f64,
}

impl SceneTime {
    /// Exactly at a frame.
    pub fn at(frame: u32) -> SceneTime {
        SceneTime { frame, alpha: 0.0 }
    }
}

/// Where the ego is at a time: ground position and yaw.
pub fn ego_at(trace: &ClipTrace, t: SceneTime) -> (DVec3, f64) {
    let f = t.frame as usize;
    let a = &trace.ego[f.min(trace.ego.len() - 1)];
    let b = &trace.ego[(f + 1).min(trace.ego.len() - 1)];
    lerp_vehicle(a, b, t.alpha)
}

const CAR_COLOURS: [[u8; 3]; 10] = [
    [235, 235, 232],
    [24, 24, 26],
    [168, 170, 174],
    [96, 98, 104],
    [150, 20, 24],
    [26, 52, 120],
    [30, 70, 48],
    [200, 190, 160],
    [70, 110, 160],
    [190, 120, 30],
];

/// Which colour of an identity each body capsule wears (see [`body::pose`]'s capsule order).
#[derive(Clone, Copy)]
enum Wear {
    Top,
    Bottom,
    Skin,
    Shoes,
    Head,
    Sleeve,
    Leg,
}

const WEAR: [Wear; CAPSULES] = [
    Wear::Top,    // torso
    Wear::Top,    // shoulders
    Wear::Head,   // head
    Wear::Top,    // upper arms
    Wear::Top,    //
    Wear::Sleeve, // forearms
    Wear::Sleeve, //
    Wear::Bottom, // thighs
    Wear::Bottom, //
    Wear::Leg,    // shins
    Wear::Leg,    //
    Wear::Shoes,  // feet
    Wear::Shoes,  //
    Wear::Skin,   // neck
];

impl FrameScene {
    /// The primitive of an id: the static scene's, or one of this frame's.
    #[inline]
    pub fn prim<'a>(&'a self, stat: &'a StaticScene, id: u32) -> &'a Prim {
        stat.prims
            .get(id as usize)
            .unwrap_or_else(|| &self.mesh.prims[id as usize - stat.prims.len()])
    }

    /// Builds the dynamic scene at time `t`.
    pub fn build(&mut self, stat: &StaticScene, script: &ClipScript, trace: &ClipTrace, t: SceneTime) {
        self.mesh.clear(stat.prims.len() as u32);
        self.capsules.clear();
        self.head_lamps.clear();
        let f0 = t.frame as usize;
        for (vi, frames) in trace.vehicles.iter().enumerate() {
            let Some(a) = frames.get(f0) else { continue };
            let b = frames.get(f0 + 1).unwrap_or(a);
            let (pos, yaw) = lerp_vehicle(a, b, t.alpha);
            let id = script.vehicles.get(vi).map_or(vi as u32, |v| v.id);
            let paint = stat.car_paint.get(vi).copied().unwrap_or(Vec3::splat(0.5));
            // An emergency vehicle's light bar flashes red and blue, alternating at 2 Hz.
            let flash = script.vehicles.get(vi).and_then(|v| v.emergency).map(|_| {
                let time_s = (f64::from(t.frame) + t.alpha) / f64::from(trace.fps.max(1));
                (time_s * 2.0).fract() < 0.5
            });
            self.push_vehicle(
                stat.rel(pos),
                yaw as f32,
                paint,
                VEHICLE_INSTANCE_BASE.saturating_add(id as u16),
                flash,
            );
        }
        // Traffic lights' lamps: red on top, amber, green at the bottom, the one of the frame's state lit.
        for g in stat.signal_heads.iter().filter_map(|&k| trace.signals.get(k)) {
            let Some(&state) = g.states.get(f0) else { continue };
            let head = stat.rel(g.position);
            let (s, c) = (g.facing_rad as f32).sin_cos();
            let face = head.truncate() + Vec2::new(c, s) * (SIGNAL_HOUSING_HALF_DEPTH_M + 0.01);
            for (k, lamp_state, colour) in [
                (1.0f32, LightState::Red, [255, 30, 20]),
                (0.0, LightState::Amber, [255, 170, 0]),
                (-1.0, LightState::Green, [40, 255, 90]),
            ] {
                // The lit lamp glows (by day too); the others are dark glass.
                let (material, albedo) = if state == lamp_state {
                    (Material::Beacon, linear(colour))
                } else {
                    (Material::Metal, linear(colour) * 0.08)
                };
                let lamp = Prim {
                    material,
                    tag: tag::TRAFFIC_LIGHT,
                    instance: 0,
                    albedo,
                    albedo2: albedo,
                    normal: Vec3::Z,
                    aux: 0,
                };
                let z = head.z + k * 0.28;
                self.mesh.upright_box(
                    face,
                    g.facing_rad as f32,
                    Vec2::new(0.02, SIGNAL_LAMP_HALF_M),
                    [z - SIGNAL_LAMP_HALF_M, z + SIGNAL_LAMP_HALF_M],
                    lamp,
                    lamp,
                );
            }
        }
        for (pi, frames) in trace.pedestrians.iter().enumerate() {
            let Some(a) = frames.get(f0) else { continue };
            let b = frames.get(f0 + 1).unwrap_or(a);
            let frame = if t.alpha > 0.0 { lerp_ped(a, b, t.alpha) } else { *a };
            let Some(ps) = script.pedestrians.get(pi) else { continue };
            let Some((outfit, child_outfit)) = stat.outfits.get(pi) else {
                continue;
            };
            let pose = body::pose(&frame, ps.identity.height_m, DVec3::ZERO);
            self.push_body(stat, &pose, outfit, pedestrian_instance(ps.id), tag::PEDESTRIAN);
            if let (Some(child), Some(child_outfit)) = (&ps.child, child_outfit) {
                let child_frame = PedFrame { gesture: None, ..frame };
                let pose = body::pose(&child_frame, child.height_m, CHILD_OFFSET_M);
                let inst = CHILD_INSTANCE_BASE.saturating_add(ps.id.min(16_383) as u16);
                self.push_body(stat, &pose, child_outfit, inst, tag::PEDESTRIAN);
            }
        }
        for (ci, frames) in trace.cyclists.iter().enumerate() {
            let (Some(a), Some(cs), Some((outfit, paint))) =
                (frames.get(f0), script.cyclists.get(ci), stat.riders.get(ci))
            else {
                continue;
            };
            let b = frames.get(f0 + 1).unwrap_or(a);
            let mut frame = *a;
            if t.alpha > 0.0 {
                let (pos, yaw) = lerp_pose(a.pos, a.yaw_rad, b.pos, b.yaw_rad, t.alpha);
                frame.pos = pos;
                frame.yaw_rad = yaw;
                frame.ridden_m = a.ridden_m + (b.ridden_m - a.ridden_m) * t.alpha;
                let mut dp = b.crank_phase - a.crank_phase;
                dp -= dp.round();
                frame.crank_phase = (a.crank_phase + dp * t.alpha).rem_euclid(1.0);
            }
            let instance = CYCLIST_INSTANCE_BASE.saturating_add(cs.id.min(16_383) as u16);
            let rider = cyclist::rider_pose(&frame, cs.rider.height_m);
            self.push_body(stat, &rider, outfit, instance, tag::RIDER);
            let tyre = linear([22, 22, 22]);
            let metal = linear([150, 150, 152]);
            let forward = {
                let (s, c) = (frame.yaw_rad as f32).sin_cos();
                Vec3::new(c, s, 0.0)
            };
            for (k, cap) in cyclist::bicycle(&frame, cs.rider.height_m).iter().enumerate() {
                // Frame tubes in the bicycle's colour; handlebar, saddle and cranks dark metal; wheels black.
                let albedo = match k {
                    0..=6 => *paint,
                    7 | 9 | 10 => metal * 0.4,
                    _ => tyre,
                };
                let sc = SceneCapsule {
                    a: stat.rel(cap.a),
                    b: stat.rel(cap.b),
                    radius_m: cap.radius_m as f32,
                };
                self.capsules.push(sc);
                let prim = self.mesh.prim(Prim {
                    material: Material::Body,
                    tag: tag::BICYCLE,
                    instance,
                    albedo,
                    albedo2: albedo,
                    normal: forward,
                    aux: (self.capsules.len() - 1) as u32,
                });
                self.mesh.capsule(&sc, prim);
            }
            // Lights (emissive at night): a white lamp under the handlebar, a red one under the saddle.
            let (sin, cos) = (frame.yaw_rad as f32).sin_cos();
            let fwd = Vec2::new(cos, sin);
            let centre = stat.rel(frame.pos);
            let hip_z = cyclist::hip_height_m(cs.rider.height_m) as f32;
            for (along, z, material, albedo) in [
                (0.43f32, hip_z - 0.12, Material::HeadLamp, linear([240, 240, 230])),
                (-0.36, hip_z - 0.16, Material::TailLamp, linear([200, 12, 12])),
            ] {
                let lamp = Prim {
                    material,
                    tag: tag::BICYCLE,
                    instance,
                    albedo,
                    albedo2: albedo,
                    normal: Vec3::Z,
                    aux: 0,
                };
                self.mesh.upright_box(
                    centre.truncate() + fwd * along,
                    frame.yaw_rad as f32,
                    Vec2::new(0.03, 0.035),
                    [centre.z + z - 0.035, centre.z + z + 0.035],
                    lamp,
                    lamp,
                );
            }
        }
    }

    /// Pushes a car; `light_bar`: an emergency vehicle's light bar on the roof, with its red half lit (`true`)
    /// or its blue half.
    fn push_vehicle(&mut self, pos: Vec3, yaw: f32, paint: Vec3, instance: u16, light_bar: Option<bool>) {
        let (l, w, h) = (VEHICLE_LENGTH_M as f32, VEHICLE_WIDTH_M as f32, VEHICLE_HEIGHT_M as f32);
        let (s, c) = yaw.sin_cos();
        let fwd = Vec2::new(c, s);
        let centre = pos.truncate();
        let base = pos.z;
        let car = |material, albedo| Prim {
            material,
            tag: tag::CAR,
            instance,
            albedo,
            albedo2: albedo,
            normal: Vec3::Z,
            aux: 0,
        };
        let body = car(Material::CarPaint, paint);
        let glass = car(Material::CarGlass, linear([14, 16, 20]));
        let tyre = car(Material::Tyre, linear([20, 20, 20]));
        // Lower body, cabin (glass sides, painted roof), four wheels.
        self.mesh.upright_box(
            centre,
            yaw,
            Vec2::new(l * 0.5, w * 0.5),
            [base + 0.3, base + 0.55 * h + 0.15],
            body,
            body,
        );
        self.mesh.upright_box(
            centre - fwd * (0.08 * l),
            yaw,
            Vec2::new(l * 0.26, w * 0.45),
            [base + 0.55 * h + 0.15, base + h],
            glass,
            body,
        );
        for (fx, sy) in [(0.32f32, 1.0f32), (0.32, -1.0), (-0.32, 1.0), (-0.32, -1.0)] {
            let wc = centre + fwd * (fx * l) + fwd.perp() * (sy * (w * 0.5 - 0.14));
            self.mesh
                .upright_box(wc, yaw, Vec2::new(0.33, 0.13), [base, base + 0.64], tyre, tyre);
        }
        // Lamps: small boxes standing just out of the front and rear faces.
        for (fx, mat, albedo) in [
            (0.5f32, Material::HeadLamp, linear([240, 240, 230])),
            (-0.5, Material::TailLamp, linear([160, 10, 10])),
        ] {
            for sy in [1.0f32, -1.0] {
                let lc = centre + fwd * (fx * l + fx.signum() * 0.01) + fwd.perp() * (sy * w * 0.33);
                self.mesh.upright_box(
                    lc,
                    yaw,
                    Vec2::new(0.03, 0.16),
                    [base + 0.6, base + 0.75],
                    car(mat, albedo),
                    car(mat, albedo),
                );
            }
        }
        if let Some(red_lit) = light_bar {
            let roof = centre - fwd * (0.08 * l);
            for (sy, lit, colour) in [(1.0f32, red_lit, [255, 20, 20]), (-1.0, !red_lit, [30, 60, 255])] {
                let albedo = if lit { linear(colour) } else { linear(colour) * 0.15 };
                let lamp = car(Material::Beacon, albedo);
                self.mesh.upright_box(
                    roof + fwd.perp() * (sy * 0.3),
                    yaw,
                    Vec2::new(0.12, 0.28),
                    [base + h, base + h + 0.14],
                    lamp,
                    lamp,
                );
            }
        }
        self.head_lamps.push((
            Vec3::new(centre.x + fwd.x * 0.5 * l, centre.y + fwd.y * 0.5 * l, base + 0.7),
            Vec3::new(fwd.x, fwd.y, -0.05).normalize(),
        ));
    }

    fn push_body(&mut self, stat: &StaticScene, pose: &body::BodyPose, outfit: &Outfit, instance: u16, tag: u8) {
        let forward = {
            let (s, c) = (pose.yaw_rad as f32).sin_cos();
            Vec3::new(c, s, 0.0)
        };
        for (cap, &(material, albedo)) in pose.capsules.iter().zip(&outfit.parts) {
            let sc = SceneCapsule {
                a: stat.rel(cap.a),
                b: stat.rel(cap.b),
                radius_m: cap.radius_m as f32,
            };
            self.capsules.push(sc);
            let prim = self.mesh.prim(Prim {
                material,
                tag,
                instance,
                albedo,
                albedo2: outfit.hair,
                normal: forward,
                aux: (self.capsules.len() - 1) as u32,
            });
            self.mesh.capsule(&sc, prim);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_in_polygon_handles_a_square() {
        let sq = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        assert!(point_in_polygon(&sq, Vec2::splat(0.5)));
        assert!(!point_in_polygon(&sq, Vec2::new(1.5, 0.5)));
    }

    #[test]
    fn actor_ids_undo_the_instance_numbering() {
        assert_eq!(actor_of_instance(0), None);
        assert_eq!(actor_of_instance(pedestrian_instance(7)), Some(7));
        assert_eq!(actor_of_instance(CHILD_INSTANCE_BASE + 7), Some(7));
        assert_eq!(actor_of_instance(VEHICLE_INSTANCE_BASE + 3), Some(3));
        assert_eq!(actor_of_instance(CYCLIST_INSTANCE_BASE + 2), Some(2));
    }

    #[test]
    fn capsule_normals_point_outwards() {
        let c = SceneCapsule {
            a: Vec3::ZERO,
            b: Vec3::Z,
            radius_m: 0.1,
        };
        assert!((c.normal(Vec3::new(0.1, 0.0, 0.5)) - Vec3::X).length() < 1e-6);
        assert!((c.normal(Vec3::new(0.0, 0.0, 1.1)) - Vec3::Z).length() < 1e-6);
    }
}
