//! A band's sparse visibility ([`BandVisibility`]): 2 × 2 samples per pixel drawn sparsely — every pixel's first
//! sample on a grid, all four only for edge candidates (pixels whose grid corners differ) — with the
//! rasteriser's own spans, keys and depth test; each row's candidates also kept as 64-column bit words, which a
//! triangle's span visits instead of every pixel.

use super::raster::*;

/// The marker of an edge pixel (its samples see different primitives) in [`BandVisibility::prim`].
pub const EDGE: u32 = EMPTY - 1;

/// The visibility of a band of image rows at 2 × 2 samples per pixel, drawn sparsely: a grid of each pixel's
/// first sample (its sample (0, 0)) for every pixel, and all four samples only for edge candidates, pixels
/// whose grid corners (their own first sample and those of the pixels right, below and diagonally below) do
/// not all see one primitive. Every drawn sample has the coverage, key and depth test of a full
/// `2w × 2h`-sample [`Raster`] drawn with the same triangles in the same order; a pixel that is not a
/// candidate is taken to be covered by its corners' primitive (only a feature narrower than a pixel could
/// hide between them, and the first-sample labels miss it too).
#[derive(Clone, Debug)]
pub struct BandVisibility {
    /// The grid: the first sample of every pixel of the band's rows and of the row below.
    pub grid: Raster,
    /// Per pixel of the band: the primitive all its samples see (or [`EDGE`] where they differ) and their
    /// mean depth key (interpolated from the corners where the pixel is not a candidate).
    pub prim: Vec<u32>,
    /// See [`BandVisibility::prim`].
    pub key: Vec<f32>,
    /// The edge candidates in (row, column) order (those whose samples turned out to agree included: their
    /// [`BandVisibility::prim`] is not [`EDGE`]): their columns, their four samples' depth keys and primitives
    /// (in the order (0, 0), (1, 0), (0, 1), (1, 1) within the pixel) and where each row's start (one more
    /// entry than rows).
    pub edge_x: Vec<u32>,
    /// See [`BandVisibility::edge_x`].
    pub edge_key: Vec<[f32; 4]>,
    /// See [`BandVisibility::edge_x`].
    pub edge_prim: Vec<[u32; 4]>,
    /// See [`BandVisibility::edge_x`].
    pub edge_rows: Vec<usize>,
    /// The candidates as bits, `w.div_ceil(64)` words per row (bit `b` of word `j`: column `64 j + b`), and
    /// the index in [`BandVisibility::edge_x`] of each word's first candidate: a triangle's span finds its
    /// candidates by words instead of searching the list.
    edge_bits: Vec<u64>,
    edge_rank: Vec<u32>,
}

/// The bits of word `j` (columns `64 j..64 j + 64`) that lie in `lo..=hi` (`j` within `lo / 64..=hi / 64`).
#[inline(always)]
fn word_mask(j: usize, lo: usize, hi: usize) -> u64 {
    let from = if j == lo / 64 { lo % 64 } else { 0 };
    let to = if j == hi / 64 { hi % 64 } else { 63 };
    (u64::MAX << from) & (u64::MAX >> (63 - to))
}

/// Whether any of the bits `lo..=hi` is set in `bits` (64 per word).
#[inline(always)]
fn any_bit(bits: &[u64], lo: usize, hi: usize) -> bool {
    lo <= hi && (lo / 64..=hi / 64).any(|j| bits[j] & word_mask(j, lo, hi) != 0)
}

/// Words of candidate bits per row of a `w`-pixel-wide band.
const fn edge_words(w: usize) -> usize {
    w.div_ceil(64)
}

impl BandVisibility {
    /// Buffers for bands of up to `rows` rows of a `w`-pixel-wide image.
    pub fn new(w: usize, rows: usize) -> BandVisibility {
        BandVisibility {
            grid: Raster::new(w, rows + 1),
            prim: vec![EMPTY; w * rows],
            key: vec![0.0; w * rows],
            edge_x: Vec::new(),
            edge_key: Vec::new(),
            edge_prim: Vec::new(),
            edge_rows: Vec::with_capacity(rows + 1),
            edge_bits: vec![0; edge_words(w) * rows],
            edge_rank: vec![0; edge_words(w) * rows],
        }
    }

