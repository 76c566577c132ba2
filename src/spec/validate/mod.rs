//! Semantic validation of a typed spec: ranges, `[min, max]` order, mixes summing to 1, names, reachability
//! of the target crossing ratio, referenced files and sanity limits. Problems point at the user's YAML
//! (or at the nearest enclosing key when the value is a default).

mod behaviour;
mod dataset;
mod sensors;
mod traffic;

use std::collections::BTreeSet;
use std::path::Path;

use super::diagnostic::{Problem, code, suggestion};
use super::tree::{Node, PathSeg, Span, Value, parse_path};
use super::types::*;

/// Tolerance on a mix's sum.
const MIX_TOLERANCE: f64 = 1e-6;

/// Validates `spec` (already merged onto the defaults); `tree` is the user's YAML for locating problems.
/// With `allow_large`, the sanity limits are not checked (`--allow-large`).
pub fn validate(spec: &Spec, tree: &Node, base_dir: &Path, allow_large: bool, problems: &mut Vec<Problem>) {
    let mut v = Validator { tree, problems };
    v.dataset(&spec.dataset, base_dir);
    v.pedestrians(&spec.pedestrians);
    v.crossing(&spec.crossing);
    v.traffic(&spec.traffic);
    v.sensors(&spec.sensors);
    v.annotations(&spec.annotations);
    v.domain_randomisation(&spec.domain_randomisation);
    v.num(
        "output.zstd_level",
        f64::from(spec.output.zstd_level),
        1.0,
        22.0,
        "a zstd level",
    );
    v.num(
        "output.jpeg_quality",
        f64::from(spec.output.jpeg_quality),
        1.0,
        100.0,
        "a JPEG quality",
    );
    v.num(
        "output.h264_qp",
        f64::from(spec.output.h264_qp),
        0.0,
        51.0,
        "an H.264 quantiser (0 best, 51 smallest)",
    );
    if spec.output.rgb_encoding == RgbEncoding::H264 && spec.sensors.rgb.enabled {
        v.h264_size(&spec.sensors.rgb);
    }
    if !allow_large {
        v.limits(spec);
    }
    super::not_yet::check(spec, tree, problems);
}

/// Number of clips a spec asks for.
pub fn clip_count(spec: &Spec) -> u64 {
    let weathers = spec.dataset.weathers.resolved().len() as u64;
    let towns = spec.dataset.towns.len() as u64;
    let count = u64::from(spec.dataset.clips.count);
    match spec.dataset.clips.per {
        ClipsPer::Weather => count * weathers,
        ClipsPer::TownAndWeather => count * weathers * towns,
    }
}

/// A rough upper estimate of a dataset's size in bytes, for the sanity limit (the planner gives a finer
/// estimate). Assumes ~1 byte per pixel for a PNG frame, 16 bytes per kept LiDAR point, events on 2% of the
/// pixels per frame at 13 bytes each, and ~300 bytes of tables per pedestrian-frame.
pub fn rough_dataset_bytes(spec: &Spec) -> f64 {
    let frames = clip_count(spec) as f64 * spec.dataset.clip_duration_s.mid() * f64::from(spec.dataset.fps);
    let s = &spec.sensors;
    let pixels = f64::from(s.rgb.width_px) * f64::from(s.rgb.height_px);
    let mut per_frame = 300.0 * f64::from(spec.pedestrians.per_clip.max());
    if s.rgb.enabled {
        per_frame += pixels;
    }
    if s.lidar.enabled {
        per_frame += f64::from(s.lidar.points_per_second) / f64::from(spec.dataset.fps.max(1))
            * (1.0 - s.lidar.dropoff_general_rate)
            * 16.0;
    }
    if s.dvs.enabled {
        per_frame += pixels * 0.02 * 13.0;
    }
    frames * per_frame
}

/// The share of pedestrians the enabled layers can make cross, as `(lowest, highest)`. With layer 1 on, every
/// target: the planner lowers the baseline for targets below it (`plan::baseline_crosser_ratio`) and adapts
/// the layers for targets above what they reach (`plan::crossing_adaptation`; a target of 1 lands near
/// [`crate::plan::calibration::MIDROAD_LADDER`]'s last realisation, which `pedsynth plan` prints).
pub fn reachable_crossing_ratio(crossing: &Crossing) -> (f64, f64) {
    let l1 = &crossing.layers.crosser_allocation;
    if l1.enabled {
        (0.0, 1.0)
    } else {
        (crossing.baseline_ratio, crossing.baseline_ratio)
    }
}

fn fmt_num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".to_owned()
    } else {
        s.to_owned()
    }
}

fn is_identifier(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

struct Validator<'a> {
    tree: &'a Node,
    problems: &'a mut Vec<Problem>,
}

