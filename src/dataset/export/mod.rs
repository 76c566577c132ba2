//! `pedsynth export FORMAT DATASET --out DIR`: a finished dataset in the layouts the field's own tools read.
//!
//! - [`dataset`] — the dataset as exporters see it (manifest checked, tables per clip, resolved spec).
//! - [`pie`] — PIE's annotations, attributes, ego-vehicle files and images (`pie_data.py` loads them).
//! - [`jaad`] — JAAD's five annotation folders, split lists and images (`jaad_data.py` loads them).
//! - [`pab`] — PedestrianActionBenchmark's pose pickles for the PIE or the JAAD export.
//! - [`openscenario`] — one ASAM OpenSCENARIO 1.2 file per clip replaying its traces, with the towns as
//!   OpenDRIVE beside them.
//! - [`coco`] — COCO's detection, keypoint and instance-segmentation JSON per split, images linked
//!   (pycocotools loads it).
//! - [`nuscenes`] — nuScenes' JSON tables, CAM_FRONT images, LIDAR_TOP `.pcd.bin` sweeps and map masks
//!   (`nuscenes-devkit` loads it).
//! - `rerun` (the `rerun` cargo feature) — one clip as a Rerun recording (`.rrd`), with Rerun's own SDK.
//! - [`seed_csv`] — the seed system's CSV layout (labels, 3D boxes, ego poses; per clip, weather, dataset).
//!
//! Exporters read the written dataset, never the simulator; every file is written under a temporary name and
//! renamed, so an interrupted export leaves complete files only and re-running it finishes the job.

pub mod coco;
pub mod dataset;
pub mod jaad;
pub mod nuscenes;
pub mod openscenario;
pub mod pab;
pub mod pie;
#[cfg(feature = "rerun")]
pub mod rerun;
pub mod seed_csv;

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::Error;
use crate::plan::TownContext;

/// Export formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// PIE (`pie_data.py`): annotations/, annotations_attributes/, annotations_vehicle/, images/.
    Pie,
    /// JAAD (`jaad_data.py`): annotations*/ (five kinds), split_ids/default/, images/.
    Jaad,
    /// PedestrianActionBenchmark's poses/pose_setNN.pkl for the PIE export.
    PabPoses,
    /// PedestrianActionBenchmark's poses/pose_set01.pkl for the JAAD export.
    PabPosesJaad,
    /// The seed system's CSV layout: <weather>/<town>/<clip>/labels.csv, pedestrians_3d.csv, ego_pose.csv.
    SeedCsv,
    /// ASAM OpenSCENARIO 1.2: <clip_id>.xosc per clip replaying its traces, towns/<town>.xodr beside them.
    Openscenario,
    /// COCO (pycocotools): annotations/<split>.json (boxes, keypoints, instance masks as RLE), images/.
    Coco,
    /// nuScenes (nuscenes-devkit): v1.0-pedsynth/*.json, samples/ and sweeps/ (CAM_FRONT, LIDAR_TOP), maps/.
    Nuscenes,
    /// One clip (`--clip ID`) as a Rerun recording: `--out CLIP.rrd` (needs the `rerun` cargo feature).
    Rerun,
}

/// How an export runs: the options of `pedsynth export`.
#[derive(Clone, Debug)]
pub struct Options {
    /// How images get into the export.
    pub link: LinkMode,
    /// Overrides the spec's `annotations.export_box`.
    pub export_box: Option<crate::spec::types::ExportBox>,
    /// nuScenes' keyframe rate, Hz.
    pub keyframe_hz: f64,
    /// The clip to export (Rerun).
    pub clip: Option<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            link: LinkMode::Hard,
            export_box: None,
            keyframe_hz: 2.0,
            clip: None,
        }
    }
}

/// How images get into an export.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LinkMode {
    /// Hard links (the default; falls back to a copy across file systems).
    #[default]
    Hard,
    /// Symbolic links to the dataset's files.
    Symlink,
    /// Copies.
    Copy,
}

