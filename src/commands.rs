//! The command implementations behind the CLI: each takes parsed arguments and output streams and returns a
//! process exit code (0 ok, 1 other failure, 2 invalid input).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use crate::dsl::types::TownRef;
use crate::dsl::{self, LoadOptions, LoadedSpec, validate};
use crate::planner::{self, Plan, TownContext};
use crate::world::RoadNetwork;

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

/// Renders any diagnostic without colour at the fixed width.
pub fn render_diagnostic(diagnostic: &dyn miette::Diagnostic) -> String {
    let handler = miette::GraphicalReportHandler::new_themed(miette::GraphicalTheme::unicode_nocolor())
        .with_width(DIAGNOSTIC_WIDTH)
        .with_links(false);
    let mut out = String::new();
    let _ = handler.render_report(&mut out, diagnostic);
    out
}

/// Loads every town a spec names (built-in towns are generated, OpenDRIVE maps read relative to the spec).
pub fn load_towns(loaded: &LoadedSpec) -> Result<BTreeMap<String, TownContext>, String> {
    load_spec_towns(&loaded.spec, &loaded.base_dir)
}

/// Loads the towns of `spec`, resolving OpenDRIVE paths against `base_dir`.
pub fn load_spec_towns(
    spec: &crate::dsl::Spec,
    base_dir: &std::path::Path,
) -> Result<BTreeMap<String, TownContext>, String> {
    let mut towns = BTreeMap::new();
    for town in &spec.dataset.towns {
        let network = match town {
            TownRef::Builtin(t) => RoadNetwork::builtin(t.name())
                .ok_or_else(|| format!("built-in town `{}` is not available", t.name()))?,
            TownRef::OpenDrive(t) => {
                let mut network =
                    RoadNetwork::from_xodr_file(&base_dir.join(&t.opendrive)).map_err(|e| render_diagnostic(&e))?;
                network.name = t.name.clone();
                network
            }
        };
        towns.insert(town.name().to_owned(), TownContext::new(network));
    }
    Ok(towns)
}

/// Options of `pedsynth plan`.
#[derive(Clone, Debug, Default)]
pub struct PlanArgs {
    /// Print JSON instead of tables.
    pub json: bool,
    /// Write the plan to this file.
    pub emit: Option<PathBuf>,
    /// Plan only this clip.
    pub only: Option<String>,
}

/// Loads a spec and its towns and compiles the plan; problems are rendered to `err` and become the exit code.
pub fn compile_plan(
    spec_path: &std::path::Path,
    options: &LoadOptions,
    only: Option<&str>,
    err: &mut dyn Write,
) -> Result<(LoadedSpec, Plan), i32> {
    let loaded = match dsl::load_file(spec_path, options) {
        Ok(loaded) => loaded,
        Err(errors) => {
            let _ = err.write_all(errors.render_plain(DIAGNOSTIC_WIDTH).as_bytes());
            return Err(exit::INVALID);
        }
    };
    let towns = match load_towns(&loaded) {
        Ok(towns) => towns,
        Err(message) => {
            let _ = writeln!(err, "{message}");
            return Err(exit::INVALID);
        }
    };
    match planner::plan(
        &loaded.spec,
        &loaded.hash(),
        &loaded.base_dir.display().to_string(),
        &towns,
        only,
    ) {
        Ok(plan) => Ok((loaded, plan)),
        Err(problems) => {
            let _ = writeln!(
                err,
                "{}: the spec cannot be planned ({} problem{}):",
                loaded.name,
                problems.len(),
                if problems.len() == 1 { "" } else { "s" }
            );
            for p in &problems {
                let _ = writeln!(err, "  × pedsynth::plan::infeasible: {p}");
            }
            let _ = writeln!(
                err,
                "  help: widen the spawn distances, lower the pedestrian or vehicle counts, or use a larger town"
            );
            Err(exit::INVALID)
        }
    }
}

