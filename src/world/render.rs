//! Top-down PNG map of a road network (north up): lanes filled by type, crosswalks, obstacles, lane-graph
//! travel ticks and a scale bar. A small scanline polygon rasteriser, a 3×5 digit font, and the `png` crate
//! with `Compression::Fast`.

use glam::DVec2;

use crate::world::{LaneType, RoadNetwork, TravelDirection};

const BACKGROUND: [u8; 3] = [214, 226, 200];

fn lane_colour(t: LaneType) -> [u8; 3] {
    match t {
        LaneType::Driving => [70, 70, 76],
        LaneType::Sidewalk => [196, 186, 168],
        LaneType::Shoulder => [120, 120, 124],
        LaneType::Parking => [92, 108, 140],
        LaneType::Median => [110, 150, 90],
        LaneType::Border => [150, 140, 120],
        LaneType::Biking => [170, 80, 70],
        LaneType::Other => [170, 190, 160],
    }
}

/// Drawing order: later types paint over earlier ones.
const ORDER: [LaneType; 8] = [
    LaneType::Other,
    LaneType::Border,
    LaneType::Median,
    LaneType::Shoulder,
    LaneType::Parking,
    LaneType::Biking,
    LaneType::Driving,
    LaneType::Sidewalk,
];

struct Canvas {
    w: usize,
    h: usize,
    /// 3 (RGB) or 1 (grey: a colour's first channel).
    channels: usize,
    px: Vec<u8>,
    xs: Vec<f64>,
}

impl Canvas {
    fn blend(&mut self, x: usize, y: usize, c: [u8; 3], alpha: f64) {
        let n = self.channels;
        let i = (y * self.w + x) * n;
        for (dst, &src) in self.px[i..i + n].iter_mut().zip(c.iter()) {
            let old = *dst as f64;
            *dst = (old + (src as f64 - old) * alpha).round() as u8;
        }
    }

    /// Even-odd scanline fill of a polygon in pixel coordinates.
    fn fill(&mut self, poly: &[DVec2], c: [u8; 3], alpha: f64) {
        if poly.len() < 3 {
            return;
        }
        let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in poly {
            y0 = y0.min(p.y);
            y1 = y1.max(p.y);
        }
        let ya = (y0.floor().max(0.0)) as usize;
        let yb = (y1.ceil().min(self.h as f64 - 1.0)).max(-1.0);
        if yb < 0.0 {
            return;
        }
        for y in ya..=yb as usize {
            let sy = y as f64 + 0.5;
            self.xs.clear();
            let mut j = poly.len() - 1;
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[j]);
                if (a.y > sy) != (b.y > sy) {
                    self.xs.push(a.x + (sy - a.y) * (b.x - a.x) / (b.y - a.y));
                }
                j = i;
            }
            self.xs.sort_by(f64::total_cmp);
            let mut k = 0;
            while k + 1 < self.xs.len() {
                let xa = (self.xs[k] - 0.5).ceil().max(0.0) as usize;
                let xb = (self.xs[k + 1] - 0.5).floor().min(self.w as f64 - 1.0);
                if xb >= 0.0 {
                    for x in xa..=xb as usize {
                        self.blend(x, y, c, alpha);
                    }
                }
                k += 2;
            }
        }
    }

    fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: [u8; 3]) {
        for y in y0.max(0)..y1.min(self.h as i64) {
            for x in x0.max(0)..x1.min(self.w as i64) {
                self.blend(x as usize, y as usize, c, 1.0);
            }
        }
    }

    /// A line of `thick` pixels (drawn as a thin quad).
    fn line(&mut self, a: DVec2, b: DVec2, thick: f64, c: [u8; 3]) {
        let d = b - a;
        let n = DVec2::new(-d.y, d.x).normalize_or_zero() * (0.5 * thick);
        self.fill(&[a - n, b - n, b + n, a + n], c, 1.0);
    }

    /// Digits and 'm' in a 3×5 font scaled by `s`.
    fn text(&mut self, x: i64, y: i64, s: i64, text: &str, c: [u8; 3]) {
        let mut cx = x;
        for ch in text.chars() {
            let glyph: [u8; 5] = match ch {
                '0' => [7, 5, 5, 5, 7],
                '1' => [2, 6, 2, 2, 7],
                '2' => [7, 1, 7, 4, 7],
                '3' => [7, 1, 7, 1, 7],
                '4' => [5, 5, 7, 1, 1],
                '5' => [7, 4, 7, 1, 7],
                '6' => [7, 4, 7, 5, 7],
                '7' => [7, 1, 1, 1, 1],
                '8' => [7, 5, 7, 5, 7],
                '9' => [7, 5, 7, 1, 7],
                'm' => [0, 0, 7, 7, 5],
                _ => [0; 5],
            };
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        let px = cx + col * s;
                        let py = y + row as i64 * s;
                        self.rect(px, py, px + s, py + s, c);
                    }
                }
            }
            cx += 4 * s;
        }
    }
}

