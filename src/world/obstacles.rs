//! Static obstacles (building blocks, poles, trees): a parry3d BVH over their bounding boxes with an exact
//! ray/oriented-box test at the leaves, for occlusion and sensor rays. Also synthesises building blocks
//! beside the sidewalks of imported maps, which carry no buildings (CARLA keeps them in its Unreal assets).

use glam::{DVec2, DVec3, Vec3};
use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::Ray;

use crate::world::{LaneType, Obstacle, ObstacleKind, RoadNetwork};

#[derive(Clone, Default)]
pub(crate) struct ObstacleIndex {
    bvh: Option<Bvh>,
}

impl std::fmt::Debug for ObstacleIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObstacleIndex")
            .field("leaves", &self.bvh.as_ref().map_or(0, |b| b.leaf_count()))
            .finish()
    }
}

fn aabb(o: &Obstacle) -> Aabb {
    let (lo, hi) = o.footprint_box();
    Aabb::new(
        Vec3::new(lo.x as f32 - 0.01, lo.y as f32 - 0.01, o.base_z_m as f32 - 0.01),
        Vec3::new(
            hi.x as f32 + 0.01,
            hi.y as f32 + 0.01,
            (o.base_z_m + o.height_m) as f32 + 0.01,
        ),
    )
}

/// Entry distance of the ray `from + t·dir` (|dir| = 1) into the box, if it enters within `max_t`.
fn ray_obb(o: &Obstacle, from: DVec3, dir: DVec3, max_t: f64) -> Option<f64> {
    let (s, c) = o.heading_rad.sin_cos();
    let ax = DVec2::new(c, s);
    let ay = DVec2::new(-s, c);
    let rel = from.truncate() - o.centre;
    let o3 = [rel.dot(ax), rel.dot(ay), from.z - (o.base_z_m + 0.5 * o.height_m)];
    let d3 = [dir.truncate().dot(ax), dir.truncate().dot(ay), dir.z];
    let h3 = [o.half_extents_m.x, o.half_extents_m.y, 0.5 * o.height_m];
    let (mut t0, mut t1) = (0.0f64, max_t);
    for k in 0..3 {
        if d3[k].abs() < 1e-12 {
            if o3[k].abs() > h3[k] {
                return None;
            }
        } else {
            let inv = 1.0 / d3[k];
            let (mut a, mut b) = ((-h3[k] - o3[k]) * inv, (h3[k] - o3[k]) * inv);
            if a > b {
                std::mem::swap(&mut a, &mut b);
            }
            t0 = t0.max(a);
            t1 = t1.min(b);
            if t0 > t1 {
                return None;
            }
        }
    }
    Some(t0)
}

impl ObstacleIndex {
    pub(crate) fn build(obstacles: &[Obstacle]) -> ObstacleIndex {
        if obstacles.is_empty() {
            return ObstacleIndex { bvh: None };
        }
        let leaves: Vec<Aabb> = obstacles.iter().map(aabb).collect();
        ObstacleIndex {
            bvh: Some(Bvh::from_leaves(BvhBuildStrategy::default(), &leaves)),
        }
    }

    pub(crate) fn first_hit(&self, obstacles: &[Obstacle], from: DVec3, to: DVec3) -> Option<f64> {
        let bvh = self.bvh.as_ref()?;
        let d = to - from;
        let len = d.length();
        if len.is_nan() || len <= 1e-9 || !len.is_finite() {
            return None;
        }
        let dir = d / len;
        let ray = Ray::new(from.as_vec3(), dir.as_vec3());
        bvh.cast_ray(&ray, len as f32, |leaf, best| {
            ray_obb(&obstacles[leaf as usize], from, dir, (best as f64).min(len)).map(|t| t as f32)
        })
        .map(|(_, t)| t as f64)
    }
}

