//! Parked cars (`traffic.parked_cars`): they stand beside the curb, parallel to the road, on the road or up on
//! the curb, clear of everything the simulation moves (checked here from the trace with a test of its own, not
//! the placement's), and the camera draws each as a car with its own instance id; `share: 0` leaves none.

use glam::{DVec2, DVec3};
use pedsynth::sensors::scene::{self, ParkedCar, tag};
use pedsynth::sim::{VEHICLE_LENGTH_M, VEHICLE_WIDTH_M};
use pedsynth::world::LaneType;

use crate::camera::{Clip, clip_at, spec};

/// Whether a plan-view point lies within `grow_m` of a car's footprint (sampled, not the placement's own test).
fn near_footprint(car: &ParkedCar, p: DVec2, grow_m: f64) -> bool {
    let fwd = DVec2::from_angle(car.yaw_rad);
    let d = p - car.centre.truncate();
    d.dot(fwd).abs() <= VEHICLE_LENGTH_M * 0.5 + grow_m && d.dot(fwd.perp()).abs() <= VEHICLE_WIDTH_M * 0.5 + grow_m
}

/// Points on the outline and inside of a vehicle footprint at `pos` heading `yaw_rad`, every 0.25 m.
fn footprint_points(pos: DVec3, yaw_rad: f64) -> Vec<DVec2> {
    let (fwd, side) = (DVec2::from_angle(yaw_rad), DVec2::from_angle(yaw_rad).perp());
    let (nl, nw) = (
        (VEHICLE_LENGTH_M / 0.25).round() as i32,
        (VEHICLE_WIDTH_M / 0.25).round() as i32,
    );
    let mut out = Vec::new();
    for i in 0..=nl {
        for j in 0..=nw {
            let a = (f64::from(i) / f64::from(nl) - 0.5) * VEHICLE_LENGTH_M;
            let b = (f64::from(j) / f64::from(nw) - 0.5) * VEHICLE_WIDTH_M;
            out.push(pos.truncate() + fwd * a + side * b);
        }
    }
    out
}

fn clips() -> Vec<Clip> {
    let overrides = ["sensors.rgb.width_px=640", "sensors.rgb.height_px=360"];
    let mut out: Vec<Clip> = (0..2)
        .map(|i| clip_at(&spec("quickstart.yaml"), &overrides, i))
        .collect();
    // A town with two lanes each way, where cars park on the road.
    let wide = [
        "sensors.rgb.width_px=640",
        "sensors.rgb.height_px=360",
        "dataset.towns=[town03_like]",
    ];
    out.push(clip_at(&spec("quickstart.yaml"), &wide, 0));
    out
}

/// The clip's parked cars, as its annotations placed them (and the sensors draw them).
fn parked(c: &Clip) -> Vec<ParkedCar> {
    c.ann.scenery.parked_cars.clone()
}

#[test]
fn parked_cars_stand_beside_the_curb_clear_of_everything_that_moves() {
    let (mut on_road, mut on_curb) = (0, 0);
    for c in clips() {
        let net = &c.towns[&c.script.town].network;
        let cars = parked(&c);
        for (k, car) in cars.iter().enumerate() {
            let at = car.centre.truncate();
            // On the road, outside junctions, parallel to the nearest driving lane.
            let hit = net.lane_at(at).expect("on a lane");
            assert!(
                matches!(
                    hit.lane_type,
                    LaneType::Driving | LaneType::Shoulder | LaneType::Parking
                ),
                "{}: car {k} {car:?} on {:?}",
                c.script.clip_id,
                hit.lane_type
            );
            assert!(!net.lanes[hit.lane as usize].in_junction);
            let lane = net.nearest_driving_lane(at, 4.0).expect("a driving lane beside it");
            let parallel = DVec2::from_angle(lane.heading_rad).dot(DVec2::from_angle(car.yaw_rad));
            assert!(parallel > 0.999, "{}: car {k} at {parallel}", c.script.clip_id);
            // Beside a sidewalk: 1.5 m to one side of its centre line lies a sidewalk (up on the curb: 0.5 m).
            let side = DVec2::from_angle(car.yaw_rad).perp();
            let reach = if car.on_curb { 0.5 } else { 1.5 };
            let beside = [at + side * reach, at - side * reach]
                .iter()
                .any(|&p| net.lane_at(p).is_some_and(|h| h.lane_type == LaneType::Sidewalk));
            assert!(beside, "{}: car {k} {car:?} not beside a sidewalk", c.script.clip_id);
            if car.on_curb {
                on_curb += 1;
            } else {
                on_road += 1;
            }
            // No vehicle (the ego included) comes within 0.2 m, no cyclist's ground point within 0.7 m and no
            // pedestrian within 0.35 m of its footprint, in any frame (in each of its axes: the placement keeps
            // 0.3, 1.0 and 0.5 m in any direction, which these bounds stay inside at a corner).
            for v in std::iter::once(&c.trace.ego).chain(&c.trace.vehicles).flatten() {
                if v.pos.truncate().distance(at) > 8.0 {
                    continue;
                }
                for p in footprint_points(v.pos, v.yaw_rad) {
                    assert!(
                        !near_footprint(car, p, 0.2),
                        "{}: a vehicle at {} hits car {k}",
                        c.script.clip_id,
                        v.pos
                    );
                }
            }
            for cy in c.trace.cyclists.iter().flatten() {
                assert!(!near_footprint(car, cy.pos.truncate(), 0.7));
            }
            for p in c.trace.pedestrians.iter().flatten() {
                assert!(
                    !near_footprint(car, p.pos.truncate(), 0.35),
                    "{}: a pedestrian at {} by car {k}",
                    c.script.clip_id,
                    p.pos
                );
            }
            // Cars do not overlap each other.
            for other in &cars[k + 1..] {
                for p in footprint_points(other.centre, other.yaw_rad) {
                    assert!(!near_footprint(car, p, 0.0));
                }
            }
        }
    }
    assert!(
        on_road >= 3 && on_curb >= 3,
        "{on_road} cars on the road, {on_curb} up on the curb"
    );
}

