//! Junction conflict zones: where two vehicles' paths cross or merge, found once per clip on a grid of path
//! samples, and the rule that decides which of two vehicles approaching a zone yields.

use glam::DVec2;

use super::Vehicle;
use crate::sim::VEHICLE_LENGTH_M;
use crate::world::bounding_box;
use crate::world::grid::CellGrid;

/// Where two vehicles' paths cross or merge: the stretch of each path whose centre line comes within
/// [`ZONE_DISTANCE_M`] of the other's at a heading difference above [`ZONE_MIN_ANGLE_RAD`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ConflictZone {
    /// Index of the other vehicle.
    pub other: usize,
    /// The zone on this vehicle's path, arc lengths `[start, end]`.
    pub me_m: (f64, f64),
    /// The zone on the other's path.
    pub other_m: (f64, f64),
}

/// Centre lines closer than this belong to a conflict zone, metres.
const ZONE_DISTANCE_M: f64 = 2.5;
/// Paths meeting at less than this angle are following, not crossing, radians.
const ZONE_MIN_ANGLE_RAD: f64 = 0.35;
/// How far ahead of its start a vehicle's path is searched for conflict zones, metres.
const ZONE_HORIZON_M: f64 = 260.0;
/// Samples of one path closer than this along it belong to the same zone, metres.
const ZONE_GAP_M: f64 = 10.0;

/// The conflict zones of every vehicle with every other, found once at set-up with a grid of cells at least
/// [`ZONE_DISTANCE_M`] wide over the path samples (1 m apart). Sorted by zone start.
pub(crate) fn conflict_zones(vehicles: &[Vehicle]) -> Vec<Vec<ConflictZone>> {
    let samples = zone_samples(vehicles);
    let n = vehicles.len();
    let mut pairs: Vec<Vec<(f64, f64)>> = vec![Vec::new(); n * n];
    let grid = sample_grid(&samples);
    for a in &samples {
        grid.for_items_around(a.pos, |kb| record_close_pair(a, &samples[kb], n, &mut pairs));
    }
    zones_from_pairs(n, pairs)
}

/// The samples by grid cell: cells at least [`ZONE_DISTANCE_M`] wide, so that every sample within that
/// distance of another is in its 3 × 3 cells (wider when the samples are spread so far that the grid would
/// have more than a few cells per sample).
fn sample_grid(samples: &[ZoneSample]) -> CellGrid {
    let (lo, hi) = bounding_box(samples.iter().map(|smp| smp.pos)).unwrap_or_default();
    let max_cells = (4 * samples.len() + 64) as f64;
    CellGrid::build(lo, hi, ZONE_DISTANCE_M, max_cells, samples.len(), |k| {
        Some((samples[k].pos, samples[k].pos))
    })
}

/// A sample of a vehicle's path for the conflict-zone search.
#[derive(Clone, Copy, Debug)]
struct ZoneSample {
    vehicle: usize,
    s_m: f64,
    pos: DVec2,
    heading_rad: f64,
}

/// Every vehicle's path from just behind it to [`ZONE_HORIZON_M`] ahead, sampled every metre.
fn zone_samples(vehicles: &[Vehicle]) -> Vec<ZoneSample> {
    let mut samples = Vec::new();
    for (vehicle, v) in vehicles.iter().enumerate() {
        let end = (v.s_m + ZONE_HORIZON_M).min(v.path.length_m());
        let mut s_m = (v.s_m - VEHICLE_LENGTH_M).max(0.0);
        while s_m <= end {
            let pose = v.path.pose_at(s_m);
            if pose.pos.is_finite() {
                samples.push(ZoneSample {
                    vehicle,
                    s_m,
                    pos: pose.pos,
                    heading_rad: pose.heading_rad,
                });
            }
            s_m += 1.0;
        }
    }
    samples
}

/// Records `(a, b)` in `pairs[a.vehicle · n + b.vehicle]` (and the reverse) when they are samples of two
/// vehicles' paths that are close and cross at an angle. Symmetric: only the order with `a.vehicle <
/// b.vehicle` records, so each unordered pair of samples is recorded once each way.
fn record_close_pair(a: &ZoneSample, b: &ZoneSample, n: usize, pairs: &mut [Vec<(f64, f64)>]) {
    if b.vehicle <= a.vehicle || a.pos.distance_squared(b.pos) > ZONE_DISTANCE_M * ZONE_DISTANCE_M {
        return;
    }
    let mut d = (a.heading_rad - b.heading_rad).abs() % std::f64::consts::TAU;
    if d > std::f64::consts::PI {
        d = std::f64::consts::TAU - d;
    }
    if d > ZONE_MIN_ANGLE_RAD {
        pairs[a.vehicle * n + b.vehicle].push((a.s_m, b.s_m));
        pairs[b.vehicle * n + a.vehicle].push((b.s_m, a.s_m));
    }
}

