//! What `pedsynth calibrate` measures in real (or generated) annotations: the camera's horizon and height from
//! box bottoms against box heights, PedestrianActionBenchmark's observation windows and six quantities of each,
//! how well each quantity tells crossers from non-crossers (the cue table), the ego's actions and the
//! pedestrians' standing and looking in those windows, and how long crossers are seen before they cross.
//!
//! Window quantities (fractions of the image size, over the window's 16 boxes): `height` (mean box height),
//! `bottom` (mean box bottom), `aspect` (mean width / height), `growth` (the height's mean relative growth per
//! frame), `jitter` (the median |second difference| of the box centre's x, a measure of hand-drawn noise) and
//! `toward_centre` (how much closer to the image's vertical centre line the box ends than it starts). They are
//! the same as tools/transfer_eval.py's.

use std::collections::BTreeMap;

use serde::Serialize;

use super::real::{EgoAction, RealBox, RealVideo};
use crate::dataset::read::protocol::PabOptions;

/// The quantities of a window, in [`QUANTITIES`] order.
pub type Quantities = [f64; 6];

/// The names of the window quantities.
pub const QUANTITIES: [&str; 6] = ["height", "bottom", "aspect", "growth", "jitter", "toward_centre"];

/// One observation window.
#[derive(Clone, Debug, PartialEq)]
pub struct Window {
    /// Its track's sequence label.
    pub crosser: bool,
    /// Its quantities.
    pub quantities: Quantities,
    /// The ego's action in the window's last frame, where annotated.
    pub ego_action: Option<EgoAction>,
    /// Standing in the window's last frame, where annotated.
    pub standing: Option<bool>,
    /// Looking at the ego in the window's last frame, where annotated.
    pub looking: Option<bool>,
}

/// The benchmark's windows of every track of `videos`.
pub fn windows(videos: &[RealVideo], pab: &PabOptions) -> Vec<Window> {
    let mut out = Vec::new();
    for v in videos {
        for t in &v.tracks {
            let end = match t.crossing_frame {
                Some(f) if t.crosser => t.boxes.partition_point(|b| b.frame <= f),
                _ => t.boxes.len(),
            };
            let track = &t.boxes[..end];
            if track.len() < pab.min_track || track.len() < pab.obs_length + pab.tte_frames.1 {
                continue;
            }
            let first = track.len() - pab.obs_length - pab.tte_frames.1;
            let last = track.len() - pab.obs_length - pab.tte_frames.0;
            for start in (first..=last).step_by(pab.stride()) {
                let w = &track[start..start + pab.obs_length];
                let tail = w[w.len() - 1];
                out.push(Window {
                    crosser: t.crosser,
                    quantities: quantities(w, v.width_px, v.height_px),
                    ego_action: v.ego_actions.get(&tail.frame).copied(),
                    standing: tail.standing,
                    looking: tail.looking,
                });
            }
        }
    }
    out
}

fn quantities(w: &[RealBox], width: f64, height: f64) -> Quantities {
    let n = w.len() as f64;
    let h = |b: &RealBox| (b.y_max_px - b.y_min_px) / height;
    let cx = |b: &RealBox| 0.5 * (b.x_min_px + b.x_max_px) / width;
    let mean_h = w.iter().map(h).sum::<f64>() / n;
    let bottom = w.iter().map(|b| b.y_max_px / height).sum::<f64>() / n;
    let aspect = w
        .iter()
        .map(|b| (b.x_max_px - b.x_min_px) / (b.y_max_px - b.y_min_px).max(1e-6))
        .sum::<f64>()
        / n;
    let (h0, h1) = (h(&w[0]).max(1e-6), h(&w[w.len() - 1]).max(1e-6));
    let growth = (h1 / h0).powf(1.0 / (n - 1.0).max(1.0)) - 1.0;
    let mut d2: Vec<f64> = w
        .windows(3)
        .map(|t| (cx(&t[2]) - 2.0 * cx(&t[1]) + cx(&t[0])).abs())
        .collect();
    let jitter = median(&mut d2);
    let toward = (cx(&w[0]) - 0.5).abs() - (cx(&w[w.len() - 1]) - 0.5).abs();
    [mean_h, bottom, aspect, growth, jitter, toward]
}

