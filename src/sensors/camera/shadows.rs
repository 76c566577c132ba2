//! Shadows and lights: the sun's shadow map (depth keys only, a square of [`SHADOW_HALF_M`] around the camera
//! along the view) and the choice of the street lamps and headlights that can light the frame.

use super::*;

/// Shadow map: resolution and half-size of the square it covers, metres.
pub(super) const SHADOW_PX: usize = 1024;

pub(super) const SHADOW_HALF_M: f32 = 60.0;

/// The orthographic sun camera of the shadow map.
#[derive(Clone, Copy, Debug)]
pub(super) struct SunView {
    pub(super) centre: Vec3,
    pub(super) u: Vec3,
    pub(super) v: Vec3,
    pub(super) dir: Vec3,
    pub(super) scale: f32,
}

impl SunView {
    /// Shadow-map pixel coordinates and depth towards the sun of a scene point.
    #[inline]
    pub(super) fn project_f32(&self, p: Vec3) -> Vec3 {
        let d = p - self.centre;
        Vec3::new(
            d.dot(self.u) * self.scale + SHADOW_PX as f32 * 0.5,
            d.dot(self.v) * self.scale + SHADOW_PX as f32 * 0.5,
            d.dot(self.dir),
        )
    }

    /// [`SunView::project_f32`] for the rasteriser.
    pub(super) fn project(&self, p: Vec3) -> DVec3 {
        self.project_f32(p).as_dvec3()
    }

    /// The sun's visibility at the lanes' scene points of a surface (1 lit, 0 in shadow) from the shadow map's
    /// depth keys, 2×2 percentage-closer filtered: the points are lifted off the surface by 5 cm and
    /// compared with a bias of 8 cm; texel centres at integers, bilinear between.
    #[inline(always)]
    pub(super) fn sunlit(&self, key: &[f32], p: V3, normal: Vec3) -> F {
        let d = p + V3::splat(normal * 0.05) - V3::splat(self.centre);
        let half = SHADOW_PX as f32 * 0.5;
        let x = d.dot_v(self.u) * self.scale + half - 0.5;
        let y = d.dot_v(self.v) * self.scale + half - 0.5;
        let depth = d.dot_v(self.dir) + 0.08;
        let (x0, y0) = (floor_int(x), floor_int(y));
        let (fx, fy) = (x - x0.round_float(), y - y0.round_float());
        let (xa, ya) = (x0.to_array(), y0.to_array());
        let last = (SHADOW_PX - 1) as i32;
        // The four texels' keys per lane (−∞, lit, off the map), then compared with the lanes' depths at
        // once: lit where the key is not beyond the point.
        let mut texels = [[f32::NEG_INFINITY; LANES]; 4];
        for i in 0..LANES {
            if xa[i] < 0 || ya[i] < 0 || xa[i] >= last || ya[i] >= last {
                continue;
            }
            let k = ya[i] as usize * SHADOW_PX + xa[i] as usize;
            // One bounds check for the four texels.
            let Some(q) = key.get(k..k + SHADOW_PX + 2) else {
                continue;
            };
            texels[0][i] = q[0];
            texels[1][i] = q[1];
            texels[2][i] = q[SHADOW_PX];
            texels[3][i] = q[SHADOW_PX + 1];
        }
        let c = texels.map(|k| F::new(k).simd_gt(depth).select(F::ZERO, F::ONE));
        let [l00, l10, l01, l11] = c;
        let a = l00 + (l10 - l00) * fx;
        let b = l01 + (l11 - l01) * fx;
        a + (b - a) * fy
    }
}

impl Renderer {
    pub(super) fn draw_shadows(&mut self, scene: &StaticScene, frame: &FrameScene, cam: Vec3, forward: Vec3) {
        if !self.light.shadows {
            self.sun = None;
            return;
        }
        let dir = self.light.sun_dir;
        let u = dir.any_orthonormal_vector();
        let v = dir.cross(u);
        let ahead = Vec3::new(forward.x, forward.y, 0.0).normalize_or_zero();
        let sun = SunView {
            centre: cam + ahead * (SHADOW_HALF_M * 0.7),
            u,
            v,
            dir,
            scale: SHADOW_PX as f32 / (2.0 * SHADOW_HALF_M),
        };
        self.shadow.clear(f32::NEG_INFINITY);
        let reach = SHADOW_HALF_M * 1.5 + 60.0;
        for cl in &scene.clusters {
            if cl.radius_m < 1000.0 && cl.centre.distance(sun.centre) - cl.radius_m <= reach {
                for tri in &scene.tris[cl.tris.start as usize..cl.tris.end as usize] {
                    let p = &scene.prims[tri.prim as usize];
                    // Ground surfaces receive shadows; casting them would only shadow themselves.
                    if matches!(
                        p.material,
                        Material::Road | Material::Sidewalk | Material::Terrain | Material::Curb
                    ) {
                        continue;
                    }
                    self.shadow.draw(tri.v.map(|q| sun.project(q)), tri.prim);
                }
            }
        }
        for tri in &frame.mesh.tris {
            // The far side of a closed mesh from the sun lies in the shadow of its near side.
            let [a, b, c] = tri.v;
            if tri.closed && (b - a).cross(c - a).dot(dir) < 0.0 {
                continue;
            }
            self.shadow.draw(tri.v.map(|q| sun.project(q)), tri.prim);
        }
        self.sun = Some(sun);
    }

    pub(super) fn choose_lights(&mut self, scene: &StaticScene, frame: &FrameScene, cam: Vec3, pose: &CameraPose) {
        self.lights.lamps.clear();
        self.lights.heads.clear();
        // Street lamps and headlights light the scene once the day has faded.
        if self.light.night < LIGHTS_ON_NIGHT {
            return;
        }
        nearest(&scene.lamps, |l| l.pos, cam, 90.0, 16, &mut self.nearby);
        self.lights
            .lamps
            .extend(self.nearby.iter().map(|&(_, i)| scene.lamps[i as usize].pos));
        // The ego's own headlights (under the camera), then the nearest traffic's.
        let fwd = pose.forward.as_vec3();
        let axis = Vec3::new(fwd.x, fwd.y, 0.0).normalize_or_zero();
        let left = Vec3::new(-axis.y, axis.x, 0.0);
        for side in [0.7f32, -0.7] {
            let lamp = cam + axis * 1.5 + left * (side - 0.3) - Vec3::Z * 0.7;
            self.lights.heads.push((lamp, axis));
        }
        nearest(&frame.head_lamps, |h| h.0, cam, 70.0, 6, &mut self.nearby);
        self.lights
            .heads
            .extend(self.nearby.iter().map(|&(_, i)| frame.head_lamps[i as usize]));
    }
}
