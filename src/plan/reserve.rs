//! Planned counts of labelled crossers, and the pure script edits the executor makes to meet them.
//!
//! Not every planned crosser ends up labelled a crosser (C = 1 in an annotated frame): about one in seven waits
//! for a gap that never comes, crosses behind the camera or is hidden by its group
//! ([`crate::plan::calibration::CROSSER_REALISATION`]). Which ones fail depends on the clip (the ego beside a waiting
//! pedestrian, a queue of traffic), so failures come in clumps and a dataset-level ratio spreads by several
//! percentage points between specs. Instead, the planner gives each clip a count of labelled crossers
//! ([`labelled_targets`]) and the executor re-simulates the clip, promoting non-crossers to crossers
//! ([`promoted`]) or demoting labelled crossers to hard negatives ([`demoted`]), until the count is met.
//! Both edits are pure functions of (spec, network, clip script, pedestrian), seeded from the clip's seed and
//! the pedestrian's id, so the result is still a pure function of (plan, clip).

use super::{
    Behaviour, ClipBasics, ClipScript, CrosserSource, PedAlloc, PedestrianScript, Role, Side, SpawnPlace,
    crosser_spawn_range, draw, place_crosser, quota, seeds, stopped_ego_within,
};
use crate::spec::types::Spec;
use crate::world::{RoadNetwork, Route};
use rand::RngExt;

/// Each clip's planned count of labelled crossers: `crossing.target_ratio` of the stratum's pedestrians,
/// rounded with a dither (`floor(target × n + u)`, `u` along a seeded golden-ratio sequence over the strata in
/// plan order, so that roundings do not pile up in one direction over the dataset), shared among the stratum's
/// clips in proportion to their planned crossers (largest remainder), at most the clip's pedestrians. `None`
/// for every clip with layer 1 (crosser allocation) off: the spec then sets no count to meet.
pub(super) fn labelled_targets(
    spec: &Spec,
    stratum_index: usize,
    basics: &[ClipBasics],
    allocs: &[PedAlloc],
) -> Vec<Option<u32>> {
    let c = &spec.crossing;
    if !c.layers.crosser_allocation.enabled {
        return vec![None; basics.len()];
    }
    let n: usize = basics.iter().map(|b| b.pedestrians).sum();
    let planned: Vec<f64> = basics
        .iter()
        .map(|b| {
            allocs[b.first_pedestrian..b.first_pedestrian + b.pedestrians]
                .iter()
                .filter(|a| a.source != CrosserSource::None)
                .count() as f64
        })
        .collect();
    let offset = (seeds::seed_u64(spec.dataset.seed, "labelled_crossers/dither") >> 11) as f64 / (1u64 << 53) as f64;
    let dither = (offset + stratum_index as f64 * 0.618_033_988_749_894_9).fract();
    let wanted = ((c.target_ratio.clamp(0.0, 1.0) * n as f64 + dither).floor() as usize).min(n);
    let counts = quota::largest_remainder(wanted, &planned);
    basics
        .iter()
        .zip(counts)
        .map(|(b, k)| Some(u32::try_from(k.min(b.pedestrians)).unwrap_or(u32::MAX)))
        .collect()
}

/// Pedestrian `i` of `clip` made a crosser ([`CrosserSource::Promoted`], normal behaviour, crossing alone)
/// placed as the planner places layer 1's crossers (a crossing point beside `route`, the ego's, within the spawn
/// range and far enough for its time in view), with the draws of a stream of its own: a non-crosser, or a crosser that
/// was not labelled one, given a new crossing point (the executor picks which); `attempt` numbers the
/// pedestrian's promotions (each draws from a stream of its own). `None` for a group's leader
/// (its companions follow it) or if no free crossing point is found.
pub fn promoted(
    spec: &Spec,
    net: &RoadNetwork,
    route: &Route,
    clip: &ClipScript,
    i: usize,
    attempt: u32,
) -> Option<PedestrianScript> {
    let p = clip.pedestrians.get(i)?;
    let leads = clip
        .pedestrians
        .iter()
        .any(|q| q.id != p.id && q.group.is_some_and(|g| g.leader == p.id));
    if leads {
        return None;
    }
    let c = &spec.crossing;
    let mut rng = seeds::clip_rng(clip.seed, &format!("promote/{}/{attempt}", p.id));
    let in_view_s = draw(&mut rng, c.timeline.in_view_before_crossing_s);
    let approach_m = draw(&mut rng, c.timeline.approach_m);
    let side = if rng.random_bool(0.5) { Side::Left } else { Side::Right };
    let (lo, hi) = crosser_spawn_range(spec, route, in_view_s);
    // Placed clear of everyone else's spawn and curb points (not of its own old ones).
    let others: Vec<PedestrianScript> = clip.pedestrians.iter().filter(|q| q.id != p.id).cloned().collect();
    let (spawn, heading, ahead, crossing, place) =
        place_crosser(net, route, lo, hi, side, approach_m, &others, &mut rng)?;
    let within = c.scenario.crosser_ego_within_m;
    let step_out_ego_within_m = (within.max() > 0.0).then(|| draw(&mut rng, within));
    let step_out_stopped_ego_within_m = step_out_ego_within_m.and(stopped_ego_within(&c.scenario));
    Some(PedestrianScript {
        role: Role::Crosser,
        crosser_source: CrosserSource::Promoted,
        behaviour: Behaviour::Normal,
        spawn_place: place,
        spawn,
        spawn_heading_rad: heading,
        ahead_of_ego_m: ahead,
        crossing,
        in_view_before_crossing_s: Some(in_view_s),
        step_out_ego_within_m,
        step_out_stopped_ego_within_m,
        curb_wait_s: None,
        group: None,
        red_light_violator: false,
        ..p.clone()
    })
}

/// Pedestrian `i` of `clip`, a crosser starting on a sidewalk, made a hard negative: it walks to the same curb
/// point, stops, looks and checks the traffic, and does not cross (its wait at the curb drawn from
/// `crossing.hard_negatives.wait_at_curb_s` with a stream of its own); a group's follower leaves its group.
/// `None` for anyone else, and for a group's leader (its companions would stay with it).
pub fn demoted(spec: &Spec, clip: &ClipScript, i: usize) -> Option<PedestrianScript> {
    let p = clip.pedestrians.get(i)?;
    if p.role != Role::Crosser
        || p.group.is_some_and(|g| g.leader == p.id)
        || p.spawn_place != SpawnPlace::Sidewalk
        || p.behaviour == Behaviour::MidroadJaywalker
        || p.crossing.is_none()
    {
        return None;
    }
    let mut rng = seeds::clip_rng(clip.seed, &format!("demote/{}", p.id));
    let wait_s = draw(&mut rng, spec.crossing.hard_negatives.wait_at_curb_s);
    Some(PedestrianScript {
        role: Role::NonCrosser,
        crosser_source: CrosserSource::None,
        behaviour: Behaviour::HardNegative,
        in_view_before_crossing_s: None,
        step_out_ego_within_m: None,
        step_out_stopped_ego_within_m: None,
        curb_wait_s: Some(wait_s),
        group: None,
        red_light_violator: false,
        ..p.clone()
    })
}
