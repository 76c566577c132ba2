//! Validation of `pedestrians` (archetypes, groups, gestures) and `crossing` (target, layers, timeline).

use super::*;

impl Validator<'_> {
    pub(super) fn pedestrians(&mut self, p: &Pedestrians) {
        self.count_range(
            "pedestrians.per_clip",
            p.per_clip,
            0,
            200,
            "a number of pedestrians per clip",
        );
        let names: Vec<&str> = p.archetypes.keys().map(String::as_str).collect();
        for name in p.archetype_mix.keys() {
            if !p.archetypes.contains_key(name) {
                let path = format!("pedestrians.archetype_mix.{name}");
                let problem = Problem::new(
                    code::UNKNOWN_NAME,
                    format!("unknown archetype `{name}` in `pedestrians.archetype_mix`"),
                )
                .at(self.key_span(&path), "unknown archetype")
                .help(format!(
                    "{} New archetypes are defined under `pedestrians.archetypes`.",
                    suggestion(name, &names)
                ));
                self.problems.push(problem);
            }
        }
        let shares: Vec<(&str, f64)> = p.archetype_mix.iter().map(|(n, s)| (n.as_str(), *s)).collect();
        self.mix("pedestrians.archetype_mix", &shares);
        for (name, a) in &p.archetypes {
            let base = format!("pedestrians.archetypes.{name}");
            self.name(&base, name, "archetype");
            self.range(
                &format!("{base}.speed_mps"),
                a.speed_mps,
                0.1,
                5.0,
                "a walking speed in m/s",
            );
            self.range(
                &format!("{base}.hesitation_s"),
                a.hesitation_s,
                0.0,
                60.0,
                "a hesitation duration in seconds",
            );
            self.probability(&format!("{base}.attention"), a.attention);
            self.probability(&format!("{base}.crossing_probability"), a.crossing_probability);
            self.range(
                &format!("{base}.ttc_threshold_s"),
                a.ttc_threshold_s,
                0.0,
                30.0,
                "a time-to-collision threshold in seconds",
            );
            self.range(
                &format!("{base}.patience_s"),
                a.patience_s,
                0.5,
                600.0,
                "a waiting time in seconds",
            );
            self.probability(&format!("{base}.distraction_probability"), a.distraction_probability);
            self.probability(
                &format!("{base}.red_light_violation_probability"),
                a.red_light_violation_probability,
            );
        }
        let sp = &p.speed_profiles;
        self.mix(
            "pedestrians.speed_profiles.mix",
            &[
                ("cautious", sp.mix.cautious),
                ("normal", sp.mix.normal),
                ("rushed", sp.mix.rushed),
                ("distracted", sp.mix.distracted),
            ],
        );
        let m = &sp.multipliers;
        for (name, value) in [
            ("cautious", m.cautious),
            ("normal", m.normal),
            ("rushed", m.rushed),
            ("distracted", m.distracted),
        ] {
            self.positive(
                &format!("pedestrians.speed_profiles.multipliers.{name}"),
                value,
                3.0,
                "a speed multiplier",
            );
        }
        let g = &p.gestures;
        self.probability(
            "pedestrians.gestures.acknowledge_probability",
            g.acknowledge_probability,
        );
        self.probability("pedestrians.gestures.nod_share", g.nod_share);
        self.probability(
            "pedestrians.gestures.wave_through_probability",
            g.wave_through_probability,
        );
    }

    pub(super) fn crossing(&mut self, c: &Crossing) {
        self.probability("crossing.target_ratio", c.target_ratio);
        self.probability("crossing.baseline_ratio", c.baseline_ratio);
        let l = &c.layers;
        self.probability(
            "crossing.layers.crosser_allocation.max_crosser_ratio",
            l.crosser_allocation.max_crosser_ratio,
        );
        self.range(
            "crossing.layers.crosser_allocation.spawn_ahead_m",
            l.crosser_allocation.spawn_ahead_m,
            0.0,
            200.0,
            "a distance ahead of the ego in metres",
        );
        let b = &l.behaviour_mix.mix;
        self.mix(
            "crossing.layers.behaviour_mix.mix",
            &[("normal", b.normal), ("sudden", b.sudden), ("jaywalk", b.jaywalk)],
        );
        self.probability(
            "crossing.layers.midroad_jaywalkers.share_of_crossers",
            l.midroad_jaywalkers.share_of_crossers,
        );
        self.num(
            "crossing.layers.midroad_jaywalkers.lateral_offset_m",
            l.midroad_jaywalkers.lateral_offset_m,
            0.0,
            5.0,
            "a lateral offset in metres",
        );
        self.probability("crossing.layers.groups.probability", l.groups.probability);
        self.mix(
            "crossing.layers.groups.size_mix",
            &[
                ("pairs", l.groups.size_mix.pairs),
                ("triples", l.groups.size_mix.triples),
            ],
        );
        self.range(
            "crossing.gap_acceptance.safety_margin_s",
            c.gap_acceptance.safety_margin_s,
            0.0,
            10.0,
            "a safety margin in seconds",
        );
        self.positive(
            "crossing.gap_acceptance.vehicle_range_m",
            c.gap_acceptance.vehicle_range_m,
            500.0,
            "a distance in metres",
        );
        if c.lookahead.points_m.is_empty() {
            self.problems.push(
                Problem::new(
                    code::OUT_OF_RANGE,
                    "`crossing.lookahead.points_m` needs at least one probe distance",
                )
                .at(self.span("crossing.lookahead.points_m"), "empty")
                .help("the paper probes at [0.5, 1.5, 2.5] m"),
            );
        }
        for (i, d) in c.lookahead.points_m.iter().enumerate() {
            self.positive(
                &format!("crossing.lookahead.points_m[{i}]"),
                *d,
                20.0,
                "a probe distance in metres",
            );
        }
        self.num(
            "crossing.lookahead.prediction_s",
            c.lookahead.prediction_s,
            0.0,
            5.0,
            "a prediction horizon in seconds",
        );
        self.positive(
            "crossing.lookahead.radius_m",
            c.lookahead.radius_m,
            20.0,
            "a safety radius in metres",
        );
        self.probability("crossing.retreat.probability", c.retreat.probability);
        self.positive(
            "crossing.retreat.window_fraction",
            c.retreat.window_fraction,
            1.0,
            "a fraction of the crossing path",
        );
        self.range(
            "crossing.retreat.speed_mps",
            c.retreat.speed_mps,
            0.1,
            10.0,
            "a speed in m/s",
        );
        self.probability(
            "crossing.patience.sudden_crossing_probability",
            c.patience.sudden_crossing_probability,
        );
        self.range(
            "crossing.decision_window_m",
            c.decision_window_m,
            0.0,
            200.0,
            "a distance to the ego in metres",
        );
        self.range(
            "crossing.timeline.in_view_before_crossing_s",
            c.timeline.in_view_before_crossing_s,
            0.0,
            60.0,
            "a time in view of the camera in seconds",
        );
        for (key, range) in [
            (
                "crossing.scenario.crosser_ego_within_m",
                c.scenario.crosser_ego_within_m,
            ),
            ("crossing.scenario.walker_ahead_m", c.scenario.walker_ahead_m),
            ("crossing.scenario.walker_lateral_m", c.scenario.walker_lateral_m),
        ] {
            self.range(key, range, 0.0, 500.0, "a distance to the ego in metres ([0, 0]: off)");
        }
        self.num(
            "crossing.scenario.crosser_stopped_ego_within_m",
            c.scenario.crosser_stopped_ego_within_m,
            0.0,
            500.0,
            "a distance to the stopped ego in metres (0: off)",
        );
        self.range(
            "crossing.timeline.approach_m",
            c.timeline.approach_m,
            0.0,
            100.0,
            "a walking distance in metres",
        );
        self.probability(
            "crossing.hard_negatives.share_of_non_crossers",
            c.hard_negatives.share_of_non_crossers,
        );
        self.range(
            "crossing.hard_negatives.wait_at_curb_s",
            c.hard_negatives.wait_at_curb_s,
            0.0,
            600.0,
            "a waiting time in seconds",
        );

        let before = self.problems.len();
        let (lo, hi) = reachable_crossing_ratio(c);
        let tolerance = if l.crosser_allocation.enabled { 1e-9 } else { 0.02 };
        let target_valid = (0.0..=1.0).contains(&c.target_ratio) && (0.0..=1.0).contains(&c.baseline_ratio);
        if self.problems.len() == before
            && target_valid
            && (c.target_ratio > hi + tolerance || c.target_ratio < lo - tolerance)
        {
            // Only the baseline can miss a target: with layer 1 on, the planner reaches every target in [0, 1].
            let help = format!(
                "with `crossing.layers.crosser_allocation` off only the baseline ({}) crosses: enable it, or set `target_ratio` to the baseline",
                fmt_num(lo)
            );
            let problem = Problem::new(
                code::UNREACHABLE_TARGET,
                format!(
                    "target crossing ratio {} is out of reach: the enabled layers give {} to {}",
                    fmt_num(c.target_ratio),
                    fmt_num(lo),
                    fmt_num(hi)
                ),
            )
            .at(self.span("crossing.target_ratio"), "unreachable target")
            .help(help);
            self.problems.push(problem);
        }
    }
}
