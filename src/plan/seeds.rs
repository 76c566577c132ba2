//! Seed derivation: every random stream is a ChaCha20 generator keyed by the dataset seed and a stable
//! identity string (a clip id, a stratum id), never by a position in a list, so adding clips elsewhere changes
//! nothing and one clip can be re-planned alone.

use rand::SeedableRng;
use rand_chacha::ChaCha20Rng;

/// Domain-separation context for blake3's key derivation.
const CONTEXT: &str = "pedsynth 2026-11 seed derivation v1";

/// 32 seed bytes for `identity` under `dataset_seed`.
pub fn seed_bytes(dataset_seed: u64, identity: &str) -> [u8; 32] {
    let mut hasher = blake3::Hasher::new_derive_key(CONTEXT);
    hasher.update(&dataset_seed.to_le_bytes());
    hasher.update(identity.as_bytes());
    *hasher.finalize().as_bytes()
}

/// A u64 seed for `identity` under `dataset_seed` (the clip seed recorded in scripts and tables).
pub fn seed_u64(dataset_seed: u64, identity: &str) -> u64 {
    let bytes = seed_bytes(dataset_seed, identity);
    u64::from_le_bytes([
        bytes[0], bytes[1], bytes[2], bytes[3], bytes[4], bytes[5], bytes[6], bytes[7],
    ])
}

/// The random stream of `identity` under `dataset_seed`.
pub fn rng_for(dataset_seed: u64, identity: &str) -> ChaCha20Rng {
    ChaCha20Rng::from_seed(seed_bytes(dataset_seed, identity))
}

/// The random stream of a clip, from its recorded seed and a purpose tag (e.g. `"plan"`, `"sim"`).
pub fn clip_rng(clip_seed: u64, purpose: &str) -> ChaCha20Rng {
    rng_for(clip_seed, purpose)
}
