//! Street furniture: litter bins, rows of bollards, traffic signs and bus shelters at the curb of sidewalks outside
//! junctions, drawn per clip from its seed. [`clip_furniture`] is a pure function of the town, the clip's seed and its trace
//! (nothing is placed where a pedestrian of the clip walks: the simulation does not steer around furniture), so
//! the renderer draws, the LiDAR sees and the annotations test occlusion against the same boxes.

use glam::{DVec2, DVec3};

use super::{LAMP_CLEARANCE_M, LampPost, for_each_curb_station, scene_bounds, tag};
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
    /// A traffic sign's post (7 cm square, 2.4 m tall; semantic `Pole`).
    SignPost,
    /// A traffic sign's plate (0.6 m square, 4 cm thick, facing along the road, its bottom 1.8 m above the
    /// sidewalk; semantic `TrafficSign`) in one of [`SIGN_COLOURS`], on a face of the post before it in the list.
    SignPlate,
    /// A bus shelter's frame: its roof, front posts and bench (grey metal; semantic `Static`).
    ShelterFrame,
    /// A bus shelter's back wall of tinted glass, along the road (semantic `Static`; opaque to cameras, LiDAR and
    /// the occlusion labels alike).
    ShelterGlass,
    /// The poster at one end of a bus shelter, in one of [`POSTER_COLOURS`], backlit at night (semantic `Static`).
    ShelterPoster,
}

impl FurnitureKind {
    /// CARLA's semantic tag of its pixels (a bin's lid and a bollard's band are tagged alike).
    pub fn semantic_tag(self) -> u8 {
        match self {
            FurnitureKind::Bin
            | FurnitureKind::Bollard
            | FurnitureKind::ShelterFrame
            | FurnitureKind::ShelterGlass
            | FurnitureKind::ShelterPoster => tag::STATIC,
            FurnitureKind::SignPost => tag::POLE,
            FurnitureKind::SignPlate => tag::TRAFFIC_SIGN,
        }
    }
}

/// One piece of street furniture: an upright, axis-aligned box standing on the sidewalk (a sign's plate too: on a
/// diagonal street it faces along the world axis nearer the street's direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Furniture {
    /// What it is.
    pub kind: FurnitureKind,
    /// Centre of its footprint, world plan view, metres.
    pub foot: DVec2,
    /// Height of its bottom: the sidewalk's at its foot (a sign's plate: 1.8 m above it), metres.
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
/// Share of candidate places with a traffic sign (drawn after the bins' and bollards' shares, so that adding signs
/// left those where they were).
const SIGN_SHARE: f64 = 0.07;
/// A sign's post height, and its plate's half side and height of its bottom above the sidewalk, metres.
const SIGN_POST_M: f64 = 2.4;
const SIGN_POST_HALF_M: f64 = 0.035;
const SIGN_PLATE_HALF_M: f64 = 0.3;
const SIGN_PLATE_BOTTOM_M: f64 = 1.8;
/// Sign plate colours (sRGB): information blue, prohibition red, warning yellow, white.
pub const SIGN_COLOURS: [[u8; 3]; 4] = [[28, 74, 160], [182, 30, 32], [236, 190, 34], [226, 226, 220]];
/// Share of candidate places with a bus shelter (drawn after the signs' share), where the sidewalk is at least
/// [`SHELTER_MIN_SIDEWALK_M`] wide.
const SHELTER_SHARE: f64 = 0.04;
const SHELTER_MIN_SIDEWALK_M: f64 = 2.4;
/// A bus shelter's half length (along the road) and half depth, its height, and the gap between its open front
/// and the curb, metres.
const SHELTER_HALF_LENGTH_M: f64 = 1.5;
const SHELTER_HALF_DEPTH_M: f64 = 0.6;
const SHELTER_HEIGHT_M: f64 = 2.4;
const SHELTER_FROM_CURB_M: f64 = 0.5;
/// Poster colours (sRGB): a bright white-blue, warm orange, green, magenta.
pub const POSTER_COLOURS: [[u8; 3]; 4] = [[214, 226, 240], [236, 150, 60], [90, 176, 96], [200, 70, 150]];
/// Bollards in a row, and their spacing along the curb, metres.
const BOLLARDS_IN_ROW: usize = 3;
const BOLLARD_SPACING_M: f64 = 1.5;
/// How far from the curb furniture stands (its centre), metres.
const FROM_CURB_M: f64 = 0.4;
/// Bin colours (sRGB): dark green, black, municipal grey, blue, red-brown.
pub const BIN_COLOURS: [[u8; 3]; 5] = [[34, 64, 40], [26, 26, 28], [98, 102, 104], [30, 56, 110], [96, 40, 30]];

