//! Dry-run statistics of a plan: what the dataset will contain before anything is simulated, as a stable JSON
//! value and as human-readable tables (`pedsynth plan`).

use std::collections::BTreeMap;

use serde::Serialize;

use super::script::{Behaviour, CrosserSource, Plan, Role};
use crate::spec::types::{RgbEncoding, Spec};

// Table-size constants measured on `specs/pedsynth_pp.yaml` (600 clips: 1,701,362 pedestrian-frames, 581,588
// annotated samples; `du -sb out/tables/*`), zstd level 3.
/// Share of pedestrian-frames that pass the visibility gate (measured: 0.342).
pub const EXPECTED_VISIBLE_SHARE: f64 = 0.342;
/// Bytes per `annotations` row (box, 2 × 17×3 keypoints, state, 3D state) (measured: 420).
pub const ANNOTATION_ROW_BYTES: f64 = 420.0;
/// Bytes per `frames` row (measured: 40.5).
pub const FRAME_ROW_BYTES: f64 = 40.5;
/// Bytes per `vehicles` row (measured: 14.5).
pub const VEHICLE_ROW_BYTES: f64 = 14.5;
/// Bytes per `tracks` row (every pedestrian in every frame: position, velocity, state, C, lane; measured on
/// `specs/pedsynth_pp.yaml` on 2026-11-24: 24,169,932 bytes for 2,939,923 rows = 8.2).
pub const TRACK_ROW_BYTES: f64 = 8.2;
/// Bytes per clip of the one-row `clips` table: mostly Parquet metadata (measured: 8,500).
pub const CLIP_FILE_BYTES: f64 = 8_500.0;
/// Bytes per pedestrian of the `pedestrians` table (measured: 924).
pub const PEDESTRIAN_ROW_BYTES: f64 = 924.0;
/// Bytes of the `events` table per pedestrian (measured: 570).
pub const EVENT_BYTES_PER_PEDESTRIAN: f64 = 570.0;
/// Bytes per pixel of each camera stream's file, measured on `specs/quickstart.yaml` at 1280 × 720
/// (BENCHMARKS.md, "Cameras": 364, 35, 18 and 12 kB per frame): RGB PNG (fast compression), depth (u16 PNG),
/// semantic (indexed PNG), instance (u16 PNG).
pub const RGB_PNG_BYTES_PER_PIXEL: f64 = 0.395;
/// RGB as JPEG (`jpeg_quality` 90) and as H.264 (`h264_qp` 20), measured the same way (BENCHMARKS.md,
/// "Cameras"); other qualities scale these roughly.
pub const RGB_JPEG_BYTES_PER_PIXEL: f64 = 0.144;
/// See [`RGB_JPEG_BYTES_PER_PIXEL`].
pub const RGB_H264_BYTES_PER_PIXEL: f64 = 0.016;
/// See [`RGB_PNG_BYTES_PER_PIXEL`].
pub const DEPTH_PNG_BYTES_PER_PIXEL: f64 = 0.038;
/// See [`RGB_PNG_BYTES_PER_PIXEL`].
pub const SEMANTIC_PNG_BYTES_PER_PIXEL: f64 = 0.019;
/// See [`RGB_PNG_BYTES_PER_PIXEL`].
pub const INSTANCE_PNG_BYTES_PER_PIXEL: f64 = 0.013;
/// CPU time to render, encode and write all camera streams of one frame, per pixel, release build (thin LTO):
/// 124.2 CPU-s for 1,070 frames of 1280 × 720 with the LiDAR, less its 10.4 CPU-s (BENCHMARKS.md, "Cameras").
pub const CAMERA_CPU_S_PER_PIXEL: f64 = 1.15e-7;
/// Bytes of the LiDAR Parquet (zstd) per expected point (`pps / fps × (1 − general drop-off)` per frame: rays
/// that hit nothing and the intensity drop-off are in the figure), measured on `specs/quickstart.yaml`:
/// 157.2 MB for 1,070 frames (BENCHMARKS.md, "LiDAR").
pub const LIDAR_POINT_BYTES: f64 = 8.0;
/// CPU time of the LiDAR per ray of the pattern (trace, drop-off, encode, write), release build: 10.4 CPU-s
/// for 1,070 frames of 33,344 rays (BENCHMARKS.md, "LiDAR").
pub const LIDAR_CPU_S_PER_RAY: f64 = 2.9e-7;
/// Bytes of the `sensor_poses` table per sensor and frame.
pub const SENSOR_POSE_ROW_BYTES: f64 = 23.5;
/// Bytes of DVS events (Parquet, zstd) per pixel and frame, measured on `specs/quickstart.yaml` (BENCHMARKS.md,
/// "Cameras": 101 kB per frame of 1280 × 720).
pub const DVS_BYTES_PER_PIXEL: f64 = 0.11;

