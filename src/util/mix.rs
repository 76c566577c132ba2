//! SplitMix64: a 64-bit mixing function for values that must be pure functions of their inputs without a
//! random stream (colours of an identity, texture noise, building placement). Random streams are ChaCha
//! (`plan::seeds`); this only scrambles a seed that already came from one, or a position.

/// SplitMix64's step: the golden-ratio increment, then Stafford's variant-13 finaliser.
#[inline]
pub fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

#[cfg(test)]
mod tests {
    #[test]
    fn matches_the_reference_sequence() {
        // SplitMix64 seeded with 0 (Vigna's reference): the first output is step(0).
        assert_eq!(super::splitmix64(0), 0xE220_A839_7B1D_CDAF);
    }
}
