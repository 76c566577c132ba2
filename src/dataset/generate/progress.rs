//! Progress of a generate run (and of an export) on stderr: a bar on a terminal, plain lines otherwise, nothing when quiet. The
//! only place that reads the wall clock, and only for what it shows the user (never for what it writes).

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

/// Progress over the clips of one run.
pub(crate) struct Progress {
    bar: Option<indicatif::ProgressBar>,
    total: usize,
    done: AtomicUsize,
    frames: AtomicU64,
    started: Instant,
    /// Print a line every this many clips (plain output); None when quiet.
    every: Option<usize>,
    /// One JSON object per clip instead.
    json: bool,
}

impl Progress {
    /// Progress over `total` clips.
    pub(crate) fn new(total: usize, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(total as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} clips  {msg}  ETA {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        Progress {
            bar,
            total,
            done: AtomicUsize::new(0),
            frames: AtomicU64::new(0),
            started: Instant::now(),
            every: (!quiet).then_some((total / 20).max(1)),
            json: false,
        }
    }

    /// Progress as one JSON object per finished clip on stderr (`generate --progress json`).
    pub(crate) fn json(total: usize) -> Self {
        Progress {
            json: true,
            ..Progress::new(total, true)
        }
    }

    /// One clip of `frames` frames is done.
    pub(crate) fn clip_done(&self, clip_id: &str, frames: u64) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        let frames = self.frames.fetch_add(frames, Ordering::Relaxed) + frames;
        let secs = self.started.elapsed().as_secs_f64().max(1e-6);
        let rate = frames as f64 / secs;
        if self.json {
            let eta = secs / done as f64 * (self.total - done) as f64;
            let line = serde_json::json!({
                "event": "clip_done",
                "clip_id": clip_id,
                "done": done,
                "total": self.total,
                "frames": frames,
                "elapsed_s": (secs * 10.0).round() / 10.0,
                "frames_per_s": rate.round(),
                "eta_s": eta.round(),
            });
            eprintln!("{line}");
            return;
        }
        match &self.bar {
            Some(bar) => {
                bar.set_message(format!("{rate:.0} frames/s"));
                bar.inc(1);
            }
            None if self
                .every
                .is_some_and(|every| done.is_multiple_of(every) || done == self.total) =>
            {
                let eta = secs / done as f64 * (self.total - done) as f64;
                // Progress is best effort: a closed stderr must not fail the run.
                eprintln!(
                    "[{done}/{}] {clip_id} done ({rate:.0} frames/s, ETA {eta:.0} s)",
                    self.total
                );
            }
            None => {}
        }
    }

    /// Clears the bar.
    pub(crate) fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
