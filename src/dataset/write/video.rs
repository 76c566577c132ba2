//! H.264 video per clip in MP4 (`output.rgb_encoding: h264`), and reading it back.
//!
//! Writing: each RGB frame is converted to I420 (BT.601 limited range, integer arithmetic, chroma the mean of
//! each 2 × 2 block), encoded by OpenH264 (Cisco's encoder, built from source; one thread, rate control off,
//! a constant quantiser `output.h264_qp`, no skipped frames, an IDR frame every second) and muxed into
//! `sensors/rgb/<clip_id>.mp4` as one video track whose timescale is the clip's frame rate: sample `i` (from
//! 0) is frame `i`, at `i / fps` seconds. The file is written under a temporary name and renamed when the clip
//! is complete, so a resumed run never keeps a half-written video. Every byte is a function of the frames and
//! the settings (no wall-clock time in the boxes; OpenH264's C code, no assembly: see `.cargo/config.toml`).
//!
//! Reading ([`read_frames`]): demuxes the MP4 and decodes frames with OpenH264's decoder (for `pedsynth
//! preview` and the tests; FFmpeg, OpenCV and JAAD's own loader read the same files).

use std::collections::{BTreeMap, BTreeSet};
use std::io::{BufWriter, Read, Seek};
use std::path::{Path, PathBuf};

use openh264::OpenH264API;
use openh264::encoder::{
    Complexity, Encoder, EncoderConfig, FrameRate, FrameType, IntraFramePeriod, QpRange, RateControlMode, UsageType,
    VuiConfig,
};
use openh264::formats::{YUVSlices, YUVSource};
use sha2::{Digest, Sha256};

use crate::error::{Error, code};
use crate::util::files::temporary_path;

/// NAL unit types (ITU-T H.264 table 7-1) that the container carries out of band.
const NAL_SPS: u8 = 7;
const NAL_PPS: u8 = 8;

/// Converts sRGB bytes (`width × height × 3`, even sizes) to I420 in `out` (Y plane, then U, then V):
/// BT.601 limited range with the usual 8-bit integer coefficients, chroma from the mean of each 2 × 2 block.
pub fn rgb_to_i420(rgb: &[u8], width: usize, height: usize, out: &mut Vec<u8>) {
    let (cw, ch) = (width / 2, height / 2);
    out.resize(width * height + 2 * cw * ch, 0);
    let (y_plane, uv) = out.split_at_mut(width * height);
    let (u_plane, v_plane) = uv.split_at_mut(cw * ch);
    let luma = |r: i32, g: i32, b: i32| (((66 * r + 129 * g + 25 * b + 128) >> 8) + 16) as u8;
    for (row, y_row) in y_plane.chunks_exact_mut(width).enumerate() {
        let src = &rgb[row * width * 3..(row + 1) * width * 3];
        for (y, px) in y_row.iter_mut().zip(src.chunks_exact(3)) {
            *y = luma(i32::from(px[0]), i32::from(px[1]), i32::from(px[2]));
        }
    }
    for j in 0..ch {
        let top = &rgb[2 * j * width * 3..(2 * j + 1) * width * 3];
        let bottom = &rgb[(2 * j + 1) * width * 3..(2 * j + 2) * width * 3];
        for i in 0..cw {
            let sum = |c: usize| {
                i32::from(top[6 * i + c])
                    + i32::from(top[6 * i + 3 + c])
                    + i32::from(bottom[6 * i + c])
                    + i32::from(bottom[6 * i + 3 + c])
            };
            // The 2 × 2 mean, rounded.
            let (r, g, b) = ((sum(0) + 2) >> 2, (sum(1) + 2) >> 2, (sum(2) + 2) >> 2);
            u_plane[j * cw + i] = (((-38 * r - 74 * g + 112 * b + 128) >> 8) + 128) as u8;
            v_plane[j * cw + i] = (((112 * r - 94 * g - 18 * b + 128) >> 8) + 128) as u8;
        }
    }
}

