//! The command implementations behind the CLI: each takes parsed arguments and output streams and returns a
//! process exit code (0 ok, 1 other failure, 2 invalid input).

use std::io::Write;
use std::path::PathBuf;

use crate::dsl::{self, LoadOptions, LoadedSpec, validate};

/// Process exit codes.
pub mod exit {
    /// Success.
    pub const OK: i32 = 0;
    /// A failure that is not the input's fault (I/O, internal).
    pub const FAILURE: i32 = 1;
    /// Invalid input: a spec, map or argument.
    pub const INVALID: i32 = 2;
}

/// Width diagnostics are rendered at.
pub const DIAGNOSTIC_WIDTH: usize = 100;

/// `pedsynth validate SPEC...`: validates each spec, prints a summary line per valid one (or the fully
/// defaulted spec with `resolved`), and every problem of the invalid ones to `err`.
pub fn validate(
    paths: &[PathBuf],
    options: &LoadOptions,
    resolved: bool,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> i32 {
    let mut code = exit::OK;
    for path in paths {
        match dsl::load_file(path, options) {
            Ok(loaded) => {
                let text = if resolved {
                    dsl::to_yaml(&loaded.spec)
                } else {
                    format!("{}\n", summary_line(&loaded))
                };
                if out.write_all(text.as_bytes()).is_err() {
                    return exit::FAILURE;
                }
            }
            Err(errors) => {
                let _ = err.write_all(errors.render_plain(DIAGNOSTIC_WIDTH).as_bytes());
                code = exit::INVALID;
            }
        }
    }
    code
}

/// One line describing a valid spec.
pub fn summary_line(loaded: &LoadedSpec) -> String {
    let spec = &loaded.spec;
    let d = &spec.dataset;
    let towns = d.towns.len();
    let weathers = d.weathers.resolved().len();
    let sensors: Vec<&str> = [
        ("rgb", spec.sensors.rgb.enabled),
        ("lidar", spec.sensors.lidar.enabled),
        ("dvs", spec.sensors.dvs.enabled),
    ]
    .into_iter()
    .filter_map(|(n, on)| on.then_some(n))
    .collect();
    format!(
        "{}: valid — dataset `{}`: {} clips ({} town{}, {} weather{}), {}–{} s at {} fps, {}–{} pedestrians/clip, target crossing ratio {:.2}, sensors: {}, spec hash {}",
        loaded.name,
        d.name,
        validate::clip_count(spec),
        towns,
        if towns == 1 { "" } else { "s" },
        weathers,
        if weathers == 1 { "" } else { "s" },
        d.clip_duration_s.min(),
        d.clip_duration_s.max(),
        d.fps,
        spec.pedestrians.per_clip.min(),
        spec.pedestrians.per_clip.max(),
        spec.crossing.target_ratio,
        if sensors.is_empty() {
            "none".to_owned()
        } else {
            sensors.join("+")
        },
        &loaded.hash()[..12],
    )
}

/// `pedsynth schema`: prints the spec's JSON Schema.
pub fn schema(out: &mut dyn Write) -> i32 {
    match out.write_all(dsl::schema::spec_schema_text().as_bytes()) {
        Ok(()) => exit::OK,
        Err(_) => exit::FAILURE,
    }
}
