//! `pedsynth export coco`: COCO's object-detection, keypoint and instance-segmentation layout, as
//! pycocotools, detectron2, mmdetection, torchvision and FiftyOne read it.
//!
//! `annotations/<split>.json` per split (`images`, `annotations`, `categories`, `info`, `licenses`) and
//! `images/<clip_id>/<frame:06>.png` (linked from `sensors/rgb`). One image per RGB frame (frames without
//! pedestrians included: they are the detector's negatives); one annotation per annotated pedestrian-frame and
//! per annotated cyclist-frame. Boxes are `[x, y, width, height]` from the box `annotations.export_box`
//! chooses; keypoints are COCO-17 with COCO's flags (0 not in the image, 1 occluded, 2 visible); masks are
//! COCO's compressed RLE of the instance image's pixels of that instance, and `area` is their count. Our own
//! fields ride along in keys COCO readers ignore. An H.264 dataset is refused (no frames to link): generate
//! with PNG RGB, or decode the MP4s first.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::dataset::{Clip, Dataset};
use super::{LinkMode, link_file, write_file};
use crate::error::{Error, code};
use crate::sensors::keypoints::{COCO17, OPENPOSE18_FROM_COCO17};

/// COCO's person skeleton (1-based keypoint indices, as in `person_keypoints_*.json`).
pub const SKELETON: [[u8; 2]; 19] = [
    [16, 14],
    [14, 12],
    [17, 15],
    [15, 13],
    [12, 13],
    [6, 12],
    [7, 13],
    [6, 7],
    [6, 8],
    [7, 9],
    [8, 10],
    [9, 11],
    [2, 3],
    [1, 2],
    [1, 3],
    [2, 4],
    [3, 5],
    [4, 6],
    [5, 7],
];

/// Category ids.
pub const PEDESTRIAN: u32 = 1;
pub const CYCLIST: u32 = 2;

/// Instance ids in the instance stream (DATASET.md, "Sensor streams").
const PEDESTRIAN_BASE: u32 = 1;
const CYCLIST_BASE: u32 = 49152;

/// What an export wrote.
#[derive(Debug, Default)]
pub struct CocoReport {
    /// Annotation files (one per split).
    pub files: usize,
    pub images: usize,
    pub annotations: usize,
    /// Annotations with a mask.
    pub masks: usize,
    pub images_note: String,
}

#[derive(Serialize)]
struct Info {
    description: String,
    version: String,
    contributor: &'static str,
    url: &'static str,
}