/// The median (0 for none).
pub fn median(xs: &mut [f64]) -> f64 {
    quantile(xs, 0.5)
}

/// The `q` quantile, nearest rank (0 for none).
pub fn quantile(xs: &mut [f64], q: f64) -> f64 {
    if xs.is_empty() {
        return 0.0;
    }
    xs.sort_by(f64::total_cmp);
    let i = ((xs.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    xs[i]
}

/// Lengths, in frames, of the pieces over which hand-drawn boxes move linearly: along every run of consecutive
/// frames of a track, a piece of the left edge ends where its second difference exceeds one pixel (an
/// annotation tool's interpolation between two keyframes, on whole pixels, keeps it within one). The
/// annotator's keyframe spacing (`annotations.annotator_box.keyframe_every`) is fitted to these.
pub fn linear_pieces(videos: &[RealVideo]) -> Vec<f64> {
    let mut pieces = Vec::new();
    for t in videos.iter().flat_map(|v| &v.tracks) {
        let mut run: Vec<f64> = Vec::new();
        let mut flush = |run: &mut Vec<f64>| {
            let mut len = 1.0;
            for w in run.windows(3) {
                if (w[2] - 2.0 * w[1] + w[0]).abs() > 1.0 {
                    pieces.push(len);
                    len = 1.0;
                } else {
                    len += 1.0;
                }
            }
            if run.len() >= 3 {
                pieces.push(len);
            }
            run.clear();
        };
        let mut last = None;
        for b in &t.boxes {
            if last.is_some_and(|f| b.frame != f + 1) {
                flush(&mut run);
            }
            run.push(b.x_min_px);
            last = Some(b.frame);
        }
        flush(&mut run);
    }
    pieces
}

/// The lags at which [`pan_wobble`] measures the common change of bearing, seconds (2 to 90 frames at 30
/// frames/s).
const PAN_LAGS_S: [f64; 8] = [2.0 / 30.0, 4.0 / 30.0, 8.0 / 30.0, 0.5, 1.0, 1.5, 2.0, 3.0];

/// The camera's heading wobble fitted to what pedestrians seen together share of their change of bearing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PanFit {
    /// The standard deviation of the simulator's smooth heading offset, degrees.
    pub sd_deg: f64,
    /// Its correlation time `T` (two first-order lags of `T`), seconds.
    pub correlation_s: f64,
}

/// The camera's heading wobble: the spread and correlation time of the simulator's smooth heading offset (two
/// first-order lags of `T`, autocorrelation `ρ(τ) = (1 + τ/T) e^{−τ/T}`) whose changes over lags of 2 frames to
/// 3 s explain what pedestrians seen together share of their change of bearing. In each video, at every lag `τ`
/// ([`PAN_LAGS_S`], in whole frames of the video), every `τ`-th frame, each pedestrian's bearing
/// `atan((centre − W/2) / f)` is compared with its bearing `τ` later; the mean product of two different
/// pedestrians' changes (their own walking and the annotators' noise are independent and drop out; a turn or
/// wobble of the car moves them all) is the variance of the common change, `V(τ) = 2 σ² (1 − ρ(τ))`. `T` is
/// the one on a 0.05 s grid (0.1–10 s) whose curve fits the logarithms of the measured `V` best (least
/// squares), `σ` the one that fits them best for that `T` (closed form). A lag counts where it has at least 100
/// pairs and a positive `V`; `None` with fewer than three such lags. The car's forward motion also moves
/// pedestrians on one side together, so this bounds the wobble from above. JAAD train: the common change's
/// root mean square grows from 0.24° over 2 frames to 6.9° over 3 s, nearly in proportion to the lag at first
/// (a smooth turn): `T` 2.1 s, `σ` 7.7° (with `T` held at 1 s, as before, one lag of 0.5 s gave 4.0°, which makes the
/// change over 3 s 5.1° and the turn rate change within half a second twice as fast as JAAD's).
pub fn pan_wobble(videos: &[RealVideo], focal_px: f64) -> Option<PanFit> {
    common_wobble(videos, |v, b| {
        ((0.5 * (b.x_min_px + b.x_max_px) - v.width_px * 0.5) / focal_px).atan()
    })
}

/// The camera's pitch wobble, as [`pan_wobble`] fits the heading's, from what pedestrians seen together share of
/// the change of their horizon's elevation: a box of height `h` whose bottom is at `b` (pixels) puts the
/// horizon at `b − slope × h` (the fitted [`HorizonFit::slope`]), which lies `atan((b − slope h − H/2) / f)`
/// below the optical axis. A nodding car moves every pedestrian's horizon together; their own steps, heights
/// and the annotators' noise drop out as the bearing's do. JAAD train: the common change's root mean square is
/// 1.5 px over 2 frames, 6.4 px over 0.5 s and 12 px over 3 s (of 1,080): σ 0.47°, `T` 0.35 s (road joints and
/// undulation under a sprung body, faster than steering).
pub fn pitch_wobble(videos: &[RealVideo], focal_px: f64, slope: f64) -> Option<PanFit> {
    common_wobble(videos, |v, b| {
        ((b.y_max_px - slope * (b.y_max_px - b.y_min_px) - v.height_px * 0.5) / focal_px).atan()
    })
}

/// [`pan_wobble`]'s fit of the common change of `angle(video, box)` (radians) across pedestrians seen together.
fn common_wobble(videos: &[RealVideo], angle: impl Fn(&RealVideo, &RealBox) -> f64) -> Option<PanFit> {
    // Each track's angle by frame, read once for every lag.
    let bearings: Vec<(f64, Vec<BTreeMap<u32, f64>>)> = videos
        .iter()
        .map(|v| {
            let tracks = v
                .tracks
                .iter()
                .map(|t| t.boxes.iter().map(|b| (b.frame, angle(v, b))).collect());
            (v.fps, tracks.collect())
        })
        .collect();
    let mut measured: Vec<(f64, f64)> = Vec::new();
    for lag_s in PAN_LAGS_S {
        let (mut sum, mut pairs) = (0.0, 0.0);
        for (fps, tracks) in &bearings {
            let lag = (lag_s * fps).round().max(1.0) as u32;
            let mut by_frame: BTreeMap<u32, Vec<f64>> = BTreeMap::new();
            for bearing in tracks {
                for (&frame, &at) in bearing.iter().filter(|(f, _)| *f % lag == 0) {
                    if let Some(&later) = bearing.get(&(frame + lag)) {
                        by_frame.entry(frame).or_default().push(later - at);
                    }
                }
            }
            for changes in by_frame.values().filter(|c| c.len() >= 2) {
                let total: f64 = changes.iter().sum();
                let squares: f64 = changes.iter().map(|c| c * c).sum();
                let n = changes.len() as f64;
                sum += 0.5 * (total * total - squares);
                pairs += 0.5 * n * (n - 1.0);
            }
        }
        if pairs >= 100.0 && sum > 0.0 {
            measured.push((lag_s, sum / pairs));
        }
    }
    if measured.len() < 3 {
        return None;
    }
    let one_minus_rho = |tau_s: f64, t_s: f64| 1.0 - (1.0 + tau_s / t_s) * (-tau_s / t_s).exp();
    let mut best: Option<(f64, f64, f64)> = None;
    for step in 2..=200 {
        let t_s = f64::from(step) * 0.05;
        // ln V = ln(2σ²) + ln(1 − ρ): the best ln(2σ²) is the mean difference.
        let diffs: Vec<f64> = measured
            .iter()
            .map(|&(tau, v)| v.ln() - one_minus_rho(tau, t_s).ln())
            .collect();
        let ln_two_var = diffs.iter().sum::<f64>() / diffs.len() as f64;
        let error: f64 = diffs.iter().map(|d| (d - ln_two_var).powi(2)).sum();
        if best.is_none_or(|(e, _, _)| error < e) {
            best = Some((error, t_s, ln_two_var));
        }
    }
    let (_, correlation_s, ln_two_var) = best?;
    Some(PanFit {
        sd_deg: (0.5 * ln_two_var.exp()).sqrt().to_degrees(),
        correlation_s,
    })
}

/// ROC AUC of `score` for `positive` (Mann–Whitney, ties counted half); `None` without both classes.
pub fn auc(samples: &[(f64, bool)]) -> Option<f64> {
    let mut s: Vec<(f64, bool)> = samples.to_vec();
    s.sort_by(|a, b| a.0.total_cmp(&b.0));
    let positives = s.iter().filter(|x| x.1).count() as f64;
    let negatives = s.len() as f64 - positives;
    if positives == 0.0 || negatives == 0.0 {
        return None;
    }
    let mut rank_sum = 0.0;
    let mut i = 0;
    while i < s.len() {
        let mut j = i;
        while j < s.len() && s[j].0 == s[i].0 {
            j += 1;
        }
        let rank = 0.5 * ((i + 1) + j) as f64;
        rank_sum += rank * s[i..j].iter().filter(|x| x.1).count() as f64;
        i = j;
    }
    Some((rank_sum - positives * (positives + 1.0) / 2.0) / (positives * negatives))
}

/// The camera's horizon and scale: box bottom = `horizon + slope × box height` (fractions of the image height),
/// fitted by least squares to unoccluded boxes at least 2 % of the image height tall.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HorizonFit {
    /// Box bottom of a box of height 0 (the horizon), fraction of the image height from the top.
    pub horizon: f64,
    /// Growth of the bottom with the box height: the camera's height over the pedestrians' mean height.
    pub slope: f64,
    /// Coefficient of determination.
    pub r2: f64,
    /// Boxes fitted.
    pub boxes: usize,
    /// Standard deviation of the fitted boxes' heights, fraction of the image height (boxes all alike in size
    /// fix no line).
    pub height_sd: f64,
}

