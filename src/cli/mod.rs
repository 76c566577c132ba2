//! The command implementations behind the CLI (the top layer): each takes parsed arguments and an output
//! stream, writes its result there and returns `Ok(())` or an [`Error`]; [`finish`] renders an error and turns
//! it into the process exit code (0 ok, 1 environment failure, 2 invalid input). `src/main.rs` parses the
//! arguments and calls these; the work itself lives in the rooms below.
//!
//! - [`town`] — `pedsynth town list|show|export`.
//! - [`cluster`] — the text of `pedsynth slurm`'s submit script and `pedsynth k8s`'s Indexed Job.

pub mod cluster;
pub mod town;

use std::io::Write;
use std::path::{Path, PathBuf};

pub use crate::dataset::generate::shard::parse_shard;
use crate::dataset::generate::shard::shard_from_env;
use crate::dataset::inputs::{compile_plan, load_input};
use crate::error::{Error, code, exit};
use crate::spec::{self, LoadOptions, LoadedSpec, validate};

/// Why this binary cannot run on this CPU, if it cannot: x86-64 builds use AVX2 (`.cargo/config.toml`), and a
/// CPU without it would stop at the first AVX2 instruction with `SIGILL` instead of a message.
pub fn unsupported_cpu() -> Option<String> {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    if !std::arch::is_x86_feature_detected!("avx2") {
        return Some(
            "error: this build of pedsynth uses AVX2, which this CPU does not have\n  help: build it for every \
             x86-64 CPU (the same outputs, slower): RUSTFLAGS=\"-C target-cpu=x86-64\" cargo build --release\n"
                .to_string(),
        );
    }
    None
}

/// Renders `result`'s error (if any) to `err` and returns the process exit code.
pub fn finish(result: Result<(), Error>, err: &mut dyn Write) -> i32 {
    match result {
        Ok(()) => exit::OK,
        Err(e) => {
            // Nothing more can be reported if stderr itself is closed; the exit code still tells.
            if err.write_all(e.render().as_bytes()).is_err() {
                return exit::FAILURE;
            }
            e.kind().exit_code()
        }
    }
}

/// Writes `text` to `out`.
fn emit(out: &mut dyn Write, text: &str) -> Result<(), Error> {
    out.write_all(text.as_bytes()).map_err(Error::output)
}

/// `pedsynth validate SPEC...`: validates each spec and prints a summary line per valid one (or the fully
/// defaulted spec with `resolved`); every problem of the invalid ones is the error.
pub fn validate(paths: &[PathBuf], options: &LoadOptions, resolved: bool, out: &mut dyn Write) -> Result<(), Error> {
    let mut errors = Vec::new();
    for path in paths {
        match spec::load_file(path, options) {
            Ok(loaded) => {
                let text = if resolved {
                    spec::to_yaml(&loaded.spec)?
                } else {
                    format!("{}\n", summary_line(&loaded)?)
                };
                emit(out, &text)?;
            }
            Err(e) => errors.push(Error::from(e)),
        }
    }
    match errors.len() {
        0 => Ok(()),
        1 => Err(errors.remove(0)),
        _ => Err(Error::Many(errors)),
    }
}

/// One line describing a valid spec.
pub fn summary_line(loaded: &LoadedSpec) -> Result<String, Error> {
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
    Ok(format!(
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
        &loaded.hash()?[..12],
    ))
}