/// The NAL units of an Annex B byte stream (start codes removed).
fn annex_b_units(stream: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = stream;
    std::iter::from_fn(move || {
        // Skip the start code (two or more zeros, then a one).
        let zeros = rest.iter().take_while(|b| **b == 0).count();
        if zeros < 2 || rest.get(zeros) != Some(&1) {
            return None;
        }
        rest = &rest[zeros + 1..];
        let end = rest
            .windows(3)
            .position(|w| w[0] == 0 && w[1] == 0 && (w[2] == 1 || w[2] == 0))
            .unwrap_or(rest.len());
        let (unit, tail) = rest.split_at(end);
        rest = tail;
        Some(unit)
    })
}

fn encode_error(e: impl std::fmt::Display) -> Error {
    Error::new(code::INTERNAL_SERIALIZE, format!("cannot encode an H.264 frame: {e}"))
}

fn mux_error(path: &Path, e: mp4::Error) -> Error {
    match e {
        mp4::Error::IoError(io) => Error::write(path, io),
        other => Error::new(
            code::INTERNAL_SERIALIZE,
            format!("cannot write the MP4 file {}: {other}", path.display()),
        ),
    }
}

/// One clip's H.264 video, written frame by frame.
pub struct ClipVideo {
    path: PathBuf,
    tmp: PathBuf,
    encoder: Encoder,
    mux: Option<mp4::Mp4Writer<BufWriter<std::fs::File>>>,
    track_added: bool,
    width: usize,
    height: usize,
    fps: u32,
    frames: u32,
    yuv: Vec<u8>,
    sample: Vec<u8>,
    sps: Vec<u8>,
    pps: Vec<u8>,
}

impl std::fmt::Debug for ClipVideo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClipVideo")
            .field("path", &self.path)
            .field("frames", &self.frames)
            .finish()
    }
}

impl ClipVideo {
    /// Starts the video at `path` (its directory is created): `width × height` (even), `fps` frames per
    /// second, quantiser `qp` (0–51).
    pub fn create(path: &Path, width: usize, height: usize, fps: u32, qp: u8) -> Result<ClipVideo, Error> {
        let config = EncoderConfig::new()
            .usage_type(UsageType::CameraVideoRealTime)
            // OpenH264's "rate control off" encodes at its own base QP (26) whatever the range; its buffer-based
            // mode with a range of one value gives every frame and macroblock the quantiser asked for (and,
            // unlike the quality mode, does not warn on stderr that skipping frames is off).
            .rate_control_mode(RateControlMode::Bufferbased)
            .qp(QpRange::new(qp.min(51), qp.min(51)))
            .skip_frames(false)
            // Every macroblock coded at the one quantiser: no background skipping, no adaptive quantisation.
            .background_detection(false)
            .adaptive_quantization(false)
            .num_threads(1)
            .complexity(Complexity::Medium)
            .max_frame_rate(FrameRate::from_hz(fps.max(1) as f32))
            .intra_frame_period(IntraFramePeriod::from_num_frames(fps.max(1)))
            .vui(VuiConfig::bt601());
        let encoder = Encoder::with_api_config(OpenH264API::from_source(), config).map_err(encode_error)?;
        let tmp = temporary_path(path);
        if let Some(dir) = tmp.parent() {
            std::fs::create_dir_all(dir).map_err(|e| Error::write(path, e))?;
        }
        let file = std::fs::File::create(&tmp).map_err(|e| Error::write(path, e))?;
        let brands = ["isom", "iso2", "avc1", "mp41"].map(|b| b.parse().expect("a four-character code"));
        let config = mp4::Mp4Config {
            major_brand: brands[0],
            minor_version: 512,
            compatible_brands: brands.to_vec(),
            timescale: 1000,
        };
        let mut video = ClipVideo {
            path: path.to_path_buf(),
            tmp,
            encoder,
            mux: None,
            track_added: false,
            width,
            height,
            fps: fps.max(1),
            frames: 0,
            yuv: Vec::new(),
            sample: Vec::new(),
            sps: Vec::new(),
            pps: Vec::new(),
        };
        // Created after `video`, so that a failure here removes the temporary file (Drop).
        video.mux = Some(
            mp4::Mp4Writer::write_start(BufWriter::with_capacity(1 << 20, file), &config)
                .map_err(|e| mux_error(path, e))?,
        );
        Ok(video)
    }

