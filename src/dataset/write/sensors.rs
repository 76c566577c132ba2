//! Sensor files: encoding and writing the camera streams of a clip as they are rendered, the DVS events of a
//! clip, and the sensor index table that joins them to the annotation tables on (clip_id, frame).
//!
//! ```text
//! sensors/rgb/<clip_id>/<frame:06>.png|jpg     sRGB 8-bit (PNG fast compression, or JPEG)
//! sensors/rgb/<clip_id>.mp4                    or H.264 video, sample i = frame i (see super::video)
//! sensors/depth/<clip_id>/<frame:06>.png       u16 millimetres (grey 16-bit), or CARLA's 24-bit RGB
//! sensors/semantic/<clip_id>/<frame:06>.png    CARLA tag ids as an indexed PNG whose palette is CARLA's
//! sensors/instance/<clip_id>/<frame:06>.png    u16 instance ids (grey 16-bit; see scene::CHILD_INSTANCE_BASE)
//! sensors/dvs/<clip_id>.parquet                events: frame, t_ns, x, y, polarity
//! tables/sensors/<clip_id>.parquet             clip_id, frame, timestamp_ns, stream, path, bytes, sha256
//! ```
//!
//! (LiDAR files: [`super::lidar`]; the index covers them too.)
//!
//! ```text
//! ```
//!
//! Every file is written atomically (a temporary name, then a rename). Blobs are not fsynced one by one
//! (thousands per clip); the clip's tables, written after every blob, mark it complete.

use std::sync::Arc;

use arrow_array::{BooleanArray, Int64Array, RecordBatch, StringArray, UInt16Array, UInt32Array, UInt64Array};
use arrow_schema::SchemaRef;
use parquet::arrow::ArrowWriter;
use rayon::prelude::*;
use sha2::{Digest, Sha256};

use super::Layout;
use super::columns::Table;
use super::tables::{self, FileMeta};
use crate::error::{Error, code};
use crate::sensors::SensorFrame;
use crate::sensors::camera::{CameraImages, SKY_DEPTH_M, dvs};
use crate::sensors::scene::tag;
use crate::spec::types::{DepthEncoding, Output, RgbEncoding, Sensors};
use crate::util::files::write_atomically_unsynced;

/// The camera streams, in the order they are written.
pub const CAMERA_STREAMS: [&str; 5] = ["rgb", "depth", "semantic", "instance", "dvs"];

/// Every sensor stream, in the order of the sensor index within a frame.
pub const STREAMS: [&str; 6] = ["rgb", "depth", "semantic", "instance", "dvs", LIDAR_STREAM];

/// The LiDAR's stream name in the sensor index and under `sensors/`.
pub const LIDAR_STREAM: &str = "lidar";

/// Sorts index rows by (frame, stream in [`STREAMS`] order); per-clip files (no frame) first.
pub fn sort_index(rows: &mut [IndexRow]) {
    let order = |s: &str| STREAMS.iter().position(|x| *x == s).unwrap_or(usize::MAX);
    rows.sort_by_key(|r| (r.frame, order(r.stream)));
}

/// One row of the sensor index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IndexRow {
    /// Frame (None for a per-clip file such as the DVS events).
    pub frame: Option<u32>,
    /// Simulated time of the frame, nanoseconds (None for a per-clip file).
    pub timestamp_ns: Option<i64>,
    /// Stream name.
    pub stream: &'static str,
    /// Path relative to the dataset root, `/`-separated.
    pub path: String,
    /// File size.
    pub bytes: u64,
    /// SHA-256 of the file, hex.
    pub sha256: String,
}

/// Writes one clip's sensor files as frames arrive. DVS events go into the clip's Parquet writer frame by
/// frame (encoded and compressed as they come), so a clip's events are never all held raw in memory.
pub struct ClipSensorWriter<'a> {
    layout: &'a Layout,
    clip_id: &'a str,
    sensors: &'a Sensors,
    output: &'a Output,
    rows: Vec<IndexRow>,
    dvs: Option<ArrowWriter<Vec<u8>>>,
    video: Option<super::video::ClipVideo>,
    fps: u32,
}