/// `pedsynth schema`: prints the spec's JSON Schema.
pub fn schema(out: &mut dyn Write) -> Result<(), Error> {
    emit(out, &spec::schema::spec_schema_text()?)
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

/// `pedsynth plan SPEC`: prints dry-run statistics, and writes the plan with `--emit`.
pub fn plan(spec_path: &Path, options: &LoadOptions, args: &PlanArgs, out: &mut dyn Write) -> Result<(), Error> {
    let (loaded, plan) = compile_plan(spec_path, options, args.only.as_deref())?;
    if let Some(path) = &args.emit {
        // The spec's directory relative to the plan file's, so that the plan holds no absolute path and still
        // finds the spec's OpenDRIVE files wherever the pair is moved together.
        let mut plan = plan.clone();
        plan.spec_dir = relative_dir(Path::new(&plan.spec_dir), path.parent().unwrap_or(Path::new("")))
            .map_err(|e| Error::read(path, e))?;
        let mut json = crate::error::to_json(&plan, true)?;
        json.push('\n');
        crate::util::files::write_atomically(path, json.as_bytes()).map_err(|e| Error::write(path, e))?;
    }
    let stats = crate::plan::stats::compute(&plan, &loaded.spec);
    let text = if args.json {
        crate::error::to_json(&stats, true)? + "\n"
    } else {
        stats.to_string()
    };
    emit(out, &text)
}

/// `pedsynth town list`.
pub fn town_list(out: &mut dyn Write) -> Result<(), Error> {
    emit(out, &town::town_list_text())
}

/// `pedsynth town show NAME_OR_XODR [--png OUT] [--json]`.
pub fn town_show(town: &str, png: Option<&Path>, json: bool, out: &mut dyn Write) -> Result<(), Error> {
    let text = town::town_show(town, png, json)?;
    emit(out, &text)
}

/// `pedsynth town export NAME --xodr OUT`.
pub fn town_export(town: &str, xodr: &Path, out: &mut dyn Write) -> Result<(), Error> {
    let text = town::town_export(town, xodr)?;
    emit(out, &text)
}

pub use crate::dataset::generate::GenerateOptions as GenerateArgs;

/// `target` relative to `base` (both taken as absolute from the working directory and normalised lexically:
/// `a/b/..` is `a`; symbolic links are not followed), `/`-separated; "." when they are the same directory.
fn relative_dir(target: &Path, base: &Path) -> std::io::Result<String> {
    use std::path::Component;
    let normal = |p: &Path| -> std::io::Result<Vec<String>> {
        let mut out: Vec<String> = Vec::new();
        for c in std::path::absolute(p)?.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                Component::Normal(n) => out.push(n.to_string_lossy().into_owned()),
                Component::RootDir | Component::Prefix(_) => {}
            }
        }
        Ok(out)
    };
    let (t, b) = (normal(target)?, normal(base)?);
    let common = t.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".to_owned(); b.len() - common];
    parts.extend(t[common..].iter().cloned());
    Ok(if parts.is_empty() {
        ".".to_owned()
    } else {
        parts.join("/")
    })
}

/// `pedsynth merge SPEC|PLAN --out DIR [SHARD_DIR...]`: completes a dataset from shard directories.
pub fn merge(
    input: &Path,
    options: &LoadOptions,
    dir: &Path,
    shards: &[PathBuf],
    out: &mut dyn Write,
) -> Result<(), Error> {
    let (plan, _) = load_input(input, options)?;
    let r = crate::dataset::generate::merge::merge(&plan, dir, shards)?;
    emit(
        out,
        &format!(
            "{}: {} clips merged ({} files, {} bytes linked or copied), {} already there; manifest and card written\nnext: pedsynth verify {}\n",
            dir.display(),
            r.merged,
            r.files,
            r.bytes,
            r.kept,
            dir.display()
        ),
    )
}

/// Writes `text` to `file` atomically (made executable when `executable`), or to `out` when no file is given.
fn emit_to(file: Option<&Path>, text: &str, executable: bool, out: &mut dyn Write) -> Result<(), Error> {
    let Some(path) = file else {
        return emit(out, text);
    };
    crate::util::files::write_atomically(path, text.as_bytes()).map_err(|e| Error::write(path, e))?;
    #[cfg(unix)]
    if executable {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).map_err(|e| Error::write(path, e))?;
    }
    Ok(())
}

/// `pedsynth slurm SPEC|PLAN --out DIR --array N ...`: writes the submit script.
pub fn slurm(
    input: &Path,
    options: &LoadOptions,
    slurm: &crate::cli::cluster::SlurmOptions,
    script: Option<&Path>,
    out: &mut dyn Write,
) -> Result<(), Error> {
    let (plan, towns) = load_input(input, options)?;
    let text = crate::cli::cluster::slurm_script(&plan, &towns, slurm)?;
    emit_to(script, &text, true, out)
}

/// `pedsynth k8s SPEC --out DIR --completions N --pvc NAME ...`: writes the Indexed Job manifest.
pub fn k8s(
    input: &Path,
    options: &LoadOptions,
    k8s: &crate::cli::cluster::K8sOptions,
    manifest: Option<&Path>,
    out: &mut dyn Write,
) -> Result<(), Error> {
    let (plan, towns) = load_input(input, options)?;
    let spec_yaml = spec::to_yaml(&plan.header().spec)?;
    let text = crate::cli::cluster::k8s_manifest(&plan, &towns, &spec_yaml, k8s)?;
    emit_to(manifest, &text, false, out)
}

