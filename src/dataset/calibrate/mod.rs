//! `pedsynth calibrate`: real annotations (JAAD's or PIE's XML layout, or a documented table) → what they show
//! (the camera's horizon and height, PedestrianActionBenchmark windows per class, the cue table, the ego's
//! actions, how long crossers are seen) → a profile, a partial spec that `plan` and `generate` lay over a spec
//! with `--profile`; and, given a generated dataset, a side-by-side report of the two.
//!
//! - [`real`] — the one model every source is read into, and the table layout's reader.
//! - [`xml`] — JAAD's and PIE's XML layouts.
//! - [`measure`] — windows, quantities, fits and AUCs.

pub mod measure;
pub mod real;
pub mod xml;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use self::measure::{Measurements, QUANTITIES};
use self::real::{EgoAction, RealBox, RealTrack, RealVideo, invalid};
use crate::dataset::read::protocol::PabOptions;
use crate::error::Error;

/// The layout real annotations come in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// JAAD's XML (github.com/ykotseruba/JAAD).
    Jaad,
    /// PIE's XML (github.com/aras62/PIE).
    Pie,
    /// The documented table layout, Parquet or CSV ([`real`]).
    Table,
}

/// How to calibrate.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrateOptions {
    /// The layout of the real annotations.
    pub format: Format,
    /// The splits to fit to (empty: every video).
    pub splits: Vec<String>,
    /// The field of view assumed for the real camera, degrees (boxes alone fix the horizon and the camera's
    /// height, not the focal length).
    pub fov_deg: f64,
    /// The pedestrians' mean height assumed for the camera's height, metres.
    pub person_height_m: f64,
    /// The benchmark's sampling.
    pub pab: PabOptions,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            format: Format::Table,
            splits: vec!["train".to_owned()],
            fov_deg: 90.0,
            person_height_m: 1.70,
            pab: PabOptions {
                overlap: 0.8,
                ..PabOptions::default()
            },
        }
    }
}