impl std::fmt::Debug for ClipSensorWriter<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClipSensorWriter")
            .field("clip_id", &self.clip_id)
            .field("files", &self.rows.len())
            .finish()
    }
}

/// PNG bytes of an image: fast deflate, and one row filter for the whole image (`Adaptive` tries all five per
/// row; the streams' fixed choices below were measured on rendered frames: see BENCHMARKS.md).
pub fn png_bytes(
    width: usize,
    height: usize,
    colour: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
    filter: png::Filter,
    palette: Option<&[u8]>,
) -> Result<Vec<u8>, Error> {
    let mut out = Vec::with_capacity(data.len() / 2 + 1024);
    let fail = |e: png::EncodingError| Error::new(code::INTERNAL_SERIALIZE, format!("cannot encode a PNG image: {e}"));
    {
        let mut enc = png::Encoder::new(&mut out, width as u32, height as u32);
        enc.set_color(colour);
        enc.set_depth(depth);
        enc.set_compression(png::Compression::Fast);
        enc.set_filter(filter);
        if let Some(p) = palette {
            enc.set_palette(p.to_vec());
        }
        let mut w = enc.write_header().map_err(fail)?;
        w.write_image_data(data).map_err(fail)?;
        w.finish().map_err(fail)?;
    }
    Ok(out)
}

/// The semantic palette (CARLA's colours) as PNG `PLTE` bytes for all 256 indices.
pub const SEMANTIC_PALETTE: [u8; 768] = {
    let mut p = [0u8; 768];
    let mut i = 0;
    while i < tag::PALETTE.len() {
        p[3 * i] = tag::PALETTE[i][0];
        p[3 * i + 1] = tag::PALETTE[i][1];
        p[3 * i + 2] = tag::PALETTE[i][2];
        i += 1;
    }
    p
};

/// The `rgb` stream's PNG of a frame.
pub fn rgb_png(img: &CameraImages) -> Result<Vec<u8>, Error> {
    png_bytes(
        img.width,
        img.height,
        png::ColorType::Rgb,
        png::BitDepth::Eight,
        &img.rgb,
        png::Filter::Paeth,
        None,
    )
}

/// The `semantic` stream's PNG of a frame: tag ids as palette indices, CARLA's palette.
pub fn semantic_png(img: &CameraImages) -> Result<Vec<u8>, Error> {
    png_bytes(
        img.width,
        img.height,
        png::ColorType::Indexed,
        png::BitDepth::Eight,
        &img.semantic,
        png::Filter::Sub,
        Some(&SEMANTIC_PALETTE),
    )
}

/// `x.round()` as an integer for `x ≥ 0`, saturated at 2^52 (0 for NaN and below 0), without the call into libm
/// that `f64::round` compiles to on x86-64 without SSE4.1 (once per depth pixel). Exact: `x − trunc(x)` has
/// no rounding error.
#[inline(always)]
fn round_non_negative(x: f64) -> u64 {
    let x = x.clamp(0.0, 4_503_599_627_370_496.0);
    let t = x as u64;
    t + u64::from(x - t as f64 >= 0.5)
}

/// Depth in CARLA's 24-bit encoding: `(R, G, B)` with `R + 256 G + 65536 B = round(d / 1000 m × (2^24 − 1))`.
pub fn carla_depth_rgb(depth_m: f32) -> [u8; 3] {
    let v =
        round_non_negative((f64::from(depth_m.clamp(0.0, SKY_DEPTH_M)) / 1000.0) * f64::from((1u32 << 24) - 1)) as u32;
    [(v & 0xff) as u8, ((v >> 8) & 0xff) as u8, ((v >> 16) & 0xff) as u8]
}

/// Depth in millimetres, rounded half up and saturated at 65535 (0 for NaN and below 0). Exact: an `f32`
/// times 1000 fits an `f64`, and so does adding one half below 65536.
#[inline]
pub fn depth_mm(depth_m: f32) -> u16 {
    ((f64::from(depth_m) * 1000.0).clamp(0.0, 65535.0) + 0.5) as u16
}

