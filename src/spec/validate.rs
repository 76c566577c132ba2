//! Semantic validation of a typed spec: ranges, `[min, max]` order, mixes summing to 1, names, reachability
//! of the target crossing ratio, referenced files and sanity limits. Problems point at the user's YAML
//! (or at the nearest enclosing key when the value is a default).

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

    /// H.264 video (4:2:0, OpenH264): an even width and height, at most 3840 × 2160 (or 2160 × 3840).
    fn h264_size(&mut self, rgb: &Rgb) {
        for (path, value) in [
            ("sensors.rgb.width_px", rgb.width_px),
            ("sensors.rgb.height_px", rgb.height_px),
        ] {
            if value % 2 != 0 {
                let problem = Problem::new(
                    code::OUT_OF_RANGE,
                    format!("`{path}` must be even for `output.rgb_encoding: h264`, found {value}"),
                )
                .at(self.span(path), "odd")
                .help(format!(
                    "H.264 stores colour at half resolution (4:2:0): use {} or {}, or another rgb_encoding",
                    value - 1,
                    value + 1
                ));
                self.problems.push(problem);
            }
        }
        let (long, short) = (rgb.width_px.max(rgb.height_px), rgb.width_px.min(rgb.height_px));
        if long > 3840 || short > 2160 {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!(
                    "an H.264 video can be at most 3840 × 2160, found {} × {}",
                    rgb.width_px, rgb.height_px
                ),
            )
            .at(self.span("sensors.rgb.width_px"), "too large for H.264")
            .help("OpenH264 encodes up to level 5.2: use png or jpeg for larger images");
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

    fn dataset(&mut self, d: &Dataset, base_dir: &Path) {
        if d.name.trim().is_empty() {
            self.problems.push(
                Problem::new(code::OUT_OF_RANGE, "`dataset.name` must not be empty")
                    .at(self.span("dataset.name"), "empty name"),
            );
        }
        let license_ok = !d.license.is_empty()
            && d.license.len() <= 64
            && d.license
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '+'));
        if !license_ok {
            self.problems.push(
                Problem::new(
                    code::OUT_OF_RANGE,
                    format!("`dataset.license` `{}` is not a licence identifier", d.license),
                )
                .at(self.span("dataset.license"), "not an identifier")
                .help("an SPDX-style id as the Hugging Face Hub lists them (cc-by-4.0, cc0-1.0, mit), `other` or `unknown`"),
            );
        }
        if d.towns.is_empty() {
            self.problems.push(
                Problem::new(code::OUT_OF_RANGE, "`dataset.towns` must name at least one town")
                    .at(self.span("dataset.towns"), "no towns")
                    .help("e.g. towns: [town01_like]"),
            );
        }
        let mut seen = BTreeSet::new();
        for (i, town) in d.towns.iter().enumerate() {
            let path = format!("dataset.towns[{i}]");
            if let TownRef::OpenDrive(t) = town {
                self.name(&format!("{path}.name"), &t.name, "town");
                let file = base_dir.join(&t.opendrive);
                if !file.is_file() {
                    let problem = Problem::new(
                        code::MISSING_FILE,
                        format!("OpenDRIVE file `{}` does not exist", t.opendrive),
                    )
                    .at(self.span(&format!("{path}.opendrive")), "no such file")
                    .help(format!(
                        "paths are relative to the spec's directory (`{}`)",
                        if base_dir.as_os_str().is_empty() {
                            ".".to_owned()
                        } else {
                            base_dir.display().to_string()
                        }
                    ));
                    self.problems.push(problem);
                }
            }
            if !seen.insert(town.name().to_owned()) {
                self.problems.push(
                    Problem::new(code::DUPLICATE_NAME, format!("town `{}` is listed twice", town.name()))
                        .at(self.span(&path), "listed again here")
                        .help("list each town once; use `dataset.clips` to get more clips"),
                );
            }
        }
        let weathers = d.weathers.resolved();
        if weathers.is_empty() {
            self.problems.push(
                Problem::new(code::OUT_OF_RANGE, "`dataset.weathers` must name at least one weather")
                    .at(self.span("dataset.weathers"), "no weathers")
                    .help("e.g. weathers: [clear_noon], or weathers: all"),
            );
        }
        let mut seen_weather = BTreeSet::new();
        for (i, w) in weathers.iter().enumerate() {
            let path = format!("dataset.weathers[{i}]");
            if let WeatherRef::Custom(c) = w {
                self.name(&format!("{path}.name"), &c.name, "weather");
                let p = &c.params;
                self.num(
                    &format!("{path}.sun_altitude_deg"),
                    p.sun_altitude_deg,
                    -90.0,
                    90.0,
                    "the sun's altitude in degrees",
                );
                self.num(
                    &format!("{path}.sun_azimuth_deg"),
                    p.sun_azimuth_deg,
                    0.0,
                    360.0,
                    "the sun's azimuth in degrees",
                );
                for (key, value) in [
                    ("cloudiness_pct", p.cloudiness_pct),
                    ("precipitation_pct", p.precipitation_pct),
                    ("fog_density_pct", p.fog_density_pct),
                    ("wetness_pct", p.wetness_pct),
                    ("wind_intensity_pct", p.wind_intensity_pct),
                ] {
                    self.num(&format!("{path}.{key}"), value, 0.0, 100.0, "a percentage");
                }
            }
            if !seen_weather.insert(w.name().to_owned()) {
                self.problems.push(
                    Problem::new(code::DUPLICATE_NAME, format!("weather `{}` is listed twice", w.name()))
                        .at(self.span(&path), "listed again here"),
                );
            }
        }
        self.num(
            "dataset.clips.count",
            f64::from(d.clips.count),
            1.0,
            f64::from(u32::MAX),
            "the number of clips",
        );
        self.range(
            "dataset.clip_duration_s",
            d.clip_duration_s,
            1.0,
            600.0,
            "a clip duration in seconds",
        );
        self.num("dataset.fps", f64::from(d.fps), 1.0, 240.0, "the frame rate");
        let known: Vec<&str> = d
            .towns
            .iter()
            .map(TownRef::name)
            .chain(BuiltinTown::ALL.iter().map(|t| t.name()))
            .collect();
        for town in d.splits.keys() {
            if !known.contains(&town.as_str()) {
                let path = format!("dataset.splits.{town}");
                let problem = Problem::new(
                    code::UNKNOWN_NAME,
                    format!("`dataset.splits` names unknown town `{town}`"),
                )
                .at(self.key_span(&path), "unknown town")
                .help(suggestion(town, &known));
                self.problems.push(problem);
            }
        }
    }

    fn pedestrians(&mut self, p: &Pedestrians) {
        self.count_range(
            "pedestrians.per_clip",
            p.per_clip,
            0,
            200,
            "a number of pedestrians per clip",
        );
        let names: Vec<&str> = p.archetypes.keys().map(String::as_str).collect();
        for name in p.archetype_mix.keys() {
            if !p.archetypes.contains_key(name) {
                let path = format!("pedestrians.archetype_mix.{name}");
                let problem = Problem::new(
                    code::UNKNOWN_NAME,
                    format!("unknown archetype `{name}` in `pedestrians.archetype_mix`"),
                )
                .at(self.key_span(&path), "unknown archetype")
                .help(format!(
                    "{} New archetypes are defined under `pedestrians.archetypes`.",
                    suggestion(name, &names)
                ));
                self.problems.push(problem);
            }
        }
        let shares: Vec<(&str, f64)> = p.archetype_mix.iter().map(|(n, s)| (n.as_str(), *s)).collect();
        self.mix("pedestrians.archetype_mix", &shares);
        for (name, a) in &p.archetypes {
            let base = format!("pedestrians.archetypes.{name}");
            self.name(&base, name, "archetype");
            self.range(
                &format!("{base}.speed_mps"),
                a.speed_mps,
                0.1,
                5.0,
                "a walking speed in m/s",
            );
            self.range(
                &format!("{base}.hesitation_s"),
                a.hesitation_s,
                0.0,
                60.0,
                "a hesitation duration in seconds",
            );
            self.probability(&format!("{base}.attention"), a.attention);
            self.probability(&format!("{base}.crossing_probability"), a.crossing_probability);
            self.range(
                &format!("{base}.ttc_threshold_s"),
                a.ttc_threshold_s,
                0.0,
                30.0,
                "a time-to-collision threshold in seconds",
            );
            self.range(
                &format!("{base}.patience_s"),
                a.patience_s,
                0.5,
                600.0,
                "a waiting time in seconds",
            );
            self.probability(&format!("{base}.distraction_probability"), a.distraction_probability);
            self.probability(
                &format!("{base}.red_light_violation_probability"),
                a.red_light_violation_probability,
            );
        }
        let sp = &p.speed_profiles;
        self.mix(
            "pedestrians.speed_profiles.mix",
            &[
                ("cautious", sp.mix.cautious),
                ("normal", sp.mix.normal),
                ("rushed", sp.mix.rushed),
                ("distracted", sp.mix.distracted),
            ],
        );
        let m = &sp.multipliers;
        for (name, value) in [
            ("cautious", m.cautious),
            ("normal", m.normal),
            ("rushed", m.rushed),
            ("distracted", m.distracted),
        ] {
            self.positive(
                &format!("pedestrians.speed_profiles.multipliers.{name}"),
                value,
                3.0,
                "a speed multiplier",
            );
        }
        let g = &p.gestures;
        self.probability(
            "pedestrians.gestures.acknowledge_probability",
            g.acknowledge_probability,
        );
        self.probability("pedestrians.gestures.nod_share", g.nod_share);
        self.probability(
            "pedestrians.gestures.wave_through_probability",
            g.wave_through_probability,
        );
    }

    fn crossing(&mut self, c: &Crossing) {
        self.probability("crossing.target_ratio", c.target_ratio);
        self.probability("crossing.baseline_ratio", c.baseline_ratio);
        let l = &c.layers;
        self.probability(
            "crossing.layers.crosser_allocation.max_crosser_ratio",
            l.crosser_allocation.max_crosser_ratio,
        );
        self.range(
            "crossing.layers.crosser_allocation.spawn_ahead_m",
            l.crosser_allocation.spawn_ahead_m,
            0.0,
            200.0,
            "a distance ahead of the ego in metres",
        );
        let b = &l.behaviour_mix.mix;
        self.mix(
            "crossing.layers.behaviour_mix.mix",
            &[("normal", b.normal), ("sudden", b.sudden), ("jaywalk", b.jaywalk)],
        );
        self.probability(
            "crossing.layers.midroad_jaywalkers.share_of_crossers",
            l.midroad_jaywalkers.share_of_crossers,
        );
        self.num(
            "crossing.layers.midroad_jaywalkers.lateral_offset_m",
            l.midroad_jaywalkers.lateral_offset_m,
            0.0,
            5.0,
            "a lateral offset in metres",
        );
        self.probability("crossing.layers.groups.probability", l.groups.probability);
        self.mix(
            "crossing.layers.groups.size_mix",
            &[
                ("pairs", l.groups.size_mix.pairs),
                ("triples", l.groups.size_mix.triples),
            ],
        );
        self.range(
            "crossing.gap_acceptance.safety_margin_s",
            c.gap_acceptance.safety_margin_s,
            0.0,
            10.0,
            "a safety margin in seconds",
        );
        self.positive(
            "crossing.gap_acceptance.vehicle_range_m",
            c.gap_acceptance.vehicle_range_m,
            500.0,
            "a distance in metres",
        );
        if c.lookahead.points_m.is_empty() {
            self.problems.push(
                Problem::new(
                    code::OUT_OF_RANGE,
                    "`crossing.lookahead.points_m` needs at least one probe distance",
                )
                .at(self.span("crossing.lookahead.points_m"), "empty")
                .help("the paper probes at [0.5, 1.5, 2.5] m"),
            );
        }
        for (i, d) in c.lookahead.points_m.iter().enumerate() {
            self.positive(
                &format!("crossing.lookahead.points_m[{i}]"),
                *d,
                20.0,
                "a probe distance in metres",
            );
        }
        self.num(
            "crossing.lookahead.prediction_s",
            c.lookahead.prediction_s,
            0.0,
            5.0,
            "a prediction horizon in seconds",
        );
        self.positive(
            "crossing.lookahead.radius_m",
            c.lookahead.radius_m,
            20.0,
            "a safety radius in metres",
        );
        self.probability("crossing.retreat.probability", c.retreat.probability);
        self.positive(
            "crossing.retreat.window_fraction",
            c.retreat.window_fraction,
            1.0,
            "a fraction of the crossing path",
        );
        self.range(
            "crossing.retreat.speed_mps",
            c.retreat.speed_mps,
            0.1,
            10.0,
            "a speed in m/s",
        );
        self.probability(
            "crossing.patience.sudden_crossing_probability",
            c.patience.sudden_crossing_probability,
        );
        self.range(
            "crossing.decision_window_m",
            c.decision_window_m,
            0.0,
            200.0,
            "a distance to the ego in metres",
        );
        self.range(
            "crossing.timeline.in_view_before_crossing_s",
            c.timeline.in_view_before_crossing_s,
            0.0,
            60.0,
            "a time in view of the camera in seconds",
        );
        self.range(
            "crossing.timeline.approach_m",
            c.timeline.approach_m,
            0.0,
            100.0,
            "a walking distance in metres",
        );
        self.probability(
            "crossing.hard_negatives.share_of_non_crossers",
            c.hard_negatives.share_of_non_crossers,
        );
        self.range(
            "crossing.hard_negatives.wait_at_curb_s",
            c.hard_negatives.wait_at_curb_s,
            0.0,
            600.0,
            "a waiting time in seconds",
        );

        let before = self.problems.len();
        let (lo, hi) = reachable_crossing_ratio(c);
        let tolerance = if l.crosser_allocation.enabled { 1e-9 } else { 0.02 };
        let target_valid = (0.0..=1.0).contains(&c.target_ratio) && (0.0..=1.0).contains(&c.baseline_ratio);
        if self.problems.len() == before
            && target_valid
            && (c.target_ratio > hi + tolerance || c.target_ratio < lo - tolerance)
        {
            // Only the baseline can miss a target: with layer 1 on, the planner reaches every target in [0, 1].
            let help = format!(
                "with `crossing.layers.crosser_allocation` off only the baseline ({}) crosses: enable it, or set `target_ratio` to the baseline",
                fmt_num(lo)
            );
            let problem = Problem::new(
                code::UNREACHABLE_TARGET,
                format!(
                    "target crossing ratio {} is out of reach: the enabled layers give {} to {}",
                    fmt_num(c.target_ratio),
                    fmt_num(lo),
                    fmt_num(hi)
                ),
            )
            .at(self.span("crossing.target_ratio"), "unreachable target")
            .help(help);
            self.problems.push(problem);
        }
    }

    fn traffic(&mut self, t: &Traffic) {
        self.count_range(
            "traffic.vehicles_per_clip",
            t.vehicles_per_clip,
            0,
            200,
            "a number of vehicles per clip",
        );
        let m = &t.profile_mix;
        self.mix(
            "traffic.profile_mix",
            &[
                ("aggressive", m.aggressive),
                ("normal", m.normal),
                ("cautious", m.cautious),
            ],
        );
        for (name, p) in [
            ("aggressive", &t.profiles.aggressive),
            ("normal", &t.profiles.normal),
            ("cautious", &t.profiles.cautious),
        ] {
            let base = format!("traffic.profiles.{name}");
            self.range(
                &format!("{base}.speed_difference_pct"),
                p.speed_difference_pct,
                -100.0,
                90.0,
                "a percentage below the speed limit (negative: faster)",
            );
            self.range(&format!("{base}.min_gap_m"), p.min_gap_m, 0.1, 50.0, "a gap in metres");
            self.range(
                &format!("{base}.time_headway_s"),
                p.time_headway_s,
                0.1,
                10.0,
                "a time headway in seconds",
            );
            self.probability(
                &format!("{base}.ignore_lights_probability"),
                p.ignore_lights_probability,
            );
            self.probability(
                &format!("{base}.ignore_walkers_probability"),
                p.ignore_walkers_probability,
            );
        }
        self.positive(
            "traffic.idm.max_accel_mps2",
            t.idm.max_accel_mps2,
            10.0,
            "an acceleration in m/s²",
        );
        self.positive(
            "traffic.idm.comfortable_decel_mps2",
            t.idm.comfortable_decel_mps2,
            10.0,
            "a deceleration in m/s²",
        );
        self.positive(
            "traffic.idm.max_decel_mps2",
            t.idm.max_decel_mps2,
            15.0,
            "a deceleration in m/s²",
        );
        self.positive("traffic.idm.exponent", t.idm.exponent, 10.0, "the IDM exponent δ");
        let e = &t.emergency;
        self.probability("traffic.emergency.clip_share", e.clip_share);
        self.mix(
            "traffic.emergency.mix",
            &[
                ("ambulance", e.mix.ambulance),
                ("fire_truck", e.mix.fire_truck),
                ("police", e.mix.police),
            ],
        );
        self.num(
            "traffic.emergency.speed_above_limit_pct",
            e.speed_above_limit_pct,
            0.0,
            100.0,
            "a percentage above the speed limit",
        );
        self.range(
            "traffic.ego.speed_below_limit_pct",
            t.ego.speed_below_limit_pct,
            0.0,
            90.0,
            "a percentage below the speed limit",
        );
        self.positive("traffic.ego.min_gap_m", t.ego.min_gap_m, 50.0, "a gap in metres");
        self.positive(
            "traffic.ego.brake_ahead_m",
            t.ego.brake_ahead_m,
            100.0,
            "a distance in metres",
        );
        self.positive(
            "traffic.ego.brake_lateral_m",
            t.ego.brake_lateral_m,
            20.0,
            "a distance in metres",
        );
        self.num(
            "traffic.ego.route_margin_m",
            t.ego.route_margin_m,
            0.0,
            1000.0,
            "a distance in metres",
        );
        self.range(
            "traffic.ego.courtesy_speed_mps",
            t.ego.courtesy_speed_mps,
            0.0,
            40.0,
            "a speed in m/s",
        );
        self.num(
            "traffic.ego.courtesy_ahead_m",
            t.ego.courtesy_ahead_m,
            0.0,
            200.0,
            "a distance in metres",
        );
        self.num(
            "traffic.ego.courtesy_lateral_m",
            t.ego.courtesy_lateral_m,
            0.0,
            50.0,
            "a distance in metres",
        );
        self.num(
            "traffic.ego.courtesy_stop_short_m",
            t.ego.courtesy_stop_short_m,
            0.0,
            50.0,
            "a distance in metres",
        );
        self.range(
            "traffic.ego.courtesy_patience_s",
            t.ego.courtesy_patience_s,
            0.0,
            120.0,
            "a waiting time in seconds",
        );
        let g = &t.signals;
        self.probability("traffic.signals.crosswalk_share", g.crosswalk_share);
        self.positive("traffic.signals.green_s", g.green_s, 300.0, "a green time in seconds");
        self.num(
            "traffic.signals.amber_s",
            g.amber_s,
            0.0,
            30.0,
            "an amber time in seconds",
        );
        self.num(
            "traffic.signals.all_red_s",
            g.all_red_s,
            0.0,
            60.0,
            "an all-red time in seconds",
        );
        let c = &t.cyclists;
        self.count_range(
            "traffic.cyclists.per_clip",
            c.per_clip,
            0,
            50,
            "a number of cyclists per clip",
        );
        self.range("traffic.cyclists.speed_mps", c.speed_mps, 0.5, 15.0, "a speed in m/s");
        self.num(
            "traffic.cyclists.edge_offset_m",
            c.edge_offset_m,
            0.3,
            3.0,
            "a distance from the lane's right edge in metres",
        );
        self.num(
            "traffic.cyclists.overtaking_clearance_m",
            c.overtaking_clearance_m,
            0.5,
            3.0,
            "a passing clearance in metres",
        );
        self.num(
            "traffic.cyclists.swerve_m",
            c.swerve_m,
            0.0,
            2.0,
            "a distance in metres",
        );
        self.probability(
            "traffic.cyclists.ignore_lights_probability",
            c.ignore_lights_probability,
        );
    }

    fn mount(&mut self, base: &str, m: &Mount) {
        self.num(
            &format!("{base}.forward_m"),
            m.forward_m,
            -10.0,
            10.0,
            "a position in metres",
        );
        self.num(&format!("{base}.left_m"), m.left_m, -5.0, 5.0, "a position in metres");
        self.num(&format!("{base}.up_m"), m.up_m, 0.0, 10.0, "a height in metres");
        self.num(
            &format!("{base}.pitch_deg"),
            m.pitch_deg,
            -90.0,
            90.0,
            "an angle in degrees",
        );
        self.num(
            &format!("{base}.yaw_deg"),
            m.yaw_deg,
            -180.0,
            180.0,
            "an angle in degrees",
        );
        self.num(
            &format!("{base}.roll_deg"),
            m.roll_deg,
            -180.0,
            180.0,
            "an angle in degrees",
        );
    }

    fn sensors(&mut self, s: &Sensors) {
        self.num(
            "sensors.rgb.width_px",
            f64::from(s.rgb.width_px),
            16.0,
            16384.0,
            "an image width in pixels",
        );
        self.num(
            "sensors.rgb.height_px",
            f64::from(s.rgb.height_px),
            16.0,
            16384.0,
            "an image height in pixels",
        );
        self.num(
            "sensors.rgb.fov_deg",
            s.rgb.fov_deg,
            1.0,
            170.0,
            "a horizontal field of view in degrees",
        );
        self.mount("sensors.rgb.mount", &s.rgb.mount);
        let l = &s.lidar;
        self.num(
            "sensors.lidar.channels",
            f64::from(l.channels),
            1.0,
            256.0,
            "a number of laser channels",
        );
        self.positive("sensors.lidar.range_m", l.range_m, 1000.0, "a range in metres");
        self.num(
            "sensors.lidar.points_per_second",
            f64::from(l.points_per_second),
            1.0,
            10_000_000.0,
            "points per second",
        );
        self.positive(
            "sensors.lidar.rotation_hz",
            l.rotation_hz,
            100.0,
            "a rotation frequency in Hz",
        );
        self.num(
            "sensors.lidar.upper_fov_deg",
            l.upper_fov_deg,
            -90.0,
            90.0,
            "an elevation in degrees",
        );
        self.num(
            "sensors.lidar.lower_fov_deg",
            l.lower_fov_deg,
            -90.0,
            90.0,
            "an elevation in degrees",
        );
        if l.lower_fov_deg > l.upper_fov_deg {
            self.problems.push(
                Problem::new(
                    code::EMPTY_RANGE,
                    format!(
                        "`sensors.lidar.lower_fov_deg` ({}) is above `upper_fov_deg` ({})",
                        fmt_num(l.lower_fov_deg),
                        fmt_num(l.upper_fov_deg)
                    ),
                )
                .at(self.span("sensors.lidar.lower_fov_deg"), "lower")
                .also(self.span("sensors.lidar.upper_fov_deg"), "upper")
                .help("the bottom channel's elevation must not exceed the top channel's"),
            );
        }
        self.positive(
            "sensors.lidar.horizontal_fov_deg",
            l.horizontal_fov_deg,
            360.0,
            "an angle in degrees",
        );
        self.num(
            "sensors.lidar.atmosphere_attenuation_per_m",
            l.atmosphere_attenuation_per_m,
            0.0,
            1.0,
            "an attenuation rate per metre",
        );
        self.probability("sensors.lidar.dropoff_general_rate", l.dropoff_general_rate);
        self.probability("sensors.lidar.dropoff_intensity_limit", l.dropoff_intensity_limit);
        self.probability("sensors.lidar.dropoff_zero_intensity", l.dropoff_zero_intensity);
        self.num(
            "sensors.lidar.noise_stddev_m",
            l.noise_stddev_m,
            0.0,
            1.0,
            "a noise level in metres",
        );
        self.mount("sensors.lidar.mount", &l.mount);
        let d = &s.dvs;
        self.positive(
            "sensors.dvs.positive_threshold",
            d.positive_threshold,
            10.0,
            "a log-intensity contrast threshold",
        );
        self.positive(
            "sensors.dvs.negative_threshold",
            d.negative_threshold,
            10.0,
            "a log-intensity contrast threshold",
        );
        self.num(
            "sensors.dvs.sigma_positive_threshold",
            d.sigma_positive_threshold,
            0.0,
            10.0,
            "a standard deviation",
        );
        self.num(
            "sensors.dvs.sigma_negative_threshold",
            d.sigma_negative_threshold,
            0.0,
            10.0,
            "a standard deviation",
        );
        self.positive(
            "sensors.dvs.log_eps",
            d.log_eps,
            1.0,
            "an epsilon added before the logarithm",
        );
        self.num(
            "sensors.dvs.substeps",
            f64::from(d.substeps),
            1.0,
            16.0,
            "images rendered per frame interval",
        );
    }

    fn annotations(&mut self, a: &Annotations) {
        let v = &a.visibility;
        if !v.require_in_front {
            let path = "annotations.visibility.require_in_front";
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!("`{path}` must be true: stage 2 of the gate cannot be turned off"),
            )
            .at(self.span(path), "must be true")
            .help("a pedestrian behind the camera has no image box, so it is never annotated; remove the key");
            self.problems.push(problem);
        }
        self.positive(
            "annotations.visibility.max_distance_m",
            v.max_distance_m,
            1000.0,
            "a distance in metres",
        );
        self.box_size("annotations.visibility.min_box_px", v.min_box_px);
        self.positive(
            "annotations.visibility.far_distance_m",
            v.far_distance_m,
            1000.0,
            "a distance in metres",
        );
        self.box_size("annotations.visibility.min_box_far_px", v.min_box_far_px);
        self.probability("annotations.visibility.max_occlusion", v.max_occlusion);
        self.num(
            "annotations.crossing_label_smoothing_frames",
            f64::from(a.crossing_label_smoothing_frames),
            0.0,
            300.0,
            "a number of frames",
        );
        self.positive(
            "annotations.look_cone_deg",
            a.look_cone_deg,
            90.0,
            "the half-angle of the cone around the gaze in which the camera counts as looked at, degrees",
        );
    }

    fn limits(&mut self, spec: &Spec) {
        let limits = &spec.limits;
        let clips = clip_count(spec);
        if clips > limits.max_clips {
            let problem = Problem::new(
                code::TOO_LARGE,
                format!(
                    "the spec asks for {clips} clips, above the limit of {}",
                    limits.max_clips
                ),
            )
            .at(self.span("dataset.clips.count"), format!("{clips} clips in all"))
            .help("pass --allow-large if you mean it, or raise `limits.max_clips`");
            self.problems.push(problem);
        }
        let pixels = u64::from(spec.sensors.rgb.width_px) * u64::from(spec.sensors.rgb.height_px);
        if pixels > limits.max_image_pixels {
            let problem = Problem::new(
                code::TOO_LARGE,
                format!(
                    "images of {pixels} pixels exceed the limit of {}",
                    limits.max_image_pixels
                ),
            )
            .at(self.span("sensors.rgb.width_px"), "image too large")
            .help("pass --allow-large if you mean it, or raise `limits.max_image_pixels`");
            self.problems.push(problem);
        }
        let bytes = rough_dataset_bytes(spec);
        if bytes > limits.max_dataset_bytes as f64 {
            let problem = Problem::new(
                code::TOO_LARGE,
                format!(
                    "the dataset would take about {:.1} TB, above the limit of {:.1} TB",
                    bytes / 1e12,
                    limits.max_dataset_bytes as f64 / 1e12
                ),
            )
            .at(self.key_span("dataset.clips"), "too much data")
            .help("pass --allow-large if you mean it, disable sensors, or raise `limits.max_dataset_bytes`");
            self.problems.push(problem);
        }
    }
}
