use std::path::Path;
use pedsynth::commands::load_towns;
use pedsynth::dsl::{self, LoadOptions};
use pedsynth::exec::sim;
use pedsynth::exec::trace::{Event, EGO_ID};
use pedsynth::planner;

#[test]
fn debug_contacts() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/pedsynth_pp.yaml");
    let options = LoadOptions { overrides: vec!["dataset.clips.count=4".into()], allow_large: true };
    let loaded = dsl::load_file(&path, &options).unwrap();
    let towns = load_towns(&loaded).unwrap();
    let plan = planner::plan(&loaded.spec, &loaded.hash(), &towns, None).unwrap();
    let traces = sim::simulate_all(&plan, &towns).unwrap();
    let mut n = 0;
    for (clip, t) in plan.clips.iter().zip(&traces) {
        for e in &t.events {
            if let Event::Contact { frame, vehicle, pedestrian, other_vehicle } = e {
                n += 1;
                if n > 25 { continue; }
                let vf = |id: u32| if id == EGO_ID { t.ego[*frame as usize] } else { t.vehicles[id as usize][*frame as usize] };
                let a = vf(*vehicle);
                let lane = |p: glam::DVec3| towns[&clip.town].network.lane_at(p.truncate()).map(|h| (h.lane, towns[&clip.town].network.lanes[h.lane as usize].in_junction));
                print!("{} f{} v{} pos {:.1},{:.1} yaw {:.2} v {:.1} lane {:?}", clip.clip_id, frame, *vehicle as i64, a.pos.x, a.pos.y, a.yaw_rad, a.speed_mps, lane(a.pos));
                if let Some(o) = other_vehicle { let b = vf(*o); println!(" | v{} pos {:.1},{:.1} yaw {:.2} v {:.1} lane {:?}", o, b.pos.x, b.pos.y, b.yaw_rad, b.speed_mps, lane(b.pos)); }
                if let Some(p) = pedestrian { let f = t.pedestrians[*p as usize][*frame as usize]; let fp = t.pedestrians[*p as usize][*frame as usize - 1]; println!(" | ped {} {:?} pos {:.1},{:.1} vel {:.2},{:.2} prev {:?} beh {:?}", p, f.state, f.pos.x, f.pos.y, f.velocity.x, f.velocity.y, fp.state, clip.pedestrians[*p as usize].behaviour); }
            }
        }
    }
    println!("{n} contacts in {} clips", plan.clips.len());
}