/// A 16-bit greyscale PNG of `w × h` samples (row-major), stored big-endian as PNG holds them.
fn gray16_png(w: usize, h: usize, samples: impl Iterator<Item = u16>, filter: png::Filter) -> Result<Vec<u8>, Error> {
    let mut raw = vec![0u8; w * h * 2];
    for (out, v) in raw.chunks_exact_mut(2).zip(samples) {
        out.copy_from_slice(&v.to_be_bytes());
    }
    png_bytes(
        w,
        h,
        png::ColorType::Grayscale,
        png::BitDepth::Sixteen,
        &raw,
        filter,
        None,
    )
}

/// A stream written as one image file per frame.
#[derive(Clone, Copy, Debug)]
enum Still {
    Rgb,
    Depth,
    Semantic,
    Instance,
}

impl Still {
    /// Stream name and file extension.
    fn file(self, output: &Output) -> (&'static str, &'static str) {
        match self {
            Still::Rgb if output.rgb_encoding == RgbEncoding::Jpeg => ("rgb", "jpg"),
            Still::Rgb => ("rgb", "png"),
            Still::Depth => ("depth", "png"),
            Still::Semantic => ("semantic", "png"),
            Still::Instance => ("instance", "png"),
        }
    }

    /// The file's bytes for a frame.
    fn encode(self, img: &CameraImages, output: &Output) -> Result<Vec<u8>, Error> {
        let (w, h) = (img.width, img.height);
        match self {
            Still::Rgb => match output.rgb_encoding {
                RgbEncoding::Jpeg => {
                    let mut out = Vec::new();
                    jpeg_encoder::Encoder::new(&mut out, output.jpeg_quality.clamp(1, 100))
                        .encode(&img.rgb, w as u16, h as u16, jpeg_encoder::ColorType::Rgb)
                        .map_err(|e| {
                            Error::new(code::INTERNAL_SERIALIZE, format!("cannot encode a JPEG image: {e}"))
                        })?;
                    Ok(out)
                }
                RgbEncoding::Png | RgbEncoding::H264 => rgb_png(img),
            },
            Still::Depth => match output.depth_encoding {
                DepthEncoding::MillimetresU16 => {
                    gray16_png(w, h, img.depth_m.iter().map(|d| depth_mm(*d)), png::Filter::Paeth)
                }
                DepthEncoding::CarlaRgb24 => {
                    let raw: Vec<u8> = img.depth_m.iter().flat_map(|d| carla_depth_rgb(*d)).collect();
                    png_bytes(
                        w,
                        h,
                        png::ColorType::Rgb,
                        png::BitDepth::Eight,
                        &raw,
                        png::Filter::Paeth,
                        None,
                    )
                }
            },
            Still::Semantic => semantic_png(img),
            Still::Instance => gray16_png(w, h, img.instance.iter().copied(), png::Filter::Up),
        }
    }
}

impl<'a> ClipSensorWriter<'a> {
    /// A writer for one clip of `fps` frames per second; `meta` goes into its Parquet file's metadata.
    pub fn new(
        layout: &'a Layout,
        clip_id: &'a str,
        fps: u32,
        sensors: &'a Sensors,
        output: &'a Output,
        meta: &FileMeta,
    ) -> Result<Self, Error> {
        let dvs = if sensors.dvs.enabled {
            let props = tables::events_writer_properties(output, meta, "dvs", clip_id);
            Some(
                ArrowWriter::try_new(Vec::new(), dvs_schema(), Some(props))
                    .map_err(|e| tables::parquet_error("dvs", clip_id, &e))?,
            )
        } else {
            None
        };
        Ok(ClipSensorWriter {
            layout,
            clip_id,
            sensors,
            output,
            rows: Vec::new(),
            dvs,
            video: None,
            fps,
        })
    }

    fn path(&self, stream: &'static str, frame: Option<(u32, i64)>, ext: &str) -> std::path::PathBuf {
        match frame {
            Some((f, _)) => self.layout.sensor_frame(stream, self.clip_id, f, ext),
            None => self.layout.sensor_clip(stream, self.clip_id, ext),
        }
    }