/// The spec values a calibration fits.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// `sensors.rgb.width_px` / `height_px`: the most common image size.
    pub width_px: u32,
    /// Image height.
    pub height_px: u32,
    /// `sensors.rgb.fov_deg` (assumed, [`CalibrateOptions::fov_deg`]).
    pub fov_deg: f64,
    /// `sensors.rgb.mount.up_m`: the horizon fit's slope × the pedestrians' mean height.
    pub up_m: f64,
    /// The pedestrians' mean height assumed, metres.
    pub person_height_m: f64,
    /// `sensors.rgb.mount.pitch_deg`: the pitch that puts the horizon where the fit has it (positive looks up).
    pub pitch_deg: f64,
    /// `sensors.rgb.mount_spread`: half-widths of the per-clip offsets of the mount's height (metres) and pitch
    /// (degrees), `√3 ×` the per-video standard deviations ([`measure::CameraSpread`]; a uniform draw of that
    /// half-width has that deviation); 0 where too few videos can be fitted alone.
    pub mount_spread: (f64, f64),
    /// `sensors.rgb.mount_spread.pitch_quantiles_deg` (in place of the uniform pitch range): the per-video
    /// horizons' quantiles at every 5 % ([`measure::horizon_quantiles`]) as pitches, less `pitch_deg`, to 0.1°;
    /// empty where fewer than 10 videos can be placed.
    pub pitch_quantiles_deg: Vec<f64>,
    /// `dataset.fps`: the most common frame rate.
    pub fps: u32,
    /// `crossing.timeline.in_view_before_crossing_s`: the 10th and 90th percentiles of how long crossers are
    /// annotated before they cross (within the spec's limits, 0.5–30 s).
    pub in_view_before_crossing_s: (f64, f64),
    /// `crossing.scenario.crosser_ego_within_m`: the 10th and 50th percentiles of crossers' distance from the
    /// camera at their crossing point (from the box height, the fitted camera and the mean height). The drawn
    /// distance is the farthest the ego may be when a crosser steps out, and simulated crossers step out at or
    /// inside it (they wait for their gap and the ego's yield): hence the nearer half of the real distances.
    /// The 50th percentile is also `crossing.scenario.crosser_stopped_ego_within_m`: a crosser waiting for the
    /// ego steps out in front of it once it has stopped within that distance (for it, or for others crossing).
    pub crosser_ego_within_m: (f64, f64),
    /// `crossing.scenario.walker_ahead_m`: the 50th and 90th percentiles of non-crossers' distance when first
    /// annotated, tracks of the benchmark's minimum length of pedestrians not labelled crossers only (a crosser
    /// whose crossing point is unknown is no walker; walkers are placed at the clip's start, and the
    /// ego drives towards them during the clip: the farther half keeps them ahead, as real bystanders are).
    pub walker_ahead_m: (f64, f64),
    /// `crossing.scenario.walker_lateral_m`: the 10th and 90th percentiles of how far to the side of the camera
    /// non-crossers are when first annotated (box centre's offset from the image's centre column, in metres at
    /// the box's distance through the mean height), the same tracks as `walker_ahead_m`.
    pub walker_lateral_m: (f64, f64),
    /// `annotations.annotator_box.min_aspect`: the 10th and 90th percentiles of the windows' box aspect
    /// (width / height) less `width_pad_px` / height, both classes ([`measure::aspect_fit`]).
    pub min_aspect: (f64, f64),
    /// `annotations.annotator_box.width_pad_px`: the pixels the real boxes' width has on top of a share of
    /// their height (small boxes are drawn relatively wider; [`measure::aspect_fit`]).
    pub width_pad_px: f64,
    /// `annotations.annotator_box.keyframe_every`: the 25th and 75th percentiles of the lengths of the pieces
    /// over which the real boxes' left edge moves linearly ([`measure::linear_pieces`]), frames.
    pub keyframe_every: (u32, u32),
    /// `traffic.ego.heading_wobble`: [`measure::pan_wobble`] with the fitted focal length (`sd_deg` to 0.1°,
    /// within the spec's 10°; `correlation_s` to 0.01 s). `None` where too few pedestrians are seen together.
    pub heading_wobble: Option<measure::PanFit>,
    /// `traffic.ego.pitch_wobble`: [`measure::pitch_wobble`] with the fitted focal length and slope (`sd_deg` to
    /// 0.01°, within the spec's 5°; `correlation_s` to 0.01 s). `None` where too few pedestrians are seen together.
    pub pitch_wobble: Option<measure::PanFit>,
    /// `crossing.layers.behaviour_mix.mix`'s `sudden` share: crossers walking in the last frame of their windows
    /// (a sudden crosser walks into the road without stopping at the curb); `normal` and `jaywalk` share the
    /// rest 2 : 1 as the paper's mix does. `None` where the real data has no standing/walking labels.
    pub sudden_share: Option<f64>,
}

/// A calibration: what was read, measured and fitted.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Calibration {
    /// The splits fitted to (empty: all).
    pub splits: Vec<String>,
    /// The measurements of the real annotations.
    pub real: Measurements,
    /// The fitted values.
    pub fit: Fit,
}

/// Reads real annotations in `format` from `dir`, keeping the videos of `splits` (all if empty).
pub fn read_real(dir: &Path, format: Format, splits: &[String]) -> Result<Vec<RealVideo>, Error> {
    if !dir.is_dir() {
        return Err(invalid(format!("{}: not a directory", dir.display())));
    }
    let videos = match format {
        Format::Jaad => xml::read_jaad(dir)?,
        Format::Pie => xml::read_pie(dir)?,
        Format::Table => real::read_tables(dir)?,
    };
    let kept: Vec<RealVideo> = videos
        .into_iter()
        .filter(|v| splits.is_empty() || splits.contains(&v.split))
        .collect();
    if kept.is_empty() {
        return Err(invalid(format!(
            "{}: no videos in split{} {}",
            dir.display(),
            if splits.len() == 1 { "" } else { "s" },
            splits.join(", ")
        ))
        .help("choose splits the annotations have with --splits (e.g. --splits train,val)"));
    }
    Ok(kept)
}

