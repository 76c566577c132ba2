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

pub mod calibration;
pub mod identity;
pub mod prepared;
pub mod quota;
pub mod reserve;
pub mod script;
pub mod seeds;
pub mod signal_plans;
mod staging;
pub mod stats;

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
pub use prepared::{PreparedPlan, plan_hash};
pub use script::*;

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

/// A compiled plan whose clip scripts are not held: each is compiled again when asked for, from the draws of
/// its stratum, which are themselves made again when needed (a few strata's draws are cached) — so `generate`
/// works through any number of clips holding nothing per clip. A plan read from a file holds its scripts
/// instead. Either way, [`LazyPlan::script`] returns the script [`plan`] would put in the plan, bit for bit.
pub struct LazyPlan {
    /// The plan without its clips (`clips` is empty).
    header: Plan,
    source: Source,
}

enum Source {
    /// The scripts of a plan file.
    Held(Vec<ClipScript>),
    /// The strata in plan order; `starts[k]` is the plan index of stratum `k`'s first clip. Their draws are
    /// made when a clip of theirs is compiled.
    Drawn {
        strata: Vec<Stratum>,
        starts: Vec<usize>,
        cache: DrawCache,
    },
}

/// The draws of the strata used last, most recent last. Draws are arithmetic on the spec and seeds, so a
/// stratum drawn twice (two workers at once, or after eviction) gives the same draws: the cache changes the
/// time taken, never a script.
#[derive(Default)]
struct DrawCache(std::sync::Mutex<Vec<(usize, std::sync::Arc<StratumDraws>)>>);

/// Strata whose draws are kept: enough for every worker of a large machine to work in its own stratum
/// (workers take clips from separate parts of the plan) while holding a bounded amount.
const CACHED_STRATA: usize = 32;

impl DrawCache {
    /// The draws of stratum `k`, made with `draw` unless cached.
    fn get(&self, k: usize, draw: impl FnOnce() -> StratumDraws) -> std::sync::Arc<StratumDraws> {
        // A worker that panicked while holding the lock left a valid list behind (the list is only pushed to
        // and rotated): the poison is ignored.
        let lock = || self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        {
            let mut entries = lock();
            if let Some(at) = entries.iter().position(|(key, _)| *key == k) {
                let entry = entries.remove(at);
                let draws = std::sync::Arc::clone(&entry.1);
                entries.push(entry);
                return draws;
            }
        }
        // Drawn without the lock, so that other workers are not held up.
        let draws = std::sync::Arc::new(draw());
        let mut entries = lock();
        if !entries.iter().any(|(key, _)| *key == k) {
            entries.push((k, std::sync::Arc::clone(&draws)));
            if entries.len() > CACHED_STRATA {
                entries.remove(0);
            }
        }
        draws
    }
}

/// What a stratum allocates across its clips; each clip's script compiles from these alone.
struct StratumDraws {
    basics: Vec<ClipBasics>,
    allocs: Vec<PedAlloc>,
    /// Driving profile of each vehicle of the stratum, in clip order.
    profiles: Vec<DrivingProfileKind>,
}

/// Which clip of the plan a plan index is, without compiling it: see [`LazyPlan::clip`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ClipRef<'a> {
    /// Clip id.
    pub clip_id: std::borrow::Cow<'a, str>,
    /// Town name.
    pub town: &'a str,
    /// Dataset split.
    pub split: crate::spec::types::Split,
}

impl LazyPlan {
    /// The spec's plan, each clip compiled when asked for (nothing is drawn yet); a clip that cannot be
    /// planned, or whose town is missing from `towns`, is reported by [`LazyPlan::script`].
    pub fn compile(spec: &Spec, spec_hash: &str, spec_dir: &str, towns: &BTreeMap<String, TownContext>) -> LazyPlan {
        let strata = strata(spec);
        let starts = strata
            .iter()
            .scan(0, |next, s| {
                let start = *next;
                *next += s.clips;
                Some(start)
            })
            .collect();
        LazyPlan {
            header: Plan {
                format_version: PLAN_FORMAT_VERSION,
                pedsynth_version: env!("CARGO_PKG_VERSION").to_owned(),
                dataset: spec.dataset.name.clone(),
                seed: spec.dataset.seed,
                spec_hash: spec_hash.to_owned(),
                target_crossing_ratio: spec.crossing.target_ratio,
                sim: SimParams::from_spec(spec),
                spec: spec.clone(),
                spec_dir: spec_dir.to_owned(),
                towns: towns
                    .iter()
                    .map(|(name, t)| (name.clone(), t.fingerprint.clone()))
                    .collect(),
                clips: Vec::new(),
            },
            source: Source::Drawn {
                strata,
                starts,
                cache: DrawCache::default(),
            },
        }
    }

    /// A plan that holds its scripts (a plan file, already checked).
    pub fn from_plan(mut plan: Plan) -> LazyPlan {
        let clips = std::mem::take(&mut plan.clips);
        LazyPlan {
            header: plan,
            source: Source::Held(clips),
        }
    }

    /// The plan without its clips (`clips` is empty).
    pub fn header(&self) -> &Plan {
        &self.header
    }

    /// The header, as a plan to put the clips in.
    pub fn into_header(self) -> Plan {
        self.header
    }

    /// The number of clips.
    pub fn len(&self) -> usize {
        match &self.source {
            Source::Held(clips) => clips.len(),
            Source::Drawn { strata, starts, .. } => {
                starts.last().copied().unwrap_or(0) + strata.last().map_or(0, |s| s.clips)
            }
        }
    }

    /// Whether the plan has no clip.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The stratum and the index in it of plan index `i` (`i < len`).
    fn locate(starts: &[usize], i: usize) -> (usize, usize) {
        let k = starts.partition_point(|&s| s <= i).saturating_sub(1);
        (k, i - starts.get(k).copied().unwrap_or(0))
    }

    /// Which clip plan index `i` is (id, town, split), if there is one; nothing is compiled or drawn.
    pub fn clip(&self, i: usize) -> Option<ClipRef<'_>> {
        match &self.source {
            Source::Held(clips) => clips.get(i).map(|c| ClipRef {
                clip_id: c.clip_id.as_str().into(),
                town: &c.town,
                split: c.split,
            }),
            Source::Drawn { strata, starts, .. } => {
                let (k, j) = Self::locate(starts, i);
                let s = strata.get(k)?;
                (j < s.clips).then(|| ClipRef {
                    clip_id: clip_id(&s.town, &s.weather, j).into(),
                    town: s.town.name(),
                    split: split_of(&self.header.spec, &s.town),
                })
            }
        }
    }

    /// The id of clip `i` (plan order), if there is one.
    pub fn clip_id(&self, i: usize) -> Option<std::borrow::Cow<'_, str>> {
        self.clip(i).map(|c| c.clip_id)
    }

    /// The plan index of the clip `id`.
    pub fn position(&self, id: &str) -> Option<usize> {
        (0..self.len()).find(|&i| self.clip_id(i).as_deref() == Some(id))
    }

    /// The script of clip `i` (plan order): borrowed from a plan file, or compiled from its stratum's draws.
    pub fn script<'a>(
        &'a self,
        i: usize,
        towns: &BTreeMap<String, TownContext>,
    ) -> Result<std::borrow::Cow<'a, ClipScript>, PlanProblem> {
        let no_clip = || PlanProblem {
            clip_id: format!("#{i}"),
            reason: NO_SUCH_CLIP.to_owned(),
        };
        let (strata, starts, cache) = match &self.source {
            Source::Held(clips) => return clips.get(i).map(std::borrow::Cow::Borrowed).ok_or_else(no_clip),
            Source::Drawn { strata, starts, cache } => (strata, starts, cache),
        };
        let (k, j) = Self::locate(starts, i);
        let s = strata.get(k).ok_or_else(no_clip)?;
        if j >= s.clips {
            return Err(no_clip());
        }
        let Some(town) = towns.get(s.town.name()) else {
            return Err(PlanProblem {
                clip_id: "*".to_owned(),
                reason: format!("town `{}` was not loaded", s.town.name()),
            });
        };
        let spec = &self.header.spec;
        let d = cache.get(k, || draw_stratum(spec, k, s));
        let b = d.basics.get(j).ok_or_else(no_clip)?;
        let archetype_names: Vec<&String> = spec.pedestrians.archetype_mix.keys().collect();
        let id = clip_id(&s.town, &s.weather, j);
        plan_clip(
            spec,
            (&s.town, &s.weather),
            town,
            (id.clone(), b),
            &d.allocs[b.first_pedestrian..b.first_pedestrian + b.pedestrians],
            b.first_pedestrian,
            &d.profiles[b.first_vehicle..b.first_vehicle + b.vehicles],
            &archetype_names,
        )
        .map(std::borrow::Cow::Owned)
        .map_err(|reason| PlanProblem { clip_id: id, reason })
    }
}

