//! The ray-cast LiDAR: CARLA's `sensor.lidar.ray_cast` (reference §2: the per-tick ray pattern, the sweep that
//! continues from tick to tick, general and intensity drop-off, atmospheric intensity, range noise) plus what
//! CARLA's semantic LiDAR adds (cosine of the incidence angle, semantic tag, instance), traced against the
//! scene the cameras render ([`super::scene`]): a pedestrian's points, pixels and box come from one geometry.
//!
//! Acceleration: a clip's static triangles are built once into two structures: the low ground-hugging ones
//! (roads, sidewalks, curbs, terrain, markings) into a 2D grid with heights per cell
//! ([`height_grid`]), the rest (buildings, trees, poles) into a parry3d BVH. The frame's agents (vehicles
//! and bodies, a few thousand triangles) go per tick into an angular index: groups of [`GROUP`] consecutive
//! triangles binned by the azimuth under which the sensor sees them. A ray is cast against the ground grid
//! up to the range, the structures up to the ground hit, then the agents up to the static hit.
//!
//! Frames: rays are generated in CARLA's sensor frame (x forward, y right, z up: left-handed, as CARLA writes
//! its points) and turned into the scene by the sensor's pose (x forward, y left, z up, right-handed) with y
//! negated. One tick per simulation frame, all rays of a tick cast from the sensor's pose at that frame (as
//! CARLA does).

use glam::{Affine3A, Vec3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::Ray;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::scene::{FrameScene, Prim, StaticScene, Tri};
use crate::spec::types::Lidar;
use crate::util::mix::splitmix64;
use height_grid::HeightGrid;

mod height_grid;

/// Triangles per group of the agents' index at most (consecutive triangles of one box or capsule lie
/// together; a group never mixes two agents).
pub const GROUP: usize = 8;

/// A triangle prepared for the Möller–Trumbore test.
#[derive(Clone, Copy, Debug)]
struct PreTri {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// Unit geometric normal.
    normal: Vec3,
    prim: u32,
}

impl PreTri {
    fn of(t: &Tri) -> PreTri {
        let (e1, e2) = (t.v[1] - t.v[0], t.v[2] - t.v[0]);
        PreTri {
            v0: t.v[0],
            e1,
            e2,
            normal: e1.cross(e2).normalize_or(Vec3::Z),
            prim: t.prim,
        }
    }

    /// Distance along the unit ray `o + t·d` to the triangle, if in (0, `max_t`).
    #[inline(always)]
    fn hit(&self, o: Vec3, d: Vec3, max_t: f32) -> Option<f32> {
        let p = d.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - self.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = d.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        (t > 1e-4 && t < max_t).then_some(t)
    }
}

/// A triangle's box, 1 mm larger on every side (flat boxes would make the slab test's `0 × ∞` a NaN).
fn tri_aabb(t: &PreTri) -> Aabb {
    let (a, b, c) = (t.v0, t.v0 + t.e1, t.v0 + t.e2);
    Aabb::new(a.min(b).min(c) - Vec3::splat(1e-3), a.max(b).max(c) + Vec3::splat(1e-3))
}

/// The first surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, metres.
    pub distance_m: f32,
    /// Primitive id (the static scene's, or the frame's after them: see [`FrameScene::prim`]).
    pub prim: u32,
    /// Unit geometric normal of the triangle hit.
    pub normal: Vec3,
}

/// Ground triangles (road, sidewalk, terrain, ground and marking tags) rise at most this much, metres: curbs
/// are, walls are not.
const GROUND_HEIGHT_M: f32 = 0.5;

/// Azimuth bins of the agents' angular index (0.5° each).
const AZIMUTH_BINS: usize = 720;

/// A group of [`GROUP`] consecutive agent triangles, with the cone of directions under which the sensor sees
/// it.
#[derive(Clone, Copy, Debug)]
struct AgentGroup {
    aabb: Aabb,
    /// The group's triangles: `agent_tris[first..end]`.
    first: u32,
    end: u32,
    /// Elevation interval in the sensor frame, radians.
    elevation: (f32, f32),
}