/// Fits [`HorizonFit`]; `None` with fewer than 10 boxes.
pub fn horizon_fit(videos: &[RealVideo]) -> Option<HorizonFit> {
    let (mut n, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for v in videos {
        for b in v.tracks.iter().flat_map(|t| &t.boxes).filter(|b| !b.occluded) {
            let x = (b.y_max_px - b.y_min_px) / v.height_px;
            let y = b.y_max_px / v.height_px;
            if x < 0.02 || !x.is_finite() || !y.is_finite() {
                continue;
            }
            n += 1.0;
            sx += x;
            sy += y;
            sxx += x * x;
            sxy += x * y;
            syy += y * y;
        }
    }
    let var_x = sxx - sx * sx / n;
    if n < 10.0 || var_x <= 0.0 {
        return None;
    }
    let slope = (sxy - sx * sy / n) / var_x;
    let horizon = (sy - slope * sx) / n;
    let var_y = syy - sy * sy / n;
    let explained = slope * (sxy - sx * sy / n);
    Some(HorizonFit {
        horizon,
        slope,
        r2: if var_y > 0.0 { explained / var_y } else { 0.0 },
        boxes: n as usize,
        height_sd: (var_x / n).sqrt(),
    })
}

/// How the camera differs from video to video: the standard deviations of [`HorizonFit`]s made per video
/// (videos with 100 or more fitted boxes whose heights spread by a standard deviation of 3 % of the image
/// height or more and whose line explains at least half of the bottoms' variance: boxes all alike in size fix no
/// line).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CameraSpread {
    /// Videos fitted.
    pub videos: usize,
    /// Standard deviation of the horizon, fraction of the image height.
    pub horizon_sd: f64,
    /// Standard deviation of the slope (camera height over the pedestrians' mean height).
    pub slope_sd: f64,
}

