//! `pedsynth preview`: a contact sheet (PNG) or an animated GIF of one clip's camera stream read from a
//! written dataset, with the annotations drawn over the frames: boxes coloured by the crossing label (red:
//! crossing, green: not crossing), pedestrian ids and behaviour states, and the COCO-17 skeleton. Frames are
//! shown at half resolution. Depth is shown near-bright/far-dark on a log scale, instance ids in hashed
//! colours, semantic tags in CARLA's palette, and DVS events of a frame as red (brighter) and blue (darker)
//! dots (over the RGB frames, read from PNG files or decoded from the clip's H.264 MP4). The LiDAR is shown from above with the 3D boxes ([`super::lidar_view`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use font8x8::UnicodeFonts;

use super::tables;
use crate::dataset::write::Layout;
use crate::dataset::write::sensors::png_bytes;
use crate::dataset::write::video::{DecodedFrames, read_frames};
use crate::error::{Error, code};
use crate::sensors::scene::tag;
use crate::util::files::write_atomically;
use crate::util::mix::splitmix64;

/// The streams a preview can show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// RGB images.
    Rgb,
    /// Semantic segmentation.
    Semantic,
    /// Instance segmentation.
    Instance,
    /// Depth.
    Depth,
    /// DVS events.
    Dvs,
    /// LiDAR points from above (see [`super::lidar_view`]).
    Lidar,
}

impl Stream {
    fn dir(self) -> &'static str {
        match self {
            Stream::Rgb | Stream::Dvs => "rgb",
            Stream::Semantic => "semantic",
            Stream::Instance => "instance",
            Stream::Depth => "depth",
            Stream::Lidar => "lidar",
        }
    }
}

/// Options of `pedsynth preview`.
#[derive(Clone, Debug)]
pub struct PreviewOptions {
    /// Clip id.
    pub clip: String,
    /// Stream to show.
    pub stream: Stream,
    /// Output file (`.png`: contact sheet of 9 frames; `.gif`: animation).
    pub out: PathBuf,
}

/// One annotated pedestrian in a frame.
struct Label {
    pedestrian: u32,
    bbox: [f32; 4],
    crossing: bool,
    state: String,
    keypoints: Vec<f32>,
}

/// An RGB canvas.
struct Canvas {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Canvas {
    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let o = (y as usize * self.w + x as usize) * 3;
            self.px[o..o + 3].copy_from_slice(&c);
        }
    }

    fn line(&mut self, a: (f32, f32), b: (f32, f32), c: [u8; 3]) {
        let n = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f32 / n as f32;
            let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            self.put(x.round() as i64, y.round() as i64, c);
            self.put(x.round() as i64 + 1, y.round() as i64, c);
        }
    }

    fn rect(&mut self, b: [f32; 4], c: [u8; 3]) {
        let (x0, y0, x1, y1) = (b[0], b[1], b[2], b[3]);
        self.line((x0, y0), (x1, y0), c);
        self.line((x1, y0), (x1, y1), c);
        self.line((x1, y1), (x0, y1), c);
        self.line((x0, y1), (x0, y0), c);
    }

    fn text(&mut self, x: i64, y: i64, s: &str, c: [u8; 3]) {
        for (i, ch) in s.chars().enumerate() {
            let Some(glyph) = font8x8::BASIC_FONTS.get(ch) else {
                continue;
            };
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    let (px, py) = (x + i as i64 * 8 + col, y + row as i64);
                    if bits & (1 << col) != 0 {
                        self.put(px, py, c);
                    } else if (0..8).contains(&col) {
                        // A dark halo keeps the text readable on any background.
                        if px >= 0 && py >= 0 && (px as usize) < self.w && (py as usize) < self.h {
                            let o = (py as usize * self.w + px as usize) * 3;
                            for v in &mut self.px[o..o + 3] {
                                *v /= 3;
                            }
                        }
                    }
                }
            }
        }
    }
}