/// Ray casting against a clip's scene: the static triangles in a ground grid and a structures BVH (built once
/// per clip) and the agents' triangles in groups indexed by the direction under which the sensor sees them
/// (rebuilt per tick).
#[derive(Default)]
pub struct Tracer {
    /// Static triangles: the ground's (road, sidewalk, curb, terrain and marking surfaces no higher than
    /// [`GROUND_HEIGHT_M`]) first, then the rest.
    stat_tris: Vec<PreTri>,
    /// How many of `stat_tris` are ground.
    ground_count: usize,
    /// Grid of the ground triangles (index `i` is triangle `i`).
    ground: HeightGrid,
    /// BVH of the other static triangles (leaf `i` is triangle `ground_count + i`).
    structure_bvh: Option<Bvh>,
    agent_tris: Vec<PreTri>,
    groups: Vec<AgentGroup>,
    /// Sensor pose of the angular index (scene from sensor, right-handed).
    sensor: Affine3A,
    /// CSR of group ids by azimuth bin (sensor frame, CARLA's azimuth: 0 forward, positive to the right).
    bin_start: Vec<u32>,
    bin_groups: Vec<u32>,
    /// Scratch of the rebuild: (bin, group) pairs and a fill cursor per bin.
    scratch: Vec<(u32, u32)>,
    cursor: Vec<u32>,
}

impl std::fmt::Debug for Tracer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tracer")
            .field("static_triangles", &self.stat_tris.len())
            .field("agent_triangles", &self.agent_tris.len())
            .field("agent_groups", &self.groups.len())
            .finish()
    }
}

/// Azimuth bin of an azimuth in radians (any value).
#[inline]
fn azimuth_bin(azimuth_rad: f32) -> usize {
    let u = (azimuth_rad / std::f32::consts::TAU).rem_euclid(1.0);
    ((u * AZIMUTH_BINS as f32) as usize).min(AZIMUTH_BINS - 1)
}

/// The nearest hit among `tris` closer than `*max_t`, which it lowers; the index of the triangle.
#[inline]
fn nearest(tris: &[PreTri], first: usize, o: Vec3, d: Vec3, max_t: &mut f32) -> Option<usize> {
    let mut best = None;
    for (k, t) in tris.iter().enumerate() {
        if let Some(h) = t.hit(o, d, *max_t) {
            *max_t = h;
            best = Some(first + k);
        }
    }
    best
}

/// Entry distance of a ray into a box, if it enters before `max_t`.
#[inline]
fn slab(aabb: &Aabb, o: Vec3, inv_d: Vec3, max_t: f32) -> bool {
    let t1 = (aabb.mins - o) * inv_d;
    let t2 = (aabb.maxs - o) * inv_d;
    let near = t1.min(t2).max_element().max(0.0);
    let far = t1.max(t2).min_element().min(max_t);
    near <= far
}

