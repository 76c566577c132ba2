//! Real annotations as `pedsynth calibrate` reads them: videos of pedestrian tracks (hand-drawn boxes, the
//! crossing label and event frame, standing/walking and looking where annotated) and the ego's action per frame,
//! from JAAD's or PIE's XML layout ([`super::xml`]) or from the documented table layout (Parquet or CSV, below).
//!
//! The table layout (DATASET.md, "Calibrating to real data"), one file per table, `.parquet` or `.csv`:
//! - `videos`: `video`, `split`, `width`, `height`, optional `fps` (30 when absent);
//! - `boxes`: `video`, `pedestrian`, `frame`, `x_min`, `y_min`, `x_max`, `y_max` (pixels), optional `occlusion`
//!   (0 none, 1 part, 2 full), `cross` (1 crossing), `action` (0 standing, 1 walking), `look` (0/1);
//! - `pedestrians`: `video`, `pedestrian`, `crossing` (1 crosses; anything else does not), optional
//!   `crossing_point` (the event frame; -1 or empty: none, and the crosser's whole track counts, as JAAD's loader
//!   has it; without the column, a crosser's first box with `cross` = 1);
//! - `vehicle` (optional): `video`, `frame`, `action` (`stopped`, `moving_slow`, `moving_fast`, `decelerating`,
//!   `accelerating`).

use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};

use arrow_array::cast::AsArray;
use arrow_array::types::{
    Float32Type, Float64Type, Int8Type, Int16Type, Int32Type, Int64Type, UInt8Type, UInt16Type, UInt32Type, UInt64Type,
};
use arrow_array::{Array, RecordBatch};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

use crate::error::{Error, code};

/// One annotated box of a pedestrian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RealBox {
    /// Video frame.
    pub frame: u32,
    /// Left, top, right, bottom, pixels.
    pub x_min_px: f64,
    /// Top.
    pub y_min_px: f64,
    /// Right.
    pub x_max_px: f64,
    /// Bottom.
    pub y_max_px: f64,
    /// Partly or fully occluded.
    pub occluded: bool,
    /// Standing (not walking), where annotated.
    pub standing: Option<bool>,
    /// Looking at the ego, where annotated.
    pub looking: Option<bool>,
}

/// A pedestrian's track.
#[derive(Clone, Debug, PartialEq)]
pub struct RealTrack {
    /// The pedestrian's id in its video.
    pub id: String,
    /// Sequence label: the pedestrian crosses.
    pub crosser: bool,
    /// A crosser's event frame (its crossing point).
    pub crossing_frame: Option<u32>,
    /// Boxes in frame order.
    pub boxes: Vec<RealBox>,
}

/// The ego's driving action in a frame (JAAD's vocabulary).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum EgoAction {
    /// Standing still.
    Stopped,
    /// Moving slowly.
    MovingSlow,
    /// Moving fast.
    MovingFast,
    /// Slowing down.
    Decelerating,
    /// Speeding up.
    Accelerating,
}

impl EgoAction {
    /// Every action, in report order.
    pub const ALL: [EgoAction; 5] = [
        EgoAction::Stopped,
        EgoAction::MovingSlow,
        EgoAction::MovingFast,
        EgoAction::Decelerating,
        EgoAction::Accelerating,
    ];

    /// JAAD's name.
    pub fn name(self) -> &'static str {
        match self {
            EgoAction::Stopped => "stopped",
            EgoAction::MovingSlow => "moving_slow",
            EgoAction::MovingFast => "moving_fast",
            EgoAction::Decelerating => "decelerating",
            EgoAction::Accelerating => "accelerating",
        }
    }

    /// The action of JAAD's name.
    pub fn from_name(name: &str) -> Option<EgoAction> {
        EgoAction::ALL.into_iter().find(|a| a.name() == name)
    }

    /// The action of a speed and acceleration (pedsynth's frames, PIE's OBD): stopped under 0.3 m/s,
    /// decelerating / accelerating beyond ∓0.5 m/s², else slow under 20 km/h (5.6 m/s), else fast.
    pub fn from_motion(speed_mps: f64, accel_mps2: f64) -> EgoAction {
        if speed_mps < 0.3 {
            EgoAction::Stopped
        } else if accel_mps2 < -0.5 {
            EgoAction::Decelerating
        } else if accel_mps2 > 0.5 {
            EgoAction::Accelerating
        } else if speed_mps < 20.0 / 3.6 {
            EgoAction::MovingSlow
        } else {
            EgoAction::MovingFast
        }
    }
}

