//! What a dataset is made from, read from disk: the towns a spec names (built-in or OpenDRIVE), the plan it
//! compiles to, and a plan file (`pedsynth plan --emit`) checked as strictly as a spec. The planner itself is
//! pure; this is the IO around it that `generate`, `merge`, the exporters and the cluster commands share.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, code};
use crate::plan::{self, Plan, PreparedPlan, TownContext};
use crate::spec::types::TownRef;
use crate::spec::{self, LoadOptions, LoadedSpec};
use crate::world::RoadNetwork;

/// Loads every town a spec names (built-in towns are generated, OpenDRIVE maps read relative to the spec).
pub fn load_towns(loaded: &LoadedSpec) -> Result<BTreeMap<String, TownContext>, Error> {
    load_spec_towns(&loaded.spec, &loaded.base_dir)
}

/// Loads the towns of `spec`, resolving OpenDRIVE paths against `base_dir`.
pub fn load_spec_towns(spec: &crate::spec::Spec, base_dir: &Path) -> Result<BTreeMap<String, TownContext>, Error> {
    let mut towns = BTreeMap::new();
    for town in &spec.dataset.towns {
        let network = match town {
            TownRef::Builtin(t) => RoadNetwork::builtin(t.name()).ok_or_else(|| {
                Error::from(crate::world::WorldError::UnknownTown {
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

/// Compiles the plan of a loaded spec and its towns (`only`: just that clip).
fn compile(loaded: &LoadedSpec, towns: &BTreeMap<String, TownContext>, only: Option<&str>) -> Result<Plan, Error> {
    let spec_dir = loaded.base_dir.display().to_string();
    plan::plan(&loaded.spec, &loaded.hash()?, &spec_dir, towns, only).map_err(|p| plan_problems(&loaded.name, &p))
}

/// The error of a spec whose plan has problems.
pub(crate) fn plan_problems(name: &str, problems: &[plan::PlanProblem]) -> Error {
    let unknown_clip = problems.len() == 1 && problems[0].reason == plan::NO_SUCH_CLIP;
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
    let loaded = spec::load_file(spec_path, options)?;
    let towns = load_towns(&loaded)?;
    let plan = compile(&loaded, &towns, only)?;
    Ok((loaded, plan))
}

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
    let bytes = crate::util::files::read_capped(path, MAX_PLAN_BYTES).map_err(|e| Error::read(path, e))?;
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
    if head.format_version != plan::PLAN_FORMAT_VERSION {
        return Err(Error::new(
            code::PLAN_UNSUPPORTED_VERSION,
            format!(
                "{}: plan format {} is not supported (this pedsynth reads {})",
                path.display(),
                head.format_version,
                plan::PLAN_FORMAT_VERSION
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
    let yaml = spec::to_yaml(&plan.spec)?;
    let name = format!("{} (its spec)", path.display());
    let options = LoadOptions {
        overrides: Vec::new(),
        allow_large: true,
        profile: None,
    };
    let loaded = spec::load_bytes(yaml.as_bytes(), &name, &spec_dir, &options)?;
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
        let compiled = plan::plan(&loaded.spec, &plan.spec_hash, &plan.spec_dir, &towns, None).map_err(|p| {
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

/// The plan and towns of a spec file (.yaml, compiled) or a plan file (.json, read and checked), prepared for
/// generation: a spec's clip scripts are compiled again one at a time when needed, not held
/// ([`plan::PreparedPlan`]).
pub fn load_input(input: &Path, options: &LoadOptions) -> Result<(PreparedPlan, BTreeMap<String, TownContext>), Error> {
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
        let loaded = spec::load_file(input, options)?;
        let towns = load_towns(&loaded)?;
        let spec_dir = loaded.base_dir.display().to_string();
        let lazy = plan::LazyPlan::compile(&loaded.spec, &loaded.hash()?, &spec_dir, &towns);
        let plan = PreparedPlan::new(lazy, &towns).map_err(|p| plan_problems(&loaded.name, &p))?;
        Ok((plan, towns))
    }
}

/// Loads a spec file, its towns and its full plan: the programmatic path to a plan (tests, benchmarks, tools).
pub fn plan_spec_file(
    path: &Path,
    options: &LoadOptions,
) -> Result<(LoadedSpec, BTreeMap<String, TownContext>, Plan), Error> {
    let loaded = spec::load_file(path, options)?;
    let towns = load_towns(&loaded)?;
    let plan = compile(&loaded, &towns, None)?;
    Ok((loaded, towns, plan))
}
