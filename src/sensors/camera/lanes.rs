//! Lane math for shading [`LANES`] pixels (or samples) at once: a vector of points ([`V3`]), floors without
//! libm, an exponential. Built on `wide::f32x8`: one AVX register in the x86-64 build (`.cargo/config.toml`
//! enables AVX2), two SSE2 registers in a build for any x86-64 CPU. Every operation is plain IEEE single
//! precision without fused multiply-adds, so the same inputs give the same bits on every machine and in both
//! builds, and each lane equals the scalar formula it replaces (tests below). Clamps against a constant use
//! `fast_max` / `fast_min` (one `vmaxps` / `vminps`): with a bound that is not NaN they give the same bits as
//! `max` / `min`, which add a NaN test of the bound and a blend (a test below).

use glam::Vec3;

/// Lanes of one shading call: points (or samples) shaded at once.
pub const LANES: usize = 8;
/// A vector of [`LANES`] floats (`wide`: two SSE registers, or one AVX register where the build targets AVX).
pub type F = wide::f32x8;
/// A vector of [`LANES`] integers.
pub type I = wide::i32x8;

/// A lane vector from a function of the lane.
#[inline(always)]
pub fn lanes_from(f: impl FnMut(usize) -> f32) -> F {
    F::new(std::array::from_fn(f))
}

/// Eight 4-vectors (one per lane) as four lane vectors: `out[k]` holds element `k` of every lane's vector.
/// A pure rearrangement (the same bits in every build); in the AVX build twelve register shuffles instead of
/// 32 scalar moves through memory.
#[inline(always)]
pub fn transpose_cells(c: &[[f32; 4]; LANES]) -> [F; 4] {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use safe_arch::{m128, set_m128_m256, shuffle_m256, unpack_hi_m256, unpack_lo_m256};
        // Lanes i and i + 4 in the low and high halves; then a 4 × 4 transpose within each half.
        let pair = |i: usize| set_m128_m256(m128::from_array(c[i + 4]), m128::from_array(c[i]));
        let (r0, r1, r2, r3) = (pair(0), pair(1), pair(2), pair(3));
        let (t0, t1) = (unpack_lo_m256(r0, r1), unpack_hi_m256(r0, r1));
        let (t2, t3) = (unpack_lo_m256(r2, r3), unpack_hi_m256(r2, r3));
        // 0x44: elements 0, 1 of the first and 0, 1 of the second; 0xEE: elements 2, 3 of each.
        [
            wide::bytemuck::cast(shuffle_m256::<0x44>(t0, t2)),
            wide::bytemuck::cast(shuffle_m256::<0xEE>(t0, t2)),
            wide::bytemuck::cast(shuffle_m256::<0x44>(t1, t3)),
            wide::bytemuck::cast(shuffle_m256::<0xEE>(t1, t3)),
        ]
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let column = |k: usize| lanes_from(|i| c[i][k]);
        [column(0), column(1), column(2), column(3)]
    }
}

/// Points or vectors, one per lane.
#[derive(Clone, Copy, Debug)]
pub struct V3 {
    /// x of the lanes.
    pub x: F,
    /// y of the lanes.
    pub y: F,
    /// z of the lanes.
    pub z: F,
}

impl V3 {
    /// Zero in every lane.
    pub const ZERO: V3 = V3 {
        x: F::ZERO,
        y: F::ZERO,
        z: F::ZERO,
    };

    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> V3 {
        V3 {
            x: F::splat(v.x),
            y: F::splat(v.y),
            z: F::splat(v.z),
        }
    }

    /// One vector per lane.
    #[inline(always)]
    pub fn from_lanes(v: [Vec3; LANES]) -> V3 {
        V3 {
            x: F::new(v.map(|p| p.x)),
            y: F::new(v.map(|p| p.y)),
            z: F::new(v.map(|p| p.z)),
        }
    }

    /// The lanes.
    #[inline(always)]
    pub fn lanes(&self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        std::array::from_fn(|i| Vec3::new(x[i], y[i], z[i]))
    }

    /// Dot product per lane, `x·x + y·y + z·z` left to right (as `Vec3::dot`).
    #[inline(always)]
    pub fn dot(self, o: V3) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Dot product with one vector.
    #[inline(always)]
    pub fn dot_v(self, o: Vec3) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Squared length per lane.
    #[inline(always)]
    pub fn length_squared(self) -> F {
        self.dot(self)
    }

    /// Scales every lane by its own factor.
    #[inline(always)]
    pub fn scale(self, s: F) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    /// `a * (1 − s) + b * s` per lane (as `Vec3::lerp`).
    #[inline(always)]
    pub fn lerp(a: Vec3, b: Vec3, s: F) -> V3 {
        let r = F::ONE - s;
        V3 {
            x: r * a.x + s * b.x,
            y: r * a.y + s * b.y,
            z: r * a.z + s * b.z,
        }
    }

