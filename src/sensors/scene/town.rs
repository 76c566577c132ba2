//! The static part of a clip's scene ([`StaticScene`]), built once per clip: the lane pieces near the ego's path
//! in culling clusters (roads at their elevation, sidewalks raised by the curb, curb faces), a terrain plane,
//! buildings, trees, poles, street lamps (synthesised along sidewalks) and traffic lights, each pedestrian's
//! [`Outfit`] ([`Outfit::of`]) and each car's paint.

use super::*;

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
pub(super) const LAMP_SPACING_M: f64 = 30.0;

/// How far around the ego's path the town is included, metres.
pub(super) const SCENE_MARGIN_M: f64 = 160.0;

/// Width of a lane marking, metres.
pub const MARK_WIDTH_M: f32 = 0.15;

/// Dashes: painted length and period along the road, metres.
pub(super) const DASH_M: (f32, f32) = (3.0, 9.0);

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
    /// Factor on the procedural textures' contrast (the clip's `look`; 1 without domain randomisation).
    pub texture_contrast: f32,
}

/// An sRGB colour (0–255) in linear RGB.
pub fn linear(c: [u8; 3]) -> Vec3 {
    let f = |v: u8| crate::util::srgb::decode(f32::from(v) / 255.0);
    Vec3::new(f(c[0]), f(c[1]), f(c[2]))
}

