//! Resolve: each band's samples turned into pixels — labels (depth, semantic, instance) as point samples of the
//! visibility, runs of up to eight pixels of one primitive shaded at once, edge pixels' samples grouped by
//! primitive and shaded per sample (antialiasing).

use super::cull::TileLights;
use super::*;

/// Rows `y0..` of the images (as many as the slices hold).
pub(super) struct Band<'a> {
    pub(super) y0: usize,
    pub(super) rgb: &'a mut [u8],
    pub(super) depth_m: &'a mut [f32],
    pub(super) semantic: &'a mut [u8],
    pub(super) instance: &'a mut [u16],
}

/// Band buffers not in use (a clone starts without any).
#[derive(Debug, Default)]
pub(super) struct BandBuffers(Mutex<Vec<BandScratch>>);

/// What resolving a band needs besides the images: its visibility grid, its edge pixels and a row's scratch,
/// kept from band to band (one set per worker at a time) so that a frame allocates nothing. Every band
/// rewrites what it reads.
#[derive(Debug)]
pub(super) struct BandScratch {
    /// The band's visibility.
    pub(super) vis: BandVisibility,
    /// The samples of the band's edge pixels (four per pixel, in (row, column) order) and their shaded colours
    /// and tags, by the sample's index in that list; their groups by primitive, shaded group by group.
    pub(super) edges: Vec<Sample>,
    pub(super) groups: Grouper,
    pub(super) edge_colour: Vec<Vec3>,
    pub(super) edge_tag: Vec<u8>,
    /// The row's linear colours, one channel each (`LANES − 1` of slack for whole-vector stores; the tone map
    /// reads groups of four).
    pub(super) rgb: [Vec<f32>; 3],
    /// The lights each tile of the band can see.
    pub(super) tiles: TileLights,
}

impl BandScratch {
    /// Buffers for bands of a `w`-pixel-wide image.
    fn new(w: usize) -> BandScratch {
        BandScratch {
            vis: BandVisibility::new(w, BAND_ROWS),
            edges: Vec::new(),
            groups: Grouper::default(),
            edge_colour: Vec::new(),
            edge_tag: Vec::new(),
            rgb: [
                vec![0.0; w + LANES - 1],
                vec![0.0; w + LANES - 1],
                vec![0.0; w + LANES - 1],
            ],
            tiles: TileLights::default(),
        }
    }
}

impl Clone for BandBuffers {
    fn clone(&self) -> BandBuffers {
        BandBuffers::default()
    }
}

/// A row's depth labels from its pixels' first samples' keys: `1 / key` metres (the sky's key 0 gives the far
/// plane). `LANES` pixels at a time: an IEEE division per lane, the same values as one at a time.
pub(super) fn depth_labels(keys: &[f32], depth_m: &mut [f32]) {
    let (whole, rest) = depth_m.as_chunks_mut::<LANES>();
    let (whole_keys, rest_keys) = keys.as_chunks::<LANES>();
    let depth = |k: F| (F::ONE / k).fast_min(F::splat(SKY_DEPTH_M)).to_array();
    for (d, k) in whole.iter_mut().zip(whole_keys) {
        *d = depth(F::new(*k));
    }
    let last = depth(lanes_from(|i| rest_keys.get(i).copied().unwrap_or(1.0)));
    for (d, v) in rest.iter_mut().zip(last) {
        *d = v;
    }
}

/// A row's instance labels from its pixels' first samples' primitives (`instance_of` a primitive; the sky's
/// 0): eight pixels at a time where they all show the primitive before them (most of a row), one at a time
/// where it changes.
pub(super) fn instance_labels(prims: &[u32], instance: &mut [u16], instance_of: impl Fn(u32) -> u16) {
    let mut last = (EMPTY, 0u16);
    let (whole, rest) = instance.as_chunks_mut::<LANES>();
    let (whole_prims, rest_prims) = prims.as_chunks::<LANES>();
    let one_by_one = |ids: &mut [u16], prims: &[u32], last: &mut (u32, u16)| {
        for (i, &p) in ids.iter_mut().zip(prims) {
            if p != last.0 {
                *last = (p, if p == EMPTY { 0 } else { instance_of(p) });
            }
            *i = last.1;
        }
    };
    for (ids, prims) in whole.iter_mut().zip(whole_prims) {
        if prims.iter().all(|&p| p == last.0) {
            *ids = [last.1; LANES];
        } else {
            one_by_one(ids, prims, &mut last);
        }
    }
    one_by_one(rest, rest_prims, &mut last);
}

