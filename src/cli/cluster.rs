//! Job files for cluster engines (pure text, no IO): `pedsynth slurm` writes a submit script for a SLURM job
//! array plus a merge job that runs after every task succeeds; `pedsynth k8s` writes a Kubernetes Indexed Job
//! (with the resolved spec in a ConfigMap). Each task or pod runs `pedsynth generate` with no `--shard`: the
//! shard comes from the engine's environment (`SLURM_ARRAY_TASK_ID`, `JOB_COMPLETION_INDEX`), and shards of
//! one run write into one `--out` on shared storage. The engines schedule; pedsynth only splits the plan.

use std::collections::BTreeMap;

use crate::error::{Error, code};
use crate::plan::{PreparedPlan, TownContext};

/// Options of `pedsynth slurm`.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// The spec or plan file, as the jobs will name it (relative paths are relative to where the script runs).
    pub input: String,
    /// `--set` overrides, passed on to every task.
    pub overrides: Vec<String>,
    /// `--profile`, passed on to every task.
    pub profile: Option<String>,
    /// The dataset directory (on storage every node sees).
    pub out: String,
    /// Array tasks.
    pub array: usize,
    /// CPUs per task (`--jobs` of each generate).
    pub cpus: u32,
    /// Wall-time limit per task (`D-HH:MM:SS` or anything sbatch takes); `None`: from the plan's estimate.
    pub time: Option<String>,
    /// Memory per task (sbatch's `--mem`, e.g. `4G`).
    pub mem: Option<String>,
    /// Partition.
    pub partition: Option<String>,
    /// The pedsynth executable the jobs run (the environment's `PEDSYNTH` overrides it at run time).
    pub pedsynth: String,
}

/// Options of `pedsynth k8s`.
#[derive(Clone, Debug, Default)]
pub struct K8sOptions {
    /// Name of the Job (and prefix of the ConfigMap); `None`: from the dataset's name.
    pub name: Option<String>,
    /// Completions (shards).
    pub completions: usize,
    /// Pods at once; `None`: all.
    pub parallelism: Option<usize>,
    /// Container image holding `pedsynth` on its PATH.
    pub image: String,
    /// CPUs per pod (request and limit; `--jobs` of each generate).
    pub cpus: u32,
    /// Memory per pod (request and limit, Kubernetes quantity such as `4Gi`).
    pub memory: String,
    /// PersistentVolumeClaim (ReadWriteMany) mounted at `/data` in every pod.
    pub pvc: String,
    /// The dataset directory inside the volume.
    pub out: String,
    /// The spec file inside the volume; `None`: the resolved spec travels in a ConfigMap.
    pub spec_on_volume: Option<String>,
}

/// Quotes `text` for a POSIX shell (single quotes; a single quote becomes `'\''`).
pub fn sh_quote(text: &str) -> String {
    let plain = !text.is_empty()
        && text
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"-_./=:,+@%".contains(&b));
    if plain {
        text.to_owned()
    } else {
        format!("'{}'", text.replace('\'', r"'\''"))
    }
}

/// A wall time limit for a task that should take `cpu_s` CPU seconds on `cpus` CPUs: three times the estimate
/// plus 10 minutes (the estimate is for this project's reference machine), as `D-HH:MM:SS`.
pub fn time_limit(cpu_s: f64, cpus: u32) -> String {
    let s = (cpu_s / f64::from(cpus.max(1)) * 3.0 + 600.0)
        .ceil()
        .clamp(0.0, 365.0 * 86_400.0) as u64;
    format!("{}-{:02}:{:02}:{:02}", s / 86_400, s / 3600 % 24, s / 60 % 60, s % 60)
}

fn check_count(what: &str, n: usize, plan: &PreparedPlan) -> Result<(), Error> {
    if n == 0 || n > plan.len() {
        return Err(Error::new(
            code::SHARD_INVALID,
            format!(
                "{what} {n}: the plan has {} clips, so 1 to {} shards",
                plan.len(),
                plan.len()
            ),
        )
        .help("each shard generates whole clips; more shards than clips would leave some idle"));
    }
    Ok(())
}