/// Building blocks beside the sidewalks of a network that has none: for each ~22 m chunk of each sidewalk
/// outside junctions, a box 1.5 m behind the sidewalk's outer border, 12 m deep, kept only if no part of it
/// lies on any lane and it does not overlap a previous box. Deterministic.
pub(crate) fn synthesize_buildings(net: &RoadNetwork) -> Vec<Obstacle> {
    let mut out: Vec<Obstacle> = Vec::new();
    let mut boxes: Vec<(DVec2, DVec2)> = Vec::new();
    for (li, lane) in net.lanes.iter().enumerate() {
        if lane.lane_type != LaneType::Sidewalk || lane.in_junction || lane.length_m < 12.0 {
            continue;
        }
        let pieces = &net.pieces[lane.pieces.start as usize..lane.pieces.end as usize];
        let mut start = 0;
        while start < pieces.len() {
            let mut end = start;
            let mut len = 0.0;
            while end < pieces.len() && len < 22.0 {
                let c = pieces[end].centre();
                len += (c[1] - c[0]).length();
                end += 1;
            }
            let chunk = &pieces[start..end];
            start = end;
            if len < 10.0 {
                continue;
            }
            let a = chunk[0].corners[3];
            let b = chunk[chunk.len() - 1].corners[2];
            let (first, last) = (&chunk[0], &chunk[chunk.len() - 1]);
            let n0 = (first.corners[3] - first.corners[0]).normalize_or_zero();
            let n1 = (last.corners[2] - last.corners[1]).normalize_or_zero();
            if n0.dot(n1) < 0.95 || n0 == DVec2::ZERO {
                continue;
            }
            let n = (n0 + n1).normalize();
            let along = b - a;
            let along_len = along.length();
            if along_len < 8.0 {
                continue;
            }
            let depth = 12.0;
            let h = crate::util::mix::splitmix64((li as u64) << 20 | start as u64);
            let height = 8.0 + (h % 23) as f64;
            let o = Obstacle {
                kind: ObstacleKind::Building,
                centre: (a + b) * 0.5 + n * (1.5 + 0.5 * depth),
                half_extents_m: DVec2::new(0.5 * (along_len - 2.0), 0.5 * depth),
                heading_rad: along.y.atan2(along.x),
                base_z_m: first.z_m as f64,
                height_m: height,
            };
            let (lo, hi) = o.footprint_box();
            if boxes
                .iter()
                .any(|(l, h)| l.x < hi.x && h.x > lo.x && l.y < hi.y && h.y > lo.y)
            {
                continue;
            }
            let mut clear = true;
            'probe: for i in 0..=6 {
                for j in 0..=4 {
                    let u = (i as f64 / 6.0) * 2.0 - 1.0;
                    let v = (j as f64 / 4.0) * 2.0 - 1.0;
                    let (sn, cs) = o.heading_rad.sin_cos();
                    let q = o.centre
                        + DVec2::new(cs, sn) * (u * o.half_extents_m.x)
                        + DVec2::new(-sn, cs) * (v * o.half_extents_m.y);
                    if net.lane_at(q).is_some() {
                        clear = false;
                        break 'probe;
                    }
                }
            }
            if clear {
                boxes.push((lo, hi));
                out.push(o);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_box() {
        let o = Obstacle {
            kind: ObstacleKind::Building,
            centre: DVec2::new(10.0, 0.0),
            half_extents_m: DVec2::new(2.0, 2.0),
            heading_rad: 0.3,
            base_z_m: 0.0,
            height_m: 10.0,
        };
        let idx = ObstacleIndex::build(&[o]);
        let hit = idx
            .first_hit(&[o], DVec3::new(0.0, 0.0, 1.0), DVec3::new(20.0, 0.0, 1.0))
            .unwrap();
        assert!(hit > 7.0 && hit < 8.5, "{hit}");
        assert!(
            idx.first_hit(&[o], DVec3::new(0.0, 0.0, 11.0), DVec3::new(20.0, 0.0, 11.0))
                .is_none()
        );
        assert!(
            idx.first_hit(&[o], DVec3::new(0.0, 5.0, 1.0), DVec3::new(20.0, 5.0, 1.0))
                .is_none()
        );
        assert!(
            idx.first_hit(&[o], DVec3::new(0.0, 0.0, 1.0), DVec3::new(5.0, 0.0, 1.0))
                .is_none()
        );
    }
}
