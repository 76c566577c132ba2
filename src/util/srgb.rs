//! sRGB's transfer function (IEC 61966-2-1): linear light in [0, 1] to the encoded value of an 8-bit image's
//! channel (÷ 255), and back. The one definition the renderer's tone curve, its inverse (auto-exposure's meter)
//! and the scene's colours use.

/// Linear light in [0, 1] → sRGB's encoded value in [0, 1].
pub fn encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB's encoded value in [0, 1] → linear light in [0, 1].
pub fn decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decoding_undoes_encoding_at_every_8_bit_level() {
        for v in 0..=255u8 {
            let s = f32::from(v) / 255.0;
            assert!((encode(decode(s)) - s).abs() < 2.0e-6, "level {v}");
        }
        assert_eq!(encode(0.0), 0.0);
        assert!((encode(1.0) - 1.0).abs() < 1.0e-6);
    }
}
