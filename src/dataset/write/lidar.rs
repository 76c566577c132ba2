//! LiDAR files of a clip, written tick by tick as the scan produces them.
//!
//! ```text
//! sensors/lidar/<clip_id>.parquet           format parquet (default): every point of the clip, see lidar_schema
//! sensors/lidar/<clip_id>/<frame:06>.bin    format carla_bin: the seed's layout, little-endian f32 x y z intensity
//! ```
//!
//! Points are in CARLA's sensor frame (x forward, y right, z up, metres); `tables/sensor_poses` holds the
//! sensor's pose per frame. The Parquet file is streamed into a temporary file (a clip has millions of
//! points) and renamed when the clip's last tick is in; each `.bin` is written atomically.

use std::sync::Arc;

use arrow_array::{ArrayRef, Float32Array, Int64Array, RecordBatch, StringArray, UInt8Array, UInt16Array, UInt32Array};
use arrow_schema::SchemaRef;
use parquet::arrow::ArrowWriter;
use sha2::{Digest, Sha256};

use super::Layout;
use super::columns::Table;
use super::sensors::{IndexRow, LIDAR_STREAM, hex};
use super::tables::{self, FileMeta};
use crate::error::Error;
use crate::sensors::LidarFrame;
use crate::sensors::lidar::LidarPoint;
use crate::sensors::scene::actor_of_instance;
use crate::spec::types::{Lidar, LidarFormat, Output};
use crate::util::files::{AtomicFile, write_atomically_unsynced};

/// The schema of a clip's LiDAR Parquet file (the table of no points): see [`lidar_batch`].
pub fn lidar_schema() -> SchemaRef {
    lidar_batch("", 0, 0, &[]).schema()
}

/// One tick's points: per point its position and intensity in the sensor's frame, the cosine of the incidence
/// angle, CARLA's semantic tag, the instance id and the actor id it maps to (null for the town).
pub fn lidar_batch(clip_id: &str, frame: u32, timestamp_ns: i64, points: &[LidarPoint]) -> RecordBatch {
    let f =
        |get: fn(&LidarPoint) -> f32| -> ArrayRef { Arc::new(Float32Array::from_iter_values(points.iter().map(get))) };
    Table::new()
        .column(
            "clip_id",
            false,
            Arc::new(StringArray::from_iter_values(points.iter().map(|_| clip_id))),
        )
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(points.iter().map(|_| frame))),
        )
        .column(
            "timestamp_ns",
            false,
            Arc::new(Int64Array::from_iter_values(points.iter().map(|_| timestamp_ns))),
        )
        .column("x", false, f(|p| p.x_m))
        .column("y", false, f(|p| p.y_m))
        .column("z", false, f(|p| p.z_m))
        .column("intensity", false, f(|p| p.intensity))
        .column("cos_incidence", false, f(|p| p.cos_incidence))
        .column(
            "tag",
            false,
            Arc::new(UInt8Array::from_iter_values(points.iter().map(|p| p.tag))),
        )
        .column(
            "instance",
            false,
            Arc::new(UInt16Array::from_iter_values(points.iter().map(|p| p.instance))),
        )
        .column(
            "actor_id",
            true,
            Arc::new(UInt32Array::from_iter(
                points.iter().map(|p| actor_of_instance(p.instance)),
            )),
        )
        .finish()
}

/// The seed's `.bin` layout of one tick: little-endian f32 `x y z intensity` per point.
pub fn carla_bin(points: &[LidarPoint]) -> Vec<u8> {
    points
        .iter()
        .flat_map(|p| [p.x_m, p.y_m, p.z_m, p.intensity])
        .flat_map(f32::to_le_bytes)
        .collect()
}

/// Writes one clip's LiDAR files as ticks arrive.
pub struct ClipLidarWriter<'a> {
    layout: &'a Layout,
    clip_id: &'a str,
    rows: Vec<IndexRow>,
    parquet: Option<ArrowWriter<AtomicFile>>,
}

impl std::fmt::Debug for ClipLidarWriter<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClipLidarWriter")
            .field("clip_id", &self.clip_id)
            .field("files", &self.rows.len())
            .finish()
    }
}

impl<'a> ClipLidarWriter<'a> {
    /// A writer for one clip; `meta` goes into its Parquet file's metadata.
    pub fn new(
        layout: &'a Layout,
        clip_id: &'a str,
        lidar: &Lidar,
        output: &Output,
        meta: &FileMeta,
    ) -> Result<Self, Error> {
        let parquet = match lidar.format {
            LidarFormat::Parquet => {
                let path = layout.sensor_clip(LIDAR_STREAM, clip_id, "parquet");
                let file = AtomicFile::create(&path).map_err(|e| Error::write(&path, e))?;
                let props = tables::writer_properties(output, meta, LIDAR_STREAM, clip_id);
                Some(
                    ArrowWriter::try_new(file, lidar_schema(), Some(props))
                        .map_err(|e| tables::parquet_error(LIDAR_STREAM, clip_id, &e))?,
                )
            }
            LidarFormat::CarlaBin => None,
        };
        Ok(ClipLidarWriter {
            layout,
            clip_id,
            rows: Vec::new(),
            parquet,
        })
    }

    /// Writes one tick.
    pub fn tick(&mut self, t: LidarFrame) -> Result<(), Error> {
        if let Some(w) = self.parquet.as_mut() {
            if !t.points.is_empty() {
                w.write(&lidar_batch(self.clip_id, t.frame, t.timestamp_ns, t.points))
                    .map_err(|e| tables::parquet_error(LIDAR_STREAM, self.clip_id, &e))?;
            }
            return Ok(());
        }
        let path = self.layout.sensor_frame(LIDAR_STREAM, self.clip_id, t.frame, "bin");
        let bytes = carla_bin(t.points);
        write_atomically_unsynced(&path, &bytes).map_err(|e| Error::write(&path, e))?;
        self.rows.push(IndexRow {
            frame: Some(t.frame),
            timestamp_ns: Some(t.timestamp_ns),
            stream: LIDAR_STREAM,
            path: self.layout.relative(&path),
            bytes: bytes.len() as u64,
            sha256: hex(&Sha256::digest(&bytes)),
        });
        Ok(())
    }

    /// Completes the clip's Parquet file (if that is the format) and returns the index rows.
    pub fn finish(mut self) -> Result<Vec<IndexRow>, Error> {
        if let Some(w) = self.parquet.take() {
            let path = self.layout.sensor_clip(LIDAR_STREAM, self.clip_id, "parquet");
            let file = w
                .into_inner()
                .map_err(|e| tables::parquet_error(LIDAR_STREAM, self.clip_id, &e))?;
            let (bytes, sha) = file.commit().map_err(|e| Error::write(&path, e))?;
            self.rows.push(IndexRow {
                frame: None,
                timestamp_ns: None,
                stream: LIDAR_STREAM,
                path: self.layout.relative(&path),
                bytes,
                sha256: hex(&sha),
            });
        }
        Ok(self.rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn carla_bin_is_four_little_endian_floats_per_point() {
        let p = LidarPoint {
            x_m: 1.0,
            y_m: -2.0,
            z_m: 0.5,
            intensity: 0.25,
            cos_incidence: 1.0,
            tag: 1,
            instance: 0,
        };
        let b = carla_bin(&[p, p]);
        assert_eq!(b.len(), 32);
        assert_eq!(f32::from_le_bytes(b[4..8].try_into().unwrap()), -2.0);
        assert_eq!(f32::from_le_bytes(b[28..32].try_into().unwrap()), 0.25);
    }
}