fn most_common<T: Ord + Copy>(xs: impl Iterator<Item = T>) -> Option<T> {
    let mut counts: BTreeMap<T, usize> = BTreeMap::new();
    for x in xs {
        *counts.entry(x).or_default() += 1;
    }
    counts.into_iter().max_by_key(|&(_, n)| n).map(|(x, _)| x)
}

/// Measures `videos` and fits the spec values.
pub fn calibrate(videos: &[RealVideo], options: &CalibrateOptions) -> Result<Calibration, Error> {
    let real = measure::measure(videos, &options.pab);
    let horizon = real.horizon.ok_or_else(|| {
        invalid("too few unoccluded boxes (10 at least, 2 % of the image height or taller) to fit the camera")
    })?;
    if real.crossing.windows == 0 || real.not_crossing.windows == 0 {
        return Err(invalid(format!(
            "the benchmark's sampling finds {} crossing and {} not-crossing windows: both classes are needed",
            real.crossing.windows, real.not_crossing.windows
        ))
        .help("use more videos (--splits), or annotations with crossing labels and tracks of 76+ frames"));
    }
    let (width_px, height_px) =
        most_common(videos.iter().map(|v| (v.width_px as u32, v.height_px as u32))).unwrap_or((1920, 1080));
    let focal_px = f64::from(width_px) / 2.0 / (options.fov_deg.to_radians() / 2.0).tan();
    let pitch_deg = ((horizon.horizon - 0.5) * f64::from(height_px) / focal_px)
        .atan()
        .to_degrees();
    // d pitch / d horizon: the horizon row is H/2 + f tan(pitch).
    let mount_spread = real.camera_spread.map_or((0.0, 0.0), |c| {
        let cos2 = pitch_deg.to_radians().cos().powi(2);
        (
            3f64.sqrt() * c.slope_sd * options.person_height_m,
            3f64.sqrt() * (c.horizon_sd * f64::from(height_px) / focal_px * cos2).to_degrees(),
        )
    });
    let round = |x: f64, d: i32| (x * 10f64.powi(d)).round() / 10f64.powi(d);
    let fitted_pitch_deg = round(pitch_deg.clamp(-30.0, 30.0), 1);
    let pitch_quantiles_deg = measure::horizon_quantiles(videos, horizon.slope, 21)
        .map(|q| {
            q.iter()
                .map(|h| {
                    let pitch = ((h - 0.5) * f64::from(height_px) / focal_px).atan().to_degrees();
                    round((pitch - fitted_pitch_deg).clamp(-45.0, 45.0), 1)
                })
                .collect()
        })
        .unwrap_or_default();
    let seen = real.seen_before_crossing_s;
    let distance = |b: &RealBox| measure::distance_m(focal_px, options.person_height_m, b.y_max_px - b.y_min_px);
    let mut at_crossing = Vec::new();
    let mut walkers_first = Vec::new();
    let mut walkers_aside = Vec::new();
    for (v, t) in videos.iter().flat_map(|v| v.tracks.iter().map(move |t| (v, t))) {
        match t.crossing_frame {
            Some(f) if t.crosser => {
                if let Some(b) = t.boxes.iter().rev().find(|b| b.frame <= f && !b.occluded) {
                    at_crossing.push(distance(b));
                }
            }
            _ if !t.crosser && t.boxes.len() >= options.pab.min_track => {
                if let Some(b) = t.boxes.iter().find(|b| !b.occluded) {
                    walkers_first.push(distance(b));
                    let centre_px = (b.x_min_px + b.x_max_px) / 2.0 - v.width_px / 2.0;
                    walkers_aside
                        .push((centre_px / (b.y_max_px - b.y_min_px).max(1.0) * options.person_height_m).abs());
                }
            }
            _ => {}
        }
    }
    let (crossers_at, walkers_at) = (measure::Spread::of(at_crossing), measure::Spread::of(walkers_first));
    let walkers_aside = measure::Spread::of(walkers_aside);
    let aspect = measure::aspect_fit(videos, &options.pab);
    let lo = round(seen.p10.clamp(0.5, 30.0), 1);
    let fit = Fit {
        width_px,
        height_px,
        fov_deg: options.fov_deg,
        up_m: round((horizon.slope * options.person_height_m).clamp(0.5, 3.0), 2),
        person_height_m: options.person_height_m,
        pitch_deg: fitted_pitch_deg,
        pitch_quantiles_deg,
        mount_spread: (
            round(mount_spread.0.clamp(0.0, 1.0), 2),
            round(mount_spread.1.clamp(0.0, 15.0), 1),
        ),
        fps: most_common(videos.iter().map(|v| v.fps.round() as u32))
            .unwrap_or(30)
            .max(1),
        in_view_before_crossing_s: (lo, round(seen.p90.clamp(lo, 30.0), 1)),
        crosser_ego_within_m: (
            round(crossers_at.p10.clamp(1.0, 100.0), 1),
            round(crossers_at.p50.clamp(1.0, 100.0), 1),
        ),
        walker_ahead_m: (
            round(walkers_at.p50.clamp(1.0, 200.0), 1),
            round(walkers_at.p90.clamp(1.0, 200.0), 1),
        ),
        walker_lateral_m: {
            let lo = round(walkers_aside.p10.clamp(0.0, 100.0), 1);
            (lo, round(walkers_aside.p90.clamp(lo, 100.0), 1))
        },
        min_aspect: (
            round(aspect.residual.p10.clamp(0.0, 2.0), 2),
            round(aspect.residual.p90.clamp(0.0, 2.0), 2),
        ),
        width_pad_px: round(aspect.pad_px.clamp(0.0, 200.0), 1),
        sudden_share: real.crossing.standing.map(|standing| round(1.0 - standing, 2)),
        heading_wobble: measure::pan_wobble(videos, focal_px).map(|p| measure::PanFit {
            sd_deg: round(p.sd_deg.clamp(0.0, 10.0), 1),
            correlation_s: round(p.correlation_s, 2),
        }),
        pitch_wobble: measure::pitch_wobble(videos, focal_px, horizon.slope).map(|p| measure::PanFit {
            sd_deg: round(p.sd_deg.clamp(0.0, 5.0), 2),
            correlation_s: round(p.correlation_s, 2),
        }),
        keyframe_every: {
            let mut pieces = measure::linear_pieces(videos);
            let mut at = |q| (measure::quantile(&mut pieces, q).round() as u32).clamp(1, 300);
            let lo = at(0.25);
            (lo, at(0.75).max(lo))
        },
    };
    Ok(Calibration {
        splits: options.splits.clone(),
        real,
        fit,
    })
}

