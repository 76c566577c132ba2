//! Shards of a run: which clips shard I of N generates (balanced by estimated cost, deterministic), and which
//! shard a cluster engine asks for through the environment (SLURM array tasks, Kubernetes Indexed Jobs).

use std::collections::{BTreeMap, BTreeSet};

use crate::error::{Error, code};
use crate::plan::{PreparedPlan, TownContext};

/// The clips of shard `index` of `count`: clips sorted by estimated CPU cost (largest first, then by id) go one
/// by one to the shard with the least cost so far (the lowest index on a tie). Deterministic: every shard of
/// a run computes the same assignment from the plan alone.
pub fn shard_clips(
    plan: &PreparedPlan,
    towns: &BTreeMap<String, TownContext>,
    index: usize,
    count: usize,
) -> BTreeSet<String> {
    let (shard_of, _) = assign_shards(plan, towns, count);
    shard_of
        .iter()
        .enumerate()
        .filter(|&(_, &k)| k as usize == index)
        .filter_map(|(i, _)| plan.clip(i).map(|c| c.clip_id.into_owned()))
        .collect()
}

/// The estimated CPU seconds of each of `count` shards ([`shard_clips`]'s assignment).
pub fn shard_cpu_s(plan: &PreparedPlan, towns: &BTreeMap<String, TownContext>, count: usize) -> Vec<f64> {
    assign_shards(plan, towns, count).1
}

/// The shard of each clip (plan order) and each shard's estimated CPU seconds. A clip's cost needs its script
/// (its frames and pedestrians), so every script is compiled again; what is held is 4 bytes per clip for the
/// assignment (16 while sorting), only when sharding.
pub(super) fn assign_shards(
    plan: &PreparedPlan,
    towns: &BTreeMap<String, TownContext>,
    count: usize,
) -> (Vec<u32>, Vec<f64>) {
    use crate::plan::stats::{CAMERA_CPU_S_PER_PIXEL, GENERATION_PEDESTRIAN_FRAMES_PER_CPU_S, LIDAR_CPU_S_PER_RAY};
    let spec = &plan.header().spec;
    let s = &spec.sensors;
    let pixels = if s.cameras_enabled() {
        f64::from(s.rgb.width_px) * f64::from(s.rgb.height_px)
    } else {
        0.0
    };
    let rays = if s.lidar.enabled {
        f64::from(s.lidar.points_per_second) / f64::from(spec.dataset.fps.max(1))
    } else {
        0.0
    };
    // A clip that cannot be compiled costs nothing here; generating it reports the problem.
    let mut clips: Vec<(f64, u32)> = (0..plan.len())
        .map(|i| {
            let cost = plan.script(i, towns).map_or(0.0, |c| {
                let frames = f64::from(c.frame_count);
                frames * c.pedestrians.len() as f64 / GENERATION_PEDESTRIAN_FRAMES_PER_CPU_S
                    + frames * pixels * CAMERA_CPU_S_PER_PIXEL
                    + frames * rays * LIDAR_CPU_S_PER_RAY
                    + frames * 1e-6
            });
            (cost, u32::try_from(i).unwrap_or(u32::MAX))
        })
        .collect();
    // Ties by clip id, which within the plan's order is a stable total order of its own (ids are unique).
    let id = |i: u32| {
        plan.clip(i as usize)
            .map(|c| c.clip_id.into_owned())
            .unwrap_or_default()
    };
    clips.sort_by(|a, b| b.0.total_cmp(&a.0).then_with(|| id(a.1).cmp(&id(b.1))));
    let mut load = vec![0.0f64; count.max(1)];
    let mut shard_of = vec![0u32; plan.len()];
    for (cost, i) in clips {
        let k = (0..load.len())
            .min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b)))
            .unwrap_or(0);
        load[k] += cost;
        shard_of[i as usize] = u32::try_from(k).unwrap_or(u32::MAX);
    }
    (shard_of, load)
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