/// The split of the clips of `town`.
fn split_of(spec: &Spec, town: &TownRef) -> crate::spec::types::Split {
    spec.dataset
        .splits
        .get(town.name())
        .copied()
        .unwrap_or(spec.dataset.default_split)
}

/// Per-clip draws that the stratum's quotas depend on.
struct ClipBasics {
    seed: u64,
    frame_count: u32,
    pedestrians: usize,
    vehicles: usize,
    /// Stratum-wide index of the clip's first pedestrian (in the stratum's allocations).
    first_pedestrian: usize,
    /// Stratum-wide index of the clip's first vehicle (in the stratum's driving profiles).
    first_vehicle: usize,
    /// The clip's emergency vehicle, if it is one of the stratum's emergency clips.
    emergency: Option<EmergencyKind>,
    /// The clip's planned count of labelled crossers ([`reserve::labelled_targets`]).
    labelled_crossers: Option<u32>,
}

/// Per-pedestrian allocations made at the stratum level (16 bytes: a plan holds one per pedestrian).
#[derive(Clone)]
struct PedAlloc {
    /// Index in the spec's archetype mix.
    archetype: u32,
    speed_profile: SpeedProfile,
    source: CrosserSource,
    behaviour: Behaviour,
    /// Stratum-wide index of the group's leader.
    group: Option<u32>,
}

/// The share of pedestrians layer 1 allocates as crossers so that, with the baseline and the measured share of
/// planned crossers that end up labelled crossers ([`crate::plan::calibration::CROSSER_REALISATION`]), the expected
/// labelled crossing ratio meets the target.
pub fn allocated_crosser_ratio(spec: &Spec) -> f64 {
    crosser_shares(spec).0
}

/// The share of the pedestrians not allocated by layer 1 that cross on their own: the spec's
/// `baseline_ratio`, lowered when the target is below what the baseline alone would give (a rare-event set of
/// 5 % crossers under the default 9 % baseline), so that any target down to 0 is met ([`adapted_baseline`]).
pub fn baseline_crosser_ratio(spec: &Spec) -> f64 {
    crosser_shares(spec).1
}

/// Whether the planner lowered the baseline for this spec's target, and to what: `Some((spec's, used))`.
pub fn adapted_baseline(spec: &Spec) -> Option<(f64, f64)> {
    let b = spec.crossing.baseline_ratio;
    let used = baseline_crosser_ratio(spec);
    (used < b).then_some((b, used))
}

/// How the planner adapts the spec's crossing layers to a target above what they reach: every pedestrian may be
/// a crosser (`max_crosser_ratio` 1), then fewer crossing groups (a single does not wait at the curb for its
/// companions, so more are seen crossing), then more mid-road jaywalkers (they start on the road), up to all of
/// them ([`crate::plan::calibration::MIDROAD_LADDER`]). `pedsynth plan` prints it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CrossingAdaptation {
    /// The share of pedestrians layer 1 may allocate (the spec's `max_crosser_ratio` lifted to 1).
    pub max_crosser_ratio: f64,
    /// The group probability used (the spec's `crossing.layers.groups.probability`, or less).
    pub group_probability: f64,
    /// The share of crossers starting mid-road used (the spec's layer 3 share, or more).
    pub midroad_share: f64,
    /// The share of planned crossers expected to be labelled crossers under these layers.
    pub realisation: f64,
}