/// Fits [`CameraSpread`]; `None` with fewer than 3 videos that can be fitted.
pub fn camera_spread(videos: &[RealVideo]) -> Option<CameraSpread> {
    let fits: Vec<HorizonFit> = videos
        .iter()
        .filter_map(|v| horizon_fit(std::slice::from_ref(v)))
        .filter(|f| f.boxes >= 100 && f.height_sd >= 0.03 && f.r2 >= 0.5)
        .collect();
    if fits.len() < 3 {
        return None;
    }
    let sd = |xs: Vec<f64>| {
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64).sqrt()
    };
    Some(CameraSpread {
        videos: fits.len(),
        horizon_sd: sd(fits.iter().map(|f| f.horizon).collect()),
        slope_sd: sd(fits.iter().map(|f| f.slope).collect()),
    })
}

/// The per-video horizons' distribution: for each video with at least 50 unoccluded boxes 2 % of the image
/// height or taller, the median of `bottom − slope × height` over them (fractions of the image height; `slope`
/// the pooled [`HorizonFit::slope`], so a video needs no spread of box sizes to be placed), and of those
/// horizons the quantiles at `quantiles` equal steps of probability from 0 to 1. `None` with fewer than 10
/// such videos or fewer than 2 quantiles. JAAD train's 5th, 50th and 95th percentiles: 0.536, 0.622, 0.685 (a
/// peak near the middle with long tails, where a uniform draw of the same standard deviation spreads evenly).
pub fn horizon_quantiles(videos: &[RealVideo], slope: f64, quantiles: usize) -> Option<Vec<f64>> {
    let mut horizons: Vec<f64> = videos
        .iter()
        .filter_map(|v| {
            let mut at: Vec<f64> = v
                .tracks
                .iter()
                .flat_map(|t| &t.boxes)
                .filter(|b| !b.occluded)
                .map(|b| ((b.y_max_px - b.y_min_px) / v.height_px, b.y_max_px / v.height_px))
                .filter(|&(h, bottom)| h >= 0.02 && h.is_finite() && bottom.is_finite())
                .map(|(h, bottom)| bottom - slope * h)
                .collect();
            (at.len() >= 50).then(|| quantile(&mut at, 0.5))
        })
        .collect();
    if horizons.len() < 10 || quantiles < 2 {
        return None;
    }
    Some(
        (0..quantiles)
            .map(|i| quantile(&mut horizons, i as f64 / (quantiles - 1) as f64))
            .collect(),
    )
}

