//! `pedsynth stats --protocol pab`: how many tracks and observation windows PedestrianActionBenchmark's sampling
//! (Kotseruba et al., WACV 2021; `../shared/interfaces/pedestrian_action_benchmark`) gets from a dataset, per
//! class and split, computed from the written tables only.
//!
//! The protocol, as the benchmark's code applies it to PIE and JAAD (`seq_type: crossing`):
//! - a **track** is a pedestrian's annotated frames in order, up to and including its **event**: the first
//!   annotated frame with C = 1 for a crosser (PIE's `crossing_point`), the last annotated frame otherwise;
//!   its class is the sequence label (crossing / not crossing);
//! - a track is **eligible** when it has at least `min_track` frames (the benchmark sets it to
//!   `obs_length + time_to_event[1]`, 76 frames);
//! - an eligible track gives the windows of `obs_length` frames that end `time_to_event` frames before the
//!   event, from the earliest to the latest, every `max(1, int((1 − overlap) · obs_length))` frames: windows
//!   start at index `len − obs − tte_max`, …, `len − obs − tte_min` of the track.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::tables;
use crate::dataset::write::Layout;
use crate::error::{Error, code};

/// The benchmark's sampling options.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PabOptions {
    /// Frames observed per window (`obs_length`).
    pub obs_length: usize,
    /// Frames from a window's end to the event: `[min, max]` (`time_to_event`).
    pub tte_frames: (usize, usize),
    /// Overlap of consecutive windows (`overlap`: 0.6 for PIE, 0.8 for JAAD).
    pub overlap: f64,
    /// Shortest eligible track, frames (`min_track_size`).
    pub min_track: usize,
}

impl Default for PabOptions {
    /// The benchmark's defaults (`configs_default.yaml`, PIE).
    fn default() -> Self {
        PabOptions {
            obs_length: 16,
            tte_frames: (30, 60),
            overlap: 0.6,
            min_track: 76,
        }
    }
}

impl PabOptions {
    /// The stride between consecutive windows, frames: `max(1, int((1 − overlap) · obs_length))`, with the
    /// benchmark's float arithmetic.
    pub fn stride(&self) -> usize {
        (((1.0 - self.overlap) * self.obs_length as f64) as usize).max(1)
    }

    /// Windows per eligible track.
    pub fn windows_per_track(&self) -> usize {
        (self.tte_frames.1 - self.tte_frames.0) / self.stride() + 1
    }

    /// Checks the options: the benchmark's sampling is only defined on tracks long enough for every window.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |why: String| Err(Error::new(code::PROTOCOL_OPTIONS, why));
        if self.obs_length == 0 {
            return bad("--obs-length must be at least 1".into());
        }
        if self.tte_frames.0 > self.tte_frames.1 {
            return bad(format!(
                "--tte {},{}: the first value must not exceed the second",
                self.tte_frames.0, self.tte_frames.1
            ));
        }
        if !(0.0..1.0).contains(&self.overlap) {
            return bad(format!("--overlap {} must be in [0, 1)", self.overlap));
        }
        let needed = self.obs_length + self.tte_frames.1;
        if self.min_track < needed {
            return bad(format!(
                "--min-track {} is shorter than obs length + largest TTE ({needed}): the benchmark's windows would \
                 start before the track",
                self.min_track
            ));
        }
        Ok(())
    }
}

/// Tracks and windows of one class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ClassCounts {
    /// Pedestrians with at least one annotated frame.
    pub tracks: u64,
    /// Tracks of at least `min_track` frames up to their event.
    pub eligible_tracks: u64,
    /// Observation windows.
    pub windows: u64,
}

/// Both classes of one split.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SplitProtocol {
    /// Crossers (sequence label 1).
    pub crossing: ClassCounts,
    /// Non-crossers.
    pub not_crossing: ClassCounts,
    /// Share of windows of class crossing.
    pub window_crossing_share: f64,
}

/// The protocol's figures for a dataset.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PabStats {
    /// The sampling options.
    pub options: PabOptions,
    /// Window stride, frames.
    pub stride: usize,
    /// Per split.
    pub splits: BTreeMap<String, SplitProtocol>,
    /// All splits.
    pub all: SplitProtocol,
    /// The dataset's target (sequence-level) crossing ratio, from the manifest.
    pub target_crossing_ratio: Option<f64>,
}

/// A pedestrian's track: its annotated frames' crossing labels in frame order.
#[derive(Default)]
struct Track {
    crosser: bool,
    /// (frame, C) of each annotated frame.
    frames: Vec<(u32, bool)>,
}

impl Track {
    /// Frames up to and including the event.
    fn length_to_event(&mut self) -> usize {
        self.frames.sort_unstable();
        if self.crosser {
            self.frames.iter().position(|f| f.1).map_or(0, |k| k + 1)
        } else {
            self.frames.len()
        }
    }
}