/// The submit script of `pedsynth slurm`: `bash` it on a login node; it submits the array and the merge job
/// (`--dependency=afterok`) and prints their ids.
pub fn slurm_script(
    plan: &PreparedPlan,
    towns: &BTreeMap<String, TownContext>,
    o: &SlurmOptions,
) -> Result<String, Error> {
    check_count("--array", o.array, plan)?;
    let longest_cpu_s = crate::dataset::generate::shard_cpu_s(plan, towns, o.array)
        .into_iter()
        .fold(0.0, f64::max);
    let time = o.time.clone().unwrap_or_else(|| time_limit(longest_cpu_s, o.cpus));
    let job = format!("pedsynth-{}", job_name(&plan.header().dataset, 40));
    let profile: String = o
        .profile
        .iter()
        .map(|p| format!(" --profile {}", sh_quote(p)))
        .collect();
    let sets: String = profile
        + &o.overrides
            .iter()
            .map(|s| format!(" --set {}", sh_quote(s)))
            .collect::<String>();
    let mut sbatch = format!("--cpus-per-task={} --time={}", o.cpus, sh_quote(&time));
    if let Some(mem) = &o.mem {
        sbatch += &format!(" --mem={}", sh_quote(mem));
    }
    if let Some(partition) = &o.partition {
        sbatch += &format!(" --partition={}", sh_quote(partition));
    }
    let (input, out) = (sh_quote(&o.input), sh_quote(&o.out));
    let logs = sh_quote(&format!("{}.logs", o.out));
    let pedsynth = sh_quote(&o.pedsynth);
    let last = o.array - 1;
    let clips = plan.len();
    let version = env!("CARGO_PKG_VERSION");
    Ok(format!(
        r#"#!/usr/bin/env bash
# Submits pedsynth dataset `{dataset}` ({clips} clips) to SLURM: an array of {n} tasks, each generating a
# cost-balanced shard of the plan into one --out on shared storage (the shard comes from SLURM_ARRAY_TASK_ID),
# then a merge job, after every task succeeded, that writes the manifest and card and verifies the dataset.
# Written by pedsynth {version} (`pedsynth slurm`). Run it with bash from the directory the paths are relative
# to; set PEDSYNTH to use another pedsynth executable. Longest shard estimate: {est:.0} CPU-s.
set -euo pipefail
mkdir -p {logs}
array_job=$(sbatch --parsable --job-name={job} --array=0-{last} {sbatch} --output={logs}/shard-%a.log <<'EOF'
#!/usr/bin/env bash
set -euo pipefail
exec "${{PEDSYNTH:-{pedsynth}}}" generate {input} --out {out} --jobs "${{SLURM_CPUS_PER_TASK:-1}}" --progress json{sets}
EOF
)
array_job=${{array_job%%;*}}
merge_job=$(sbatch --parsable --job-name={job}-merge --dependency=afterok:"$array_job" --kill-on-invalid-dep=yes \
  --cpus-per-task=1 --time={merge_time} --output={logs}/merge.log <<'EOF'
#!/usr/bin/env bash
set -euo pipefail
"${{PEDSYNTH:-{pedsynth}}}" merge {input} --out {out}{sets}
exec "${{PEDSYNTH:-{pedsynth}}}" verify {out}
EOF
)
merge_job=${{merge_job%%;*}}
echo "submitted array job $array_job ({n} tasks) and merge job $merge_job; logs in "{logs}
"#,
        dataset = plan.header().dataset,
        n = o.array,
        est = longest_cpu_s,
        merge_time = sh_quote(&time_limit(clips as f64 * 2.0, 1)),
    ))
}

/// A name usable as a Kubernetes object name and SLURM job name: lower-case letters, digits and `-`,
/// starting and ending with a letter or digit, at most `max` characters.
pub fn job_name(text: &str, max: usize) -> String {
    let mut name = String::new();
    for c in text.chars() {
        let c = c.to_ascii_lowercase();
        if c.is_ascii_alphanumeric() {
            name.push(c);
        } else if !name.ends_with('-') {
            name.push('-');
        }
    }
    let name: String = name.trim_matches('-').chars().take(max).collect();
    let name = name.trim_end_matches('-').to_owned();
    if name.is_empty() { "dataset".to_owned() } else { name }
}

/// A YAML double-quoted string.
fn yaml_str(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_else(|_| "\"\"".to_owned())
}