impl Renderer {
    /// Resolves the visibility buffer into the images, in bands of rows on the current rayon pool (each pixel
    /// is a pure function of the buffers, so the bytes do not depend on how the bands are spread).
    pub(super) fn resolve(
        &self,
        scene: &StaticScene,
        frame: &FrameScene,
        pose: &CameraPose,
        cam: Vec3,
        out: &mut CameraImages,
    ) {
        let w = self.camera.width_px as usize;
        let rows = BAND_ROWS;
        out.rgb
            .par_chunks_mut(w * 3 * rows)
            .zip(out.depth_m.par_chunks_mut(w * rows))
            .zip(out.semantic.par_chunks_mut(w * rows))
            .zip(out.instance.par_chunks_mut(w * rows))
            .enumerate()
            .for_each(|(band, (((rgb, depth_m), semantic), instance))| {
                let band = Band {
                    y0: band * rows,
                    rgb,
                    depth_m,
                    semantic,
                    instance,
                };
                self.resolve_band(scene, frame, pose, cam, band);
            });
    }

    pub(super) fn resolve_band(
        &self,
        scene: &StaticScene,
        frame: &FrameScene,
        pose: &CameraPose,
        cam: Vec3,
        out: Band,
    ) {
        let c = &self.camera;
        let w = c.width_px as usize;
        let y0 = out.y0;
        let h = out.depth_m.len() / w;
        // The shading context, given the lights to test where it is used.
        let base = ShadeContext {
            scene,
            frame,
            light: &self.light,
            noise: &self.noise,
            lamps: &[],
            heads: &[],
        };
        let view = View {
            cam,
            right: pose.right.as_vec3(),
            down: pose.down.as_vec3(),
            fwd: pose.forward.as_vec3(),
            cx: c.width_px as f32 * 0.5,
            cy: c.height_px as f32 * 0.5,
            inv_f: 1.0 / c.focal_px as f32,
        };
        let inv_ss = 1.0 / SS as f32;
        let mut taken = self.band_buffers.0.lock().map_or(None, |mut b| b.pop());
        let BandScratch {
            vis,
            edges,
            groups,
            edge_colour,
            edge_tag,
            rgb,
            tiles,
        } = taken.get_or_insert_with(|| BandScratch::new(w));
        vis.draw(&self.tris, &self.bins[y0 / BAND_ROWS], y0, h, c.height_px as usize);
        tiles.cull(&self.lights, vis, &view, y0, h);
        // The edge pixels' samples, listed and shaded up to `LANES` of one primitive at a time (over the band, so
        // that the lanes fill).
        edges.clear();
        for row in 0..h {
            let y = y0 + row;
            for e in vis.edge_rows[row]..vis.edge_rows[row + 1] {
                let x = vis.edge_x[e] as usize;
                if vis.prim[row * w + x] != EDGE {
                    continue;
                }
                for (i, (prim, key)) in vis.edge_prim[e].into_iter().zip(vis.edge_key[e]).enumerate() {
                    let (sx, sy) = ((i % SS) as f32, (i / SS) as f32);
                    edges.push(Sample {
                        prim,
                        key,
                        u: x as f32 + (sx + 0.5) * inv_ss,
                        v: y as f32 + (sy + 0.5) * inv_ss,
                    });
                }
            }
        }
        groups.group(edges.iter().map(|s| s.prim));
        edge_colour.resize(edges.len(), Vec3::ZERO);
        edge_tag.resize(edges.len(), 0);
        let (lamps, heads) = tiles.band(&self.lights);
        let band_ctx = ShadeContext { lamps, heads, ..base };
        for group in groups.groups() {
            for chunk in group.chunks(LANES) {
                let at = |i: usize| &edges[chunk[i.min(chunk.len() - 1)] as usize];
                let lane = |f: fn(&Sample) -> f32| lanes_from(|i| f(at(i)));
                let (colour, tags) = self.shade(
                    &band_ctx,
                    &view,
                    at(0).prim,
                    lane(|s| s.key),
                    lane(|s| s.u),
                    lane(|s| s.v),
                );
                for (&o, (c, t)) in chunk.iter().zip(colour.lanes().into_iter().zip(tags)) {
                    edge_colour[o as usize] = c;
                    edge_tag[o as usize] = t;
                }
            }
        }
        // The edge pixels' samples in `edge_colour`, in (row, column) order.
        let mut e = 0;
        for row in 0..h {
            let y = y0 + row;
            let v_centre = F::splat(y as f32 + 0.5);
            let labels = row * w..(row + 1) * w;
            let (grid_prim, grid_key) = (&vis.grid.prim[labels.clone()], &vis.grid.key[labels.clone()]);
            // Labels: the first sample's depth (the sky's key 0 gives the far plane) and instance.
            depth_labels(grid_key, &mut out.depth_m[labels.clone()]);
            instance_labels(grid_prim, &mut out.instance[labels.clone()], |p| {
                frame.prim(scene, p).instance
            });
            let row_prim = &vis.prim[labels.clone()];
            let row_key = &vis.key[labels.clone()];
            // Pixels whose samples see one primitive: shaded at their centres, up to `LANES` neighbours of one
            // primitive at a time.
            let semantic = &mut out.semantic[labels];
            let mut x = 0;
            while x < w {
                let prim = row_prim[x];
                if prim == EDGE {
                    x += 1;
                    continue;
                }
                let mut end = x + 1;
                while end < w && end - x < LANES && row_prim[end] == prim {
                    end += 1;
                }
                let n = end - x;
                let key = lanes_from(|i| row_key[x + i.min(n - 1)]);
                let u = F::splat(x as f32 + 0.5) + lanes_from(|i| i as f32);
                let (lamps, heads) = tiles.run(&self.lights, x, end);
                let ctx = ShadeContext { lamps, heads, ..base };
                let (colour, tags) = self.shade(&ctx, &view, prim, key, u, v_centre);
                // All lanes are stored: those past `n` are overwritten by the pixels they fall on.
                for (channel, lanes) in rgb.iter_mut().zip([colour.x, colour.y, colour.z]) {
                    channel[x..x + LANES].copy_from_slice(&lanes.to_array());
                }
                match semantic.get_mut(x..x + LANES) {
                    Some(all) => all.copy_from_slice(&tags),
                    None => semantic[x..end].copy_from_slice(&tags[..n]),
                }
                x = end;
            }
            // Edge pixels (candidates whose samples differ): the mean of their samples' colours, the first
            // sample's tag.
            let candidates = &vis.edge_x[vis.edge_rows[row]..vis.edge_rows[row + 1]];
            for x in candidates.iter().map(|&x| x as usize).filter(|&x| row_prim[x] == EDGE) {
                let c = &edge_colour[e..e + 4];
                let colour = (c[0] + c[1] + c[2] + c[3]) * 0.25;
                for (channel, v) in rgb.iter_mut().zip(colour.to_array()) {
                    channel[x] = v;
                }
                semantic[x] = edge_tag[e];
                e += 4;
            }
            if let Some(vignette) = &self.vignette {
                vignette.dim_row(y, rgb);
            }
            let luts = [&*self.luts[0], &*self.luts[1], &*self.luts[2]];
            tone_map(rgb, luts, &mut out.rgb[row * w * 3..(row + 1) * w * 3]);
        }
        self.draw_streaks(y0, out.rgb);
        if let (Ok(mut pool), Some(scratch)) = (self.band_buffers.0.lock(), taken) {
            pool.push(scratch);
        }
    }