impl std::fmt::Display for LinkMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LinkMode::Hard => "hard links",
            LinkMode::Symlink => "symbolic links",
            LinkMode::Copy => "copies",
        })
    }
}

/// Writes a file under a temporary name, then renames it (creating its directory).
pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    }
    crate::util::files::write_atomically_unsynced(path, bytes).map_err(|e| Error::write(path, e))
}

/// Puts `from` at `to` as `mode` says; an existing `to` of the same size is kept (a resumed export).
pub(crate) fn link_file(from: &Path, to: &Path, mode: LinkMode) -> Result<(), Error> {
    let size = |p: &Path| std::fs::metadata(p).map(|m| m.len());
    if let (Ok(a), Ok(b)) = (size(from), size(to))
        && a == b
    {
        return Ok(());
    }
    let _ = std::fs::remove_file(to);
    let tmp = crate::util::files::temporary_path(to);
    let result = match mode {
        LinkMode::Hard => std::fs::hard_link(from, &tmp).or_else(|_| std::fs::copy(from, &tmp).map(|_| ())),
        LinkMode::Symlink => {
            let target = std::path::absolute(from).map_err(|e| Error::read(from, e))?;
            std::os::unix::fs::symlink(target, &tmp)
        }
        LinkMode::Copy => std::fs::copy(from, &tmp).map(|_| ()),
    };
    result.and_then(|()| std::fs::rename(&tmp, to)).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::write(to, e)
    })
}

/// A progress bar over `clips` clips on a terminal (nothing otherwise).
pub(crate) fn progress(clips: usize) -> crate::dataset::generate::progress::Progress {
    use std::io::IsTerminal;
    crate::dataset::generate::progress::Progress::new(clips, !std::io::stderr().is_terminal())
}

/// What a dataset's RGB stream offers an export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RgbFiles {
    /// PNG frames: linked as the loaders' `images/`.
    Png,
    /// One H.264 MP4 per clip: linked as the datasets' own videos (`JAAD_clips/`, `PIE_clips/`), from which
    /// their loaders' `extract_and_save_images()` extract the frames.
    Mp4,
    /// Nothing the loaders read (no RGB stream, or JPEG).
    None,
}

/// What the dataset's RGB stream offers, and the line that says what happens to images.
pub(crate) fn images_note(ds: &dataset::Dataset, link: LinkMode) -> (RgbFiles, String) {
    let rgb = ds.manifest.sensors.get("rgb").map(String::as_str).unwrap_or("disabled");
    if rgb.starts_with("rendered") && rgb.ends_with(".png") {
        (RgbFiles::Png, format!("images linked ({link}) from sensors/rgb"))
    } else if rgb.starts_with("rendered: sensors/rgb/<clip_id>.mp4") {
        (
            RgbFiles::Mp4,
            format!(
                "videos linked ({link}) from sensors/rgb (H.264 MP4): the loader's extract_and_save_images() \
                 writes images/ from them"
            ),
        )
    } else if rgb.starts_with("rendered") {
        (
            RgbFiles::None,
            "images absent: the RGB stream is JPEG (the loaders read .png or .mp4); annotations only".to_owned(),
        )
    } else {
        (
            RgbFiles::None,
            "images absent: the dataset has no RGB stream; annotations only".to_owned(),
        )
    }
}

