//! Measures the crossing realisation that `src/calibration.rs` records: the share of planned crossers (layer 1)
//! that end up labelled crossers (C = 1 in at least one annotated frame), per spec.
//!
//! Run: `cargo run --release --example realisation -- specs/balanced_50.yaml specs/pedsynth_pp.yaml [--set KEY=VALUE]...`

use std::path::Path;

use pedsynth::dsl::LoadOptions;
use pedsynth::exec::observe::{self, rig::Rig};
use pedsynth::exec::simulate;
use pedsynth::planner::{CrosserSource, Role};
use pedsynth::world::LaneType;
use rayon::prelude::*;

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
    };
    for spec in specs {
        let (_, towns, plan) = match pedsynth::commands::plan_spec_file(Path::new(&spec), &options) {
            Ok(x) => x,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        let rig = Rig::from_spec(&plan.spec.sensors);
        // (pedestrians, allocated, allocated labelled, allocated on a driving lane, baseline, baseline labelled,
        // allocated never annotated, pedestrians never annotated, unlabelled allocated crossers that never had
        // C = 1, ... that had C = 1 only behind the camera, ... only in front of it but not annotated, allocated in
        // clips with an emergency vehicle, ... labelled)
        let per_clip: Vec<(&str, [usize; 13])> = plan
            .clips
            .par_iter()
            .map(|clip| {
                let net = &towns[&clip.town].network;
                let trace = simulate::simulate(clip, &plan.sim, net);
                let ann = observe::observe(clip, &trace, &plan.spec, &rig, net).annotations;
                let mut c = [0usize; 13];
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
                                let behind = crossing_frames.iter().all(|&f| {
                                    let (e, q) = (&trace.ego[f], &trace.pedestrians[i][f]);
                                    (q.pos - e.pos).truncate().dot(glam::DVec2::from_angle(e.yaw_rad)) < 0.0
                                });
                                match (crossing_frames.is_empty(), behind) {
                                    (true, _) => c[8] += 1,
                                    (false, true) => c[9] += 1,
                                    (false, false) => c[10] += 1,
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
                (clip.town.as_str(), c)
            })
            .collect();
        let counts: Vec<[usize; 13]> = per_clip.iter().map(|&(_, c)| c).collect();
        // Allocated crossers and those labelled, per town.
        let mut towns_seen: std::collections::BTreeMap<&str, (usize, usize)> = std::collections::BTreeMap::new();
        for &(town, c) in &per_clip {
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
