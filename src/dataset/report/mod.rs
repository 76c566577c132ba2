//! `pedsynth report DATASET [--compare OTHER] --out report.html`: one self-contained HTML page that shows a
//! finished dataset's distributions as plots, and another's beside them: a second generated dataset, or real
//! annotations (JAAD's or PIE's XML, or the table layout `calibrate` reads), whose boxes, crossing ratio, time
//! in view before crossing and benchmark windows are drawn beside ours (the rest is simulation-only and shown
//! as absent).
//!
//! - [`svg`] — the grouped bar charts, inline SVG.
//!
//! The page has no script and loads nothing: plots are inline SVG, thumbnails PNG data URIs, styles inline. It
//! is a function of the datasets' files (no time, no paths), so the same datasets give the same bytes. Data
//! come from the written tables only: `stats` and `stats --protocol pab` (the same code), the exporters' view of
//! each clip, and the labelled frames `preview` draws.

pub mod svg;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;

use crate::dataset::export::dataset::Dataset;
use crate::dataset::read::{preview, protocol, stats};
use crate::error::{Error, code};
use svg::{Series, bars, bin_labels, escape, histogram};

/// The plots' titles, in page order (the browser test looks for each).
pub const TITLES: [&str; 10] = [
    "Crossing ratio: target and achieved, per split",
    "Behaviour states: share of annotated frames",
    "Archetypes: share of pedestrians",
    "Walking speed: annotated frames moving at 0.3 m/s or more",
    "Time in view before crossing (crossers)",
    "PedestrianActionBenchmark windows per class and split",
    "Box height: fraction of the image height",
    "Box position: bottom edge, fraction of the image height from the top",
    "Box position: centre, fraction of the image width",
    "Sensor and table sizes",
];

/// The plots of quantities only a simulation has (states, archetypes, ground speeds, sensor sizes): real
/// annotations are shown absent from them.
const SIMULATION_ONLY: [bool; 10] = [false, true, true, true, false, false, false, false, false, true];

/// The title of the per-weather samples.
pub const SAMPLES_TITLE: &str = "Samples per weather";

/// What to compare a dataset with.
#[derive(Clone, Debug)]
pub enum Compare<'a> {
    /// A second generated dataset.
    Dataset(&'a Path),
    /// Real annotations in a layout `calibrate` reads, keeping the videos of `splits` (all if empty).
    Real {
        dir: &'a Path,
        format: crate::dataset::calibrate::Format,
        splits: &'a [String],
    },
}

/// What the report reads from one dataset.
struct Summary {
    name: String,
    /// Real annotations (not a generated dataset).
    real: bool,
    version: String,
    stats: stats::DatasetStats,
    pab: protocol::PabStats,
    speeds_mps: Vec<f64>,
    seen_before_crossing_s: Vec<f64>,
    box_height: Vec<f64>,
    box_bottom: Vec<f64>,
    box_centre: Vec<f64>,
    /// Bytes per stream directory under `sensors/`, and `tables`.
    sizes: BTreeMap<String, u64>,
    /// Per weather: its first clip and a labelled thumbnail of it (none without PNG RGB).
    samples: Vec<(String, String, Option<Vec<u8>>)>,
}

impl Summary {
    /// Adds a box `[x_min, y_min, x_max, y_max]` (pixels) of an image `(width, height)` to the box plots.
    fn add_box(&mut self, [x0, y0, x1, y1]: [f64; 4], (w, h): (f64, f64)) {
        self.box_height.push((y1 - y0) / h);
        self.box_bottom.push(y1 / h);
        self.box_centre.push((x0 + x1) / 2.0 / w);
    }

    /// A summary with its figures and no samples yet.
    fn empty(name: String, version: String, stats: stats::DatasetStats, pab: protocol::PabStats) -> Summary {
        Summary {
            name,
            real: false,
            version,
            stats,
            pab,
            speeds_mps: Vec::new(),
            seen_before_crossing_s: Vec::new(),
            box_height: Vec::new(),
            box_bottom: Vec::new(),
            box_centre: Vec::new(),
            sizes: BTreeMap::new(),
            samples: Vec::new(),
        }
    }
}