impl Tracer {
    /// A tracer for a clip's static scene.
    pub fn new(stat: &StaticScene) -> Tracer {
        // Flat ground boxes and tall structures mixed in one tree would make every node tall and wide, so a
        // ray grazing the ground would enter most of them: the ground goes into a grid of its own.
        let is_ground = |t: &PreTri| {
            let tag = stat.prims.get(t.prim as usize).map_or(0, |p| p.tag);
            let z = [t.v0.z, t.v0.z + t.e1.z, t.v0.z + t.e2.z];
            z.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b)) - z.iter().fold(f32::INFINITY, |a, &b| a.min(b))
                <= GROUND_HEIGHT_M
                && matches!(
                    tag,
                    super::scene::tag::ROAD
                        | super::scene::tag::SIDEWALK
                        | super::scene::tag::TERRAIN
                        | super::scene::tag::GROUND
                        | super::scene::tag::ROAD_LINE
                )
        };
        let (mut stat_tris, structures): (Vec<PreTri>, Vec<PreTri>) =
            stat.tris.iter().map(PreTri::of).partition(is_ground);
        let ground_count = stat_tris.len();
        stat_tris.extend(structures);
        let leaves: Vec<Aabb> = stat_tris[ground_count..].iter().map(tri_aabb).collect();
        Tracer {
            ground: HeightGrid::new(&stat_tris[..ground_count]),
            structure_bvh: (!leaves.is_empty()).then(|| Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves)),
            stat_tris,
            ground_count,
            ..Tracer::default()
        }
    }

    /// Takes a frame's agents and indexes them for rays from a sensor at `scene_from_sensor`: each group of
    /// [`GROUP`] triangles goes into the azimuth bins its bounding sphere covers, with its elevation
    /// interval (both exact for the sphere, so conservative for the triangles).
    pub fn set_agents(&mut self, frame: &FrameScene, scene_from_sensor: &Affine3A) {
        self.agent_tris.clear();
        self.agent_tris.extend(frame.mesh.tris.iter().map(PreTri::of));
        self.sensor = *scene_from_sensor;
        let sensor_from_scene = scene_from_sensor.inverse();
        self.groups.clear();
        self.scratch.clear();
        // Groups of up to GROUP consecutive triangles of one agent (a group spanning two agents would have a
        // bounding sphere as large as the distance between them).
        let instance = |t: &PreTri| {
            t.prim
                .checked_sub(frame.mesh.base)
                .and_then(|i| frame.mesh.prims.get(i as usize))
                .map(|p| p.instance)
        };
        let mut first = 0;
        while first < self.agent_tris.len() {
            let who = instance(&self.agent_tris[first]);
            let mut end = first + 1;
            while end < self.agent_tris.len() && end - first < GROUP && instance(&self.agent_tris[end]) == who {
                end += 1;
            }
            let g = &self.agent_tris[first..end];
            let gi = self.groups.len();
            let (group_first, group_end) = (first as u32, end as u32);
            first = end;
            let aabb = g[1..].iter().fold(tri_aabb(&g[0]), |a, t| a.merged(&tri_aabb(t)));
            // Bounding sphere in the sensor frame, azimuth measured CARLA's way (y right).
            let c = sensor_from_scene.transform_point3(aabb.center());
            let r = aabb.half_extents().length();
            let (c, dist) = (Vec3::new(c.x, -c.y, c.z), c.length());
            let horizontal = c.truncate().length();
            let elevation = if dist <= r {
                (-std::f32::consts::FRAC_PI_2, std::f32::consts::FRAC_PI_2)
            } else {
                let e = c.z.atan2(horizontal);
                let a = (r / dist).asin();
                (e - a, e + a)
            };
            self.groups.push(AgentGroup {
                aabb,
                first: group_first,
                end: group_end,
                elevation,
            });
            let g = gi as u32;
            if horizontal <= r * 1.001 {
                self.scratch.extend((0..AZIMUTH_BINS as u32).map(|b| (b, g)));
            } else {
                let az = c.y.atan2(c.x);
                let half = (r / horizontal).asin();
                let (lo, hi) = (azimuth_bin(az - half), azimuth_bin(az + half));
                let mut b = lo;
                loop {
                    self.scratch.push((b as u32, g));
                    if b == hi {
                        break;
                    }
                    b = (b + 1) % AZIMUTH_BINS;
                }
            }
        }
        self.bin_start.clear();
        self.bin_start.resize(AZIMUTH_BINS + 1, 0);
        for &(b, _) in &self.scratch {
            self.bin_start[b as usize + 1] += 1;
        }
        for b in 0..AZIMUTH_BINS {
            self.bin_start[b + 1] += self.bin_start[b];
        }
        // Counting sort of the (bin, group) pairs into the bins, with a cursor per bin kept between ticks.
        self.bin_groups.clear();
        self.bin_groups.resize(self.scratch.len(), 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.bin_start);
        for &(b, g) in &self.scratch {
            self.bin_groups[self.cursor[b as usize] as usize] = g;
            self.cursor[b as usize] += 1;
        }
    }

    fn hit_of(tri: &PreTri, t: f32) -> Hit {
        Hit {
            distance_m: t,
            prim: tri.prim,
            normal: tri.normal,
        }
    }

    /// The first static surface along the unit ray within `max_m`. `hint` is a triangle the ray probably
    /// hits (the previous ray's, say), tested first to shorten the search; it is set to the triangle hit.
    pub fn cast_static(&self, o: Vec3, d: Vec3, max_m: f32, hint: &mut u32) -> Option<Hit> {
        let mut limit = max_m;
        let mut best = self
            .stat_tris
            .get(*hint as usize)
            .and_then(|t| t.hit(o, d, limit))
            .map(|t| {
                limit = t;
                *hint as usize
            });
        // The ground first: its hit bounds the structures' search.
        if let Some((i, t)) = self.ground.cast(&self.stat_tris[..self.ground_count], o, d, limit) {
            limit = t;
            best = Some(i);
        }
        if let Some(bvh) = &self.structure_bvh {
            let found = std::cell::Cell::new(usize::MAX);
            // The best distance so far bounds the search (slightly enlarged, so that an equal hit in the BVH
            // is its own nearest, deterministically).
            let offset = self.ground_count;
            if let Some((_, t)) = bvh.cast_ray(&Ray::new(o, d), limit * (1.0 + 1e-6) + 1e-6, |leaf, best_t| {
                let t = self.stat_tris[offset + leaf as usize].hit(o, d, best_t)?;
                found.set(offset + leaf as usize);
                Some(t)
            }) && t <= limit
            {
                limit = t;
                best = Some(found.get());
            }
        }
        let i = best?;
        *hint = i as u32;
        Some(Self::hit_of(&self.stat_tris[i], limit))
    }

    /// The first agent surface along the unit ray from any origin within `max_m` (a slab test per group).
    pub fn cast_agents(&self, o: Vec3, d: Vec3, max_m: f32) -> Option<Hit> {
        let inv = d.recip();
        let mut limit = max_m;
        let mut best = None;
        for g in &self.groups {
            if slab(&g.aabb, o, inv, limit) {
                let tris = &self.agent_tris[g.first as usize..g.end as usize];
                best = nearest(tris, g.first as usize, o, d, &mut limit).or(best);
            }
        }
        best.map(|i| Self::hit_of(&self.agent_tris[i], limit))
    }

    /// The first agent surface along a ray from the indexed sensor's origin, given the ray's sensor-frame
    /// elevation and azimuth bin, within `max_m`.
    #[inline]
    fn cast_agents_from_sensor(&self, d: Vec3, elevation_rad: f32, bin: usize, max_m: f32) -> Option<Hit> {
        let ids = &self.bin_groups[self.bin_start[bin] as usize..self.bin_start[bin + 1] as usize];
        if ids.is_empty() {
            return None;
        }
        let o: Vec3 = self.sensor.translation.into();
        let inv = d.recip();
        let mut limit = max_m;
        let mut best = None;
        for &gi in ids {
            let g = &self.groups[gi as usize];
            if elevation_rad < g.elevation.0 || elevation_rad > g.elevation.1 || !slab(&g.aabb, o, inv, limit) {
                continue;
            }
            let tris = &self.agent_tris[g.first as usize..g.end as usize];
            best = nearest(tris, g.first as usize, o, d, &mut limit).or(best);
        }
        best.map(|i| Self::hit_of(&self.agent_tris[i], limit))
    }

    /// The first surface along the unit ray within `max_m`.
    pub fn cast(&self, o: Vec3, d: Vec3, max_m: f32) -> Option<Hit> {
        let mut hint = u32::MAX;
        let stat = self.cast_static(o, d, max_m, &mut hint);
        let limit = stat.map_or(max_m, |h| h.distance_m);
        self.cast_agents(o, d, limit).or(stat)
    }
}