/// One video (or pedsynth clip) of real annotations.
#[derive(Clone, Debug, PartialEq)]
pub struct RealVideo {
    /// Video name.
    pub name: String,
    /// Its split (`train`, `val`, `test`, or what the source calls it).
    pub split: String,
    /// Image width, pixels.
    pub width_px: f64,
    /// Image height, pixels.
    pub height_px: f64,
    /// Frames per second.
    pub fps: f64,
    /// Pedestrian tracks, sorted by id.
    pub tracks: Vec<RealTrack>,
    /// The ego's action per frame, where annotated.
    pub ego_actions: BTreeMap<u32, EgoAction>,
}

/// An error about the real input (exit code 2).
pub(super) fn invalid(message: impl Into<String>) -> Error {
    Error::new(code::REAL_INVALID, message)
}

/// A cell of a table read from Parquet or CSV.
#[derive(Clone, Debug, PartialEq)]
enum Cell {
    Null,
    Num(f64),
    Str(String),
}

impl Cell {
    fn num(&self) -> Option<f64> {
        match self {
            Cell::Num(x) => Some(*x),
            Cell::Str(s) => s.trim().parse().ok(),
            Cell::Null => None,
        }
    }

    fn text(&self) -> String {
        match self {
            Cell::Num(x) if x.fract() == 0.0 && x.abs() < 1e15 => format!("{}", *x as i64),
            Cell::Num(x) => x.to_string(),
            Cell::Str(s) => s.clone(),
            Cell::Null => String::new(),
        }
    }
}

/// A table as named columns of cells.
struct Table {
    path: PathBuf,
    rows: usize,
    columns: BTreeMap<String, Vec<Cell>>,
}

impl Table {
    fn column(&self, name: &str) -> Result<&[Cell], Error> {
        self.columns.get(name).map(Vec::as_slice).ok_or_else(|| {
            invalid(format!("{}: no column `{name}`", self.path.display()))
                .help("see DATASET.md, \"Calibrating to real data\", for the table layout")
        })
    }

    fn optional(&self, name: &str) -> Option<&[Cell]> {
        self.columns.get(name).map(Vec::as_slice)
    }

    fn num(&self, name: &str, row: usize) -> Result<f64, Error> {
        self.column(name)?[row].num().filter(|x| x.is_finite()).ok_or_else(|| {
            invalid(format!(
                "{}: row {}: `{name}` is not a number",
                self.path.display(),
                row + 1
            ))
        })
    }
}

/// Reads `dir/name.parquet` or `dir/name.csv`; `None` when neither exists.
fn read_table(dir: &Path, name: &str) -> Result<Option<Table>, Error> {
    let parquet = dir.join(format!("{name}.parquet"));
    let csv = dir.join(format!("{name}.csv"));
    if parquet.is_file() {
        read_parquet(&parquet).map(Some)
    } else if csv.is_file() {
        read_csv(&csv).map(Some)
    } else {
        Ok(None)
    }
}

fn read_parquet(path: &Path) -> Result<Table, Error> {
    let bad = |e: &dyn std::fmt::Display| invalid(format!("{}: {e}", path.display()));
    let file = File::open(path).map_err(|e| Error::read(path, e))?;
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        .map_err(|e| bad(&e))?
        .build()
        .map_err(|e| bad(&e))?;
    let mut table = Table {
        path: path.to_path_buf(),
        rows: 0,
        columns: BTreeMap::new(),
    };
    for batch in reader {
        let batch: RecordBatch = batch.map_err(|e| bad(&e))?;
        for (field, array) in batch.schema().fields().iter().zip(batch.columns()) {
            let cells = table.columns.entry(field.name().clone()).or_default();
            cells.resize(table.rows, Cell::Null);
            append_cells(array.as_ref(), cells);
        }
        table.rows += batch.num_rows();
    }
    for cells in table.columns.values_mut() {
        cells.resize(table.rows, Cell::Null);
    }
    Ok(table)
}

