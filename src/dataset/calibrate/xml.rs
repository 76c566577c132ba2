//! JAAD's and PIE's annotation layouts (their authors' XML, as `jaad_data.py` and `pie_data.py` read it) as
//! [`RealVideo`]s.
//!
//! - JAAD (`REAL_DIR/annotations/<video>.xml`, `annotations_attributes/<video>_attributes.xml`,
//!   `annotations_vehicle/<video>_vehicle.xml`, `split_ids/default/{train,val,test}.txt`): tracks labelled
//!   `pedestrian` (behaviour tracks) and `ped` (bystanders, never crossers); `people` (groups) are skipped, as
//!   the benchmark skips them. 30 frames per second.
//! - PIE (`REAL_DIR/annotations/<set>/<video>_annt.xml`, `annotations_attributes/<set>/<video>_attributes.xml`,
//!   optional `annotations_vehicle/<set>/<video>_obd.xml`): `pedestrian` tracks; boxes marked `outside` are
//!   skipped as PIE's loader skips them; the split is the set's (PIE's default split). The ego's action comes
//!   from the OBD speed (km/h) and its change over one second. 30 frames per second.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use roxmltree::{Document, Node};

use super::real::{EgoAction, RealBox, RealTrack, RealVideo, invalid};
use crate::error::Error;

/// Frames per second of JAAD's and PIE's videos.
const FPS: f64 = 30.0;

fn read_xml(path: &Path) -> Result<String, Error> {
    crate::util::files::read_capped(path, 1 << 30)
        .map_err(|e| invalid(format!("cannot read {}: {e}", path.display())))
        .and_then(|bytes| String::from_utf8(bytes).map_err(|_| invalid(format!("{}: not UTF-8", path.display()))))
}

fn parse<'a>(path: &Path, text: &'a str) -> Result<Document<'a>, Error> {
    Document::parse(text).map_err(|e| invalid(format!("{}: not well-formed XML: {e}", path.display())))
}

/// The files of `dir` whose names end in `suffix`, sorted.
fn files_ending(dir: &Path, suffix: &str) -> Result<Vec<PathBuf>, Error> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        invalid(format!("{}: {e}", dir.display())).help("is this the root of the dataset's annotations (--format)?")
    })?;
    let mut out: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.ends_with(suffix))
        })
        .collect();
    out.sort();
    Ok(out)
}

fn child<'a, 'i>(node: Node<'a, 'i>, path: &[&str]) -> Option<Node<'a, 'i>> {
    let mut node = node;
    for name in path {
        node = node.children().find(|c| c.has_tag_name(*name))?;
    }
    Some(node)
}

/// A box's `<attribute name="NAME">` text.
fn attribute<'a>(b: Node<'a, '_>, name: &str) -> Option<&'a str> {
    b.children()
        .find(|c| c.has_tag_name("attribute") && c.attribute("name") == Some(name))
        .and_then(|c| c.text())
}

fn number(node: Node, name: &str, path: &Path) -> Result<f64, Error> {
    node.attribute(name)
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|x| x.is_finite())
        .ok_or_else(|| {
            let line = node.document().text_pos_at(node.range().start).row;
            invalid(format!("{}:{line}: `{name}` missing or not a number", path.display()))
        })
}