#[derive(Serialize)]
struct Category {
    id: u32,
    name: &'static str,
    supercategory: &'static str,
    keypoints: [&'static str; 17],
    skeleton: [[u8; 2]; 19],
}

#[derive(Serialize)]
struct Image {
    id: u64,
    file_name: String,
    width: u32,
    height: u32,
    // Ours: COCO readers ignore them.
    clip_id: String,
    frame: u32,
    town: String,
    weather: String,
}

#[derive(Serialize)]
struct Rle {
    size: [u32; 2],
    counts: String,
}

#[derive(Serialize)]
struct Annotation {
    id: u64,
    image_id: u64,
    category_id: u32,
    bbox: [f32; 4],
    area: f64,
    iscrowd: u8,
    #[serde(skip_serializing_if = "Option::is_none")]
    segmentation: Option<Rle>,
    keypoints: Vec<f32>,
    num_keypoints: u32,
    // Ours: COCO readers ignore them.
    /// Unique over the file: one per (clip, pedestrian) or (clip, cyclist).
    track_id: u64,
    /// The `pedestrian` or `cyclist` id within the clip.
    instance: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    crossing: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    behaviour_state: Option<String>,
    /// Frames until the first crossing frame (null after it and for pedestrians that never cross).
    #[serde(skip_serializing_if = "Option::is_none")]
    tte_frames: Option<Option<u32>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    occlusion: Option<f32>,
}

#[derive(Serialize)]
struct File {
    info: Info,
    licenses: [(); 0],
    images: Vec<Image>,
    annotations: Vec<Annotation>,
    categories: Vec<Category>,
}

fn refuse(msg: String) -> Error {
    Error::new(code::DATASET_INVALID, msg)
}

/// Writes the COCO layout of `ds` into `out`.
pub fn export(ds: &Dataset, out: &Path, link: LinkMode) -> Result<CocoReport, Error> {
    let frames = super::image_frames(ds, link, "COCO")?;
    let with_images = frames.is_some();
    let (ext, images_note) = frames.unwrap_or_else(|| ("png", super::images_note(ds, link).1));
    let with_masks = ds
        .manifest
        .sensors
        .get("instance")
        .is_some_and(|s| s.starts_with("rendered"));
    let with_cyclists = ds.spec.traffic.cyclists.per_clip.1 > 0;
    let (width, height) = (ds.spec.sensors.rgb.width_px, ds.spec.sensors.rgb.height_px);
    let mut categories = vec![category(PEDESTRIAN, "pedestrian")];
    if with_cyclists {
        categories.push(category(CYCLIST, "cyclist"));
    }
    let mut splits: BTreeMap<&str, Vec<&super::dataset::ClipInfo>> = BTreeMap::new();
    for info in &ds.clips {
        splits.entry(info.split.as_str()).or_default().push(info);
    }
    let mut report = CocoReport {
        images_note: if with_masks {
            images_note
        } else {
            format!("{images_note}; no masks (the dataset has no instance stream)")
        },
        ..CocoReport::default()
    };
    let progress = super::progress(ds.clips.len());
    for (split, clips) in splits {
        let mut file = File {
            info: Info {
                description: format!("{} ({split} split), exported by pedsynth", ds.spec.dataset.name),
                version: ds.manifest.pedsynth_version.clone(),
                contributor: "pedsynth",
                url: "",
            },
            licenses: [],
            images: Vec::new(),
            annotations: Vec::new(),
            categories: categories.iter().map(|c| category(c.id, c.name)).collect(),
        };
        let mut next_track = 1;
        for info in clips {
            let clip = ds.load(info)?;
            let tracks = FrameAnnotations::of(&clip, with_cyclists, &mut next_track);
            for frame in 0..clip.frame_count {
                let from = ds.layout.sensor_frame("rgb", &clip.clip_id, frame, ext);
                if with_images {
                    if !from.exists() {
                        continue;
                    }
                    let to = out.join("images").join(&clip.clip_id).join(format!("{frame:06}.{ext}"));
                    if let Some(dir) = to.parent() {
                        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
                    }
                    link_file(&from, &to, link)?;
                }
                let image_id = file.images.len() as u64 + 1;
                file.images.push(Image {
                    id: image_id,
                    file_name: format!("{}/{frame:06}.{ext}", clip.clip_id),
                    width,
                    height,
                    clip_id: clip.clip_id.clone(),
                    frame,
                    town: clip.town.clone(),
                    weather: clip.weather.clone(),
                });
                let wanted = tracks.in_frame(frame);
                if wanted.is_empty() {
                    continue;
                }
                let masks = if with_masks {
                    let ids: Vec<u32> = wanted.iter().map(|a| a.instance_id).collect();
                    Some(instance_masks(
                        &ds.layout.sensor_frame("instance", &clip.clip_id, frame, "png"),
                        &ids,
                    )?)
                } else {
                    None
                };
                let mut masks = masks.map(Vec::into_iter);
                for a in wanted {
                    let [x0, y0, x1, y1] = a.bbox_px;
                    let bbox = [x0, y0, x1 - x0, y1 - y0];
                    let (segmentation, area) = match masks.as_mut().and_then(Iterator::next) {
                        Some((rle, area)) => {
                            report.masks += 1;
                            (Some(rle), area as f64)
                        }
                        None => (None, f64::from(bbox[2]) * f64::from(bbox[3])),
                    };
                    let (keypoints, num_keypoints) = coco_keypoints(&a.keypoints);
                    file.annotations.push(Annotation {
                        id: file.annotations.len() as u64 + 1,
                        image_id,
                        category_id: a.category,
                        bbox,
                        area,
                        iscrowd: 0,
                        segmentation,
                        keypoints,
                        num_keypoints,
                        track_id: a.track_id,
                        instance: a.instance,
                        crossing: a.crossing,
                        behaviour_state: a.state.clone(),
                        tte_frames: (a.category == PEDESTRIAN).then_some(a.tte_frames),
                        occlusion: a.occlusion,
                    });
                }
            }
            progress.clip_done(&clip.clip_id, u64::from(clip.frame_count));
        }
        let bytes = serde_json::to_vec(&file).map_err(|e| refuse(format!("COCO JSON: {e}")))?;
        write_file(&out.join("annotations").join(format!("{split}.json")), &bytes)?;
        report.files += 1;
        report.images += file.images.len();
        report.annotations += file.annotations.len();
    }
    progress.finish();
    Ok(report)
}

fn category(id: u32, name: &'static str) -> Category {
    Category {
        id,
        name,
        supercategory: "person",
        keypoints: COCO17,
        skeleton: SKELETON,
    }
}

/// One instance to annotate in one frame.
struct Wanted {
    category: u32,
    instance: u32,
    instance_id: u32,
    track_id: u64,
    bbox_px: [f32; 4],
    keypoints: Vec<f32>,
    crossing: Option<bool>,
    state: Option<String>,
    tte_frames: Option<u32>,
    occlusion: Option<f32>,
}

/// A clip's annotations by frame, pedestrians first (by id), then cyclists (by id).
struct FrameAnnotations {
    by_frame: BTreeMap<u32, Vec<Wanted>>,
}

impl FrameAnnotations {
    fn of(clip: &Clip, with_cyclists: bool, next_track: &mut u64) -> FrameAnnotations {
        let mut by_frame: BTreeMap<u32, Vec<Wanted>> = BTreeMap::new();
        for p in clip.pedestrians.values() {
            if p.frames.is_empty() {
                continue;
            }
            let track_id = *next_track;
            *next_track += 1;
            for f in &p.frames {
                by_frame.entry(f.frame).or_default().push(Wanted {
                    category: PEDESTRIAN,
                    instance: p.id,
                    instance_id: PEDESTRIAN_BASE + p.id,
                    track_id,
                    bbox_px: f.bbox_px,
                    keypoints: f.keypoints.clone(),
                    crossing: Some(f.crossing),
                    state: Some(f.state.clone()),
                    tte_frames: p.first_crossing_frame.and_then(|c| c.checked_sub(f.frame)),
                    occlusion: Some(f.occlusion),
                });
            }
        }
        if with_cyclists {
            let mut track_of: BTreeMap<u32, u64> = BTreeMap::new();
            for c in &clip.cyclists {
                let (true, Some(b)) = (c.annotated, c.bbox) else {
                    continue;
                };
                let track_id = *track_of.entry(c.cyclist).or_insert_with(|| {
                    *next_track += 1;
                    *next_track - 1
                });
                by_frame.entry(c.frame).or_default().push(Wanted {
                    category: CYCLIST,
                    instance: c.cyclist,
                    instance_id: CYCLIST_BASE + c.cyclist,
                    track_id,
                    bbox_px: b.map(|v| v as f32),
                    keypoints: c.keypoints.clone(),
                    crossing: None,
                    state: None,
                    tte_frames: None,
                    occlusion: None,
                });
            }
        }
        FrameAnnotations { by_frame }
    }