    /// The fogged colours and the semantic tags of `LANES` samples of one primitive (or of the sky) at pixel
    /// coordinates `(u, v)` with depth keys `key`.
    #[inline(always)]
    pub(super) fn shade(&self, ctx: &ShadeContext, view: &View, prim: u32, key: F, u: F, v: F) -> (V3, [u8; LANES]) {
        let su = (u - view.cx) * view.inv_f;
        let sv = (v - view.cy) * view.inv_f;
        let ray = V3::splat(view.fwd) + V3::splat(view.right).scale(su) + V3::splat(view.down).scale(sv);
        if prim == EMPTY {
            if let Some(fog) = self.fogged_sky {
                return (V3::splat(fog), [tag::SKY; LANES]);
            }
            let dir = ray.scale(F::ONE / ray.length_squared().sqrt());
            let sky = self.light.sky(dir);
            return (
                shade::fog(&self.light, sky, F::splat(light::SKY_FOG_M)),
                [tag::SKY; LANES],
            );
        }
        let prim: &Prim = ctx.frame.prim(ctx.scene, prim);
        let z = F::ONE / key;
        let p = V3::splat(view.cam) + ray.scale(z);
        let ray_len = ray.length_squared().sqrt();
        // A flat surface turned away from the sun gets none of it whether in shadow or not (bodies shade
        // with per-point normals).
        let away =
            prim.normal.dot(self.light.sun_dir) <= 0.0 && !matches!(prim.material, Material::Body | Material::Head);
        let shadow = match &self.sun {
            Some(sun) if !away => sun.sunlit(&self.shadow.key, p, prim.normal),
            _ => F::ONE,
        };
        let pts = shade::Points {
            p,
            ray,
            ray_len,
            shadow,
            depth_m: z,
        };
        let (colour, semantic) = shade::surface(ctx, prim, &pts);
        (shade::fog(&self.light, colour, ray_len * z), semantic)
    }
}