/// The markings of each lane's inner and outer border.
pub(super) fn lane_marks(town: &RoadNetwork) -> Vec<[Mark; 2]> {
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

impl LampPost {
    /// The box of its pole as the renderer draws it: centre and half extents, world metres (the arm and the light
    /// are above any line of sight to a pedestrian).
    pub fn pole_box(&self) -> (DVec3, DVec3) {
        let half = f64::from(LAMP_POLE_HALF_WIDTH_M);
        let height_m = f64::from(LAMP_HEIGHT_M + LAMP_POLE_ABOVE_LIGHT_M);
        (
            self.foot.extend(self.base_z_m + height_m * 0.5),
            DVec3::new(half, half, height_m * 0.5),
        )
    }
}

/// Half the width of a (square) lamp pole, metres.
pub const LAMP_POLE_HALF_WIDTH_M: f32 = 0.07;

/// How far the pole rises above the light, metres.
pub const LAMP_POLE_ABOVE_LIGHT_M: f32 = 0.2;

/// A place at the curb of a sidewalk, where street lamps and street furniture stand.
#[derive(Clone, Copy, Debug)]
pub(super) struct CurbStation {
    /// The sidewalk lane (index into the town's lanes).
    pub lane: usize,
    /// The place's number along its lane, from 1.
    pub place: u64,
    /// The sidewalk's inner (road-side) edge there, world plan view, metres.
    pub inner: DVec2,
    /// Unit direction toward the road.
    pub to_road: DVec2,
    /// Unit direction along the sidewalk.
    pub along: DVec2,
    /// The sidewalk's width there, metres.
    pub width_m: f64,
    /// The sidewalk's height there, metres.
    pub z_m: f64,
}

/// Calls `f` at places every `spacing_m` along each sidewalk outside junctions, the first half a spacing from
/// the sidewalk's start (a pure function of the town).
pub(super) fn for_each_curb_station(town: &RoadNetwork, spacing_m: f64, mut f: impl FnMut(CurbStation)) {
    for (lane_idx, lane) in town.lanes.iter().enumerate() {
        if lane.lane_type != LaneType::Sidewalk || lane.in_junction {
            continue;
        }
        let (mut next_m, mut along, mut place) = (spacing_m * 0.5, 0.0, 0);
        for piece in &town.pieces[lane.pieces.start as usize..lane.pieces.end as usize] {
            let [c0, c1] = piece.centre();
            let len = c0.distance(c1);
            while along + len >= next_m && len > 1e-6 {
                let t = (next_m - along) / len;
                let inner = piece.corners[0].lerp(piece.corners[1], t);
                next_m += spacing_m;
                place += 1;
                f(CurbStation {
                    lane: lane_idx,
                    place,
                    inner,
                    to_road: (inner - c0.lerp(c1, t)).normalize_or_zero(),
                    along: (c1 - c0) / len,
                    width_m: f64::from(piece.width_m[0]),
                    z_m: f64::from(piece.z_m),
                });
            }
            along += len;
        }
    }
}

/// The street lamps of `town` whose foot satisfies `near`: one every [`LAMP_SPACING_M`] along each sidewalk
/// outside junctions, at the curb (a pure function of the town, so the renderer draws and the annotations
/// test occlusion against the same poles).
pub fn street_lamp_posts(town: &RoadNetwork, near: impl Fn(DVec2) -> bool) -> Vec<LampPost> {
    let mut posts = Vec::new();
    for_each_curb_station(town, LAMP_SPACING_M, |s| {
        let foot = s.inner - s.to_road * (0.35f64).min(0.4 * s.width_m);
        if near(foot) && s.width_m >= 1.0 {
            posts.push(LampPost {
                foot,
                base_z_m: s.z_m,
                to_road: s.to_road,
            });
        }
    });
    posts
}

/// Clearance between a lamp pole and the path of any pedestrian of the clip (the body's radius, a child
/// walking beside it, the pole), metres.
pub(super) const LAMP_CLEARANCE_M: f64 = 1.0;

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
pub(super) const SIGNAL_POST_HALF_WIDTH_M: f32 = 0.06;

/// Half the height of a traffic light's housing (three lamps above each other), metres.
pub const SIGNAL_HOUSING_HALF_HEIGHT_M: f32 = 0.45;

/// Half the width of a traffic light's housing, metres.
pub const SIGNAL_HOUSING_HALF_WIDTH_M: f32 = 0.17;

/// Half the depth of a traffic light's housing (along its facing), metres.
pub const SIGNAL_HOUSING_HALF_DEPTH_M: f32 = 0.12;

/// Half the side of a traffic light's lamp, metres.
pub(super) const SIGNAL_LAMP_HALF_M: f32 = 0.11;

/// `p` relative to the scene origin, f32.
pub(super) fn stat_rel(origin: DVec3, p: DVec3) -> Vec3 {
    (p - origin).as_vec3()
}

impl StaticScene {
    /// Builds the static scene of a clip: the town within [`SCENE_MARGIN_M`] of the ego's path, with the clip's
    /// `scenery` ([`ClipScenery::new`] of the same clip; the annotations carry it).
    pub fn build(script: &ClipScript, trace: &ClipTrace, town: &RoadNetwork, scenery: &ClipScenery) -> StaticScene {
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
        const SHOP_SIGNS: [[u8; 3]; 8] = [
            [160, 30, 34],
            [24, 70, 140],
            [30, 110, 60],
            [220, 180, 40],
            [30, 30, 32],
            [230, 230, 224],
            [200, 90, 30],
            [110, 40, 110],
        ];
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
                    let mut wall = flat(Material::Wall, tag::BUILDING, colour, Vec3::Z, i as u32);
                    // Two buildings in five have shops on the ground floor: display windows under a sign band
                    // in the second colour (the shader draws them).
                    if (h >> 24) % 5 < 2 {
                        wall.albedo2 = linear(SHOP_SIGNS[((h >> 32) % SHOP_SIGNS.len() as u64) as usize]);
                    }
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
        for post in &scenery.lamp_posts {
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

        // Street furniture (bins, rows of bollards, signs, bus shelters) at the curb, per clip.
        for item in &scenery.furniture {
            let c = (item.foot - origin.truncate()).as_vec2();
            let half = item.half_m.truncate().as_vec2();
            let base = (item.base_z_m - origin.z) as f32;
            let top = base + 2.0 * item.half_m.z as f32;
            let body = flat(Material::Metal, item.kind.semantic_tag(), linear(item.rgb), Vec3::Z, 0);
            match item.kind {
                FurnitureKind::Bin => {
                    let lid = flat(Material::Metal, tag::STATIC, linear(item.rgb) * 0.6, Vec3::Z, 0);
                    b.mesh.upright_box(c, 0.0, half, [base, top], body, lid);
                }
                FurnitureKind::SignPost | FurnitureKind::SignPlate | FurnitureKind::ShelterFrame => {
                    b.mesh.upright_box(c, 0.0, half, [base, top], body, body);
                }
                FurnitureKind::ShelterPoster => {
                    let poster = flat(Material::Poster, item.kind.semantic_tag(), linear(item.rgb), Vec3::Z, 0);
                    b.mesh.upright_box(c, 0.0, half, [base, top], poster, poster);
                }
                FurnitureKind::ShelterGlass => {
                    let glass = flat(
                        Material::CarGlass,
                        item.kind.semantic_tag(),
                        linear(item.rgb),
                        Vec3::Z,
                        0,
                    );
                    b.mesh.upright_box(c, 0.0, half, [base, top], glass, glass);
                }
                FurnitureKind::Bollard => {
                    // Dark, with a light reflective band 0.1 m below its top.
                    let band = flat(Material::Metal, tag::STATIC, linear([200, 200, 196]), Vec3::Z, 0);
                    b.mesh.upright_box(c, 0.0, half, [base, top - 0.2], body, body);
                    b.mesh.upright_box(c, 0.0, half, [top - 0.2, top - 0.1], band, band);
                    b.mesh.upright_box(c, 0.0, half, [top - 0.1, top], body, body);
                }
            }
            close_cluster(&b, &mut clusters, &mut cluster_start);
        }

        // Parked cars along the curbs, per clip, their lamps dark.
        for (id, car) in scenery.parked_cars.iter().enumerate() {
            let (paint, instance) = (linear(car.rgb), parked_instance(id as u32));
            b.mesh.car(
                stat_rel(origin, car.centre),
                car.yaw_rad as f32,
                paint,
                instance,
                CarLamps::Off,
            );
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

        let mut scene = StaticScene {
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
            texture_contrast: script.look.texture_contrast as f32,
        };
        if let Some(colours) = SceneryColours::of(&script.look) {
            colours.apply(&mut scene.prims, &mut scene.car_paint);
        }
        scene
    }

    /// The scene-relative position of a world point.
    pub fn rel(&self, p: DVec3) -> Vec3 {
        (p - self.origin).as_vec3()
    }
}