/// One LiDAR return, in CARLA's sensor frame (x forward, y right, z up, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LidarPoint {
    /// Forward, metres.
    pub x_m: f32,
    /// Right, metres.
    pub y_m: f32,
    /// Up, metres.
    pub z_m: f32,
    /// `exp(−attenuation × distance)`.
    pub intensity: f32,
    /// Cosine of the angle between the ray and the surface normal (CARLA's semantic LiDAR), in [0, 1].
    pub cos_incidence: f32,
    /// CARLA semantic tag of the surface.
    pub tag: u8,
    /// Instance id, as in the camera's instance stream (0: static scene).
    pub instance: u16,
}

/// The rays of one tick: `rays_per_channel` azimuths from `start_deg` in steps of `step_deg` (before
/// wrapping into the horizontal field of view).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickPattern {
    /// Azimuth of the first ray, degrees in [0, hfov), before the −hfov/2 shift.
    pub start_deg: f64,
    /// Azimuth step between rays, degrees.
    pub step_deg: f64,
    /// Rays per channel: `round(pps × dt / channels)`.
    pub rays_per_channel: u32,
}

impl TickPattern {
    /// The pattern of tick `tick` (one per frame at `fps`): CARLA's sweep, `rotation_hz × hfov × dt` degrees
    /// per tick, continuing where the previous tick ended.
    pub fn of(l: &Lidar, fps: u32, tick: u32) -> TickPattern {
        let dt = 1.0 / f64::from(fps.max(1));
        let channels = l.channels.max(1);
        let rays = (f64::from(l.points_per_second) * dt / f64::from(channels)).round() as u32;
        let sweep = l.rotation_hz * l.horizontal_fov_deg * dt;
        let hfov = l.horizontal_fov_deg.max(1e-9);
        TickPattern {
            start_deg: (f64::from(tick) * sweep).rem_euclid(hfov),
            step_deg: if rays > 0 { sweep / f64::from(rays) } else { 0.0 },
            rays_per_channel: rays,
        }
    }