/// The profile a calibration writes: a partial spec, with what it was fitted to in comments.
pub fn profile_yaml(c: &Calibration, source: &str) -> String {
    let f = &c.fit;
    let m = &c.real;
    let h = m.horizon.unwrap_or(measure::HorizonFit {
        horizon: 0.5,
        slope: 0.0,
        r2: 0.0,
        boxes: 0,
        height_sd: 0.0,
    });
    let splits = if c.splits.is_empty() {
        "all".to_owned()
    } else {
        c.splits.join(", ")
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# pedsynth profile fitted by `pedsynth calibrate` to {source} (splits: {splits}):"
    );
    let _ = writeln!(
        out,
        "# {} videos, {} pedestrian tracks ({} crossers), {} crossing and {} not-crossing benchmark windows.",
        m.videos, m.tracks, m.crossers, m.crossing.windows, m.not_crossing.windows
    );
    let _ = writeln!(
        out,
        "# Camera: box bottom = {:.3} + {:.3} x box height (fractions of the image height; {} unoccluded boxes, R^2 {:.2}).",
        h.horizon, h.slope, h.boxes, h.r2
    );
    let _ = writeln!(out, "# Use it with `pedsynth plan|generate SPEC --profile THIS_FILE`.");
    let _ = writeln!(out, "dataset:\n  fps: {}", f.fps);
    let _ = writeln!(
        out,
        "sensors:\n  rgb:\n    width_px: {}\n    height_px: {}\n    fov_deg: {}  # assumed: boxes do not fix the focal length",
        f.width_px, f.height_px, f.fov_deg
    );
    let _ = writeln!(
        out,
        "    mount:\n      up_m: {}  # the fit's slope x a {:.2} m mean pedestrian\n      pitch_deg: {}  # puts the horizon {:.3} of the height from the top",
        f.up_m, f.person_height_m, f.pitch_deg, h.horizon
    );
    if let Some(c) = m.camera_spread.filter(|_| f.mount_spread != (0.0, 0.0)) {
        let (up, pitch) = f.mount_spread;
        let _ = writeln!(
            out,
            "    mount_spread:  # per clip: {} videos fitted alone, horizon sd {:.3}, slope sd {:.3}\n      up_m: [{}, {}]",
            c.videos, c.horizon_sd, c.slope_sd, -up, up
        );
        if f.pitch_quantiles_deg.is_empty() {
            let _ = writeln!(out, "      pitch_deg: [{}, {}]", -pitch, pitch);
        } else {
            let list: Vec<String> = f.pitch_quantiles_deg.iter().map(|q| q.to_string()).collect();
            let _ = writeln!(
                out,
                "      pitch_quantiles_deg: [{}]  # the videos' horizons (median of bottom - slope x height) at every 5 %, as pitches about pitch_deg",
                list.join(", ")
            );
        }
    }
    let _ = writeln!(
        out,
        "crossing:\n  timeline:\n    in_view_before_crossing_s: [{}, {}]  # crossers annotated before crossing: p10 {:.1} s, median {:.1} s, p90 {:.1} s",
        f.in_view_before_crossing_s.0,
        f.in_view_before_crossing_s.1,
        m.seen_before_crossing_s.p10,
        m.seen_before_crossing_s.p50,
        m.seen_before_crossing_s.p90
    );
    let _ = writeln!(
        out,
        "  scenario:\n    crosser_ego_within_m: [{}, {}]  # crossers' distance at their crossing point (p10, p50)\n    crosser_stopped_ego_within_m: {}  # and they go in front of an ego stopped within the p50\n    walker_ahead_m: [{}, {}]  # non-crossers' distance when first annotated (p50, p90)\n    walker_lateral_m: [{}, {}]  # and how far to the side (p10, p90)",
        f.crosser_ego_within_m.0,
        f.crosser_ego_within_m.1,
        f.crosser_ego_within_m.1,
        f.walker_ahead_m.0,
        f.walker_ahead_m.1,
        f.walker_lateral_m.0,
        f.walker_lateral_m.1
    );
    if let Some(sudden) = f.sudden_share {
        let normal = (((1.0 - sudden) * 2.0 / 3.0) * 100.0).round() / 100.0;
        let jaywalk = ((1.0 - sudden - normal) * 100.0).round() / 100.0;
        let _ = writeln!(
            out,
            "  layers:\n    behaviour_mix:\n      mix: {{normal: {normal}, sudden: {sudden}, jaywalk: {jaywalk}}}  # {:.0} % of real crossers walk 1-2 s before crossing",
            100.0 * sudden
        );
    }
    if f.heading_wobble.is_some() || f.pitch_wobble.is_some() {
        let _ = writeln!(out, "traffic:\n  ego:");
    }
    let wobbles = [
        (
            "heading_wobble",
            f.heading_wobble,
            "of their change of bearing over 2 frames to 3 s (an upper bound: includes the car's forward motion)",
        ),
        (
            "pitch_wobble",
            f.pitch_wobble,
            "of the change of their horizon (bottom - slope x height) over 2 frames to 3 s",
        ),
    ];
    for (key, fit, what) in wobbles {
        if let Some(measure::PanFit { sd_deg, correlation_s }) = fit {
            let _ = writeln!(
                out,
                "    {key}: {{sd_deg: {sd_deg}, correlation_s: {correlation_s}}}  # what pedestrians seen together share {what}"
            );
        }
    }
    let _ = writeln!(
        out,
        "annotations:\n  export_box: annotator  # exports and comparisons read the hand-drawn-like box\n  annotator_box:\n    min_aspect: [{}, {}]  # the real boxes' width / height in benchmark windows, less width_pad_px / height (p10, p90)\n    width_pad_px: {}  # the real boxes' width = aspect x height + this (least squares over the windows)\n    keyframe_every: [{}, {}]  # frames over which the real boxes move linearly (p25, p75): keyframes, interpolated",
        f.min_aspect.0, f.min_aspect.1, f.width_pad_px, f.keyframe_every.0, f.keyframe_every.1
    );
    out
}