/// How far from the camera a pedestrian of `person_height_m` is whose box is `box_height_px` tall, through a
/// pinhole of focal length `focal_px`, metres.
pub fn distance_m(focal_px: f64, person_height_m: f64, box_height_px: f64) -> f64 {
    focal_px * person_height_m / box_height_px.max(1.0)
}

/// `p10`, `p50`, `p90` of a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Spread {
    /// 10th percentile.
    pub p10: f64,
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
}

impl Spread {
    /// The spread of `xs`.
    pub fn of(mut xs: Vec<f64>) -> Spread {
        Spread {
            p10: quantile(&mut xs, 0.1),
            p50: quantile(&mut xs, 0.5),
            p90: quantile(&mut xs, 0.9),
        }
    }
}

/// How wide people draw boxes of a given height: benchmark windows' mean aspect (width / height) against their
/// mean height in pixels, fitted as `aspect = a + pad_px / height` by least squares (a width of
/// `a × height + pad_px`; `pad_px` is 0 for fewer than 10 windows or heights that do not vary).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AspectFit {
    /// The pixels people add to a box's width whatever its height.
    pub pad_px: f64,
    /// The spread of the windows' aspect less `pad_px / height`: the aspect a box of any height is drawn with.
    pub residual: Spread,
}

/// [`AspectFit`] of the windows of `videos`.
pub fn aspect_fit(videos: &[RealVideo], pab: &PabOptions) -> AspectFit {
    let pairs: Vec<(f64, f64)> = videos
        .iter()
        .flat_map(|v| {
            windows(std::slice::from_ref(v), pab)
                .into_iter()
                .map(move |w| (w.quantities[0] * v.height_px, w.quantities[2]))
        })
        .filter(|&(h, a)| h >= 1.0 && a.is_finite())
        .collect();
    let n = pairs.len() as f64;
    let (mean_x, mean_y) = pairs
        .iter()
        .fold((0.0, 0.0), |(sx, sy), &(h, a)| (sx + 1.0 / h / n, sy + a / n));
    let (sxy, sxx) = pairs.iter().fold((0.0, 0.0), |(sxy, sxx), &(h, a)| {
        let dx = 1.0 / h - mean_x;
        (sxy + dx * (a - mean_y), sxx + dx * dx)
    });
    let pad_px = if pairs.len() >= 10 && sxx > 0.0 {
        (sxy / sxx).max(0.0)
    } else {
        0.0
    };
    AspectFit {
        pad_px,
        residual: Spread::of(pairs.iter().map(|&(h, a)| a - pad_px / h).collect()),
    }
}

/// What one class's windows look like.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ClassSummary {
    /// Windows.
    pub windows: usize,
    /// Each quantity's spread, by name.
    pub quantities: BTreeMap<String, Spread>,
    /// Share of windows ending with each ego action (of those with one annotated).
    pub ego_actions: BTreeMap<String, f64>,
    /// Share of windows ending standing (of those annotated).
    pub standing: Option<f64>,
    /// Share of windows ending looking at the ego (of those annotated).
    pub looking: Option<f64>,
}

