//! The annotator box: the tight box of the projected body redrawn as a person draws it in JAAD or PIE — looser
//! than the silhouette (a margin, and never narrower than a drawn aspect plus a few pixels, so small boxes are
//! relatively wider), on whole pixels, with a little noise from frame to frame (`annotations.annotator_box`). A
//! pure function of (clip seed, pedestrian, frame): the per-pedestrian draws and the per-frame noise come from
//! SplitMix64 of those, so any thread computes the same.
//!
//! With `keyframe_every` above one frame, [`keyframe_track`] redraws a pedestrian's boxes as an annotation tool
//! does between a person's keyframes: the keyframes' boxes as above, and between them the corner, width and
//! height interpolated linearly, each on whole pixels (JAAD's boxes hold their width and height from one frame
//! to the next in 56 % and 52 % of frames: train + val, 1,604 tracks).

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
    let w_drawn = ((x1 - x0).max(0.0) + margin * h).max(min_aspect * h_drawn + params.width_pad_px);
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

/// One pedestrian's annotator boxes drawn at keyframes and interpolated between them: `frames` (ascending) and
/// `tight_px` (its tight boxes) are the pedestrian's annotated frames. Each run of consecutive frames starts
/// and ends on a keyframe; within it, gaps are drawn from `keyframe_every` per pedestrian and keyframe. The
/// keyframes' boxes are [`annotator_box`]'s (before rounding); between them `x_min`, `y_min`, the width and the
/// height are interpolated linearly and each rounded (with `whole_pixels`), so `x_max = x_min + width`.
pub fn keyframe_track(
    frames: &[u32],
    tight_px: &[[f64; 4]],
    params: &AnnotatorBox,
    (clip_seed, pedestrian): (u64, u32),
    (width_px, height_px): (u32, u32),
) -> Vec<[f64; 4]> {
    let exact = AnnotatorBox {
        whole_pixels: false,
        ..params.clone()
    };
    let who = splitmix64(clip_seed ^ 0x6b65_7966 ^ splitmix64(u64::from(pedestrian)));
    let (lo, hi) = (params.keyframe_every.min().max(1), params.keyframe_every.max().max(1));
    let drawn = |i: usize| -> [f64; 4] {
        let [x0, y0, x1, y1] = annotator_box(
            tight_px[i],
            &exact,
            (clip_seed, pedestrian, frames[i]),
            (width_px, height_px),
        );
        [x0, y0, x1 - x0, y1 - y0]
    };
    let mut out = Vec::with_capacity(frames.len());
    let mut start = 0;
    while start < frames.len() {
        // The run of consecutive frames from `start`.
        let mut end = start + 1;
        while end < frames.len() && frames[end] == frames[end - 1] + 1 {
            end += 1;
        }
        let mut key = start;
        let mut key_box = drawn(key);
        out.push(key_box);
        while key + 1 < end {
            let h = splitmix64(who ^ splitmix64(u64::from(frames[key]) + 1));
            let gap = lo + (unit(h) * f64::from(hi - lo + 1)) as u32;
            let next = (key + gap as usize).min(end - 1);
            let next_box = drawn(next);
            for i in key + 1..=next {
                let t = (i - key) as f64 / (next - key) as f64;
                out.push(std::array::from_fn(|j| key_box[j] + (next_box[j] - key_box[j]) * t));
            }
            key = next;
            key_box = next_box;
        }
        start = end;
    }
    let (w, h) = (f64::from(width_px), f64::from(height_px));
    out.into_iter()
        .map(|b| {
            let b = if params.whole_pixels { b.map(f64::round) } else { b };
            [
                b[0].clamp(0.0, w),
                b[1].clamp(0.0, h),
                (b[0] + b[2]).clamp(0.0, w),
                (b[1] + b[3]).clamp(0.0, h),
            ]
        })
        .collect()
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
            width_pad_px: 0.0,
            noise_px: 0.0,
            whole_pixels: true,
            keyframe_every: crate::spec::types::CountRange(1, 1),
        };
        let b = annotator_box([100.2, 200.0, 120.2, 300.0], &params, (7, 3, 0), (1920, 1080));
        // Height 100 → 110 (5 above, 5 below); width max(20 + 10, 0.4 × 110 = 44) = 44 around x 110.2.
        assert_eq!(b, [88.0, 195.0, 132.0, 305.0]);
    }

    #[test]
    fn the_width_pad_widens_small_boxes_relatively_more_than_large_ones() {
        let params = AnnotatorBox {
            margin_frac: Range(0.0, 0.0),
            min_aspect: Range(0.4, 0.4),
            width_pad_px: 4.0,
            noise_px: 0.0,
            whole_pixels: false,
            keyframe_every: crate::spec::types::CountRange(1, 1),
        };
        // Narrow silhouettes 40 and 400 px tall: the narrowest width is 0.4 × height + 4 px.
        let small = annotator_box([100.0, 200.0, 105.0, 240.0], &params, (7, 3, 0), (1920, 1080));
        let large = annotator_box([100.0, 200.0, 150.0, 600.0], &params, (7, 3, 0), (1920, 1080));
        assert_eq!(small, [102.5 - 10.0, 200.0, 102.5 + 10.0, 240.0]);
        assert_eq!(large, [125.0 - 82.0, 200.0, 125.0 + 82.0, 600.0]);
        // A silhouette wider than that keeps its own width: the pad widens only the narrowest box.
        let wide = annotator_box([100.0, 200.0, 130.0, 240.0], &params, (7, 3, 0), (1920, 1080));
        assert_eq!(wide[2] - wide[0], 30.0);
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

    #[test]
    fn keyframes_hold_the_size_between_them_and_follow_the_tight_box_at_them() {
        let params = AnnotatorBox {
            margin_frac: Range(0.0, 0.0),
            min_aspect: Range(0.0, 0.0),
            width_pad_px: 0.0,
            noise_px: 0.0,
            whole_pixels: true,
            keyframe_every: crate::spec::types::CountRange(10, 10),
        };
        // A box walking right 3.3 px a frame and growing 0.13 px a frame, frames 0–24 and (a gap) 40–44.
        let frames: Vec<u32> = (0..25).chain(40..45).collect();
        let tight: Vec<[f64; 4]> = frames
            .iter()
            .map(|&f| {
                let (x, g) = (100.0 + 3.3 * f64::from(f), 0.13 * f64::from(f));
                [x, 200.0 - g, x + 20.0 + 0.3 * g, 260.0]
            })
            .collect();
        let got = keyframe_track(&frames, &tight, &params, (7, 1), (1920, 1080));
        assert_eq!(got.len(), frames.len());
        // Keyframes (0, 10, 20, the run's end 24, the next run's start 40 and end 44) equal the tight box rounded.
        for i in [0, 10, 20, 24, 25, 29] {
            let [x0, y0, x1, y1] = tight[i];
            let want = [
                x0.round(),
                y0.round(),
                x0.round() + (x1 - x0).round(),
                y0.round() + (y1 - y0).round(),
            ];
            assert_eq!(got[i], want, "frame {}", frames[i]);
        }
        // Between keyframes the width and height change in whole-pixel steps and mostly hold.
        let held = got
            .windows(2)
            .filter(|w| (w[1][2] - w[1][0]) == (w[0][2] - w[0][0]) && (w[1][3] - w[1][1]) == (w[0][3] - w[0][1]))
            .count();
        assert!(held >= 15, "{held} of {} frame pairs hold the size", got.len() - 1);
        assert!(got.iter().flatten().all(|v| v.fract() == 0.0));
        // Every frame a keyframe: the per-frame boxes themselves.
        let every = AnnotatorBox {
            keyframe_every: crate::spec::types::CountRange(1, 1),
            ..params.clone()
        };
        let per_frame = keyframe_track(&frames, &tight, &every, (7, 1), (1920, 1080));
        for (i, b) in per_frame.iter().enumerate() {
            let one = annotator_box(
                tight[i],
                &AnnotatorBox {
                    whole_pixels: false,
                    ..every.clone()
                },
                (7, 1, frames[i]),
                (1920, 1080),
            );
            let [x0, y0, x1, y1] = one;
            let want = [
                x0.round(),
                y0.round(),
                x0.round() + (x1 - x0).round(),
                y0.round() + (y1 - y0).round(),
            ];
            assert_eq!(*b, want, "frame {}", frames[i]);
        }
    }
}
