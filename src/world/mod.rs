//! Road networks: the town model, its two sources (built-in procedural towns and OpenDRIVE import) and the
//! spatial queries the planner and the simulation use.

/// Names of the built-in procedural towns, in the order `pedsynth town list` shows them. They are modelled on
/// the paper's CARLA towns but are not CARLA's maps, hence the `_like` suffix.
pub const BUILTIN_TOWN_NAMES: [&str; 4] = ["town01_like", "town02_like", "town03_like", "town05_like"];