/// The planner's adaptation of the crossing layers for `spec`'s target, if the spec's own layers do not reach
/// it ([`CrossingAdaptation`]); `None` with layer 1 off or a target they reach.
pub fn crossing_adaptation(spec: &Spec) -> Option<CrossingAdaptation> {
    let c = &spec.crossing;
    let l = &c.layers;
    if !l.crosser_allocation.enabled {
        return None;
    }
    let r0 = crate::plan::calibration::crosser_realisation(spec).0;
    let (r_singles, ladder) = crate::plan::calibration::adapted_realisations(spec);
    let t = c.target_ratio;
    let b = c.baseline_ratio.clamp(0.0, 1.0);
    let max = l.crosser_allocation.max_crosser_ratio.clamp(0.0, 1.0);
    if t <= (max + (1.0 - max) * b) * r0 + 1e-12 {
        return None;
    }
    let groups = if l.groups.enabled {
        l.groups.probability.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let midroad = if l.midroad_jaywalkers.enabled {
        l.midroad_jaywalkers.share_of_crossers.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut a = CrossingAdaptation {
        max_crosser_ratio: 1.0,
        group_probability: groups,
        midroad_share: midroad,
        realisation: r0,
    };
    if t <= r0 {
        return Some(a);
    }
    // Fewer groups, in proportion, until none.
    if groups > 0.0 {
        let x = ((t - r0) / (r_singles - r0)).min(1.0);
        a.group_probability = groups * (1.0 - x);
        a.realisation = r0 + (r_singles - r0) * x;
        if x < 1.0 {
            return Some(a);
        }
        a.group_probability = 0.0;
    }
    // Then more mid-road jaywalkers, along the measured ladder (linear between its steps), up to all of them.
    let mut from = (midroad, a.realisation);
    let base = a.realisation;
    for &(share, realisation) in ladder.iter().filter(|s| s.0 > midroad && s.1 > base) {
        let y = ((t - from.1) / (realisation - from.1)).clamp(0.0, 1.0);
        a.midroad_share = from.0 + (share - from.0) * y;
        a.realisation = from.1 + (realisation - from.1) * y;
        if y < 1.0 {
            break;
        }
        from = (share, realisation);
    }
    Some(a)
}

/// (layer 1's allocated share, the baseline share of the rest).
fn crosser_shares(spec: &Spec) -> (f64, f64) {
    let c = &spec.crossing;
    let l1 = &c.layers.crosser_allocation;
    let b = c.baseline_ratio.clamp(0.0, 1.0);
    if !l1.enabled {
        return (0.0, b);
    }
    // Plan enough crossers that the expected share labelled crossers in the dataset meets the target; allocated
    // and baseline crossers are labelled at the same measured rate (that of the adapted layers, above what the
    // spec's layers reach).
    let (realisation, max) = match crossing_adaptation(spec) {
        Some(a) => (a.realisation, a.max_crosser_ratio),
        None => (
            crate::plan::calibration::crosser_realisation(spec).0,
            l1.max_crosser_ratio,
        ),
    };
    let planned = (c.target_ratio / realisation).clamp(0.0, 1.0);
    if planned <= b {
        // The baseline alone would overshoot: it carries all the crossers, at the planned share.
        return (0.0, planned);
    }
    let r = if b >= 1.0 { 0.0 } else { (planned - b) / (1.0 - b) };
    (r.clamp(0.0, max), b)
}

/// The draws of stratum `stratum_index` (plan order): each clip's basics, then the stratum's pedestrian
/// allocations, each clip's count of labelled crossers and the driving profiles.
fn draw_stratum(spec: &Spec, stratum_index: usize, stratum: &Stratum) -> StratumDraws {
    let seed = spec.dataset.seed;
    let d = &spec.dataset;
    let (mut first_pedestrian, mut first_vehicle) = (0, 0);
    let basics: Vec<ClipBasics> = (0..stratum.clips)
        .map(|k| {
            let clip_seed = seeds::seed_u64(seed, &clip_id(&stratum.town, &stratum.weather, k));
            let mut rng = seeds::clip_rng(clip_seed, "basics");
            let duration_s = rng.random_range(d.clip_duration_s.min()..=d.clip_duration_s.max());
            let frame_count = ((duration_s * f64::from(d.fps)).round() as u32).max(1);
            let p = &spec.pedestrians.per_clip;
            let v = &spec.traffic.vehicles_per_clip;
            let basics = ClipBasics {
                seed: clip_seed,
                frame_count,
                pedestrians: rng.random_range(p.min()..=p.max()) as usize,
                vehicles: rng.random_range(v.min()..=v.max()) as usize,
                first_pedestrian,
                first_vehicle,
                emergency: None,
                labelled_crossers: None,
            };
            first_pedestrian += basics.pedestrians;
            first_vehicle += basics.vehicles;
            basics
        })
        .collect();
    let mut basics = basics;
    allocate_emergencies(spec, stratum, &mut basics);

    let allocs = allocate_pedestrians(spec, stratum, &basics);
    let wanted = reserve::labelled_targets(spec, stratum_index, &basics, &allocs);
    for (b, wanted) in basics.iter_mut().zip(wanted) {
        b.labelled_crossers = wanted;
    }
    let m = &spec.traffic.profile_mix;
    let mut stratum_rng = seeds::rng_for(
        seed,
        &format!("stratum/{}/{}/vehicles", stratum.town.name(), stratum.weather.name()),
    );
    let profiles = quota::allocate(first_vehicle, &[m.aggressive, m.normal, m.cautious], &mut stratum_rng)
        .into_iter()
        .map(|k| DrivingProfileKind::ALL[k])
        .collect();
    StratumDraws {
        basics,
        allocs,
        profiles,
    }
}

/// Emergency clips: `clip_share` of the dataset's clips, exact over the whole dataset (systematic sampling over
/// the strata in plan order with a seeded offset, so each stratum gets its share within one clip and no state
/// is kept), the stratum's ones chosen at random, their kinds by the mix along a seeded golden-ratio sequence
/// over the dataset's emergency clips. All from streams of their own, drawn only when emergencies are enabled
/// (turning them on shifts no other draw).
fn allocate_emergencies(spec: &Spec, stratum: &Stratum, basics: &mut [ClipBasics]) {
    let e = &spec.traffic.emergency;
    if !e.enabled || basics.is_empty() {
        return;
    }
    let seed = spec.dataset.seed;
    let unit = |tag: &str| (seeds::seed_u64(seed, tag) >> 11) as f64 / (1u64 << 53) as f64;
    let (phi, phi_kind) = (unit("emergency/offset"), unit("emergency/kinds"));
    let share = e.clip_share.clamp(0.0, 1.0);
    let before: usize = strata(spec)
        .iter()
        .take_while(|s| !(s.town.name() == stratum.town.name() && s.weather.name() == stratum.weather.name()))
        .map(|s| s.clips)
        .sum();
    let cumulative = |n: usize| (n as f64 * share + phi).floor() as usize;
    let count = cumulative(before + basics.len()) - cumulative(before);
    let first = cumulative(before) - cumulative(0);
    let mut rng = seeds::rng_for(
        seed,
        &format!("stratum/{}/{}/emergency", stratum.town.name(), stratum.weather.name()),
    );
    let chosen = quota::weighted_choice(count, &vec![1.0; basics.len()], &mut rng);
    let mix = [e.mix.ambulance, e.mix.fire_truck, e.mix.police];
    let total: f64 = mix.iter().sum();
    for (j, b) in basics
        .iter_mut()
        .zip(chosen)
        .filter(|(_, c)| *c)
        .map(|(b, _)| b)
        .enumerate()
    {
        let u = (phi_kind + (first + j) as f64 * 0.618_033_988_749_894_9).fract() * total;
        let mut acc = 0.0;
        let kind = (0..mix.len())
            .find(|&k| {
                acc += mix[k];
                u < acc && mix[k] > 0.0
            })
            .or_else(|| (0..mix.len()).rev().find(|&k| mix[k] > 0.0))
            .unwrap_or(0);
        b.emergency = Some(EmergencyKind::ALL[kind]);
    }
}

fn allocate_pedestrians(spec: &Spec, stratum: &Stratum, basics: &[ClipBasics]) -> Vec<PedAlloc> {
    let n: usize = basics.iter().map(|b| b.pedestrians).sum();
    let p = &spec.pedestrians;
    let c = &spec.crossing;
    let tag = |what: &str| format!("stratum/{}/{}/{what}", stratum.town.name(), stratum.weather.name());
    let seed = spec.dataset.seed;

    let shares: Vec<f64> = p.archetype_mix.values().copied().collect();
    let archetypes = quota::allocate(n, &shares, &mut seeds::rng_for(seed, &tag("archetypes")));
    let sm = &p.speed_profiles.mix;
    let speed = quota::allocate(
        n,
        &[sm.cautious, sm.normal, sm.rushed, sm.distracted],
        &mut seeds::rng_for(seed, &tag("speed")),
    );

    // Crossers: layer 1 allocates what the target needs beyond the baseline; the archetype's crossing
    // propensity weights who is chosen. The rest cross at the baseline rate, as CARLA's walkers do.
    let weights: Vec<f64> = archetypes
        .iter()
        .map(|&a| {
            p.archetype_mix
                .keys()
                .nth(a)
                .and_then(|name| p.archetypes.get(name))
                .map_or(0.5, |x| x.crossing_probability.max(1e-3))
        })
        .collect();
    let mut rng = seeds::rng_for(seed, &tag("crossers"));
    let r = allocated_crosser_ratio(spec);
    let allocated = quota::largest_remainder(n, &[r, 1.0 - r])[0];
    let allocated_mask = quota::weighted_choice(allocated, &weights, &mut rng);
    let rest: Vec<usize> = (0..n).filter(|&i| !allocated_mask[i]).collect();
    let b = baseline_crosser_ratio(spec);
    let baseline = quota::largest_remainder(rest.len(), &[b, 1.0 - b])[0];
    let rest_weights: Vec<f64> = rest.iter().map(|&i| weights[i]).collect();
    let baseline_mask = quota::weighted_choice(baseline, &rest_weights, &mut rng);

    let mut out: Vec<PedAlloc> = (0..n)
        .map(|i| PedAlloc {
            archetype: u32::try_from(archetypes[i]).unwrap_or(u32::MAX),
            speed_profile: SpeedProfile::ALL[speed[i]],
            source: CrosserSource::None,
            behaviour: Behaviour::None,
            group: None,
        })
        .collect();
    for (k, &i) in rest.iter().enumerate() {
        if baseline_mask[k] {
            out[i].source = CrosserSource::Baseline;
            out[i].behaviour = Behaviour::Normal;
        }
    }

    // Layer 4: group units among each clip's allocated crossers. A group starts at a crosser with probability
    // q, chosen so that the expected share of grouped crossers is the spec's group probability.
    let g = &c.layers.groups;
    let adaptation = crossing_adaptation(spec);
    let mut group_rng = seeds::rng_for(seed, &tag("groups"));
    let triple_share = g.size_mix.triples / (g.size_mix.pairs + g.size_mix.triples).max(1e-12);
    let mean_size = 2.0 + triple_share;
    let f = adaptation
        .map_or(g.probability, |a| a.group_probability)
        .clamp(0.0, 1.0);
    let q = if g.enabled {
        (f / (mean_size - f * (mean_size - 1.0))).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut units: Vec<Vec<usize>> = Vec::new();
    let mut first = 0;
    for clip in basics {
        let crossers: Vec<usize> = (first..first + clip.pedestrians)
            .filter(|&i| allocated_mask[i])
            .collect();
        first += clip.pedestrians;
        let mut k = 0;
        while k < crossers.len() {
            let left = crossers.len() - k;
            let size = if left >= 2 && group_rng.random_bool(q) {
                if left >= 3 && group_rng.random_bool(triple_share.clamp(0.0, 1.0)) {
                    3
                } else {
                    2
                }
            } else {
                1
            };
            units.push(crossers[k..k + size].to_vec());
            k += size;
        }
    }

    // Behaviours with exact quotas over allocated crossers: layer 3's mid-road share, then layer 2's mix. A
    // group shares one behaviour: groups take the behaviour with the most room left, singles fill the rest.
    let total: usize = units.iter().map(Vec::len).sum();
    let l3 = &c.layers.midroad_jaywalkers;
    let midroad_share = match adaptation {
        Some(a) => a.midroad_share,
        None if l3.enabled => l3.share_of_crossers,
        None => 0.0,
    };
    let midroad = quota::largest_remainder(total, &[midroad_share, 1.0 - midroad_share])[0];
    let mix = &c.layers.behaviour_mix;
    let mix_shares = if mix.enabled {
        [mix.mix.normal, mix.mix.sudden, mix.mix.jaywalk]
    } else {
        [1.0, 0.0, 0.0]
    };
    let rest_counts = quota::largest_remainder(total - midroad, &mix_shares);
    let kinds = [
        Behaviour::MidroadJaywalker,
        Behaviour::Normal,
        Behaviour::Sudden,
        Behaviour::Jaywalk,
    ];
    let mut remaining = [midroad, rest_counts[0], rest_counts[1], rest_counts[2]];
    let mut behaviour_rng = seeds::rng_for(seed, &tag("behaviours"));
    let (mut groups, mut singles): (Vec<Vec<usize>>, Vec<Vec<usize>>) = units.into_iter().partition(|u| u.len() > 1);
    groups.sort_by_key(|u| std::cmp::Reverse(u.len()));
    let mut assigned: Vec<(Vec<usize>, Behaviour)> = Vec::new();
    for unit in groups {
        let best = (0..kinds.len())
            .filter(|&k| remaining[k] >= unit.len())
            .max_by_key(|&k| (remaining[k], std::cmp::Reverse(k)));
        match best {
            Some(k) => {
                remaining[k] -= unit.len();
                assigned.push((unit, kinds[k]));
            }
            None => singles.extend(unit.into_iter().map(|i| vec![i])),
        }
    }
    let mut pool: Vec<Behaviour> = kinds
        .iter()
        .zip(remaining)
        .flat_map(|(k, n)| std::iter::repeat_n(*k, n))
        .collect();
    pool.shuffle(&mut behaviour_rng);
    assigned.extend(singles.into_iter().zip(pool));
    for (unit, behaviour) in assigned {
        for &i in &unit {
            out[i].source = CrosserSource::Allocated;
            out[i].behaviour = behaviour;
            if unit.len() > 1 {
                out[i].group = Some(u32::try_from(unit[0]).unwrap_or(u32::MAX));
            }
        }
    }

    // Hard negatives: an exact share of the non-crossers, chosen at random.
    let non_crossers: Vec<usize> = (0..n).filter(|&i| out[i].source == CrosserSource::None).collect();
    let h = c.hard_negatives.share_of_non_crossers.clamp(0.0, 1.0);
    let hard = quota::largest_remainder(non_crossers.len(), &[h, 1.0 - h])[0];
    let mut hard_rng = seeds::rng_for(seed, &tag("hard_negatives"));
    let chosen = quota::weighted_choice(hard, &vec![1.0; non_crossers.len()], &mut hard_rng);
    for (k, &i) in non_crossers.iter().enumerate() {
        if chosen[k] {
            out[i].behaviour = Behaviour::HardNegative;
        }
    }
    out
}

/// The ego's planned cruise speed upper bound, for route length checks, m/s.
const MAX_URBAN_SPEED_MPS: f64 = 14.0;

#[allow(clippy::too_many_arguments)]
fn plan_clip(
    spec: &Spec,
    (town_ref, weather): (&TownRef, &WeatherRef),
    town: &TownContext,
    (clip_id, basics): (String, &ClipBasics),
    peds: &[PedAlloc],
    first_ped: usize,
    vehicle_profiles: &[DrivingProfileKind],
    archetype_names: &[&String],
) -> Result<ClipScript, String> {
    let mut rng = seeds::clip_rng(basics.seed, "plan");
    let net = &town.network;
    let fps = spec.dataset.fps;
    let duration_s = f64::from(basics.frame_count) / f64::from(fps);
    let l1 = &spec.crossing.layers.crosser_allocation;
    let ahead_max = l1.spawn_ahead_m.max().max(spec.annotations.visibility.max_distance_m);
    let needed_m = ahead_max + MAX_URBAN_SPEED_MPS * duration_s + spec.traffic.ego.route_margin_m;

    // The ego route, with room ahead for every pedestrian; a route along which the clip's pedestrians or
    // vehicles cannot be placed is replaced by another (a few tries), then the clip is infeasible.
    let ego_spec = &spec.traffic.ego;
    let mut last_error = String::new();
    let mut planned = None;
    for _ in 0..ROUTE_ATTEMPTS {
        let route = net
            .random_route(&mut rng, needed_m)
            .ok_or_else(|| format!("no route of {needed_m:.0} m in town `{}`", net.name))?;
        let ego = EgoScript {
            route: route_script(&route, 0.0),
            speed_below_limit_pct: rng
                .random_range(ego_spec.speed_below_limit_pct.min()..=ego_spec.speed_below_limit_pct.max()),
            min_gap_m: ego_spec.min_gap_m,
            brake_ahead_m: ego_spec.brake_ahead_m,
            brake_lateral_m: ego_spec.brake_lateral_m,
            courtesy_speed_mps: draw(&mut rng, ego_spec.courtesy_speed_mps),
            courtesy_ahead_m: ego_spec.courtesy_ahead_m,
            courtesy_lateral_m: ego_spec.courtesy_lateral_m,
            courtesy_stop_short_m: ego_spec.courtesy_stop_short_m,
            courtesy_patience_s: draw(&mut rng, ego_spec.courtesy_patience_s),
        };
        let placed = plan_pedestrians(
            spec,
            net,
            &route,
            peds,
            first_ped,
            archetype_names,
            duration_s,
            basics.seed,
            &mut rng,
        )
        .and_then(|pedestrians| {
            plan_vehicles(spec, town, &route, &pedestrians, vehicle_profiles, needed_m, &mut rng)
                .map(|v| (pedestrians, v))
        });
        match placed {
            Ok((pedestrians, vehicles)) => {
                planned = Some((route, ego, pedestrians, vehicles));
                break;
            }
            Err(e) => last_error = e,
        }
    }
    let Some((route, ego, pedestrians, mut vehicles)) = planned else {
        return Err(format!("{last_error} (tried {ROUTE_ATTEMPTS} ego routes)"));
    };
    if let Some(kind) = basics.emergency {
        vehicles.push(plan_emergency(
            spec,
            town,
            &ego.route,
            &pedestrians,
            &vehicles,
            kind,
            needed_m,
            basics.seed,
        )?);
    }
    let cyclists = plan_cyclists(spec, town, &ego.route, &pedestrians, &vehicles, needed_m, basics.seed);
    // Where lights run, the clip's signalised crossing is staged (the ego waits at red in front of it), and the
    // ego's red-light waits count in the crossers' timelines.
    let cruise_mps = ego_cruise_mps(net, &ego);
    let timing = &spec.traffic.signals;
    let lights = timing.enabled && !net.signals.is_empty();
    let (signal_offsets, plans) = if lights {
        let drawn = signal_plans::SignalPlans::new(net, timing, basics.seed);
        let schedule = staging::EgoSchedule::with_lights(cruise_mps, net, &route, &drawn);
        let offsets: Vec<(u32, f64)> =
            staging::staged_offset(net, basics.seed, &route, &pedestrians, (&drawn, &schedule))
                .into_iter()
                .collect();
        let plans = drawn.with_offsets(&offsets);
        (offsets, Some(plans))
    } else {
        (Vec::new(), None)
    };
    let schedule = match &plans {
        Some(plans) => staging::EgoSchedule::with_lights(cruise_mps, net, &route, plans),
        None => staging::EgoSchedule::cruising(cruise_mps),
    };
    // The clip lasts at least as long as its crossers' timelines, up to a cap.
    let needed_s = pedestrians
        .iter()
        .filter_map(|p| timeline_duration_s(p, &schedule, plans.as_ref().map(|plans| (plans, net))))
        .fold(0.0, f64::max);
    let extension_s = (needed_s - duration_s).clamp(0.0, (MAX_TIMELINE_EXTENSION - 1.0) * duration_s);
    let frame_count = if extension_s > 0.0 {
        ((duration_s + extension_s) * f64::from(fps)).round() as u32
    } else {
        basics.frame_count
    };

    Ok(ClipScript {
        clip_id,
        seed: basics.seed,
        town: town_ref.name().to_owned(),
        weather: weather.name().to_owned(),
        weather_params: weather.params(),
        split: split_of(spec, town_ref),
        fps,
        frame_count,
        ego,
        vehicles,
        pedestrians,
        cyclists,
        signal_offsets,
        timeline_extension_s: f64::from(frame_count - basics.frame_count) / f64::from(fps),
        labelled_crossers: basics.labelled_crossers,
    })
}

/// A clip is lengthened to at most this multiple of its drawn duration for its crossers' timelines.
const MAX_TIMELINE_EXTENSION: f64 = 2.0;
/// Distance at which the planner estimates that the ego's camera starts to see a pedestrian, metres (the
/// visibility gate admits an adult within about 30–35 m; the simulation decides the real moment).
const VIEW_DISTANCE_ESTIMATE_M: f64 = 30.0;
/// Time after a crossing for the crosser to reach the far sidewalk in view, seconds.
const CROSSING_MARGIN_S: f64 = 1.5;

/// The ego's cruising speed at its start, m/s.
fn ego_cruise_mps(net: &RoadNetwork, ego: &EgoScript) -> f64 {
    let limit = ego
        .route
        .lanes
        .first()
        .and_then(|&l| net.lanes.get(l as usize))
        .map_or(30.0 / 3.6, |l| {
            if l.speed_limit_mps > 0.5 {
                l.speed_limit_mps
            } else {
                30.0 / 3.6
            }
        });
    (limit * (1.0 - ego.speed_below_limit_pct / 100.0)).max(1.0)
}

/// The time a crosser's timeline needs from the clip's start, seconds: until it is in view (the ego, waiting at
/// red lights on the way, comes within view, or it walks to its curb), its time in view, and the crossing. At a
/// signalised crosswalk (where `lights` run) "walk" sets the moment instead: the first after it has reached its
/// curb and checked.
fn timeline_duration_s(
    p: &PedestrianScript,
    schedule: &staging::EgoSchedule,
    lights: Option<(&signal_plans::SignalPlans, &RoadNetwork)>,
) -> Option<f64> {
    let in_view_s = p.in_view_before_crossing_s?;
    let crossing = p.crossing.as_ref()?;
    let speed = p.base_speed_mps.max(0.3);
    let curb = crossing.near_curb - crossing.direction * CURB_STANDOFF_M;
    let approach_s = p.spawn.distance(curb) / speed;
    let into_view_s = schedule.time_at(p.ahead_of_ego_m - VIEW_DISTANCE_ESTIMATE_M);
    let signal = lights
        .filter(|_| !p.red_light_violator)
        .and_then(|(plans, net)| Some((plans, net, staging::crossing_signal(net, p)?)));
    let start_s = match signal {
        Some((plans, net, signal)) => staging::walk_start_s(plans, net, signal, approach_s + staging::SIGNAL_CHECK_S),
        None => approach_s.max(into_view_s) + in_view_s,
    };
    Some(start_s + crossing.carriageway_width_m / speed + CROSSING_MARGIN_S)
}

fn route_script(route: &Route, start_s_m: f64) -> RouteScript {
    let mut lanes: Vec<u32> = Vec::new();
    for p in &route.points {
        if lanes.last() != Some(&p.lane) {
            lanes.push(p.lane);
        }
    }
    let pose = route.pose_at(start_s_m);
    RouteScript {
        lanes,
        length_m: route.length_m(),
        start_s_m,
        start: pose.pos,
        start_heading_rad: pose.heading_rad,
    }
}

/// The ego's speed while easing off for a waiting pedestrian, as the planner estimates it when placing crossers,
/// m/s (within the default courtesy speeds; the simulation decides the real speed).
const COURTESY_SPEED_ESTIMATE_MPS: f64 = 2.5;
/// The distance the ego covers while easing off from its cruising speed, as the planner estimates it, metres.
const EGO_BRAKING_ESTIMATE_M: f64 = 10.0;

/// A crosser's sidewalk is at most this far to the side of the ego's route, metres: farther (across a junction,
/// beside a wide road) the ego's camera loses it before it crosses.
const MAX_CROSSER_LATERAL_M: f64 = 12.0;

/// Ego routes tried before a clip is declared infeasible.
const ROUTE_ATTEMPTS: usize = 8;
/// Mid-road jaywalkers start at most this far ahead of the ego, metres: they cross at once, and farther away
/// their whole crossing would be too small in the image to be annotated.
const MIDROAD_MAX_AHEAD_M: f64 = 30.0;
/// A crosser placed at a signalised crosswalk stands this far before the route's entry into the junction
/// along the route, metres: the middle of the crosswalk at the road's mouth (0.5 to 3.5 m from its end).
const SIGNALISED_CROSSWALK_BEFORE_ENTRY_M: f64 = 2.0;
/// How far from the curb a crosser starts, metres.
pub const CURB_STANDOFF_M: f64 = 0.3;
/// Minimum distance between two pedestrians' spawn and curb points, metres (beyond the avoidance radius, so that
/// two waiting pedestrians do not push each other away from their spots).
const PED_SPACING_M: f64 = 1.2;
/// Attempts to place one pedestrian before the clip is declared infeasible.
const PLACEMENT_ATTEMPTS: usize = 60;

#[allow(clippy::too_many_arguments)]
fn plan_pedestrians(
    spec: &Spec,
    net: &RoadNetwork,
    route: &Route,
    peds: &[PedAlloc],
    first_ped: usize,
    archetype_names: &[&String],
    duration_s: f64,
    clip_seed: u64,
    rng: &mut ChaCha20Rng,
) -> Result<Vec<PedestrianScript>, String> {
    let p = &spec.pedestrians;
    let c = &spec.crossing;
    let spawn_ahead = c.layers.crosser_allocation.spawn_ahead_m;
    let far_m = spec.annotations.visibility.max_distance_m.min(route.length_m() - 1.0);
    let mut scripts: Vec<PedestrianScript> = Vec::with_capacity(peds.len());
    let mut crosser_side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
    // Traffic lights: the route's signalised junction entries and a stream of their own for the draws (none when
    // lights do not run, so that turning them on shifts no other draw but the placements it changes).
    let mut signal_draws = spec.traffic.signals.enabled.then(|| {
        (
            seeds::clip_rng(clip_seed, "plan/signals"),
            crate::world::signals::signalised_entries(net, route),
        )
    });
    // Group ids are numbered by leader, in pedestrian order.
    let mut leaders: Vec<u32> = peds.iter().filter_map(|a| a.group).collect();
    leaders.sort_unstable();
    leaders.dedup();

    for (i, alloc) in peds.iter().enumerate() {
        let id = i as u32;
        let name = archetype_names
            .get(alloc.archetype as usize)
            .map_or("casual_person", |s| s.as_str());
        let a = p.archetypes.get(name).cloned().unwrap_or_default();
        let base_speed_mps = draw(rng, a.speed_mps);
        let hesitation_s = draw(rng, a.hesitation_s);
        let ttc_threshold_s = draw(rng, a.ttc_threshold_s);
        let safety_margin_s = draw(rng, c.gap_acceptance.safety_margin_s);
        let patience_s = draw(rng, a.patience_s);
        let distracted_at_s = if alloc.speed_profile == SpeedProfile::Distracted {
            Some(0.0)
        } else if rng.random_bool(a.distraction_probability.clamp(0.0, 1.0)) {
            Some(rng.random_range(0.0..duration_s.max(0.1)))
        } else {
            None
        };
        let group = alloc.group.map(|leader| GroupRef {
            group_id: leaders.iter().position(|&l| l == leader).unwrap_or(0) as u32,
            leader: (leader as usize - first_ped) as u32,
        });
        let role = if alloc.source == CrosserSource::None {
            Role::NonCrosser
        } else {
            Role::Crosser
        };

        // The timeline: crossers that start on a sidewalk are in view for a planned time before stepping out;
        // hard negatives wait at the curb for a planned time.
        let timeline = &c.timeline;
        let in_view_before_crossing_s = (role == Role::Crosser && alloc.behaviour != Behaviour::MidroadJaywalker)
            .then(|| draw(rng, timeline.in_view_before_crossing_s));
        let curb_wait_s =
            (alloc.behaviour == Behaviour::HardNegative).then(|| draw(rng, c.hard_negatives.wait_at_curb_s));

        // Placement.
        let leader = group
            .filter(|g| g.leader != id)
            .and_then(|g| scripts.get(g.leader as usize));
        let placed = if let Some(leader) = leader {
            place_follower(net, leader, &scripts, rng)
        } else {
            match (role, alloc.behaviour) {
                (Role::Crosser, Behaviour::MidroadJaywalker) => place_midroad(
                    net,
                    route,
                    crate::spec::types::Range(
                        spawn_ahead.min(),
                        spawn_ahead.max().min(MIDROAD_MAX_AHEAD_M).max(spawn_ahead.min()),
                    ),
                    c.layers.midroad_jaywalkers.lateral_offset_m,
                    &scripts,
                    rng,
                ),
                (Role::Crosser, _) | (_, Behaviour::HardNegative) => {
                    // Allocated and baseline crossers, and hard negatives, start within the spawn range ahead of
                    // the ego, far enough that the ego (easing off for them) cannot pass before their time in
                    // view is up.
                    let (lo, hi) = crosser_spawn_range(spec, route, in_view_before_crossing_s.unwrap_or(0.0));
                    let approach_m = draw(rng, timeline.approach_m);
                    // Where lights run, a share of them waits at a signalised crosswalk on the ego's route (the
                    // first one in range), across the ego's approach road at the junction's mouth.
                    let at_signal = signal_draws.as_mut().and_then(|(sig_rng, entries)| {
                        if !sig_rng.random_bool(spec.traffic.signals.crosswalk_share.clamp(0.0, 1.0)) {
                            return None;
                        }
                        let s = entries
                            .iter()
                            .map(|&(s, _)| s - SIGNALISED_CROSSWALK_BEFORE_ENTRY_M)
                            .find(|&s| s >= spawn_ahead.min() && s <= far_m)?;
                        place_crosser(net, route, s, s, crosser_side, approach_m, &scripts, rng)
                    });
                    let placed = at_signal
                        .or_else(|| place_crosser(net, route, lo, hi, crosser_side, approach_m, &scripts, rng));
                    crosser_side = if crosser_side == Side::Left {
                        Side::Right
                    } else {
                        Side::Left
                    };
                    placed
                }
                // Walkers too start within the spawn range, so that the camera sees them about as long as crossers
                // (the benchmark protocol counts a track only when it is long enough).
                (Role::NonCrosser, _) => place_sidewalk(net, route, spawn_ahead.min(), far_m, &scripts, rng),
            }
        };
        let (spawn, heading, ahead, crossing, place) = placed.ok_or_else(|| {
            format!(
                "cannot place pedestrian {id} ({}, {}) on a {} near the ego's route",
                name,
                alloc.behaviour.name(),
                if alloc.behaviour == Behaviour::MidroadJaywalker {
                    "driving lane"
                } else {
                    "sidewalk"
                }
            )
        })?;
        let keeps_crossing = role == Role::Crosser || alloc.behaviour == Behaviour::HardNegative;
        let crossing = if keeps_crossing { crossing } else { None };
        if keeps_crossing && crossing.is_none() {
            return Err(format!("pedestrian {id} is a crosser but has no road to cross"));
        }
        let (identity, child) = identity::identities(clip_seed, id, name, a.body);
        scripts.push(PedestrianScript {
            id,
            archetype: name.to_owned(),
            body: a.body,
            base_speed_mps,
            hesitation_s,
            attention: a.attention,
            ttc_threshold_s,
            safety_margin_s,
            patience_s,
            distracted_at_s,
            role,
            crosser_source: alloc.source,
            behaviour: alloc.behaviour,
            group,
            speed_profile: alloc.speed_profile,
            spawn_place: place,
            spawn,
            spawn_heading_rad: heading,
            ahead_of_ego_m: ahead,
            crossing,
            in_view_before_crossing_s,
            curb_wait_s,
            identity,
            child,
            // A group crosses with its leader: followers share the leader's choice.
            red_light_violator: match leader {
                Some(l) => l.red_light_violator,
                None => signal_draws
                    .as_mut()
                    .is_some_and(|(sig_rng, _)| sig_rng.random_bool(a.red_light_violation_probability.clamp(0.0, 1.0))),
            },
        });
    }
    Ok(scripts)
}

type Placement = (DVec2, f64, f64, Option<CrossingScript>, SpawnPlace);

/// Where along the ego's route (arc length from its start, metres) a crosser starting on a sidewalk is placed:
/// within layer 1's spawn range and the visibility gate's distance, and far enough that the ego, easing off for
/// it, cannot pass before its `in_view_s` is up.
fn crosser_spawn_range(spec: &Spec, route: &Route, in_view_s: f64) -> (f64, f64) {
    let c = &spec.crossing;
    let spawn_ahead = c.layers.crosser_allocation.spawn_ahead_m;
    let far_m = spec.annotations.visibility.max_distance_m.min(route.length_m() - 1.0);
    let (lo, hi) = (spawn_ahead.min(), spawn_ahead.max().min(far_m));
    let lo =
        (c.decision_window_m.min() + EGO_BRAKING_ESTIMATE_M + COURTESY_SPEED_ESTIMATE_MPS * in_view_s).clamp(lo, hi);
    (lo, hi)
}

fn draw(rng: &mut ChaCha20Rng, r: crate::spec::types::Range) -> f64 {
    if r.max() > r.min() {
        rng.random_range(r.min()..=r.max())
    } else {
        r.min()
    }
}

/// Whether `p` is at least [`PED_SPACING_M`] from every earlier pedestrian's spawn point and curb point (two
/// pedestrians bound for the same spot would block each other there).
fn far_from_others(p: DVec2, scripts: &[PedestrianScript]) -> bool {
    scripts.iter().all(|s| {
        s.spawn.distance(p) >= PED_SPACING_M
            && s.crossing
                .as_ref()
                .is_none_or(|c| (c.near_curb - c.direction * CURB_STANDOFF_M).distance(p) >= PED_SPACING_M)
    })
}

fn crossing_script(c: &crate::world::Crossing) -> CrossingScript {
    CrossingScript {
        near_curb: c.near_curb,
        far_curb: c.far_curb,
        end: c.end,
        direction: c.direction,
        carriageway_width_m: c.carriageway_width_m,
    }
}

fn is_lane(net: &RoadNetwork, p: DVec2, kind: LaneType) -> bool {
    net.lane_at(p).is_some_and(|h| h.lane_type == kind)
}

#[allow(clippy::too_many_arguments)]
fn place_crosser(
    net: &RoadNetwork,
    route: &Route,
    lo: f64,
    hi: f64,
    side: Side,
    approach_m: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for attempt in 0..PLACEMENT_ATTEMPTS {
        let s = if hi > lo { rng.random_range(lo..hi) } else { lo };
        let side = if attempt % 2 == 0 {
            side
        } else if side == Side::Left {
            Side::Right
        } else {
            Side::Left
        };
        let Some(sample) = net.sidewalk_beside(route, s, side) else {
            continue;
        };
        if !far_from_others(sample.pos, scripts)
            || !is_lane(net, sample.pos, LaneType::Sidewalk)
            || sample.pos.distance(route.pose_at(s).pos) > MAX_CROSSER_LATERAL_M
        {
            continue;
        }
        let Some(crossing) = net.crossing_at(sample.pos) else {
            continue;
        };
        if crossing.carriageway_width_m < 2.0 {
            continue;
        }
        // The curb point, facing the road (if that spot is free sidewalk); the pedestrian starts up to
        // `approach_m` along the curb from it and walks there.
        let heading = crossing.direction.to_angle();
        let at_curb = crossing.near_curb - crossing.direction * CURB_STANDOFF_M;
        let free = is_lane(net, at_curb, LaneType::Sidewalk) && far_from_others(at_curb, scripts);
        if !free {
            return Some((
                sample.pos,
                heading,
                s,
                Some(crossing_script(&crossing)),
                SpawnPlace::Sidewalk,
            ));
        }
        let first = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let (spawn, spawn_heading) =
            approach_start(net, at_curb, crossing.direction.perp(), approach_m, first, scripts)
                .unwrap_or((at_curb, heading));
        return Some((
            spawn,
            spawn_heading,
            s,
            Some(crossing_script(&crossing)),
            SpawnPlace::Sidewalk,
        ));
    }
    None
}

/// Where a pedestrian bound for `curb` starts when it walks `approach_m` along the curb (direction `along`,
/// trying `first` then the other way, then half the distance): the start and its heading, if the whole walk is
/// on free sidewalk.
fn approach_start(
    net: &RoadNetwork,
    curb: DVec2,
    along: DVec2,
    approach_m: f64,
    first: f64,
    scripts: &[PedestrianScript],
) -> Option<(DVec2, f64)> {
    if approach_m < 0.5 {
        return None;
    }
    for distance in [approach_m, 0.5 * approach_m] {
        for sign in [first, -first] {
            let start = curb + along * (sign * distance);
            let steps = distance.ceil() as usize;
            let on_sidewalk = (1..=steps).all(|k| {
                let p = curb + along * (sign * distance * k as f64 / steps as f64);
                is_lane(net, p, LaneType::Sidewalk)
            });
            if on_sidewalk && far_from_others(start, scripts) {
                return Some((start, (curb - start).to_angle()));
            }
        }
    }
    None
}

fn place_sidewalk(
    net: &RoadNetwork,
    route: &Route,
    lo: f64,
    hi: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for _ in 0..PLACEMENT_ATTEMPTS {
        let s = if hi > lo { rng.random_range(lo..hi) } else { lo };
        let side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
        let Some(sample) = net.sidewalk_beside(route, s, side) else {
            continue;
        };
        if !far_from_others(sample.pos, scripts) || !is_lane(net, sample.pos, LaneType::Sidewalk) {
            continue;
        }
        let along = route.pose_at(s).heading_rad;
        let heading = if rng.random_bool(0.5) {
            along
        } else {
            wrap_angle(along + PI)
        };
        // Non-crossers never cross: no crossing vector (the costliest query) is computed for them.
        let crossing = None;
        return Some((sample.pos, heading, s, crossing, SpawnPlace::Sidewalk));
    }
    None
}

fn place_midroad(
    net: &RoadNetwork,
    route: &Route,
    ahead: crate::spec::types::Range,
    lateral_m: f64,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    for _ in 0..PLACEMENT_ATTEMPTS {
        let s = rng.random_range(ahead.min()..=ahead.max()).min(route.length_m() - 1.0);
        let origin_side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
        let Some(sample) = net.sidewalk_beside(route, s, origin_side) else {
            continue;
        };
        let Some(crossing) = net.crossing_at(sample.pos) else {
            continue;
        };
        if crossing.carriageway_width_m < 2.0 {
            continue;
        }
        // Spawn in a driving lane at the ego lane's centre ± the lateral offset, on the crossing line.
        let pose = route.pose_at(s);
        let target = pose.pos + crossing.direction * rng.random_range(-lateral_m..=lateral_m);
        let t = (target - crossing.near_curb)
            .dot(crossing.direction)
            .clamp(0.5, crossing.carriageway_width_m - 0.5);
        let spawn = crossing.near_curb + crossing.direction * t;
        if !is_lane(net, spawn, LaneType::Driving) || !far_from_others(spawn, scripts) {
            continue;
        }
        return Some((
            spawn,
            crossing.direction.to_angle(),
            s,
            Some(crossing_script(&crossing)),
            SpawnPlace::DrivingLane,
        ));
    }
    None
}

fn place_follower(
    net: &RoadNetwork,
    leader: &PedestrianScript,
    scripts: &[PedestrianScript],
    rng: &mut ChaCha20Rng,
) -> Option<Placement> {
    // Beside the leader along the curb (the leader's crossing line, shifted), walking with it.
    let along = leader
        .crossing
        .as_ref()
        .map_or(DVec2::from_angle(leader.spawn_heading_rad).perp(), |c| {
            c.direction.perp()
        });
    for _ in 0..PLACEMENT_ATTEMPTS {
        let offset = rng.random_range(PED_SPACING_M..2.5) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let shift = along * offset;
        let p = leader.spawn + shift;
        let kind = if leader.spawn_place == SpawnPlace::DrivingLane {
            LaneType::Driving
        } else {
            LaneType::Sidewalk
        };
        if !is_lane(net, p, kind) || !far_from_others(p, scripts) {
            continue;
        }
        let crossing = leader.crossing.clone().map(|c| CrossingScript {
            near_curb: c.near_curb + shift,
            far_curb: c.far_curb + shift,
            end: c.end + shift,
            ..c
        });
        if crossing.as_ref().is_none_or(|c| {
            kind == LaneType::Sidewalk
                && !(is_lane(net, c.near_curb - c.direction * CURB_STANDOFF_M, LaneType::Sidewalk)
                    && is_lane(net, c.end, LaneType::Sidewalk))
        }) {
            continue;
        }
        return Some((
            p,
            leader.spawn_heading_rad,
            leader.ahead_of_ego_m,
            crossing,
            leader.spawn_place,
        ));
    }
    None
}

/// Minimum distance between vehicle spawns, metres.
const VEHICLE_SPACING_M: f64 = 10.0;

fn plan_vehicles(
    spec: &Spec,
    town: &TownContext,
    ego_route: &Route,
    peds: &[PedestrianScript],
    profiles: &[DrivingProfileKind],
    needed_m: f64,
    rng: &mut ChaCha20Rng,
) -> Result<Vec<VehicleScript>, String> {
    let net = &town.network;
    let ego_start = ego_route.points[0].pos;
    // Candidates within 150 m of the ego start, away from it and from pedestrians on the road.
    let candidates: Vec<&SpawnPoint> = town
        .spawn_points
        .iter()
        .filter(|sp| {
            let d = sp.pos.distance(ego_start);
            d > VEHICLE_SPACING_M && d < 150.0 && clear_of_road_pedestrians(sp, peds)
        })
        .collect();
    let mut out: Vec<VehicleScript> = Vec::with_capacity(profiles.len());
    let mut taken: Vec<DVec2> = vec![ego_start];
    for (i, &kind) in profiles.iter().enumerate() {
        let p = match kind {
            DrivingProfileKind::Aggressive => &spec.traffic.profiles.aggressive,
            DrivingProfileKind::Normal => &spec.traffic.profiles.normal,
            DrivingProfileKind::Cautious => &spec.traffic.profiles.cautious,
        };
        let draw = |rng: &mut ChaCha20Rng, r: crate::spec::types::Range| {
            if r.max() > r.min() {
                rng.random_range(r.min()..=r.max())
            } else {
                r.min()
            }
        };
        let mut placed = None;
        for _ in 0..PLACEMENT_ATTEMPTS {
            if candidates.is_empty() {
                break;
            }
            let sp = candidates[rng.random_range(0..candidates.len())];
            if taken.iter().any(|t| t.distance(sp.pos) < VEHICLE_SPACING_M) {
                continue;
            }
            let Some(script) = route_from_spawn(net, sp, needed_m, rng) else {
                continue;
            };
            placed = Some((script.start, script));
            break;
        }
        let Some((pos, route)) = placed else {
            return Err(format!(
                "cannot place vehicle {i} on a free driving lane within 150 m of the ego"
            ));
        };
        taken.push(pos);
        out.push(VehicleScript {
            id: i as u32,
            profile: kind,
            speed_difference_pct: draw(rng, p.speed_difference_pct),
            min_gap_m: draw(rng, p.min_gap_m),
            time_headway_s: draw(rng, p.time_headway_s),
            ignores_lights: rng.random_bool(p.ignore_lights_probability.clamp(0.0, 1.0)),
            ignores_walkers: rng.random_bool(p.ignore_walkers_probability.clamp(0.0, 1.0)),
            route,
            emergency: None,
        });
    }
    Ok(out)
}

/// Whether a vehicle may spawn at `sp`: no pedestrian starts on the road within 15 m of it.
fn clear_of_road_pedestrians(sp: &SpawnPoint, peds: &[PedestrianScript]) -> bool {
    peds.iter()
        .all(|p| p.spawn_place != SpawnPlace::DrivingLane || p.spawn.distance(sp.pos) > 15.0)
}

/// A route from a spawn point: a lane walk of `needed_m` beyond it, not a polyline (the executor builds the
/// polyline, so planning 10k clips stays fast).
fn route_from_spawn(net: &RoadNetwork, sp: &SpawnPoint, needed_m: f64, rng: &mut ChaCha20Rng) -> Option<RouteScript> {
    let lanes = net.lane_walk(sp.lane, needed_m + sp.lane_s_m, rng)?;
    let length_m = lanes.iter().map(|&l| net.lanes[l as usize].length_m).sum();
    Some(RouteScript {
        lanes,
        length_m,
        start_s_m: sp.lane_s_m,
        start: sp.pos,
        start_heading_rad: sp.heading_rad,
    })
}

/// The clip's emergency vehicle: on a driving lane 40–150 m ahead of the ego's start heading towards it
/// (oncoming) where the town has one, else anywhere 20–150 m away; clear of the other vehicles and of
/// pedestrians on the road; from its own stream.
#[allow(clippy::too_many_arguments)]
fn plan_emergency(
    spec: &Spec,
    town: &TownContext,
    ego_route: &RouteScript,
    peds: &[PedestrianScript],
    vehicles: &[VehicleScript],
    kind: EmergencyKind,
    needed_m: f64,
    clip_seed: u64,
) -> Result<VehicleScript, String> {
    let net = &town.network;
    let mut rng = seeds::clip_rng(clip_seed, "emergency");
    let ego_start = ego_route.start;
    let ego_dir = DVec2::from_angle(ego_route.start_heading_rad);
    let free = |sp: &&SpawnPoint| {
        clear_of_road_pedestrians(sp, peds)
            && vehicles
                .iter()
                .all(|v| v.route.start.distance(sp.pos) >= VEHICLE_SPACING_M)
    };
    let oncoming: Vec<&SpawnPoint> = town
        .spawn_points
        .iter()
        .filter(|sp| {
            let d = sp.pos - ego_start;
            (40.0..150.0).contains(&d.length())
                && d.dot(ego_dir) > 0.7 * d.length()
                && DVec2::from_angle(sp.heading_rad).dot(ego_dir) < -0.7
        })
        .filter(free)
        .collect();
    let any: Vec<&SpawnPoint> = town
        .spawn_points
        .iter()
        .filter(|sp| (20.0..150.0).contains(&sp.pos.distance(ego_start)))
        .filter(free)
        .collect();
    for candidates in [oncoming, any] {
        for _ in 0..PLACEMENT_ATTEMPTS.min(candidates.len().max(1) * 2) {
            if candidates.is_empty() {
                break;
            }
            let sp = candidates[rng.random_range(0..candidates.len())];
            let Some(route) = route_from_spawn(net, sp, needed_m, &mut rng) else {
                continue;
            };
            return Ok(VehicleScript {
                id: vehicles.len() as u32,
                profile: DrivingProfileKind::Aggressive,
                speed_difference_pct: -spec.traffic.emergency.speed_above_limit_pct,
                min_gap_m: 2.0,
                time_headway_s: 1.0,
                ignores_lights: true,
                ignores_walkers: false,
                route,
                emergency: Some(kind),
            });
        }
    }
    Err("cannot place the emergency vehicle on a free driving lane within 150 m of the ego".to_owned())
}

/// Bicycle frame colours (sRGB).
const BIKE_COLOURS: [[u8; 3]; 8] = [
    [200, 30, 30],
    [20, 20, 22],
    [230, 230, 225],
    [30, 80, 170],
    [40, 130, 60],
    [240, 170, 20],
    [120, 120, 125],
    [0, 150, 160],
];
/// Cyclists start at least this far from the ego and from every vehicle's start, metres.
const CYCLIST_SPACING_M: f64 = 8.0;

/// A vehicle starting within this distance behind a cyclist in its lane could not stop for it, metres (from
/// 60 km/h at 8 m/s² with a second's reaction, plus the lengths).
const CYCLIST_CLEAR_BEHIND_M: f64 = 40.0;

/// Whether a vehicle starting at `route`'s start would come up behind a cyclist starting at `sp` in the same
/// lane within [`CYCLIST_CLEAR_BEHIND_M`].
fn closing_from_behind(route: &RouteScript, sp: &SpawnPoint) -> bool {
    let dir = DVec2::from_angle(route.start_heading_rad);
    let d = sp.pos - route.start;
    let along = d.dot(dir);
    along > 0.0
        && along < CYCLIST_CLEAR_BEHIND_M
        && d.dot(dir.perp()).abs() < 2.5
        && DVec2::from_angle(sp.heading_rad).dot(dir) > 0.7
}

/// The clip's cyclists (`traffic.cyclists.per_clip`), all from the stream `cyclists` (and their riders' looks
/// from `cyclist/<id>/identity`), so that adding cyclists changes no other draw of the plan. Every other one
/// starts ahead of the ego in its direction (15–80 m: the ego catches up and overtakes it), the others anywhere
/// 15–120 m away; clear of the vehicles' starts and of pedestrians on the road. A cyclist that finds no free
/// lane is left out (cyclists are optional scenery; `pedsynth stats` counts those placed).
fn plan_cyclists(
    spec: &Spec,
    town: &TownContext,
    ego_route: &RouteScript,
    peds: &[PedestrianScript],
    vehicles: &[VehicleScript],
    needed_m: f64,
    clip_seed: u64,
) -> Vec<CyclistScript> {
    let c = &spec.traffic.cyclists;
    if c.per_clip.max() == 0 {
        return Vec::new();
    }
    let net = &town.network;
    let mut rng = seeds::clip_rng(clip_seed, "cyclists");
    let count = rng.random_range(c.per_clip.min()..=c.per_clip.max().max(c.per_clip.min()));
    let ego_start = ego_route.start;
    let ego_dir = DVec2::from_angle(ego_route.start_heading_rad);
    let mut taken: Vec<DVec2> = vehicles.iter().map(|v| v.route.start).collect();
    taken.push(ego_start);
    let mut out = Vec::with_capacity(count as usize);
    for k in 0..count {
        let candidates_for = |same_way: bool, taken: &[DVec2]| -> Vec<&SpawnPoint> {
            town.spawn_points
                .iter()
                .filter(|sp| {
                    let d = sp.pos - ego_start;
                    let ahead =
                        d.dot(ego_dir) > 0.7 * d.length() && DVec2::from_angle(sp.heading_rad).dot(ego_dir) > 0.7;
                    let range = if same_way { 15.0..80.0 } else { 15.0..120.0 };
                    range.contains(&d.length())
                        && (!same_way || ahead)
                        && clear_of_road_pedestrians(sp, peds)
                        && taken.iter().all(|t| t.distance(sp.pos) >= CYCLIST_SPACING_M)
                        && !vehicles.iter().any(|v| closing_from_behind(&v.route, sp))
                })
                .collect()
        };
        let mut candidates = if k % 2 == 0 {
            candidates_for(true, &taken)
        } else {
            Vec::new()
        };
        if candidates.is_empty() {
            candidates = candidates_for(false, &taken);
        }
        for _ in 0..PLACEMENT_ATTEMPTS.min(candidates.len() * 2) {
            let sp = candidates[rng.random_range(0..candidates.len())];
            let Some(route) = route_from_spawn(net, sp, needed_m, &mut rng) else {
                continue;
            };
            taken.push(sp.pos);
            let id = out.len() as u32;
            out.push(CyclistScript {
                id,
                route,
                speed_mps: draw(&mut rng, c.speed_mps),
                edge_offset_m: c.edge_offset_m,
                ignores_lights: rng.random_bool(c.ignore_lights_probability.clamp(0.0, 1.0)),
                rider: identity::rider_identity(clip_seed, id),
                bike_rgb: BIKE_COLOURS[rng.random_range(0..BIKE_COLOURS.len())],
            });
            break;
        }
    }
    out
}

fn wrap_angle(a: f64) -> f64 {
    let mut a = a % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a <= -PI {
        a += 2.0 * PI;
    }
    a
}
