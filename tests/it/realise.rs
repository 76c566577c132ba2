//! The executor's realisation (`sensors::realise`): clips re-simulated with pedestrians promoted or demoted until
//! they have their planned count of labelled crossers. On the held-out spec (3 clips per weather, 18 clips) at
//! a middle and a crossing-heavy target: the clips meet their counts (measured on all 180 clips of the spec at
//! 14 targets, with and without traffic lights, cyclists and emergency vehicles: at most 6 miss, by 1 to 3
//! pedestrians; on these 18, none), every edit is one the documentation names, the result is the same when
//! computed again, and a spec that sets no count is simulated once.

use std::path::Path;

use pedsynth::plan::{Behaviour, CrosserSource, Role};
use pedsynth::sensors::realise::realise;
use pedsynth::sim::rig::Rig;
use pedsynth::spec::LoadOptions;

fn plan(
    overrides: &[&str],
) -> (
    pedsynth::plan::Plan,
    std::collections::BTreeMap<String, pedsynth::plan::TownContext>,
) {
    let options = LoadOptions {
        overrides: overrides
            .iter()
            .map(|s| (*s).to_owned())
            .chain(["dataset.clips.count=3".to_owned()])
            .collect(),
        allow_large: false,
        profile: None,
    };
    let (_, towns, plan) =
        pedsynth::dataset::inputs::plan_spec_file(Path::new("tests/data/specs/heldout_crossing.yaml"), &options)
            .unwrap_or_else(|e| panic!("{e}"));
    (plan, towns)
}

/// Realises every clip at `target`; returns (clips meeting their count, labelled, planned, promotions,
/// demotions).
fn check_target(target: f64) -> (usize, u32, u32, usize, usize) {
    let set = format!("crossing.target_ratio={target}");
    let (plan, towns) = plan(&[set.as_str()]);
    let rig = Rig::from_spec(&plan.spec.sensors);
    let (mut met, mut got, mut wanted, mut promoted, mut demoted) = (0, 0, 0, 0, 0);
    for clip in &plan.clips {
        let net = &towns[&clip.town].network;
        let r = realise(clip, &plan.spec, &plan.sim, &rig, net);
        let w = clip.labelled_crossers.expect("layer 1 is on: every clip has a count");
        let g = r.labelled_crossers();
        met += usize::from(g == w);
        got += g;
        wanted += w;
        assert!(r.rounds < r.simulations && r.simulations <= pedsynth::sensors::realise::MAX_ROUNDS + 1);
        assert_eq!(r.script.pedestrians.len(), clip.pedestrians.len(), "{}", clip.clip_id);
        assert_eq!(r.script.ego, clip.ego, "{}: the ego is the plan's", clip.clip_id);
        for (p, q) in clip.pedestrians.iter().zip(&r.script.pedestrians) {
            if p == q {
                continue;
            }
            let ctx = format!("{} pedestrian {}", clip.clip_id, p.id);
            assert_eq!(
                (q.id, &q.identity, &q.archetype),
                (p.id, &p.identity, &p.archetype),
                "{ctx}: same person"
            );
            match q.role {
                Role::Crosser => {
                    // Promoted: a single normal crosser with a crossing.
                    promoted += 1;
                    assert_eq!(q.crosser_source, CrosserSource::Promoted, "{ctx}");
                    assert_eq!(q.behaviour, Behaviour::Normal, "{ctx}");
                    assert!(q.group.is_none() && q.crossing.is_some(), "{ctx}");
                    assert!(q.in_view_before_crossing_s.is_some(), "{ctx}");
                }
                Role::NonCrosser => {
                    // Demoted: a crosser of the plan, now a hard negative bound for the same curb.
                    demoted += 1;
                    assert_eq!(p.role, Role::Crosser, "{ctx}: only crossers are demoted");
                    assert_eq!(q.behaviour, Behaviour::HardNegative, "{ctx}");
                    assert_eq!(q.crosser_source, CrosserSource::None, "{ctx}");
                    assert_eq!(q.crossing, p.crossing, "{ctx}: the same curb");
                    assert!(q.curb_wait_s.is_some() && q.group.is_none(), "{ctx}");
                }
            }
        }
    }
    eprintln!(
        "target {target}: {met} of {} clips meet their count; {got} labelled of {wanted} planned; {promoted} promoted, {demoted} demoted",
        plan.clips.len()
    );
    // The whole spec (180 clips) misses in at most 6 clips: in 18, allow 2.
    assert!(met + 2 >= plan.clips.len(), "{met} of {} clips", plan.clips.len());
    assert!(got.abs_diff(wanted) <= 3, "{got} labelled of {wanted} planned");
    (met, got, wanted, promoted, demoted)
}

#[test]
fn clips_meet_their_count_of_labelled_crossers_at_a_middle_target() {
    let (_, _, _, promoted, demoted) = check_target(0.5);
    // Both edits happen (measured on these 18 clips; without them a tenth of the planned crossers go unlabelled).
    assert!(promoted > 0 && demoted > 0, "{promoted} promoted, {demoted} demoted");
}

#[test]
fn clips_meet_their_count_of_labelled_crossers_at_a_crossing_heavy_target() {
    let (_, _, _, promoted, _) = check_target(0.95);
    // Almost every pedestrian is a planned crosser: the count is met by giving unlabelled ones a new crossing.
    assert!(promoted > 0);
}

#[test]
fn realising_a_clip_again_gives_the_same_script_trace_and_labels() {
    let (plan, towns) = plan(&[]);
    let rig = Rig::from_spec(&plan.spec.sensors);
    for clip in plan.clips.iter().take(4) {
        let net = &towns[&clip.town].network;
        let a = realise(clip, &plan.spec, &plan.sim, &rig, net);
        let b = realise(clip, &plan.spec, &plan.sim, &rig, net);
        assert_eq!(a.script, b.script);
        assert_eq!((a.rounds, a.simulations), (b.rounds, b.simulations));
        assert_eq!(
            serde_json::to_string(&a.trace).expect("trace"),
            serde_json::to_string(&b.trace).expect("trace")
        );
        assert_eq!(a.labelled_crossers(), b.labelled_crossers());
    }
}

#[test]
fn without_layer_1_no_count_is_set_and_each_clip_is_simulated_once() {
    let (plan, towns) = plan(&[
        "crossing.layers.crosser_allocation.enabled=false",
        "crossing.target_ratio=0.09",
    ]);
    let rig = Rig::from_spec(&plan.spec.sensors);
    for clip in plan.clips.iter().take(3) {
        assert_eq!(clip.labelled_crossers, None);
        let r = realise(clip, &plan.spec, &plan.sim, &rig, &towns[&clip.town].network);
        assert_eq!((r.rounds, r.simulations), (0, 1));
        assert!(matches!(r.script, std::borrow::Cow::Borrowed(_)));
    }
}
