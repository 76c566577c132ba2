//! Time-to-collision, gap acceptance and the in-road lookahead: pure functions of positions and velocities
//! (world frame, metres, seconds), unit-tested here and used by the pedestrian behaviour machine.
//!
//! TTC follows the paper: for a pedestrian at `p` and a vehicle at `q` with velocity `v_veh`, the closing speed
//! is `v_close = v_veh · (p − q)/|p − q|`, and `TTC = |p − q| / v_close` when `v_close > 0`, `∞` otherwise.
//! A gap is accepted when the minimum TTC over **all** vehicles in range exceeds
//! `τ_ttc + Δ_safety + w_road / s_cross`.

use glam::DVec2;

/// Time to collision of a vehicle at `vehicle_pos_m` moving with `vehicle_velocity_mps` towards a pedestrian at
/// `ped_pos_m`, seconds; `f64::INFINITY` when the vehicle is not closing the gap.
pub fn ttc_s(ped_pos_m: DVec2, vehicle_pos_m: DVec2, vehicle_velocity_mps: DVec2) -> f64 {
    let d = ped_pos_m - vehicle_pos_m;
    let dist_m = d.length();
    if dist_m <= 1e-9 {
        return 0.0;
    }
    let closing_mps = vehicle_velocity_mps.dot(d / dist_m);
    if closing_mps > 1e-9 {
        dist_m / closing_mps
    } else {
        f64::INFINITY
    }
}

/// The minimum TTC over the vehicles (position, velocity) within `range_m` of the pedestrian, seconds
/// (`∞` when none is in range or closing).
pub fn min_ttc_s(ped_pos_m: DVec2, vehicles: impl IntoIterator<Item = (DVec2, DVec2)>, range_m: f64) -> f64 {
    let range2 = range_m * range_m;
    vehicles
        .into_iter()
        .filter(|(q, _)| q.distance_squared(ped_pos_m) <= range2)
        .map(|(q, v)| ttc_s(ped_pos_m, q, v))
        .fold(f64::INFINITY, f64::min)
}

/// The gap-acceptance threshold `τ_ttc + Δ_safety + w_road / s_cross`, seconds.
pub fn gap_threshold_s(ttc_threshold_s: f64, safety_margin_s: f64, road_width_m: f64, crossing_speed_mps: f64) -> f64 {
    ttc_threshold_s + safety_margin_s + road_width_m / crossing_speed_mps.max(0.1)
}

/// Whether the gap is accepted: the minimum TTC strictly exceeds the threshold.
pub fn gap_accepted(min_ttc_s: f64, threshold_s: f64) -> bool {
    min_ttc_s > threshold_s
}

/// Distance from `p` to an oriented box (centre, heading, half length along the heading, half width), metres
/// (0 inside).
pub fn distance_to_box_m(p: DVec2, centre: DVec2, heading_rad: f64, half_length_m: f64, half_width_m: f64) -> f64 {
    let (s, c) = heading_rad.sin_cos();
    let d = p - centre;
    let local = DVec2::new(d.x * c + d.y * s, -d.x * s + d.y * c);
    let outside = DVec2::new(
        (local.x.abs() - half_length_m).max(0.0),
        (local.y.abs() - half_width_m).max(0.0),
    );
    outside.length()
}

/// The lookahead probe points of a pedestrian at `pos_m` crossing along the unit vector `dir`: the points
/// `points_m` ahead along `dir`, then the position predicted `prediction_s` ahead from `velocity_mps`. Writes
/// into `out` (cleared first) so the per-step loop does not allocate.
pub fn probe_points(
    pos_m: DVec2,
    dir: DVec2,
    velocity_mps: DVec2,
    points_m: &[f64],
    prediction_s: f64,
    out: &mut Vec<DVec2>,
) {
    out.clear();
    out.extend(points_m.iter().map(|&d| pos_m + dir * d));
    out.push(pos_m + velocity_mps * prediction_s);
}

