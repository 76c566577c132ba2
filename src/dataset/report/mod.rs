//! `pedsynth report DATASET [--compare OTHER] --out report.html`: one self-contained HTML page that shows a
//! finished dataset's distributions as plots, and another dataset's beside them.
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

/// The title of the per-weather samples.
pub const SAMPLES_TITLE: &str = "Samples per weather";

/// What the report reads from one dataset.
struct Summary {
    name: String,
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
    let mut summary = Summary {
        name: ds.spec.dataset.name.clone(),
        version: ds.manifest.pedsynth_version.clone(),
        stats,
        pab,
        speeds_mps: Vec::new(),
        seen_before_crossing_s: Vec::new(),
        box_height: Vec::new(),
        box_bottom: Vec::new(),
        box_centre: Vec::new(),
        sizes: BTreeMap::new(),
        samples: Vec::new(),
    };
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
                let [x0, y0, x1, y1] = f.bbox_px.map(f64::from);
                summary.box_height.push((y1 - y0) / h);
                summary.box_bottom.push(y1 / h);
                summary.box_centre.push((x0 + x1) / 2.0 / w);
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

/// Writes the report of `dir` (with `compare` beside it) to `out`; returns the line to print.
pub fn report(dir: &Path, compare: Option<&Path>, out: &Path) -> Result<String, Error> {
    if let Some(other) = compare
        && !other.join("manifest.json").is_file()
    {
        return Err(refuse(format!(
            "{}: not a pedsynth dataset (no manifest.json); --compare takes a generated dataset",
            other.display()
        )));
    }
    let mut summaries = vec![summarise(dir)?];
    if let Some(other) = compare {
        let mut s = summarise(other)?;
        if s.name == summaries[0].name {
            s.name = format!("{} (compared)", s.name);
        }
        summaries.push(s);
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
        ("weathers", &|s| escape(&s.stats.weathers.join(", "))),
    ];
    for (label, value) in rows {
        let _ = write!(h, "<tr><th>{label}</th>");
        for s in summaries {
            let _ = write!(h, "<td>{}</td>", value(s));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    for (title, plot) in TITLES.iter().zip(&plots) {
        let _ = writeln!(h, "<section><h2>{}</h2>{plot}</section>", escape(title));
    }
    let _ = writeln!(h, "<h2>{SAMPLES_TITLE}</h2>");
    for s in summaries {
        let _ = writeln!(h, "<h3>{}</h3><div>", escape(&s.name));
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
