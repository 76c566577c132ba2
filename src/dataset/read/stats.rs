//! `pedsynth stats DIR`: dataset statistics computed from the written tables only (the paper's Table 5 plus
//! target vs achieved crossing ratio, state shares, per-archetype crossing rates and speeds, per-split counts).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::tables;
use crate::dataset::write::Layout;
use crate::error::Error;

/// Counts of one split.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SplitCounts {
    /// Clips.
    pub clips: u64,
    /// Frames.
    pub frames: u64,
    /// Pedestrians.
    pub pedestrians: u64,
    /// Sequence-level crossers.
    pub crossers: u64,
    /// Annotated samples.
    pub samples: u64,
}

/// Per-archetype figures.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ArchetypeStats {
    /// Pedestrians.
    pub pedestrians: u64,
    /// Sequence-level crossers.
    pub crossers: u64,
    /// crossers / pedestrians.
    pub crossing_rate: f64,
    /// Mean speed over annotated samples where the pedestrian moves (> 0.2 m/s), m/s.
    pub mean_moving_speed_mps: f64,
}

/// Dataset statistics.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DatasetStats {
    /// Clips.
    pub clips: u64,
    /// Frames.
    pub frames: u64,
    /// Mean frames per clip.
    pub mean_frames_per_clip: f64,
    /// Mean clip duration, seconds.
    pub mean_duration_s: f64,
    /// Unique pedestrians.
    pub pedestrians: u64,
    /// Sequence-level crossers (C = 1 in at least one annotated frame).
    pub crossing: u64,
    /// The others.
    pub non_crossing: u64,
    /// crossing / pedestrians.
    pub crossing_share: f64,
    /// non_crossing / pedestrians.
    pub non_crossing_share: f64,
    /// crossing / non_crossing.
    pub c_nc_ratio: f64,
    /// Annotated samples (pedestrian-frames).
    pub annotated_samples: u64,
    /// Mean annotated samples per clip.
    pub samples_per_clip: f64,
    /// Weathers.
    pub weathers: Vec<String>,
    /// Towns.
    pub towns: Vec<String>,
    /// Target crossing ratio (from the manifest).
    pub target_crossing_ratio: Option<f64>,
    /// Achieved sequence-level crossing ratio (= crossing_share).
    pub achieved_crossing_ratio: f64,
    /// Share of annotated samples in each behaviour state.
    pub state_shares: BTreeMap<String, f64>,
    /// Annotated samples in each behaviour state.
    pub state_samples: BTreeMap<String, u64>,
    /// Annotated samples with C = 1.
    pub crossing_samples: u64,
    /// Annotated samples in which the pedestrian looks at the ego's camera (`look`).
    pub looking_samples: u64,
    /// looking_samples / annotated_samples.
    pub looking_share: f64,
    /// Annotated samples in which the pedestrian walks (`action` = walking).
    pub walking_samples: u64,
    /// walking_samples / annotated_samples.
    pub walking_share: f64,
    /// Annotated samples per gesture (`hand_ack`, `hand_yield`, `nod`; none left out).
    pub gesture_samples: BTreeMap<String, u64>,
    /// Pedestrians seen making each gesture in at least one annotated frame.
    pub gesturing_pedestrians: BTreeMap<String, u64>,
    /// Annotated samples per reaction (`clear_path`, `speed_up`, `slow_down`; none left out).
    pub reaction_samples: BTreeMap<String, u64>,
    /// Per archetype.
    pub archetypes: BTreeMap<String, ArchetypeStats>,
    /// Per split.
    pub splits: BTreeMap<String, SplitCounts>,
    /// Pedestrian-frames rejected by the visibility gate, by reason.
    pub rejected: BTreeMap<String, u64>,
    /// Vehicle contacts recorded.
    pub contacts: u64,
    /// Clips with an emergency vehicle, per kind.
    pub emergency_clips: BTreeMap<String, u64>,
    /// Vehicle-frames (traffic and ego) stopping for an emergency vehicle.
    pub yielding_vehicle_frames: u64,
    /// Red lights a vehicle (traffic or ego) stopped for.
    pub red_lights_stopped_for: u64,
    /// Red lights run by vehicles that ignore lights or by emergency vehicles: the violations.
    pub red_light_violations: u64,
    /// Red lights run from the dilemma zone by vehicles that heed lights (too close to stop when the light
    /// turned amber, or placed too close to a red light at a clip's start).
    pub red_lights_run_unavoidably: u64,
    /// Signal compliance: stops at red / (stops at red + violations); `None` without either.
    pub signal_compliance: Option<f64>,
    /// Pedestrians annotated at a signalised crosswalk (their crossing runs along one).
    pub pedestrians_at_signals: u64,
    /// Annotated samples of pedestrians crossing while their signal shows "don't walk".
    pub against_signal_samples: u64,
    /// Annotated samples on a crosswalk.
    pub on_crosswalk_samples: u64,
    /// Cyclists (over all clips).
    pub cyclists: u64,
    /// Cyclist-frames whose box reaches into the image.
    pub cyclist_frames_in_view: u64,
    /// Cyclist-frames passing the visibility gate.
    pub cyclist_samples: u64,
    /// Overtakes of a cyclist by a vehicle (the ego or traffic).
    pub cyclist_overtakes: u64,
    /// The smallest side-to-side clearance of any overtake, metres (`None` without overtakes).
    pub min_overtaking_clearance_m: Option<f64>,
    /// Cyclists swerving around a pedestrian (per cyclist and pedestrian).
    pub cyclist_swerves: u64,
    /// Cyclists braking for a pedestrian (per cyclist and pedestrian).
    pub cyclist_brakes_for_pedestrians: u64,
    /// In-road conflicts of crossing pedestrians with a cyclist.
    pub pedestrian_cyclist_conflicts: u64,
    /// Contacts involving a cyclist.
    pub cyclist_contacts: u64,
    /// Red lights cyclists stopped for.
    pub cyclist_red_lights_stopped_for: u64,
    /// Red lights cyclists rode through.
    pub cyclist_red_light_runs: u64,
}

