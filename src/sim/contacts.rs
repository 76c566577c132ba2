//! Contacts, the last stage of a step: a pedestrian disc overlapping a vehicle footprint, or two overlapping
//! footprints, is recorded as an [`Event::Contact`] (once, when it starts) and resolved so that nothing overlaps
//! in the next frame: the pedestrian is pushed out and the vehicle stopped; of two vehicles, the one behind
//! backs off along its path and stops.

use glam::DVec2;

use super::pedestrian::Ped;
use super::vehicle::Vehicle;
#[cfg(test)]
use super::vehicle::{HALF_LENGTH_M, HALF_WIDTH_M};
use super::{PED_RADIUS_M, ttc};
use crate::sim::trace::Event;

/// Cheap pre-check: a pedestrian farther than this from a vehicle centre beyond half its length and the
/// pedestrian's radius cannot touch it, metres.
const PED_PRECHECK_MARGIN_M: f64 = 0.5;
/// Same for two vehicles beyond one vehicle length, metres.
const VEHICLE_PRECHECK_MARGIN_M: f64 = 0.1;
/// A pushed-out pedestrian ends up this far beyond its radius from the footprint, metres.
const PUSH_OUT_CLEARANCE_M: f64 = 0.01;
/// The vehicle behind backs off in steps of this length, metres ...
const BACK_OFF_STEP_M: f64 = 0.25;
/// ... at most this many times (10 m).
const BACK_OFF_MAX_STEPS: usize = 40;

/// Which pairs are in contact now (so that a contact is an event only when it starts).
#[derive(Clone, Debug)]
pub(crate) struct Contacts {
    pedestrians: usize,
    vehicles: usize,
    /// `[vehicle · pedestrians + pedestrian]`.
    ped_vehicle: Vec<bool>,
    /// `[a · vehicles + b]`, a < b.
    vehicle_vehicle: Vec<bool>,
}

impl Contacts {
    /// No contacts yet between `vehicles` vehicles and `pedestrians` pedestrians.
    pub(super) fn new(vehicles: usize, pedestrians: usize) -> Contacts {
        Contacts {
            pedestrians,
            vehicles,
            ped_vehicle: vec![false; vehicles * pedestrians],
            vehicle_vehicle: vec![false; vehicles * vehicles],
        }
    }

    /// Detects, records (as events of `frame`) and resolves the contacts of this step.
    pub(super) fn resolve(&mut self, frame: u32, vehicles: &mut [Vehicle], peds: &mut [Ped], events: &mut Vec<Event>) {
        let (np, nv) = (self.pedestrians, self.vehicles);
        for (vi, v) in vehicles.iter_mut().enumerate() {
            for (pi, p) in peds.iter_mut().enumerate() {
                let reach = v.half_length_m + PED_RADIUS_M + PED_PRECHECK_MARGIN_M;
                let touching = v.pose.pos.distance_squared(p.body.pos) < reach.powi(2)
                    && ttc::distance_to_box_m(
                        p.body.pos,
                        v.pose.pos,
                        v.pose.heading_rad,
                        v.half_length_m,
                        v.half_width_m,
                    ) < PED_RADIUS_M;
                let flag = &mut self.ped_vehicle[vi * np + pi];
                if touching {
                    if !*flag {
                        events.push(Event::Contact {
                            frame,
                            vehicle: v.id,
                            pedestrian: Some(p.traits.id),
                            other_vehicle: None,
                        });
                    }
                    p.body.pos = push_out_of_box(p.body.pos, v.pose.pos, v.pose.heading_rad, v.half_extents());
                    v.speed_mps = 0.0;
                }
                *flag = touching;
            }
        }
        for a in 0..nv {
            for b in a + 1..nv {
                let (va, vb) = (&vehicles[a], &vehicles[b]);
                let reach = (va.half_length_m + vb.half_length_m) + VEHICLE_PRECHECK_MARGIN_M;
                let touching = va.pose.pos.distance_squared(vb.pose.pos) < reach.powi(2)
                    && boxes_overlap(
                        (va.pose.pos, va.pose.dir, va.half_extents()),
                        (vb.pose.pos, vb.pose.dir, vb.half_extents()),
                    );
                let flag = &mut self.vehicle_vehicle[a * nv + b];
                if touching {
                    if !*flag {
                        events.push(Event::Contact {
                            frame,
                            vehicle: va.id,
                            pedestrian: None,
                            other_vehicle: Some(vb.id),
                        });
                    }
                    // The one behind (the other is ahead along its heading) backs off and stops.
                    let a_behind = (vb.pose.pos - va.pose.pos).dot(va.pose.dir) > 0.0;
                    let (back, other) = if a_behind { (a, b) } else { (b, a) };
                    let o = &vehicles[other];
                    let fixed = (o.pose.pos, o.pose.dir, o.half_extents());
                    for _ in 0..BACK_OFF_MAX_STEPS {
                        let v = &mut vehicles[back];
                        v.back_off_and_stop(BACK_OFF_STEP_M);
                        if !boxes_overlap((v.pose.pos, v.pose.dir, v.half_extents()), fixed) || v.s_m <= 0.0 {
                            break;
                        }
                    }
                }
                *flag = touching;
            }
        }
    }
}

