//! What the sensor benchmarks share: the first clip of `specs/quickstart.yaml` (with `--set` overrides), its
//! simulation, and its busiest annotated frame (most annotated pedestrians, earliest on ties).
#![allow(dead_code)]

use std::path::Path;

use pedsynth::plan::ClipScript;
use pedsynth::sensors;
use pedsynth::sensors::camera::{CameraImages, Renderer, streak_seed};
use pedsynth::sensors::scene::{FrameScene, SceneTime, StaticScene, ego_at};
use pedsynth::sim;
use pedsynth::sim::rig::CameraPose;
use pedsynth::sim::rig::Rig;
use pedsynth::sim::trace::ClipTrace;
use pedsynth::spec::LoadOptions;
use pedsynth::spec::types::Sensors;
use pedsynth::world::RoadNetwork;

/// A simulated clip and its busiest annotated frame.
pub struct BusyClip {
    pub script: ClipScript,
    pub trace: ClipTrace,
    pub rig: Rig,
    pub sensors: Sensors,
    pub net: RoadNetwork,
    pub scene: StaticScene,
    pub frame: u32,
}

/// The first quickstart clip under `overrides`, simulated, with its static scene and busiest frame.
pub fn busy_quickstart_clip(overrides: &[String]) -> BusyClip {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let options = LoadOptions {
        overrides: overrides.to_vec(),
        allow_large: false,
        profile: None,
    };
    let (_, towns, plan) = pedsynth::dataset::inputs::plan_spec_file(&path, &options).expect("quickstart plans");
    let script = plan.clips[0].clone();
    let net = towns[&script.town].network.clone();
    let trace = sim::simulate(&script, &plan.sim, &net);
    let rig = Rig::for_clip(&plan.spec.sensors, script.seed);
    let ann = sensors::observe(&script, &trace, &plan.spec, &rig, &net).annotations;
    let mut counts = vec![0u32; trace.frame_count as usize];
    for r in &ann.rows {
        counts[r.frame as usize] += 1;
    }
    let frame = (0..counts.len())
        .max_by_key(|&f| (counts[f], std::cmp::Reverse(f)))
        .unwrap_or(0) as u32;
    let scene = StaticScene::build(&script, &trace, &net, &ann.scenery);
    BusyClip {
        script,
        trace,
        rig,
        sensors: plan.spec.sensors.clone(),
        net,
        scene,
        frame,
    }
}

impl BusyClip {
    /// The scene of frame `frame` and the camera's pose in it.
    pub fn camera_frame(&self, frame: u32) -> (FrameScene, CameraPose) {
        let t = SceneTime::at(frame);
        let mut scene = FrameScene::default();
        scene.build(&self.scene, &self.script, &self.trace, t);
        let (pos, yaw, pitch) = ego_at(&self.trace, t);
        (scene, self.rig.camera.at(pos, yaw, pitch))
    }

    /// A renderer with the clip's lighting, set up for its busiest frame.
    pub fn busy_render(&self) -> BusyRender {
        let (frame, pose) = self.camera_frame(self.frame);
        BusyRender {
            // Exposed as the clip is (auto-exposure's gain is in the tone curve's table: no cost per frame).
            renderer: pedsynth::sensors::clip_renderer(&self.scene, &self.script, &self.trace, &self.rig),
            frame,
            pose,
            img: CameraImages::default(),
        }
    }

    /// Renders the busiest frame (on the current rayon pool).
    pub fn render_busy(&self, r: &mut BusyRender) {
        let seed = streak_seed(self.script.seed, self.frame, 0);
        r.renderer.render(&self.scene, &r.frame, &r.pose, seed, &mut r.img);
    }
}

/// A renderer for the busiest frame of a clip, with that frame's scene, the camera pose and the images.
pub struct BusyRender {
    pub renderer: Renderer,
    pub frame: FrameScene,
    pub pose: CameraPose,
    pub img: CameraImages,
}