/// Computes the statistics of the dataset in `dir` from its tables.
pub fn compute(dir: &Path) -> Result<DatasetStats, Error> {
    let layout = Layout::new(dir);
    let mut s = DatasetStats::default();
    // Only the target from the manifest, read as a stream (its clip list grows with the dataset).
    #[derive(serde::Deserialize)]
    struct Target {
        target_crossing_ratio: Option<f64>,
    }
    s.target_crossing_ratio = std::fs::File::open(layout.manifest())
        .ok()
        .and_then(|f| serde_json::from_reader::<_, Target>(std::io::BufReader::new(f)).ok())
        .and_then(|m| m.target_crossing_ratio);
    let mut towns = std::collections::BTreeSet::new();
    let mut weathers = std::collections::BTreeSet::new();
    let mut duration_s = 0.0;
    let mut states: BTreeMap<String, u64> = BTreeMap::new();
    let mut speed_sums: BTreeMap<String, (f64, u64)> = BTreeMap::new();
    for path in tables::files(&layout, "clips")? {
        let mut split = String::new();
        let mut emergency_clip = false;
        for b in tables::read(
            &path,
            &[
                "town",
                "weather",
                "split",
                "frame_count",
                "duration_s",
                "annotated_samples",
                "rejected_too_far",
                "rejected_behind",
                "rejected_too_small",
                "rejected_outside_image",
                "rejected_occluded",
                "contacts",
                "emergency",
            ],
        )? {
            let (town, weather, splits) = (b.strings("town")?, b.strings("weather")?, b.strings("split")?);
            let (frame_count, samples_col) = (b.u32s("frame_count")?, b.u64s("annotated_samples")?);
            let (durations, contacts) = (b.f64s("duration_s")?, b.u32s("contacts")?);
            let emergency = b.strings("emergency")?;
            for i in 0..b.rows() {
                split = splits[i].to_owned();
                let frames = u64::from(frame_count.value(i));
                let samples = samples_col.value(i);
                s.clips += 1;
                s.frames += frames;
                s.annotated_samples += samples;
                duration_s += durations.value(i);
                s.contacts += u64::from(contacts.value(i));
                for reason in ["too_far", "behind", "too_small", "outside_image", "occluded"] {
                    *s.rejected.entry(reason.to_owned()).or_default() +=
                        b.u64s(&format!("rejected_{reason}"))?.value(i);
                }
                let sp = s.splits.entry(split.clone()).or_default();
                sp.clips += 1;
                sp.frames += frames;
                sp.samples += samples;
                towns.insert(town[i].to_owned());
                weathers.insert(weather[i].to_owned());
                emergency_clip |= !emergency[i].is_empty();
                if !emergency[i].is_empty() {
                    *s.emergency_clips.entry(emergency[i].to_owned()).or_default() += 1;
                }
            }
        }
        let clip_id = path
            .file_stem()
            .map(|x| x.to_string_lossy().into_owned())
            .unwrap_or_default();
        // Pedestrians of this clip: sequence labels and archetypes.
        let mut archetype_of: Vec<String> = Vec::new();
        for b in tables::read(
            &layout.table("pedestrians", &clip_id),
            &["pedestrian", "archetype", "crosser"],
        )? {
            let (ids, archetypes, crossers) = (b.u32s("pedestrian")?, b.strings("archetype")?, b.bools("crosser")?);
            for (i, archetype) in archetypes.iter().enumerate() {
                let id = ids.value(i) as usize;
                let archetype = (*archetype).to_owned();
                let crosser = crossers.value(i);
                if archetype_of.len() <= id {
                    archetype_of.resize(id + 1, String::new());
                }
                archetype_of[id] = archetype.clone();
                s.pedestrians += 1;
                s.crossing += u64::from(crosser);
                let a = s.archetypes.entry(archetype).or_default();
                a.pedestrians += 1;
                a.crossers += u64::from(crosser);
                let sp = s.splits.entry(split.clone()).or_default();
                sp.pedestrians += 1;
                sp.crossers += u64::from(crosser);
            }
        }
        // Only a clip with an emergency vehicle has vehicles yielding to one.
        if emergency_clip {
            for (table, column) in [("vehicles", "yielding"), ("frames", "ego_yielding")] {
                for b in tables::read(&layout.table(table, &clip_id), &[column])? {
                    s.yielding_vehicle_frames += b.bools(column)?.true_count() as u64;
                }
            }
        }
        for b in tables::read(
            &layout.table("events", &clip_id),
            &["kind", "unavoidable", "cyclist", "min_clearance_m", "swerved"],
        )? {
            let (kind, unavoidable) = (b.strings("kind")?, b.bools("unavoidable")?);
            let (cyclist, clearance, swerved) = (b.u32s("cyclist")?, b.f32s("min_clearance_m")?, b.bools("swerved")?);
            for (i, kind) in kind.iter().enumerate() {
                let by_cyclist = arrow_array::Array::is_valid(cyclist, i);
                match *kind {
                    "stopped_at_red_light" if by_cyclist => s.cyclist_red_lights_stopped_for += 1,
                    "ran_red_light" if by_cyclist => s.cyclist_red_light_runs += 1,
                    "stopped_at_red_light" => s.red_lights_stopped_for += 1,
                    "ran_red_light" if unavoidable.value(i) => s.red_lights_run_unavoidably += 1,
                    "ran_red_light" => s.red_light_violations += 1,
                    "overtook_cyclist" => {
                        s.cyclist_overtakes += 1;
                        let c = f64::from(clearance.value(i));
                        s.min_overtaking_clearance_m = Some(s.min_overtaking_clearance_m.map_or(c, |m| m.min(c)));
                    }
                    "cyclist_yielded" if swerved.value(i) => s.cyclist_swerves += 1,
                    "cyclist_yielded" => s.cyclist_brakes_for_pedestrians += 1,
                    "conflict" if by_cyclist => s.pedestrian_cyclist_conflicts += 1,
                    "contact" if by_cyclist => s.cyclist_contacts += 1,
                    _ => {}
                }
            }
        }
        let mut cyclist_ids = std::collections::BTreeSet::new();
        for b in tables::read(
            &layout.table("cyclists", &clip_id),
            &["cyclist", "in_view", "annotated"],
        )? {
            let (ids, in_view, annotated) = (b.u32s("cyclist")?, b.bools("in_view")?, b.bools("annotated")?);
            cyclist_ids.extend(ids.values().iter().copied());
            s.cyclist_frames_in_view += in_view.true_count() as u64;
            s.cyclist_samples += annotated.true_count() as u64;
        }
        s.cyclists += cyclist_ids.len() as u64;
        let mut gestured = std::collections::BTreeSet::new();
        let mut at_signals = std::collections::BTreeSet::new();
        for b in tables::read(
            &layout.table("annotations", &clip_id),
            &[
                "pedestrian",
                "state",
                "crossing",
                "vx_mps",
                "vy_mps",
                "look",
                "action",
                "gesture",
                "reaction",
                "walk_signal",
                "against_signal",
                "on_crosswalk",
            ],
        )? {
            let ped = b.u32s("pedestrian")?;
            let state = b.strings("state")?;
            let crossing = b.bools("crossing")?;
            let (vx, vy) = (b.f32s("vx_mps")?, b.f32s("vy_mps")?);
            let (look, action) = (b.bools("look")?, b.strings("action")?);
            let (gesture, reaction) = (b.strings("gesture")?, b.strings("reaction")?);
            let (walk_signal, against, on_crosswalk) = (
                b.strings("walk_signal")?,
                b.bools("against_signal")?,
                b.bools("on_crosswalk")?,
            );
            s.against_signal_samples += against.true_count() as u64;
            s.on_crosswalk_samples += on_crosswalk.true_count() as u64;
            for (i, w) in walk_signal.iter().enumerate() {
                if !w.is_empty() {
                    at_signals.insert(ped.value(i));
                }
            }
            for (i, state) in state.iter().enumerate() {
                *states.entry((*state).to_owned()).or_default() += 1;
                s.crossing_samples += u64::from(crossing.value(i));
                s.looking_samples += u64::from(look.value(i));
                s.walking_samples += u64::from(action[i] == "walking");
                if gesture[i] != "none" {
                    *s.gesture_samples.entry(gesture[i].to_owned()).or_default() += 1;
                    gestured.insert((gesture[i].to_owned(), ped.value(i)));
                }
                if reaction[i] != "none" {
                    *s.reaction_samples.entry(reaction[i].to_owned()).or_default() += 1;
                }
                let speed = f64::from(vx.value(i)).hypot(f64::from(vy.value(i)));
                if speed > 0.2
                    && let Some(a) = archetype_of.get(ped.value(i) as usize)
                {
                    let e = speed_sums.entry(a.clone()).or_default();
                    e.0 += speed;
                    e.1 += 1;
                }
            }
        }
        for (g, _) in gestured {
            *s.gesturing_pedestrians.entry(g).or_default() += 1;
        }
        s.pedestrians_at_signals += at_signals.len() as u64;
    }
    s.non_crossing = s.pedestrians - s.crossing;
    let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    s.crossing_share = ratio(s.crossing, s.pedestrians);
    s.non_crossing_share = ratio(s.non_crossing, s.pedestrians);
    s.c_nc_ratio = ratio(s.crossing, s.non_crossing);
    s.achieved_crossing_ratio = s.crossing_share;
    let faced = s.red_lights_stopped_for + s.red_light_violations;
    s.signal_compliance = (faced > 0).then(|| ratio(s.red_lights_stopped_for, faced));
    s.mean_frames_per_clip = ratio(s.frames, s.clips);
    s.mean_duration_s = if s.clips == 0 { 0.0 } else { duration_s / s.clips as f64 };
    s.samples_per_clip = ratio(s.annotated_samples, s.clips);
    s.looking_share = ratio(s.looking_samples, s.annotated_samples);
    s.walking_share = ratio(s.walking_samples, s.annotated_samples);
    let total: u64 = states.values().sum();
    s.state_shares = states.iter().map(|(k, v)| (k.clone(), ratio(*v, total))).collect();
    s.state_samples = states;
    for (name, a) in &mut s.archetypes {
        a.crossing_rate = ratio(a.crossers, a.pedestrians);
        if let Some((sum, n)) = speed_sums.get(name) {
            a.mean_moving_speed_mps = sum / *n as f64;
        }
    }
    s.towns = towns.into_iter().collect();
    s.weathers = weathers.into_iter().collect();
    Ok(s)
}

