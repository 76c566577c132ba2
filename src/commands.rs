//! The command implementations behind the CLI: each takes parsed arguments and an output stream, writes its
//! result there and returns `Ok(())` or an [`Error`]; [`finish`] renders an error and turns it into the process
//! exit code (0 ok, 1 environment failure, 2 invalid input).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::dsl::types::TownRef;
use crate::dsl::{self, LoadOptions, LoadedSpec, validate};
use crate::error::{Error, code};
use crate::planner::{self, Plan, PreparedPlan, TownContext};
use crate::world::RoadNetwork;

/// Process exit codes.
pub mod exit {
    /// Success.
    pub const OK: i32 = 0;
    /// A failure that is not the input's fault (I/O, disk, permissions, internal).
    pub const FAILURE: i32 = 1;
    /// Invalid input: a spec, plan, map, argument or dataset.
    pub const INVALID: i32 = 2;
}

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

/// Width diagnostics are rendered at.
pub const DIAGNOSTIC_WIDTH: usize = 100;

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
        match dsl::load_file(path, options) {
            Ok(loaded) => {
                let text = if resolved {
                    dsl::to_yaml(&loaded.spec)?
                } else {
                    format!("{}\n", summary_line(&loaded)?)
                };
                emit(out, &text)?;
            }
            Err(e) => errors.push(Error::Spec(e)),
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
    emit(out, &dsl::schema::spec_schema_text()?)
}

/// Renders any diagnostic without colour at the fixed width.
pub fn render_diagnostic(diagnostic: &dyn miette::Diagnostic) -> String {
    let handler = miette::GraphicalReportHandler::new_themed(miette::GraphicalTheme::unicode_nocolor())
        .with_width(DIAGNOSTIC_WIDTH)
        .with_links(false);
    let mut out = String::new();
    if handler.render_report(&mut out, diagnostic).is_err() {
        // The handler failed half-way (it writes to a String, so only a formatting bug can do this): fall back
        // to the plain message rather than lose the error.
        out = format!("{diagnostic}\n");
    }
    out
}

/// Loads every town a spec names (built-in towns are generated, OpenDRIVE maps read relative to the spec).
pub fn load_towns(loaded: &LoadedSpec) -> Result<BTreeMap<String, TownContext>, Error> {
    load_spec_towns(&loaded.spec, &loaded.base_dir)
}

