//! Road paint as a function of the lane piece a road point lies on: lane markings and crosswalk stripes are not
//! geometry, so the label streams and the image agree exactly.

use super::*;

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