    fn put(&mut self, stream: &'static str, frame: Option<(u32, i64)>, ext: &str, bytes: &[u8]) -> Result<(), Error> {
        let path = self.path(stream, frame, ext);
        write_atomically_unsynced(&path, bytes).map_err(|e| Error::write(&path, e))?;
        self.index(stream, frame, &path, bytes.len() as u64, &Sha256::digest(bytes));
        Ok(())
    }

    fn index(
        &mut self,
        stream: &'static str,
        frame: Option<(u32, i64)>,
        path: &std::path::Path,
        bytes: u64,
        sha: &[u8],
    ) {
        self.rows.push(IndexRow {
            frame: frame.map(|f| f.0),
            timestamp_ns: frame.map(|f| f.1),
            stream,
            path: self.layout.relative(path),
            bytes,
            sha256: hex(sha),
        });
    }

    /// Encodes and writes the enabled streams of one frame. The images of a frame are encoded in parallel on
    /// the current rayon pool (and beside the clip's video), then written and indexed in a fixed order.
    pub fn frame(&mut self, f: SensorFrame) -> Result<(), Error> {
        let img: &CameraImages = f.images;
        let at = Some((f.frame, f.timestamp_ns));
        let (sensors, output) = (self.sensors, self.output);
        let mut stills: Vec<Still> = Vec::with_capacity(4);
        if sensors.rgb.enabled && output.rgb_encoding != RgbEncoding::H264 {
            stills.push(Still::Rgb);
        }
        if sensors.depth.enabled {
            stills.push(Still::Depth);
        }
        if sensors.semantic.enabled {
            stills.push(Still::Semantic);
        }
        if sensors.instance.enabled {
            stills.push(Still::Instance);
        }
        if sensors.rgb.enabled && output.rgb_encoding == RgbEncoding::H264 && self.video.is_none() {
            let path = self.path("rgb", None, "mp4");
            self.video = Some(super::video::ClipVideo::create(
                &path,
                img.width,
                img.height,
                self.fps,
                output.h264_qp,
            )?);
        }
        let video = self.video.as_mut();
        let (pushed, encoded) = rayon::join(
            || video.map_or(Ok(()), |v| v.push(&img.rgb)),
            || {
                stills
                    .par_iter()
                    .map(|&still| still.encode(img, output).map(|bytes| (still, bytes)))
                    .collect::<Result<Vec<_>, Error>>()
            },
        );
        pushed?;
        for (still, bytes) in encoded? {
            let (stream, ext) = still.file(output);
            self.put(stream, at, ext, &bytes)?;
        }
        if let Some(dvs) = self.dvs.as_mut()
            && !f.events.is_empty()
        {
            dvs.write(&dvs_batch(f.frame, f.events))
                .map_err(|e| tables::parquet_error("dvs", self.clip_id, &e))?;
        }
        Ok(())
    }

    /// Writes the per-clip files (DVS events, the H.264 video) and returns the index rows, sorted by (frame,
    /// stream).
    pub fn finish(mut self) -> Result<Vec<IndexRow>, Error> {
        if let Some(video) = self.video.take() {
            let path = self.path("rgb", None, "mp4");
            let (bytes, sha) = video.finish()?;
            self.index("rgb", None, &path, bytes, &sha);
        }
        if let Some(dvs) = self.dvs.take() {
            let bytes = dvs
                .into_inner()
                .map_err(|e| tables::parquet_error("dvs", self.clip_id, &e))?;
            self.put("dvs", None, "parquet", &bytes)?;
        }
        sort_index(&mut self.rows);
        Ok(self.rows)
    }
}

/// Lower-case hex of bytes.
pub(crate) fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write;
    bytes.iter().fold(String::with_capacity(bytes.len() * 2), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    })
}

/// The schema of a clip's DVS events (the table of no events): see [`dvs_batch`].
fn dvs_schema() -> SchemaRef {
    dvs_batch(0, &[]).schema()
}