    /// Encodes the next frame (`width × height × 3` sRGB bytes).
    pub fn push(&mut self, rgb: &[u8]) -> Result<(), Error> {
        let (w, h) = (self.width, self.height);
        rgb_to_i420(rgb, w, h, &mut self.yuv);
        let (y, uv) = self.yuv.split_at(w * h);
        let (u, v) = uv.split_at(w * h / 4);
        let source = YUVSlices::new((y, u, v), (w, h), (w, w / 2, w / 2));
        let stream = self.encoder.encode(&source).map_err(encode_error)?;
        let sync = match stream.frame_type() {
            FrameType::IDR => true,
            FrameType::I | FrameType::P => false,
            other => return Err(encode_error(format!("frame {} came out as {other:?}", self.frames))),
        };
        // Annex B → length-prefixed NAL units; SPS and PPS go into the track's avcC box.
        self.sample.clear();
        for l in 0..stream.num_layers() {
            let Some(layer) = stream.layer(l) else { continue };
            for n in 0..layer.nal_count() {
                let Some(nal) = layer.nal_unit(n) else { continue };
                for unit in annex_b_units(nal) {
                    match unit.first().map(|b| b & 0x1f) {
                        Some(NAL_SPS) => {
                            if self.sps.is_empty() {
                                self.sps = unit.to_vec();
                            } else if self.sps != unit {
                                return Err(encode_error("the encoder changed its sequence parameter set"));
                            }
                        }
                        Some(NAL_PPS) => {
                            if self.pps.is_empty() {
                                self.pps = unit.to_vec();
                            } else if self.pps != unit {
                                return Err(encode_error("the encoder changed its picture parameter set"));
                            }
                        }
                        Some(_) => {
                            self.sample.extend_from_slice(&(unit.len() as u32).to_be_bytes());
                            self.sample.extend_from_slice(unit);
                        }
                        None => {}
                    }
                }
            }
        }
        let mux = self.mux.as_mut().ok_or_else(|| encode_error("the video is finished"))?;
        if !self.track_added {
            if self.sps.len() < 4 || self.pps.is_empty() {
                return Err(encode_error("the first frame has no parameter sets"));
            }
            let track = mp4::TrackConfig {
                track_type: mp4::TrackType::Video,
                timescale: self.fps,
                language: "und".to_owned(),
                media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                    width: w as u16,
                    height: h as u16,
                    seq_param_set: self.sps.clone(),
                    pic_param_set: self.pps.clone(),
                }),
            };
            mux.add_track(&track).map_err(|e| mux_error(&self.path, e))?;
            self.track_added = true;
        }
        let sample = mp4::Mp4Sample {
            start_time: u64::from(self.frames),
            duration: 1,
            rendering_offset: 0,
            is_sync: sync,
            bytes: mp4::Bytes::copy_from_slice(&self.sample),
        };
        mux.write_sample(1, &sample).map_err(|e| mux_error(&self.path, e))?;
        self.frames += 1;
        Ok(())
    }

    /// Finishes the file and moves it to its path; returns its size and SHA-256.
    pub fn finish(mut self) -> Result<(u64, [u8; 32]), Error> {
        let mut mux = self.mux.take().ok_or_else(|| encode_error("the video is finished"))?;
        mux.write_end().map_err(|e| mux_error(&self.path, e))?;
        let file = mux
            .into_writer()
            .into_inner()
            .map_err(|e| Error::write(&self.path, e.into_error()))?;
        drop(file);
        // Hashed from the file (the muxer seeks back to patch sizes, so it cannot be hashed as written).
        let mut hasher = Sha256::new();
        let mut reader = std::fs::File::open(&self.tmp).map_err(|e| Error::read(&self.tmp, e))?;
        let (mut bytes, mut buf) = (0u64, vec![0u8; 1 << 16]);
        loop {
            let n = reader.read(&mut buf).map_err(|e| Error::read(&self.tmp, e))?;
            if n == 0 {
                break;
            }
            hasher.update(&buf[..n]);
            bytes += n as u64;
        }
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::write(&self.path, e))?;
        Ok((bytes, hasher.finalize().into()))
    }
}

