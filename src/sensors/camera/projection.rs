//! Projection: a frame's triangles (static scene and frame scene) taken to the camera's optical frame, clipped
//! at the near plane, set up once and binned by bands of rows ([`BAND_ROWS`]), then each band's sparse
//! visibility drawn ([`BandVisibility`](super::raster::BandVisibility)) on the rayon pool.

use super::*;

impl Renderer {
    pub(super) fn draw_visibility(&mut self, scene: &StaticScene, frame: &FrameScene, optical_from_scene: &DAffine3) {
        let c = &self.camera;
        let m = optical_from_scene.matrix3.as_mat3();
        let t = optical_from_scene.translation.as_vec3();
        let (f, cx, cy) = (c.focal_px as f32, c.width_px as f32 * 0.5, c.height_px as f32 * 0.5);
        let ss = SS as f32;
        // Frustum side slopes (|x| ≤ z·sx, |y| ≤ z·sy) with the corners' secants for the sphere test.
        let (sx, sy) = (cx / f, cy / f);
        let (kx, ky) = ((1.0 + sx * sx).sqrt(), (1.0 + sy * sy).sqrt());
        let (sw, sh) = (c.width_px as usize * SS, c.height_px as usize * SS);
        self.tris.clear();
        let tris = &mut self.tris;
        let mut draw = |tri: &crate::sensors::scene::Tri| {
            let v = tri.v.map(|p| m * p + t);
            // Behind the near plane, or the far side of a closed mesh (seen from the camera at the origin).
            if v.iter().all(|p| p.z < NEAR_M) || (tri.closed && (v[1] - v[0]).cross(v[2] - v[0]).dot(v[0]) > 0.0) {
                return;
            }
            let mut poly = [Vec3::ZERO; 4];
            let n = clip_near(v, NEAR_M, &mut poly);
            let proj = |p: Vec3| {
                let inv = 1.0 / p.z;
                DVec3::new(
                    f64::from((f * p.x * inv + cx) * ss),
                    f64::from((f * p.y * inv + cy) * ss),
                    f64::from(inv),
                )
            };
            for k in 1..n.saturating_sub(1) {
                let v = [proj(poly[0]), proj(poly[k]), proj(poly[k + 1])];
                tris.extend(Setup::new(v, tri.prim, sw, sh));
            }
        };
        for cl in &scene.clusters {
            let o = m * cl.centre + t;
            let r = cl.radius_m;
            let visible = o.z + r >= NEAR_M
                && o.x - r * kx <= o.z * sx
                && -o.x - r * kx <= o.z * sx
                && o.y - r * ky <= o.z * sy
                && -o.y - r * ky <= o.z * sy
                && (o.length() - r <= FAR_M || r > 1000.0);
            if visible {
                for tri in &scene.tris[cl.tris.start as usize..cl.tris.end as usize] {
                    draw(tri);
                }
            }
        }
        for tri in &frame.mesh.tris {
            draw(tri);
        }
        // Each triangle into the bands of rows it reaches, in drawing order: a band's sample rows and the
        // first of the band below (its grid's last row).
        let band_samples = BAND_ROWS * SS;
        for bin in &mut self.bins {
            bin.clear();
        }
        let last_bin = self.bins.len() - 1;
        for (i, t) in self.tris.iter().enumerate() {
            let first = (t.row0 as usize).saturating_sub(band_samples).div_ceil(band_samples);
            let last = (t.row1 as usize / band_samples).min(last_bin);
            for bin in &mut self.bins[first..=last] {
                bin.push(i as u32);
            }
        }
    }
}