/// One frame's DVS events: `frame` (the frame whose interval (previous, this] holds the event), `t_ns`, `x`,
/// `y`, `polarity` (true: brighter).
pub fn dvs_batch(frame: u32, events: &[dvs::Event]) -> RecordBatch {
    Table::new()
        .column(
            "frame",
            false,
            Arc::new(UInt32Array::from_iter_values(events.iter().map(|_| frame))),
        )
        .column(
            "t_ns",
            false,
            Arc::new(Int64Array::from_iter_values(events.iter().map(|e| e.t_ns))),
        )
        .column(
            "x",
            false,
            Arc::new(UInt16Array::from_iter_values(events.iter().map(|e| e.x))),
        )
        .column(
            "y",
            false,
            Arc::new(UInt16Array::from_iter_values(events.iter().map(|e| e.y))),
        )
        .column(
            "polarity",
            false,
            Arc::new(BooleanArray::from_iter(events.iter().map(|e| Some(e.positive)))),
        )
        .finish()
}

/// The `sensors` index table of a clip.
pub fn index_batch(clip_id: &str, rows: &[IndexRow]) -> RecordBatch {
    Table::new()
        .column(
            "clip_id",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|_| clip_id))),
        )
        .column(
            "frame",
            true,
            Arc::new(UInt32Array::from_iter(rows.iter().map(|r| r.frame))),
        )
        .column(
            "timestamp_ns",
            true,
            Arc::new(Int64Array::from_iter(rows.iter().map(|r| r.timestamp_ns))),
        )
        .column(
            "stream",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.stream))),
        )
        .column(
            "path",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.path.as_str()))),
        )
        .column(
            "bytes",
            false,
            Arc::new(UInt64Array::from_iter_values(rows.iter().map(|r| r.bytes))),
        )
        .column(
            "sha256",
            false,
            Arc::new(StringArray::from_iter_values(rows.iter().map(|r| r.sha256.as_str()))),
        )
        .finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #[test]
        fn fast_round_equals_the_standard_round(x in 0.0f64..2.0e6, k in 0u32..2_000_000) {
            for v in [x, f64::from(k), f64::from(k) + 0.5, f64::from(k) + 0.499_999_999_999_999_9] {
                proptest::prop_assert_eq!(round_non_negative(v), v.round() as u64, "{}", v);
            }
        }

        #[test]
        fn millimetres_are_the_rounded_depth(d in -1.0f32..80.0, k in 0u32..70_000) {
            // Any depth, and depths exactly half a millimetre off a whole one.
            let half = (k as f32 + 0.5) / 1000.0;
            for v in [d, half, f32::from_bits(half.to_bits() + 1), f32::from_bits(half.to_bits() - 1)] {
                let want = (f64::from(v) * 1000.0).round().clamp(0.0, 65535.0) as u16;
                proptest::prop_assert_eq!(depth_mm(v), want, "{}", v);
            }
        }
    }

    #[test]
    fn fast_round_edge_cases() {
        assert_eq!(round_non_negative(f64::NAN), 0);
        assert_eq!(round_non_negative(-3.7), 0);
        assert_eq!(round_non_negative(0.499_999_999_999_999_94), 0);
        assert_eq!(round_non_negative(2.5), 3);
        assert_eq!(round_non_negative(f64::INFINITY), 1 << 52);
        assert_eq!(depth_mm(f32::INFINITY), 65535);
        assert_eq!(depth_mm(f32::NAN), 0);
        assert_eq!(depth_mm(-2.0), 0);
        assert_eq!(depth_mm(1.2345), 1235);
    }

    #[test]
    fn depth_encodings_round_trip() {
        assert_eq!(depth_mm(12.3456), 12346);
        assert_eq!(depth_mm(100.0), 65535, "saturates");
        let [r, g, b] = carla_depth_rgb(37.5);
        let back =
            1000.0 * (f64::from(r) + 256.0 * f64::from(g) + 65536.0 * f64::from(b)) / f64::from((1u32 << 24) - 1);
        assert!((back - 37.5).abs() < 1e-4, "{back}");
    }

    #[test]
    fn sha256_is_the_standard_one() {
        assert_eq!(
            hex(&Sha256::digest(b"abc")),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
