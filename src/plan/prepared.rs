//! A plan prepared for generation: its header and the plan's hash, with the clips' scripts compiled again one
//! at a time when a worker needs them ([`LazyPlan`]). Preparing compiles every clip once (which checks that each
//! can be planned) and streams its JSON into the plan's hash, so nothing held while a dataset is generated grows
//! with the number of clips: which clip an index is ([`PreparedPlan::clip`]) is arithmetic on the spec.
//!
//! Pure: hashing is arithmetic on the plan's JSON, which is never held whole.

use std::collections::BTreeMap;

use serde::Serialize;

use super::{ClipRef, ClipScript, LazyPlan, Plan, PlanProblem, TownContext};
use crate::util::stream_json::Streamed;

/// A plan ready to generate: see the module documentation.
pub struct PreparedPlan {
    /// The plan and its scripts.
    lazy: LazyPlan,
    /// blake3 of the plan's JSON without `spec_dir` ([`plan_hash`]).
    pub plan_hash: String,
}

impl PreparedPlan {
    /// Prepares `lazy`: compiles each clip once, hashing its JSON. Fails with every clip that cannot be planned
    /// (a town that was not loaded counts once).
    pub fn new(lazy: LazyPlan, towns: &BTreeMap<String, TownContext>) -> Result<PreparedPlan, Vec<PlanProblem>> {
        let mut problems = Vec::new();
        let scripts = (0..lazy.len()).filter_map(|i| match lazy.script(i, towns) {
            Ok(script) => Some(Ok::<_, std::convert::Infallible>(script)),
            Err(p) => {
                problems.push(p);
                None
            }
        });
        // The hash is wrong when a clip is missing, and then not used.
        let hashed = hash_plan(lazy.header(), &Streamed::new(scripts, lazy.len()));
        problems.dedup();
        if !problems.is_empty() {
            return Err(problems);
        }
        let plan_hash = hashed.map_err(|e| {
            vec![PlanProblem {
                clip_id: "*".to_owned(),
                reason: format!("cannot serialise the plan: {e}"),
            }]
        })?;
        Ok(PreparedPlan { lazy, plan_hash })
    }

    /// A plan whose scripts are all held (tests, a plan file).
    pub fn from_plan(plan: Plan) -> Result<PreparedPlan, Vec<PlanProblem>> {
        PreparedPlan::new(LazyPlan::from_plan(plan), &BTreeMap::new())
    }

    /// The plan without its clips (`clips` is empty: see [`PreparedPlan::clip`] and [`PreparedPlan::script`]).
    pub fn header(&self) -> &Plan {
        self.lazy.header()
    }

    /// The number of clips.
    pub fn len(&self) -> usize {
        self.lazy.len()
    }

    /// Whether the plan has no clip.
    pub fn is_empty(&self) -> bool {
        self.lazy.is_empty()
    }

    /// Which clip plan index `i` is (id, town, split), without compiling it.
    pub fn clip(&self, i: usize) -> Option<ClipRef<'_>> {
        self.lazy.clip(i)
    }

    /// Every clip in plan order ([`PreparedPlan::clip`]), made one at a time.
    pub fn clips(&self) -> impl Iterator<Item = ClipRef<'_>> + '_ {
        (0..self.len()).filter_map(|i| self.clip(i))
    }

    /// The script of clip `i` (plan order).
    pub fn script<'a>(
        &'a self,
        i: usize,
        towns: &BTreeMap<String, TownContext>,
    ) -> Result<std::borrow::Cow<'a, ClipScript>, PlanProblem> {
        self.lazy.script(i, towns)
    }
}

/// blake3 of a plan's canonical JSON, without `spec_dir`: where the spec file lies (and how its path was
/// spelled) does not change the dataset, so the same spec run from another directory, or its
/// `spec.resolved.yaml`, resumes the same dataset and writes the same manifest.
pub fn plan_hash(plan: &Plan) -> Result<String, serde_json::Error> {
    hash_plan(plan, &plan.clips)
}