/// A dataset written by pedsynth, read into the same model as real annotations: tight boxes, the crossing
/// label and first crossing frame, standing and looking, the ego's action from its speed and acceleration
/// ([`EgoAction::from_motion`]).
pub fn synthetic_videos(dir: &Path) -> Result<Vec<RealVideo>, Error> {
    let ds = crate::dataset::export::dataset::Dataset::open(dir)?;
    let rgb = &ds.spec.sensors.rgb;
    let mut videos = Vec::with_capacity(ds.clips.len());
    for info in &ds.clips {
        let clip = ds.load(info)?;
        let tracks = clip
            .pedestrians
            .values()
            .map(|p| RealTrack {
                id: p.id.to_string(),
                crosser: p.crosser,
                crossing_frame: p.frames.iter().find(|f| f.crossing).map(|f| f.frame),
                boxes: p
                    .frames
                    .iter()
                    .map(|f| RealBox {
                        frame: f.frame,
                        x_min_px: f64::from(f.bbox_px[0]),
                        y_min_px: f64::from(f.bbox_px[1]),
                        x_max_px: f64::from(f.bbox_px[2]),
                        y_max_px: f64::from(f.bbox_px[3]),
                        occluded: f.occlusion > 0.0,
                        standing: Some(f.action == "standing"),
                        looking: Some(f.look),
                    })
                    .collect(),
            })
            .collect();
        let ego_actions = clip
            .ego
            .iter()
            .enumerate()
            .map(|(i, e)| (i as u32, EgoAction::from_motion(e.speed_mps, e.accel_mps2)))
            .collect();
        videos.push(RealVideo {
            name: info.clip_id.clone(),
            split: info.split.clone(),
            width_px: f64::from(rgb.width_px),
            height_px: f64::from(rgb.height_px),
            fps: f64::from(info.fps),
            tracks,
            ego_actions,
        });
    }
    Ok(videos)
}