    /// Azimuth of ray `j`, degrees in [−hfov/2, hfov/2) (CARLA: `fmod(θ₀ + j·step, hfov) − hfov/2`).
    pub fn azimuth_deg(&self, l: &Lidar, j: u32) -> f64 {
        (self.start_deg + f64::from(j) * self.step_deg).rem_euclid(l.horizontal_fov_deg.max(1e-9))
            - l.horizontal_fov_deg / 2.0
    }
}

/// Elevation of channel `i`, degrees: `upper − i (upper − lower) / (channels − 1)`.
pub fn channel_elevation_deg(l: &Lidar, i: u32) -> f64 {
    if l.channels <= 1 {
        return l.upper_fov_deg;
    }
    l.upper_fov_deg - f64::from(i) * (l.upper_fov_deg - l.lower_fov_deg) / f64::from(l.channels - 1)
}

/// What a tick did, for the tests of the drop-off model and the benchmark.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TickStats {
    /// Rays of the pattern (`rays_per_channel × channels`).
    pub rays: u64,
    /// Rays kept by the general drop-off and traced.
    pub traced: u64,
    /// Traced rays that hit a surface within range.
    pub hits: u64,
    /// Hits kept by the intensity drop-off (the points).
    pub kept: u64,
    /// Expected number of kept hits under the intensity drop-off model (sum of keep probabilities).
    pub expected_kept: f64,
    /// Variance of the number of kept hits under the model.
    pub kept_variance: f64,
}

impl std::ops::AddAssign for TickStats {
    fn add_assign(&mut self, o: TickStats) {
        self.rays += o.rays;
        self.traced += o.traced;
        self.hits += o.hits;
        self.kept += o.kept;
        self.expected_kept += o.expected_kept;
        self.kept_variance += o.kept_variance;
    }
}

/// The seed of a tick's channel (general drop-off, noise and intensity drop-off draws).
fn channel_seed(clip_seed: u64, tick: u32, channel: u32) -> u64 {
    splitmix64(clip_seed ^ 0x11da_5eed ^ splitmix64((u64::from(tick) << 20) | u64::from(channel)))
}

/// Probability that a return of `intensity` survives the intensity drop-off (reference §2).
pub fn keep_probability(l: &Lidar, intensity: f64) -> f64 {
    if intensity > l.dropoff_intensity_limit {
        1.0
    } else {
        let limit = l.dropoff_intensity_limit.max(1e-12);
        ((l.dropoff_zero_intensity / limit) * intensity + (1.0 - l.dropoff_zero_intensity)).clamp(0.0, 1.0)
    }
}

/// Scratch of a scan, reused from tick to tick.
#[derive(Clone, Debug, Default)]
pub struct ScanScratch {
    azimuth: Vec<(f32, f32, u32)>,
}

