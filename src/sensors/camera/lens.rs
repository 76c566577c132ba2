//! The lens: a distorting camera's frame is drawn by a pinhole of the same focal length on a canvas large enough
//! to hold every pixel's undistorted position, then resampled through the lens. RGB is interpolated
//! (bilinear, per channel); the label streams (depth, semantic, instance) take the canvas pixel nearest to each
//! pixel's label sample, so they stay point samples of the scene and agree with each other.

use glam::DVec2;
use rayon::prelude::*;

use super::CameraImages;
use super::round::floor_f32;
use crate::sim::rig::Camera;
use crate::util::lens::Lens;

/// Pixels of canvas kept beyond the farthest undistorted pixel on each side.
const MARGIN_PX: f64 = 2.0;

/// A distorting camera's canvas and, per image pixel, where its centre and its label sample lie on the canvas.
#[derive(Clone, Debug)]
pub(super) struct LensWarp {
    /// The pinhole that draws the canvas (same focal length; the image's centre at the canvas's centre).
    pub(super) canvas_camera: Camera,
    /// The canvas, drawn each frame.
    pub(super) canvas: CameraImages,
    /// Per image pixel (row-major): its centre's position on the canvas, pixels from the canvas's corner.
    centre_on_canvas: Vec<[f32; 2]>,
    /// Per image pixel: the canvas pixel whose label sample is nearest its own label sample's position.
    label_source: Vec<u32>,
}

impl LensWarp {
    /// The warp of a distorting camera (`None` for a pinhole, or a lens that cannot be inverted over the
    /// image, which the spec's validation rejects).
    pub(super) fn new(camera: &Camera) -> Option<LensWarp> {
        if camera.lens.is_pinhole() {
            return None;
        }
        let lens = camera.lens;
        let (w, h) = (camera.width_px as usize, camera.height_px as usize);
        let (half_w, half_h) = (f64::from(camera.width_px) * 0.5, f64::from(camera.height_px) * 0.5);
        let f = camera.focal_px;
        // Image point → offset from the principal point on the pinhole's image plane, pixels.
        let undistorted = |p: DVec2| -> Option<DVec2> {
            let (x, y) = lens.undistort((p.x - half_w) / f, (p.y - half_h) / f)?;
            Some(DVec2::new(x * f, y * f))
        };
        // The canvas covers every pixel's undistorted corners: the border's are the extremes of a lens that
        // grows monotonically over the image (as validated), and the corners of the image are among them.
        let mut reach = DVec2::ZERO;
        let border = (0..=w)
            .flat_map(|x| [(x, 0), (x, h)])
            .chain((0..=h).flat_map(|y| [(0, y), (w, y)]));
        for (x, y) in border {
            let p = undistorted(DVec2::new(x as f64, y as f64))?;
            reach = reach.max(p.abs());
        }
        let margin_x = (reach.x - half_w + MARGIN_PX).max(0.0).ceil() as u32;
        let margin_y = (reach.y - half_h + MARGIN_PX).max(0.0).ceil() as u32;
        let canvas_camera = Camera {
            width_px: camera.width_px + 2 * margin_x,
            height_px: camera.height_px + 2 * margin_y,
            lens: Lens::new([0.0; 5]),
            ..*camera
        };
        let (cw, ch) = (canvas_camera.width_px as usize, canvas_camera.height_px as usize);
        let (cx, cy) = (
            f64::from(canvas_camera.width_px) * 0.5,
            f64::from(canvas_camera.height_px) * 0.5,
        );
        let mut centre_on_canvas = Vec::with_capacity(w * h);
        let mut label_source = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let centre = undistorted(DVec2::new(x as f64 + 0.5, y as f64 + 0.5))?;
                centre_on_canvas.push([(centre.x + cx) as f32, (centre.y + cy) as f32]);
                // Label samples sit at (x + 0.25, y + 0.25) of their pixel, on the canvas as in the image.
                let sample = undistorted(DVec2::new(x as f64 + 0.25, y as f64 + 0.25))?;
                let sx = ((sample.x + cx - 0.25).round() as i64).clamp(0, cw as i64 - 1) as usize;
                let sy = ((sample.y + cy - 0.25).round() as i64).clamp(0, ch as i64 - 1) as usize;
                label_source.push((sy * cw + sx) as u32);
            }
        }
        Some(LensWarp {
            canvas_camera,
            canvas: CameraImages::default(),
            centre_on_canvas,
            label_source,
        })
    }

    /// Resamples the drawn canvas into the image `out` (already sized), rows in parallel (each pixel is a pure
    /// function of the canvas).
    pub(super) fn apply(&self, out: &mut CameraImages) {
        let (w, canvas) = (out.width, &self.canvas);
        let (cw, ch) = (canvas.width, canvas.height);
        out.rgb
            .par_chunks_mut(3 * w)
            .zip(out.depth_m.par_chunks_mut(w))
            .zip(out.semantic.par_chunks_mut(w))
            .zip(out.instance.par_chunks_mut(w))
            .enumerate()
            .for_each(|(y, (((rgb, depth), semantic), instance))| {
                let row = y * w..(y + 1) * w;
                for (x, (&[u, v], &src)) in self.centre_on_canvas[row.clone()]
                    .iter()
                    .zip(&self.label_source[row])
                    .enumerate()
                {
                    let src = src as usize;
                    depth[x] = canvas.depth_m[src];
                    semantic[x] = canvas.semantic[src];
                    instance[x] = canvas.instance[src];
                    // Bilinear between the four canvas pixels around the centre (pixel centres at +0.5).
                    let (fu, fv) = (u - 0.5, v - 0.5);
                    let (x0, y0) = (floor_f32(fu), floor_f32(fv));
                    let (tx, ty) = (fu - x0, fv - y0);
                    let clamp = |i: f32, n: usize| (i.max(0.0) as usize).min(n - 1);
                    let (xa, xb) = (clamp(x0, cw), clamp(x0 + 1.0, cw));
                    let (ya, yb) = (clamp(y0, ch), clamp(y0 + 1.0, ch));
                    for c in 0..3 {
                        let at = |xx: usize, yy: usize| f32::from(canvas.rgb[(yy * cw + xx) * 3 + c]);
                        let top = at(xa, ya) * (1.0 - tx) + at(xb, ya) * tx;
                        let bottom = at(xa, yb) * (1.0 - tx) + at(xb, yb) * tx;
                        rgb[x * 3 + c] = (top * (1.0 - ty) + bottom * ty + 0.5) as u8;
                    }
                }
            });
    }
}
