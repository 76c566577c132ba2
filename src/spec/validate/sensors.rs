//! Validation of `sensors` (mounts, cameras, H.264 sizes, DVS, LiDAR) and `annotations`.

use super::*;

impl Validator<'_> {
    /// H.264 video (4:2:0, OpenH264): an even width and height, at most 3840 × 2160 (or 2160 × 3840).
    pub(super) fn h264_size(&mut self, rgb: &Rgb) {
        for (path, value) in [
            ("sensors.rgb.width_px", rgb.width_px),
            ("sensors.rgb.height_px", rgb.height_px),
        ] {
            if value % 2 != 0 {
                let problem = Problem::new(
                    code::OUT_OF_RANGE,
                    format!("`{path}` must be even for `output.rgb_encoding: h264`, found {value}"),
                )
                .at(self.span(path), "odd")
                .help(format!(
                    "H.264 stores colour at half resolution (4:2:0): use {} or {}, or another rgb_encoding",
                    value - 1,
                    value + 1
                ));
                self.problems.push(problem);
            }
        }
        let (long, short) = (rgb.width_px.max(rgb.height_px), rgb.width_px.min(rgb.height_px));
        if long > 3840 || short > 2160 {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!(
                    "an H.264 video can be at most 3840 × 2160, found {} × {}",
                    rgb.width_px, rgb.height_px
                ),
            )
            .at(self.span("sensors.rgb.width_px"), "too large for H.264")
            .help("OpenH264 encodes up to level 5.2: use png or jpeg for larger images");
            self.problems.push(problem);
        }
    }

    /// `sensors.rgb.mount_spread.pitch_quantiles_deg`: each within ±45°, ascending, at least two, and not
    /// together with a `pitch_deg` range.
    fn pitch_quantiles(&mut self, spread: &crate::spec::types::MountSpread) {
        let path = "sensors.rgb.mount_spread.pitch_quantiles_deg";
        let q = &spread.pitch_quantiles_deg;
        if q.is_empty() {
            return;
        }
        if q.len() == 1 {
            let problem = Problem::new(code::OUT_OF_RANGE, format!("`{path}` has one quantile"))
                .at(self.span(path), "one value")
                .help("give the lowest and the highest at least (or use `pitch_deg` for a uniform range)");
            self.problems.push(problem);
        }
        let before = self.problems.len();
        for (i, &v) in q.iter().enumerate() {
            self.num(&format!("{path}[{i}]"), v, -45.0, 45.0, "a pitch offset in degrees");
        }
        if self.problems.len() == before
            && let Some(i) = q.windows(2).position(|w| w[1] < w[0])
        {
            let problem = Problem::new(
                code::EMPTY_RANGE,
                format!("`{path}` falls from {} to {}", fmt_num(q[i]), fmt_num(q[i + 1])),
            )
            .at(self.span(&format!("{path}[{}]", i + 1)), "lower than the one before")
            .help("list the quantiles in ascending order, from the lowest to the highest");
            self.problems.push(problem);
        }
        if spread.pitch_deg != crate::spec::types::Range(0.0, 0.0) {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!("`{path}` and `sensors.rgb.mount_spread.pitch_deg` both give the pitch's spread"),
            )
            .at(self.span(path), "quantiles")
            .also(self.span("sensors.rgb.mount_spread.pitch_deg"), "range")
            .help("keep one: the quantiles of a measured distribution, or a uniform range");
            self.problems.push(problem);
        }
    }

    pub(super) fn mount(&mut self, base: &str, m: &Mount) {
        self.num(
            &format!("{base}.forward_m"),
            m.forward_m,
            -10.0,
            10.0,
            "a position in metres",
        );
        self.num(&format!("{base}.left_m"), m.left_m, -5.0, 5.0, "a position in metres");
        self.num(&format!("{base}.up_m"), m.up_m, 0.0, 10.0, "a height in metres");
        self.num(
            &format!("{base}.pitch_deg"),
            m.pitch_deg,
            -90.0,
            90.0,
            "an angle in degrees",
        );
        self.num(
            &format!("{base}.yaw_deg"),
            m.yaw_deg,
            -180.0,
            180.0,
            "an angle in degrees",
        );
        self.num(
            &format!("{base}.roll_deg"),
            m.roll_deg,
            -180.0,
            180.0,
            "an angle in degrees",
        );
    }

    /// `sensors.rgb.distortion`: coefficients in a real lens's range, and a lens that does not fold over inside
    /// the image (its radial map grows out to the image's corners, so every pixel sees one direction).
    fn distortion(&mut self, rgb: &Rgb) {
        let d = &rgb.distortion;
        let before = self.problems.len();
        for (key, value, bound) in [
            ("k1", d.k1, 2.0),
            ("k2", d.k2, 2.0),
            ("p1", d.p1, 0.2),
            ("p2", d.p2, 0.2),
            ("k3", d.k3, 2.0),
        ] {
            self.num(
                &format!("sensors.rgb.distortion.{key}"),
                value,
                -bound,
                bound,
                "an OpenCV distortion coefficient",
            );
        }
        let valid_size = rgb.width_px >= 1 && rgb.height_px >= 1 && rgb.fov_deg > 0.0 && rgb.fov_deg < 180.0;
        if self.problems.len() > before || d.is_zero() || !valid_size {
            return;
        }
        let lens = crate::util::lens::Lens::new(d.coefficients());
        let f = f64::from(rgb.width_px) / (2.0 * (rgb.fov_deg.to_radians() / 2.0).tan());
        let (x, y) = (f64::from(rgb.width_px) * 0.5 / f, f64::from(rgb.height_px) * 0.5 / f);
        // The renderer inverts the lens at every border pixel (its canvas covers their undistorted positions):
        // check the border, 2 % out for the canvas's margin, at 257 points an edge.
        let mut border = (0..=256).flat_map(|k| {
            let t = f64::from(k) / 128.0 - 1.0;
            [(t * x, y), (t * x, -y), (x, t * y), (-x, t * y)]
        });
        let folds = border.any(|(bx, by)| lens.undistort(bx * 1.02, by * 1.02).is_none());
        if folds {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!(
                    "`sensors.rgb.distortion` folds over inside the image: its radial map stops growing at {:.0}° off \
                     the axis, before the image's corners",
                    lens.valid_r2.sqrt().atan().to_degrees()
                ),
            )
            .at(self.span("sensors.rgb.distortion"), "this lens")
            .help("a real lens's calibration keeps k1 r² + k2 r⁴ + k3 r⁶ small over the image; check the signs and the order [k1, k2, p1, p2, k3]");
            self.problems.push(problem);
        }
    }

    /// `domain_randomisation`: ranges in what a light, a sun and a camera can be.
    pub(super) fn domain_randomisation(&mut self, d: &DomainRandomisation) {
        let base = "domain_randomisation";
        self.range(
            &format!("{base}.light_intensity"),
            d.light_intensity,
            0.05,
            20.0,
            "a factor on the light",
        );
        self.range(
            &format!("{base}.sun_azimuth_offset_deg"),
            d.sun_azimuth_offset_deg,
            -180.0,
            180.0,
            "an angle in degrees",
        );
        self.range(
            &format!("{base}.sun_altitude_offset_deg"),
            d.sun_altitude_offset_deg,
            -90.0,
            90.0,
            "an angle in degrees",
        );
        self.range(
            &format!("{base}.white_balance"),
            d.white_balance,
            0.2,
            5.0,
            "a gain per colour channel",
        );
        self.range(
            &format!("{base}.exposure_key"),
            d.exposure_key,
            0.05,
            20.0,
            "a factor on auto-exposure's key",
        );
        self.range(
            &format!("{base}.scenery_hue_deg"),
            d.scenery_hue_deg,
            -180.0,
            180.0,
            "an angle in degrees round the colour wheel",
        );
        self.range(
            &format!("{base}.scenery_saturation"),
            d.scenery_saturation,
            0.0,
            5.0,
            "a factor on colour saturation (0: grey)",
        );
        self.range(
            &format!("{base}.scenery_brightness"),
            d.scenery_brightness,
            0.05,
            5.0,
            "a factor on the scenery's albedo",
        );
        self.range(
            &format!("{base}.texture_contrast"),
            d.texture_contrast,
            0.0,
            5.0,
            "a factor on the textures' contrast (0: flat colours)",
        );
    }

    /// `sensors.rgb`'s exposure, vignetting, noise and motion blur.
    fn imaging(&mut self, rgb: &Rgb) {
        self.positive(
            "sensors.rgb.exposure.key",
            rgb.exposure.key,
            10.0,
            "a linear brightness (clear noon meters about 0.12)",
        );
        self.num(
            "sensors.rgb.exposure.max_gain",
            rgb.exposure.max_gain,
            1.0,
            1000.0,
            "a gain of at least 1",
        );
        self.num(
            "sensors.rgb.vignetting",
            rgb.vignetting,
            0.0,
            0.9,
            "a share of the light lost at the corners",
        );
        self.num(
            "sensors.rgb.noise.shot",
            rgb.noise.shot,
            0.0,
            1.0,
            "a standard deviation",
        );
        self.num(
            "sensors.rgb.noise.read",
            rgb.noise.read,
            0.0,
            1.0,
            "a standard deviation",
        );
        self.num(
            "sensors.rgb.motion_blur.shutter_ms",
            rgb.motion_blur.shutter_ms,
            0.0,
            1000.0,
            "a shutter time in milliseconds",
        );
        self.num(
            "sensors.rgb.motion_blur.max_shutter_ms",
            rgb.motion_blur.max_shutter_ms,
            0.0,
            1000.0,
            "a shutter time in milliseconds",
        );
        self.num(
            "sensors.rgb.motion_blur.samples",
            f64::from(rgb.motion_blur.samples),
            1.0,
            32.0,
            "a number of renders per frame",
        );
    }

    pub(super) fn sensors(&mut self, s: &Sensors) {
        self.num(
            "sensors.rgb.width_px",
            f64::from(s.rgb.width_px),
            16.0,
            16384.0,
            "an image width in pixels",
        );
        self.num(
            "sensors.rgb.height_px",
            f64::from(s.rgb.height_px),
            16.0,
            16384.0,
            "an image height in pixels",
        );
        self.num(
            "sensors.rgb.fov_deg",
            s.rgb.fov_deg,
            1.0,
            170.0,
            "a horizontal field of view in degrees",
        );
        self.mount("sensors.rgb.mount", &s.rgb.mount);
        let spread = &s.rgb.mount_spread;
        self.range(
            "sensors.rgb.mount_spread.up_m",
            spread.up_m,
            -5.0,
            5.0,
            "a height offset in metres",
        );
        if spread.up_m.min() > -5.0 && s.rgb.mount.up_m + spread.up_m.min() < 0.1 {
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!(
                    "`sensors.rgb.mount_spread.up_m` lowers the camera to {} m, below 0.1 m above the road",
                    fmt_num(s.rgb.mount.up_m + spread.up_m.min())
                ),
            )
            .at(self.span("sensors.rgb.mount_spread.up_m[0]"), "lowest offset")
            .help("keep `mount.up_m` + `mount_spread.up_m[0]` at 0.1 m or more");
            self.problems.push(problem);
        }
        self.range(
            "sensors.rgb.mount_spread.pitch_deg",
            spread.pitch_deg,
            -45.0,
            45.0,
            "a pitch offset in degrees",
        );
        self.pitch_quantiles(spread);
        self.distortion(&s.rgb);
        self.imaging(&s.rgb);
        let l = &s.lidar;
        self.num(
            "sensors.lidar.channels",
            f64::from(l.channels),
            1.0,
            256.0,
            "a number of laser channels",
        );
        self.positive("sensors.lidar.range_m", l.range_m, 1000.0, "a range in metres");
        self.num(
            "sensors.lidar.points_per_second",
            f64::from(l.points_per_second),
            1.0,
            10_000_000.0,
            "points per second",
        );
        self.positive(
            "sensors.lidar.rotation_hz",
            l.rotation_hz,
            100.0,
            "a rotation frequency in Hz",
        );
        self.num(
            "sensors.lidar.upper_fov_deg",
            l.upper_fov_deg,
            -90.0,
            90.0,
            "an elevation in degrees",
        );
        self.num(
            "sensors.lidar.lower_fov_deg",
            l.lower_fov_deg,
            -90.0,
            90.0,
            "an elevation in degrees",
        );
        if l.lower_fov_deg > l.upper_fov_deg {
            self.problems.push(
                Problem::new(
                    code::EMPTY_RANGE,
                    format!(
                        "`sensors.lidar.lower_fov_deg` ({}) is above `upper_fov_deg` ({})",
                        fmt_num(l.lower_fov_deg),
                        fmt_num(l.upper_fov_deg)
                    ),
                )
                .at(self.span("sensors.lidar.lower_fov_deg"), "lower")
                .also(self.span("sensors.lidar.upper_fov_deg"), "upper")
                .help("the bottom channel's elevation must not exceed the top channel's"),
            );
        }
        self.positive(
            "sensors.lidar.horizontal_fov_deg",
            l.horizontal_fov_deg,
            360.0,
            "an angle in degrees",
        );
        self.num(
            "sensors.lidar.atmosphere_attenuation_per_m",
            l.atmosphere_attenuation_per_m,
            0.0,
            1.0,
            "an attenuation rate per metre",
        );
        self.probability("sensors.lidar.dropoff_general_rate", l.dropoff_general_rate);
        self.probability("sensors.lidar.dropoff_intensity_limit", l.dropoff_intensity_limit);
        self.probability("sensors.lidar.dropoff_zero_intensity", l.dropoff_zero_intensity);
        self.num(
            "sensors.lidar.noise_stddev_m",
            l.noise_stddev_m,
            0.0,
            1.0,
            "a noise level in metres",
        );
        self.mount("sensors.lidar.mount", &l.mount);
        let d = &s.dvs;
        self.positive(
            "sensors.dvs.positive_threshold",
            d.positive_threshold,
            10.0,
            "a log-intensity contrast threshold",
        );
        self.positive(
            "sensors.dvs.negative_threshold",
            d.negative_threshold,
            10.0,
            "a log-intensity contrast threshold",
        );
        self.num(
            "sensors.dvs.sigma_positive_threshold",
            d.sigma_positive_threshold,
            0.0,
            10.0,
            "a standard deviation",
        );
        self.num(
            "sensors.dvs.sigma_negative_threshold",
            d.sigma_negative_threshold,
            0.0,
            10.0,
            "a standard deviation",
        );
        self.positive(
            "sensors.dvs.log_eps",
            d.log_eps,
            1.0,
            "an epsilon added before the logarithm",
        );
        self.num(
            "sensors.dvs.substeps",
            f64::from(d.substeps),
            1.0,
            16.0,
            "images rendered per frame interval",
        );
    }

    pub(super) fn annotations(&mut self, a: &Annotations) {
        let v = &a.visibility;
        if !v.require_in_front {
            let path = "annotations.visibility.require_in_front";
            let problem = Problem::new(
                code::OUT_OF_RANGE,
                format!("`{path}` must be true: stage 2 of the gate cannot be turned off"),
            )
            .at(self.span(path), "must be true")
            .help("a pedestrian behind the camera has no image box, so it is never annotated; remove the key");
            self.problems.push(problem);
        }
        self.positive(
            "annotations.visibility.max_distance_m",
            v.max_distance_m,
            1000.0,
            "a distance in metres",
        );
        self.box_size("annotations.visibility.min_box_px", v.min_box_px);
        self.positive(
            "annotations.visibility.far_distance_m",
            v.far_distance_m,
            1000.0,
            "a distance in metres",
        );
        self.box_size("annotations.visibility.min_box_far_px", v.min_box_far_px);
        self.probability("annotations.visibility.max_occlusion", v.max_occlusion);
        self.num(
            "annotations.crossing_label_smoothing_frames",
            f64::from(a.crossing_label_smoothing_frames),
            0.0,
            300.0,
            "a number of frames",
        );
        self.positive(
            "annotations.look_cone_deg",
            a.look_cone_deg,
            90.0,
            "the half-angle of the cone around the gaze in which the camera counts as looked at, degrees",
        );
        let b = &a.annotator_box;
        self.range(
            "annotations.annotator_box.margin_frac",
            b.margin_frac,
            0.0,
            1.0,
            "a margin as a fraction of the box height",
        );
        self.range(
            "annotations.annotator_box.min_aspect",
            b.min_aspect,
            0.0,
            2.0,
            "a width / height ratio",
        );
        self.num(
            "annotations.annotator_box.width_pad_px",
            b.width_pad_px,
            0.0,
            200.0,
            "pixels added to the narrowest box's width",
        );
        self.num(
            "annotations.annotator_box.noise_px",
            b.noise_px,
            0.0,
            100.0,
            "a noise in pixels",
        );
        self.count_range(
            "annotations.annotator_box.keyframe_every",
            b.keyframe_every,
            1,
            300,
            "frames between drawn keyframes",
        );
    }
}