/// COCO-17 skeleton edges.
const SKELETON: [(usize, usize); 16] = [
    (0, 1),
    (0, 2),
    (1, 3),
    (2, 4),
    (5, 6),
    (5, 7),
    (7, 9),
    (6, 8),
    (8, 10),
    (5, 11),
    (6, 12),
    (11, 12),
    (11, 13),
    (13, 15),
    (12, 14),
    (14, 16),
];

/// A labelled thumbnail of one RGB frame of `clip` (the frame with the most annotated pedestrians, the earliest
/// of those), at the preview's half resolution, as PNG bytes; `None` when the clip has no PNG RGB frames.
pub fn thumbnail_png(dir: &Path, clip: &str) -> Result<Option<Vec<u8>>, Error> {
    let layout = Layout::new(dir);
    let labels = labels(&layout, clip)?;
    let frames = frame_count(&layout, clip)?;
    let best = (0..frames)
        .max_by_key(|f| (labels.get(f).map_or(0, Vec::len), std::cmp::Reverse(*f)))
        .unwrap_or(0);
    if !layout.sensor_frame("rgb", clip, best, "png").is_file() {
        return Ok(None);
    }
    let options = PreviewOptions {
        clip: clip.to_owned(),
        stream: Stream::Rgb,
        out: PathBuf::new(),
    };
    let mut c = frame_canvas(&layout, &options, best, &[], None)?;
    draw_labels(&mut c, labels.get(&best).map_or(&[], Vec::as_slice));
    c.text(6, 6, &format!("{clip} frame {best}"), [255, 255, 255]);
    // At most 400 px wide: the mean of each k × k block.
    let k = c.w.div_ceil(400).max(1);
    let (w, h) = (c.w / k, c.h / k);
    let mut px = vec![0u8; w * h * 3];
    for y in 0..h {
        for x in 0..w {
            for ch in 0..3 {
                let mut sum = 0u32;
                for dy in 0..k {
                    for dx in 0..k {
                        sum += u32::from(c.px[((y * k + dy) * c.w + x * k + dx) * 3 + ch]);
                    }
                }
                px[(y * w + x) * 3 + ch] = (sum / (k * k) as u32) as u8;
            }
        }
    }
    png_bytes(
        w,
        h,
        png::ColorType::Rgb,
        png::BitDepth::Eight,
        &px,
        png::Filter::Adaptive,
        None,
    )
    .map(Some)
}

/// A 16-bit grey PNG (the instance stream) as row-major values: width, height, values.
pub(crate) fn read_u16_png(path: &Path) -> Result<(usize, usize, Vec<u16>), Error> {
    let (w, h, bytes, colour, depth) = decode_png(path)?;
    if colour != png::ColorType::Grayscale || depth != png::BitDepth::Sixteen {
        return Err(Error::new(
            code::DATASET_INVALID,
            format!("{}: {colour:?} {depth:?}, not 16-bit grey", path.display()),
        ));
    }
    Ok((
        w,
        h,
        bytes
            .chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect(),
    ))
}

fn decode_png(path: &Path) -> Result<(usize, usize, Vec<u8>, png::ColorType, png::BitDepth), Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::read(path, e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let invalid = |e: &dyn std::fmt::Display| Error::new(code::DATASET_INVALID, format!("{}: {e}", path.display()));
    let mut reader = decoder.read_info().map_err(|e| invalid(&e))?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or_else(|| invalid(&"image too large"))?];
    let info = reader.next_frame(&mut buf).map_err(|e| invalid(&e))?;
    buf.truncate(info.buffer_size());
    Ok((
        info.width as usize,
        info.height as usize,
        buf,
        info.color_type,
        info.bit_depth,
    ))
}

