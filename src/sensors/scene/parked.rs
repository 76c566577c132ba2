//! Parked cars along the curbs (`traffic.parked_cars`): scenery, drawn per clip from its seed. [`clip_parked_cars`]
//! is a pure function of the town, the clip's script and its trace (and the lamps and furniture it keeps clear of), so the renderer draws, the LiDAR sees and the
//! annotations test occlusion against the same cars. The simulation does not know them: a car stays only where
//! no vehicle, cyclist or pedestrian of the clip passes in any frame.

use glam::{DVec2, DVec3};

use super::{CAR_COLOURS, Furniture, LAMP_POLE_HALF_WIDTH_M, LampPost, for_each_curb_station, scene_bounds};
use crate::plan::ClipScript;
use crate::sim::trace::ClipTrace;
use crate::sim::{VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use crate::util::mix::splitmix64;
use crate::world::{LaneType, RoadNetwork};

/// A parked car: the simulation's vehicle footprint and height ([`crate::sim::VEHICLE_LENGTH_M`] …) at rest. Its
/// id (the `parked_cars` table's, [`super::parked_instance`]) is its index in [`clip_parked_cars`]' list.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParkedCar {
    /// Centre of its ground footprint (on the road surface), world metres.
    pub centre: DVec3,
    /// Heading: along the curb, facing the traffic of the lane it stands in, radians.
    pub yaw_rad: f64,
    /// Paint, sRGB (one of the traffic's car colours).
    pub rgb: [u8; 3],
    /// Whether its curb-side wheels stand up on the sidewalk (where the lane leaves no room to pass it).
    pub on_curb: bool,
}

impl ParkedCar {
    /// Unit vector along its heading, plan view.
    pub fn forward(&self) -> DVec2 {
        DVec2::from_angle(self.yaw_rad)
    }
}

/// Distance between candidate places along a curb, metres: a car length and room to pull out.
pub const PARKED_SPACING_M: f64 = 7.0;
/// Where a parked car's side stands from the sidewalk's edge, metres, in the order tried: on the road 0.25 m
/// from the curb, or (where that leaves too little room to pass) with its curb-side wheels up on the sidewalk,
/// straddling the curb as drivers do on narrow streets.
const CURB_OFFSETS_M: [f64; 2] = [0.25, -0.9];
/// Room a parked car leaves to a junction (beyond its ends, along the road) and to a crosswalk (around its
/// footprint), metres.
const JUNCTION_GAP_M: f64 = 4.0;
const CROSSWALK_GAP_M: f64 = 2.0;
/// Clearance between a parked car's footprint and a moving vehicle's (their sides), metres.
const VEHICLE_CLEARANCE_M: f64 = 0.3;
/// Clearance between a parked car's footprint and a pedestrian's centre (a body's half width and a margin), a
/// cyclist's centre (half a bicycle's length), and a lamp post's or a piece of furniture's side, metres.
const PEDESTRIAN_CLEARANCE_M: f64 = 0.5;
const CYCLIST_CLEARANCE_M: f64 = 1.0;
const FURNITURE_CLEARANCE_M: f64 = 0.3;