/// Pedestrian-frames simulated, annotated and written per CPU-second by `pedsynth generate` (annotation tables
/// only), release build: 2,939,923 pedestrian-frames of `specs/pedsynth_pp.yaml` in 32.6 CPU-seconds
/// (BENCHMARKS.md, "Generation", with the pre-crossing timeline).
pub const GENERATION_PEDESTRIAN_FRAMES_PER_CPU_S: f64 = 90_000.0;

/// Clips in one (town, weather) cell.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellStats {
    /// Town.
    pub town: String,
    /// Weather.
    pub weather: String,
    /// Clips.
    pub clips: usize,
}

/// Counts per split.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SplitStats {
    /// Clips.
    pub clips: usize,
    /// Frames.
    pub frames: u64,
    /// Pedestrians.
    pub pedestrians: usize,
    /// Planned crossers.
    pub crossers: usize,
}

/// The baseline the planner used instead of the spec's, for a target below what the spec's baseline gives.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AdaptedBaseline {
    /// The spec's `crossing.baseline_ratio`.
    pub spec_ratio: f64,
    /// The share of pedestrians planned as baseline crossers.
    pub used_ratio: f64,
}

/// Group statistics.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GroupStats {
    /// Number of groups.
    pub groups: usize,
    /// Pedestrians in a group.
    pub grouped_pedestrians: usize,
    /// Groups of two.
    pub pairs: usize,
    /// Groups of three.
    pub triples: usize,
}

/// Estimated output size.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SizeEstimate {
    /// Bytes per annotation table.
    pub tables: BTreeMap<String, u64>,
    /// Bytes per sensor (enabled sensors only).
    pub sensors: BTreeMap<String, u64>,
    /// Total bytes.
    pub total: u64,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Dry-run statistics of a plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlanStats {
    /// Dataset name.
    pub dataset: String,
    /// Spec hash.
    pub spec_hash: String,
    /// Clips.
    pub clips: usize,
    /// Clips per (town, weather).
    pub cells: Vec<CellStats>,
    /// Frames.
    pub frames: u64,
    /// Mean frames per clip.
    pub mean_frames_per_clip: f64,
    /// Total duration, seconds.
    pub duration_s: f64,
    /// Pedestrians.
    pub pedestrians: usize,
    /// Planned crossers.
    pub crossers: usize,
    /// Planned crossers by source (layer-1 allocation or baseline).
    pub crossers_by_source: BTreeMap<String, usize>,
    /// Planned sequence-level crossing ratio.
    pub planned_crossing_ratio: f64,
    /// Pedestrians the clips' counts of labelled crossers add up to (`ClipScript::labelled_crossers`, which the
    /// executor meets by promoting and demoting pedestrians); 0 when the clips set none (layer 1 off).
    pub labelled_crossers: usize,
    /// Expected share of pedestrians labelled crossers in the dataset: the clips' counts of labelled crossers
    /// over the pedestrians where they set them, else planned crossers × the measured realisation
    /// (`calibration::CROSSER_REALISATION`).
    pub expected_crossing_ratio: f64,
    /// One standard deviation of the labelled crossing ratio around `expected_crossing_ratio`: with counts per
    /// clip, their measured misses (`calibration::LABELLED_COUNT_MISS_VARIANCE` per clip with a planned
    /// crosser); else each planned crosser's outcome (binomial) and the realisation's spread between specs
    /// (`calibration::CROSSER_REALISATION_SPREAD`).
    pub expected_crossing_ratio_sd: f64,
    /// The baseline the planner used when it lowered the spec's `baseline_ratio` to meet a low target (else
    /// none).
    pub adapted_baseline: Option<AdaptedBaseline>,
    /// How the planner adapted the crossing layers to a target above what the spec's layers reach (else none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapted_layers: Option<super::CrossingAdaptation>,
    /// Target crossing ratio.
    pub target_crossing_ratio: f64,
    /// Pedestrians per archetype.
    pub archetypes: BTreeMap<String, usize>,
    /// Pedestrians per behaviour type.
    pub behaviours: BTreeMap<String, usize>,
    /// Groups.
    pub groups: GroupStats,
    /// Pedestrians per initial speed profile.
    pub speed_profiles: BTreeMap<String, usize>,
    /// Traffic vehicles.
    pub vehicles: usize,
    /// Vehicles per driving profile (emergency vehicles not counted).
    pub driving_profiles: BTreeMap<String, usize>,
    /// Clips with an emergency vehicle, per kind (`traffic.emergency`).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub emergency_clips: BTreeMap<String, usize>,
    /// Cyclists (`traffic.cyclists`).
    #[serde(skip_serializing_if = "is_zero")]
    pub cyclists: usize,
    /// Pedestrian-frames (every pedestrian in every frame).
    pub pedestrian_frames: u64,
    /// Estimated annotated samples (pedestrian-frames that pass the visibility gate).
    pub estimated_annotated_samples: u64,
    /// Estimated output size.
    pub estimated_bytes: SizeEstimate,
    /// Estimated generation time on one core, seconds (simulation, annotation tables and camera streams).
    pub estimated_generation_cpu_s: f64,
    /// Counts per split.
    pub splits: BTreeMap<String, SplitStats>,
    /// The crossers' pre-crossing timelines.
    pub timeline: TimelineStats,
}