/// A stream's frame as a half-resolution RGB canvas.
fn frame_canvas(
    layout: &Layout,
    options: &PreviewOptions,
    frame: u32,
    events: &[(u32, u16, u16, bool)],
    video: Option<&DecodedFrames>,
) -> Result<Canvas, Error> {
    let path = layout.sensor_frame(options.stream.dir(), &options.clip, frame, "png");
    let from_video = video.and_then(|v| v.frames.get(&frame).map(|rgb| (v, rgb)));
    let (w, h, data, colour, depth) = if let Some((v, rgb)) = from_video {
        (
            v.width,
            v.height,
            rgb.clone(),
            png::ColorType::Rgb,
            png::BitDepth::Eight,
        )
    } else if video.is_some() {
        return Err(Error::new(
            code::DATASET_INVALID,
            format!("the clip's video has no frame {frame}"),
        ));
    } else if options.stream == Stream::Dvs && !path.is_file() {
        return Err(Error::new(
            code::DATASET_INVALID,
            "the DVS preview draws events over the RGB frames, which this dataset does not have as PNG or MP4",
        ));
    } else {
        decode_png(&path).map_err(|e| {
            if path.is_file() {
                e
            } else {
                Error::new(
                    code::DATASET_INVALID,
                    format!(
                        "{} is missing: was the `{}` stream rendered as PNG? (see manifest.json's `sensors`)",
                        path.display(),
                        options.stream.dir()
                    ),
                )
            }
        })?
    };
    let sixteen = depth == png::BitDepth::Sixteen;
    let channels = data.len() / (w * h * if sixteen { 2 } else { 1 });
    let rgb_at = |i: usize| -> [u8; 3] {
        if sixteen {
            let v = u16::from_be_bytes([data[2 * i * channels], data[2 * i * channels + 1]]);
            return match options.stream {
                Stream::Instance => {
                    if v == 0 {
                        [0, 0, 0]
                    } else {
                        let hsh = splitmix64(u64::from(v));
                        [(hsh >> 8) as u8 | 64, (hsh >> 24) as u8 | 64, (hsh >> 40) as u8 | 64]
                    }
                }
                _ => {
                    // Millimetres: bright near, dark far, log scale over 0.5–65 m.
                    let m = (f32::from(v) / 1000.0).max(0.5);
                    let g = (255.0 * (1.0 - (m / 0.5).ln() / (65.5f32 / 0.5).ln())).clamp(0.0, 255.0) as u8;
                    [g, g, g]
                }
            };
        }
        match (colour, channels) {
            (_, 3) => [data[3 * i], data[3 * i + 1], data[3 * i + 2]],
            (_, 4) => [data[4 * i], data[4 * i + 1], data[4 * i + 2]],
            _ => {
                let v = data[i * channels];
                if options.stream == Stream::Semantic {
                    tag::PALETTE.get(usize::from(v)).copied().unwrap_or([255, 255, 255])
                } else {
                    [v, v, v]
                }
            }
        }
    };
    let (cw, ch) = (w / 2, h / 2);
    let mut canvas = Canvas {
        w: cw,
        h: ch,
        px: vec![0; cw * ch * 3],
    };
    for y in 0..ch {
        for x in 0..cw {
            let mut c = rgb_at(2 * y * w + 2 * x);
            if options.stream == Stream::Dvs {
                c = c.map(|v| v / 4);
            }
            canvas.put(x as i64, y as i64, c);
        }
    }
    for &(_, x, y, positive) in events.iter().filter(|e| e.0 == frame) {
        let c = if positive { [255, 40, 40] } else { [60, 110, 255] };
        canvas.put(i64::from(x / 2), i64::from(y / 2), c);
    }
    Ok(canvas)
}