/// The parked cars of a clip: a candidate place every [`PARKED_SPACING_M`] along each sidewalk outside junctions
/// within [`scene_bounds`] holds a car with probability `script.parked_car_share` (drawn from the clip's seed, the
/// sidewalk lane and the place), parallel to the curb, facing the traffic of the nearest driving lane, at the
/// first of [`CURB_OFFSETS_M`] where it keeps clear of every vehicle (the ego included), cyclist and pedestrian
/// of the trace in every frame and of the lamp posts and furniture. A place is left out where no offset keeps
/// clear, where the car's road side leaves the road's driving, parking or shoulder lanes (or its curb side
/// those and the sidewalk), or where it lies within [`JUNCTION_GAP_M`] of a junction along the road or
/// [`CROSSWALK_GAP_M`] of a crosswalk.
pub fn clip_parked_cars(
    script: &ClipScript,
    trace: &ClipTrace,
    town: &RoadNetwork,
    lamps: &[LampPost],
    furniture: &[Furniture],
) -> Vec<ParkedCar> {
    let share = script.parked_car_share;
    if share <= 0.0 {
        return Vec::new();
    }
    let (lo, hi) = scene_bounds(trace);
    let near = |p: DVec2| p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y;
    let half = DVec2::new(VEHICLE_LENGTH_M * 0.5, VEHICLE_WIDTH_M * 0.5);
    let outside_junction = |p: DVec2, sidewalk_too: bool| {
        town.lane_at(p).is_some_and(|hit| {
            let road = matches!(
                hit.lane_type,
                LaneType::Driving | LaneType::Parking | LaneType::Shoulder
            );
            (road || (sidewalk_too && hit.lane_type == LaneType::Sidewalk))
                && !town.lanes[hit.lane as usize].in_junction
        })
    };
    let mut out = Vec::new();
    for_each_curb_station(town, PARKED_SPACING_M, |s| {
        let h = splitmix64(script.seed ^ 0x9a4c_edca_75ed ^ splitmix64(((s.lane as u64) << 24) | s.place));
        let u = (h >> 11) as f64 / (1u64 << 53) as f64;
        if u >= share || !near(s.inner) {
            return;
        }
        let Some(lane) = town.nearest_driving_lane(s.inner + s.to_road * 2.0, 4.0) else {
            return;
        };
        // Parallel to the curb, facing the lane's traffic.
        let along = if DVec2::from_angle(lane.heading_rad).dot(s.along) >= 0.0 {
            s.along
        } else {
            -s.along
        };
        let rgb = CAR_COLOURS[(splitmix64(h) % CAR_COLOURS.len() as u64) as usize];
        for offset_m in CURB_OFFSETS_M {
            let centre = s.inner + s.to_road * (offset_m + half.y);
            let road_side = centre + s.to_road * half.y;
            let curb_side = centre - s.to_road * half.y;
            let reach = half.x + JUNCTION_GAP_M;
            let placed = [-1.0, 1.0].iter().all(|&fx| {
                outside_junction(road_side + along * (fx * half.x), false)
                    && outside_junction(curb_side + along * (fx * half.x), true)
                    && outside_junction(centre + along * (fx * reach), true)
            }) && !near_crosswalk(town, centre, half.length() + CROSSWALK_GAP_M);
            if !placed {
                continue;
            }
            // On the road's surface (a car up on the curb stands level at the road's height).
            let Some(z_m) = town
                .lane_at(road_side - s.to_road * 0.1)
                .map(|hit| f64::from(town.pieces[hit.piece as usize].z_m))
            else {
                continue;
            };
            let car = ParkedCar {
                centre: centre.extend(z_m),
                yaw_rad: along.to_angle(),
                rgb,
                on_curb: offset_m < 0.0,
            };
            if clear_of_trace(&car, script, trace) && clear_of_street_objects(&car, lamps, furniture) {
                out.push(car);
                return;
            }
        }
    });
    out
}

/// Whether the car keeps [`FURNITURE_CLEARANCE_M`] from every lamp post and piece of furniture.
fn clear_of_street_objects(car: &ParkedCar, lamps: &[LampPost], furniture: &[Furniture]) -> bool {
    let lamp_reach = f64::from(LAMP_POLE_HALF_WIDTH_M) * std::f64::consts::SQRT_2 + FURNITURE_CLEARANCE_M;
    lamps.iter().all(|l| distance_to_footprint(car, l.foot) > lamp_reach)
        && furniture
            .iter()
            .all(|f| distance_to_footprint(car, f.foot) > f.half_m.truncate().length() + FURNITURE_CLEARANCE_M)
}

/// Whether any crosswalk's bounding box comes within `reach_m` of `centre`.
fn near_crosswalk(town: &RoadNetwork, centre: DVec2, reach_m: f64) -> bool {
    town.crosswalks.iter().any(|cw| {
        crate::world::bounding_box(cw.polygon.iter().copied()).is_some_and(|(lo, hi)| {
            let d = (lo - centre).max(centre - hi).max(DVec2::ZERO);
            d.length_squared() <= reach_m * reach_m
        })
    })
}

/// Plan-view distance from a point to a car's footprint (0 inside).
fn distance_to_footprint(car: &ParkedCar, p: DVec2) -> f64 {
    let fwd = car.forward();
    let d = p - car.centre.truncate();
    let local = DVec2::new(
        d.dot(fwd).abs() - VEHICLE_LENGTH_M * 0.5,
        d.dot(fwd.perp()).abs() - VEHICLE_WIDTH_M * 0.5,
    );
    local.max(DVec2::ZERO).length()
}

/// Whether two rectangles (centre, unit forward, half length and width), each grown by `margin_m` / 2 on every
/// side, overlap (separating axes).
fn footprints_overlap(a: (DVec2, DVec2), b: (DVec2, DVec2), half: DVec2, margin_m: f64) -> bool {
    let grown = half + DVec2::splat(margin_m * 0.5);
    let d = b.0 - a.0;
    let axes = [a.1, a.1.perp(), b.1, b.1.perp()];
    axes.iter().all(|&axis| {
        let extent = |fwd: DVec2| grown.x * fwd.dot(axis).abs() + grown.y * fwd.perp().dot(axis).abs();
        d.dot(axis).abs() <= extent(a.1) + extent(b.1)
    })
}

