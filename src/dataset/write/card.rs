//! The dataset card: the `README.md` that `generate` writes into a finished dataset. It says what the dataset
//! is, which spec made it, its counts and crossing ratio, its sensors and licence, and carries Hugging Face
//! front matter (`license`, `configs:` with one config per table naming its Parquet files per split), so that
//! `datasets.load_dataset(DIR, "annotations")` loads a table as is, and the Hub shows the card.
//!
//! Pure text from the spec, the manifest and the statistics of the tables: no date, no absolute path, so the
//! card is as reproducible as the tables.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::dataset::read::stats::DatasetStats;
use crate::dataset::write::manifest::Manifest;
use crate::dataset::write::tables::TABLES;
use crate::spec::Spec;

/// The card's file name in the dataset directory.
pub const CARD_FILE: &str = "README.md";

/// Hugging Face's name of one of our splits.
fn hf_split(split: &str) -> &str {
    match split {
        "val" => "validation",
        other => other,
    }
}

/// Hugging Face's size category of a number of samples.
fn size_category(n: u64) -> &'static str {
    match n {
        0..1_000 => "n<1K",
        1_000..10_000 => "1K<n<10K",
        10_000..100_000 => "10K<n<100K",
        100_000..1_000_000 => "100K<n<1M",
        1_000_000..10_000_000 => "1M<n<10M",
        _ => "10M<n<100M",
    }
}

fn quoted(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".to_owned())
}

/// What each table holds, for the card's table list (DATASET.md has the columns).
fn table_summary(table: &str) -> &'static str {
    match table {
        "clips" => "one row per clip: town, weather, split, seed, counts",
        "frames" => "one row per frame: time and the ego's pose, speed and acceleration",
        "pedestrians" => "one row per pedestrian: archetype, behaviour, sequence label (crosser), intention onset",
        "annotations" => {
            "one row per annotated pedestrian-frame: box, crossing label C, behaviour state, TTE, occlusion, COCO-17 \
             keypoints (2D and 3D), 3D box"
        }
        "tracks" => "one row per pedestrian and frame, seen or not: position, velocity, state, C",
        "vehicles" => "one row per traffic vehicle and frame: pose, speed, driving profile",
        "events" => "state changes, crossing decisions, conflicts, contacts, red lights run or stopped for",
        "traffic_lights" => "one row per traffic light near the ego and frame: id, junction, phase, state, position",
        "sensor_poses" => "each sensor's world pose per frame",
        "sensors" => "one row per sensor file (path, size, SHA-256)",
        _ => "",
    }
}

/// Calls its argument with each clip's id and split (`train`, `val`, `test`), in plan order: the card walks the
/// clips once per table and split instead of holding their list.
pub type ClipList<'a> = &'a dyn Fn(&mut dyn FnMut(&str, &str));

/// The card of a finished dataset, as text ([`write`]).
pub fn render<C>(
    spec: &Spec,
    manifest: &Manifest<C>,
    clips: ClipList<'_>,
    rows: &BTreeMap<(&str, &str), u64>,
    stats: &DatasetStats,
) -> String {
    let mut bytes = Vec::new();
    // Writing into memory does not fail.
    let _ = write(spec, manifest, clips, rows, stats, &mut bytes);
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Writes the card of a finished dataset to `out`, streamed (its file lists grow with the clips). `clips`
/// gives each clip id and its split in plan order ([`ClipList`]); `rows` the rows of each (table,
/// split). A split whose files of a table hold no row is left out of that table's config (`datasets` cannot
/// load a split without data), and a table without any row gets no config.
pub fn write<C>(
    spec: &Spec,
    manifest: &Manifest<C>,
    clips: ClipList<'_>,
    rows: &BTreeMap<(&str, &str), u64>,
    stats: &DatasetStats,
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let mut x = Text { out, error: None };
    write_text(spec, manifest, clips, rows, stats, &mut x);
    x.error.map_or(Ok(()), Err)
}

/// `fmt::Write` into an `io::Write`, keeping the first IO error (the card's text is written with `write!`).
struct Text<'a> {
    out: &'a mut dyn std::io::Write,
    error: Option<std::io::Error>,
}

impl Text<'_> {
    fn push_str(&mut self, s: &str) {
        let _ = std::fmt::Write::write_str(self, s);
    }
}

impl std::fmt::Write for Text<'_> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        if self.error.is_some() {
            return Err(std::fmt::Error);
        }
        self.out.write_all(s.as_bytes()).map_err(|e| {
            self.error = Some(e);
            std::fmt::Error
        })
    }
}