pub(crate) fn render_png(net: &RoadNetwork, px_per_m: f64, max_side_px: u32) -> Vec<u8> {
    let margin = 10.0;
    let lo = net.bounds.0 - DVec2::splat(margin);
    let hi = net.bounds.1 + DVec2::splat(margin);
    let ext = hi - lo;
    let mut scale = if px_per_m.is_finite() && px_per_m > 0.0 {
        px_per_m
    } else {
        2.0
    };
    let max_side = max_side_px.clamp(16, 16384) as f64;
    scale = scale.min(max_side / ext.x.max(ext.y));
    let w = ((ext.x * scale).ceil() as usize).max(1);
    let h = ((ext.y * scale).ceil() as usize).max(1);
    let mut cv = Canvas {
        w,
        h,
        channels: 3,
        px: Vec::with_capacity(w * h * 3),
        xs: Vec::new(),
    };
    for _ in 0..w * h {
        cv.px.extend_from_slice(&BACKGROUND);
    }
    let to_px = |p: DVec2| DVec2::new((p.x - lo.x) * scale, (hi.y - p.y) * scale);
    for t in ORDER {
        let colour = lane_colour(t);
        for lane in net.lanes.iter().filter(|l| l.lane_type == t) {
            for p in &net.pieces[lane.pieces.start as usize..lane.pieces.end as usize] {
                let q = p.corners.map(to_px);
                cv.fill(&q, colour, 1.0);
            }
        }
    }
    // Zebra crosswalks: white stripes across the walking direction.
    for cw in &net.crosswalks {
        let poly: Vec<DVec2> = cw.polygon.iter().map(|&p| to_px(p)).collect();
        if poly.len() == 4 {
            // Stripes run along the crossing: split along the longer axis.
            let long = (poly[3] - poly[0]).length() > (poly[1] - poly[0]).length();
            let stripes = ((if long {
                (poly[3] - poly[0]).length()
            } else {
                (poly[1] - poly[0]).length()
            }) / (0.5 * scale))
                .max(1.0) as usize;
            for k in (0..stripes).step_by(2) {
                let f0 = k as f64 / stripes as f64;
                let f1 = (k + 1) as f64 / stripes as f64;
                let quad = if long {
                    [
                        poly[0].lerp(poly[3], f0),
                        poly[1].lerp(poly[2], f0),
                        poly[1].lerp(poly[2], f1),
                        poly[0].lerp(poly[3], f1),
                    ]
                } else {
                    [
                        poly[0].lerp(poly[1], f0),
                        poly[0].lerp(poly[1], f1),
                        poly[3].lerp(poly[2], f1),
                        poly[3].lerp(poly[2], f0),
                    ]
                };
                cv.fill(&quad, [245, 245, 245], 0.9);
            }
        } else {
            cv.fill(&poly, [245, 245, 245], 0.7);
        }
    }
    // Travel-direction ticks on driving lanes: a short light stroke every ~20 m pointing along travel.
    for (i, lane) in net.lanes.iter().enumerate() {
        if lane.lane_type != LaneType::Driving || lane.in_junction || lane.travel == TravelDirection::Undirected {
            continue;
        }
        let c = net.lane_centre_line(i as u32);
        let mut acc = 0.0;
        for w in c.windows(2) {
            let d = (w[1] - w[0]).length();
            acc += d;
            if acc >= 20.0 && d > 0.0 {
                acc = 0.0;
                let dir = (w[1] - w[0]) / d;
                let tip = w[1];
                let tail = tip - dir * 2.5;
                let side = DVec2::new(-dir.y, dir.x) * 0.8;
                cv.line(to_px(tail), to_px(tip), (0.25 * scale).max(1.0), [230, 230, 120]);
                cv.line(
                    to_px(tip),
                    to_px(tip - dir * 1.0 + side),
                    (0.25 * scale).max(1.0),
                    [230, 230, 120],
                );
                cv.line(
                    to_px(tip),
                    to_px(tip - dir * 1.0 - side),
                    (0.25 * scale).max(1.0),
                    [230, 230, 120],
                );
            }
        }
    }
    for o in &net.obstacles {
        let q = o.footprint().map(to_px);
        cv.fill(&q, [150, 104, 84], 1.0);
        for k in 0..4 {
            cv.line(q[k], q[(k + 1) % 4], 1.0, [90, 60, 50]);
        }
    }
    // Scale bar, bottom left.
    let target = 0.2 * w as f64 / scale;
    let bar_m = [5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0]
        .into_iter()
        .rev()
        .find(|&m| m <= target)
        .unwrap_or(5.0);
    let bar_px = (bar_m * scale).round() as i64;
    let (x0, y0) = (12i64, h as i64 - 30);
    let label = format!("{}m", bar_m as i64);
    let s = 2;
    let text_w = label.len() as i64 * 4 * s;
    cv.rect(x0 - 6, y0 - 16, x0 + bar_px.max(text_w) + 6, y0 + 16, [255, 255, 255]);
    cv.rect(x0, y0 + 2, x0 + bar_px, y0 + 8, [0, 0, 0]);
    cv.rect(x0, y0 - 2, x0 + 2, y0 + 12, [0, 0, 0]);
    cv.rect(x0 + bar_px - 2, y0 - 2, x0 + bar_px, y0 + 12, [0, 0, 0]);
    cv.text(x0, y0 - 13, s, &label, [0, 0, 0]);

    encode(&cv, png::ColorType::Rgb)
}