/// A video's size and tracks from a CVAT-style annotation file (JAAD's and PIE's).
fn read_tracks(path: &Path, labels: &[&str], skip_outside: bool) -> Result<(f64, f64, Vec<RealTrack>), Error> {
    let text = read_xml(path)?;
    let doc = parse(path, &text)?;
    let root = doc.root_element();
    let size = |name: &str| {
        child(root, &["meta", "task", "original_size", name])
            .and_then(|n| n.text())
            .and_then(|t| t.trim().parse::<f64>().ok())
            .filter(|&x| x >= 1.0)
            .ok_or_else(|| invalid(format!("{}: no meta/task/original_size/{name}", path.display())))
    };
    let (width, height) = (size("width")?, size("height")?);
    let mut tracks = Vec::new();
    for track in root.children().filter(|c| c.has_tag_name("track")) {
        if !track.attribute("label").is_some_and(|l| labels.contains(&l)) {
            continue;
        }
        let mut boxes = Vec::new();
        let mut id = None;
        for b in track.children().filter(|c| c.has_tag_name("box")) {
            id = id.or_else(|| attribute(b, "id").map(str::to_owned));
            if skip_outside && b.attribute("outside") == Some("1") {
                continue;
            }
            boxes.push(RealBox {
                frame: number(b, "frame", path)?.max(0.0) as u32,
                x_min_px: number(b, "xtl", path)?,
                y_min_px: number(b, "ytl", path)?,
                x_max_px: number(b, "xbr", path)?,
                y_max_px: number(b, "ybr", path)?,
                occluded: attribute(b, "occlusion").map_or(b.attribute("occluded") == Some("1"), |o| o != "none"),
                standing: attribute(b, "action").map(|a| a == "standing"),
                looking: attribute(b, "look").map(|l| l == "looking"),
            });
        }
        let Some(id) = id else { continue };
        if boxes.is_empty() {
            continue;
        }
        boxes.sort_by_key(|b| b.frame);
        tracks.push(RealTrack {
            id,
            crosser: false,
            crossing_frame: None,
            boxes,
        });
    }
    Ok((width, height, tracks))
}

/// Each pedestrian's `(crossing == 1, crossing_point)` from an attributes file.
fn read_attributes(path: &Path) -> Result<BTreeMap<String, (bool, Option<u32>)>, Error> {
    let text = read_xml(path)?;
    let doc = parse(path, &text)?;
    Ok(doc
        .root_element()
        .children()
        .filter(|c| c.has_tag_name("pedestrian"))
        .filter_map(|p| {
            let id = p.attribute("id")?.to_owned();
            let crosser = p.attribute("crossing") == Some("1");
            let point = p
                .attribute("crossing_point")
                .and_then(|v| v.trim().parse::<i64>().ok())
                .filter(|&f| f >= 0);
            Some((id, (crosser, point.map(|f| f as u32))))
        })
        .collect())
}

fn label_tracks(tracks: &mut [RealTrack], attributes: &BTreeMap<String, (bool, Option<u32>)>) {
    for t in tracks {
        if let Some(&(crosser, point)) = attributes.get(&t.id) {
            // As JAAD's loader: a crosser without a crossing point (-1) keeps its whole track.
            t.crosser = crosser;
            t.crossing_frame = if crosser { point } else { None };
        }
    }
}

/// JAAD's layout under `dir`.
pub fn read_jaad(dir: &Path) -> Result<Vec<RealVideo>, Error> {
    let mut split_of: BTreeMap<String, String> = BTreeMap::new();
    for split in ["train", "val", "test"] {
        let path = dir.join("split_ids/default").join(format!("{split}.txt"));
        if let Ok(text) = std::fs::read_to_string(&path) {
            for name in text.split_whitespace() {
                split_of.insert(name.to_owned(), split.to_owned());
            }
        }
    }
    let files = files_ending(&dir.join("annotations"), ".xml")?;
    if files.is_empty() {
        return Err(invalid(format!(
            "{}: no annotation files (annotations/<video>.xml)",
            dir.display()
        )));
    }
    let mut videos = Vec::new();
    for path in files {
        let Some(name) = path.file_stem().and_then(|s| s.to_str()).map(str::to_owned) else {
            continue;
        };
        let (width_px, height_px, mut tracks) = read_tracks(&path, &["pedestrian", "ped"], false)?;
        let attributes_path = dir
            .join("annotations_attributes")
            .join(format!("{name}_attributes.xml"));
        label_tracks(&mut tracks, &read_attributes(&attributes_path)?);
        let mut ego_actions = BTreeMap::new();
        let vehicle = dir.join("annotations_vehicle").join(format!("{name}_vehicle.xml"));
        if vehicle.is_file() {
            let text = read_xml(&vehicle)?;
            for f in parse(&vehicle, &text)?
                .root_element()
                .children()
                .filter(|c| c.has_tag_name("frame"))
            {
                if let (Some(a), Ok(frame)) = (
                    f.attribute("action").and_then(EgoAction::from_name),
                    number(f, "id", &vehicle),
                ) {
                    ego_actions.insert(frame.max(0.0) as u32, a);
                }
            }
        }
        videos.push(RealVideo {
            split: split_of.get(&name).cloned().unwrap_or_else(|| "unknown".to_owned()),
            name,
            width_px,
            height_px,
            fps: FPS,
            tracks,
            ego_actions,
        });
    }
    Ok(videos)
}