/// Appends an Arrow column's values as cells (numbers of any width, booleans as 0/1, strings; anything else
/// as null).
fn append_cells(array: &dyn Array, cells: &mut Vec<Cell>) {
    macro_rules! numbers {
        ($($t:ty),*) => {
            $(if let Some(a) = array.as_primitive_opt::<$t>() {
                cells.extend((0..a.len()).map(|i| if a.is_null(i) { Cell::Null } else { Cell::Num(a.value(i) as f64) }));
                return;
            })*
        };
    }
    numbers!(
        Float64Type,
        Float32Type,
        Int64Type,
        Int32Type,
        Int16Type,
        Int8Type,
        UInt64Type,
        UInt32Type,
        UInt16Type,
        UInt8Type
    );
    if let Some(a) = array.as_boolean_opt() {
        cells.extend((0..a.len()).map(|i| {
            if a.is_null(i) {
                Cell::Null
            } else {
                Cell::Num(f64::from(u8::from(a.value(i))))
            }
        }));
    } else if let Some(a) = array.as_string_opt::<i32>() {
        cells.extend((0..a.len()).map(|i| {
            if a.is_null(i) {
                Cell::Null
            } else {
                Cell::Str(a.value(i).to_owned())
            }
        }));
    } else if let Some(a) = array.as_string_opt::<i64>() {
        cells.extend((0..a.len()).map(|i| {
            if a.is_null(i) {
                Cell::Null
            } else {
                Cell::Str(a.value(i).to_owned())
            }
        }));
    } else {
        cells.extend((0..array.len()).map(|_| Cell::Null));
    }
}

/// A CSV file with a header row; fields separated by commas, optionally in double quotes (`""` for a quote);
/// an empty field is null.
fn read_csv(path: &Path) -> Result<Table, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines
        .next()
        .ok_or_else(|| invalid(format!("{}: empty file (a header row is needed)", path.display())))?;
    let names = split_csv(header);
    let mut columns: Vec<Vec<Cell>> = vec![Vec::new(); names.len()];
    let mut rows = 0;
    for (i, line) in lines.enumerate() {
        let fields = split_csv(line);
        if fields.len() != names.len() {
            return Err(invalid(format!(
                "{}: line {}: {} fields where the header has {}",
                path.display(),
                i + 2,
                fields.len(),
                names.len()
            )));
        }
        for (column, field) in columns.iter_mut().zip(fields) {
            column.push(if field.is_empty() {
                Cell::Null
            } else if let Ok(x) = field.parse::<f64>() {
                Cell::Num(x)
            } else {
                Cell::Str(field)
            });
        }
        rows += 1;
    }
    Ok(Table {
        path: path.to_path_buf(),
        rows,
        columns: names.into_iter().zip(columns).collect(),
    })
}

fn split_csv(line: &str) -> Vec<String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.trim_end_matches('\r').chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(std::mem::take(&mut field).trim().to_owned()),
            (c, _) => field.push(c),
        }
    }
    fields.push(field.trim().to_owned());
    fields
}