/// Loads the towns of `spec`, resolving OpenDRIVE paths against `base_dir`.
pub fn load_spec_towns(spec: &crate::dsl::Spec, base_dir: &Path) -> Result<BTreeMap<String, TownContext>, Error> {
    let mut towns = BTreeMap::new();
    for town in &spec.dataset.towns {
        let network = match town {
            TownRef::Builtin(t) => RoadNetwork::builtin(t.name()).ok_or_else(|| {
                Error::World(crate::world::WorldError::UnknownTown {
                    name: t.name().to_owned(),
                })
            })?,
            TownRef::OpenDrive(t) => {
                let mut network = RoadNetwork::from_xodr_file(&base_dir.join(&t.opendrive))?;
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

/// Compiles the plan of a loaded spec and its towns (`only`: just that clip).
fn compile(loaded: &LoadedSpec, towns: &BTreeMap<String, TownContext>, only: Option<&str>) -> Result<Plan, Error> {
    let spec_dir = loaded.base_dir.display().to_string();
    planner::plan(&loaded.spec, &loaded.hash()?, &spec_dir, towns, only).map_err(|p| plan_problems(&loaded.name, &p))
}

/// The error of a spec whose plan has problems.
fn plan_problems(name: &str, problems: &[planner::PlanProblem]) -> Error {
    let unknown_clip = problems.len() == 1 && problems[0].reason == planner::NO_SUCH_CLIP;
    if unknown_clip {
        return Error::new(code::PLAN_UNKNOWN_CLIP, problems[0].to_string())
            .help("`pedsynth plan SPEC --json` lists the clip ids");
    }
    let list: Vec<String> = problems.iter().map(|p| format!("    {p}")).collect();
    Error::new(
        code::PLAN_INFEASIBLE,
        format!(
            "{name}: the spec cannot be planned ({} problem{}):\n{}",
            problems.len(),
            if problems.len() == 1 { "" } else { "s" },
            list.join("\n")
        ),
    )
    .help("widen the spawn distances, lower the pedestrian or vehicle counts, or use a larger town")
}

/// Loads a spec and its towns and compiles the plan.
pub fn compile_plan(spec_path: &Path, options: &LoadOptions, only: Option<&str>) -> Result<(LoadedSpec, Plan), Error> {
    let loaded = dsl::load_file(spec_path, options)?;
    let towns = load_towns(&loaded)?;
    let plan = compile(&loaded, &towns, only)?;
    Ok((loaded, plan))
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
        crate::fsutil::write_atomically(path, json.as_bytes()).map_err(|e| Error::write(path, e))?;
    }
    let stats = planner::stats::compute(&plan, &loaded.spec);
    let text = if args.json {
        crate::error::to_json(&stats, true)? + "\n"
    } else {
        stats.to_string()
    };
    emit(out, &text)
}

/// `pedsynth town list`.
pub fn town_list(out: &mut dyn Write) -> Result<(), Error> {
    emit(out, &crate::world::town_list_text())
}

/// `pedsynth town show NAME_OR_XODR [--png OUT] [--json]`.
pub fn town_show(town: &str, png: Option<&Path>, json: bool, out: &mut dyn Write) -> Result<(), Error> {
    let text = crate::world::town_show(town, png, json)?;
    emit(out, &text)
}

/// `pedsynth town export NAME --xodr OUT`.
pub fn town_export(town: &str, xodr: &Path, out: &mut dyn Write) -> Result<(), Error> {
    let text = crate::world::town_export(town, xodr)?;
    emit(out, &text)
}

pub use crate::exec::generate::GenerateOptions as GenerateArgs;

/// Largest plan file read (PedSynth++'s 600 clips take 13.5 MB; a 10,000-clip plan about 230 MB).
pub const MAX_PLAN_BYTES: u64 = 1 << 30;

/// Reads a plan file (`pedsynth plan --emit`) and the towns it names (relative paths resolve against the
/// directory the plan was made in, as recorded in the plan), and checks it as strictly as a spec: its format and
/// pedsynth versions, its spec (validated like a spec file, and hashing to the plan's `spec_hash`), every town's
/// fingerprint (a plan made for another version of a map is refused), and every clip against the clip its spec
/// compiles to (lane indices, counts, ranges, seeds: the first differing value is named by its JSON path). A plan
/// may hold a subset of the clips (`plan --emit --only`), never clips its spec does not make. Every problem is
/// reported at once.
pub fn read_plan(path: &Path) -> Result<(Plan, BTreeMap<String, TownContext>), Error> {
    let bytes = crate::fsutil::read_capped(path, MAX_PLAN_BYTES).map_err(|e| Error::read(path, e))?;
    read_plan_bytes(&bytes, path)
}

/// [`read_plan`] of a plan file's bytes; `path` names it in messages, and the plan's `spec_dir` resolves
/// against its directory.
pub fn read_plan_bytes(bytes: &[u8], path: &Path) -> Result<(Plan, BTreeMap<String, TownContext>), Error> {
    let invalid = |what: String| {
        Error::new(code::PLAN_INVALID, format!("{}: {what}", path.display()))
            .help("make a plan with `pedsynth plan SPEC --emit PLAN.json`, and do not edit it")
    };
    let text = std::str::from_utf8(bytes).map_err(|e| invalid(format!("not a pedsynth plan (not UTF-8: {e})")))?;
    #[derive(serde::Deserialize)]
    struct Head {
        format_version: u32,
    }
    let head: Head = serde_json::from_str(text).map_err(|e| invalid(format!("not a pedsynth plan: {e}")))?;
    if head.format_version != planner::PLAN_FORMAT_VERSION {
        return Err(Error::new(
            code::PLAN_UNSUPPORTED_VERSION,
            format!(
                "{}: plan format {} is not supported (this pedsynth reads {})",
                path.display(),
                head.format_version,
                planner::PLAN_FORMAT_VERSION
            ),
        )
        .help("re-plan the spec with this pedsynth"));
    }
    let plan: Plan = serde_json::from_str(text).map_err(|e| invalid(format!("not a pedsynth plan: {e}")))?;
    if plan.pedsynth_version != env!("CARGO_PKG_VERSION") {
        return Err(Error::new(
            code::PLAN_UNSUPPORTED_VERSION,
            format!(
                "{}: made by pedsynth {}, and this is pedsynth {} (a dataset is reproducible for one version)",
                path.display(),
                plan.pedsynth_version,
                env!("CARGO_PKG_VERSION")
            ),
        )
        .help("re-plan the spec with this pedsynth, or generate with the pedsynth that made the plan"));
    }
    let spec_dir = path.parent().unwrap_or(Path::new("")).join(&plan.spec_dir);
    // The spec, validated as a spec file is (the sanity limits were the planner's to apply).
    let yaml = dsl::to_yaml(&plan.spec)?;
    let name = format!("{} (its spec)", path.display());
    let options = LoadOptions {
        overrides: Vec::new(),
        allow_large: true,
    };
    let loaded = dsl::load_bytes(yaml.as_bytes(), &name, &spec_dir, &options)?;
    let mut problems = Vec::new();
    if loaded.hash()? != plan.spec_hash {
        problems.push("its spec does not hash to its spec_hash (the spec or the hash was edited)".to_owned());
    }
    let towns = load_spec_towns(&loaded.spec, &spec_dir)?;
    if !plan.towns.keys().eq(towns.keys()) {
        let names = |keys: Vec<&String>| keys.iter().map(|k| k.as_str()).collect::<Vec<_>>().join(", ");
        problems.push(format!(
            "it records towns [{}] but its spec loads [{}]",
            names(plan.towns.keys().collect()),
            names(towns.keys().collect())
        ));
    }
    for (town, fingerprint) in &plan.towns {
        if let Some(t) = towns.get(town)
            && &t.fingerprint != fingerprint
        {
            problems.push(format!(
                "town `{town}` differs from the map the plan was made for (fingerprint {}… here, {}… in the plan)",
                &t.fingerprint[..12],
                fingerprint.get(..12).unwrap_or(fingerprint)
            ));
        }
    }
    if problems.is_empty() {
        let compiled = planner::plan(&loaded.spec, &plan.spec_hash, &plan.spec_dir, &towns, None).map_err(|p| {
            invalid(format!(
                "its spec cannot be planned: {}",
                p.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("; ")
            ))
        })?;
        problems.extend(plan_differences(&plan, &compiled)?);
    }
    if !problems.is_empty() {
        let shown: Vec<String> = problems.iter().take(20).map(|p| format!("    {p}")).collect();
        let more = problems.len().saturating_sub(shown.len());
        return Err(invalid(format!(
            "{} problem{}:\n{}{}",
            problems.len(),
            if problems.len() == 1 { "" } else { "s" },
            shown.join("\n"),
            if more > 0 {
                format!("\n    ... and {more} more")
            } else {
                String::new()
            }
        )));
    }
    Ok((plan, towns))
}

/// Where a plan read from a file differs from the plan its spec compiles to: top-level values, then each clip
/// against the compiled clip of the same id (unknown and repeated ids too), as JSON paths.
fn plan_differences(plan: &Plan, compiled: &Plan) -> Result<Vec<String>, Error> {
    let json = |v: &Plan| -> Result<serde_json::Value, Error> {
        serde_json::to_value(v).map_err(|e| Error::new(code::INTERNAL_SERIALIZE, format!("plan as JSON: {e}")))
    };
    let (mut a, mut b) = (json(plan)?, json(compiled)?);
    let (clips_a, clips_b) = (a["clips"].take(), b["clips"].take());
    let mut out = Vec::new();
    json_differences("", &a, &b, &mut out);
    let by_id: BTreeMap<&str, &serde_json::Value> = clips_b
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|c| Some((c["clip_id"].as_str()?, c)))
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    for (i, clip) in clips_a.as_array().into_iter().flatten().enumerate() {
        let id = clip["clip_id"].as_str().unwrap_or("");
        if !seen.insert(id) {
            out.push(format!("clips[{i}]: clip `{id}` appears twice"));
        } else if let Some(expected) = by_id.get(id) {
            json_differences(&format!("clips[{i}]"), clip, expected, &mut out);
        } else {
            out.push(format!("clips[{i}]: its spec makes no clip `{id}`"));
        }
    }
    Ok(out)
}

/// Appends the first difference under every differing branch (`path: VALUE, but the spec compiles to VALUE`).
fn json_differences(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<String>) {
    use serde_json::Value;
    let short = |v: &Value| {
        let s = v.to_string();
        if s.chars().count() > 60 {
            format!("{}…", s.chars().take(60).collect::<String>())
        } else {
            s
        }
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            for k in keys {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match (x.get(k), y.get(k)) {
                    (Some(u), Some(v)) => json_differences(&p, u, v, out),
                    (Some(_), None) => out.push(format!("{p}: not a field of a plan")),
                    (None, Some(_)) => out.push(format!("{p}: missing")),
                    (None, None) => {}
                }
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                json_differences(&format!("{path}[{i}]"), u, v, out);
            }
        }
        (Value::Array(x), Value::Array(y)) => out.push(format!(
            "{path}: {} entries, but the spec compiles to {}",
            x.len(),
            y.len()
        )),
        _ if a != b => out.push(format!("{path}: {}, but the spec compiles to {}", short(a), short(b))),
        _ => {}
    }
}

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

/// A shard from the environment, `((index, count), source)`.
pub type EnvShard = ((usize, usize), &'static str);

/// Parses `I/N` (shard I of N, 0-based).
pub fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let (i, n) = text
        .split_once('/')
        .ok_or_else(|| format!("expected I/N (shard I of N, 0-based), found `{text}`"))?;
    let parse = |x: &str| x.trim().parse::<usize>().map_err(|e| format!("`{x}`: {e}"));
    let (i, n) = (parse(i)?, parse(n)?);
    if n == 0 || i >= n {
        return Err(format!("shard {i} of {n}: I must be in 0..N and N at least 1"));
    }
    Ok((i, n))
}

/// The shard a cluster engine asks for through the environment: a SLURM array task (`SLURM_ARRAY_TASK_ID`
/// minus `SLURM_ARRAY_TASK_MIN` of `SLURM_ARRAY_TASK_COUNT`) or a Kubernetes Indexed Job pod
/// (`JOB_COMPLETION_INDEX` of `PEDSYNTH_SHARD_COUNT`, which `pedsynth k8s`-style manifests set to the
/// completions). Returns the shard and where it came from.
pub fn shard_from_env(var: &dyn Fn(&str) -> Option<String>) -> Result<Option<EnvShard>, Error> {
    let num = |name: &str| -> Result<Option<usize>, Error> {
        var(name)
            .map(|v| {
                v.trim().parse::<usize>().map_err(|_| {
                    Error::new(
                        code::SHARD_INVALID,
                        format!("{name}={v:?} is not a non-negative integer"),
                    )
                })
            })
            .transpose()
    };
    let check = |i: usize, n: usize, source: &'static str| {
        if n == 0 || i >= n {
            Err(Error::new(
                code::SHARD_INVALID,
                format!("{source}: shard {i} of {n} is out of range"),
            ))
        } else {
            Ok(Some(((i, n), source)))
        }
    };
    if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
        let count = num("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
            Error::new(
                code::SHARD_INVALID,
                "SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not",
            )
        })?;
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let i = id.checked_sub(min).ok_or_else(|| {
            Error::new(
                code::SHARD_INVALID,
                format!("SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}"),
            )
        })?;
        return check(i, count, "SLURM array task");
    }
    if let Some(index) = num("JOB_COMPLETION_INDEX")? {
        let count = num("PEDSYNTH_SHARD_COUNT")?.ok_or_else(|| {
            Error::new(
                code::SHARD_INVALID,
                "JOB_COMPLETION_INDEX is set but PEDSYNTH_SHARD_COUNT (the Job's completions) is not",
            )
        })?;
        return check(index, count, "Kubernetes Indexed Job");
    }
    Ok(None)
}

