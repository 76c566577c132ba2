//! The dynamic part of a scene ([`FrameScene`]), built per frame (or per DVS sub-step, between two frames):
//! traffic vehicles (body, cabin, wheels, lamps, wear), cyclists and pedestrians (the capsules of
//! [`body::pose`](crate::sensors::body::pose), the very body the keypoints come from), whose primitive ids
//! follow the static scene's.

use super::*;

/// The dynamic part of a frame's scene (traffic and pedestrians); its primitive ids follow the static
/// scene's.
#[derive(Clone, Debug, Default)]
pub struct FrameScene {
    /// Triangles and primitives of the frame's agents.
    pub mesh: Mesh,
    /// Body capsules (for [`Material::Body`] normals).
    pub capsules: Vec<SceneCapsule>,
    /// Vehicle head lamps (position, forward axis), for lighting.
    pub head_lamps: Vec<(Vec3, Vec3)>,
}

/// Linear interpolation of two vehicle frames (the DVS's sub-frame renders).
pub(super) fn lerp_vehicle(a: &VehicleFrame, b: &VehicleFrame, t: f64) -> (DVec3, f64) {
    lerp_pose(a.pos, a.yaw_rad, b.pos, b.yaw_rad, t)
}

/// Linear interpolation of two poses (position, yaw the short way round).
pub(super) fn lerp_pose(a: DVec3, a_yaw: f64, b: DVec3, b_yaw: f64, t: f64) -> (DVec3, f64) {
    let dyaw = (b_yaw - a_yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    (a.lerp(b, t), a_yaw + dyaw * t)
}

/// Linear interpolation of two pedestrian frames (state and flags of the nearer one).
pub(super) fn lerp_ped(a: &PedFrame, b: &PedFrame, t: f64) -> PedFrame {
    let wrap = |d: f64| (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    let mut out = if t < 0.5 { *a } else { *b };
    out.pos = a.pos.lerp(b.pos, t);
    out.yaw_rad = a.yaw_rad + wrap(b.yaw_rad - a.yaw_rad) * t;
    out.head_yaw_rad = a.head_yaw_rad + wrap(b.head_yaw_rad - a.head_yaw_rad) * t;
    out.velocity = a.velocity.lerp(b.velocity, t);
    let mut dp = b.gait_phase - a.gait_phase;
    dp -= dp.round();
    out.gait_phase = (a.gait_phase + dp * t).rem_euclid(1.0);
    if let (Some((ga, ta)), Some((gb, tb))) = (a.gesture, b.gesture)
        && ga == gb
    {
        out.gesture = Some((ga, ta + (tb - ta) * t));
    }
    out
}

pub(super) const CAR_COLOURS: [[u8; 3]; 10] = [
    [235, 235, 232],
    [24, 24, 26],
    [168, 170, 174],
    [96, 98, 104],
    [150, 20, 24],
    [26, 52, 120],
    [30, 70, 48],
    [200, 190, 160],
    [70, 110, 160],
    [190, 120, 30],
];

/// Which colour of an identity each body capsule wears (see [`body::pose`]'s capsule order).
#[derive(Clone, Copy)]
pub(super) enum Wear {
    Top,
    Bottom,
    Skin,
    Shoes,
    Head,
    Sleeve,
    Leg,
    Hair,
    Headwear,
    Carry,
    Garment,
}

pub(super) const WEAR: [Wear; CAPSULES] = [
    Wear::Top,      // torso, left half
    Wear::Top,      // shoulders
    Wear::Head,     // head
    Wear::Top,      // upper arms
    Wear::Top,      //
    Wear::Sleeve,   // forearms
    Wear::Sleeve,   //
    Wear::Bottom,   // thighs
    Wear::Bottom,   //
    Wear::Leg,      // shins
    Wear::Leg,      //
    Wear::Shoes,    // feet
    Wear::Shoes,    //
    Wear::Skin,     // neck
    Wear::Skin,     // hands
    Wear::Skin,     //
    Wear::Bottom,   // hips
    Wear::Top,      // torso, right half
    Wear::Hair,     // hair (long, bun)
    Wear::Headwear, // hat
    Wear::Carry,    // bag
    Wear::Garment,  // skirt, dress, coat
    Wear::Skin,     // jaw
];

impl FrameScene {
    /// The primitive of an id: the static scene's, or one of this frame's.
    #[inline]
    pub fn prim<'a>(&'a self, stat: &'a StaticScene, id: u32) -> &'a Prim {
        stat.prims
            .get(id as usize)
            .unwrap_or_else(|| &self.mesh.prims[id as usize - stat.prims.len()])
    }

    /// Builds the dynamic scene at time `t`.
    pub fn build(&mut self, stat: &StaticScene, script: &ClipScript, trace: &ClipTrace, t: SceneTime) {
        self.mesh.clear(stat.prims.len() as u32);
        self.capsules.clear();
        self.head_lamps.clear();
        let f0 = t.frame as usize;
        for (vi, frames) in trace.vehicles.iter().enumerate() {
            let Some(a) = frames.get(f0) else { continue };
            let b = frames.get(f0 + 1).unwrap_or(a);
            let (pos, yaw) = lerp_vehicle(a, b, t.alpha);
            let id = script.vehicles.get(vi).map_or(vi as u32, |v| v.id);
            let paint = stat.car_paint.get(vi).copied().unwrap_or(Vec3::splat(0.5));
            // An emergency vehicle's light bar flashes red and blue, alternating at 2 Hz.
            let flash = script.vehicles.get(vi).and_then(|v| v.emergency).map(|_| {
                let time_s = (f64::from(t.frame) + t.alpha) / f64::from(trace.fps.max(1));
                (time_s * 2.0).fract() < 0.5
            });
            self.push_vehicle(
                stat.rel(pos),
                yaw as f32,
                paint,
                VEHICLE_INSTANCE_BASE.saturating_add(id as u16),
                flash,
            );
        }
        // Traffic lights' lamps: red on top, amber, green at the bottom, the one of the frame's state lit.
        for g in stat.signal_heads.iter().filter_map(|&k| trace.signals.get(k)) {
            let Some(&state) = g.states.get(f0) else { continue };
            let head = stat.rel(g.position);
            let (s, c) = (g.facing_rad as f32).sin_cos();
            let face = head.truncate() + Vec2::new(c, s) * (SIGNAL_HOUSING_HALF_DEPTH_M + 0.01);
            for (k, lamp_state, colour) in [
                (1.0f32, LightState::Red, [255, 30, 20]),
                (0.0, LightState::Amber, [255, 170, 0]),
                (-1.0, LightState::Green, [40, 255, 90]),
            ] {
                // The lit lamp glows (by day too); the others are dark glass.
                let (material, albedo) = if state == lamp_state {
                    (Material::Beacon, linear(colour))
                } else {
                    (Material::Metal, linear(colour) * 0.08)
                };
                let lamp = Prim {
                    material,
                    tag: tag::TRAFFIC_LIGHT,
                    instance: 0,
                    albedo,
                    albedo2: albedo,
                    normal: Vec3::Z,
                    aux: 0,
                };
                let z = head.z + k * 0.28;
                self.mesh.upright_box(
                    face,
                    g.facing_rad as f32,
                    Vec2::new(0.02, SIGNAL_LAMP_HALF_M),
                    [z - SIGNAL_LAMP_HALF_M, z + SIGNAL_LAMP_HALF_M],
                    lamp,
                    lamp,
                );
            }
        }
        for (pi, frames) in trace.pedestrians.iter().enumerate() {
            let Some(a) = frames.get(f0) else { continue };
            let b = frames.get(f0 + 1).unwrap_or(a);
            let frame = if t.alpha > 0.0 { lerp_ped(a, b, t.alpha) } else { *a };
            let Some(ps) = script.pedestrians.get(pi) else { continue };
            let Some((outfit, child_outfit)) = stat.outfits.get(pi) else {
                continue;
            };
            let pose = body::pose(&frame, ps.identity.height_m, &ps.identity.figure, DVec3::ZERO);
            self.push_body(stat, &pose, outfit, pedestrian_instance(ps.id), tag::PEDESTRIAN);
            if let (Some(child), Some(child_outfit)) = (&ps.child, child_outfit) {
                let child_frame = PedFrame { gesture: None, ..frame };
                let pose = body::pose(&child_frame, child.height_m, &child.figure, CHILD_OFFSET_M);
                let inst = CHILD_INSTANCE_BASE.saturating_add(ps.id.min(16_383) as u16);
                self.push_body(stat, &pose, child_outfit, inst, tag::PEDESTRIAN);
            }
        }
        for (ci, frames) in trace.cyclists.iter().enumerate() {
            let (Some(a), Some(cs), Some((outfit, paint))) =
                (frames.get(f0), script.cyclists.get(ci), stat.riders.get(ci))
            else {
                continue;
            };
            let b = frames.get(f0 + 1).unwrap_or(a);
            let mut frame = *a;
            if t.alpha > 0.0 {
                let (pos, yaw) = lerp_pose(a.pos, a.yaw_rad, b.pos, b.yaw_rad, t.alpha);
                frame.pos = pos;
                frame.yaw_rad = yaw;
                frame.ridden_m = a.ridden_m + (b.ridden_m - a.ridden_m) * t.alpha;
                let mut dp = b.crank_phase - a.crank_phase;
                dp -= dp.round();
                frame.crank_phase = (a.crank_phase + dp * t.alpha).rem_euclid(1.0);
            }
            let instance = CYCLIST_INSTANCE_BASE.saturating_add(cs.id.min(8_191) as u16);
            let rider = cyclist::rider_pose(&frame, cs.rider.height_m, &cs.rider.figure);
            self.push_body(stat, &rider, outfit, instance, tag::RIDER);
            let tyre = linear([22, 22, 22]);
            let metal = linear([150, 150, 152]);
            let forward = {
                let (s, c) = (frame.yaw_rad as f32).sin_cos();
                Vec3::new(c, s, 0.0)
            };
            for (k, cap) in cyclist::bicycle(&frame, cs.rider.height_m).iter().enumerate() {
                // Frame tubes in the bicycle's colour; handlebar, saddle and cranks dark metal; wheels black.
                let albedo = match k {
                    0..=6 => *paint,
                    7 | 9 | 10 => metal * 0.4,
                    _ => tyre,
                };
                let sc = SceneCapsule {
                    a: stat.rel(cap.a),
                    b: stat.rel(cap.b),
                    radius_m: cap.radius_m as f32,
                };
                self.capsules.push(sc);
                let prim = self.mesh.prim(Prim {
                    material: Material::Body,
                    tag: tag::BICYCLE,
                    instance,
                    albedo,
                    albedo2: albedo,
                    normal: forward,
                    aux: (self.capsules.len() - 1) as u32,
                });
                self.mesh.capsule(&sc, prim);
            }
            // Lights (emissive at night): a white lamp under the handlebar, a red one under the saddle.
            let (sin, cos) = (frame.yaw_rad as f32).sin_cos();
            let fwd = Vec2::new(cos, sin);
            let centre = stat.rel(frame.pos);
            let hip_z = cyclist::hip_height_m(cs.rider.height_m) as f32;
            for (along, z, material, albedo) in [
                (0.43f32, hip_z - 0.12, Material::HeadLamp, linear([240, 240, 230])),
                (-0.36, hip_z - 0.16, Material::TailLamp, linear([200, 12, 12])),
            ] {
                let lamp = Prim {
                    material,
                    tag: tag::BICYCLE,
                    instance,
                    albedo,
                    albedo2: albedo,
                    normal: Vec3::Z,
                    aux: 0,
                };
                self.mesh.upright_box(
                    centre.truncate() + fwd * along,
                    frame.yaw_rad as f32,
                    Vec2::new(0.03, 0.035),
                    [centre.z + z - 0.035, centre.z + z + 0.035],
                    lamp,
                    lamp,
                );
            }
        }
    }

    /// Pushes a traffic vehicle (lamps lit; `light_bar`: an emergency vehicle's, see [`Mesh::car`]) and its head
    /// lamps' light.
    fn push_vehicle(&mut self, pos: Vec3, yaw: f32, paint: Vec3, instance: u16, light_bar: Option<bool>) {
        self.mesh.car(pos, yaw, paint, instance, CarLamps::Lit { light_bar });
        let l = VEHICLE_LENGTH_M as f32;
        let (s, c) = yaw.sin_cos();
        let fwd = Vec2::new(c, s);
        self.head_lamps.push((
            Vec3::new(pos.x + fwd.x * 0.5 * l, pos.y + fwd.y * 0.5 * l, pos.z + 0.7),
            Vec3::new(fwd.x, fwd.y, -0.05).normalize(),
        ));
    }

    fn push_body(&mut self, stat: &StaticScene, pose: &body::BodyPose, outfit: &Outfit, instance: u16, tag: u8) {
        let forward = {
            let (s, c) = (pose.yaw_rad as f32).sin_cos();
            Vec3::new(c, s, 0.0)
        };
        // The face looks where the head does (level).
        let gaze = Vec3::new(pose.gaze.x as f32, pose.gaze.y as f32, 0.0)
            .try_normalize()
            .unwrap_or(forward);
        for ((cap, &(material, albedo)), &patterned) in pose.capsules.iter().zip(&outfit.parts).zip(&outfit.patterned) {
            if !cap.is_present() {
                continue;
            }
            let sc = SceneCapsule {
                a: stat.rel(cap.a),
                b: stat.rel(cap.b),
                radius_m: cap.radius_m as f32,
            };
            self.capsules.push(sc);
            let (pattern, albedo2) = match material {
                Material::Head => (outfit.head_style, outfit.hair),
                _ if patterned => outfit.pattern,
                _ => (PATTERN_PLAIN, albedo),
            };
            let prim = self.mesh.prim(Prim {
                material,
                tag,
                instance,
                albedo,
                albedo2,
                normal: if material == Material::Head { gaze } else { forward },
                aux: body_aux(self.capsules.len() - 1, pattern),
            });
            self.mesh.capsule(&sc, prim);
        }
        if let (Some(u), Some(colour)) = (&pose.umbrella, outfit.umbrella) {
            self.push_umbrella(stat, u, colour, forward);
        }
    }

    /// An umbrella: a dark metal shaft and a canopy of `colour`, semantic `Dynamic` with instance 0 (not an
    /// annotated object: the holder's mask, box and keypoints leave it out).
    fn push_umbrella(&mut self, stat: &StaticScene, u: &body::Umbrella, colour: Vec3, forward: Vec3) {
        let part = |material, albedo, normal| Prim {
            material,
            tag: tag::DYNAMIC,
            instance: 0,
            albedo,
            albedo2: albedo,
            normal,
            aux: 0,
        };
        let shaft = self.mesh.prim(part(Material::Metal, linear([40, 40, 42]), forward));
        let (grip, top) = (stat.rel(u.grip), stat.rel(u.top));
        self.mesh.capsule(
            &SceneCapsule {
                a: grip,
                b: top,
                radius_m: 0.011,
            },
            shaft,
        );
        self.mesh.canopy(
            top,
            (top - grip).normalize_or(Vec3::Z),
            u.radius_m as f32,
            [body::Umbrella::PEAK_M as f32, body::Umbrella::RIM_DROP_M as f32],
            part(Material::Fabric, colour, Vec3::Z),
        );
    }
}