fn draw_labels(canvas: &mut Canvas, labels: &[Label]) {
    for l in labels {
        let colour = if l.crossing { [235, 50, 40] } else { [60, 220, 90] };
        let b = l.bbox.map(|v| v * 0.5);
        for (a, c) in SKELETON {
            let (ka, kc) = (&l.keypoints[3 * a..3 * a + 3], &l.keypoints[3 * c..3 * c + 3]);
            if ka[2] > 0.0 && kc[2] > 0.0 {
                canvas.line((ka[0] * 0.5, ka[1] * 0.5), (kc[0] * 0.5, kc[1] * 0.5), [250, 220, 60]);
            }
        }
        canvas.rect(b, colour);
        let text = format!("{} {}", l.pedestrian, l.state);
        canvas.text(b[0] as i64, b[1] as i64 - 10, &text, colour);
    }
}

/// Reads a clip's annotations, by frame.
fn labels(layout: &Layout, clip: &str) -> Result<BTreeMap<u32, Vec<Label>>, Error> {
    let path = layout.table("annotations", clip);
    if !path.is_file() {
        return Err(Error::new(
            code::DATASET_INVALID,
            format!(
                "no clip `{clip}` in {} (or it is not finished)",
                layout.root().display()
            ),
        )
        .help("`pedsynth stats DIR` lists the dataset; manifest.json lists every clip and its status"));
    }
    let cols = [
        "frame",
        "pedestrian",
        "bbox_x_min",
        "bbox_y_min",
        "bbox_x_max",
        "bbox_y_max",
        "crossing",
        "state",
        "keypoints",
    ];
    let mut out: BTreeMap<u32, Vec<Label>> = BTreeMap::new();
    for b in tables::read(&path, &cols)? {
        let (frame, ped) = (b.u32s("frame")?, b.u32s("pedestrian")?);
        let bx = [
            b.f32s("bbox_x_min")?,
            b.f32s("bbox_y_min")?,
            b.f32s("bbox_x_max")?,
            b.f32s("bbox_y_max")?,
        ];
        let crossing = b.bools("crossing")?;
        let states = b.strings("state")?;
        let (kp, width) = b.f32_lists("keypoints")?;
        for i in 0..b.rows() {
            out.entry(frame.value(i)).or_default().push(Label {
                pedestrian: ped.value(i),
                bbox: bx.map(|c| c.value(i)),
                crossing: crossing.value(i),
                state: states[i].to_owned(),
                keypoints: kp[i * width..(i + 1) * width].to_vec(),
            });
        }
    }
    Ok(out)
}

/// The frame count of a clip (from its `frames` table).
fn frame_count(layout: &Layout, clip: &str) -> Result<u32, Error> {
    let mut n = 0u32;
    for b in tables::read(&layout.table("frames", clip), &["frame"])? {
        let f = b.u32s("frame")?;
        n = n.max((0..b.rows()).map(|i| f.value(i) + 1).max().unwrap_or(0));
    }
    Ok(n)
}

fn dvs_events(layout: &Layout, clip: &str) -> Result<Vec<(u32, u16, u16, bool)>, Error> {
    let path = layout.sensor_clip("dvs", clip, "parquet");
    let mut out = Vec::new();
    for b in tables::read(&path, &["frame", "x", "y", "polarity"])? {
        let (f, x, y, p) = (b.u32s("frame")?, b.u16s("x")?, b.u16s("y")?, b.bools("polarity")?);
        out.extend((0..b.rows()).map(|i| (f.value(i), x.value(i), y.value(i), p.value(i))));
    }
    Ok(out)
}

