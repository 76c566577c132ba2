//! `pedsynth export pab-poses` / `pab-poses-jaad`: PedestrianActionBenchmark's pose files
//! (`poses/pose_setNN.pkl`, read by its unmodified `utils.get_pose`) for the PIE export's sets and videos, or
//! for the JAAD export (one `pose_set01.pkl`, the set `get_pose` reads for JAAD): `{video: {"<frame:05d>_<id>":
//! 36 floats}}`, OpenPose-18 joints in the benchmark's order (neck = mid-shoulder) from our keypoints, `x, y`
//! normalised within the pedestrian's box, and 0, 0 for a joint that is hidden or outside the box.

use std::collections::BTreeMap;
use std::path::Path;

use super::dataset::{AnnotatedFrame, Dataset};
use super::pie::{SETS, assign_videos, track_id};
use super::write_file;
use crate::error::{Error, code};
use crate::sensors::keypoints::push_keypoints;
use crate::spec::types::PoseFormat;

/// The 36 values of one pedestrian-frame.
pub fn pose36(f: &AnnotatedFrame) -> Vec<f64> {
    let mut op = Vec::with_capacity(54);
    match f.keypoints.len() {
        51 => {
            let mut coco = [0.0f32; 51];
            coco.copy_from_slice(&f.keypoints);
            push_keypoints(&coco, PoseFormat::Openpose18, true, &mut op);
        }
        54 => op.extend_from_slice(&f.keypoints),
        _ => return vec![0.0; 36],
    }
    let [x0, y0, x1, y1] = f.bbox_px.map(f64::from);
    let (w, h) = ((x1 - x0).max(1e-6), (y1 - y0).max(1e-6));
    let mut out = Vec::with_capacity(36);
    for j in op.chunks_exact(3) {
        let (x, y) = ((f64::from(j[0]) - x0) / w, (f64::from(j[1]) - y0) / h);
        if j[2] >= 2.0 && (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y) {
            out.extend([x, y]);
        } else {
            out.extend([0.0, 0.0]);
        }
    }
    out
}

/// What the export wrote.
#[derive(Debug, Default)]
pub struct PosesReport {
    pub files: usize,
    pub entries: usize,
    pub with_pose: usize,
}

/// Writes `out/poses/pose_setNN.pkl`: the six PIE sets, or JAAD's `set01`.
pub fn export(ds: &Dataset, out: &Path, jaad: bool) -> Result<PosesReport, Error> {
    // (set, video, id of each pedestrian) per clip, as the PIE or JAAD export names them.
    type Names = (String, String, Box<dyn Fn(u32) -> String>);
    let names: Vec<Names> = if jaad {
        super::jaad::assign_videos(&ds.clips)
            .into_iter()
            .map(|v| {
                let video = v.video.clone();
                let id: Box<dyn Fn(u32) -> String> = Box::new(move |p| super::jaad::track_id(&v, p));
                ("set01".to_owned(), video, id)
            })
            .collect()
    } else {
        assign_videos(&ds.clips)?
            .into_iter()
            .map(|v| {
                let (set, video) = (v.set.clone(), v.video.clone());
                let id: Box<dyn Fn(u32) -> String> = Box::new(move |p| track_id(&v, p));
                (set, video, id)
            })
            .collect()
    };
    let set_names: Vec<String> = if jaad {
        vec!["set01".to_owned()]
    } else {
        SETS.iter()
            .flat_map(|(_, sets)| sets.iter().map(|s| s.to_string()))
            .collect()
    };
    let dir = out.join("poses");
    std::fs::create_dir_all(&dir).map_err(|e| Error::write(&dir, e))?;
    let mut report = PosesReport::default();
    // One set at a time: a pickle is one object, so a set's poses are held until it is written.
    for set in &set_names {
        let mut videos: BTreeMap<String, BTreeMap<String, Vec<f64>>> = BTreeMap::new();
        for (info, (_, video, name)) in ds.clips.iter().zip(&names).filter(|(_, (s, _, _))| s == set) {
            let clip = ds.load(info)?;
            let entries = videos.entry(video.clone()).or_default();
            for p in clip.pedestrians.values() {
                let id = name(p.id);
                for f in &p.frames {
                    let pose = pose36(f);
                    report.entries += 1;
                    report.with_pose += usize::from(pose.iter().any(|&x| x != 0.0));
                    entries.insert(format!("{:05}_{id}", f.frame), pose);
                }
            }
        }
        let mut bytes = Vec::new();
        serde_pickle::to_writer(&mut bytes, &videos, serde_pickle::SerOptions::new())
            .map_err(|e| Error::new(code::INTERNAL_SERIALIZE, format!("pose_{set}.pkl: {e}")))?;
        write_file(&dir.join(format!("pose_{set}.pkl")), &bytes)?;
        report.files += 1;
    }
    Ok(report)
}
