//! Street furniture: litter bins and rows of bollards at the curb of sidewalks outside junctions, drawn per clip
//! from its seed. [`clip_furniture`] is a pure function of the town, the clip's seed and its trace (nothing is
//! placed where a pedestrian of the clip walks: the simulation does not steer around furniture), so the
//! renderer draws, the LiDAR sees and the annotations test occlusion against the same boxes.

use glam::{DVec2, DVec3};

use super::{LAMP_CLEARANCE_M, LampPost, for_each_curb_station, scene_bounds};
use crate::sim::trace::ClipTrace;
use crate::util::mix::splitmix64;
use crate::world::RoadNetwork;

/// What a piece of furniture is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FurnitureKind {
    /// A litter bin (a box 0.44 m square and 0.9 m tall) in one of [`BIN_COLOURS`].
    Bin,
    /// A bollard (0.14 m square, 0.9 m tall, a light band near its top).
    Bollard,
}

/// One piece of street furniture: an upright, axis-aligned box standing on the sidewalk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Furniture {
    /// What it is.
    pub kind: FurnitureKind,
    /// Centre of its footprint, world plan view, metres.
    pub foot: DVec2,
    /// Height of the sidewalk at its foot, metres.
    pub base_z_m: f64,
    /// Half its extents along x and y (world axes) and half its height, metres.
    pub half_m: DVec3,
    /// Its colour, sRGB (bins vary per piece; bollards are dark grey).
    pub rgb: [u8; 3],
}

impl Furniture {
    /// The centre of its box, world metres.
    pub fn centre(&self) -> DVec3 {
        self.foot.extend(self.base_z_m + self.half_m.z)
    }
}

/// Distance between candidate places for furniture along a sidewalk, metres.
const SPACING_M: f64 = 9.0;
/// Share of candidate places with a bin, and with a row of bollards.
const BIN_SHARE: f64 = 0.16;
const BOLLARD_SHARE: f64 = 0.10;
/// Bollards in a row, and their spacing along the curb, metres.
const BOLLARDS_IN_ROW: usize = 3;
const BOLLARD_SPACING_M: f64 = 1.5;
/// How far from the curb furniture stands (its centre), metres.
const FROM_CURB_M: f64 = 0.4;
/// Bin colours (sRGB): dark green, black, municipal grey, blue, red-brown.
pub const BIN_COLOURS: [[u8; 3]; 5] = [[34, 64, 40], [26, 26, 28], [98, 102, 104], [30, 56, 110], [96, 40, 30]];

/// The street furniture of a clip: candidate places every [`SPACING_M`] along each sidewalk outside junctions
/// within [`scene_bounds`], each holding a bin or a row of bollards with the shares above (drawn from the clip's
/// seed, the lane and the place), leaving out any piece within 1.5 m of a lamp post or within
/// [`LAMP_CLEARANCE_M`] (plus its half width) of a pedestrian of the clip in any frame.
pub fn clip_furniture(trace: &ClipTrace, town: &RoadNetwork, clip_seed: u64, lamps: &[LampPost]) -> Vec<Furniture> {
    let (lo, hi) = scene_bounds(trace);
    let near = |p: DVec2| p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y;
    let mut out = Vec::new();
    for_each_curb_station(town, SPACING_M, |s| {
        let foot = s.inner - s.to_road * FROM_CURB_M;
        if s.width_m < 1.5 || !near(foot) {
            return;
        }
        let h = splitmix64(clip_seed ^ 0xf00d_5eed ^ splitmix64(((s.lane as u64) << 24) | s.place));
        let u = (h >> 11) as f64 / (1u64 << 53) as f64;
        if u < BIN_SHARE {
            out.push(Furniture {
                kind: FurnitureKind::Bin,
                foot,
                base_z_m: s.z_m,
                half_m: DVec3::new(0.22, 0.22, 0.45),
                rgb: BIN_COLOURS[(splitmix64(h) % BIN_COLOURS.len() as u64) as usize],
            });
        } else if u < BIN_SHARE + BOLLARD_SHARE {
            let mid = (BOLLARDS_IN_ROW as f64 - 1.0) * 0.5;
            out.extend((0..BOLLARDS_IN_ROW).map(|k| Furniture {
                kind: FurnitureKind::Bollard,
                foot: foot + s.along * ((k as f64 - mid) * BOLLARD_SPACING_M),
                base_z_m: s.z_m,
                half_m: DVec3::new(0.07, 0.07, 0.45),
                rgb: [44, 46, 50],
            }));
        }
    });
    out.retain(|f| {
        let reach = LAMP_CLEARANCE_M + f.half_m.x.max(f.half_m.y);
        lamps.iter().all(|l| l.foot.distance_squared(f.foot) > 1.5 * 1.5)
            && trace
                .pedestrians
                .iter()
                .flatten()
                .all(|p| p.pos.truncate().distance_squared(f.foot) > reach * reach)
    });
    out
}
