//! The renderable scene of a clip: triangles with a primitive table (material, CARLA semantic tag, instance
//! id, albedo, normal), built from the town (once per clip) and from the trace (once per frame). One source for
//! every camera stream and, later, for LiDAR: what a camera draws is what a ray would hit.
//!
//! - Static part ([`StaticScene`]): the lane pieces near the ego's path (roads at their elevation, sidewalks
//!   raised by the world's curb, curb faces), a terrain plane, buildings (walls and roofs), trees, poles and
//!   street lamps (synthesised along sidewalks; towns and maps rarely carry them), street furniture and parked
//!   cars (per clip, [`clip_furniture`], [`clip_parked_cars`]). Lane markings and crosswalk
//!   stripes are not geometry: they are painted by the surface functions ([`road_paint`]) from the lane
//!   piece a road pixel belongs to, so the label streams and the image agree exactly.
//! - Dynamic part ([`FrameScene`]): traffic vehicles (body, cabin, wheels, lamps) and pedestrians (the
//!   capsules of [`super::body::pose`], the very body the keypoints come from) at a frame, or at a time between
//!   two frames for the DVS's sub-frame renders.
//!
//! Positions are `f32` metres relative to the clip's [`StaticScene::origin`] (a world point near the ego's
//! path), which keeps single precision at the millimetre over a town.

mod car;
mod frame;
mod furniture;
mod outfit;
mod paint;
mod parked;
mod recolour;
mod town;

use std::collections::BTreeMap;
use std::ops::Range;

use glam::{DVec2, DVec3, Vec2, Vec3};

use super::body::{self, CAPSULES, CHILD_OFFSET_M};
use super::cyclist;
use crate::plan::{ClipScript, EmergencyKind, Garment, HairStyle, Identity, Pattern};
use crate::sim::trace::{ClipTrace, LightState, PedFrame, VehicleFrame};
use crate::sim::{VEHICLE_HEIGHT_M, VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::util::mix::splitmix64;
use crate::world::{CURB_HEIGHT_M, LaneType, ObstacleKind, RoadNetwork, TravelDirection};

pub use car::*;
pub use frame::*;
pub use furniture::*;
pub use outfit::*;
pub use paint::*;
pub use parked::*;
pub use recolour::*;
pub use town::*;

/// The scenery placed per clip along the ego's path: street lamps ([`clip_lamp_posts`]), street furniture
/// ([`clip_furniture`]) and parked cars ([`clip_parked_cars`]). Computed once per clip and shared by the
/// occlusion labels (which test against it) and the sensors (which draw it: [`StaticScene::build`]), so both
/// see the same objects.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClipScenery {
    /// Street lamps along the sidewalks.
    pub lamp_posts: Vec<LampPost>,
    /// Bins, bollards, signs and bus shelters at the curbs.
    pub furniture: Vec<Furniture>,
    /// Parked cars along the curbs, by id (the `parked_cars` table's `parked_car`).
    pub parked_cars: Vec<ParkedCar>,
}

impl ClipScenery {
    /// The scenery of the clip `script` whose simulation gave `trace`.
    pub fn new(script: &ClipScript, trace: &ClipTrace, town: &RoadNetwork) -> ClipScenery {
        let lamp_posts = clip_lamp_posts(trace, town);
        let furniture = clip_furniture(trace, town, script.seed, &lamp_posts);
        let parked_cars = clip_parked_cars(script, trace, town, &lamp_posts, &furniture);
        ClipScenery {
            lamp_posts,
            furniture,
            parked_cars,
        }
    }
}

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
    /// Traffic signs' plates.
    pub const TRAFFIC_SIGN: u8 = 8;
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
    /// Street furniture that does not move (bins, bollards).
    pub const STATIC: u8 = 20;
    /// Things that move but are not annotated objects (CARLA: bags, buggies, animals): a pedestrian's umbrella.
    pub const DYNAMIC: u8 = 21;
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
/// [`CYCLIST_INSTANCE_BASE`]` + cyclist` for a cyclist, [`PARKED_INSTANCE_BASE`]` + car` for a parked car (its id
/// in the `parked_cars` table).
pub const CHILD_INSTANCE_BASE: u16 = 16_384;
/// See [`CHILD_INSTANCE_BASE`].
pub const VEHICLE_INSTANCE_BASE: u16 = 32_768;
/// [`CYCLIST_INSTANCE_BASE`]` + cyclist` for a cyclist (rider and bicycle; its id in the `cyclists` table; ids beyond
/// 8,191 share the last instance).
pub const CYCLIST_INSTANCE_BASE: u16 = 49_152;
/// [`PARKED_INSTANCE_BASE`]` + car` for a parked car (its id in the `parked_cars` table; ids beyond 8,191 share the
/// last instance).
pub const PARKED_INSTANCE_BASE: u16 = 57_344;