/// [`plan_hash`] of the plan `header` with the clips `clips` (its own `clips` are not read): the JSON is
/// streamed into the hasher, never held (a 6,000-clip plan is tens of megabytes).
fn hash_plan<C: Serialize>(header: &Plan, clips: &C) -> Result<String, serde_json::Error> {
    // The plan's fields by reference, `spec_dir` blanked. The test below holds this mirror equal to the JSON
    // of a clone with an empty `spec_dir`, field for field.
    #[derive(Serialize)]
    struct Hashed<'a, C> {
        format_version: u32,
        pedsynth_version: &'a str,
        dataset: &'a str,
        seed: u64,
        spec_hash: &'a str,
        target_crossing_ratio: f64,
        sim: &'a super::SimParams,
        spec: &'a crate::spec::Spec,
        spec_dir: &'a str,
        towns: &'a BTreeMap<String, String>,
        clips: &'a C,
    }
    let hashed = Hashed {
        format_version: header.format_version,
        pedsynth_version: &header.pedsynth_version,
        dataset: &header.dataset,
        seed: header.seed,
        spec_hash: &header.spec_hash,
        target_crossing_ratio: header.target_crossing_ratio,
        sim: &header.sim,
        spec: &header.spec,
        spec_dir: "",
        towns: &header.towns,
        clips,
    };
    let mut hasher = blake3::Hasher::new();
    serde_json::to_writer(&mut hasher, &hashed)?;
    Ok(hasher.finalize().to_hex().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in towns a shipped spec names (the loading of OpenDRIVE towns is `dataset::inputs`' IO).
    fn builtin_towns(spec: &crate::spec::Spec) -> BTreeMap<String, TownContext> {
        let town = |name: &str| crate::world::RoadNetwork::builtin(name).expect("a built-in town");
        spec.dataset
            .towns
            .iter()
            .map(|t| (t.name().to_owned(), TownContext::new(town(t.name()))))
            .collect()
    }

    fn quickstart() -> (crate::spec::LoadedSpec, BTreeMap<String, TownContext>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
        let loaded = crate::spec::load_file(&path, &Default::default()).expect("quickstart");
        let towns = builtin_towns(&loaded.spec);
        (loaded, towns)
    }

    #[test]
    fn plan_hash_is_the_hash_of_the_plans_json_without_its_spec_dir() {
        let (loaded, towns) = quickstart();
        let hash = loaded.hash().expect("spec hash");
        let plan = super::super::plan(&loaded.spec, &hash, "specs", &towns, None).expect("quickstart");
        let mut blank = plan.clone();
        blank.spec_dir = String::new();
        let json = serde_json::to_string(&blank).expect("json");
        let expected = blake3::hash(json.as_bytes()).to_hex().to_string();
        // Equal when every field of `Plan` is in `hash_plan`'s mirror, in order.
        assert_eq!(plan_hash(&plan).expect("hash"), expected);
        let mut moved = plan.clone();
        moved.spec_dir = "../elsewhere".into();
        assert_eq!(
            plan_hash(&moved).expect("hash"),
            expected,
            "where the spec lies does not matter"
        );
        moved.seed += 1;
        assert_ne!(plan_hash(&moved).expect("hash"), expected);
    }

    #[test]
    fn a_prepared_plan_compiles_the_scripts_and_the_hash_of_the_held_plan() {
        let (loaded, towns) = quickstart();
        let mut spec = loaded.spec.clone();
        spec.dataset.clips.count = 3;
        let plan = super::super::plan(&spec, "h", "dir", &towns, None).expect("plan");
        let prepared = PreparedPlan::new(LazyPlan::compile(&spec, "h", "dir", &towns), &towns).expect("prepared");
        assert_eq!(prepared.plan_hash, plan_hash(&plan).expect("hash"));
        assert_eq!(prepared.len(), plan.clips.len());
        assert!(prepared.header().clips.is_empty());
        for (i, script) in plan.clips.iter().enumerate() {
            let clip = prepared.clip(i).expect("clip");
            assert_eq!(
                (&*clip.clip_id, clip.town, clip.split),
                (script.clip_id.as_str(), script.town.as_str(), script.split)
            );
            assert_eq!(&*prepared.script(i, &towns).expect("script"), script, "clip {i}");
        }
        assert_eq!(prepared.clip(plan.clips.len()), None);
        let held = PreparedPlan::from_plan(plan.clone()).expect("held");
        assert_eq!(held.plan_hash, prepared.plan_hash);
        assert!(held.clips().eq(prepared.clips()));
        assert_eq!(&*held.script(1, &BTreeMap::new()).expect("held script"), &plan.clips[1]);
    }

    #[test]
    fn scripts_asked_for_in_any_order_across_more_strata_than_are_cached_equal_the_plans() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/pedsynth_pp.yaml");
        let loaded = crate::spec::load_file(&path, &Default::default()).expect("spec");
        let towns = builtin_towns(&loaded.spec);
        let mut spec = loaded.spec.clone();
        spec.dataset.clips.count = 1;
        spec.dataset.clips.per = crate::spec::types::ClipsPer::TownAndWeather;
        let plan = super::super::plan(&spec, "h", "dir", &towns, None).expect("plan");
        let n = plan.clips.len();
        assert!(n > super::super::CACHED_STRATA, "{n} strata of one clip");
        let lazy = LazyPlan::compile(&spec, "h", "dir", &towns);
        // Strided twice round: every stratum is drawn, evicted and drawn again.
        for i in (0..2 * n).map(|k| k * 7 % n) {
            assert_eq!(&*lazy.script(i, &towns).expect("script"), &plan.clips[i], "clip {i}");
        }
    }

    #[test]
    fn a_missing_town_is_one_problem_and_no_hash() {
        let (loaded, towns) = quickstart();
        let lazy = LazyPlan::compile(&loaded.spec, "h", "dir", &towns);
        let problems = PreparedPlan::new(lazy, &BTreeMap::new()).err().expect("refused");
        assert_eq!(problems.len(), loaded.spec.dataset.towns.len(), "{problems:?}");
        assert!(problems[0].reason.contains("was not loaded"), "{problems:?}");
    }
}
