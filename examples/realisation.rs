//! Measures the crossing realisation that `src/calibration.rs` records: the share of planned crossers (layer 1)
//! that end up labelled crossers (C = 1 in at least one annotated frame), per spec.
//!
//! It then realises every clip as `generate` does (`sensors::realise`: promotions and demotions until the clip
//! has its planned count of labelled crossers) and prints the resulting crossing ratio and how many clips met
//! their count.
//!
//! Run: `cargo run --release --example realisation -- specs/balanced_50.yaml specs/pedsynth_pp.yaml [--set KEY=VALUE]...`
//!
//! With `REALISATION_WHY=1` it also prints, on stderr, one line per unlabelled allocated crosser: why (never
//! crossed, crossed only behind the camera, crossed in front unannotated), its state and distance to its curb
//! when the ego passed it (or the clip ended), how long before that it reached its curb, the states it went
//! through in the last 10 s, the ego's speed, the share of the clip the ego drove slower than 4 m/s and stood,
//! and its group's members with their distances to their curbs.

use std::path::Path;

use pedsynth::plan::{CrosserSource, Role};
use pedsynth::sensors;
use pedsynth::sim;
use pedsynth::sim::rig::Rig;
use pedsynth::spec::LoadOptions;
use pedsynth::world::LaneType;
use rayon::prelude::*;

/// One clip's town, counts (see `main`), lines on unlabelled crossers and the executor's realisation counts.
type ClipCounts<'a> = (&'a str, [usize; 13], Vec<String>, [usize; 6]);