/// `pedsynth plan SPEC`: prints dry-run statistics, and writes the plan with `--emit`.
pub fn plan(
    spec_path: &std::path::Path,
    options: &LoadOptions,
    args: &PlanArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> i32 {
    let (loaded, plan) = match compile_plan(spec_path, options, args.only.as_deref(), err) {
        Ok(x) => x,
        Err(code) => return code,
    };
    if let Some(path) = &args.emit {
        let mut json = serde_json::to_string_pretty(&plan).unwrap_or_default();
        json.push('\n');
        if let Err(e) = crate::fsutil::write_atomically(path, json.as_bytes()) {
            let _ = writeln!(err, "cannot write plan to {}: {e}", path.display());
            return exit::FAILURE;
        }
    }
    let stats = planner::stats::compute(&plan, &loaded.spec);
    let text = if args.json {
        let mut t = serde_json::to_string_pretty(&stats).unwrap_or_default();
        t.push('\n');
        t
    } else {
        planner::stats::render_text(&stats)
    };
    match out.write_all(text.as_bytes()) {
        Ok(()) => exit::OK,
        Err(_) => exit::FAILURE,
    }
}

/// `pedsynth town list`.
pub fn town_list(out: &mut dyn Write) -> i32 {
    match out.write_all(crate::world::town_list_text().as_bytes()) {
        Ok(()) => exit::OK,
        Err(_) => exit::FAILURE,
    }
}

/// `pedsynth town show NAME_OR_XODR [--png OUT] [--json]`.
pub fn town_show(
    town: &str,
    png: Option<&std::path::Path>,
    json: bool,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> i32 {
    match crate::world::town_show(town, png, json) {
        Ok(text) => match out.write_all(text.as_bytes()) {
            Ok(()) => exit::OK,
            Err(_) => exit::FAILURE,
        },
        Err(e) => {
            let _ = err.write_all(render_diagnostic(&e).as_bytes());
            if matches!(e, crate::world::WorldError::Io { .. }) {
                exit::FAILURE
            } else {
                exit::INVALID
            }
        }
    }
}

/// Options of `pedsynth generate`.
#[derive(Clone, Debug, Default)]
pub struct GenerateArgs {
    /// Output directory.
    pub out: PathBuf,
    /// Worker threads.
    pub jobs: Option<usize>,
    /// Generate only this clip.
    pub only: Option<String>,
    /// No progress output.
    pub quiet: bool,
}

/// `pedsynth generate SPEC|PLAN --out DIR`: plans (or reads a plan), simulates, annotates and writes.
pub fn generate(
    input: &std::path::Path,
    options: &LoadOptions,
    args: &GenerateArgs,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> i32 {
    let is_plan = input.extension().is_some_and(|e| e == "json");
    let (plan, towns) = if is_plan {
        if !options.overrides.is_empty() {
            let _ = writeln!(
                err,
                "--set applies to specs, not to a plan file: re-plan with `pedsynth plan SPEC --set ... --emit PLAN`"
            );
            return exit::INVALID;
        }
        let plan: Plan = match std::fs::read_to_string(input)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
        {
            Ok(plan) => plan,
            Err(e) => {
                let _ = writeln!(err, "{}: not a pedsynth plan: {e}", input.display());
                return exit::INVALID;
            }
        };
        if plan.format_version != planner::PLAN_FORMAT_VERSION {
            let _ = writeln!(
                err,
                "{}: plan format {} is not supported (this pedsynth reads {})",
                input.display(),
                plan.format_version,
                planner::PLAN_FORMAT_VERSION
            );
            return exit::INVALID;
        }
        match load_spec_towns(&plan.spec, std::path::Path::new(&plan.spec_dir)) {
            Ok(towns) => (plan, towns),
            Err(message) => {
                let _ = writeln!(err, "{message}");
                return exit::INVALID;
            }
        }
    } else {
        let (loaded, plan) = match compile_plan(input, options, None, err) {
            Ok(x) => x,
            Err(code) => return code,
        };
        match load_towns(&loaded) {
            Ok(towns) => (plan, towns),
            Err(message) => {
                let _ = writeln!(err, "{message}");
                return exit::INVALID;
            }
        }
    };
    let gen_options = crate::exec::generate::GenerateOptions {
        out_dir: args.out.clone(),
        jobs: args.jobs,
        only: args.only.clone(),
    };
    match crate::exec::generate::generate(&plan, &towns, &gen_options, args.quiet) {
        Ok(report) => {
            let _ = writeln!(
                out,
                "{}: generated {} clip{} ({} already done): {} frames, {} pedestrian-frames, {} annotated samples\nnext: pedsynth stats {}",
                args.out.display(),
                report.generated,
                if report.generated == 1 { "" } else { "s" },
                report.skipped,
                report.frames,
                report.pedestrian_frames,
                report.samples,
                args.out.display()
            );
            exit::OK
        }
        Err(e @ crate::exec::generate::GenerateError::Refused(_)) => {
            let _ = writeln!(err, "{e}");
            exit::INVALID
        }
        Err(e) => {
            let _ = writeln!(err, "{e}");
            exit::FAILURE
        }
    }
}

/// `pedsynth stats DIR [--json]`: statistics computed from the written tables.
pub fn stats(dir: &std::path::Path, json: bool, out: &mut dyn Write, err: &mut dyn Write) -> i32 {
    match crate::exec::read::stats::compute(dir) {
        Ok(stats) => {
            let text = if json {
                serde_json::to_string_pretty(&stats).unwrap_or_default() + "\n"
            } else {
                crate::exec::read::stats::render_text(&stats)
            };
            match out.write_all(text.as_bytes()) {
                Ok(()) => exit::OK,
                Err(_) => exit::FAILURE,
            }
        }
        Err(e) => {
            let _ = writeln!(err, "cannot read the dataset: {e}");
            exit::INVALID
        }
    }
}

/// Loads a spec file, its towns and its full plan: the programmatic path to a plan (tests, benchmarks, tools).
/// Problems come back as rendered text.
pub fn plan_spec_file(
    path: &std::path::Path,
    options: &LoadOptions,
) -> Result<(LoadedSpec, BTreeMap<String, TownContext>, Plan), String> {
    let loaded = dsl::load_file(path, options).map_err(|e| e.render_plain(DIAGNOSTIC_WIDTH))?;
    let towns = load_towns(&loaded)?;
    let plan = planner::plan(
        &loaded.spec,
        &loaded.hash(),
        &loaded.base_dir.display().to_string(),
        &towns,
        None,
    )
    .map_err(|problems| problems.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("\n"))?;
    Ok((loaded, towns, plan))
}