/// The manifest of `pedsynth k8s`: a ConfigMap with the resolved spec (unless it is on the volume) and an
/// Indexed Job whose pods each generate the shard of their `JOB_COMPLETION_INDEX` into `/data/<out>`; the last
/// pod to finish writes the manifest and the card. `spec_yaml` is the resolved spec.
pub fn k8s_manifest(
    plan: &PreparedPlan,
    towns: &BTreeMap<String, TownContext>,
    spec_yaml: &str,
    o: &K8sOptions,
) -> Result<String, Error> {
    check_count("--completions", o.completions, plan)?;
    for (flag, path) in [("--out", Some(&o.out)), ("--spec-on-volume", o.spec_on_volume.as_ref())] {
        if let Some(path) = path
            && (path.is_empty() || path.starts_with('/') || path.split('/').any(|c| c == ".."))
        {
            return Err(Error::new(
                code::SHARD_INVALID,
                format!("{flag} {path:?}: give a relative path inside the volume (mounted at /data)"),
            ));
        }
    }
    if o.spec_on_volume.is_none()
        && let Some(town) = plan
            .header()
            .spec
            .dataset
            .towns
            .iter()
            .find(|t| matches!(t, crate::spec::types::TownRef::OpenDrive(_)))
    {
        return Err(Error::new(
            code::SHARD_INVALID,
            format!(
                "town `{}` is an OpenDRIVE file, which a ConfigMap holding the spec cannot carry",
                town.name()
            ),
        )
        .help("copy the spec and its maps onto the volume and pass --spec-on-volume PATH"));
    }
    let name = o.name.clone().map_or_else(
        || format!("pedsynth-{}", job_name(&plan.header().dataset, 40)),
        |n| job_name(&n, 50),
    );
    let parallelism = o.parallelism.unwrap_or(o.completions).clamp(1, o.completions);
    let spec_path = match &o.spec_on_volume {
        Some(p) => format!("/data/{p}"),
        None => "/spec/spec.yaml".to_owned(),
    };
    let longest_cpu_s = crate::dataset::generate::shard_cpu_s(plan, towns, o.completions)
        .into_iter()
        .fold(0.0, f64::max);
    let deadline_s = (longest_cpu_s / f64::from(o.cpus.max(1)) * 3.0 + 600.0).ceil() as u64 * 2;
    let mut text = format!(
        "# pedsynth dataset `{dataset}` ({clips} clips) as a Kubernetes Indexed Job of {n} completions: each pod\n\
         # generates the cost-balanced shard of its JOB_COMPLETION_INDEX into /data/{out} on the claim `{pvc}`\n\
         # (ReadWriteMany), and the last pod to finish writes the manifest and the card. Written by pedsynth\n\
         # {version} (`pedsynth k8s`); apply with `kubectl apply -f`. Longest shard estimate: {est:.0} CPU-s.\n",
        dataset = plan.header().dataset,
        clips = plan.len(),
        n = o.completions,
        out = o.out,
        pvc = o.pvc,
        version = env!("CARGO_PKG_VERSION"),
        est = longest_cpu_s,
    );
    if o.spec_on_volume.is_none() {
        text += &format!(
            "apiVersion: v1\nkind: ConfigMap\nmetadata:\n  name: {name}-spec\n  labels:\n    app.kubernetes.io/name: pedsynth\n\
             data:\n  spec.yaml: |\n"
        );
        for line in spec_yaml.lines() {
            if line.is_empty() {
                text.push('\n');
            } else {
                text += &format!("    {line}\n");
            }
        }
        text += "---\n";
    }
    let command = [
        "pedsynth",
        "generate",
        &spec_path,
        "--out",
        &format!("/data/{}", o.out),
        "--jobs",
        &o.cpus.to_string(),
        "--progress",
        "json",
    ]
    .iter()
    .map(|a| yaml_str(a))
    .collect::<Vec<_>>()
    .join(", ");
    text += &format!(
        "apiVersion: batch/v1\nkind: Job\nmetadata:\n  name: {name}\n  labels:\n    app.kubernetes.io/name: pedsynth\n\
         spec:\n  completionMode: Indexed\n  completions: {n}\n  parallelism: {parallelism}\n  backoffLimitPerIndex: 2\n\
         \x20 activeDeadlineSeconds: {deadline_s}\n  template:\n    metadata:\n      labels:\n        app.kubernetes.io/name: pedsynth\n\
         \x20   spec:\n      restartPolicy: Never\n      containers:\n        - name: generate\n          image: {image}\n\
         \x20         command: [{command}]\n          env:\n            - name: PEDSYNTH_SHARD_COUNT\n              value: \"{n}\"\n\
         \x20         resources:\n            requests:\n              cpu: \"{cpus}\"\n              memory: {memory}\n\
         \x20           limits:\n              cpu: \"{cpus}\"\n              memory: {memory}\n          volumeMounts:\n\
         \x20           - name: data\n              mountPath: /data\n",
        n = o.completions,
        image = yaml_str(&o.image),
        cpus = o.cpus,
        memory = yaml_str(&o.memory),
    );
    if o.spec_on_volume.is_none() {
        text += "            - name: spec\n              mountPath: /spec\n              readOnly: true\n";
    }
    text += &format!(
        "      volumes:\n        - name: data\n          persistentVolumeClaim:\n            claimName: {}\n",
        yaml_str(&o.pvc)
    );
    if o.spec_on_volume.is_none() {
        text += &format!("        - name: spec\n          configMap:\n            name: {name}-spec\n");
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_quoting_survives_quotes_and_spaces() {
        assert_eq!(sh_quote("specs/quickstart.yaml"), "specs/quickstart.yaml");
        assert_eq!(sh_quote("my data"), "'my data'");
        assert_eq!(sh_quote("it's"), r"'it'\''s'");
        assert_eq!(sh_quote(""), "''");
        assert_eq!(sh_quote("$HOME"), "'$HOME'");
    }

    #[test]
    fn time_limits_are_three_times_the_estimate_plus_ten_minutes() {
        assert_eq!(time_limit(0.0, 2), "0-00:10:00");
        assert_eq!(time_limit(3600.0, 1), "0-03:10:00");
        assert_eq!(time_limit(86_400.0, 2), "1-12:10:00");
    }

    #[test]
    fn job_names_are_dns_labels() {
        assert_eq!(job_name("PedSynth++ v2", 50), "pedsynth-v2");
        assert_eq!(job_name("__", 50), "dataset");
        assert_eq!(job_name("a-b-c-d", 3), "a-b");
    }
}