/// Reads the table layout from `dir` (see the module's documentation).
pub fn read_tables(dir: &Path) -> Result<Vec<RealVideo>, Error> {
    let missing = |name: &str| {
        invalid(format!("{}: no `{name}.parquet` or `{name}.csv`", dir.display()))
            .help("see DATASET.md, \"Calibrating to real data\", for the table layout")
    };
    let videos = read_table(dir, "videos")?.ok_or_else(|| missing("videos"))?;
    let boxes = read_table(dir, "boxes")?.ok_or_else(|| missing("boxes"))?;
    let pedestrians = read_table(dir, "pedestrians")?.ok_or_else(|| missing("pedestrians"))?;
    let vehicle = read_table(dir, "vehicle")?;

    let mut out: BTreeMap<String, RealVideo> = BTreeMap::new();
    for row in 0..videos.rows {
        let name = videos.column("video")?[row].text();
        let video = RealVideo {
            name: name.clone(),
            split: videos.column("split")?[row].text(),
            width_px: videos.num("width", row)?,
            height_px: videos.num("height", row)?,
            fps: videos.optional("fps").and_then(|c| c[row].num()).unwrap_or(30.0),
            tracks: Vec::new(),
            ego_actions: BTreeMap::new(),
        };
        if video.width_px < 1.0 || video.height_px < 1.0 || video.fps <= 0.0 {
            return Err(invalid(format!(
                "{}: video `{name}` has no image size or frame rate",
                videos.path.display()
            )));
        }
        out.insert(name, video);
    }
    let mut labels: BTreeMap<(String, String), (bool, Option<f64>)> = BTreeMap::new();
    for row in 0..pedestrians.rows {
        let key = (
            pedestrians.column("video")?[row].text(),
            pedestrians.column("pedestrian")?[row].text(),
        );
        let crosser = pedestrians.column("crossing")?[row].num() == Some(1.0);
        let point = pedestrians
            .optional("crossing_point")
            .and_then(|c| c[row].num())
            .filter(|&f| f >= 0.0);
        labels.insert(key, (crosser, point));
    }
    let has_point_column = pedestrians.optional("crossing_point").is_some();
    let flag = |name: &str, row: usize| boxes.optional(name).and_then(|c| c[row].num());
    let mut tracks: BTreeMap<(String, String), Vec<(RealBox, bool)>> = BTreeMap::new();
    for row in 0..boxes.rows {
        let key = (
            boxes.column("video")?[row].text(),
            boxes.column("pedestrian")?[row].text(),
        );
        let frame = boxes.num("frame", row)?;
        let b = RealBox {
            frame: frame.max(0.0) as u32,
            x_min_px: boxes.num("x_min", row)?,
            y_min_px: boxes.num("y_min", row)?,
            x_max_px: boxes.num("x_max", row)?,
            y_max_px: boxes.num("y_max", row)?,
            occluded: flag("occlusion", row).is_some_and(|o| o > 0.0),
            standing: flag("action", row).map(|a| a == 0.0),
            looking: flag("look", row).map(|l| l > 0.0),
        };
        tracks
            .entry(key)
            .or_default()
            .push((b, flag("cross", row) == Some(1.0)));
    }
    for ((video, id), mut rows) in tracks {
        let Some(v) = out.get_mut(&video) else {
            return Err(invalid(format!(
                "{}: boxes of video `{video}`, which `videos` does not list",
                boxes.path.display()
            )));
        };
        rows.sort_by_key(|(b, _)| b.frame);
        let (crosser, point) = labels
            .get(&(video.clone(), id.clone()))
            .copied()
            .unwrap_or((false, None));
        // As JAAD's loader: a crosser without a crossing point (-1) keeps its whole track.
        let first_cross = || rows.iter().find(|(_, c)| *c).map(|(b, _)| b.frame);
        let crossing_frame = match (crosser, point) {
            (false, _) => None,
            (true, Some(p)) => Some(p as u32),
            (true, None) if has_point_column => None,
            (true, None) => first_cross(),
        };
        v.tracks.push(RealTrack {
            id,
            crosser,
            crossing_frame,
            boxes: rows.into_iter().map(|(b, _)| b).collect(),
        });
    }
    if let Some(vehicle) = vehicle {
        for row in 0..vehicle.rows {
            let name = vehicle.column("video")?[row].text();
            let action = vehicle.column("action")?[row].text();
            if let (Some(v), Some(a)) = (out.get_mut(&name), EgoAction::from_name(&action)) {
                v.ego_actions.insert(vehicle.num("frame", row)?.max(0.0) as u32, a);
            }
        }
    }
    Ok(out.into_values().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_split_with_quotes() {
        assert_eq!(split_csv("a, \"b,c\" ,\"d\"\"e\",,"), ["a", "b,c", "d\"e", "", ""]);
    }

    #[test]
    fn ego_actions_from_motion() {
        assert_eq!(EgoAction::from_motion(0.1, 0.0), EgoAction::Stopped);
        assert_eq!(EgoAction::from_motion(8.0, -1.0), EgoAction::Decelerating);
        assert_eq!(EgoAction::from_motion(4.0, 0.0), EgoAction::MovingSlow);
        assert_eq!(EgoAction::from_motion(10.0, 0.1), EgoAction::MovingFast);
    }
}