/// The statistics as text (the paper's Table 5 first).
impl std::fmt::Display for DatasetStats {
    fn fmt(&self, o: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = self;
        writeln!(o, "Dataset statistics (from the tables)")?;
        writeln!(o, "  clips                      {}", s.clips)?;
        writeln!(o, "  frames                     {}", s.frames)?;
        writeln!(o, "  avg frames per clip        {:.1}", s.mean_frames_per_clip)?;
        writeln!(o, "  avg clip duration          {:.1} s", s.mean_duration_s)?;
        writeln!(o, "  unique pedestrians         {}", s.pedestrians)?;
        writeln!(
            o,
            "    crossing (C)             {} ({:.1}%)",
            s.crossing,
            100.0 * s.crossing_share
        )?;
        writeln!(
            o,
            "    non-crossing (NC)        {} ({:.1}%)",
            s.non_crossing,
            100.0 * s.non_crossing_share
        )?;
        writeln!(o, "  C/NC ratio                 {:.2}:1", s.c_nc_ratio)?;
        writeln!(o, "  annotated samples          {}", s.annotated_samples)?;
        writeln!(o, "  avg samples per clip       {:.0}", s.samples_per_clip)?;
        writeln!(
            o,
            "  weathers                   {} ({})",
            s.weathers.len(),
            s.weathers.join(", ")
        )?;
        writeln!(
            o,
            "  towns                      {} ({})",
            s.towns.len(),
            s.towns.join(", ")
        )?;
        match s.target_crossing_ratio {
            Some(t) => {
                writeln!(
                    o,
                    "\ncrossing ratio: target {:.3}, achieved {:.3} ({:+.1} pp)",
                    t,
                    s.achieved_crossing_ratio,
                    100.0 * (s.achieved_crossing_ratio - t)
                )?;
            }
            None => {
                writeln!(o, "\ncrossing ratio: achieved {:.3}", s.achieved_crossing_ratio)?;
            }
        }
        writeln!(o, "\nshare of annotated samples per state")?;
        for (k, v) in &s.state_shares {
            writeln!(o, "  {k:<20} {:6.2}%", 100.0 * v)?;
        }
        writeln!(o, "\nbehaviour labels (annotated samples)")?;
        writeln!(
            o,
            "  looking at the ego         {} ({:.1}%)",
            s.looking_samples,
            100.0 * s.looking_share
        )?;
        writeln!(
            o,
            "  walking                    {} ({:.1}%)",
            s.walking_samples,
            100.0 * s.walking_share
        )?;
        for (k, v) in &s.gesture_samples {
            let peds = s.gesturing_pedestrians.get(k).copied().unwrap_or(0);
            writeln!(o, "  gesture {k:<18} {v} ({peds} pedestrians)")?;
        }
        for (k, v) in &s.reaction_samples {
            writeln!(o, "  reaction {k:<17} {v}")?;
        }
        writeln!(
            o,
            "\nper archetype                pedestrians crossers  rate   moving speed"
        )?;
        for (k, a) in &s.archetypes {
            writeln!(
                o,
                "  {k:<26} {:>9} {:>8} {:5.1}%  {:.2} m/s",
                a.pedestrians,
                a.crossers,
                100.0 * a.crossing_rate,
                a.mean_moving_speed_mps
            )?;
        }
        writeln!(o, "\nper split")?;
        for (k, sp) in &s.splits {
            writeln!(
                o,
                "  {k:<6} {:>6} clips {:>9} frames {:>7} pedestrians {:>7} crossers {:>9} samples",
                sp.clips, sp.frames, sp.pedestrians, sp.crossers, sp.samples
            )?;
        }
        writeln!(o, "\nvisibility gate rejections (pedestrian-frames)")?;
        for (k, v) in &s.rejected {
            writeln!(o, "  {k:<14} {v}")?;
        }
        writeln!(o, "vehicle contacts             {}", s.contacts)?;
        let emergencies: u64 = s.emergency_clips.values().sum();
        if emergencies > 0 {
            let kinds: Vec<String> = s.emergency_clips.iter().map(|(k, n)| format!("{k} {n}")).collect();
            writeln!(o, "emergency clips              {emergencies} ({})", kinds.join(", "))?;
            writeln!(o, "vehicle-frames yielding      {}", s.yielding_vehicle_frames)?;
        }
        if let Some(c) = s.signal_compliance {
            writeln!(
                o,
                "red lights                   {} stopped for, {} violations, {} run from the dilemma zone \
                 (compliance {:.1} %)",
                s.red_lights_stopped_for,
                s.red_light_violations,
                s.red_lights_run_unavoidably,
                100.0 * c
            )?;
        }
        if s.cyclists > 0 {
            writeln!(
                o,
                "cyclists                     {} ({} frames in view, {} samples passing the gate)",
                s.cyclists, s.cyclist_frames_in_view, s.cyclist_samples
            )?;
            let clearance = s
                .min_overtaking_clearance_m
                .map_or_else(String::new, |c| format!(", smallest clearance {c:.2} m"));
            writeln!(o, "  overtaken by vehicles      {}{clearance}", s.cyclist_overtakes)?;
            writeln!(
                o,
                "  yielding to pedestrians    {} swerves, {} brakings; {} pedestrian conflicts with cyclists",
                s.cyclist_swerves, s.cyclist_brakes_for_pedestrians, s.pedestrian_cyclist_conflicts
            )?;
            writeln!(
                o,
                "  contacts, red lights       {} contacts; {} red lights stopped for, {} ridden through",
                s.cyclist_contacts, s.cyclist_red_lights_stopped_for, s.cyclist_red_light_runs
            )?;
        }
        if s.pedestrians_at_signals > 0 {
            writeln!(
                o,
                "signalised crosswalks        {} pedestrians, {} samples crossing against the signal",
                s.pedestrians_at_signals, s.against_signal_samples
            )?;
        }
        Ok(())
    }
}