impl Drop for ClipVideo {
    fn drop(&mut self) {
        // Unfinished (an error, or a panic elsewhere): the temporary file goes.
        if self.mux.take().is_some() {
            std::fs::remove_file(&self.tmp).ok();
        }
    }
}

/// Frames of an MP4 video decoded to sRGB.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DecodedFrames {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Frames asked for (that the video has), `width × height × 3` bytes each.
    pub frames: BTreeMap<u32, Vec<u8>>,
    /// Samples in the video's track.
    pub sample_count: u32,
}

/// Decodes the frames `wanted` (sample `i` = frame `i`) of the first video track of an MP4 file written by
/// [`ClipVideo`] (or any H.264 MP4 without B-frames).
pub fn read_frames(path: &Path, wanted: &BTreeSet<u32>) -> Result<DecodedFrames, Error> {
    let invalid = |e: &dyn std::fmt::Display| Error::new(code::DATASET_INVALID, format!("{}: {e}", path.display()));
    let file = std::fs::File::open(path).map_err(|e| Error::read(path, e))?;
    let size = file.metadata().map_err(|e| Error::read(path, e))?.len();
    let mut reader = mp4::Mp4Reader::read_header(std::io::BufReader::new(file), size).map_err(|e| invalid(&e))?;
    read_track(&mut reader, wanted).map_err(|e| invalid(&e))
}