/// `pedsynth generate SPEC|PLAN --out DIR`: plans (or reads a plan), simulates, annotates and writes.
pub fn generate(input: &Path, options: &LoadOptions, args: &GenerateArgs, out: &mut dyn Write) -> Result<(), Error> {
    let mut args = args.clone();
    if args.shard.is_none()
        && let Some(((i, n), source)) = shard_from_env(&|name| std::env::var(name).ok())?
    {
        if !args.quiet {
            // Best effort: the log line says where the shard came from.
            let _ = writeln!(std::io::stderr(), "shard {i}/{n} (from the {source}'s environment)");
        }
        args.shard = Some((i, n));
    }
    let args = &args;
    let (plan, towns) = load_input(input, options)?;
    let report = crate::dataset::generate::generate(&plan, &towns, args)?;
    emit(
        out,
        &format!(
            "{}: generated {} clip{} ({} already done): {} frames, {} pedestrian-frames, {} annotated samples\nnext: pedsynth stats {}\n",
            args.out.display(),
            report.generated,
            if report.generated == 1 { "" } else { "s" },
            report.skipped,
            report.frames,
            report.pedestrian_frames,
            report.samples,
            args.out.display()
        ),
    )
}

/// `pedsynth stats DIR [--json] [--protocol pab ...]`: statistics computed from the written tables, or, with a
/// protocol, what a benchmark's sampling gets from them.
pub fn stats(
    dir: &Path,
    json: bool,
    protocol: Option<&crate::dataset::read::protocol::PabOptions>,
    out: &mut dyn Write,
) -> Result<(), Error> {
    crate::dataset::export::dataset::refuse_unverified(dir)?;
    if let Some(options) = protocol {
        let stats = crate::dataset::read::protocol::compute(dir, options)?;
        let text = if json {
            crate::error::to_json(&stats, true)? + "\n"
        } else {
            stats.to_string()
        };
        return emit(out, &text);
    }
    let stats = crate::dataset::read::stats::compute(dir)?;
    let text = if json {
        crate::error::to_json(&stats, true)? + "\n"
    } else {
        stats.to_string()
    };
    emit(out, &text)
}

/// Where `pedsynth calibrate` reads and writes.
pub struct CalibratePaths<'a> {
    /// The real annotations.
    pub real_dir: &'a Path,
    /// The profile to write.
    pub profile: &'a Path,
    /// A generated dataset to compare with.
    pub compare: Option<&'a Path>,
    /// Where to write the comparison as Markdown.
    pub report: Option<&'a Path>,
}

/// `pedsynth calibrate REAL_DIR --format F --out PROFILE.yaml [--compare DATASET [--report R.md]]`: fits and
/// writes the profile (atomically), prints what was measured and fitted, and the comparison where asked.
pub fn calibrate(
    paths: &CalibratePaths,
    options: &crate::dataset::calibrate::CalibrateOptions,
    json: bool,
    out: &mut dyn Write,
) -> Result<(), Error> {
    use crate::dataset::calibrate as cal;
    if !(options.fov_deg > 1.0 && options.fov_deg < 179.0) {
        return Err(Error::new(
            crate::error::code::REAL_INVALID,
            format!("--fov-deg {} is not a field of view (1–179°)", options.fov_deg),
        ));
    }
    options.pab.validate()?;
    let real = cal::read_real(paths.real_dir, options.format, &options.splits)?;
    let calibration = cal::calibrate(&real, options)?;
    let source = paths.real_dir.file_name().map_or_else(
        || paths.real_dir.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let yaml = cal::profile_yaml(&calibration, &source);
    crate::util::files::write_atomically(paths.profile, yaml.as_bytes()).map_err(|e| Error::write(paths.profile, e))?;
    let comparison = match paths.compare {
        Some(dir) => Some(cal::compare(&real, &cal::synthetic_videos(dir)?, &options.pab)),
        None => None,
    };
    if let (Some(c), Some(report)) = (&comparison, paths.report) {
        let name = paths.compare.map(|d| d.display().to_string()).unwrap_or_default();
        let text = cal::report_markdown(c, &source, &name);
        crate::util::files::write_atomically(report, text.as_bytes()).map_err(|e| Error::write(report, e))?;
    }
    if json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            calibration: &'a cal::Calibration,
            comparison: Option<&'a cal::Comparison>,
        }
        let value = Out {
            calibration: &calibration,
            comparison: comparison.as_ref(),
        };
        return emit(out, &(crate::error::to_json(&value, true)? + "\n"));
    }
    let mut text = format!("wrote {}:\n{yaml}", paths.profile.display());
    match &comparison {
        Some(c) => {
            text += &cal::report_markdown(
                c,
                &source,
                &paths.compare.unwrap_or(Path::new("")).display().to_string(),
            )
        }
        None => {
            text += "\ncues in the real data (AUC of each window quantity for crossing; 0.5 none, < 0.5 reversed):\n";
            for (q, a) in &calibration.real.cues {
                text += &format!("  {q:<14} {a:.2}\n");
            }
        }
    }
    emit(out, &text)
}