#[test]
fn parked_cars_are_drawn_as_cars_with_their_own_instance() {
    let mut seen = 0;
    for c in clips() {
        let cars = parked(&c);
        for frame in (0..c.trace.frame_count as usize).step_by(30) {
            let ego = c.trace.ego[frame];
            let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
            let img = c.render(frame as u32);
            for (id, car) in cars.iter().enumerate() {
                // The middle of its side at door height (0.6 m up), 5–30 m away.
                let point = car.centre + DVec3::Z * 0.6;
                let at = cam.project(point);
                let distance_m = car.centre.truncate().distance(cam.centre.truncate());
                if !(5.0..30.0).contains(&distance_m) || at.depth_m <= 0.0 || !cam.in_image(at.px) {
                    continue;
                }
                let (x, y) = (at.px.x as usize, at.px.y as usize);
                if x >= img.width || y >= img.height {
                    continue;
                }
                let i = y * img.width + x;
                // Its surface lies up to half its length nearer than its centre; something nearer still (a person,
                // a traffic car) may cover it: the depth says so.
                if img.depth_m[i] < at.depth_m as f32 - 2.5 {
                    continue;
                }
                assert_eq!(
                    img.semantic[i],
                    tag::CAR,
                    "{} frame {frame}: car {id}",
                    c.script.clip_id
                );
                assert_eq!(
                    img.instance[i],
                    scene::parked_instance(id as u32),
                    "{} frame {frame}: car {id}",
                    c.script.clip_id
                );
                seen += 1;
            }
        }
    }
    assert!(seen >= 10, "only {seen} parked cars checked in view");
}

#[test]
fn a_share_of_zero_parks_no_car() {
    let c = clip_at(
        &spec("quickstart.yaml"),
        &[
            "traffic.parked_cars.share=0",
            "sensors.rgb.width_px=320",
            "sensors.rgb.height_px=180",
        ],
        0,
    );
    assert!(parked(&c).is_empty());
    let img = c.render(c.busy_frames(1)[0]);
    assert!(!img.instance.iter().any(|&i| i >= scene::PARKED_INSTANCE_BASE));
}

#[test]
fn keypoints_behind_a_parked_car_are_labelled_occluded() {
    // Every visible (v = 2) keypoint of an annotated pedestrian whose pixel and its eight neighbours show a parked
    // car nearer than the joint would be a label that the occlusion test got wrong; keypoints labelled occluded
    // (v = 1) behind a parked car show that the case occurs.
    let (mut checked, mut hidden_by_car) = (0, 0);
    for c in clips() {
        let frames: std::collections::BTreeSet<u32> = c.ann.rows.iter().map(|r| r.frame).collect();
        for &frame in frames.iter().step_by(6) {
            let ego = c.trace.ego[frame as usize];
            let cam = c.rig.camera.at(ego.pos, ego.yaw_rad, ego.pitch_rad);
            let img = c.render(frame);
            for row in c.ann.rows.iter().filter(|r| r.frame == frame) {
                for j in 0..17 {
                    let (x, y, v) = (row.keypoints[3 * j], row.keypoints[3 * j + 1], row.keypoints[3 * j + 2]);
                    if v == 0.0 {
                        continue;
                    }
                    let joint = DVec3::new(
                        f64::from(row.keypoints_3d[3 * j]),
                        f64::from(row.keypoints_3d[3 * j + 1]),
                        f64::from(row.keypoints_3d[3 * j + 2]),
                    );
                    let depth = cam.project(joint).depth_m as f32;
                    let (cx, cy) = (x as i64, y as i64);
                    let car_in_front = (-1..=1).all(|dy| {
                        (-1..=1).all(|dx| {
                            let (px, py) = (cx + dx, cy + dy);
                            if px < 0 || py < 0 || px >= img.width as i64 || py >= img.height as i64 {
                                return false;
                            }
                            let i = py as usize * img.width + px as usize;
                            img.instance[i] >= scene::PARKED_INSTANCE_BASE && img.depth_m[i] < depth - 0.3
                        })
                    });
                    if v == 2.0 {
                        checked += 1;
                        assert!(
                            !car_in_front,
                            "{} frame {frame}: pedestrian {} joint {j} labelled visible behind a parked car",
                            c.script.clip_id, row.pedestrian
                        );
                    } else if car_in_front {
                        hidden_by_car += 1;
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "{checked} visible keypoints checked");
    assert!(
        hidden_by_car >= 5,
        "only {hidden_by_car} keypoints hidden by a parked car"
    );
}