/// The street furniture of a clip: candidate places every [`SPACING_M`] along each sidewalk outside junctions
/// within [`scene_bounds`], each holding a bin, a row of bollards, a sign or (where the sidewalk is wide enough) a
/// bus shelter with the shares above (drawn from the clip's seed, the lane and the place), leaving out any piece
/// within 1.5 m of a lamp post (a shelter: 1.5 m plus its half length) or within [`LAMP_CLEARANCE_M`] (plus its half
/// width) of a pedestrian of the clip in any frame.
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
        } else if u < BIN_SHARE + BOLLARD_SHARE + SIGN_SHARE {
            out.push(Furniture {
                kind: FurnitureKind::SignPost,
                foot,
                base_z_m: s.z_m,
                half_m: DVec3::new(SIGN_POST_HALF_M, SIGN_POST_HALF_M, SIGN_POST_M * 0.5),
                rgb: [120, 122, 124],
            });
            // The plate faces along the road: thin along the world axis nearer the sidewalk's direction, and
            // mounted on the post's face towards `-along` (the post shows behind it from the other side).
            let (thin, wide) = (0.02, SIGN_PLATE_HALF_M);
            let (half_m, face) = if s.along.x.abs() >= s.along.y.abs() {
                (
                    DVec3::new(thin, wide, SIGN_PLATE_HALF_M),
                    DVec2::new(-s.along.x.signum(), 0.0),
                )
            } else {
                (
                    DVec3::new(wide, thin, SIGN_PLATE_HALF_M),
                    DVec2::new(0.0, -s.along.y.signum()),
                )
            };
            out.push(Furniture {
                kind: FurnitureKind::SignPlate,
                foot: foot + face * (SIGN_POST_HALF_M + thin + 0.005),
                base_z_m: s.z_m + SIGN_PLATE_BOTTOM_M,
                half_m,
                rgb: SIGN_COLOURS[(splitmix64(h) % SIGN_COLOURS.len() as u64) as usize],
            });
        } else if u < BIN_SHARE + BOLLARD_SHARE + SIGN_SHARE + SHELTER_SHARE && s.width_m >= SHELTER_MIN_SIDEWALK_M {
            let centre = s.inner - s.to_road * (SHELTER_FROM_CURB_M + SHELTER_HALF_DEPTH_M);
            // Its parts go or stay together: the shelter as a whole keeps clear, by its half length.
            if clear(trace, lamps, centre, SHELTER_HALF_LENGTH_M, 1.5 + SHELTER_HALF_LENGTH_M) {
                let poster = POSTER_COLOURS[(splitmix64(h) % POSTER_COLOURS.len() as u64) as usize];
                shelter(&mut out, centre, s.z_m, s.along, s.to_road, poster);
            }
        }
    });
    out.retain(|f| match f.kind {
        // A sign's post and plate go or stay together: both keep the plate's clearance.
        FurnitureKind::SignPost | FurnitureKind::SignPlate => clear(trace, lamps, f.foot, SIGN_PLATE_HALF_M, 1.5),
        FurnitureKind::Bin | FurnitureKind::Bollard => clear(trace, lamps, f.foot, f.half_m.x.max(f.half_m.y), 1.5),
        // Placed clear as a whole.
        FurnitureKind::ShelterFrame | FurnitureKind::ShelterGlass | FurnitureKind::ShelterPoster => true,
    });
    out
}

/// Whether a piece standing at `foot` (plan view) of half width `half_width_m` is more than `lamp_gap_m` from every
/// lamp's foot and more than [`LAMP_CLEARANCE_M`] plus its half width from every pedestrian of the clip in every
/// frame.
fn clear(trace: &ClipTrace, lamps: &[LampPost], foot: DVec2, half_width_m: f64, lamp_gap_m: f64) -> bool {
    let reach = LAMP_CLEARANCE_M + half_width_m;
    lamps
        .iter()
        .all(|l| l.foot.distance_squared(foot) > lamp_gap_m * lamp_gap_m)
        && trace
            .pedestrians
            .iter()
            .flatten()
            .all(|p| p.pos.truncate().distance_squared(foot) > reach * reach)
}

/// Pushes the parts of a bus shelter centred (plan view) at `centre` on a sidewalk at height `z_m`, its length along
/// the world axis nearer `along` and its open front towards `to_road`: a roof, two front posts, a glass back wall,
/// a bench against it and a poster closing the end towards `+along`.
fn shelter(out: &mut Vec<Furniture>, centre: DVec2, z_m: f64, along: DVec2, to_road: DVec2, poster: [u8; 3]) {
    // Axis-aligned like every piece: the length runs along x or y, the depth along the other.
    let along_x = along.x.abs() >= along.y.abs();
    let (ax, ay) = if along_x {
        (DVec2::new(along.x.signum(), 0.0), DVec2::new(0.0, to_road.y.signum()))
    } else {
        (DVec2::new(0.0, along.y.signum()), DVec2::new(to_road.x.signum(), 0.0))
    };
    // A box's half extents in world axes from its half length (along the road), half depth and half height.
    let half = |length: f64, depth: f64, height: f64| {
        if along_x {
            DVec3::new(length, depth, height)
        } else {
            DVec3::new(depth, length, height)
        }
    };
    let (l, d, top) = (SHELTER_HALF_LENGTH_M, SHELTER_HALF_DEPTH_M, SHELTER_HEIGHT_M);
    let frame = [150, 154, 158];
    let mut part = |kind, foot: DVec2, base_m: f64, half_m: DVec3, rgb| {
        out.push(Furniture {
            kind,
            foot,
            base_z_m: z_m + base_m,
            half_m,
            rgb,
        })
    };
    part(
        FurnitureKind::ShelterFrame,
        centre,
        top - 0.08,
        half(l + 0.05, d + 0.05, 0.04),
        frame,
    );
    for end in [-1.0, 1.0] {
        let foot = centre + ax * (end * (l - 0.04)) + ay * (d - 0.04);
        part(
            FurnitureKind::ShelterFrame,
            foot,
            0.0,
            half(0.035, 0.035, (top - 0.08) * 0.5),
            frame,
        );
    }
    part(
        FurnitureKind::ShelterGlass,
        centre - ay * (d - 0.02),
        0.1,
        half(l - 0.05, 0.02, (top - 0.2) * 0.5),
        [52, 62, 70],
    );
    part(
        FurnitureKind::ShelterFrame,
        centre - ay * (d - 0.25),
        0.0,
        half(l * 0.6, 0.2, 0.23),
        frame,
    );
    part(
        FurnitureKind::ShelterPoster,
        centre + ax * (l - 0.03) - ay * 0.1,
        0.3,
        half(0.03, d - 0.15, 0.8),
        poster,
    );
}