/// The crossers' pre-crossing timelines and what they do to clip lengths.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TimelineStats {
    /// Crossers with a timeline (all but mid-road jaywalkers).
    pub crossers: usize,
    /// Planned time in view before crossing: median, seconds.
    pub median_in_view_s: f64,
    /// Planned share of those crossers in view for at least 2.53 s (76 frames at 30 FPS, the benchmark's
    /// shortest usable track).
    pub share_at_least_76_frames: f64,
    /// Clips lengthened beyond their drawn duration so that their crossers' timelines fit.
    pub lengthened_clips: usize,
    /// Mean lengthening of those clips, seconds.
    pub mean_lengthening_s: f64,
    /// Clips longer than `dataset.clip_duration_s`'s maximum (only where `dataset.max_extension_s` allows).
    pub clips_beyond_duration_range: usize,
    /// The longest clip, seconds.
    pub longest_clip_s: f64,
    /// The longest a clip may be: `clip_duration_s`'s maximum plus `max_extension_s`, seconds.
    pub duration_bound_s: f64,
}

fn round(x: f64, digits: i32) -> f64 {
    let f = 10f64.powi(digits);
    (x * f).round() / f
}

/// Computes the statistics of `plan` made from `spec`.
pub fn compute(plan: &Plan, spec: &Spec) -> PlanStats {
    let mut cells: BTreeMap<(String, String), usize> = BTreeMap::new();
    let mut in_view: Vec<f64> = Vec::new();
    // Whether the clips set counts of labelled crossers, and how many of those have a planned crosser.
    let (mut counts_set, mut counted_clips) = (false, 0usize);
    let mut lengthening_s = 0.0;
    let mut stats = PlanStats {
        dataset: plan.dataset.clone(),
        spec_hash: plan.spec_hash.clone(),
        clips: plan.clips.len(),
        cells: Vec::new(),
        frames: 0,
        mean_frames_per_clip: 0.0,
        duration_s: 0.0,
        pedestrians: 0,
        crossers: 0,
        crossers_by_source: BTreeMap::new(),
        planned_crossing_ratio: 0.0,
        labelled_crossers: 0,
        expected_crossing_ratio: 0.0,
        expected_crossing_ratio_sd: 0.0,
        adapted_baseline: super::adapted_baseline(spec).map(|(spec_ratio, used)| AdaptedBaseline {
            spec_ratio,
            used_ratio: round(used, 4),
        }),
        adapted_layers: super::crossing_adaptation(spec),
        target_crossing_ratio: plan.target_crossing_ratio,
        archetypes: spec.pedestrians.archetype_mix.keys().map(|k| (k.clone(), 0)).collect(),
        behaviours: Behaviour::ALL.iter().map(|b| (b.name().to_owned(), 0)).collect(),
        groups: GroupStats::default(),
        speed_profiles: super::script::SpeedProfile::ALL
            .iter()
            .map(|s| (s.name().to_owned(), 0))
            .collect(),
        vehicles: 0,
        driving_profiles: super::script::DrivingProfileKind::ALL
            .iter()
            .map(|p| (p.name().to_owned(), 0))
            .collect(),
        emergency_clips: BTreeMap::new(),
        cyclists: 0,
        pedestrian_frames: 0,
        estimated_annotated_samples: 0,
        estimated_bytes: SizeEstimate::default(),
        estimated_generation_cpu_s: 0.0,
        splits: BTreeMap::new(),
        timeline: TimelineStats::default(),
    };
    let mut vehicle_frames = 0u64;
    for clip in &plan.clips {
        *cells.entry((clip.town.clone(), clip.weather.clone())).or_default() += 1;
        let frames = u64::from(clip.frame_count);
        stats.frames += frames;
        stats.duration_s += clip.duration_s();
        stats.pedestrians += clip.pedestrians.len();
        stats.pedestrian_frames += frames * clip.pedestrians.len() as u64;
        stats.vehicles += clip.vehicles.len();
        vehicle_frames += frames * clip.vehicles.len() as u64;
        let split = stats
            .splits
            .entry(format!("{:?}", clip.split).to_lowercase())
            .or_default();
        split.clips += 1;
        split.frames += frames;
        split.pedestrians += clip.pedestrians.len();
        let mut groups: BTreeMap<u32, usize> = BTreeMap::new();
        for p in &clip.pedestrians {
            *stats.archetypes.entry(p.archetype.clone()).or_default() += 1;
            *stats.behaviours.entry(p.behaviour.name().to_owned()).or_default() += 1;
            *stats
                .speed_profiles
                .entry(p.speed_profile.name().to_owned())
                .or_default() += 1;
            if p.role == Role::Crosser {
                stats.crossers += 1;
                split.crossers += 1;
                let source = if p.crosser_source == CrosserSource::Baseline {
                    "baseline"
                } else {
                    "allocated"
                };
                *stats.crossers_by_source.entry(source.to_owned()).or_default() += 1;
            }
            if let Some(g) = p.group {
                *groups.entry(g.group_id).or_default() += 1;
            }
        }
        for size in groups.values() {
            stats.groups.groups += 1;
            stats.groups.grouped_pedestrians += size;
            match size {
                2 => stats.groups.pairs += 1,
                3 => stats.groups.triples += 1,
                _ => {}
            }
        }
        for v in &clip.vehicles {
            match v.emergency {
                Some(kind) => *stats.emergency_clips.entry(kind.name().to_owned()).or_default() += 1,
                None => *stats.driving_profiles.entry(v.profile.name().to_owned()).or_default() += 1,
            }
        }
        stats.cyclists += clip.cyclists.len();
        in_view.extend(clip.pedestrians.iter().filter_map(|p| p.in_view_before_crossing_s));
        if let Some(k) = clip.labelled_crossers {
            stats.labelled_crossers += k as usize;
            counts_set = true;
            // A clip without a planned crosser has nothing to miss (it labels none and promotes none).
            if clip.pedestrians.iter().any(|p| p.role == Role::Crosser) {
                counted_clips += 1;
            }
        }
        let clip_s = f64::from(clip.frame_count) / f64::from(clip.fps.max(1));
        stats.timeline.longest_clip_s = stats.timeline.longest_clip_s.max(round(clip_s, 3));
        if clip_s > spec.dataset.clip_duration_s.max() + 1e-9 {
            stats.timeline.clips_beyond_duration_range += 1;
        }
        if clip.timeline_extension_s > 0.0 {
            stats.timeline.lengthened_clips += 1;
            lengthening_s += clip.timeline_extension_s;
        }
    }
    stats.timeline.duration_bound_s = round(spec.dataset.clip_duration_s.max() + spec.dataset.max_extension_s, 3);
    in_view.sort_by(f64::total_cmp);
    stats.timeline.crossers = in_view.len();
    if !in_view.is_empty() {
        stats.timeline.median_in_view_s = round(in_view[in_view.len() / 2], 2);
        let long = in_view.iter().filter(|&&t| t * 30.0 >= 76.0).count();
        stats.timeline.share_at_least_76_frames = round(long as f64 / in_view.len() as f64, 3);
    }
    if stats.timeline.lengthened_clips > 0 {
        stats.timeline.mean_lengthening_s = round(lengthening_s / stats.timeline.lengthened_clips as f64, 2);
    }
    stats.cells = cells
        .into_iter()
        .map(|((town, weather), clips)| CellStats { town, weather, clips })
        .collect();
    stats.duration_s = round(stats.duration_s, 3);
    if stats.clips > 0 {
        stats.mean_frames_per_clip = round(stats.frames as f64 / stats.clips as f64, 1);
    }
    if stats.pedestrians > 0 {
        stats.planned_crossing_ratio = round(stats.crossers as f64 / stats.pedestrians as f64, 4);
        // Allocated and baseline crossers alike end up labelled at the measured realisation (the planner
        // allocates on that assumption).
        let (realisation, spread) = crate::plan::calibration::crosser_realisation(spec);
        let realisation = super::crossing_adaptation(spec).map_or(realisation, |a| a.realisation);
        let crossers = stats.crossers as f64;
        let (expected, variance) = if counts_set {
            (
                stats.labelled_crossers as f64,
                counted_clips as f64 * crate::plan::calibration::LABELLED_COUNT_MISS_VARIANCE,
            )
        } else {
            (
                crossers * realisation,
                crossers * realisation * (1.0 - realisation) + (crossers * spread).powi(2),
            )
        };
        stats.expected_crossing_ratio = round(expected / stats.pedestrians as f64, 4);
        stats.expected_crossing_ratio_sd = round(variance.sqrt() / stats.pedestrians as f64, 4);
    }
    stats.estimated_annotated_samples = (stats.pedestrian_frames as f64 * EXPECTED_VISIBLE_SHARE).round() as u64;
    stats.estimated_bytes = estimate_bytes(&stats, spec, vehicle_frames);
    let s = &spec.sensors;
    let camera_pixels = if s.cameras_enabled() {
        f64::from(s.rgb.width_px) * f64::from(s.rgb.height_px)
    } else {
        0.0
    };
    let lidar_rays = if s.lidar.enabled {
        (f64::from(s.lidar.points_per_second) / f64::from(spec.dataset.fps.max(1)) / f64::from(s.lidar.channels.max(1)))
            .round()
            * f64::from(s.lidar.channels)
    } else {
        0.0
    };
    stats.estimated_generation_cpu_s = round(
        stats.pedestrian_frames as f64 / GENERATION_PEDESTRIAN_FRAMES_PER_CPU_S
            + stats.frames as f64 * camera_pixels * CAMERA_CPU_S_PER_PIXEL
            + stats.frames as f64 * lidar_rays * LIDAR_CPU_S_PER_RAY,
        1,
    );
    stats
}

