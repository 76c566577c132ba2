//! Small helpers every room may use (the bottom layer, beside `error`): atomic file writes and capped reads,
//! SplitMix64 for values that are pure functions of a seed, JSON sequences streamed from iterators, and XML
//! escaping.

pub mod files;
pub mod mix;
pub mod stream_json;
pub(crate) mod xml;
