//! `pedsynth export seed-csv`: the seed system's CSV layout (../shared/reference/seed-system-facts.md, "Its
//! output layout") for scripts written against it, without its defects: one row per annotated
//! pedestrian-frame (never duplicated), every annotated pedestrian present, labels constant within a track
//! where the seed's changed, and frame ids that match the images.
//!
//! Per clip, `<weather>/<town>/<clip_id>/`: `labels.csv` (the seed's columns, then `pose_x_i, pose_y_i,
//! pose_conf_i` for the 17 COCO joints), `pedestrians_3d.csv`, `ego_pose.csv` and the RGB frames
//! (`000000.png`, linked); per weather `<weather>/labels.csv` and for the dataset `labels.csv`, the combined
//! rows.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::dataset::{Clip, Dataset};
use super::{LinkMode, link_frames, write_file};
use crate::error::Error;
use crate::util::files::AtomicFile;

/// The seed's `labels.csv` columns, before the pose columns.
pub const LABEL_COLUMNS: [&str; 12] = [
    "video_id",
    "frame_id",
    "pedestrian_id",
    "bbox_x_min",
    "bbox_y_min",
    "bbox_x_max",
    "bbox_y_max",
    "crossing",
    "crossing_point",
    "behavior_type",
    "distance_to_ego",
    "visible",
];

fn label_header() -> String {
    let mut h = LABEL_COLUMNS.join(",");
    for i in 0..17 {
        let _ = write!(h, ",pose_x_{i},pose_y_{i},pose_conf_{i}");
    }
    h.push('\n');
    h
}

/// A clip's `labels.csv` rows (no header), in (frame, pedestrian) order.
fn label_rows(clip: &Clip) -> String {
    let mut rows: Vec<(u32, u32, String)> = Vec::new();
    for p in clip.pedestrians.values() {
        for f in &p.frames {
            let b = f.bbox_px;
            let mut r = format!(
                "{},{},{},{:.2},{:.2},{:.2},{:.2},{},{},{},{:.3},1",
                clip.clip_id,
                f.frame,
                p.id,
                b[0],
                b[1],
                b[2],
                b[3],
                u8::from(f.crossing),
                p.first_crossing_frame.map_or(-1, i64::from),
                p.behaviour,
                f.distance_to_ego_m,
            );
            // COCO-17 as written (the OpenPose-18 option's neck is dropped): u, v, confidence = flag / 2.
            let coco: Vec<f32> = if f.keypoints.len() == 54 {
                crate::sensors::keypoints::OPENPOSE18_FROM_COCO17
                    .iter()
                    .zip(f.keypoints.chunks_exact(3))
                    .filter_map(|(c, j)| c.map(|c| (c, j)))
                    .fold(vec![0.0; 51], |mut out, (c, j)| {
                        out[3 * c..3 * c + 3].copy_from_slice(j);
                        out
                    })
            } else {
                f.keypoints.clone()
            };
            for j in coco.chunks_exact(3) {
                let _ = write!(r, ",{:.2},{:.2},{}", j[0], j[1], j[2] / 2.0);
            }
            r.push('\n');
            rows.push((f.frame, p.id, r));
        }
    }
    rows.sort_by_key(|(frame, id, _)| (*frame, *id));
    rows.into_iter().map(|(_, _, r)| r).collect()
}

fn pedestrians_3d(clip: &Clip) -> String {
    let mut rows: Vec<(u32, u32, String)> = Vec::new();
    for p in clip.pedestrians.values() {
        for f in &p.frames {
            let b = f.box3d_m;
            rows.push((
                f.frame,
                p.id,
                format!(
                    "{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.4}\n",
                    clip.clip_id, f.frame, p.id, b[0], b[1], b[2], b[3], b[4], b[5], f.yaw_rad
                ),
            ));
        }
    }
    rows.sort_by_key(|(frame, id, _)| (*frame, *id));
    let mut out = String::from("video_id,frame_id,pedestrian_id,center_x,center_y,center_z,size_x,size_y,size_z,yaw\n");
    out.extend(rows.into_iter().map(|(_, _, r)| r));
    out
}

fn ego_pose(clip: &Clip) -> String {
    let mut out = String::from("video_id,frame_id,timestamp_ns,x,y,z,yaw,speed_mps,accel_mps2\n");
    for (i, e) in clip.ego.iter().enumerate() {
        let t_ns = i as u64 * 1_000_000_000 / u64::from(clip.fps.max(1));
        let _ = writeln!(
            out,
            "{},{i},{t_ns},{:.4},{:.4},{:.4},{:.5},{:.4},{:.4}",
            clip.clip_id, e.x_m, e.y_m, e.z_m, e.yaw_rad, e.speed_mps, e.accel_mps2
        );
    }
    out
}

/// What the export wrote.
#[derive(Debug, Default)]
pub struct SeedReport {
    pub clips: usize,
    pub rows: usize,
    pub images: usize,
    pub images_note: String,
}

/// Writes the seed's layout of `ds` into `out`.
pub fn export(ds: &Dataset, out: &Path, link: LinkMode) -> Result<SeedReport, Error> {
    let (rgb_files, mut images_note) = super::images_note(ds, link);
    if rgb_files == super::RgbFiles::Mp4 {
        images_note = "images absent: the RGB stream is H.264 video and the seed's layout holds PNG frames; \
                       annotations only"
            .to_owned();
    }
    let png_images = rgb_files == super::RgbFiles::Png;
    let mut report = SeedReport {
        clips: ds.clips.len(),
        images_note,
        ..SeedReport::default()
    };
    let header = label_header();
    // The combined files are written as the clips go (an export holds one clip at a time), each under a
    // temporary name until the last clip is in.
    let combined = |path: &Path| -> Result<AtomicFile, Error> {
        let mut f = AtomicFile::create(path).map_err(|e| Error::write(path, e))?;
        f.write_all(header.as_bytes()).map_err(|e| Error::write(path, e))?;
        Ok(f)
    };
    let all_path = out.join("labels.csv");
    let mut all = combined(&all_path)?;
    let mut weathers: BTreeMap<String, (std::path::PathBuf, AtomicFile)> = BTreeMap::new();
    let progress = super::progress(ds.clips.len());
    for info in &ds.clips {
        let clip = &ds.load(info)?;
        let dir = out.join(&clip.weather).join(&clip.town).join(&clip.clip_id);
        let rows = label_rows(clip);
        report.rows += rows.lines().count();
        write_file(&dir.join("labels.csv"), format!("{header}{rows}").as_bytes())?;
        write_file(&dir.join("pedestrians_3d.csv"), pedestrians_3d(clip).as_bytes())?;
        write_file(&dir.join("ego_pose.csv"), ego_pose(clip).as_bytes())?;
        if !weathers.contains_key(&clip.weather) {
            let path = out.join(&clip.weather).join("labels.csv");
            let file = combined(&path)?;
            weathers.insert(clip.weather.clone(), (path, file));
        }
        if let Some((path, file)) = weathers.get_mut(&clip.weather) {
            file.write_all(rows.as_bytes()).map_err(|e| Error::write(path, e))?;
        }
        all.write_all(rows.as_bytes()).map_err(|e| Error::write(&all_path, e))?;
        if png_images {
            report.images += link_frames(ds, clip, &dir, 6, link)?;
        }
        progress.clip_done(&clip.clip_id, u64::from(clip.frame_count));
    }
    progress.finish();
    for (path, file) in weathers.into_values() {
        file.commit().map_err(|e| Error::write(&path, e))?;
    }
    all.commit().map_err(|e| Error::write(&all_path, e))?;
    Ok(report)
}
