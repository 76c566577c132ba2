//! A car's mesh ([`Mesh::car`]): lower body, cabin, wheels and lamps, as boxes. One geometry for the traffic
//! vehicles of a frame ([`FrameScene`]) and the parked cars of the static scene ([`StaticScene`]), the size of
//! the simulation's vehicle footprint (`sim::VEHICLE_*`), which the occlusion labels test against too.

use super::*;

/// A car's lamps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CarLamps {
    /// A running car: head lamps and tail lamps glow (at night they light the road); `light_bar`: an emergency
    /// vehicle's bar on the roof, with its red half lit (`true`) or its blue half.
    Lit {
        /// The emergency light bar, if any.
        light_bar: Option<bool>,
    },
    /// A parked car: its lamps are dark glass.
    Off,
}

/// How much shorter than the footprint a car's body is at each end, metres: its lamps (6 cm deep) stand 3 cm out of it,
/// to 5 mm inside the footprint.
const LAMP_DEPTH_M: f32 = 0.035;
/// How far inside its footprint's sides and height a car's mesh stays, metres.
const INSET_M: f32 = 0.005;

impl Mesh {
    /// Adds a car standing on `pos` (ground centre, scene-relative) facing `yaw_rad`, painted `paint` (linear),
    /// every primitive tagged [`tag::CAR`] with `instance`.
    pub fn car(&mut self, pos: Vec3, yaw_rad: f32, paint: Vec3, instance: u16, lamps: CarLamps) {
        // 5 mm inside the footprint's sides and height, so that rounding (the scene is single precision) leaves no
        // surface outside the box.
        let (l, w, h) = (
            VEHICLE_LENGTH_M as f32,
            VEHICLE_WIDTH_M as f32 - 2.0 * INSET_M,
            VEHICLE_HEIGHT_M as f32 - INSET_M,
        );
        let (s, c) = yaw_rad.sin_cos();
        let fwd = Vec2::new(c, s);
        let centre = pos.truncate();
        let base = pos.z;
        let car = |material, albedo| Prim {
            material,
            tag: tag::CAR,
            instance,
            albedo,
            albedo2: albedo,
            normal: Vec3::Z,
            aux: 0,
        };
        let body = car(Material::CarPaint, paint);
        let glass = car(Material::CarGlass, linear([14, 16, 20]));
        let tyre = car(Material::Tyre, linear([20, 20, 20]));
        // Lower body, cabin (glass sides, painted roof), four wheels. The body stops [`LAMP_DEPTH_M`] short of the
        // footprint's ends, where the lamps stand out of it: the whole car stays inside its footprint (a box of
        // the `parked_cars` or `vehicles` table holds every LiDAR point of it).
        self.upright_box(
            centre,
            yaw_rad,
            Vec2::new(l * 0.5 - LAMP_DEPTH_M, w * 0.5),
            [base + 0.3, base + 0.55 * h + 0.15],
            body,
            body,
        );
        self.upright_box(
            centre - fwd * (0.08 * l),
            yaw_rad,
            Vec2::new(l * 0.26, w * 0.45),
            [base + 0.55 * h + 0.15, base + h],
            glass,
            body,
        );
        for (fx, sy) in [(0.32f32, 1.0f32), (0.32, -1.0), (-0.32, 1.0), (-0.32, -1.0)] {
            let wc = centre + fwd * (fx * l) + fwd.perp() * (sy * (w * 0.5 - 0.14));
            self.upright_box(wc, yaw_rad, Vec2::new(0.33, 0.13), [base, base + 0.64], tyre, tyre);
        }
        // Lamps: small boxes standing out of the front and rear faces to 5 mm inside the footprint's ends; a parked
        // car's are dark.
        let lit = matches!(lamps, CarLamps::Lit { .. });
        for (fx, mat, albedo) in [
            (0.5f32, Material::HeadLamp, linear([240, 240, 230])),
            (-0.5, Material::TailLamp, linear([160, 10, 10])),
        ] {
            let lamp = if lit {
                car(mat, albedo)
            } else {
                car(Material::CarGlass, albedo * 0.3)
            };
            for sy in [1.0f32, -1.0] {
                let lc = centre + fwd * (fx * l - fx.signum() * LAMP_DEPTH_M) + fwd.perp() * (sy * w * 0.33);
                self.upright_box(
                    lc,
                    yaw_rad,
                    Vec2::new(0.03, 0.16),
                    [base + 0.6, base + 0.75],
                    lamp,
                    lamp,
                );
            }
        }
        if let CarLamps::Lit {
            light_bar: Some(red_lit),
        } = lamps
        {
            let roof = centre - fwd * (0.08 * l);
            for (sy, lit, colour) in [(1.0f32, red_lit, [255, 20, 20]), (-1.0, !red_lit, [30, 60, 255])] {
                let albedo = if lit { linear(colour) } else { linear(colour) * 0.15 };
                let lamp = car(Material::Beacon, albedo);
                self.upright_box(
                    roof + fwd.perp() * (sy * 0.3),
                    yaw_rad,
                    Vec2::new(0.12, 0.28),
                    [base + h, base + h + 0.14],
                    lamp,
                    lamp,
                );
            }
        }
    }
}
