//! The dataset's Parquet tables: schemas (keys first, Waymo-v2 style), Arrow record batches built from a
//! clip's script, trace and annotations, encoded as Parquet bytes (the writer stores them atomically).
//!
//! Layout: `tables/<table>/<clip_id>.parquet`, one file per clip and table, so that pyarrow, polars and DuckDB
//! read each table directory as one dataset. Every file carries `pedsynth.schema_version`, `pedsynth.version`,
//! `pedsynth.spec_hash` and `pedsynth.clip_id` in its key-value metadata. DATASET.md documents every column.

mod clip;
mod people;
mod traffic;

use std::sync::Arc;

use arrow_array::builder::{FixedSizeListBuilder, Float32Builder};
use arrow_array::{
    ArrayRef, BooleanArray, Float32Array, Float64Array, Int32Array, Int64Array, RecordBatch, StringArray, UInt32Array,
    UInt64Array,
};
use arrow_schema::{DataType, Field};
use parquet::arrow::ArrowWriter;
use parquet::basic::{Compression as ParquetCompression, ZstdLevel};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{WriterProperties, WriterPropertiesBuilder};

use super::columns::{Table, repeated_utf8};
use crate::error::{Error, code};
use crate::plan::ClipScript;
use crate::sensors::annotate::ClipAnnotations;
use crate::sim::trace::{ClipTrace, Event, LightState, PedestrianId, VehicleId, WalkSignal};
use crate::spec::types::{Compression, Output, PoseFormat};
use crate::world::LaneType;
pub use clip::*;
pub use people::*;
pub use traffic::*;

/// Version of the table schemas; bump on any change to a column.
pub const SCHEMA_VERSION: u32 = 12;

/// The tables, in the order they are written (`clips` last: its file marks the clip complete).
pub const TABLES: [&str; 12] = [
    "frames",
    "pedestrians",
    "annotations",
    "tracks",
    "vehicles",
    "cyclists",
    "parked_cars",
    "events",
    "traffic_lights",
    "sensor_poses",
    "sensors",
    "clips",
];

/// Metadata every file carries.
#[derive(Clone, Debug)]
pub struct FileMeta {
    /// blake3 of the resolved spec.
    pub spec_hash: String,
}

fn lane_name(l: LaneType) -> &'static str {
    match l {
        LaneType::Driving => "driving",
        LaneType::Sidewalk => "sidewalk",
        LaneType::Shoulder => "shoulder",
        LaneType::Parking => "parking",
        LaneType::Median => "median",
        LaneType::Border => "border",
        LaneType::Biking => "biking",
        LaneType::Other => "other",
    }
}

fn snake<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_value(value)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

/// The Parquet writer settings of a dataset file: the spec's codec (zstd by default) and the file's key-value
/// metadata.
pub fn writer_properties(output: &Output, meta: &FileMeta, table: &str, clip_id: &str) -> WriterProperties {
    properties_builder(output, meta, table, clip_id).build()
}

/// [`writer_properties`] for the DVS events: millions of rows of mostly distinct values, where dictionary pages
/// cost time (interning every value) and zstd alone packs tighter (quickstart: 81.7 MB instead of 89.0 MB;
/// the LiDAR's quantised columns are the other way round, 158 MB with dictionaries and 205 MB without).
pub fn events_writer_properties(output: &Output, meta: &FileMeta, table: &str, clip_id: &str) -> WriterProperties {
    properties_builder(output, meta, table, clip_id)
        .set_dictionary_enabled(false)
        .build()
}

fn properties_builder(output: &Output, meta: &FileMeta, table: &str, clip_id: &str) -> WriterPropertiesBuilder {
    let compression = match output.compression {
        Compression::Zstd => ParquetCompression::ZSTD(ZstdLevel::try_new(output.zstd_level as i32).unwrap_or_default()),
        Compression::Snappy => ParquetCompression::SNAPPY,
        Compression::None => ParquetCompression::UNCOMPRESSED,
    };
    let kv = |k: &str, v: String| KeyValue::new(k.to_owned(), v);
    WriterProperties::builder()
        .set_compression(compression)
        .set_created_by(format!("pedsynth {}", env!("CARGO_PKG_VERSION")))
        .set_key_value_metadata(Some(vec![
            kv("pedsynth.schema_version", SCHEMA_VERSION.to_string()),
            kv("pedsynth.version", env!("CARGO_PKG_VERSION").to_owned()),
            kv("pedsynth.spec_hash", meta.spec_hash.clone()),
            kv("pedsynth.table", table.to_owned()),
            kv("pedsynth.clip_id", clip_id.to_owned()),
        ]))
}

/// The error of a file that cannot be encoded as Parquet.
pub fn parquet_error(table: &str, clip_id: &str, e: &parquet::errors::ParquetError) -> Error {
    Error::new(
        code::INTERNAL_SERIALIZE,
        format!("cannot encode table `{table}` of clip {clip_id} as Parquet: {e}"),
    )
}

/// The Parquet bytes of a record batch, with [`writer_properties`].
pub fn parquet_bytes(
    batch: &RecordBatch,
    output: &Output,
    meta: &FileMeta,
    table: &str,
    clip_id: &str,
) -> Result<Vec<u8>, Error> {
    let props = writer_properties(output, meta, table, clip_id);
    let encode = || -> Result<Vec<u8>, parquet::errors::ParquetError> {
        let mut writer = ArrowWriter::try_new(Vec::new(), batch.schema(), Some(props))?;
        writer.write(batch)?;
        writer.into_inner()
    };
    encode().map_err(|e| parquet_error(table, clip_id, &e))
}