/// Computes the protocol's figures for the dataset in `dir`.
pub fn compute(dir: &Path, options: &PabOptions) -> Result<PabStats, Error> {
    options.validate()?;
    let layout = Layout::new(dir);
    let target_crossing_ratio = std::fs::read_to_string(layout.manifest())
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|m| m["target_crossing_ratio"].as_f64());
    let mut stats = PabStats {
        options: *options,
        stride: options.stride(),
        splits: BTreeMap::new(),
        all: SplitProtocol::default(),
        target_crossing_ratio,
    };
    for path in tables::files(&layout, "clips")? {
        let clip_id = path
            .file_stem()
            .map(|x| x.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut split = String::new();
        for b in tables::read(&path, &["split"])? {
            if let Some(s) = b.strings("split")?.first() {
                split = (*s).to_owned();
            }
        }
        let mut tracks: BTreeMap<u32, Track> = BTreeMap::new();
        for b in tables::read(&layout.table("pedestrians", &clip_id), &["pedestrian", "crosser"])? {
            let (ids, crossers) = (b.u32s("pedestrian")?, b.bools("crosser")?);
            for i in 0..b.rows() {
                tracks.entry(ids.value(i)).or_default().crosser = crossers.value(i);
            }
        }
        for b in tables::read(
            &layout.table("annotations", &clip_id),
            &["pedestrian", "frame", "crossing"],
        )? {
            let (ids, frames, crossing) = (b.u32s("pedestrian")?, b.u32s("frame")?, b.bools("crossing")?);
            for i in 0..b.rows() {
                tracks
                    .entry(ids.value(i))
                    .or_default()
                    .frames
                    .push((frames.value(i), crossing.value(i)));
            }
        }
        let counts = stats.splits.entry(split).or_default();
        for track in tracks.values_mut() {
            if track.frames.is_empty() {
                continue;
            }
            let length = track.length_to_event();
            let class = if track.crosser {
                &mut counts.crossing
            } else {
                &mut counts.not_crossing
            };
            class.tracks += 1;
            if length >= options.min_track {
                class.eligible_tracks += 1;
                class.windows += options.windows_per_track() as u64;
            }
        }
    }
    for split in stats.splits.values_mut() {
        split.window_crossing_share = share(split.crossing.windows, split.not_crossing.windows);
        for (all, one) in [
            (&mut stats.all.crossing, split.crossing),
            (&mut stats.all.not_crossing, split.not_crossing),
        ] {
            all.tracks += one.tracks;
            all.eligible_tracks += one.eligible_tracks;
            all.windows += one.windows;
        }
    }
    stats.all.window_crossing_share = share(stats.all.crossing.windows, stats.all.not_crossing.windows);
    Ok(stats)
}

fn share(crossing: u64, not_crossing: u64) -> f64 {
    let total = crossing + not_crossing;
    if total == 0 {
        0.0
    } else {
        crossing as f64 / total as f64
    }
}

impl std::fmt::Display for PabStats {
    fn fmt(&self, out: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let o = &self.options;
        writeln!(
            out,
            "PedestrianActionBenchmark protocol: obs {} frames, time to event {}–{} frames, overlap {} (stride {}), \
             tracks of at least {} frames up to the event",
            o.obs_length, o.tte_frames.0, o.tte_frames.1, o.overlap, self.stride, o.min_track
        )?;
        writeln!(
            out,
            "\n  split  class          tracks  eligible   windows  window share"
        )?;
        let rows = self
            .splits
            .iter()
            .map(|(k, v)| (k.as_str(), v))
            .chain([("all", &self.all)]);
        for (name, s) in rows {
            writeln!(
                out,
                "  {name:<6} {:<13} {:>7} {:>9} {:>9}",
                "crossing", s.crossing.tracks, s.crossing.eligible_tracks, s.crossing.windows
            )?;
            let c = s.not_crossing;
            writeln!(
                out,
                "  {:<6} {:<13} {:>7} {:>9} {:>9}  {:>12.3}",
                "", "not_crossing", c.tracks, c.eligible_tracks, c.windows, s.window_crossing_share
            )?;
        }
        match self.target_crossing_ratio {
            Some(t) => writeln!(
                out,
                "\nwindow-level crossing share {:.3} (target {t:.3}, {:+.1} pp)",
                self.all.window_crossing_share,
                100.0 * (self.all.window_crossing_share - t)
            ),
            None => writeln!(
                out,
                "\nwindow-level crossing share {:.3}",
                self.all.window_crossing_share
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_follow_the_benchmark_arithmetic() {
        let pie = PabOptions::default();
        assert_eq!(pie.stride(), 6, "int(0.4 * 16) = int(6.4)");
        assert_eq!(pie.windows_per_track(), 6, "range(start, start + 30 + 1, 6)");
        let jaad = PabOptions { overlap: 0.8, ..pie };
        assert_eq!(
            jaad.stride(),
            3,
            "int(0.19999999999999996 * 16) = int(3.1999999999999993)"
        );
        assert_eq!(jaad.windows_per_track(), 11);
        let single = PabOptions {
            tte_frames: (30, 30),
            min_track: 46,
            ..pie
        };
        assert_eq!(single.windows_per_track(), 1);
        assert!(PabOptions { min_track: 75, ..pie }.validate().is_err());
        assert!(PabOptions { overlap: 1.0, ..pie }.validate().is_err());
    }

    #[test]
    fn a_track_ends_at_its_event() {
        let mut crosser = Track {
            crosser: true,
            frames: vec![(5, false), (3, false), (9, true), (7, false), (11, true)],
        };
        assert_eq!(
            crosser.length_to_event(),
            4,
            "frames 3, 5, 7 and the first C = 1 frame, 9"
        );
        let mut walker = Track {
            crosser: false,
            frames: vec![(1, false), (2, false)],
        };
        assert_eq!(walker.length_to_event(), 2);
    }
}