/// The instance id of parked car `id`.
pub fn parked_instance(id: u32) -> u16 {
    PARKED_INSTANCE_BASE.saturating_add(id.min(u32::from(u16::MAX - PARKED_INSTANCE_BASE)) as u16)
}

/// The instance id of pedestrian `id`.
pub fn pedestrian_instance(id: u32) -> u16 {
    (1 + id).min(u32::from(CHILD_INSTANCE_BASE) - 1) as u16
}

/// The actor an instance id belongs to, as the tables number it: the pedestrian id (for a pedestrian and the
/// child walking with it), the vehicle id, the cyclist id or the parked car's id; `None` for the static scene.
/// Undoes [`pedestrian_instance`], [`CHILD_INSTANCE_BASE`], [`VEHICLE_INSTANCE_BASE`], [`CYCLIST_INSTANCE_BASE`]
/// and [`parked_instance`].
pub fn actor_of_instance(instance: u16) -> Option<u32> {
    match instance {
        0 => None,
        i if i >= PARKED_INSTANCE_BASE => Some(u32::from(i - PARKED_INSTANCE_BASE)),
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
    /// A backlit poster (a bus shelter's): lit like any surface by day, and glowing in its colour at night.
    Poster,
    /// An umbrella's canopy (plain diffuse cloth; its two sides are separate primitives with their own normals).
    Fabric,
    /// Skin or clothing of a body part; `aux` holds the capsule's index in [`FrameScene::capsules`] (smooth
    /// normals) and the cloth's pattern ([`body_aux`]; its second colour is `albedo2`).
    Body,
    /// A head: skin in front, hair on top and at the back (`albedo2`); `aux` as for [`Material::Body`], with how
    /// the hair falls ([`HEAD_SHORT_HAIR`], [`HEAD_LONG_HAIR`]) in place of a pattern; `normal` is the gaze (level).
    Head,
}

/// A body primitive's `aux`: its capsule's index in [`FrameScene::capsules`] in the low 24 bits, and its cloth
/// pattern above them ([`PATTERN_PLAIN`], [`PATTERN_STRIPES`], [`PATTERN_CHECKS`]; the pattern's second colour is
/// the primitive's `albedo2`).
pub fn body_aux(capsule: usize, pattern: u32) -> u32 {
    (capsule as u32 & 0x00ff_ffff) | (pattern << 24)
}
/// The capsule index of a body primitive's `aux` ([`body_aux`]).
pub fn body_capsule(aux: u32) -> usize {
    (aux & 0x00ff_ffff) as usize
}
/// The cloth pattern of a body primitive's `aux` ([`body_aux`]).
pub fn body_pattern(aux: u32) -> u32 {
    aux >> 24
}
/// Plain cloth or skin.
pub const PATTERN_PLAIN: u32 = 0;
/// Horizontal stripes ([`crate::plan::Pattern::Stripes`]).
pub const PATTERN_STRIPES: u32 = 1;
/// Checks ([`crate::plan::Pattern::Checks`]).
pub const PATTERN_CHECKS: u32 = 2;
/// A head's `aux` pattern bits ([`body_aux`]) say how its hair falls: short ([`HEAD_SHORT_HAIR`]: crown, temples
/// and the back down to the nape, the ears bare; also buns and bald scalps) or long ([`HEAD_LONG_HAIR`]: over the
/// ears and the sides of the head too, framing the face).
pub const HEAD_SHORT_HAIR: u32 = 0;
/// See [`HEAD_SHORT_HAIR`].
pub const HEAD_LONG_HAIR: u32 = 1;

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
    /// Whether the triangle is part of a closed mesh wound counter-clockwise seen from outside (a capsule's):
    /// facing away from a camera, it is hidden behind the mesh's own front and the camera skips it.
    pub closed: bool,
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
            closed: false,
        });
        self.tris.push(Tri {
            v: [q[0], q[2], q[3]],
            prim,
            closed: false,
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

    /// Adds a canopy (an umbrella's): a low cone of `ribs` facets around `axis` (unit), its peak `peak_m` above
    /// `top` and its rim of `radius_m` `drop_m` below it along the axis. Each facet is two primitives of `cloth`
    /// with their own flat normals: the outer side, and an inner one 1.5 cm below it along the axis facing
    /// down (a camera below the canopy sees its inside, shaded as such).
    pub fn canopy(&mut self, top: Vec3, axis: Vec3, radius_m: f32, [peak_m, drop_m]: [f32; 2], cloth: Prim) {
        const RIBS: usize = 8;
        const INNER_M: f32 = 0.015;
        let u = axis.any_orthonormal_vector();
        let v = axis.cross(u);
        let peak = top + axis * peak_m;
        let rim = |k: usize| {
            let (s, c) = (k as f32 * std::f32::consts::TAU / RIBS as f32).sin_cos();
            top - axis * drop_m + (u * c + v * s) * radius_m
        };
        for k in 0..RIBS {
            let (a, b) = (rim(k), rim(k + 1));
            let mut n = (a - peak).cross(b - peak).normalize_or(axis);
            if n.dot(axis) < 0.0 {
                n = -n;
            }
            for (side, shift) in [(n, Vec3::ZERO), (-n, -axis * INNER_M)] {
                let prim = self.prim(Prim { normal: side, ..cloth });
                self.tris.push(Tri {
                    v: [peak + shift, a + shift, b + shift],
                    prim,
                    closed: false,
                });
            }
        }
    }

    /// Adds a capsule as a closed polyhedron (8 sides, two rings per cap) of one primitive.
    pub fn capsule(&mut self, c: &SceneCapsule, prim: u32) {
        const N: usize = 8;
        // Vertices sit slightly outside the surface so the polygon's silhouette matches the capsule's on average.
        let r = c.radius_m * crate::sensors::body::CAPSULE_MESH_SCALE;
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
            let closed = |v| Tri { v, prim, closed: true };
            self.tris.push(closed([poles[0], rings[0][k1], rings[0][k]]));
            self.tris.push(closed([poles[1], rings[3][k], rings[3][k1]]));
            for r2 in 0..3 {
                let (p, q) = (&rings[r2], &rings[r2 + 1]);
                self.tris.push(closed([p[k], p[k1], q[k1]]));
                self.tris.push(closed([p[k], q[k1], q[k]]));
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

/// Where the ego is at a time: ground position, yaw and body pitch.
pub fn ego_at(trace: &ClipTrace, t: SceneTime) -> (DVec3, f64, f64) {
    let f = t.frame as usize;
    let a = &trace.ego[f.min(trace.ego.len() - 1)];
    let b = &trace.ego[(f + 1).min(trace.ego.len() - 1)];
    let (pos, yaw_rad) = lerp_vehicle(a, b, t.alpha);
    (pos, yaw_rad, a.pitch_rad + (b.pitch_rad - a.pitch_rad) * t.alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A capsule's mesh is closed and wound counter-clockwise seen from outside (what lets the camera skip its
    /// far side): every triangle's normal points away from the axis, and its edges pair up (each edge used
    /// once in each direction); other meshes are not marked closed.
    #[test]
    fn capsule_meshes_are_closed_and_wound_outwards() {
        let mut mesh = Mesh::default();
        for (a, b, r) in [
            (Vec3::ZERO, Vec3::new(0.0, 0.0, 0.5), 0.05),
            (Vec3::new(1.0, 2.0, 0.3), Vec3::new(1.3, 1.8, 0.9), 0.11),
            (Vec3::new(-2.0, 0.5, 1.0), Vec3::new(-2.4, 0.5, 0.2), 0.08),
        ] {
            mesh.clear(0);
            mesh.capsule(&SceneCapsule { a, b, radius_m: r }, 7);
            let mut edges = std::collections::BTreeMap::new();
            for t in &mesh.tris {
                assert!(t.closed && t.prim == 7);
                let n = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]);
                let centroid = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
                // The nearest point of the axis segment.
                let d = b - a;
                let s = if d.length_squared() > 0.0 {
                    ((centroid - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                assert!(n.dot(centroid - (a + d * s)) > 0.0, "inward triangle {t:?}");
                for k in 0..3 {
                    let key = |p: Vec3| p.to_array().map(f32::to_bits);
                    *edges.entry((key(t.v[k]), key(t.v[(k + 1) % 3]))).or_insert(0) += 1;
                }
            }
            for (&(p, q), &n) in &edges {
                assert_eq!((n, edges.get(&(q, p))), (1, Some(&1)), "an open or doubled edge");
            }
        }
        mesh.clear(0);
        mesh.quad([Vec3::ZERO, Vec3::X, Vec3::ONE, Vec3::Y], 0);
        assert!(mesh.tris.iter().all(|t| !t.closed));
    }

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
        assert_eq!(actor_of_instance(parked_instance(5)), Some(5));
        // The last cyclist instance (ids are clamped to 8,191) is still a cyclist's, not a parked car's.
        assert_eq!(actor_of_instance(CYCLIST_INSTANCE_BASE + 8_191), Some(8_191));
        assert_eq!(parked_instance(u32::MAX), u16::MAX);
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