impl Validator<'_> {
    fn path(text: &str) -> Vec<PathSeg> {
        parse_path(text).unwrap_or_default()
    }

    fn span(&self, path: &str) -> Span {
        self.tree.span_at(&Self::path(path))
    }

    fn key_span(&self, path: &str) -> Span {
        let p = Self::path(path);
        self.tree.key_span_at(&p).unwrap_or_else(|| self.tree.span_at(&p))
    }

    /// `lo ≤ value ≤ hi`.
    fn num(&mut self, path: &str, value: f64, lo: f64, hi: f64, what: &str) {
        if !(lo..=hi).contains(&value) || !value.is_finite() {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!(
                    "`{path}` must be between {} and {}, found {}",
                    fmt_num(lo),
                    fmt_num(hi),
                    fmt_num(value)
                ),
            )
            .at(
                self.span(path),
                format!("out of range [{}, {}]", fmt_num(lo), fmt_num(hi)),
            )
            .help(format!("`{path}` is {what}"));
            self.problems.push(problem);
        }
    }

    /// `lo < value ≤ hi`.
    fn positive(&mut self, path: &str, value: f64, hi: f64, what: &str) {
        if !(value > 0.0 && value <= hi) {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!(
                    "`{path}` must be above 0 and at most {}, found {}",
                    fmt_num(hi),
                    fmt_num(value)
                ),
            )
            .at(self.span(path), format!("out of range (0, {}]", fmt_num(hi)))
            .help(format!("`{path}` is {what}"));
            self.problems.push(problem);
        }
    }

    fn probability(&mut self, path: &str, value: f64) {
        self.num(path, value, 0.0, 1.0, "a probability or share (0–1)");
    }

    /// A `[min, max]` range: both ends within `[lo, hi]` and min ≤ max.
    fn range(&mut self, path: &str, r: Range, lo: f64, hi: f64, what: &str) {
        let before = self.problems.len();
        self.num(&format!("{path}[0]"), r.min(), lo, hi, what);
        self.num(&format!("{path}[1]"), r.max(), lo, hi, what);
        if self.problems.len() == before && r.min() > r.max() {
            let problem = Problem::new(
                code::EMPTY_RANGE,
                format!("`{path}` has min {} > max {}", fmt_num(r.min()), fmt_num(r.max())),
            )
            .at(self.span(&format!("{path}[0]")), "min")
            .also(self.span(&format!("{path}[1]")), "max")
            .help("write the range as [min, max] with min ≤ max");
            self.problems.push(problem);
        }
    }

    /// A box size: width and height each in `[0, 4096]` pixels (either may be the larger).
    fn box_size(&mut self, path: &str, b: BoxSize) {
        let list = matches!(self.tree.at(&Self::path(path)).map(|n| &n.value), Some(Value::Seq(_)));
        let (w, h) = if list {
            (format!("{path}[0]"), format!("{path}[1]"))
        } else {
            (format!("{path}.width_px"), format!("{path}.height_px"))
        };
        self.num(&w, b.width_px, 0.0, 4096.0, "a box width in pixels");
        self.num(&h, b.height_px, 0.0, 4096.0, "a box height in pixels");
    }

    fn count_range(&mut self, path: &str, r: CountRange, lo: u32, hi: u32, what: &str) {
        self.range(
            path,
            Range(f64::from(r.min()), f64::from(r.max())),
            f64::from(lo),
            f64::from(hi),
            what,
        );
    }

    /// Each share in `[0, 1]` and the shares sum to 1.
    fn mix(&mut self, path: &str, shares: &[(&str, f64)]) {
        let before = self.problems.len();
        for (name, share) in shares {
            self.probability(&format!("{path}.{name}"), *share);
        }
        let sum: f64 = shares.iter().map(|(_, s)| s).sum();
        if self.problems.len() == before && (sum - 1.0).abs() > MIX_TOLERANCE {
            let terms: Vec<String> = shares
                .iter()
                .filter(|(_, s)| *s != 0.0)
                .map(|(n, s)| format!("{n} {}", fmt_num(*s)))
                .collect();
            let problem = Problem::new(
                code::MIX_SUM,
                format!("the shares of `{path}` sum to {}, not 1", fmt_num(sum)),
            )
            .at(self.key_span(path), format!("sum = {}", fmt_num(sum)))
            .help(format!(
                "make the shares sum to 1 ({} = {})",
                terms.join(" + "),
                fmt_num(sum)
            ));
            self.problems.push(problem);
        }
    }

    fn name(&mut self, path: &str, name: &str, what: &str) {
        if !is_identifier(name) {
            let problem = Problem::new(code::INVALID_NAME, format!("{what} name `{name}` is not a valid name"))
                .at(self.span(path), "invalid name")
                .help("use 1–64 lowercase letters, digits and `_` (names appear in clip ids and file names)");
            self.problems.push(problem);
        }
    }
}
