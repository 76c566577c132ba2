//! The annotator box: the tight box of the projected body redrawn as a person draws it in JAAD or PIE — looser
//! than the silhouette (a margin, and never narrower than a drawn aspect), on whole pixels, with a little noise
//! from frame to frame (`annotations.annotator_box`). A pure function of (clip seed, pedestrian, frame): the
//! per-pedestrian draws and the per-frame noise come from SplitMix64 of those, so any thread computes the same.

use crate::spec::types::AnnotatorBox;
use crate::util::mix::splitmix64;

/// A uniform draw in [0, 1) from a 64-bit hash.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// A standard normal draw from two hashes (Box–Muller).
fn normal(a: u64, b: u64) -> f64 {
    let u1 = unit(a).max(1e-12);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * unit(b)).cos()
}

/// The annotator box of pedestrian `pedestrian` in `frame` of the clip seeded `clip_seed`, from its tight box
/// `[x_min, y_min, x_max, y_max]` (pixels) in an image of `width_px` × `height_px`.
pub fn annotator_box(
    tight_px: [f64; 4],
    params: &AnnotatorBox,
    (clip_seed, pedestrian, frame): (u64, u32, u32),
    (width_px, height_px): (u32, u32),
) -> [f64; 4] {
    let who = splitmix64(clip_seed ^ 0xa770_7a70 ^ splitmix64(u64::from(pedestrian)));
    let draw = |salt: u64, lo: f64, hi: f64| lo + (hi - lo) * unit(splitmix64(who ^ salt));
    let margin = draw(1, params.margin_frac.min(), params.margin_frac.max());
    let min_aspect = draw(2, params.min_aspect.min(), params.min_aspect.max());
    let [x0, y0, x1, y1] = tight_px;
    let h = (y1 - y0).max(0.0);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let h_drawn = h * (1.0 + margin);
    let w_drawn = ((x1 - x0).max(0.0) + margin * h).max(min_aspect * h_drawn);
    let at = splitmix64(who ^ splitmix64(u64::from(frame) + 1));
    let noise = |edge: u64| params.noise_px * normal(splitmix64(at ^ edge), splitmix64(at ^ (edge + 16)));
    let mut b = [
        cx - 0.5 * w_drawn + noise(1),
        cy - 0.5 * h_drawn + noise(2),
        cx + 0.5 * w_drawn + noise(3),
        cy + 0.5 * h_drawn + noise(4),
    ];
    if params.whole_pixels {
        b = b.map(f64::round);
    }
    let (w, hh) = (f64::from(width_px), f64::from(height_px));
    [
        b[0].clamp(0.0, w),
        b[1].clamp(0.0, hh),
        b[2].clamp(0.0, w),
        b[3].clamp(0.0, hh),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::types::Range;

    #[test]
    fn a_narrow_silhouette_gets_a_box_of_the_drawn_aspect_on_whole_pixels_around_its_centre() {
        let params = AnnotatorBox {
            margin_frac: Range(0.1, 0.1),
            min_aspect: Range(0.4, 0.4),
            noise_px: 0.0,
            whole_pixels: true,
        };
        let b = annotator_box([100.2, 200.0, 120.2, 300.0], &params, (7, 3, 0), (1920, 1080));
        // Height 100 → 110 (5 above, 5 below); width max(20 + 10, 0.4 × 110 = 44) = 44 around x 110.2.
        assert_eq!(b, [88.0, 195.0, 132.0, 305.0]);
    }

    #[test]
    fn noise_is_a_pure_function_of_clip_pedestrian_and_frame_with_the_asked_spread() {
        let params = AnnotatorBox {
            whole_pixels: false,
            ..AnnotatorBox::default()
        };
        let tight = [500.0, 400.0, 540.0, 600.0];
        let at = |f| annotator_box(tight, &params, (11, 2, f), (1920, 1080));
        assert_eq!(at(5), at(5));
        assert_ne!(at(5), at(6));
        // The left edge's spread over many frames is the asked standard deviation.
        let xs: Vec<f64> = (0..4000).map(|f| at(f)[0]).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64).sqrt();
        assert!((sd - params.noise_px).abs() < 0.05, "sd {sd}");
        // Pedestrians draw their own margin and aspect: without noise, a narrow silhouette's box width differs.
        let still = AnnotatorBox {
            noise_px: 0.0,
            ..params
        };
        let width = |p| {
            let b = annotator_box(tight, &still, (11, p, 5), (1920, 1080));
            b[2] - b[0]
        };
        assert_ne!(width(2), width(3));
    }
}