/// The plan and towns of a spec file (.yaml, compiled) or a plan file (.json, read and checked), prepared for
/// generation: a spec's clip scripts are compiled again one at a time when needed, not held
/// ([`planner::PreparedPlan`]).
fn load_input(input: &Path, options: &LoadOptions) -> Result<(PreparedPlan, BTreeMap<String, TownContext>), Error> {
    if input.extension().is_some_and(|e| e == "json") {
        if !options.overrides.is_empty() {
            return Err(
                Error::new(code::PLAN_OVERRIDE, "--set applies to specs, not to a plan file")
                    .help("re-plan with `pedsynth plan SPEC --set ... --emit PLAN`"),
            );
        }
        let (plan, towns) = read_plan(input)?;
        let name = input.display().to_string();
        Ok((
            PreparedPlan::from_plan(plan).map_err(|p| plan_problems(&name, &p))?,
            towns,
        ))
    } else {
        let loaded = dsl::load_file(input, options)?;
        let towns = load_towns(&loaded)?;
        let spec_dir = loaded.base_dir.display().to_string();
        let lazy = planner::LazyPlan::compile(&loaded.spec, &loaded.hash()?, &spec_dir, &towns);
        let plan = PreparedPlan::new(lazy, &towns).map_err(|p| plan_problems(&loaded.name, &p))?;
        Ok((plan, towns))
    }
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
    let r = crate::exec::generate::merge::merge(&plan, dir, shards)?;
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
    crate::fsutil::write_atomically(path, text.as_bytes()).map_err(|e| Error::write(path, e))?;
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
    slurm: &crate::exec::generate::cluster::SlurmOptions,
    script: Option<&Path>,
    out: &mut dyn Write,
) -> Result<(), Error> {
    let (plan, towns) = load_input(input, options)?;
    let text = crate::exec::generate::cluster::slurm_script(&plan, &towns, slurm)?;
    emit_to(script, &text, true, out)
}