/// Everything measured in one set of annotations.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Measurements {
    /// Videos (or clips).
    pub videos: usize,
    /// Pedestrian tracks.
    pub tracks: usize,
    /// Tracks of crossers.
    pub crossers: usize,
    /// The horizon fit, where there were enough boxes.
    pub horizon: Option<HorizonFit>,
    /// How the horizon and scale differ between videos, where enough videos can be fitted.
    pub camera_spread: Option<CameraSpread>,
    /// Crossing windows.
    pub crossing: ClassSummary,
    /// Not-crossing windows.
    pub not_crossing: ClassSummary,
    /// How well each quantity tells crossing from not-crossing windows (AUC; 0.5 none, below 0.5 reversed).
    pub cues: BTreeMap<String, f64>,
    /// How long crossers are annotated before their crossing point, seconds (those first annotated before it).
    pub seen_before_crossing_s: Spread,
}

fn share(xs: impl Iterator<Item = bool>) -> Option<f64> {
    let (mut yes, mut all) = (0usize, 0usize);
    for x in xs {
        all += 1;
        yes += usize::from(x);
    }
    (all > 0).then(|| yes as f64 / all as f64)
}

fn summary(windows: &[&Window]) -> ClassSummary {
    let quantities = QUANTITIES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            (
                (*name).to_owned(),
                Spread::of(windows.iter().map(|w| w.quantities[i]).collect()),
            )
        })
        .collect();
    let with_action: Vec<EgoAction> = windows.iter().filter_map(|w| w.ego_action).collect();
    let ego_actions = if with_action.is_empty() {
        BTreeMap::new()
    } else {
        EgoAction::ALL
            .iter()
            .map(|a| {
                let n = with_action.iter().filter(|x| *x == a).count();
                (a.name().to_owned(), n as f64 / with_action.len() as f64)
            })
            .collect()
    };
    ClassSummary {
        windows: windows.len(),
        quantities,
        ego_actions,
        standing: share(windows.iter().filter_map(|w| w.standing)),
        looking: share(windows.iter().filter_map(|w| w.looking)),
    }
}

/// Measures `videos` with the benchmark's sampling `pab`.
pub fn measure(videos: &[RealVideo], pab: &PabOptions) -> Measurements {
    let all = windows(videos, pab);
    let crossing: Vec<&Window> = all.iter().filter(|w| w.crosser).collect();
    let not_crossing: Vec<&Window> = all.iter().filter(|w| !w.crosser).collect();
    let cues = QUANTITIES
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            let samples: Vec<(f64, bool)> = all.iter().map(|w| (w.quantities[i], w.crosser)).collect();
            Some(((*name).to_owned(), auc(&samples)?))
        })
        .collect();
    // Crossers already crossing when first annotated (about half of JAAD's) say nothing about the time before.
    let seen: Vec<f64> = videos
        .iter()
        .flat_map(|v| {
            v.tracks.iter().filter_map(move |t| {
                let first = t.boxes.first()?.frame;
                let at = t.crossing_frame.filter(|&f| t.crosser && f > first)?;
                Some(f64::from(at - first) / v.fps)
            })
        })
        .collect();
    Measurements {
        videos: videos.len(),
        tracks: videos.iter().map(|v| v.tracks.len()).sum(),
        crossers: videos.iter().flat_map(|v| &v.tracks).filter(|t| t.crosser).count(),
        horizon: horizon_fit(videos),
        camera_spread: camera_spread(videos),
        crossing: summary(&crossing),
        not_crossing: summary(&not_crossing),
        cues,
        seen_before_crossing_s: Spread::of(seen),
    }
}

