//! Validation of `dataset` (towns, weathers, clips, splits, seeds) and the sanity limits on a whole spec.

use super::*;

impl Validator<'_> {
    pub(super) fn dataset(&mut self, d: &Dataset, base_dir: &Path) {
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
        self.num(
            "dataset.max_extension_s",
            d.max_extension_s,
            0.0,
            600.0,
            "a lengthening in seconds",
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

    pub(super) fn limits(&mut self, spec: &Spec) {
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
