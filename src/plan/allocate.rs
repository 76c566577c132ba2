//! A stratum's draws: every mix of a (town, weather) cell allocated with exact quotas (largest remainder) and
//! shuffled with the stratum's stream — clip basics, pedestrians per clip, crossers from the target (with the
//! crossing-heavy adaptation beyond what the spec's layers reach), behaviours, emergency clips.

use super::*;

/// Per-clip draws that the stratum's quotas depend on.
pub(super) struct ClipBasics {
    pub(super) seed: u64,
    pub(super) frame_count: u32,
    pub(super) pedestrians: usize,
    pub(super) vehicles: usize,
    /// Stratum-wide index of the clip's first pedestrian (in the stratum's allocations).
    pub(super) first_pedestrian: usize,
    /// Stratum-wide index of the clip's first vehicle (in the stratum's driving profiles).
    pub(super) first_vehicle: usize,
    /// The clip's emergency vehicle, if it is one of the stratum's emergency clips.
    pub(super) emergency: Option<EmergencyKind>,
    /// The clip's planned count of labelled crossers ([`reserve::labelled_targets`]).
    pub(super) labelled_crossers: Option<u32>,
}

/// Per-pedestrian allocations made at the stratum level (16 bytes: a plan holds one per pedestrian).
#[derive(Clone)]
pub(super) struct PedAlloc {
    /// Index in the spec's archetype mix.
    pub(super) archetype: u32,
    pub(super) speed_profile: SpeedProfile,
    pub(super) source: CrosserSource,
    pub(super) behaviour: Behaviour,
    /// Stratum-wide index of the group's leader.
    pub(super) group: Option<u32>,
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
pub(super) fn crosser_shares(spec: &Spec) -> (f64, f64) {
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
pub(super) fn draw_stratum(spec: &Spec, stratum_index: usize, stratum: &Stratum) -> StratumDraws {
    let seed = spec.dataset.seed;
    let d = &spec.dataset;
    let (mut first_pedestrian, mut first_vehicle) = (0, 0);
    let basics: Vec<ClipBasics> = (0..stratum.clips)
        .map(|k| {
            let clip_seed = seeds::seed_u64(seed, &clip_id(&stratum.town, &stratum.weather, k));
            let mut rng = seeds::clip_rng(clip_seed, "basics");
            let duration_s = rng.random_range(d.clip_duration_s.min()..=d.clip_duration_s.max());
            // Whole frames within the range (a bound that is no whole number of frames is not rounded past).
            let fps = f64::from(d.fps);
            let frame_count = ((duration_s * fps).round().min((d.clip_duration_s.max() * fps).floor()) as u32).max(1);
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
pub(super) fn allocate_emergencies(spec: &Spec, stratum: &Stratum, basics: &mut [ClipBasics]) {
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

pub(super) fn allocate_pedestrians(spec: &Spec, stratum: &Stratum, basics: &[ClipBasics]) -> Vec<PedAlloc> {
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