fn encode(cv: &Canvas, colour: png::ColorType) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, cv.w as u32, cv.h as u32);
        enc.set_color(colour);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut wr = enc
            .write_header()
            .expect("in-memory PNG header cannot fail for a non-empty image");
        wr.write_image_data(&cv.px)
            .expect("in-memory PNG data has the size of the header");
        wr.finish().expect("in-memory PNG finish cannot fail");
    }
    out
}

/// A grey PNG of `size_px` (width, height) whose pixel (i, j) covers the square of side `m_per_px` with its
/// lower-left corner at `origin + (i, h − 1 − j) · m_per_px` (north up): 255 where a lane of any type (driving
/// surface, sidewalk, median, …) covers the pixel's centre, 0 elsewhere — nuScenes' "semantic prior" map mask.
pub(crate) fn surface_mask_png(net: &RoadNetwork, origin: DVec2, m_per_px: f64, size_px: (usize, usize)) -> Vec<u8> {
    let (w, h) = size_px;
    let mut cv = Canvas {
        w,
        h,
        channels: 1,
        px: vec![0; w * h],
        xs: Vec::new(),
    };
    let to_px = |p: DVec2| DVec2::new((p.x - origin.x) / m_per_px, h as f64 - (p.y - origin.y) / m_per_px);
    for lane in &net.lanes {
        for p in &net.pieces[lane.pieces.start as usize..lane.pieces.end as usize] {
            cv.fill(&p.corners.map(to_px), [255; 3], 1.0);
        }
    }
    encode(&cv, png::ColorType::Grayscale)
}