/// For each quantity, how well it alone tells windows of `a` from windows of `b` (AUC folded to ≥ 0.5:
/// 0.5 = the same distribution).
pub fn separation(a: &[Window], b: &[Window]) -> BTreeMap<String, f64> {
    QUANTITIES
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            let samples: Vec<(f64, bool)> = a
                .iter()
                .map(|w| (w.quantities[i], false))
                .chain(b.iter().map(|w| (w.quantities[i], true)))
                .collect();
            let x = auc(&samples)?;
            Some(((*name).to_owned(), x.max(1.0 - x)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auc_counts_ties_half_and_orders() {
        assert_eq!(auc(&[(1.0, false), (2.0, true)]), Some(1.0));
        assert_eq!(auc(&[(2.0, false), (1.0, true)]), Some(0.0));
        assert_eq!(auc(&[(1.0, false), (1.0, true)]), Some(0.5));
        assert_eq!(auc(&[(1.0, true)]), None);
        // Positives 1, 3, 4 against negatives 0, 2: 5 of the 6 pairs ordered.
        let s = [(0.0, false), (2.0, false), (1.0, true), (3.0, true), (4.0, true)];
        assert!((auc(&s).unwrap() - 5.0 / 6.0).abs() < 1e-12);
    }

    /// A video of one track whose boxes lie on `bottom = horizon + slope × height` (fractions of 1000 px).
    fn line_video(horizon: f64, slope: f64, boxes: u32) -> RealVideo {
        let boxes: Vec<RealBox> = (1..=boxes)
            .map(|i| {
                let h = 10.0 + 4.0 * f64::from(i % 60);
                let bottom = 1000.0 * horizon + slope * h;
                RealBox {
                    frame: i,
                    x_min_px: 0.0,
                    y_min_px: bottom - h,
                    x_max_px: h / 3.0,
                    y_max_px: bottom,
                    occluded: false,
                    standing: None,
                    looking: None,
                }
            })
            .collect();
        RealVideo {
            name: "v".into(),
            split: "train".into(),
            width_px: 1920.0,
            height_px: 1000.0,
            fps: 30.0,
            tracks: vec![super::super::real::RealTrack {
                id: "p".into(),
                crosser: false,
                crossing_frame: None,
                boxes,
            }],
            ego_actions: BTreeMap::new(),
        }
    }

    #[test]
    fn horizon_fit_recovers_a_line() {
        let fit = horizon_fit(&[line_video(0.6, 0.8, 49)]).unwrap();
        assert!((fit.horizon - 0.6).abs() < 1e-9 && (fit.slope - 0.8).abs() < 1e-9 && fit.r2 > 0.999);
    }

    #[test]
    fn camera_spread_is_the_deviation_of_per_video_lines() {
        let videos = [
            line_video(0.55, 0.7, 120),
            line_video(0.60, 0.8, 120),
            line_video(0.65, 0.9, 120),
            line_video(0.9, 0.1, 50), // too few boxes to count
        ];
        let c = camera_spread(&videos).unwrap();
        assert_eq!(c.videos, 3);
        assert!(
            (c.horizon_sd - 0.05).abs() < 1e-9 && (c.slope_sd - 0.1).abs() < 1e-9,
            "{c:?}"
        );
        assert_eq!(camera_spread(&videos[..2]), None, "two videos are too few");
    }

    #[test]
    fn horizon_quantiles_place_each_video_by_its_median_horizon_at_the_pooled_slope() {
        // Twelve videos on the pooled slope 0.8, horizons 0.50, 0.51, …, 0.61; one more with too few boxes.
        let mut videos: Vec<RealVideo> = (0..12)
            .map(|i| line_video(0.5 + 0.01 * f64::from(i), 0.8, 120))
            .collect();
        videos.push(line_video(0.9, 0.8, 40));
        let q = horizon_quantiles(&videos, 0.8, 3).unwrap();
        assert_eq!(q.len(), 3);
        // Lowest, median (nearest rank of 12: the 7th, 0.56) and highest; the short video is left out.
        for (got, want) in q.iter().zip([0.50, 0.56, 0.61]) {
            assert!((got - want).abs() < 1e-9, "{q:?}");
        }
        assert_eq!(horizon_quantiles(&videos[..9], 0.8, 3), None, "nine videos are too few");
        assert_eq!(
            horizon_quantiles(&videos, 0.8, 1),
            None,
            "one quantile is no distribution"
        );
    }

    /// Videos whose pedestrians all turn with one smooth heading offset (the simulator's two lags of `t_s`,
    /// spread `sd_deg`), each with its own bearing and 0.3° of independent noise per frame; with `nod`, the
    /// offset and the noise move the boxes up and down (a pitch) instead.
    fn panning_videos(sd_deg: f64, t_s: f64, videos: u64) -> Vec<RealVideo> {
        moving_videos(sd_deg, t_s, videos, false)
    }

    fn moving_videos(sd_deg: f64, t_s: f64, videos: u64, nod: bool) -> Vec<RealVideo> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let (fps, frames, focal_px) = (30.0, 900u32, 960.0);
        let rho = (-1.0 / (fps * t_s)).exp();
        let sd_inner = sd_deg.to_radians() * (1.0 + rho) / (1.0 + rho * rho).sqrt();
        (0..videos)
            .map(|v| {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(v);
                let mut z = || -> f64 { StandardNormal.sample(&mut rng) };
                let (mut inner, mut offset) = (0.0, 0.0);
                let offsets: Vec<f64> = (0..3000 + frames)
                    .map(|_| {
                        inner = rho * inner + sd_inner * (1.0 - rho * rho).sqrt() * z();
                        offset = rho * offset + (1.0 - rho) * inner;
                        offset
                    })
                    .skip(3000)
                    .collect();
                let tracks = (0..4)
                    .map(|p| super::super::real::RealTrack {
                        id: p.to_string(),
                        crosser: false,
                        crossing_frame: None,
                        boxes: (0..frames)
                            .map(|frame| {
                                let angle =
                                    -0.3 + 0.2 * f64::from(p) + offsets[frame as usize] + 0.3f64.to_radians() * z();
                                let (centre, horizon) = if nod {
                                    (960.0 + 100.0 * f64::from(p), 540.0 + focal_px * (0.1 * angle).tan())
                                } else {
                                    (960.0 + focal_px * angle.tan(), 524.0)
                                };
                                // Boxes 120 px tall on a slope of 0.8: the bottom is 96 px below the horizon.
                                RealBox {
                                    frame,
                                    x_min_px: centre - 20.0,
                                    y_min_px: horizon + 96.0 - 120.0,
                                    x_max_px: centre + 20.0,
                                    y_max_px: horizon + 96.0,
                                    occluded: false,
                                    standing: None,
                                    looking: None,
                                }
                            })
                            .collect(),
                    })
                    .collect();
                RealVideo {
                    name: format!("v{v}"),
                    split: "train".into(),
                    width_px: 1920.0,
                    height_px: 1080.0,
                    fps,
                    tracks,
                    ego_actions: BTreeMap::new(),
                }
            })
            .collect()
    }

    #[test]
    fn pan_wobble_recovers_the_spread_and_the_correlation_time_of_a_common_turn() {
        for (sd_deg, t_s) in [(6.0, 2.0), (3.0, 0.7)] {
            let fit = pan_wobble(&panning_videos(sd_deg, t_s, 60), 960.0).unwrap();
            assert!(
                (fit.sd_deg / sd_deg - 1.0).abs() < 0.12 && (fit.correlation_s / t_s - 1.0).abs() < 0.15,
                "{fit:?} for {sd_deg}° and {t_s} s"
            );
        }
        // One pedestrian per video: nobody to share a turn with.
        let mut alone = panning_videos(6.0, 2.0, 5);
        for v in &mut alone {
            v.tracks.truncate(1);
        }
        assert_eq!(pan_wobble(&alone, 960.0), None);
    }

    #[test]
    fn pitch_wobble_recovers_the_spread_and_the_correlation_time_of_a_common_nod() {
        // The boxes' horizon moves by a tenth of the angle drawn (a nod of 0.5° and 0.35 s from one of 5°).
        for (sd_deg, t_s) in [(5.0, 0.35), (8.0, 1.0)] {
            let fit = pitch_wobble(&moving_videos(sd_deg, t_s, 60, true), 960.0, 0.8).unwrap();
            assert!(
                (fit.sd_deg / (0.1 * sd_deg) - 1.0).abs() < 0.12 && (fit.correlation_s / t_s - 1.0).abs() < 0.15,
                "{fit:?} for {}° and {t_s} s",
                0.1 * sd_deg
            );
        }
        // A pan moves no horizon: the fit finds (almost) nothing in level boxes.
        let level = pitch_wobble(&panning_videos(6.0, 2.0, 20), 960.0, 0.8);
        assert!(level.is_none_or(|f| f.sd_deg < 0.01), "{level:?}");
    }
}
