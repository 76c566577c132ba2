//! Floors and ceilings without libm calls, one place for all of them: scalar `f32` floors for texture lookups,
//! `f64` floors and ceilings for the rasteriser's span bounds (one rounding instruction where the build has
//! SSE4.1, integer conversions elsewhere), and the eight-lane floor of the shading. Each equals the standard
//! function on its stated range (tested here), so no pixel depends on which one a build uses.

use super::lanes::{F, I};

/// `x.floor()` without the call into libm that `f32::floor` compiles to on x86-64 without SSE4.1 (a hot
/// spot of texture lookups); the same value for every finite `x` and NaN (only `−0.0` becomes `+0.0`).
#[inline(always)]
pub fn floor_f32(x: f32) -> f32 {
    // Every float of magnitude 2^23 or more is an integer already.
    if x.abs() < 8_388_608.0 { floor_i32(x) as f32 } else { x }
}

/// Adding `1.5 × 2^23` to a float of magnitude below [`ROUNDING_RANGE`] rounds it to an integer, held in the
/// sum's low mantissa bits (its unit in the last place is 1).
const ROUNDING_MAGIC: f32 = 12_582_912.0;
const ROUNDING_RANGE: f32 = 4_194_304.0;

/// `x.floor()` as an integer, for `|x| < 2^31` (texture coordinates; NaN gives 0). Below 2^22 in magnitude
/// (every texture and shadow-map coordinate) without the saturating float-to-integer conversion, whose
/// range checks cost as much as the rest of a texture lookup.
#[inline(always)]
pub fn floor_i32(x: f32) -> i32 {
    if x.abs() < ROUNDING_RANGE {
        let big = x + ROUNDING_MAGIC;
        let nearest = big.to_bits() as i32 - ROUNDING_MAGIC.to_bits() as i32;
        nearest - i32::from(big - ROUNDING_MAGIC > x)
    } else {
        let t = x as i32;
        t - i32::from(t as f32 > x)
    }
}

/// `x.ceil()`: one rounding instruction where the build has SSE4.1 (the x86-64 build's AVX2 includes it),
/// otherwise [`ceil_by_conversion`] instead of the call into libm that `ceil` compiles to on x86-64 without
/// SSE4.1.
#[inline(always)]
pub fn ceil_f64(x: f64) -> f64 {
    if cfg!(any(target_feature = "sse4.1", not(target_arch = "x86_64"))) {
        x.ceil()
    } else {
        ceil_by_conversion(x)
    }
}

/// `x.floor()` as [`ceil_f64`].
#[inline(always)]
pub fn floor_f64(x: f64) -> f64 {
    if cfg!(any(target_feature = "sse4.1", not(target_arch = "x86_64"))) {
        x.floor()
    } else {
        floor_by_conversion(x)
    }
}

/// `x.ceil()` through integer conversions (`x` within ±2⁶³, NaN kept).
#[inline(always)]
pub fn ceil_by_conversion(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t < x {
        t + 1.0
    } else if x.is_nan() {
        x
    } else {
        t
    }
}

/// `x.floor()` as [`ceil_by_conversion`]./// `x.floor()` as [`ceil_by_conversion`].
#[inline(always)]
pub fn floor_by_conversion(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else if x.is_nan() {
        x
    } else {
        t
    }
}

/// `x.floor()` per lane as an integer, for `|x| < 2^31` (NaN and larger values give `i32::MIN`): rounding
/// to nearest, then one down where that went up.
#[inline(always)]
pub fn floor_int(x: F) -> I {
    let r = x.fast_round_int();
    let up: I = wide::bytemuck::cast(r.round_float().simd_gt(x));
    r + up
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn fast_floors_equal_the_standard_floor(x in -3.0e9f32..3.0e9f32, small in -1.0e4f32..1.0e4f32) {
            for v in [x, small, small.trunc(), small.trunc() - 0.5] {
                prop_assert_eq!(floor_f32(v), v.floor(), "{}", v);
                if v.abs() < 2.0e9 {
                    prop_assert_eq!(floor_i32(v) as f32, v.floor(), "{}", v);
                }
            }
        }
    }

    proptest! {
        #[test]
        fn the_lane_floor_is_the_floor(a in -2.0e9f32..2.0e9, b in -1.0e4f32..1.0e4, c in -3.0f32..3.0) {
            let v = [a, b, c, b.trunc() - 0.5, -a, -b, -c, 0.5 - b.trunc()];
            let got = floor_int(F::new(v)).to_array();
            for (g, x) in got.iter().zip(v) {
                prop_assert_eq!(*g as f32, x.floor(), "{}", x);
            }
        }
    }

    #[test]
    fn fast_floor_edge_cases() {
        for v in [
            0.0f32,
            1.0,
            -1.0,
            -0.5,
            0.5,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            1.0e30,
            -1.0e30,
            4_194_303.5,
            -4_194_303.5,
            4_194_304.0,
            -4_194_304.0,
            4_194_304.5,
            -4_194_304.5,
            2.5,
            -2.5,
            3.5,
            -3.5,
            0.999_999_94,
            -0.999_999_94,
        ] {
            assert_eq!(floor_f32(v), v.floor(), "{v}");
            if v.abs() < 2.0e9 {
                assert_eq!(floor_i32(v) as f32, v.floor(), "{v}");
            }
        }
        assert!(floor_f32(f32::NAN).is_nan());
        assert_eq!(floor_f32(f32::INFINITY), f32::INFINITY);
        assert_eq!(floor_f32(f32::NEG_INFINITY), f32::NEG_INFINITY);
    }

    #[test]
    fn the_inline_ceil_and_floor_equal_the_library_ones() {
        for x in [
            -3.5,
            -3.0,
            -2.7,
            -0.5,
            -0.0,
            0.0,
            1e-300,
            0.2,
            0.5,
            1.0,
            2.5,
            1279.999,
            1280.0,
            4.0e15,
            f64::NAN,
        ] {
            // Equal values (the sign of a zero result may differ, which no caller sees), NaN for NaN.
            let same = |a: f64, b: f64| a == b || (a.is_nan() && b.is_nan());
            assert!(same(ceil_by_conversion(x), x.ceil()), "{x}");
            assert!(same(floor_by_conversion(x), x.floor()), "{x}");
            assert!(same(ceil_f64(x), x.ceil()) && same(floor_f64(x), x.floor()), "{x}");
        }
    }
}