fn main() {
    // `--set KEY=VALUE` arguments apply to every spec.
    let args: Vec<String> = std::env::args().skip(1).collect();
    let overrides: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let specs = args
        .iter()
        .enumerate()
        .filter(|(i, a)| *a != "--set" && (*i == 0 || args[i - 1] != "--set"))
        .map(|(_, a)| a.clone());
    let options = LoadOptions {
        overrides,
        allow_large: false,
        profile: None,
    };
    for spec in specs {
        let (_, towns, plan) = match pedsynth::dataset::inputs::plan_spec_file(Path::new(&spec), &options) {
            Ok(x) => x,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        // (pedestrians, allocated, allocated labelled, allocated on a driving lane, baseline, baseline labelled,
        // allocated never annotated, pedestrians never annotated, unlabelled allocated crossers that never had
        // C = 1, ... that had C = 1 only behind the camera, ... only in front of it but not annotated, allocated in
        // clips with an emergency vehicle, ... labelled)
        let why_wanted = std::env::var_os("REALISATION_WHY").is_some();
        let per_clip: Vec<ClipCounts> = plan
            .clips
            .par_iter()
            .map(|clip| {
                let net = &towns[&clip.town].network;
                let rig = Rig::for_clip(&plan.spec.sensors, clip.seed);
                let trace = sim::simulate(clip, &plan.sim, net);
                let ann = sensors::observe(clip, &trace, &plan.spec, &rig, net).annotations;
                let mut c = [0usize; 13];
                let mut why: Vec<String> = Vec::new();
                for (i, p) in clip.pedestrians.iter().enumerate() {
                    c[0] += 1;
                    let labelled = usize::from(ann.pedestrians[i].crosser);
                    let unseen = usize::from(ann.pedestrians[i].annotated_frames == 0);
                    c[7] += unseen;
                    let on_road = trace.pedestrians[i]
                        .iter()
                        .any(|f| f.state.is_crossing() && f.lane_type == Some(LaneType::Driving));
                    match (p.role, p.crosser_source) {
                        (Role::Crosser, CrosserSource::Allocated) => {
                            c[1] += 1;
                            if clip.vehicles.iter().any(|v| v.emergency.is_some()) {
                                c[11] += 1;
                                c[12] += labelled;
                            }
                            c[2] += labelled;
                            c[3] += usize::from(on_road);
                            c[6] += unseen;
                            if labelled == 0 {
                                let crossing_frames: Vec<usize> =
                                    (0..ann.crossing[i].len()).filter(|&f| ann.crossing[i][f]).collect();
                                let behind = crossing_frames
                                    .iter()
                                    .all(|&f| from_ego_m(&trace, f, trace.pedestrians[i][f].pos).x < 0.0);
                                let (slot, kind) = match (crossing_frames.is_empty(), behind) {
                                    (true, _) => (8, "never crossed"),
                                    (false, true) => (9, "crossed behind"),
                                    (false, false) => (10, "unannotated"),
                                };
                                c[slot] += 1;
                                if why_wanted {
                                    why.push(why_unlabelled(kind, clip, &trace, i));
                                }
                            }
                        }
                        (Role::Crosser, CrosserSource::Baseline) => {
                            c[4] += 1;
                            c[5] += labelled;
                        }
                        _ => {}
                    }
                }
                // The executor's realisation (`sensors::realise`): (planned labelled crossers, labelled, clips with a
                // count, clips meeting it, re-simulations, squared miss).
                let r = pedsynth::sensors::realise::realise(clip, &plan.spec, &plan.sim, &rig, net);
                let wanted = clip.labelled_crossers.map_or(0, |w| w as usize);
                let got = r.labelled_crossers() as usize;
                if std::env::var_os("REALISATION_MISSES").is_some() && clip.labelled_crossers.is_some() && got != wanted
                {
                    eprintln!(
                        "{}: {got} labelled of {wanted} planned, {} pedestrians, {} re-simulations (kept: round {})",
                        clip.clip_id,
                        clip.pedestrians.len(),
                        r.simulations - 1,
                        r.rounds
                    );
                }
                let topup = [
                    wanted,
                    got,
                    usize::from(clip.labelled_crossers.is_some()),
                    usize::from(clip.labelled_crossers.is_some() && got == wanted),
                    r.simulations - 1,
                    got.abs_diff(wanted).pow(2),
                ];
                (clip.town.as_str(), c, why, topup)
            })
            .collect();
        let counts: Vec<[usize; 13]> = per_clip.iter().map(|(_, c, _, _)| *c).collect();
        if why_wanted {
            for (_, _, why, _) in &per_clip {
                for w in why {
                    eprintln!("{w}");
                }
            }
        }
        // Allocated crossers and those labelled, per town.
        let mut towns_seen: std::collections::BTreeMap<&str, (usize, usize)> = std::collections::BTreeMap::new();
        for &(town, c, _, _) in &per_clip {
            let e = towns_seen.entry(town).or_default();
            e.0 += c[1];
            e.1 += c[2];
        }
        let t = counts.iter().fold([0usize; 13], |mut acc, c| {
            for k in 0..13 {
                acc[k] += c[k];
            }
            acc
        });
        let share = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
        println!(
            "{spec}: {} pedestrians ({:.3} never annotated), crossing ratio {:.3} (target {}); allocated crossers {}: on a driving lane {:.3}, labelled {:.3}, never annotated {:.3}; baseline crossers {}: labelled {:.3}",
            t[0],
            share(t[7], t[0]),
            share(t[2] + t[5], t[0]),
            plan.spec.crossing.target_ratio,
            t[1],
            share(t[3], t[1]),
            share(t[2], t[1]),
            share(t[6], t[1]),
            t[4],
            share(t[5], t[4])
        );
        println!(
            "  unlabelled allocated crossers: {:.3} never crossed in the clip, {:.3} crossed only behind the camera, \
             {:.3} crossed in front of it unannotated (too far, small, occluded, out of the image)",
            share(t[8], t[1]),
            share(t[9], t[1]),
            share(t[10], t[1])
        );
        let u = per_clip.iter().fold([0usize; 6], |mut acc, (_, _, _, x)| {
            for k in 0..6 {
                acc[k] += x[k];
            }
            acc
        });
        println!(
            "  realised by the executor (promotions and demotions): crossing ratio {:.4} ({} labelled of {} planned \
             over {} pedestrians); {} of {} clips meet their count (mean squared miss {:.3}); {} re-simulations",
            share(u[1], t[0]),
            u[1],
            u[0],
            t[0],
            u[3],
            u[2],
            share(u[5], u[2]),
            u[4]
        );
        let by_town: Vec<String> = towns_seen
            .iter()
            .map(|(town, &(n, l))| format!("{town} {:.3} ({n})", share(l, n)))
            .collect();
        println!("  allocated crossers labelled per town: {}", by_town.join(", "));
        if t[11] > 0 {
            println!(
                "  allocated crossers labelled in clips with an emergency vehicle {:.3} ({}), in the others {:.3} ({})",
                share(t[12], t[11]),
                t[11],
                share(t[2] - t[12], t[1] - t[11]),
                t[1] - t[11]
            );
        }
    }
}

/// One line on why allocated crosser `i` of `clip` was not labelled a crosser (`kind`), from its trace.
fn why_unlabelled(
    kind: &str,
    clip: &pedsynth::plan::ClipScript,
    trace: &pedsynth::sim::trace::ClipTrace,
    i: usize,
) -> String {
    let p = &clip.pedestrians[i];
    let frames = &trace.pedestrians[i];
    let passed = (0..frames.len()).find(|&f| from_ego_m(trace, f, frames[f].pos).x < 0.0);
    let at = passed.unwrap_or(frames.len() - 1);
    let curb_m = |j: usize| {
        clip.pedestrians[j].crossing.as_ref().map_or(f64::NAN, |x| {
            x.near_curb.distance(trace.pedestrians[j][at].pos.truncate())
        })
    };
    let reached = p
        .crossing
        .as_ref()
        .and_then(|x| (0..frames.len()).find(|&f| x.near_curb.distance(frames[f].pos.truncate()) < 0.7));
    let mut states: Vec<pedsynth::sim::trace::PedState> = frames[at.saturating_sub(10 * clip.fps as usize)..=at]
        .iter()
        .map(|f| f.state)
        .collect();
    states.dedup();
    let offset = from_ego_m(trace, at, frames[at].pos);
    let ego = &trace.ego[at];
    let share = |pred: &dyn Fn(f64) -> bool| {
        trace.ego[..=at].iter().filter(|e| pred(e.speed_mps)).count() as f64 / (at + 1) as f64
    };
    let group: Vec<String> = p
        .group
        .iter()
        .flat_map(|g| {
            clip.pedestrians
                .iter()
                .enumerate()
                .filter(move |(_, q)| q.group.is_some_and(|h| h.group_id == g.group_id))
                .map(move |(j, q)| {
                    format!(
                        "{}{}: {:.1} m",
                        if q.id == g.leader { "leader " } else { "" },
                        q.id,
                        curb_m(j)
                    )
                })
        })
        .collect();
    format!(
        "{kind}: {} pedestrian {} ({:?}): {} at frame {at} ({:.0} % of the clip) in {:?}, {:.1} m from its curb, {:.1} m \
         ahead and {:.1} m to the right of the ego; reached its curb {} frames before; states {}; ego at {:.1} m/s, slower \
         than 4 m/s {:.0} % and standing {:.0} % of the time; group [{}]",
        clip.clip_id,
        p.id,
        p.behaviour,
        if passed.is_some() {
            "the ego passed it"
        } else {
            "the clip ended"
        },
        100.0 * at as f64 / frames.len() as f64,
        frames[at].state,
        curb_m(i),
        offset.x,
        offset.y,
        reached.map_or("never".to_owned(), |r| (at as i64 - r as i64).to_string()),
        states.iter().map(|s| format!("{s:?}")).collect::<Vec<_>>().join(" > "),
        ego.speed_mps,
        100.0 * share(&|v| v < 4.0),
        100.0 * share(&|v| v < 0.3),
        group.join(", "),
    )
}

/// Where `pos` lies from the ego in frame `f`, metres: `x` ahead along its heading (negative: behind it), `y`
/// to its right.
fn from_ego_m(trace: &pedsynth::sim::trace::ClipTrace, f: usize, pos: glam::DVec3) -> glam::DVec2 {
    let e = &trace.ego[f];
    let (d, heading) = ((pos - e.pos).truncate(), glam::DVec2::from_angle(e.yaw_rad));
    glam::DVec2::new(d.dot(heading), d.perp_dot(heading))
}
