//! A plan that keeps only its strata: [`LazyPlan`] draws a stratum when a clip of it is asked for (the last
//! [`CACHED_STRATA`] strata's draws cached behind a mutex, so workers can share it) and compiles the clip's
//! script, bit for bit the script [`plan`] returns; [`LazyPlan::clip`] says which clip an index is without
//! drawing.

use super::*;

/// A compiled plan whose clip scripts are not held: each is compiled again when asked for, from the draws of
/// its stratum, which are themselves made again when needed (a few strata's draws are cached) — so `generate`
/// works through any number of clips holding nothing per clip. A plan read from a file holds its scripts
/// instead. Either way, [`LazyPlan::script`] returns the script [`plan`] would put in the plan, bit for bit.
pub struct LazyPlan {
    /// The plan without its clips (`clips` is empty).
    header: Plan,
    source: Source,
}

pub(super) enum Source {
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
pub(super) struct DrawCache(std::sync::Mutex<Vec<(usize, std::sync::Arc<StratumDraws>)>>);

/// Strata whose draws are kept: enough for every worker of a large machine to work in its own stratum
/// (workers take clips from separate parts of the plan) while holding a bounded amount.
pub(super) const CACHED_STRATA: usize = 32;

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
pub(super) struct StratumDraws {
    pub(super) basics: Vec<ClipBasics>,
    pub(super) allocs: Vec<PedAlloc>,
    /// Driving profile of each vehicle of the stratum, in clip order.
    pub(super) profiles: Vec<DrivingProfileKind>,
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
pub(super) fn split_of(spec: &Spec, town: &TownRef) -> crate::spec::types::Split {
    spec.dataset
        .splits
        .get(town.name())
        .copied()
        .unwrap_or(spec.dataset.default_split)
}
