//! Realisation: simulate and observe a clip, then, where its plan sets a count of labelled crossers
//! (`ClipScript::labelled_crossers`), re-simulate it with pedestrians edited by `plan::reserve` until the clip
//! has that many: short of it, non-crossers and crossers that were not labelled are promoted to crossers at a
//! new crossing point; over it, labelled crossers are demoted to hard negatives. A dataset's crossing ratio then
//! lands on its target instead of spreading with each clip's chance failures.
//!
//! Rounds are bounded ([`MAX_ROUNDS`]); each round edits as many pedestrians as the count is off by, in a fixed
//! order (to promote: non-crossers, then crossers not labelled, each by id; to demote: labelled crossers by id, a
//! promoted one restored as planned rather than demoted; a demoted or restored pedestrian is never promoted
//! again), and the round closest to the count (the earliest of equals) is kept. Everything is a pure function of
//! (plan, clip): determinism, resume and sharding hold.

use std::borrow::Cow;

use crate::plan::{ClipScript, Role, SimParams, reserve};
use crate::sensors::{self, Observations};
use crate::sim::trace::ClipTrace;
use crate::sim::{self, rig::Rig};
use crate::spec::types::Spec;
use crate::world::RoadNetwork;

/// Re-simulations at most, after the first simulation.
pub const MAX_ROUNDS: usize = 6;

/// A clip as it was simulated and observed: the script it ran (the plan's, or one with pedestrians promoted
/// or demoted), its trace and its observations.
pub struct Realised<'a> {
    /// The script the trace was simulated from (tables and sensors describe this one).
    pub script: Cow<'a, ClipScript>,
    /// The simulation.
    pub trace: ClipTrace,
    /// The annotations.
    pub observations: Observations,
    /// The round kept: 0 for the first simulation, k for the k-th re-simulation.
    pub rounds: usize,
    /// Simulations run in all (1 when the first met the count or the clip sets none).
    pub simulations: usize,
}

impl Realised<'_> {
    /// Pedestrians labelled crossers (C = 1 in an annotated frame).
    pub fn labelled_crossers(&self) -> u32 {
        labelled(&self.observations)
    }
}

fn labelled(o: &Observations) -> u32 {
    o.annotations.pedestrians.iter().filter(|p| p.crosser).count() as u32
}

/// Simulates and observes `script`, re-simulating with promoted or demoted pedestrians while its labelled
/// crossers miss its planned count (see the module documentation).
pub fn realise<'a>(script: &'a ClipScript, spec: &Spec, sim: &SimParams, rig: &Rig, net: &RoadNetwork) -> Realised<'a> {
    let run = |s: &ClipScript| {
        let trace = sim::simulate(s, sim, net);
        let observations = sensors::observe(s, &trace, spec, rig, net);
        (trace, observations)
    };
    let (trace, observations) = run(script);
    let mut best = Realised {
        script: Cow::Borrowed(script),
        trace,
        observations,
        rounds: 0,
        simulations: 1,
    };
    let Some(wanted) = script.labelled_crossers else {
        return best;
    };
    let mut best_miss = labelled(&best.observations).abs_diff(wanted);
    // Promotions of each pedestrian so far, and whether it was demoted (then it is never promoted again).
    let mut promotions = vec![0u32; script.pedestrians.len()];
    let mut demoted = vec![false; script.pedestrians.len()];
    // The last round's script and observations, where they are not the best's.
    let mut current: Option<(ClipScript, Observations)> = None;
    // The ego's route, built when a first promotion needs it (the script holds its lanes).
    let mut route: Option<Option<crate::world::Route>> = None;
    let mut simulations = 1;
    for round in 1..=MAX_ROUNDS {
        let (s, o) = match &current {
            Some((s, o)) => (s, o),
            None => (best.script.as_ref(), &best.observations),
        };
        let have = labelled(o);
        if have == wanted {
            break;
        }
        let mut next = s.clone();
        let mut left = have.abs_diff(wanted);
        let is_labelled = |i: usize| o.annotations.pedestrians.get(i).is_some_and(|a| a.crosser);
        // Candidates in order: to promote, non-crossers first, then crossers that were not labelled (a new
        // crossing point); to demote, labelled crossers.
        let order: Vec<usize> = if have < wanted {
            let n = next.pedestrians.len();
            let non_crossers = (0..n).filter(|&i| next.pedestrians[i].role == Role::NonCrosser);
            let unlabelled = (0..n).filter(|&i| next.pedestrians[i].role == Role::Crosser && !is_labelled(i));
            non_crossers.chain(unlabelled).collect()
        } else {
            (0..next.pedestrians.len())
                .filter(|&i| next.pedestrians[i].role == Role::Crosser && is_labelled(i))
                .collect()
        };
        for i in order {
            if left == 0 {
                break;
            }
            if demoted[i] {
                continue;
            }
            let edit = if have < wanted {
                let route = route.get_or_insert_with(|| net.route_through(&script.ego.route.lanes_in(net)));
                route
                    .as_ref()
                    .and_then(|route| reserve::promoted(spec, net, route, &next, i, promotions[i]))
            } else if promotions[i] > 0 {
                // A promoted pedestrian is not demoted but restored as planned.
                Some(script.pedestrians[i].clone())
            } else {
                reserve::demoted(spec, &next, i)
            };
            if let Some(p) = edit {
                next.pedestrians[i] = p;
                if have < wanted {
                    promotions[i] += 1;
                } else {
                    demoted[i] = true;
                }
                left -= 1;
            }
        }
        if left == have.abs_diff(wanted) {
            // No candidate left.
            break;
        }
        let (trace, observations) = run(&next);
        simulations += 1;
        let miss = labelled(&observations).abs_diff(wanted);
        if miss < best_miss {
            best_miss = miss;
            best = Realised {
                script: Cow::Owned(next),
                trace,
                observations,
                rounds: round,
                simulations: 0,
            };
            current = None;
        } else {
            current = Some((next, observations));
        }
    }
    best.simulations = simulations;
    best
}