/// Real against generated, side by side.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// The real annotations' measurements.
    pub real: Measurements,
    /// The generated dataset's.
    pub synthetic: Measurements,
    /// How well each quantity alone tells a synthetic window from a real one (AUC ≥ 0.5; 0.5 = the same).
    pub separation: BTreeMap<String, f64>,
}

/// Compares real annotations with a generated dataset's.
pub fn compare(real: &[RealVideo], synthetic: &[RealVideo], pab: &PabOptions) -> Comparison {
    Comparison {
        real: measure::measure(real, pab),
        synthetic: measure::measure(synthetic, pab),
        separation: measure::separation(&measure::windows(real, pab), &measure::windows(synthetic, pab)),
    }
}

/// The comparison as Markdown: counts, the camera fit, each quantity's spread per class and its separation,
/// the cue table, the ego's actions and the pedestrians' standing and looking.
pub fn report_markdown(c: &Comparison, real_name: &str, synthetic_name: &str) -> String {
    let (r, s) = (&c.real, &c.synthetic);
    let mut out = String::new();
    let _ = writeln!(out, "# Real ({real_name}) against generated ({synthetic_name})\n");
    let _ = writeln!(out, "| | real | generated |\n|---|---|---|");
    let _ = writeln!(out, "| videos / clips | {} | {} |", r.videos, s.videos);
    let _ = writeln!(
        out,
        "| tracks (crossers) | {} ({}) | {} ({}) |",
        r.tracks, r.crossers, s.tracks, s.crossers
    );
    let _ = writeln!(
        out,
        "| windows crossing / not | {} / {} | {} / {} |",
        r.crossing.windows, r.not_crossing.windows, s.crossing.windows, s.not_crossing.windows
    );
    let fit = |m: &Measurements| {
        m.horizon.map_or("–".to_owned(), |h| {
            format!("{:.3} + {:.3} × height", h.horizon, h.slope)
        })
    };
    let _ = writeln!(out, "| box bottom (fraction of the height) | {} | {} |", fit(r), fit(s));
    let _ = writeln!(
        out,
        "| crossers seen before crossing, median s | {:.1} | {:.1} |\n",
        r.seen_before_crossing_s.p50, s.seen_before_crossing_s.p50
    );
    let _ = writeln!(
        out,
        "## Window quantities (median, p10–p90), and how well each alone tells generated from real (AUC; 0.5 = same)\n"
    );
    let _ = writeln!(
        out,
        "| quantity | real C | generated C | real NC | generated NC | separation AUC |\n|---|---|---|---|---|---|"
    );
    let spread = |m: &measure::ClassSummary, q: &str| {
        m.quantities.get(q).map_or("–".to_owned(), |x| {
            format!("{:.4} ({:.4}–{:.4})", x.p50, x.p10, x.p90)
        })
    };
    for q in QUANTITIES {
        let _ = writeln!(
            out,
            "| {q} | {} | {} | {} | {} | {:.2} |",
            spread(&r.crossing, q),
            spread(&s.crossing, q),
            spread(&r.not_crossing, q),
            spread(&s.not_crossing, q),
            c.separation.get(q).copied().unwrap_or(f64::NAN)
        );
    }
    let _ = writeln!(
        out,
        "\n## Cues: how well each quantity tells crossing from not-crossing windows (AUC; 0.5 none, < 0.5 reversed)\n"
    );
    let _ = writeln!(out, "| quantity | real | generated | difference |\n|---|---|---|---|");
    for q in QUANTITIES {
        let (a, b) = (
            r.cues.get(q).copied().unwrap_or(f64::NAN),
            s.cues.get(q).copied().unwrap_or(f64::NAN),
        );
        let _ = writeln!(out, "| {q} | {a:.2} | {b:.2} | {:+.2} |", b - a);
    }
    let _ = writeln!(
        out,
        "\n## The ego's action and the pedestrian's in each window's last frame (shares)\n"
    );
    let _ = writeln!(
        out,
        "| | real C | generated C | real NC | generated NC |\n|---|---|---|---|---|"
    );
    let pct = |x: Option<f64>| x.map_or("–".to_owned(), |x| format!("{:.0} %", 100.0 * x));
    for a in EgoAction::ALL {
        let get = |m: &measure::ClassSummary| pct(m.ego_actions.get(a.name()).copied());
        let _ = writeln!(
            out,
            "| ego {} | {} | {} | {} | {} |",
            a.name(),
            get(&r.crossing),
            get(&s.crossing),
            get(&r.not_crossing),
            get(&s.not_crossing)
        );
    }
    let _ = writeln!(
        out,
        "| standing | {} | {} | {} | {} |",
        pct(r.crossing.standing),
        pct(s.crossing.standing),
        pct(r.not_crossing.standing),
        pct(s.not_crossing.standing)
    );
    let _ = writeln!(
        out,
        "| looking | {} | {} | {} | {} |",
        pct(r.crossing.looking),
        pct(s.crossing.looking),
        pct(r.not_crossing.looking),
        pct(s.not_crossing.looking)
    );
    out
}
