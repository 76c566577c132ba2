//! The executor: turns each clip script of a plan into files of the dataset, in three stages per clip:
//!
//! ```text
//! ClipScript ──simulate──▶ ClipTrace ──observe──▶ Observations ──write──▶ files under --out
//! ```
//!
//! - [`simulate`] — everything that moves: vehicles, the ego, pedestrians and their 12-state behaviour machine.
//! - [`realise`] — simulate and observe a clip, re-simulating with pedestrians promoted or demoted until it has
//!   its planned count of labelled crossers.
//! - [`trace`] — what the simulation produces (per-frame agent states and events).
//! - [`observe`] — pure functions of (script, trace, frame): sensor rig, bodies, annotations, the scene and
//!   the camera streams (handed to the writer frame by frame).
//! - [`write`] — the only code that touches the output directory: layout, tables, sensor files, manifest.
//! - [`generate`] — orchestration of `pedsynth generate`: clips in parallel, resume, progress.
//! - [`read`] — code that reads a written dataset (`pedsynth stats`), never re-simulating.
//! - [`export`] — `pedsynth export`: a written dataset in other tools' layouts (PIE, PedestrianActionBenchmark).

pub mod export;
pub mod generate;
pub mod observe;
pub mod read;
pub mod realise;
pub mod simulate;
pub mod trace;
pub mod write;

use crate::error::Error;
use crate::planner::{ClipScript, Plan, TownContext};

/// What one clip produced, for the run's report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClipCounts {
    /// Frames simulated.
    pub frames: u64,
    /// Pedestrian-frames simulated.
    pub pedestrian_frames: u64,
    /// Annotated samples written.
    pub samples: u64,
    /// Camera frames rendered.
    pub rendered_frames: u64,
}

/// Generates one clip: simulate, observe, write. Every file it writes is a pure function of (plan, clip).
pub fn run_clip(
    plan: &Plan,
    script: &ClipScript,
    town: &TownContext,
    rig: &observe::rig::Rig,
    out: &write::DatasetWriter,
) -> Result<ClipCounts, Error> {
    let realised = realise::realise(script, &plan.spec, &plan.sim, rig, &town.network);
    let (script, trace, observations) = (realised.script.as_ref(), &realised.trace, &realised.observations);
    let sensors = &plan.spec.sensors;
    let mut images = 0u64;
    let mut sensor_rows = Vec::new();
    if sensors.cameras_enabled() || sensors.lidar.enabled {
        let stat = observe::scene::StaticScene::build(script, trace, &town.network);
        // Cameras and LiDAR write disjoint files: side by side on the rayon pool (an idle worker takes one).
        let (cameras, lidar) = rayon::join(
            || -> Result<Vec<write::sensors::IndexRow>, Error> {
                if !sensors.cameras_enabled() {
                    return Ok(Vec::new());
                }
                let mut files = out.clip_sensors(plan, script)?;
                observe::render_cameras(&stat, script, trace, sensors, rig, |frame| {
                    images += 1;
                    files.frame(frame)
                })?;
                files.finish()
            },
            || -> Result<Vec<write::sensors::IndexRow>, Error> {
                if !sensors.lidar.enabled {
                    return Ok(Vec::new());
                }
                let mut files = out.clip_lidar(plan, script)?;
                observe::scan_lidar(&stat, script, trace, &sensors.lidar, rig, |tick| files.tick(tick))?;
                files.finish()
            },
        );
        sensor_rows.extend(cameras?);
        sensor_rows.extend(lidar?);
        write::sensors::sort_index(&mut sensor_rows);
    }
    out.write_clip(plan, script, trace, observations, rig, &sensor_rows)?;
    Ok(ClipCounts {
        frames: u64::from(script.frame_count),
        pedestrian_frames: u64::from(script.frame_count) * script.pedestrians.len() as u64,
        samples: observations.annotations.rows.len() as u64,
        rendered_frames: images,
    })
}
