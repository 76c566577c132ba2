//! OpenDRIVE (.xodr 1.4–1.7) import: `parse` turns XML into raw records with line numbers, `geometry`
//! evaluates reference lines and cubic profiles, `build` turns raw records into the road-network model, and
//! `write` exports a built-in town as OpenDRIVE.
//! The caps below protect against hostile input (OOM, absurd values).

pub(crate) mod build;
pub(crate) mod geometry;
pub(crate) mod parse;
pub mod write;

/// Largest .xodr file we read.
pub const MAX_FILE_BYTES: u64 = 256 * 1024 * 1024;
/// Most XML nodes we parse.
pub const MAX_NODES: u32 = 20_000_000;
/// Most lane pieces a network may have (about 4 GB of lanes at 1 m steps would be absurd anyway).
pub const MAX_PIECES: usize = 4_000_000;
/// Longest road or geometry record.
pub const MAX_LENGTH_M: f64 = 100_000.0;
/// Widest lane.
pub const MAX_WIDTH_M: f64 = 50.0;
/// Largest lane offset (`<laneOffset>`, the shift of the lane reference line from the road's; real maps use a
/// few metres). Without it a cubic offset sends the lanes millions of metres away, and everything sampled
/// along the lanes (spawn points every 10 m) grows without bound (found by the fuzzer).
pub const MAX_LANE_OFFSET_M: f64 = 200.0;
/// Largest absolute coordinate.
pub const MAX_ABS_COORD_M: f64 = 10_000_000.0;