fn refuse(msg: String) -> Error {
    Error::new(code::DATASET_INVALID, msg)
}

/// Total size of the files under `dir` (0 when it does not exist).
fn dir_bytes(dir: &Path) -> Result<u64, Error> {
    let mut total = 0;
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(0);
    };
    for entry in entries {
        let entry = entry.map_err(|e| Error::read(dir, e))?;
        let meta = entry.metadata().map_err(|e| Error::read(&entry.path(), e))?;
        total += if meta.is_dir() {
            dir_bytes(&entry.path())?
        } else {
            meta.len()
        };
    }
    Ok(total)
}

fn summarise(dir: &Path) -> Result<Summary, Error> {
    let ds = Dataset::open(dir)?;
    let stats = stats::compute(dir)?;
    let pab = protocol::compute(dir, &protocol::PabOptions::default())?;
    let (w, h) = (
        f64::from(ds.spec.sensors.rgb.width_px),
        f64::from(ds.spec.sensors.rgb.height_px),
    );
    let mut summary = Summary::empty(
        ds.spec.dataset.name.clone(),
        ds.manifest.pedsynth_version.clone(),
        stats,
        pab,
    );
    let mut weathers = BTreeSet::new();
    for info in &ds.clips {
        let clip = ds.load(info)?;
        for p in clip.pedestrians.values() {
            if let (Some(first), Some(cross)) = (p.frames.first(), p.first_crossing_frame)
                && first.frame <= cross
            {
                summary
                    .seen_before_crossing_s
                    .push(f64::from(cross - first.frame) / f64::from(clip.fps.max(1)));
            }
            for f in &p.frames {
                if f.speed_mps >= 0.3 {
                    summary.speeds_mps.push(f64::from(f.speed_mps));
                }
                summary.add_box(f.bbox_px.map(f64::from), (w, h));
            }
        }
        if weathers.insert(info.weather.clone()) {
            summary.samples.push((
                info.weather.clone(),
                info.clip_id.clone(),
                preview::thumbnail_png(dir, &info.clip_id)?,
            ));
        }
    }
    summary
        .sizes
        .insert("tables".to_owned(), dir_bytes(&dir.join("tables"))?);
    let sensors = dir.join("sensors");
    if let Ok(entries) = std::fs::read_dir(&sensors) {
        for entry in entries {
            let entry = entry.map_err(|e| Error::read(&sensors, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            summary.sizes.insert(name, dir_bytes(&entry.path())?);
        }
    }
    Ok(summary)
}

/// Categories as the union of each summary's keys, sorted.
fn union<'a>(keys: impl Iterator<Item = &'a String>) -> Vec<String> {
    keys.cloned().collect::<BTreeSet<_>>().into_iter().collect()
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

/// The real annotations' layout in `dir` as `calibrate` reads it: the table layout where `boxes.parquet` or
/// `boxes.csv` is, PIE's XML where `annotations/` holds set folders, JAAD's XML where it holds `.xml` files.
pub fn detect_real_format(dir: &Path) -> Option<crate::dataset::calibrate::Format> {
    use crate::dataset::calibrate::Format;
    if dir.join("boxes.parquet").is_file() || dir.join("boxes.csv").is_file() {
        return Some(Format::Table);
    }
    let entries: Vec<_> = std::fs::read_dir(dir.join("annotations")).ok()?.flatten().collect();
    if entries.iter().any(|e| e.path().is_dir()) {
        Some(Format::Pie)
    } else if entries.iter().any(|e| e.path().extension().is_some_and(|x| x == "xml")) {
        Some(Format::Jaad)
    } else {
        None
    }
}

/// The summary of real annotations: their videos' boxes, crossers, time in view before the crossing point and
/// PedestrianActionBenchmark windows (no states, archetypes, speeds, sensors or samples: the plots show them
/// empty for it).
fn summarise_real(dir: &Path, format: crate::dataset::calibrate::Format, splits: &[String]) -> Result<Summary, Error> {
    use crate::dataset::calibrate::{measure, read_real};
    let videos = read_real(dir, format, splits)?;
    let name = format!(
        "real: {}",
        dir.file_name()
            .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned())
    );
    let mut stats = stats::DatasetStats::default();
    let pab = protocol::PabStats {
        options: protocol::PabOptions::default(),
        stride: 0,
        splits: BTreeMap::new(),
        all: protocol::SplitProtocol::default(),
        target_crossing_ratio: None,
    };
    let mut summary = Summary::empty(
        name,
        "(real annotations)".to_owned(),
        stats::DatasetStats::default(),
        pab,
    );
    summary.real = true;
    let options = protocol::PabOptions::default();
    let mut by_split: BTreeMap<String, Vec<crate::dataset::calibrate::real::RealVideo>> = BTreeMap::new();
    for v in &videos {
        let split = stats.splits.entry(v.split.clone()).or_default();
        split.clips += 1;
        let frames = v
            .tracks
            .iter()
            .flat_map(|t| t.boxes.iter().map(|b| u64::from(b.frame) + 1))
            .max()
            .unwrap_or(0);
        split.frames += frames;
        stats.clips += 1;
        stats.frames += frames;
        for t in &v.tracks {
            split.pedestrians += 1;
            split.samples += t.boxes.len() as u64;
            stats.pedestrians += 1;
            stats.annotated_samples += t.boxes.len() as u64;
            if t.crosser {
                split.crossers += 1;
                stats.crossing += 1;
            }
            if let (Some(first), Some(cross)) = (t.boxes.first(), t.crossing_frame)
                && first.frame <= cross
            {
                summary
                    .seen_before_crossing_s
                    .push(f64::from(cross - first.frame) / v.fps.max(1.0));
            }
            for b in &t.boxes {
                summary.add_box(
                    [b.x_min_px, b.y_min_px, b.x_max_px, b.y_max_px],
                    (v.width_px, v.height_px),
                );
            }
        }
        by_split.entry(v.split.clone()).or_default().push(v.clone());
    }
    stats.achieved_crossing_ratio = ratio(stats.crossing, stats.pedestrians);
    for (split, vs) in by_split {
        let mut p = protocol::SplitProtocol::default();
        for w in measure::windows(&vs, &options) {
            if w.crosser {
                p.crossing.windows += 1;
            } else {
                p.not_crossing.windows += 1;
            }
        }
        summary.pab.splits.insert(split, p);
    }
    summary.stats = stats;
    Ok(summary)
}

/// Writes the report of `dir` (with `compare` beside it) to `out`; returns the line to print.
pub fn report(dir: &Path, compare: Option<Compare<'_>>, out: &Path) -> Result<String, Error> {
    if let Some(Compare::Dataset(other)) = &compare
        && !other.join("manifest.json").is_file()
    {
        return Err(refuse(format!(
            "{}: not a pedsynth dataset (no manifest.json), nor real annotations `calibrate` reads (JAAD's or PIE's \
             XML, or boxes.parquet/boxes.csv); name their layout with --real-format",
            other.display()
        )));
    }
    let mut summaries = vec![summarise(dir)?];
    match compare {
        Some(Compare::Dataset(other)) => {
            let mut s = summarise(other)?;
            if s.name == summaries[0].name {
                s.name = format!("{} (compared)", s.name);
            }
            summaries.push(s);
        }
        Some(Compare::Real { dir, format, splits }) => summaries.push(summarise_real(dir, format, splits)?),
        None => {}
    }
    let html = page(&summaries);
    crate::util::files::write_atomically(out, html.as_bytes()).map_err(|e| Error::write(out, e))?;
    Ok(format!(
        "{}: report of {}{} ({} plots, {} KB)\n",
        out.display(),
        summaries[0].name,
        summaries
            .get(1)
            .map(|s| format!(" against {}", s.name))
            .unwrap_or_default(),
        TITLES.len(),
        html.len() / 1024
    ))
}

/// A row of the summary table: a dataset's value as HTML.
type Cell = dyn Fn(&Summary) -> String;

/// The page.
fn page(summaries: &[Summary]) -> String {
    let mut plots: Vec<String> = Vec::new();
    let names = || summaries.iter().map(|s| s.name.clone());
    // Crossing ratio per split.
    let splits = union(summaries.iter().flat_map(|s| s.stats.splits.keys()));
    let mut categories = splits.clone();
    categories.push("all".to_owned());
    let mut series: Vec<Series> = summaries
        .iter()
        .map(|s| Series {
            name: format!("{} achieved", s.name),
            values: splits
                .iter()
                .map(|k| s.stats.splits.get(k).map_or(0.0, |c| ratio(c.crossers, c.pedestrians)))
                .chain([s.stats.achieved_crossing_ratio])
                .collect(),
        })
        .collect();
    // One target series when the datasets share their target, one per dataset otherwise.
    let targets: Vec<(String, f64)> = summaries
        .iter()
        .filter_map(|s| s.stats.target_crossing_ratio.map(|t| (format!("{} target", s.name), t)))
        .collect();
    let shared = targets.len() == summaries.len() && targets.iter().all(|(_, t)| *t == targets[0].1);
    for (name, t) in if shared { &targets[..1] } else { &targets[..] } {
        series.push(Series {
            name: if shared { "target".to_owned() } else { name.clone() },
            values: vec![*t; categories.len()],
        });
    }
    plots.push(bars(TITLES[0], "crossers / pedestrians", &categories, &series));
    // States.
    let states = union(summaries.iter().flat_map(|s| s.stats.state_shares.keys()));
    plots.push(bars(
        TITLES[1],
        "share",
        &states,
        &summaries
            .iter()
            .map(|s| Series {
                name: s.name.clone(),
                values: states
                    .iter()
                    .map(|k| s.stats.state_shares.get(k).copied().unwrap_or(0.0))
                    .collect(),
            })
            .collect::<Vec<_>>(),
    ));
    // Archetypes.
    let archetypes = union(summaries.iter().flat_map(|s| s.stats.archetypes.keys()));
    plots.push(bars(
        TITLES[2],
        "share of pedestrians",
        &archetypes,
        &summaries
            .iter()
            .map(|s| Series {
                name: s.name.clone(),
                values: archetypes
                    .iter()
                    .map(|k| {
                        ratio(
                            s.stats.archetypes.get(k).map_or(0, |a| a.pedestrians),
                            s.stats.pedestrians,
                        )
                    })
                    .collect(),
            })
            .collect::<Vec<_>>(),
    ));
    let hist = |title: &str, unit: &str, pick: &dyn Fn(&Summary) -> &[f64], lo: f64, step: f64, bins: usize| {
        bars(
            title,
            unit,
            &bin_labels(lo, step, bins),
            &summaries
                .iter()
                .zip(names())
                .map(|(s, name)| Series {
                    name,
                    values: histogram(pick(s), lo, step, bins),
                })
                .collect::<Vec<_>>(),
        )
    };
    plots.push(hist(TITLES[3], "share (m/s bins)", &|s| &s.speeds_mps, 0.0, 0.2, 15));
    plots.push(hist(
        TITLES[4],
        "share (s bins)",
        &|s| &s.seen_before_crossing_s,
        0.0,
        1.0,
        13,
    ));
    // Benchmark windows.
    let pab_splits = union(summaries.iter().flat_map(|s| s.pab.splits.keys()));
    let pab_categories: Vec<String> = pab_splits
        .iter()
        .flat_map(|k| [format!("{k} crossing"), format!("{k} not crossing")])
        .collect();
    plots.push(bars(
        TITLES[5],
        "windows (16 frames, TTE 30–60, overlap 0.6)",
        &pab_categories,
        &summaries
            .iter()
            .map(|s| Series {
                name: s.name.clone(),
                values: pab_splits
                    .iter()
                    .flat_map(|k| {
                        let p = s.pab.splits.get(k);
                        [
                            p.map_or(0.0, |p| p.crossing.windows as f64),
                            p.map_or(0.0, |p| p.not_crossing.windows as f64),
                        ]
                    })
                    .collect(),
            })
            .collect::<Vec<_>>(),
    ));
    plots.push(hist(
        TITLES[6],
        "share of annotated frames",
        &|s| &s.box_height,
        0.0,
        0.025,
        16,
    ));
    plots.push(hist(
        TITLES[7],
        "share of annotated frames",
        &|s| &s.box_bottom,
        0.0,
        0.05,
        20,
    ));
    plots.push(hist(
        TITLES[8],
        "share of annotated frames",
        &|s| &s.box_centre,
        0.0,
        0.05,
        20,
    ));
    let streams = union(summaries.iter().flat_map(|s| s.sizes.keys()));
    plots.push(bars(
        TITLES[9],
        "MB",
        &streams,
        &summaries
            .iter()
            .map(|s| Series {
                name: s.name.clone(),
                values: streams
                    .iter()
                    .map(|k| s.sizes.get(k).copied().unwrap_or(0) as f64 / 1e6)
                    .collect(),
            })
            .collect::<Vec<_>>(),
    ));

    let mut h = String::new();
    let title = match summaries {
        [a, b] => format!("pedsynth report: {} against {}", a.name, b.name),
        _ => format!("pedsynth report: {}", summaries[0].name),
    };
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/><title>{0}</title><style>\
         body{{font-family:sans-serif;margin:24px;color:#222}}\
         section{{display:inline-block;vertical-align:top;margin:0 24px 24px 0}}\
         h2{{font-size:16px;margin:8px 0}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         figure{{display:inline-block;margin:0 12px 12px 0}}figcaption{{font-size:12px}}\
         img{{display:block}}</style></head><body>\n<h1>{0}</h1>\n",
        escape(&title)
    );
    h.push_str("<table><tr><th></th>");
    for s in summaries {
        let _ = write!(h, "<th>{}</th>", escape(&s.name));
    }
    h.push_str("</tr>\n");
    let rows: [(&str, &Cell); 8] = [
        ("pedsynth version", &|s| escape(&s.version)),
        ("clips", &|s| s.stats.clips.to_string()),
        ("frames", &|s| s.stats.frames.to_string()),
        ("pedestrians", &|s| s.stats.pedestrians.to_string()),
        ("annotated pedestrian-frames", &|s| {
            s.stats.annotated_samples.to_string()
        }),
        ("crossing ratio (target)", &|s| {
            s.stats
                .target_crossing_ratio
                .map_or("none".to_owned(), |t| format!("{t:.3}"))
        }),
        ("crossing ratio (achieved)", &|s| {
            format!("{:.3}", s.stats.achieved_crossing_ratio)
        }),
        ("weathers", &|s| {
            if s.real {
                "n/a".to_owned()
            } else {
                escape(&s.stats.weathers.join(", "))
            }
        }),
    ];
    for (label, value) in rows {
        let _ = write!(h, "<tr><th>{label}</th>");
        for s in summaries {
            let _ = write!(h, "<td>{}</td>", value(s));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    for ((title, plot), simulation_only) in TITLES.iter().zip(&plots).zip(SIMULATION_ONLY) {
        let absent: Vec<String> = summaries
            .iter()
            .filter(|s| s.real && simulation_only)
            .map(|s| format!("<p>{}: not in real annotations</p>", escape(&s.name)))
            .collect();
        let _ = writeln!(
            h,
            "<section><h2>{}</h2>{plot}{}</section>",
            escape(title),
            absent.concat()
        );
    }
    let _ = writeln!(h, "<h2>{SAMPLES_TITLE}</h2>");
    for s in summaries {
        let _ = writeln!(h, "<h3>{}</h3><div>", escape(&s.name));
        if s.real {
            h.push_str("<p>real annotations: no images</p>");
        }
        for (weather, clip, png) in &s.samples {
            match png {
                Some(bytes) => {
                    let _ = write!(
                        h,
                        "<figure><img alt=\"{0} {1}\" src=\"data:image/png;base64,{2}\"/><figcaption>{0}: {1}\
                         </figcaption></figure>",
                        escape(weather),
                        escape(clip),
                        base64::engine::general_purpose::STANDARD.encode(bytes)
                    );
                }
                None => {
                    let _ = write!(
                        h,
                        "<figure><figcaption>{}: {} (no PNG RGB frames)</figcaption></figure>",
                        escape(weather),
                        escape(clip)
                    );
                }
            }
        }
        h.push_str("</div>\n");
    }
    h.push_str("</body></html>\n");
    h
}