fn read_track<R: Read + Seek>(reader: &mut mp4::Mp4Reader<R>, wanted: &BTreeSet<u32>) -> Result<DecodedFrames, String> {
    let (track_id, track) = reader
        .tracks()
        .iter()
        .find(|(_, t)| t.track_type().ok() == Some(mp4::TrackType::Video))
        .ok_or("no video track")?;
    let track_id = *track_id;
    let (sps, pps) = (
        track.sequence_parameter_set().map_err(|e| e.to_string())?.to_vec(),
        track.picture_parameter_set().map_err(|e| e.to_string())?.to_vec(),
    );
    let sample_count = track.sample_count();
    let mut out = DecodedFrames {
        width: usize::from(track.width()),
        height: usize::from(track.height()),
        frames: BTreeMap::new(),
        sample_count,
    };
    let Some(&last) = wanted.iter().next_back() else {
        return Ok(out);
    };
    let mut decoder = openh264::decoder::Decoder::new().map_err(|e| e.to_string())?;
    let mut packet = Vec::new();
    for frame in 0..sample_count.min(last.saturating_add(1)) {
        let sample = reader
            .read_sample(track_id, frame + 1)
            .map_err(|e| e.to_string())?
            .ok_or_else(|| format!("sample {} is missing", frame + 1))?;
        packet.clear();
        if frame == 0 {
            for ps in [&sps, &pps] {
                packet.extend_from_slice(&[0, 0, 0, 1]);
                packet.extend_from_slice(ps);
            }
        }
        let mut rest: &[u8] = &sample.bytes;
        while rest.len() >= 4 {
            let n = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
            let unit = rest.get(4..4 + n).ok_or("a NAL unit runs past its sample")?;
            packet.extend_from_slice(&[0, 0, 0, 1]);
            packet.extend_from_slice(unit);
            rest = &rest[4 + n..];
        }
        let decoded = decoder
            .decode(&packet)
            .map_err(|e| format!("frame {frame}: {e}"))?
            .ok_or_else(|| format!("frame {frame} decoded to nothing"))?;
        if wanted.contains(&frame) {
            let (w, h) = decoded.dimensions();
            let mut rgb = vec![0; w * h * 3];
            decoded.write_rgb8(&mut rgb);
            out.width = w;
            out.height = h;
            out.frames.insert(frame, rgb);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn i420_of_grey_white_and_primaries() {
        // 2 × 2 blocks: black, white, red, grey.
        let mut rgb = vec![0u8; 8 * 2 * 3];
        for y in 0..2 {
            for (x, c) in [[0, 0, 0], [255, 255, 255], [255, 0, 0], [128, 128, 128]]
                .iter()
                .enumerate()
            {
                for dx in 0..2 {
                    let o = (y * 8 + 2 * x + dx) * 3;
                    rgb[o..o + 3].copy_from_slice(c);
                }
            }
        }
        let mut yuv = Vec::new();
        rgb_to_i420(&rgb, 8, 2, &mut yuv);
        let (y, uv) = yuv.split_at(16);
        let (u, v) = uv.split_at(4);
        // BT.601 limited range: black 16, white 235, neutral chroma 128; red has V near 240.
        assert_eq!(&y[0..4], &[16, 16, 235, 235]);
        assert_eq!((u[0], v[0]), (128, 128));
        assert_eq!((u[1], v[1]), (128, 128));
        assert_eq!((y[4], u[2], v[2]), (82, 90, 240));
        assert_eq!((y[6], u[3], v[3]), (126, 128, 128));
    }

    #[test]
    fn annex_b_units_split_on_three_and_four_byte_start_codes() {
        let s = [0, 0, 0, 1, 0x67, 1, 2, 0, 0, 1, 0x68, 3, 0, 0, 0, 1, 0x65, 4, 5];
        let units: Vec<&[u8]> = annex_b_units(&s).collect();
        assert_eq!(units, vec![&[0x67, 1, 2][..], &[0x68, 3][..], &[0x65, 4, 5][..]]);
    }

    /// A moving gradient with a moving square: encoded, muxed, demuxed and decoded, every frame close to
    /// its source (PSNR), the file deterministic, and a dropped writer leaves no file behind.
    #[test]
    fn a_video_round_trips_through_mp4_and_is_byte_identical_twice() {
        let (w, h, n) = (96usize, 64usize, 40u32);
        let frame = |k: u32| -> Vec<u8> {
            let mut rgb = vec![0u8; w * h * 3];
            for y in 0..h {
                for x in 0..w {
                    let inside = (x as u32).wrapping_sub(2 * k) < 16 && (20..40).contains(&y);
                    let o = (y * w + x) * 3;
                    rgb[o] = if inside { 230 } else { (x * 2 + k as usize) as u8 };
                    rgb[o + 1] = if inside { 40 } else { (y * 3) as u8 };
                    rgb[o + 2] = if inside { 30 } else { 100 };
                }
            }
            rgb
        };
        let dir = std::env::temp_dir().join(format!("pedsynth-video-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let write = |name: &str, qp: u8| {
            let path = dir.join(name);
            let mut v = ClipVideo::create(&path, w, h, 30, qp).unwrap();
            for k in 0..n {
                v.push(&frame(k)).unwrap();
            }
            let (bytes, sha) = v.finish().unwrap();
            assert_eq!(bytes, std::fs::metadata(&path).unwrap().len());
            (std::fs::read(&path).unwrap(), sha)
        };
        let (a, sha_a) = write("a.mp4", 18);
        let (b, sha_b) = write("b.mp4", 18);
        // The quantiser is the one asked for: a coarser one gives a smaller file.
        let (coarse, _) = write("coarse.mp4", 40);
        assert!(
            coarse.len() * 2 < a.len(),
            "QP 40: {} bytes, QP 18: {}",
            coarse.len(),
            a.len()
        );
        assert!(a == b && sha_a == sha_b, "two encodings of the same frames differ");
        assert_eq!(sha_a, <[u8; 32]>::from(Sha256::digest(&a)));
        let wanted: BTreeSet<u32> = (0..n).collect();
        let decoded = read_frames(&dir.join("a.mp4"), &wanted).unwrap();
        assert_eq!((decoded.width, decoded.height, decoded.sample_count), (w, h, n));
        assert_eq!(decoded.frames.len(), n as usize);
        for (k, rgb) in &decoded.frames {
            let src = frame(*k);
            let mse = src
                .iter()
                .zip(rgb)
                .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
                .sum::<f64>();
            let psnr = 10.0 * (255.0f64 * 255.0 * src.len() as f64 / mse.max(1e-9)).log10();
            assert!(psnr > 35.0, "frame {k}: PSNR {psnr:.1} dB");
        }
        // An unfinished video leaves nothing.
        let path = dir.join("c.mp4");
        let mut v = ClipVideo::create(&path, w, h, 30, 18).unwrap();
        v.push(&frame(0)).unwrap();
        drop(v);
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        std::fs::remove_dir_all(&dir).ok();
        assert!(!left.iter().any(|n| n.contains("c.mp4")), "{left:?}");
    }
}