/// PIE's layout under `dir`.
pub fn read_pie(dir: &Path) -> Result<Vec<RealVideo>, Error> {
    let sets_dir = dir.join("annotations");
    let mut sets: Vec<PathBuf> = std::fs::read_dir(&sets_dir)
        .map_err(|e| {
            invalid(format!("{}: {e}", sets_dir.display())).help("PIE's layout: annotations/<setNN>/<video>_annt.xml")
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    sets.sort();
    let mut videos = Vec::new();
    for set_dir in sets {
        let Some(set) = set_dir.file_name().and_then(|s| s.to_str()).map(str::to_owned) else {
            continue;
        };
        let split = crate::dataset::export::pie::SETS
            .iter()
            .find(|(_, sets)| sets.contains(&set.as_str()))
            .map_or("unknown", |(split, _)| split);
        for path in files_ending(&set_dir, "_annt.xml")? {
            let Some(name) = path
                .file_name()
                .and_then(|s| s.to_str())
                .and_then(|n| n.strip_suffix("_annt.xml"))
            else {
                continue;
            };
            let name = name.to_owned();
            let (width_px, height_px, mut tracks) = read_tracks(&path, &["pedestrian"], true)?;
            let attributes_path = dir
                .join("annotations_attributes")
                .join(&set)
                .join(format!("{name}_attributes.xml"));
            label_tracks(&mut tracks, &read_attributes(&attributes_path)?);
            let obd = dir
                .join("annotations_vehicle")
                .join(&set)
                .join(format!("{name}_obd.xml"));
            let ego_actions = if obd.is_file() {
                read_obd(&obd)?
            } else {
                BTreeMap::new()
            };
            videos.push(RealVideo {
                name: format!("{set}/{name}"),
                split: split.to_owned(),
                width_px,
                height_px,
                fps: FPS,
                tracks,
                ego_actions,
            });
        }
    }
    if videos.is_empty() {
        return Err(invalid(format!(
            "{}: no annotation files (annotations/<setNN>/<video>_annt.xml)",
            dir.display()
        )));
    }
    Ok(videos)
}

/// The ego's action per frame from PIE's OBD speed (km/h) and its change over one second.
fn read_obd(path: &Path) -> Result<BTreeMap<u32, EgoAction>, Error> {
    let text = read_xml(path)?;
    let doc = parse(path, &text)?;
    let mut speeds: Vec<(u32, f64)> = Vec::new();
    for f in doc.root_element().children().filter(|c| c.has_tag_name("frame")) {
        speeds.push((
            number(f, "id", path)?.max(0.0) as u32,
            number(f, "OBD_speed", path)? / 3.6,
        ));
    }
    speeds.sort_by_key(|s| s.0);
    let half = (FPS / 2.0) as usize;
    Ok(speeds
        .iter()
        .enumerate()
        .map(|(i, &(frame, speed))| {
            let (a, b) = (i.saturating_sub(half), (i + half).min(speeds.len() - 1));
            let dt = (speeds[b].0 as f64 - speeds[a].0 as f64) / FPS;
            let accel = if dt > 0.0 {
                (speeds[b].1 - speeds[a].1) / dt
            } else {
                0.0
            };
            (frame, EgoAction::from_motion(speed, accel))
        })
        .collect())
}
