//! Small helpers every room may use (the bottom layer, beside `error`): atomic file writes and capped reads,
//! SplitMix64 for values that are pure functions of a seed, JSON sequences streamed from iterators, XML
//! escaping, Brown–Conrady lens distortion and sRGB's transfer function.

pub mod files;
pub mod lens;
pub mod mix;
pub mod srgb;
pub mod stream_json;
pub(crate) mod xml;