/// Writes the preview of one clip; returns what was written.
pub fn preview(dir: &Path, options: &PreviewOptions) -> Result<String, Error> {
    let layout = Layout::new(dir);
    let labels = labels(&layout, &options.clip)?;
    let frames = frame_count(&layout, &options.clip)?;
    let events = if options.stream == Stream::Dvs {
        dvs_events(&layout, &options.clip)?
    } else {
        Vec::new()
    };
    let gif = options.out.extension().is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    // Every third frame (10 images per second of a 30 FPS clip), at most 120.
    let gif_picks: Vec<u32> = (0..frames).step_by(3).take(120).collect();
    // Nine frames spread over the clip, preferring frames with annotated pedestrians.
    let mut sheet_picks: Vec<u32> = (0..9)
        .map(|k| {
            let lo = frames * k / 9;
            let hi = (frames * (k + 1) / 9).max(lo + 1);
            (lo..hi)
                .max_by_key(|f| (labels.get(f).map_or(0, Vec::len), std::cmp::Reverse(*f)))
                .unwrap_or(lo)
        })
        .collect();
    sheet_picks.dedup();
    let lidar = if options.stream == Stream::Lidar {
        let wanted = if gif { &gif_picks } else { &sheet_picks };
        Some(super::lidar_view::LidarFrames::read(
            &layout,
            &options.clip,
            &wanted.iter().copied().collect(),
        )?)
    } else {
        None
    };
    // RGB as H.264 video: the picked frames decoded once.
    let mp4 = layout.sensor_clip("rgb", &options.clip, "mp4");
    let video = if matches!(options.stream, Stream::Rgb | Stream::Dvs) && mp4.is_file() {
        let wanted = if gif { &gif_picks } else { &sheet_picks };
        Some(read_frames(&mp4, &wanted.iter().copied().collect())?)
    } else {
        None
    };
    let empty = Vec::new();
    let render = |f: u32| -> Result<Canvas, Error> {
        let mut c = if let Some(l) = &lidar {
            let n = super::lidar_view::VIEW_PX;
            Canvas {
                w: n,
                h: n,
                px: l.view(f),
            }
        } else {
            let mut c = frame_canvas(&layout, options, f, &events, video.as_ref())?;
            draw_labels(&mut c, labels.get(&f).unwrap_or(&empty));
            c
        };
        c.text(6, 6, &format!("{} frame {f}", options.clip), [255, 255, 255]);
        Ok(c)
    };
    let bytes = if gif {
        let picks = gif_picks;
        let mut out = Vec::new();
        {
            let first = render(picks.first().copied().unwrap_or(0))?;
            let fail =
                |e: gif::EncodingError| Error::new(code::INTERNAL_SERIALIZE, format!("cannot encode the GIF: {e}"));
            let mut enc = gif::Encoder::new(&mut out, first.w as u16, first.h as u16, &[]).map_err(fail)?;
            enc.set_repeat(gif::Repeat::Infinite).map_err(fail)?;
            for f in picks {
                let c = render(f)?;
                let mut frame = gif::Frame::from_rgb_speed(c.w as u16, c.h as u16, &c.px, 10);
                frame.delay = 10;
                enc.write_frame(&frame).map_err(fail)?;
            }
        }
        out
    } else {
        let picks = sheet_picks;
        let tiles: Vec<Canvas> = picks.iter().map(|f| render(*f)).collect::<Result<_, _>>()?;
        let (tw, th) = (tiles[0].w, tiles[0].h);
        let cols = 3;
        let rows = tiles.len().div_ceil(cols);
        let (sw, sh) = (tw * cols, th * rows);
        let mut sheet = vec![0u8; sw * sh * 3];
        for (k, t) in tiles.iter().enumerate() {
            let (ox, oy) = ((k % cols) * tw, (k / cols) * th);
            for y in 0..th {
                let src = &t.px[y * tw * 3..(y + 1) * tw * 3];
                let o = ((oy + y) * sw + ox) * 3;
                sheet[o..o + tw * 3].copy_from_slice(src);
            }
        }
        png_bytes(
            sw,
            sh,
            png::ColorType::Rgb,
            png::BitDepth::Eight,
            &sheet,
            png::Filter::Adaptive,
            None,
        )?
    };
    write_atomically(&options.out, &bytes).map_err(|e| Error::write(&options.out, e))?;
    Ok(format!(
        "{}: {} of clip {} ({} frames)\n",
        options.out.display(),
        if gif { "animation" } else { "contact sheet" },
        options.clip,
        frames
    ))
}