/// Whether a vehicle footprint (centre, heading, half extents) lies within `radius_m` of any probe point.
pub fn probes_hit_box(
    probes: &[DVec2],
    centre: DVec2,
    heading_rad: f64,
    half_length_m: f64,
    half_width_m: f64,
    radius_m: f64,
) -> bool {
    probes
        .iter()
        .any(|&p| distance_to_box_m(p, centre, heading_rad, half_length_m, half_width_m) < radius_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ttc_is_distance_over_closing_speed() {
        let t = ttc_s(DVec2::new(20.0, 0.0), DVec2::ZERO, DVec2::new(10.0, 0.0));
        assert!((t - 2.0).abs() < 1e-12);
        // Oblique approach: only the projected speed closes the gap.
        let t = ttc_s(DVec2::new(30.0, 40.0), DVec2::ZERO, DVec2::new(10.0, 0.0));
        assert!((t - 50.0 / 6.0).abs() < 1e-9);
    }

    #[test]
    fn ttc_is_infinite_when_not_closing() {
        assert_eq!(
            ttc_s(DVec2::new(20.0, 0.0), DVec2::ZERO, DVec2::new(-10.0, 0.0)),
            f64::INFINITY
        );
        assert_eq!(ttc_s(DVec2::new(20.0, 0.0), DVec2::ZERO, DVec2::ZERO), f64::INFINITY);
        assert_eq!(
            ttc_s(DVec2::new(0.0, 20.0), DVec2::ZERO, DVec2::new(10.0, 0.0)),
            f64::INFINITY
        );
    }

    #[test]
    fn min_ttc_considers_every_vehicle_in_range() {
        let p = DVec2::new(0.0, 0.0);
        let vehicles = [
            (DVec2::new(-50.0, 0.0), DVec2::new(10.0, 0.0)),   // 5 s
            (DVec2::new(30.0, 0.0), DVec2::new(-10.0, 0.0)),   // 3 s
            (DVec2::new(100.0, 0.0), DVec2::new(-100.0, 0.0)), // out of range
        ];
        assert!((min_ttc_s(p, vehicles, 60.0) - 3.0).abs() < 1e-12);
        assert_eq!(min_ttc_s(p, [], 60.0), f64::INFINITY);
    }

    #[test]
    fn gap_threshold_adds_the_crossing_time() {
        assert!((gap_threshold_s(4.0, 0.5, 7.0, 1.4) - 9.5).abs() < 1e-12);
        assert!(gap_accepted(9.6, 9.5));
        assert!(!gap_accepted(9.5, 9.5));
        assert!(gap_accepted(f64::INFINITY, 9.5));
    }

    #[test]
    fn box_distance() {
        assert_eq!(
            distance_to_box_m(DVec2::new(1.0, 0.5), DVec2::ZERO, 0.0, 2.3, 0.95),
            0.0
        );
        assert!((distance_to_box_m(DVec2::new(5.3, 0.0), DVec2::ZERO, 0.0, 2.3, 0.95) - 3.0).abs() < 1e-12);
        // Rotated a quarter turn: the long side is along y.
        let h = std::f64::consts::FRAC_PI_2;
        assert!((distance_to_box_m(DVec2::new(0.0, 5.3), DVec2::ZERO, h, 2.3, 0.95) - 3.0).abs() < 1e-9);
    }

    #[test]
    fn probes_cover_points_and_prediction() {
        let mut out = Vec::new();
        probe_points(
            DVec2::ZERO,
            DVec2::X,
            DVec2::new(1.0, 0.0),
            &[0.5, 1.5, 2.5],
            0.5,
            &mut out,
        );
        assert_eq!(out.len(), 4);
        assert_eq!(out[2], DVec2::new(2.5, 0.0));
        assert_eq!(out[3], DVec2::new(0.5, 0.0));
        assert!(probes_hit_box(&out, DVec2::new(7.0, 0.0), 0.0, 2.3, 0.95, 3.0));
        assert!(!probes_hit_box(&out, DVec2::new(8.0, 0.0), 0.0, 2.3, 0.95, 3.0));
    }
}