fn write_text<C>(
    spec: &Spec,
    manifest: &Manifest<C>,
    clips: ClipList<'_>,
    rows: &BTreeMap<(&str, &str), u64>,
    stats: &DatasetStats,
    x: &mut Text<'_>,
) {
    // Each Hugging Face split name and our split it stands for.
    let mut by_split: BTreeMap<String, String> = BTreeMap::new();
    clips(&mut |_, split| {
        if !by_split.contains_key(hf_split(split)) {
            by_split.insert(hf_split(split).to_owned(), split.to_owned());
        }
    });
    let rows_of = |table: &str, split: &str| rows.get(&(table, split)).copied().unwrap_or(0);
    // Splits in the conventional order.
    let order = |s: &str| match s {
        "train" => 0,
        "validation" => 1,
        "test" => 2,
        _ => 3,
    };
    let mut splits: Vec<(String, String)> = by_split.into_iter().collect();
    splits.sort_by_key(|(s, _)| (order(s), s.to_string()));

    let _ = write!(
        x,
        "---\nlicense: {}\npretty_name: {}\ntags:\n- synthetic\n- pedestrian-crossing\n- pedestrian-intention\n- autonomous-driving\n- pedsynth\ntask_categories:\n- video-classification\n- object-detection\n- keypoint-detection\nsize_categories:\n- {}\nconfigs:\n",
        spec.dataset.license,
        quoted(&spec.dataset.name),
        size_category(stats.annotated_samples)
    );
    let mut empty = Vec::new();
    for table in TABLES {
        let filled: Vec<&(String, String)> = splits.iter().filter(|(_, ours)| rows_of(table, ours) > 0).collect();
        if filled.is_empty() {
            empty.push(table);
            continue;
        }
        let _ = writeln!(x, "- config_name: {table}");
        if table == "annotations" {
            x.push_str("  default: true\n");
        }
        x.push_str("  data_files:\n");
        for (split, ours) in filled {
            let _ = writeln!(x, "  - split: {split}\n    path:");
            clips(&mut |id, clip_split| {
                if clip_split == ours {
                    let _ = writeln!(x, "    - {}", quoted(&format!("tables/{table}/{id}.parquet")));
                }
            });
        }
    }
    x.push_str("---\n\n");

    let _ = write!(
        x,
        "# {}\n\nA synthetic pedestrian-crossing dataset generated by pedsynth {} (no game engine: its own \
         simulator and renderer) from the spec in `spec.resolved.yaml` (blake3 `{}`, dataset seed {}). The same \
         spec and pedsynth version give the same bytes: `pedsynth generate spec.resolved.yaml --out DIR` makes it \
         again, and `manifest.json` lists the blake3 of every table file.\n\n",
        spec.dataset.name, manifest.pedsynth_version, manifest.spec_hash, spec.dataset.seed
    );
    x.push_str("## Contents\n\n| | |\n|---|---|\n");
    let rows = [
        ("clips", stats.clips.to_string()),
        ("frames", format!("{} at {} FPS", stats.frames, spec.dataset.fps)),
        ("mean clip duration", format!("{:.1} s", stats.mean_duration_s)),
        ("pedestrians", stats.pedestrians.to_string()),
        (
            "crossing / not crossing (sequence label)",
            format!("{} / {}", stats.crossing, stats.non_crossing),
        ),
        (
            "crossing ratio",
            format!(
                "{:.3} achieved (target {:.3})",
                stats.achieved_crossing_ratio, manifest.target_crossing_ratio
            ),
        ),
        (
            "annotated samples (pedestrian-frames)",
            stats.annotated_samples.to_string(),
        ),
        ("annotated samples with C = 1", stats.crossing_samples.to_string()),
        ("towns", stats.towns.join(", ")),
        ("weathers", stats.weathers.join(", ")),
        ("licence", spec.dataset.license.clone()),
    ];
    for (k, v) in rows {
        let _ = writeln!(x, "| {k} | {v} |");
    }
    x.push_str("\n### Splits\n\n| split | clips | frames | pedestrians | crossers | annotated samples |\n|---|---|---|---|---|---|\n");
    for (split, c) in &stats.splits {
        let _ = writeln!(
            x,
            "| {} | {} | {} | {} | {} | {} |",
            hf_split(split),
            c.clips,
            c.frames,
            c.pedestrians,
            c.crossers,
            c.samples
        );
    }
    x.push_str("\n### Sensors\n\n");
    for (stream, status) in &manifest.sensors {
        let _ = writeln!(x, "- `{stream}`: {status}");
    }
    x.push_str(
        "\n### Tables\n\nParquet (zstd), one file per clip and table under `tables/<table>/<clip_id>.parquet`; \
         DATASET.md in pedsynth's repository documents every column and label.\n\n",
    );
    for table in TABLES {
        let note = if empty.contains(&table) {
            " (no rows in this dataset)"
        } else {
            ""
        };
        let _ = writeln!(x, "- `{table}`: {}{note}", table_summary(table));
    }
    x.push_str(
        "\n## Loading\n\n```python\nfrom datasets import load_dataset\nannotations = load_dataset(\"path/to/this/dataset\", \"annotations\")  # or \"tracks\", \"pedestrians\", ...\n\nimport pyarrow.dataset as pads\ntable = pads.dataset(\"path/to/this/dataset/tables/annotations\").to_table()\n```\n\n\
         `pedsynth export pie|jaad|pab-poses|seed-csv|openscenario DIR --out OUT` writes it in the layouts PIE's, \
         JAAD's and PedestrianActionBenchmark's loaders, the seed system's scripts and OpenSCENARIO players read.\n",
    );
    let _ = write!(
        x,
        "\n## Licence\n\n`{}` (the spec's `dataset.license`). The data is synthetic: no real person is depicted.\n",
        spec.dataset.license
    );
}
