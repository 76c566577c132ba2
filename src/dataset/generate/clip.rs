//! One clip of a dataset, from script to files, in three stages:
//!
//! ```text
//! ClipScript ──sim──▶ ClipTrace ──sensors──▶ Observations, frames, ticks ──write──▶ files under --out
//! ```
//!
//! [`run_clip`] realises the clip (`sensors::realise`: simulate and annotate, re-simulating with pedestrians
//! promoted or demoted until it has its planned count of labelled crossers), renders the cameras beside the
//! LiDAR on the rayon pool, and writes the clip through [`DatasetWriter`](crate::dataset::crate::dataset::write::DatasetWriter).

use crate::error::Error;
use crate::plan::{ClipScript, Plan, TownContext};

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
    rig: &crate::sim::rig::Rig,
    out: &crate::dataset::write::DatasetWriter,
) -> Result<ClipCounts, Error> {
    let realised = crate::sensors::realise::realise(script, &plan.spec, &plan.sim, rig, &town.network);
    let (script, trace, observations) = (realised.script.as_ref(), &realised.trace, &realised.observations);
    let sensors = &plan.spec.sensors;
    let mut images = 0u64;
    let mut sensor_rows = Vec::new();
    if sensors.cameras_enabled() || sensors.lidar.enabled {
        // The scenery the annotations placed and tested against, drawn as it is.
        let scenery = &observations.annotations.scenery;
        let stat = crate::sensors::scene::StaticScene::build(script, trace, &town.network, scenery);
        // Cameras and LiDAR write disjoint files: side by side on the rayon pool (an idle worker takes one).
        let (cameras, lidar) = rayon::join(
            || -> Result<Vec<crate::dataset::write::sensors::IndexRow>, Error> {
                if !sensors.cameras_enabled() {
                    return Ok(Vec::new());
                }
                let mut files = out.clip_sensors(plan, script)?;
                crate::sensors::render_cameras(&stat, script, trace, sensors, rig, |frame| {
                    images += 1;
                    files.frame(frame)
                })?;
                files.finish()
            },
            || -> Result<Vec<crate::dataset::write::sensors::IndexRow>, Error> {
                if !sensors.lidar.enabled {
                    return Ok(Vec::new());
                }
                let mut files = out.clip_lidar(plan, script)?;
                crate::sensors::scan_lidar(&stat, script, trace, &sensors.lidar, rig, |tick| files.tick(tick))?;
                files.finish()
            },
        );
        sensor_rows.extend(cameras?);
        sensor_rows.extend(lidar?);
        crate::dataset::write::sensors::sort_index(&mut sensor_rows);
    }
    out.write_clip(plan, script, trace, observations, rig, &sensor_rows)?;
    Ok(ClipCounts {
        frames: u64::from(script.frame_count),
        pedestrian_frames: u64::from(script.frame_count) * script.pedestrians.len() as u64,
        samples: observations.annotations.rows.len() as u64,
        rendered_frames: images,
    })
}