/// The zones of each vehicle from the close pairs `(s_i, s_j)` per ordered `(i, j)` (in any order: each list
/// is sorted here), sorted by zone start.
fn zones_from_pairs(n: usize, mut pairs: Vec<Vec<(f64, f64)>>) -> Vec<Vec<ConflictZone>> {
    let mut out = vec![Vec::new(); n];
    for i in 0..n {
        for j in 0..n {
            let list = &mut pairs[i * n + j];
            if list.is_empty() {
                continue;
            }
            list.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
            let mut zone: Option<ConflictZone> = None;
            for &(si, sj) in list.iter() {
                match zone.as_mut() {
                    Some(z) if si - z.me_m.1 <= ZONE_GAP_M => {
                        z.me_m.1 = si;
                        z.other_m.0 = z.other_m.0.min(sj);
                        z.other_m.1 = z.other_m.1.max(sj);
                    }
                    _ => {
                        if let Some(z) = zone.take() {
                            out[i].push(z);
                        }
                        zone = Some(ConflictZone {
                            other: j,
                            me_m: (si, si),
                            other_m: (sj, sj),
                        });
                    }
                }
            }
            out[i].extend(zone);
        }
        out[i].sort_by(|a, b| a.me_m.0.total_cmp(&b.me_m.0).then(a.other.cmp(&b.other)));
    }
    out
}

/// The standing obstacle (gap from the front bumper, metres) at which vehicle `i` must yield in a conflict zone,
/// if it must: a vehicle already in the zone goes first; otherwise the one that would reach it first (ties:
/// the ego, then lower ids). Both vehicles evaluate the same rule, so exactly one of them yields.
pub(super) fn zone_yield_gap_m(me: &Vehicle, vehicles: &[Vehicle], zone: &ConflictZone, look: f64) -> Option<f64> {
    let other = &vehicles[zone.other];
    let my_front = me.s_m + me.half_length_m;
    let other_front = other.s_m + other.half_length_m;
    if me.s_m - me.half_length_m > zone.me_m.1 || other.s_m - other.half_length_m > zone.other_m.1 {
        return None; // one of us has passed
    }
    let dist_me = zone.me_m.0 - my_front;
    if dist_me > look {
        return None;
    }
    let dist_other = zone.other_m.0 - other_front;
    let (in_me, in_other) = (dist_me <= 0.0, dist_other <= 0.0);
    let yield_now = match (in_me, in_other) {
        (true, false) => false,
        (false, true) => true,
        (true, true) => me.id > other.id,
        (false, false) => {
            let t_me = dist_me / me.speed_mps.max(0.5);
            let t_other = dist_other / other.speed_mps.max(0.5);
            t_other < t_me || (t_other == t_me && other.id < me.id)
        }
    };
    yield_now.then_some(dist_me - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::trace::VehicleId;
    use crate::sim::vehicle::path::tests::winding_path;

    /// Vehicles on copies of the winding path, rotated about `pivot` and shifted, crossing each other.
    fn crossing_vehicles(pivot: DVec2, shifts: &[(f64, DVec2)]) -> Vec<Vehicle> {
        let base = winding_path();
        shifts
            .iter()
            .enumerate()
            .map(|(k, &(angle_rad, shift))| {
                let path = base.moved(pivot, angle_rad, shift);
                Vehicle::new(
                    VehicleId::Traffic(k as u32),
                    path,
                    3.0 * k as f64,
                    1.0,
                    2.0,
                    1.5,
                    false,
                    None,
                )
            })
            .collect()
    }

    #[test]
    fn conflict_zones_from_the_grid_match_the_all_pairs_search() {
        let pivot = DVec2::new(40.0, 10.0);
        let near = [
            (0.0, DVec2::ZERO),
            (1.2, DVec2::new(5.0, -3.0)),
            (-0.9, DVec2::new(-8.0, 4.0)),
            (0.1, DVec2::new(0.0, 1.0)),
        ];
        // One vehicle kilometres away spreads the points so far that the grid's cells are widened.
        let spread = [
            (0.0, DVec2::ZERO),
            (1.5, DVec2::new(2.0, 2.0)),
            (0.7, DVec2::new(4000.0, -2500.0)),
        ];
        for shifts in [&near[..], &spread[..]] {
            let vehicles = crossing_vehicles(pivot, shifts);
            let samples = zone_samples(&vehicles);
            let n = vehicles.len();
            let mut pairs = vec![Vec::new(); n * n];
            for a in &samples {
                for b in &samples {
                    record_close_pair(a, b, n, &mut pairs);
                }
            }
            let expected = zones_from_pairs(n, pairs);
            let zones: usize = expected.iter().map(Vec::len).sum();
            assert!(zones >= 2, "the paths cross: {expected:?}");
            assert_eq!(conflict_zones(&vehicles), expected);
        }
        let spread = crossing_vehicles(pivot, &spread);
        let grid = sample_grid(&zone_samples(&spread));
        assert!(grid.cell_m() > ZONE_DISTANCE_M, "the spread case widens the cells");
    }
}