/// Casts one tick's rays from the sensor at `scene_from_sensor` (right-handed, scene-relative) and appends
/// the kept returns to `out`. `prim` maps a hit's primitive id to its primitive.
#[allow(clippy::too_many_arguments)]
pub fn scan<'p>(
    l: &Lidar,
    fps: u32,
    tick: u32,
    clip_seed: u64,
    scene_from_sensor: &Affine3A,
    tracer: &Tracer,
    prim: impl Fn(u32) -> &'p Prim,
    scratch: &mut ScanScratch,
    out: &mut Vec<LidarPoint>,
) -> TickStats {
    let pattern = TickPattern::of(l, fps, tick);
    let n = pattern.rays_per_channel;
    scratch.azimuth.clear();
    scratch.azimuth.extend((0..n).map(|j| {
        let h = pattern.azimuth_deg(l, j).to_radians();
        let (s, c) = h.sin_cos();
        (s as f32, c as f32, azimuth_bin(h as f32) as u32)
    }));
    let origin = scene_from_sensor.translation.into();
    let rot = scene_from_sensor.matrix3;
    let range = l.range_m as f32;
    let atten = l.atmosphere_attenuation_per_m as f32;
    let noise = l.noise_stddev_m as f32;
    let general = l.dropoff_general_rate as f32;
    let mut stats = TickStats {
        rays: u64::from(n) * u64::from(l.channels),
        ..TickStats::default()
    };
    debug_assert!(
        (Vec3::from(tracer.sensor.translation) - Vec3::from(scene_from_sensor.translation)).length() < 1e-4,
        "the tracer's agents are indexed for this sensor pose"
    );
    for ch in 0..l.channels {
        let elevation = channel_elevation_deg(l, ch).to_radians();
        let (sv, cv) = elevation.sin_cos();
        let (sv, cv, elevation) = (sv as f32, cv as f32, elevation as f32);
        let mut rng = ChaCha8Rng::seed_from_u64(channel_seed(clip_seed, tick, ch));
        let mut hint = u32::MAX;
        for &(sh, ch_, bin) in &scratch.azimuth {
            // CARLA draws the general drop-off before tracing.
            if rng.random::<f32>() < general {
                continue;
            }
            stats.traced += 1;
            // CARLA's sensor frame (y right) → right-handed sensor frame (y left) → scene.
            let carla = Vec3::new(cv * ch_, cv * sh, sv);
            let dir: Vec3 = rot * Vec3::new(carla.x, -carla.y, carla.z);
            let stat = tracer.cast_static(origin, dir, range, &mut hint);
            let limit = stat.map_or(range, |h| h.distance_m);
            let Some(hit) = tracer
                .cast_agents_from_sensor(dir, elevation, bin as usize, limit)
                .or(stat)
            else {
                continue;
            };
            stats.hits += 1;
            let intensity = (-atten * hit.distance_m).exp();
            let mut d = hit.distance_m;
            if noise > 0.0 {
                let z: f32 = StandardNormal.sample(&mut rng);
                d += z * noise;
            }
            let p = keep_probability(l, f64::from(intensity));
            stats.expected_kept += p;
            stats.kept_variance += p * (1.0 - p);
            if p < 1.0 && rng.random::<f64>() >= p {
                continue;
            }
            stats.kept += 1;
            let pr = prim(hit.prim);
            let point = carla * d;
            out.push(LidarPoint {
                x_m: point.x,
                y_m: point.y,
                z_m: point.z,
                intensity,
                cos_incidence: hit.normal.dot(dir).abs().min(1.0),
                tag: pr.tag,
                instance: pr.instance,
            });
        }
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keep_probability_is_continuous_at_the_limit() {
        let l = Lidar::default();
        assert!((keep_probability(&l, 0.0) - (1.0 - l.dropoff_zero_intensity)).abs() < 1e-12);
        assert!((keep_probability(&l, l.dropoff_intensity_limit) - 1.0).abs() < 1e-12);
        assert_eq!(keep_probability(&l, 0.95), 1.0);
    }

    #[test]
    fn the_paper_sensor_casts_521_rays_per_channel_per_frame_at_30_fps() {
        let l = Lidar::default();
        let p = TickPattern::of(&l, 30, 0);
        assert_eq!(p.rays_per_channel, 521, "round(1e6 / 30 / 64)");
        assert!(
            (p.step_deg * 521.0 - 240.0).abs() < 1e-9,
            "20 Hz × 360° / 30 FPS = 240° per tick"
        );
        assert!((TickPattern::of(&l, 30, 1).start_deg - 240.0).abs() < 1e-9);
        assert!((TickPattern::of(&l, 30, 2).start_deg - 120.0).abs() < 1e-9);
        assert!((channel_elevation_deg(&l, 0) - 15.0).abs() < 1e-12);
        assert!((channel_elevation_deg(&l, 63) + 25.0).abs() < 1e-12);
    }
}