/// `pedsynth k8s SPEC --out DIR --completions N --pvc NAME ...`: writes the Indexed Job manifest.
pub fn k8s(
    input: &Path,
    options: &LoadOptions,
    k8s: &crate::exec::generate::cluster::K8sOptions,
    manifest: Option<&Path>,
    out: &mut dyn Write,
) -> Result<(), Error> {
    let (plan, towns) = load_input(input, options)?;
    let spec_yaml = dsl::to_yaml(&plan.header().spec)?;
    let text = crate::exec::generate::cluster::k8s_manifest(&plan, &towns, &spec_yaml, k8s)?;
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
    let report = crate::exec::generate::generate(&plan, &towns, args)?;
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
    protocol: Option<&crate::exec::read::protocol::PabOptions>,
    out: &mut dyn Write,
) -> Result<(), Error> {
    crate::exec::export::dataset::refuse_unverified(dir)?;
    if let Some(options) = protocol {
        let stats = crate::exec::read::protocol::compute(dir, options)?;
        let text = if json {
            crate::error::to_json(&stats, true)? + "\n"
        } else {
            stats.to_string()
        };
        return emit(out, &text);
    }
    let stats = crate::exec::read::stats::compute(dir)?;
    let text = if json {
        crate::error::to_json(&stats, true)? + "\n"
    } else {
        stats.to_string()
    };
    emit(out, &text)
}