fn estimate_bytes(stats: &PlanStats, spec: &Spec, vehicle_frames: u64) -> SizeEstimate {
    let mut e = SizeEstimate::default();
    let frames = stats.frames as f64;
    e.tables.insert(
        "annotations".into(),
        (stats.estimated_annotated_samples as f64 * ANNOTATION_ROW_BYTES) as u64,
    );
    e.tables.insert("frames".into(), (frames * FRAME_ROW_BYTES) as u64);
    e.tables.insert(
        "tracks".into(),
        (stats.pedestrian_frames as f64 * TRACK_ROW_BYTES) as u64,
    );
    e.tables
        .insert("vehicles".into(), (vehicle_frames as f64 * VEHICLE_ROW_BYTES) as u64);
    e.tables.insert(
        "pedestrians".into(),
        (stats.pedestrians as f64 * PEDESTRIAN_ROW_BYTES) as u64,
    );
    e.tables
        .insert("clips".into(), (stats.clips as f64 * CLIP_FILE_BYTES) as u64);
    let sensors_posed = if spec.sensors.lidar.enabled { 2.0 } else { 1.0 };
    e.tables.insert(
        "sensor_poses".into(),
        (stats.frames as f64 * sensors_posed * SENSOR_POSE_ROW_BYTES) as u64,
    );
    e.tables.insert(
        "events".into(),
        (stats.pedestrians as f64 * EVENT_BYTES_PER_PEDESTRIAN) as u64,
    );
    let s = &spec.sensors;
    let pixels = f64::from(s.rgb.width_px) * f64::from(s.rgb.height_px);
    let rgb_bytes_per_pixel = match spec.output.rgb_encoding {
        RgbEncoding::Png => RGB_PNG_BYTES_PER_PIXEL,
        RgbEncoding::Jpeg => RGB_JPEG_BYTES_PER_PIXEL,
        RgbEncoding::H264 => RGB_H264_BYTES_PER_PIXEL,
    };
    for (stream, on, bytes_per_pixel) in [
        ("rgb", s.rgb.enabled, rgb_bytes_per_pixel),
        ("depth", s.depth.enabled, DEPTH_PNG_BYTES_PER_PIXEL),
        ("semantic", s.semantic.enabled, SEMANTIC_PNG_BYTES_PER_PIXEL),
        ("instance", s.instance.enabled, INSTANCE_PNG_BYTES_PER_PIXEL),
        ("dvs", s.dvs.enabled, DVS_BYTES_PER_PIXEL),
    ] {
        if on {
            e.sensors
                .insert(stream.into(), (frames * pixels * bytes_per_pixel) as u64);
        }
    }
    if s.lidar.enabled {
        let per_frame = f64::from(s.lidar.points_per_second) / f64::from(spec.dataset.fps.max(1))
            * (1.0 - s.lidar.dropoff_general_rate);
        e.sensors
            .insert("lidar".into(), (frames * per_frame * LIDAR_POINT_BYTES) as u64);
    }
    e.total = e.tables.values().sum::<u64>() + e.sensors.values().sum::<u64>();
    e
}