/// The RGB frames an export that links image files can use: `Some((extension, note))` for PNG or JPEG frames
/// (`note` says how they get there), `None` without an RGB stream. An H.264 stream is refused (exit 2) with what
/// to do, naming the format (`what`).
pub(crate) fn image_frames(
    ds: &dataset::Dataset,
    link: LinkMode,
    what: &str,
) -> Result<Option<(&'static str, String)>, Error> {
    let (rgb, note) = images_note(ds, link);
    let jpeg = ds
        .manifest
        .sensors
        .get("rgb")
        .is_some_and(|s| s.starts_with("rendered") && s.ends_with(".jpg"));
    match rgb {
        RgbFiles::Mp4 => Err(Error::new(
            crate::error::code::DATASET_INVALID,
            format!(
                "{}: the RGB stream is H.264 video, and {what} links image files: generate the dataset with \
                 output.rgb_encoding: png (or jpeg), or decode sensors/rgb/<clip_id>.mp4 into \
                 sensors/rgb/<clip_id>/<frame:06>.png first",
                ds.layout.root().display()
            ),
        )),
        RgbFiles::Png => Ok(Some(("png", note))),
        RgbFiles::None if jpeg => Ok(Some(("jpg", format!("images linked ({link}) from sensors/rgb (JPEG)")))),
        RgbFiles::None => Ok(None),
    }
}

/// Links a clip's H.264 video to `to`; returns whether it was there.
pub(crate) fn link_video(
    ds: &dataset::Dataset,
    clip: &dataset::Clip,
    to: &Path,
    link: LinkMode,
) -> Result<bool, Error> {
    let from = ds.layout.sensor_clip("rgb", &clip.clip_id, "mp4");
    if !from.exists() {
        return Ok(false);
    }
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    }
    link_file(&from, to, link)?;
    Ok(true)
}

/// Links a clip's RGB frames into `dir` as `<frame>.png` with `digits` digits; returns how many.
pub(crate) fn link_frames(
    ds: &dataset::Dataset,
    clip: &dataset::Clip,
    dir: &Path,
    digits: usize,
    link: LinkMode,
) -> Result<usize, Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let mut linked = 0;
    for frame in 0..clip.frame_count {
        let from = ds.layout.sensor_frame("rgb", &clip.clip_id, frame, "png");
        if from.exists() {
            link_file(&from, &dir.join(format!("{frame:0digits$}.png")), link)?;
            linked += 1;
        }
    }
    Ok(linked)
}

/// The dataset's towns, for map attributes; a town that cannot be loaded (an OpenDRIVE file not found
/// beside the dataset) is left out with a warning.
pub(crate) fn towns(ds: &dataset::Dataset, warn: &mut dyn FnMut(String)) -> BTreeMap<String, TownContext> {
    match crate::dataset::inputs::load_spec_towns(&ds.spec, ds.layout.root()) {
        Ok(towns) => towns,
        Err(e) => {
            warn(format!(
                "warning: the towns cannot be loaded ({e}); intersection, num_lanes, signalized and \
                 traffic_direction are written as unknown (midblock, 0, n/a, TW)"
            ));
            BTreeMap::new()
        }
    }
}