/// Moves a pedestrian disc at `p` out of a vehicle footprint (half extents `half`: along, across), to just
/// beyond its radius.
fn push_out_of_box(p: DVec2, centre: DVec2, heading_rad: f64, half: DVec2) -> DVec2 {
    let (s, c) = heading_rad.sin_cos();
    let d = p - centre;
    let local = DVec2::new(d.x * c + d.y * s, -d.x * s + d.y * c);
    let r = PED_RADIUS_M + PUSH_OUT_CLEARANCE_M;
    let clamped = DVec2::new(local.x.clamp(-half.x, half.x), local.y.clamp(-half.y, half.y));
    let out = if clamped != local {
        // Outside the box but within the radius: push along the normal.
        clamped + (local - clamped).normalize_or(DVec2::Y) * r
    } else {
        // Inside: leave through the nearest side.
        let dx = half.x - local.x.abs();
        let dy = half.y - local.y.abs();
        if dy <= dx {
            DVec2::new(local.x, local.y.signum() * (half.y + r))
        } else {
            DVec2::new(local.x.signum() * (half.x + r), local.y)
        }
    };
    centre + DVec2::new(out.x * c - out.y * s, out.x * s + out.y * c)
}

/// A vehicle footprint: centre, unit heading, half extents (along, across).
type Footprint = (DVec2, DVec2, DVec2);

/// Whether two vehicle footprints overlap (separating axis test).
pub(crate) fn boxes_overlap((ca, ua, ha): Footprint, (cb, ub, hb): Footprint) -> bool {
    let axes = [ua, ua.perp(), ub, ub.perp()];
    let d = cb - ca;
    axes.iter().all(|&ax| {
        let ra = ha.x * ua.dot(ax).abs() + ha.y * ua.perp().dot(ax).abs();
        let rb = hb.x * ub.dot(ax).abs() + hb.y * ub.perp().dot(ax).abs();
        d.dot(ax).abs() <= ra + rb
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_overlap_and_push_out() {
        let car = DVec2::new(HALF_LENGTH_M, HALF_WIDTH_M);
        let at = |x: f64, angle: f64| (DVec2::new(x, 0.0), DVec2::from_angle(angle), car);
        assert!(boxes_overlap(at(0.0, 0.0), at(4.0, 0.0)));
        assert!(!boxes_overlap(at(0.0, 0.0), at(4.7, 0.0)));
        assert!(boxes_overlap(at(0.0, 0.0), at(3.0, std::f64::consts::FRAC_PI_2)));
        // A bicycle (1.75 × 0.65 m) beside a car: apart at 1.3 m centre to centre, touching at 1.2 m.
        let bike = DVec2::new(0.875, 0.325);
        let beside = |y: f64| (DVec2::new(0.0, y), DVec2::X, bike);
        assert!(!boxes_overlap(at(0.0, 0.0), beside(1.3)));
        assert!(boxes_overlap(at(0.0, 0.0), beside(1.2)));
        let p = push_out_of_box(DVec2::new(1.0, 0.5), DVec2::ZERO, 0.0, car);
        assert!(ttc::distance_to_box_m(p, DVec2::ZERO, 0.0, HALF_LENGTH_M, HALF_WIDTH_M) >= PED_RADIUS_M);
        let p = push_out_of_box(DVec2::new(2.5, 0.0), DVec2::ZERO, 1.0, car);
        assert!(ttc::distance_to_box_m(p, DVec2::ZERO, 1.0, HALF_LENGTH_M, HALF_WIDTH_M) >= PED_RADIUS_M);
        let p = push_out_of_box(DVec2::new(0.2, 0.1), DVec2::ZERO, 0.0, bike);
        assert!(ttc::distance_to_box_m(p, DVec2::ZERO, 0.0, bike.x, bike.y) >= PED_RADIUS_M);
    }
}
