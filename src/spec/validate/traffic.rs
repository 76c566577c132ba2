//! Validation of `traffic` (vehicles, driving profiles, signals, cyclists, emergency vehicles).

use super::*;

impl Validator<'_> {
    pub(super) fn traffic(&mut self, t: &Traffic) {
        self.count_range(
            "traffic.vehicles_per_clip",
            t.vehicles_per_clip,
            0,
            200,
            "a number of vehicles per clip",
        );
        let m = &t.profile_mix;
        self.mix(
            "traffic.profile_mix",
            &[
                ("aggressive", m.aggressive),
                ("normal", m.normal),
                ("cautious", m.cautious),
            ],
        );
        for (name, p) in [
            ("aggressive", &t.profiles.aggressive),
            ("normal", &t.profiles.normal),
            ("cautious", &t.profiles.cautious),
        ] {
            let base = format!("traffic.profiles.{name}");
            self.range(
                &format!("{base}.speed_difference_pct"),
                p.speed_difference_pct,
                -100.0,
                90.0,
                "a percentage below the speed limit (negative: faster)",
            );
            self.range(&format!("{base}.min_gap_m"), p.min_gap_m, 0.1, 50.0, "a gap in metres");
            self.range(
                &format!("{base}.time_headway_s"),
                p.time_headway_s,
                0.1,
                10.0,
                "a time headway in seconds",
            );
            self.probability(
                &format!("{base}.ignore_lights_probability"),
                p.ignore_lights_probability,
            );
            self.probability(
                &format!("{base}.ignore_walkers_probability"),
                p.ignore_walkers_probability,
            );
        }
        self.positive(
            "traffic.idm.max_accel_mps2",
            t.idm.max_accel_mps2,
            10.0,
            "an acceleration in m/s²",
        );
        self.positive(
            "traffic.idm.comfortable_decel_mps2",
            t.idm.comfortable_decel_mps2,
            10.0,
            "a deceleration in m/s²",
        );
        self.positive(
            "traffic.idm.max_decel_mps2",
            t.idm.max_decel_mps2,
            15.0,
            "a deceleration in m/s²",
        );
        self.positive("traffic.idm.exponent", t.idm.exponent, 10.0, "the IDM exponent δ");
        let e = &t.emergency;
        self.probability("traffic.emergency.clip_share", e.clip_share);
        self.mix(
            "traffic.emergency.mix",
            &[
                ("ambulance", e.mix.ambulance),
                ("fire_truck", e.mix.fire_truck),
                ("police", e.mix.police),
            ],
        );
        self.num(
            "traffic.emergency.speed_above_limit_pct",
            e.speed_above_limit_pct,
            0.0,
            100.0,
            "a percentage above the speed limit",
        );
        self.range(
            "traffic.ego.speed_below_limit_pct",
            t.ego.speed_below_limit_pct,
            0.0,
            90.0,
            "a percentage below the speed limit",
        );
        self.positive("traffic.ego.min_gap_m", t.ego.min_gap_m, 50.0, "a gap in metres");
        self.num(
            "traffic.ego.heading_wobble.sd_deg",
            t.ego.heading_wobble.sd_deg,
            0.0,
            10.0,
            "a standard deviation of the heading in degrees",
        );
        self.num(
            "traffic.ego.heading_wobble.correlation_s",
            t.ego.heading_wobble.correlation_s,
            0.05,
            60.0,
            "a correlation time in seconds",
        );
        self.num(
            "traffic.ego.pitch_wobble.sd_deg",
            t.ego.pitch_wobble.sd_deg,
            0.0,
            5.0,
            "a standard deviation of the body pitch in degrees",
        );
        self.num(
            "traffic.ego.pitch_wobble.correlation_s",
            t.ego.pitch_wobble.correlation_s,
            0.05,
            60.0,
            "a correlation time in seconds",
        );
        self.positive(
            "traffic.ego.brake_ahead_m",
            t.ego.brake_ahead_m,
            100.0,
            "a distance in metres",
        );
        self.positive(
            "traffic.ego.brake_lateral_m",
            t.ego.brake_lateral_m,
            20.0,
            "a distance in metres",
        );
        self.num(
            "traffic.ego.route_margin_m",
            t.ego.route_margin_m,
            0.0,
            1000.0,
            "a distance in metres",
        );
        self.range(
            "traffic.ego.courtesy_speed_mps",
            t.ego.courtesy_speed_mps,
            0.0,
            40.0,
            "a speed in m/s",
        );
        self.num(
            "traffic.ego.courtesy_ahead_m",
            t.ego.courtesy_ahead_m,
            0.0,
            200.0,
            "a distance in metres",
        );
        self.num(
            "traffic.ego.courtesy_lateral_m",
            t.ego.courtesy_lateral_m,
            0.0,
            50.0,
            "a distance in metres",
        );
        self.num(
            "traffic.ego.courtesy_stop_short_m",
            t.ego.courtesy_stop_short_m,
            0.0,
            50.0,
            "a distance in metres",
        );
        self.range(
            "traffic.ego.courtesy_patience_s",
            t.ego.courtesy_patience_s,
            0.0,
            120.0,
            "a waiting time in seconds",
        );
        let g = &t.signals;
        self.probability("traffic.signals.crosswalk_share", g.crosswalk_share);
        self.positive("traffic.signals.green_s", g.green_s, 300.0, "a green time in seconds");
        self.num(
            "traffic.signals.amber_s",
            g.amber_s,
            0.0,
            30.0,
            "an amber time in seconds",
        );
        self.num(
            "traffic.signals.all_red_s",
            g.all_red_s,
            0.0,
            60.0,
            "an all-red time in seconds",
        );
        self.probability("traffic.parked_cars.share", t.parked_cars.share);
        let c = &t.cyclists;
        self.count_range(
            "traffic.cyclists.per_clip",
            c.per_clip,
            0,
            50,
            "a number of cyclists per clip",
        );
        self.range("traffic.cyclists.speed_mps", c.speed_mps, 0.5, 15.0, "a speed in m/s");
        self.num(
            "traffic.cyclists.edge_offset_m",
            c.edge_offset_m,
            0.3,
            3.0,
            "a distance from the lane's right edge in metres",
        );
        self.num(
            "traffic.cyclists.overtaking_clearance_m",
            c.overtaking_clearance_m,
            0.5,
            3.0,
            "a passing clearance in metres",
        );
        self.num(
            "traffic.cyclists.swerve_m",
            c.swerve_m,
            0.0,
            2.0,
            "a distance in metres",
        );
        self.probability(
            "traffic.cyclists.ignore_lights_probability",
            c.ignore_lights_probability,
        );
    }
}