/// Runs an export; returns the summary lines to print.
pub fn export(
    dir: &Path,
    format: Format,
    out: &Path,
    options: &Options,
    warn: &mut dyn FnMut(String),
) -> Result<String, Error> {
    let (link, export_box) = (options.link, options.export_box);
    let mut ds = dataset::Dataset::open(dir)?;
    // `--box` overrides the spec's `annotations.export_box`.
    if let Some(b) = export_box {
        ds.spec.annotations.export_box = b;
    }
    if format == Format::Rerun {
        return export_rerun(&ds, options.clip.as_deref(), out);
    }
    std::fs::create_dir_all(out).map_err(|e| Error::write(out, e))?;
    Ok(match format {
        Format::Pie => {
            let r = pie::export(&ds, out, link, warn)?;
            format!(
                "{}: PIE layout of {} clips: {} videos, {} pedestrian tracks, {} vehicle tracks, {} images, {} \
                 MP4 videos\n{}\n",
                out.display(),
                ds.clips.len(),
                r.videos,
                r.pedestrian_tracks,
                r.vehicle_tracks,
                r.images,
                r.videos_linked,
                r.images_note
            )
        }
        Format::Jaad => {
            let r = jaad::export(&ds, out, link, warn)?;
            format!(
                "{}: JAAD layout of {} clips: {} videos, {} pedestrian tracks, {} images, {} MP4 videos\n{}\n",
                out.display(),
                ds.clips.len(),
                r.videos,
                r.pedestrian_tracks,
                r.images,
                r.videos_linked,
                r.images_note
            )
        }
        Format::SeedCsv => {
            let r = seed_csv::export(&ds, out, link)?;
            format!(
                "{}: the seed's CSV layout of {} clips: {} label rows, {} images\n{}\n",
                out.display(),
                r.clips,
                r.rows,
                r.images,
                r.images_note
            )
        }
        Format::Openscenario => {
            let r = openscenario::export(&ds, out)?;
            format!(
                "{}: {} OpenSCENARIO files ({} entities, {} of them parked cars; {} trajectory vertices for {} entity-frames) and {} towns as OpenDRIVE in towns/\n",
                out.display(),
                r.scenarios,
                r.entities,
                r.parked,
                r.vertices,
                r.frames,
                r.towns
            )
        }
        Format::Coco => {
            let r = coco::export(&ds, out, link)?;
            format!(
                "{}: COCO layout of {} clips: {} annotation files (annotations/<split>.json), {} images, {} \
                 annotations, {} with a mask\n{}\n",
                out.display(),
                ds.clips.len(),
                r.files,
                r.images,
                r.annotations,
                r.masks,
                r.images_note
            )
        }
        Format::Nuscenes => {
            let r = nuscenes::export(&ds, out, link, options.keyframe_hz)?;
            format!(
                "{}: nuScenes layout ({}) of {} clips: {} scenes, {} samples (a keyframe every {} frames), {} \
                 sample_data ({} images, {} LiDAR sweeps), {} instances, {} box annotations, {} maps\n{}\n",
                out.display(),
                nuscenes::VERSION,
                ds.clips.len(),
                r.scenes,
                r.samples,
                r.keyframe_step,
                r.sample_data,
                r.images,
                r.lidar_files,
                r.instances,
                r.annotations,
                r.maps,
                r.images_note
            )
        }
        Format::Rerun => unreachable!("handled above"),
        Format::PabPoses | Format::PabPosesJaad => {
            let r = pab::export(&ds, out, format == Format::PabPosesJaad)?;
            format!(
                "{}: {} pose files (poses/pose_setNN.pkl), {} pedestrian-frames, {} with a pose\n",
                out.display(),
                r.files,
                r.entries,
                r.with_pose
            )
        }
    })
}

/// `export rerun`: the clip `--clip` names into the `.rrd` file `out`.
fn export_rerun(ds: &dataset::Dataset, clip: Option<&str>, out: &Path) -> Result<String, Error> {
    let names = || {
        ds.clips
            .iter()
            .map(|c| c.clip_id.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some(clip) = clip else {
        return Err(Error::new(
            crate::error::code::EXPORT_OPTIONS,
            format!(
                "export rerun writes one clip: add --clip ID (the dataset's clips: {})",
                names()
            ),
        ));
    };
    if !ds.clips.iter().any(|c| c.clip_id == clip) {
        return Err(Error::new(
            crate::error::code::EXPORT_OPTIONS,
            format!(
                "--clip {clip}: no such clip in {}; its clips are: {}",
                ds.layout.root().display(),
                names()
            ),
        ));
    }
    #[cfg(feature = "rerun")]
    {
        let r = rerun::export(ds, clip, out)?;
        let rows: u64 = r.rows.values().sum();
        Ok(format!(
            "{}: Rerun recording of clip {clip}: {} frames, {} entities, {} rows (open it with `rerun {}`)\n",
            out.display(),
            r.frames,
            r.rows.len(),
            rows,
            out.display()
        ))
    }
    #[cfg(not(feature = "rerun"))]
    {
        let _ = (clip, out);
        Err(Error::new(
            crate::error::code::EXPORT_OPTIONS,
            "this pedsynth was built without Rerun's SDK: build it with `cargo build --release --features rerun` \
             (the `rerun` feature adds Rerun's ~480 crates to the build)"
                .to_owned(),
        ))
    }
}