/// Whether no vehicle, cyclist or pedestrian of the trace (a child beside its parent included) comes near the
/// car in any frame.
fn clear_of_trace(car: &ParkedCar, script: &ClipScript, trace: &ClipTrace) -> bool {
    let centre = car.centre.truncate();
    let fwd = car.forward();
    let half = DVec2::new(VEHICLE_LENGTH_M * 0.5, VEHICLE_WIDTH_M * 0.5);
    // Two footprints farther apart than this cannot touch.
    let reach2 = (2.0 * half.length() + VEHICLE_CLEARANCE_M).powi(2);
    let vehicles_clear = std::iter::once(&trace.ego)
        .chain(trace.vehicles.iter())
        .flatten()
        .all(|v| {
            let p = v.pos.truncate();
            p.distance_squared(centre) > reach2
                || !footprints_overlap(
                    (centre, fwd),
                    (p, DVec2::from_angle(v.yaw_rad)),
                    half,
                    VEHICLE_CLEARANCE_M,
                )
        });
    let cyclists_clear = trace
        .cyclists
        .iter()
        .flatten()
        .all(|c| distance_to_footprint(car, c.pos.truncate()) > CYCLIST_CLEARANCE_M);
    let child_m = crate::sensors::body::CHILD_OFFSET_M.length();
    let pedestrians_clear = trace.pedestrians.iter().enumerate().all(|(i, frames)| {
        let with_child = script.pedestrians.get(i).is_some_and(|p| p.child.is_some());
        let clearance = PEDESTRIAN_CLEARANCE_M + if with_child { child_m } else { 0.0 };
        frames
            .iter()
            .all(|f| distance_to_footprint(car, f.pos.truncate()) > clearance)
    });
    vehicles_clear && cyclists_clear && pedestrians_clear
}

#[cfg(test)]
mod tests {
    use super::*;

    fn car_at(x: f64, y: f64, yaw_rad: f64) -> ParkedCar {
        ParkedCar {
            centre: DVec3::new(x, y, 0.0),
            yaw_rad,
            rgb: [0; 3],
            on_curb: false,
        }
    }

    #[test]
    fn footprint_distance_is_zero_inside_and_grows_outside() {
        let car = car_at(10.0, 5.0, std::f64::consts::FRAC_PI_2);
        assert_eq!(distance_to_footprint(&car, DVec2::new(10.0, 5.0)), 0.0);
        // Along its length (world y): half the length to the bumper.
        assert!((distance_to_footprint(&car, DVec2::new(10.0, 5.0 + VEHICLE_LENGTH_M * 0.5 + 1.0)) - 1.0).abs() < 1e-9);
        // Beside it (world x): half the width to the side.
        assert!((distance_to_footprint(&car, DVec2::new(10.0 + VEHICLE_WIDTH_M * 0.5 + 0.4, 5.0)) - 0.4).abs() < 1e-9);
    }

    #[test]
    fn footprints_overlap_by_separating_axes() {
        let half = DVec2::new(VEHICLE_LENGTH_M * 0.5, VEHICLE_WIDTH_M * 0.5);
        let east = DVec2::X;
        // Side by side in two lanes 3.5 m apart: clear; 1.8 m apart: touching.
        assert!(!footprints_overlap(
            (DVec2::ZERO, east),
            (DVec2::new(0.0, 3.5), east),
            half,
            0.3
        ));
        assert!(footprints_overlap(
            (DVec2::ZERO, east),
            (DVec2::new(0.0, 1.8), east),
            half,
            0.3
        ));
        // Nose to tail 4.8 m apart: clear without a margin, touching with 0.3 m.
        assert!(!footprints_overlap(
            (DVec2::ZERO, east),
            (DVec2::new(4.8, 0.0), east),
            half,
            0.0
        ));
        assert!(footprints_overlap(
            (DVec2::ZERO, east),
            (DVec2::new(4.8, 0.0), east),
            half,
            0.3
        ));
        // Crossing at right angles: a car 3 m ahead across the nose touches, 3.8 m clear.
        let north = DVec2::Y;
        assert!(footprints_overlap(
            (DVec2::ZERO, east),
            (DVec2::new(3.0, 0.0), north),
            half,
            0.0
        ));
        assert!(!footprints_overlap(
            (DVec2::ZERO, east),
            (DVec2::new(3.4, 0.0), north),
            half,
            0.0
        ));
    }
}