    /// Lane by lane: `mask` ? `a` : `b`.
    #[inline(always)]
    pub fn select(mask: F, a: V3, b: V3) -> V3 {
        V3 {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }

    /// Unit vectors, or zero where the length is zero or not finite (as `Vec3::normalize_or_zero`).
    #[inline(always)]
    pub fn normalize_or_zero(self) -> V3 {
        let rcp = F::ONE / self.length_squared().sqrt();
        let ok = rcp.is_finite() & rcp.simd_gt(F::ZERO);
        let n = self.scale(rcp);
        V3::select(ok, n, V3::ZERO)
    }
}

impl std::ops::Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl std::ops::Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

/// Component-wise product.
impl std::ops::Mul for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}

/// `e^x` per lane (Cephes' `expf` polynomial, relative error below 2·10⁻⁷), `x` clamped to [−87.3, 88.3].
#[inline(always)]
pub fn exp_lanes(x: F) -> F {
    let x = x.fast_max(F::splat(-87.3)).fast_min(F::splat(88.3));
    let n = (x * std::f32::consts::LOG2_E).fast_round_int();
    let nf = n.round_float();
    let r = x - nf * 0.693_359_4 - nf * -2.121_944_4e-4;
    let mut y = F::splat(1.987_569_1e-4);
    y = y * r + 1.398_199_9e-3;
    y = y * r + 8.333_452e-3;
    y = y * r + 4.166_579_6e-2;
    y = y * r + 0.166_666_65;
    y = y * r + 0.5;
    let y = y * r * r + r + 1.0;
    let scale: F = wide::bytemuck::cast((n + 127) << 23);
    y * scale
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn the_lane_exp_is_within_a_few_ulps(x in -87.0f32..88.0) {
            let got = exp_lanes(F::splat(x)).to_array()[0];
            let want = f64::from(x).exp();
            let rel = ((f64::from(got) - want) / want).abs();
            prop_assert!(rel < 4.0e-7, "exp({}) = {} against {} ({:e})", x, got, want, rel);
        }
    }

    #[test]
    fn clamps_against_a_constant_are_the_same_bits_fast_or_not() {
        let x = F::new([
            f32::NAN,
            -0.0,
            0.0,
            -1.0e-30,
            1.0e-30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.5,
        ]);
        for bound in [0.0, -0.0, 1.0, -87.3, 1.0e-12, f32::INFINITY] {
            let b = F::splat(bound);
            let bits = |v: F| v.to_array().map(f32::to_bits);
            assert_eq!(bits(x.fast_max(b)), bits(x.max(b)), "max against {bound}");
            assert_eq!(bits(x.fast_min(b)), bits(x.min(b)), "min against {bound}");
        }
    }

    #[test]
    fn the_cell_transpose_moves_every_element_to_its_place() {
        let c: [[f32; 4]; LANES] = std::array::from_fn(|i| std::array::from_fn(|k| (10 * i + k) as f32 + 0.5));
        let got = transpose_cells(&c).map(|v| v.to_array());
        for (k, lanes) in got.iter().enumerate() {
            for (i, v) in lanes.iter().enumerate() {
                assert_eq!(*v, c[i][k], "lane {i} element {k}");
            }
        }
    }

    #[test]
    fn exp_saturates_instead_of_overflowing() {
        let got = exp_lanes(F::new([-1.0e4, -87.3, 0.0, 1.0e4, -1.0e4, -87.3, 0.0, 1.0e4])).to_array();
        assert!(got[0] >= 0.0 && got[0] < 1.0e-37);
        assert_eq!(got[2], 1.0);
        assert!(got[3].is_finite() && got[3] > 1.0e38);
    }

    #[test]
    fn vectors_match_glam_lane_by_lane() {
        let a = [
            Vec3::new(1.0, -2.0, 0.5),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(3.0, 4.0, 12.0),
            Vec3::new(-1.0e-3, 2.0e-3, 0.0),
            Vec3::new(f32::NAN, 1.0, 0.0),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(-5.0, 7.0, -9.0),
        ];
        let b = Vec3::new(0.3, -0.7, 0.2);
        let v = V3::from_lanes(a);
        let n = v.normalize_or_zero().lanes();
        let d = v.dot_v(b).to_array();
        let s = [0.0, 0.25, 0.5, 1.0, 0.1, 0.7, 0.9, 0.33];
        let l = V3::lerp(b, a[2], F::new(s)).lanes();
        for i in 0..LANES {
            assert_eq!(n[i], a[i].normalize_or_zero(), "{i}");
            assert_eq!(d[i].to_bits(), a[i].dot(b).to_bits(), "{i}");
            assert_eq!(l[i], b.lerp(a[2], s[i]));
        }
    }
}