/// Bytes as a short human-readable figure.
pub fn human_bytes(bytes: u64) -> String {
    let units = ["B", "kB", "MB", "GB", "TB"];
    let mut x = bytes as f64;
    let mut unit = 0;
    while x >= 1000.0 && unit + 1 < units.len() {
        x /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{x:.1} {}", units[unit])
    }
}

fn share(n: usize, total: usize) -> String {
    if total == 0 {
        "-".to_owned()
    } else {
        format!("{:5.1}%", 100.0 * n as f64 / total as f64)
    }
}

/// The statistics as human-readable tables.
impl std::fmt::Display for PlanStats {
    fn fmt(&self, out: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let stats = self;
        writeln!(
            out,
            "plan for dataset `{}` (spec {})",
            stats.dataset,
            &stats.spec_hash[..stats.spec_hash.len().min(12)]
        )?;
        writeln!(out)?;
        // Clips per town × weather.
        let towns: Vec<&str> = {
            let mut t: Vec<&str> = stats.cells.iter().map(|c| c.town.as_str()).collect();
            t.dedup();
            t.sort();
            t.dedup();
            t
        };
        let mut weathers: Vec<&str> = stats.cells.iter().map(|c| c.weather.as_str()).collect();
        weathers.sort();
        weathers.dedup();
        let width = towns.iter().map(|t| t.len()).max().unwrap_or(4).max(5);
        write!(out, "clips per town × weather\n{:width$}", "")?;
        for w in &weathers {
            write!(out, " {:>w$}", w, w = w.len().max(4))?;
        }
        writeln!(out, " {:>5}", "total")?;
        for t in &towns {
            write!(out, "{t:width$}")?;
            let mut total = 0;
            for w in &weathers {
                let n = stats
                    .cells
                    .iter()
                    .find(|c| c.town == *t && c.weather == *w)
                    .map_or(0, |c| c.clips);
                total += n;
                write!(out, " {:>w$}", n, w = w.len().max(4))?;
            }
            writeln!(out, " {total:>5}")?;
        }
        writeln!(out)?;
        writeln!(out, "clips                 {}", stats.clips)?;
        writeln!(
            out,
            "frames                {} ({:.1} per clip, {:.1} s in all)",
            stats.frames, stats.mean_frames_per_clip, stats.duration_s
        )?;
        writeln!(out, "pedestrians           {}", stats.pedestrians)?;
        writeln!(
            out,
            "planned crossers      {} (allocated {}, baseline {})",
            stats.crossers,
            stats.crossers_by_source.get("allocated").copied().unwrap_or(0),
            stats.crossers_by_source.get("baseline").copied().unwrap_or(0)
        )?;
        writeln!(
            out,
            "planned crossing ratio {:.3}: expected labelled crossing ratio {:.3} ± {:.3} (1 s.d.; target {:.3})",
            stats.planned_crossing_ratio,
            stats.expected_crossing_ratio,
            stats.expected_crossing_ratio_sd,
            stats.target_crossing_ratio
        )?;
        if stats.labelled_crossers > 0 {
            writeln!(
                out,
                "labelled crossers     {} planned, clip by clip: generate promotes or demotes pedestrians until each clip has its count",
                stats.labelled_crossers
            )?;
        }
        if let Some(a) = &stats.adapted_layers {
            writeln!(
                out,
                "note: the target is above what the spec's crossing layers reach, so the planner adapted them: up to {:.0} % of the pedestrians crossers, crossing groups at probability {:.3}, {:.3} of the crossers starting mid-road (expected realisation {:.3})",
                100.0 * a.max_crosser_ratio,
                a.group_probability,
                a.midroad_share,
                a.realisation
            )?;
        }
        if let Some(b) = &stats.adapted_baseline {
            writeln!(
                out,
                "note: baseline crossers planned at {:.3} of the pedestrians, not the spec's crossing.baseline_ratio {:.3}, which alone would overshoot the target",
                b.used_ratio, b.spec_ratio
            )?;
        }
        writeln!(out, "vehicles              {}", stats.vehicles)?;
        if !stats.emergency_clips.is_empty() {
            let kinds: Vec<String> = stats.emergency_clips.iter().map(|(k, n)| format!("{k} {n}")).collect();
            writeln!(
                out,
                "emergency clips       {} ({})",
                stats.emergency_clips.values().sum::<usize>(),
                kinds.join(", ")
            )?;
        }
        if stats.cyclists > 0 {
            writeln!(out, "cyclists              {}", stats.cyclists)?;
        }
        writeln!(
            out,
            "pedestrian-frames     {} (≈ {} annotated samples)",
            stats.pedestrian_frames, stats.estimated_annotated_samples
        )?;
        for (title, map, total) in [
            ("archetypes", &stats.archetypes, stats.pedestrians),
            ("behaviours", &stats.behaviours, stats.pedestrians),
            ("speed profiles", &stats.speed_profiles, stats.pedestrians),
            ("driving profiles", &stats.driving_profiles, stats.vehicles),
        ] {
            writeln!(out, "\n{title}")?;
            for (k, v) in map {
                writeln!(out, "  {k:<20} {v:>7} {}", share(*v, total))?;
            }
        }
        let g = &stats.groups;
        writeln!(
            out,
            "\ngroups\n  {} groups ({} pairs, {} triples), {} grouped pedestrians",
            g.groups, g.pairs, g.triples, g.grouped_pedestrians
        )?;
        let t = &stats.timeline;
        writeln!(
            out,
            "\ncrossing timeline\n  {} crossers step out after a planned time in view of the ego's camera: median {:.1} s, {:.0}% at least 76 frames\n  {} clips lengthened for their crossers' timelines (mean +{:.1} s); longest clip {:.1} s, {} beyond `dataset.clip_duration_s` (bound {:.1} s: its maximum plus `dataset.max_extension_s`)",
            t.crossers,
            t.median_in_view_s,
            100.0 * t.share_at_least_76_frames,
            t.lengthened_clips,
            t.mean_lengthening_s,
            t.longest_clip_s,
            t.clips_beyond_duration_range,
            t.duration_bound_s
        )?;
        writeln!(out, "\nsplits")?;
        for (name, s) in &stats.splits {
            writeln!(
                out,
                "  {name:<6} {:>6} clips {:>9} frames {:>7} pedestrians {:>7} crossers",
                s.clips, s.frames, s.pedestrians, s.crossers
            )?;
        }
        writeln!(
            out,
            "\nestimated generation time {:.1} s on one core, {:.1} s on two",
            stats.estimated_generation_cpu_s,
            stats.estimated_generation_cpu_s / 2.0
        )?;
        writeln!(
            out,
            "\nestimated output size (total {})",
            human_bytes(stats.estimated_bytes.total)
        )?;
        for (k, v) in &stats.estimated_bytes.tables {
            writeln!(out, "  table  {k:<12} {:>10}", human_bytes(*v))?;
        }
        for (k, v) in &stats.estimated_bytes.sensors {
            writeln!(out, "  sensor {k:<12} {:>10}", human_bytes(*v))?;
        }
        Ok(())
    }
}
