//! The planner: compiles a validated spec and its towns into a deterministic [`Plan`] of seeded clip scripts.
//!
//! The planner is pure: no IO, no threads, no clocks. Towns are loaded by the caller and passed in.
//!
//! Clips are grouped in *strata*, one per (town, weather) cell. Within a stratum every mix (archetypes,
//! crossers, behaviours, speed profiles, driving profiles) is allocated with exact quotas (largest remainder)
//! and then shuffled with the stratum's seeded stream, so planned proportions equal the targets up to one unit
//! of rounding per stratum. Every random stream is keyed by the dataset seed and a stable identity (the
//! stratum or clip id), so adding a weather or a town leaves every other stratum's clips byte-identical, and
//! `--only CLIP_ID` re-plans exactly the same script.

mod allocate;
pub mod calibration;
mod clip;
pub mod identity;
mod lazy;
mod look;
mod pedestrians;
pub mod prepared;
pub mod quota;
pub mod reserve;
pub mod script;
pub mod seeds;
pub mod signal_plans;
mod staging;
pub mod stats;
mod traffic;

use std::collections::BTreeMap;
use std::f64::consts::PI;

use glam::DVec2;
use rand::RngExt;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha20Rng;
use serde::Serialize;

use crate::spec::types::{ClipsPer, Spec, TownRef, WeatherRef};
use crate::world::{LaneType, RoadNetwork};
use crate::world::{Route, Side, SpawnPoint};
use allocate::*;
pub use allocate::{
    CrossingAdaptation, adapted_baseline, allocated_crosser_ratio, baseline_crosser_ratio, crossing_adaptation,
};
use clip::*;
use lazy::*;
pub use lazy::{ClipRef, LazyPlan};
pub use pedestrians::CURB_STANDOFF_M;
use pedestrians::*;
pub use prepared::{PreparedPlan, plan_hash};
pub use script::*;
use traffic::*;

/// A town ready for planning: its road network and derived spawn candidates.
pub struct TownContext {
    /// The road network.
    pub network: RoadNetwork,
    /// Vehicle spawn candidates (driving lanes outside junctions).
    pub spawn_points: Vec<SpawnPoint>,
    /// The network's [`RoadNetwork::fingerprint`], recorded in plans.
    pub fingerprint: String,
}

impl TownContext {
    /// Prepares a town for planning.
    pub fn new(network: RoadNetwork) -> Self {
        let spawn_points = network.driving_spawn_points(10.0);
        let fingerprint = network.fingerprint();
        TownContext {
            network,
            spawn_points,
            fingerprint,
        }
    }
}

/// The reason given when `--only` names a clip the spec does not have.
pub const NO_SUCH_CLIP: &str = "no such clip in this spec";

/// Why a clip could not be planned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlanProblem {
    /// The clip (or `*` for the whole plan).
    pub clip_id: String,
    /// What went wrong.
    pub reason: String,
}

impl std::fmt::Display for PlanProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "clip {}: {}", self.clip_id, self.reason)
    }
}

/// One (town, weather) cell and its number of clips (clip `k`'s id is [`clip_id`]).
#[derive(Clone, Debug)]
struct Stratum {
    town: TownRef,
    weather: WeatherRef,
    clips: usize,
}

/// The id of clip `k` of the stratum (`town`, `weather`): `<town>-<weather>-<NNNN>`.
fn clip_id(town: &TownRef, weather: &WeatherRef, k: usize) -> String {
    format!("{}-{}-{k:04}", town.name(), weather.name())
}

/// Which clips the spec asks for, grouped by stratum, in plan order.
fn strata(spec: &Spec) -> Vec<Stratum> {
    let weathers = spec.dataset.weathers.resolved();
    let towns = &spec.dataset.towns;
    let count = spec.dataset.clips.count as usize;
    let mut cells: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for (wi, weather) in weathers.iter().enumerate() {
        for ti in 0..towns.len() {
            let n = match spec.dataset.clips.per {
                ClipsPer::TownAndWeather => count,
                // `count` clips per weather spread round-robin over the towns, starting at a town chosen by the
                // weather's name so that a small count does not always favour the first town.
                ClipsPer::Weather => {
                    let offset = (seeds::seed_u64(spec.dataset.seed, &format!("town-offset/{}", weather.name()))
                        % towns.len() as u64) as usize;
                    let first = (ti + towns.len() - offset) % towns.len();
                    if first < count {
                        (count - first).div_ceil(towns.len())
                    } else {
                        0
                    }
                }
            };
            cells.insert((ti, wi), n);
        }
    }
    cells
        .into_iter()
        .filter(|&(_, n)| n > 0)
        .map(|((ti, wi), clips)| Stratum {
            town: towns[ti].clone(),
            weather: weathers[wi].clone(),
            clips,
        })
        .collect()
}

/// Compiles `spec` into a plan; `spec_dir` is recorded for resolving the spec's relative paths. `towns` maps each town name of the spec to its prepared road network.
/// With `only`, plans just that clip (its stratum's draws are made in full, so the script is identical).
pub fn plan(
    spec: &Spec,
    spec_hash: &str,
    spec_dir: &str,
    towns: &BTreeMap<String, TownContext>,
    only: Option<&str>,
) -> Result<Plan, Vec<PlanProblem>> {
    let lazy = LazyPlan::compile(spec, spec_hash, spec_dir, towns);
    let indices: Vec<usize> = match only {
        Some(id) => vec![lazy.position(id).ok_or_else(|| {
            vec![PlanProblem {
                clip_id: id.to_owned(),
                reason: NO_SUCH_CLIP.to_owned(),
            }]
        })?],
        None => (0..lazy.len()).collect(),
    };
    let mut clips = Vec::with_capacity(indices.len());
    let mut problems = Vec::new();
    for i in indices {
        match lazy.script(i, towns) {
            Ok(script) => clips.push(script.into_owned()),
            Err(p) => problems.push(p),
        }
    }
    // A town that was not loaded is one problem, not one per clip.
    problems.dedup();
    if !problems.is_empty() {
        return Err(problems);
    }
    let mut plan = lazy.into_header();
    plan.clips = clips;
    Ok(plan)
}