    /// Draws the image rows `y0..y0 + h` of an `image_h`-row image: the triangles `bin` of `tris` (set up at
    /// 2 × 2 samples per pixel), in that order; `bin` must hold every triangle that reaches the band's sample
    /// rows or the first sample row below it.
    pub fn draw(&mut self, tris: &[Setup], bin: &[u32], y0: usize, h: usize, image_h: usize) {
        // The band's grid: the first sample of each pixel, its triangles drawn in order.
        let w = self.grid.width;
        self.grid.clear(0.0);
        for &i in bin {
            self.grid.draw_grid_rows(&tris[i as usize], y0..=y0 + h, y0);
        }
        let Self {
            grid,
            prim: band_prim,
            key: band_key,
            edge_x,
            edge_key,
            edge_prim,
            edge_rows,
            edge_bits,
            edge_rank,
        } = self;
        let words = edge_words(w);
        // Pixels whose grid corners (their own first sample and those of the pixels right, below and
        // diagonally below) see one primitive are taken to be covered by it (only a feature narrower than a
        // pixel could hide between the corners), with the depth key of their centre interpolated from the
        // corners; the others are edge candidates, whose four samples are drawn below.
        edge_x.clear();
        edge_key.clear();
        edge_prim.clear();
        edge_rows.clear();
        for row in 0..h {
            edge_rows.push(edge_x.len());
            let (g0, g1) = (
                &grid.prim[row * w..(row + 1) * w],
                &grid.prim[(row + 1) * w..(row + 2) * w],
            );
            let (k0, k1) = (
                &grid.key[row * w..(row + 1) * w],
                &grid.key[(row + 1) * w..(row + 2) * w],
            );
            let prims = &mut band_prim[row * w..(row + 1) * w];
            let keys = &mut band_key[row * w..(row + 1) * w];
            // Branch-free over the row, on slices of one length (the compiler vectorises these), then the rare
            // edges collected.
            let n = w - 1;
            let (p00, p10, p01, p11) = (&g0[..n], &g0[1..=n], &g1[..n], &g1[1..=n]);
            let (k00, k10, k01) = (&k0[..n], &k0[1..=n], &k1[..n]);
            let (prims_n, keys_n) = (&mut prims[..n], &mut keys[..n]);
            for i in 0..n {
                keys_n[i] = k00[i] + ((k10[i] - k00[i]) + (k01[i] - k00[i])) * 0.25;
            }
            for i in 0..n {
                let p = p00[i];
                let same = (p10[i] == p) & (p01[i] == p) & (p11[i] == p);
                prims_n[i] = if same { p } else { EDGE };
            }
            // The last column and the image's last row have no corners beyond them.
            prims[w - 1] = EDGE;
            if y0 + row + 1 == image_h {
                prims.fill(EDGE);
            }
            // The candidates by words of 64 columns: their bits (a loop the compiler vectorises), then each set
            // bit listed.
            let (bits, rank) = (
                &mut edge_bits[row * words..(row + 1) * words],
                &mut edge_rank[row * words..(row + 1) * words],
            );
            for (j, chunk) in prims.chunks(64).enumerate() {
                let mut m = 0u64;
                for (b, &p) in chunk.iter().enumerate() {
                    m |= u64::from(p == EDGE) << b;
                }
                bits[j] = m;
                rank[j] = edge_x.len() as u32;
                while m != 0 {
                    let x = 64 * j + m.trailing_zeros() as usize;
                    edge_x.push(x as u32);
                    edge_key.push([k0[x], 0.0, 0.0, 0.0]);
                    edge_prim.push([g0[x], EMPTY, EMPTY, EMPTY]);
                    m &= m - 1;
                }
            }
        }
        edge_rows.push(edge_x.len());
        // The edge candidates' other three samples: the band's triangles drawn in order at those samples only,
        // with the keys and the depth test of the rasteriser (so the same samples as a full-resolution buffer).
        if !edge_x.is_empty() {
            for &i in bin {
                let t = &tris[i as usize];
                let rows = (t.row0 as usize).max(2 * y0)..=(t.row1 as usize).min(2 * (y0 + h) - 1);
                // The pixels the triangle's bounds reach: a row without candidates among them needs no span.
                let (reach_lo, reach_hi) = t.pixel_reach(w);
                for sample_row in rows {
                    let (sy, row) = (sample_row % 2, sample_row / 2 - y0);
                    if !any_bit(&edge_bits[row * words..(row + 1) * words], reach_lo, reach_hi) {
                        continue;
                    }
                    let Some(span) = t.span(sample_row) else {
                        continue;
                    };
                    // The candidates with a sample in the span: pixels `x0 / 2..=x1 / 2` (the first of them
                    // through its right column only where `x0` is odd, as the column test below says).
                    let (lo, hi) = (span.x0 / 2, (span.x1 / 2).min(w - 1));
                    let (bits, rank) = (
                        &edge_bits[row * words..(row + 1) * words],
                        &edge_rank[row * words..(row + 1) * words],
                    );
                    for j in lo / 64..=hi / 64 {
                        let mask = word_mask(j, lo, hi);
                        // Candidates of the word left of the span still count for the index of the first one
                        // in it.
                        let left = bits[j] & !(u64::MAX << mask.trailing_zeros());
                        let mut e = rank[j] as usize + left.count_ones() as usize;
                        let mut m = bits[j] & mask;
                        while m != 0 {
                            let x = 64 * j + m.trailing_zeros() as usize;
                            // Sample (0, 0) is the grid's.
                            for sx in (1 - sy)..2 {
                                let column = 2 * x + sx;
                                if column < span.x0 || column > span.x1 {
                                    continue;
                                }
                                let key = span.key(column);
                                let k = sy * 2 + sx;
                                if key > edge_key[e][k] {
                                    edge_key[e][k] = key;
                                    edge_prim[e][k] = t.prim;
                                }
                            }
                            e += 1;
                            m &= m - 1;
                        }
                    }
                }
            }
        }
        // Candidates whose four samples see one primitive after all: that primitive, the mean of their keys.
        for row in 0..h {
            for e in edge_rows[row]..edge_rows[row + 1] {
                let (p, k) = (edge_prim[e], edge_key[e]);
                if p[1] == p[0] && p[2] == p[0] && p[3] == p[0] {
                    let at = row * w + edge_x[e] as usize;
                    band_prim[at] = p[0];
                    band_key[at] = (k[0] + k[1] + k[2] + k[3]) * 0.25;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn the_grid_of_every_other_sample_equals_those_samples_of_the_full_raster() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (w, h) = (37usize, 29usize);
        let mut full = Raster::new(w, h);
        full.clear(0.0);
        // Grid of (w + 1) / 2 × (h + 1) / 2, drawn as two bands of grid rows to exercise the origin.
        let (gw, gh) = (w.div_ceil(2), h.div_ceil(2));
        let mut top = Raster::new(gw, 8);
        let mut bottom = Raster::new(gw, gh - 8);
        top.clear(0.0);
        bottom.clear(0.0);
        for prim in 0..60u32 {
            let v: [DVec3; 3] = std::array::from_fn(|_| {
                DVec3::new(
                    rng.random_range(-5.0..w as f64 + 5.0),
                    rng.random_range(-5.0..h as f64 + 5.0),
                    rng.random_range(0.01..1.0),
                )
            });
            if let Some(t) = Setup::new(v, prim, w, h) {
                full.draw_rows(&t, t.row0 as usize..=t.row1 as usize, 0);
                top.draw_grid_rows(&t, 0..=7, 0);
                bottom.draw_grid_rows(&t, 8..=gh - 1, 8);
            }
        }
        for j in 0..gh {
            for i in 0..gw {
                let (g, at) = if j < 8 {
                    (&top, j * gw + i)
                } else {
                    (&bottom, (j - 8) * gw + i)
                };
                let f = 2 * j * w + 2 * i;
                assert_eq!(
                    (g.prim[at], g.key[at].to_bits()),
                    (full.prim[f], full.key[f].to_bits()),
                    "{i},{j}"
                );
            }
        }
    }

    #[test]
    fn band_visibility_draws_the_samples_of_the_full_raster_wherever_a_pixel_has_an_edge() {
        // An image of 23 × 20 pixels (bands of 8, 8 and 4 rows) at 2 × 2 samples per pixel: one word of
        // candidate bits per row.
        band_visibility_equals_the_full_raster(23, 11, 3.0..30.0);
    }

    #[test]
    fn band_visibility_finds_candidates_across_words_of_bits() {
        // 150 pixels: three words of candidate bits per row (the last one partly used), triangles up to
        // three words wide, so that spans start, end and pass within and across words.
        band_visibility_equals_the_full_raster(150, 12, 3.0..200.0);
    }

    /// Draws rounds of random triangles into a `w × 20`-pixel image both as bands and as a full raster at
    /// 2 × 2 samples per pixel and compares every grid sample, every candidate's four samples and every pixel's
    /// resolution.
    fn band_visibility_equals_the_full_raster(w: usize, seed: u64, radius: std::ops::Range<f64>) {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let h = 20usize;
        let (sw, sh) = (2 * w, 2 * h);
        let (mut edge_pixels, mut missed) = (0, 0);
        for round in 0..20 {
            let mut tris = Vec::new();
            for prim in 0..12u32 {
                // Triangles of a few pixels and larger, some reaching past the image.
                let (cx, cy, r) = (
                    rng.random_range(-4.0..sw as f64 + 4.0),
                    rng.random_range(-4.0..sh as f64 + 4.0),
                    rng.random_range(radius.clone()),
                );
                let v: [DVec3; 3] = std::array::from_fn(|_| {
                    DVec3::new(
                        cx + rng.random_range(-r..r),
                        cy + rng.random_range(-r..r),
                        rng.random_range(0.01..1.0),
                    )
                });
                tris.extend(Setup::new(v, prim + round * 100, sw, sh));
            }
            let mut full = Raster::new(sw, sh);
            full.clear(0.0);
            for t in &tris {
                full.draw_rows(t, t.row0 as usize..=t.row1 as usize, 0);
            }
            let sample = |x: usize, y: usize, k: usize| {
                let i = (2 * y + k / 2) * sw + 2 * x + k % 2;
                (full.prim[i], full.key[i].to_bits())
            };
            let all: Vec<u32> = (0..tris.len() as u32).collect();
            let mut band = BandVisibility::new(w, 8);
            for y0 in (0..h).step_by(8) {
                let rows = 8.min(h - y0);
                band.draw(&tris, &all, y0, rows, h);
                for row in 0..rows {
                    let y = y0 + row;
                    // The grid is every pixel's first sample.
                    for x in 0..w {
                        let g = (band.grid.prim[row * w + x], band.grid.key[row * w + x].to_bits());
                        assert_eq!(g, sample(x, y, 0), "grid {x},{y}");
                    }
                    // Edge candidates: all four samples as the full raster has them.
                    let candidates = band.edge_rows[row]..band.edge_rows[row + 1];
                    for e in candidates.clone() {
                        let x = band.edge_x[e] as usize;
                        for k in 0..4 {
                            let got = (band.edge_prim[e][k], band.edge_key[e][k].to_bits());
                            assert_eq!(got, sample(x, y, k), "pixel {x},{y} sample {k}");
                        }
                        // Resolved: one primitive with the mean key where the samples agree, an edge where not.
                        let p = band.edge_prim[e];
                        if p.iter().all(|&q| q == p[0]) {
                            let k = band.edge_key[e];
                            assert_eq!(band.prim[row * w + x], p[0]);
                            assert_eq!(band.key[row * w + x], (k[0] + k[1] + k[2] + k[3]) * 0.25);
                        } else {
                            assert_eq!(band.prim[row * w + x], EDGE, "pixel {x},{y}");
                        }
                    }
                    // Other pixels: one primitive, the full raster's first sample's.
                    for x in 0..w {
                        let is_candidate = band.edge_x[candidates.clone()].contains(&(x as u32));
                        let samples: Vec<u32> = (0..4).map(|k| sample(x, y, k).0).collect();
                        let edge = samples.iter().any(|&p| p != samples[0]);
                        edge_pixels += usize::from(edge);
                        if !is_candidate {
                            assert_eq!(band.prim[row * w + x], samples[0], "pixel {x},{y}");
                            missed += usize::from(edge);
                        }
                    }
                }
            }
        }
        // A pixel whose samples differ but whose corners agree holds a feature narrower than a pixel between
        // them (here the sharp tips of random triangles): 69 of 1,637 edge pixels in the 23-pixel-wide image.
        assert!(edge_pixels > 1000, "{edge_pixels}");
        assert!(
            missed * 20 < edge_pixels,
            "{missed} of {edge_pixels} edge pixels missed"
        );
    }
}