/// `pedsynth verify DIR [--tables-only]`: prints what was checked; a dataset with problems is an error
/// (exit 2) that lists them all.
pub fn verify(dir: &Path, tables_only: bool, out: &mut dyn Write) -> Result<(), Error> {
    use crate::exec::read::verify::{Depth, verify};
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
    options: &crate::exec::read::preview::PreviewOptions,
    out: &mut dyn Write,
) -> Result<(), Error> {
    let text = crate::exec::read::preview::preview(dir, options)?;
    emit(out, &text)
}

/// `pedsynth export FORMAT DIR --out OUT`: a finished dataset in a format other tools read.
pub fn export(
    dir: &Path,
    format: crate::exec::export::Format,
    to: &Path,
    link: crate::exec::export::LinkMode,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<(), Error> {
    let mut warnings = Vec::new();
    let text = crate::exec::export::export(dir, format, to, link, &mut |w| warnings.push(w))?;
    for w in warnings {
        writeln!(err, "{w}").map_err(Error::output)?;
    }
    emit(out, &text)
}

/// Loads a spec file, its towns and its full plan: the programmatic path to a plan (tests, benchmarks, tools).
pub fn plan_spec_file(
    path: &Path,
    options: &LoadOptions,
) -> Result<(LoadedSpec, BTreeMap<String, TownContext>, Plan), Error> {
    let loaded = dsl::load_file(path, options)?;
    let towns = load_towns(&loaded)?;
    let plan = compile(&loaded, &towns, None)?;
    Ok((loaded, towns, plan))
}