/// `pedsynth verify DIR [--tables-only]`: prints what was checked; a dataset with problems is an error
/// (exit 2) that lists them all.
pub fn verify(dir: &Path, tables_only: bool, out: &mut dyn Write) -> Result<(), Error> {
    use crate::dataset::verify::{Depth, verify};
    let depth = if tables_only { Depth::Tables } else { Depth::Full };
    let r = verify(dir, depth)?;
    if !r.problems.is_empty() {
        let list: Vec<String> = r.problems.iter().map(|p| format!("    {p}")).collect();
        return Err(Error::new(
            code::DATASET_INVALID,
            format!("{}: {} problem(s):\n{}", dir.display(), r.problems.len(), list.join("\n")),
        )
        .help("a changed or missing file: regenerate its clip (delete its tables/*/<clip_id>.parquet and re-run `pedsynth generate`)"));
    }
    let sensors = if tables_only {
        "sensor files not read (--tables-only)".to_owned()
    } else {
        format!(
            "{} sensor files ({} bytes) match the index's sizes and SHA-256",
            r.sensor_files, r.sensor_bytes
        )
    };
    emit(
        out,
        &format!(
            "{}: OK — {} clips complete; {} table files match the manifest's blake3, metadata, schemas, row counts and joins; {sensors}\n",
            dir.display(),
            r.clips,
            r.table_files
        ),
    )
}

/// `pedsynth preview DIR`: a contact sheet or GIF of one clip's camera stream with its labels.
pub fn preview(
    dir: &Path,
    options: &crate::dataset::read::preview::PreviewOptions,
    out: &mut dyn Write,
) -> Result<(), Error> {
    let text = crate::dataset::read::preview::preview(dir, options)?;
    emit(out, &text)
}

/// `pedsynth report DIR [--compare OTHER] --out FILE.html`: the dataset's distributions as one HTML page.
/// `pedsynth report DIR [--compare DATASET|REAL] --out FILE.html`: `--compare` names a generated dataset (it has a
/// manifest) or real annotations, whose layout is `real.0` or detected.
pub fn report(
    dir: &Path,
    compare: Option<&Path>,
    real: (Option<crate::dataset::calibrate::Format>, &[String]),
    to: &Path,
    out: &mut dyn Write,
) -> Result<(), Error> {
    use crate::dataset::report::{Compare, detect_real_format};
    let compare = compare.map(|other| {
        if other.join("manifest.json").is_file() {
            Compare::Dataset(other)
        } else if let Some(format) = real.0.or_else(|| detect_real_format(other)) {
            Compare::Real {
                dir: other,
                format,
                splits: real.1,
            }
        } else {
            Compare::Dataset(other)
        }
    });
    let text = crate::dataset::report::report(dir, compare, to)?;
    emit(out, &text)
}

/// `pedsynth export FORMAT DIR --out OUT [--box tight|annotator]`: a finished dataset in a format other tools
/// read (`--box` chooses the 2D box over the spec's `annotations.export_box`).
pub fn export(
    dir: &Path,
    format: crate::dataset::export::Format,
    to: &Path,
    how: &crate::dataset::export::Options,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<(), Error> {
    let mut warnings = Vec::new();
    let text = crate::dataset::export::export(dir, format, to, how, &mut |w| warnings.push(w))?;
    for w in warnings {
        writeln!(err, "{w}").map_err(Error::output)?;
    }
    emit(out, &text)
}