    fn in_frame(&self, frame: u32) -> &[Wanted] {
        self.by_frame.get(&frame).map_or(&[], Vec::as_slice)
    }
}

/// Our keypoints (COCO-17 or OpenPose-18 `u, v, flag`) as COCO's 51 values and `num_keypoints`: joints not
/// in the image are `0, 0, 0`.
pub(crate) fn coco_keypoints(ours: &[f32]) -> (Vec<f32>, u32) {
    let joints = ours.len() / 3;
    let mut out = Vec::with_capacity(51);
    let mut labelled = 0;
    for k in 0..17 {
        // OpenPose-18 (`annotations.pose_format: openpose18`) holds COCO joint k where its table says so.
        let j = if joints == 18 {
            OPENPOSE18_FROM_COCO17.iter().position(|&c| c == Some(k)).unwrap_or(k)
        } else {
            k
        };
        match ours.get(3 * j..3 * j + 3) {
            Some(&[u, v, flag]) if flag >= 1.0 => {
                out.extend([u, v, flag]);
                labelled += 1;
            }
            _ => out.extend([0.0, 0.0, 0.0]),
        }
    }
    (out, labelled)
}

/// Reads a 16-bit instance image and returns, for each id, its mask as COCO's compressed RLE and its pixel
/// count.
fn instance_masks(path: &Path, ids: &[u32]) -> Result<Vec<(Rle, u64)>, Error> {
    let (w, h, data) = crate::dataset::read::preview::read_u16_png(path)?;
    Ok(masks_of(&data, w, h, ids))
}

/// The masks of `ids` in a row-major `w` × `h` image of instance ids, as COCO's compressed RLE (column-major
/// runs, starting with background) and pixel counts. One pass over the image for all ids.
fn masks_of(ids_image: &[u16], w: usize, h: usize, ids: &[u32]) -> Vec<(Rle, u64)> {
    struct Run {
        counts: Vec<u32>,
        last_toggle: usize,
        area: u64,
    }
    let mut runs: Vec<Run> = ids
        .iter()
        .map(|_| Run {
            counts: Vec::new(),
            last_toggle: 0,
            area: 0,
        })
        .collect();
    let slot = |id: u16| ids.iter().position(|&i| i == u32::from(id));
    let mut previous: Option<usize> = None;
    let mut p = 0;
    for x in 0..w {
        for y in 0..h {
            let here = slot(ids_image[y * w + x]);
            if here != previous {
                if let Some(k) = previous {
                    let r = &mut runs[k];
                    r.counts.push((p - r.last_toggle) as u32);
                    r.last_toggle = p;
                }
                if let Some(k) = here {
                    let r = &mut runs[k];
                    r.counts.push((p - r.last_toggle) as u32);
                    r.last_toggle = p;
                }
                previous = here;
            }
            if let Some(k) = here {
                runs[k].area += 1;
            }
            p += 1;
        }
    }
    runs.into_iter()
        .map(|mut r| {
            // The last run: ones when the instance reaches the last pixel, zeros otherwise.
            r.counts.push((p - r.last_toggle) as u32);
            (
                Rle {
                    size: [h as u32, w as u32],
                    counts: rle_string(&r.counts),
                },
                r.area,
            )
        })
        .collect()
}

/// COCO's compressed RLE string (pycocotools' `rleToString`: each count, less the count two before it from
/// the third on, in 5-bit groups with a continuation bit, offset by 48).
fn rle_string(counts: &[u32]) -> String {
    let mut s = String::new();
    for (i, &c) in counts.iter().enumerate() {
        let mut x = i64::from(c);
        if i > 2 {
            x -= i64::from(counts[i - 2]);
        }
        loop {
            let mut c = (x & 0x1f) as u8;
            x >>= 5;
            let more = if c & 0x10 != 0 { x != -1 } else { x != 0 };
            if more {
                c |= 0x20;
            }
            s.push(char::from(c + 48));
            if !more {
                break;
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// pycocotools' decoder, by the book (`rleFrString` + `rleDecode`), to check the encoder against.
    fn decode(s: &str, n: usize) -> Vec<bool> {
        let bytes = s.as_bytes();
        let (mut counts, mut p) = (Vec::<i64>::new(), 0);
        while p < bytes.len() {
            let (mut x, mut k, mut more) = (0i64, 0, true);
            while more {
                let c = i64::from(bytes[p]) - 48;
                x |= (c & 0x1f) << (5 * k);
                more = c & 0x20 != 0;
                p += 1;
                k += 1;
                if !more && c & 0x10 != 0 {
                    x |= -1i64 << (5 * k);
                }
            }
            if counts.len() > 2 {
                x += counts[counts.len() - 2];
            }
            counts.push(x);
        }
        let mut out = Vec::with_capacity(n);
        let mut v = false;
        for c in counts {
            out.extend(std::iter::repeat_n(v, c as usize));
            v = !v;
        }
        out
    }

    #[test]
    fn masks_round_trip_through_cocos_decoder_in_column_major_order() {
        let (w, h) = (7, 5);
        // Two instances and background; instance 3 touches the first pixel and the last column.
        let mut img = vec![0u16; w * h];
        for y in 0..h {
            for x in 0..w {
                img[y * w + x] = match (x, y) {
                    (0, 0) | (6, _) => 3,
                    (2..=4, 1..=3) => 9,
                    _ => 0,
                };
            }
        }
        let masks = masks_of(&img, w, h, &[9, 3, 12]);
        for (k, id) in [9u16, 3, 12].into_iter().enumerate() {
            let decoded = decode(&masks[k].0.counts, w * h);
            assert_eq!(decoded.len(), w * h, "id {id}: counts cover the image");
            for x in 0..w {
                for y in 0..h {
                    assert_eq!(decoded[x * h + y], img[y * w + x] == id, "id {id} at ({x}, {y})");
                }
            }
            let area = img.iter().filter(|&&v| v == id).count() as u64;
            assert_eq!(masks[k].1, area);
        }
        // Large counts (over 16 and over 2^10) and negative differences encode and decode too.
        let counts = [0, 5000, 3, 70_000, 1, 17, 2];
        let total: u32 = counts.iter().sum();
        let decoded = decode(&rle_string(&counts), total as usize);
        assert_eq!(decoded.len(), total as usize);
        assert_eq!(decoded.iter().filter(|&&b| b).count() as u32, 5000 + 70_000 + 17);
    }

    #[test]
    fn openpose_keypoints_become_cocos_order_and_joints_out_of_the_image_are_zero() {
        // OpenPose-18: joint j at (j, 100 + j), flag 2, except the right wrist (4) out of the image.
        let mut ours = Vec::new();
        for j in 0..18 {
            ours.extend([j as f32, 100.0 + j as f32, if j == 4 { 0.0 } else { 2.0 }]);
        }
        let (coco, n) = coco_keypoints(&ours);
        assert_eq!(n, 16);
        // COCO's left eye is OpenPose's 14, its right wrist (10) OpenPose's 4.
        assert_eq!(&coco[3..6], &[14.0, 114.0, 2.0]);
        assert_eq!(&coco[30..33], &[0.0, 0.0, 0.0]);
    }
}
