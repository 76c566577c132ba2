//! `domain_randomisation`: ranges from which each clip draws how it looks — the light's strength and the sun's
//! direction, the camera's colour balance and exposure, the scenery's colours and the textures' contrast — from
//! its own seed. Off (every range a single value that changes nothing) by default.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::Range;

/// Domain randomisation: each range `[min, max]` is drawn uniformly per clip from the clip's seed (the stream
/// `"domain randomisation"`), so a clip looks the same whatever else the spec changes. The draws are recorded in
/// the plan's clip scripts (`look`, and the weather's sun angles).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct DomainRandomisation {
    /// Factor on the sun's and the sky's light (and the sky's colour), `[1, 1]` by default.
    pub light_intensity: Range,
    /// Degrees added to the weather's sun azimuth, `[0, 0]` by default.
    pub sun_azimuth_offset_deg: Range,
    /// Degrees added to the weather's sun altitude (clamped to ±90°), `[0, 0]` by default.
    pub sun_altitude_offset_deg: Range,
    /// The camera's colour balance: a gain on the linear light drawn per channel (red, green, blue), `[1, 1]`
    /// by default.
    pub white_balance: Range,
    /// Factor on auto-exposure's `key` (how bright the camera exposes), `[1, 1]` by default.
    pub exposure_key: Range,
    /// Degrees the scenery's colours (buildings, shop signs, ground, trees, street furniture, cars' paint; not
    /// people, road markings or lights) turn round the colour wheel, `[0, 0]` by default.
    pub scenery_hue_deg: Range,
    /// Factor on the scenery's colour saturation (0: grey), `[1, 1]` by default.
    pub scenery_saturation: Range,
    /// Factor on the scenery's brightness (its albedo), `[1, 1]` by default.
    pub scenery_brightness: Range,
    /// Factor on the contrast of every procedural texture (asphalt, tiles, walls, grass, bark, foliage,
    /// clothes' weave; 0: flat colours), `[1, 1]` by default.
    pub texture_contrast: Range,
}

impl Default for DomainRandomisation {
    fn default() -> Self {
        DomainRandomisation {
            light_intensity: Range(1.0, 1.0),
            sun_azimuth_offset_deg: Range(0.0, 0.0),
            sun_altitude_offset_deg: Range(0.0, 0.0),
            white_balance: Range(1.0, 1.0),
            exposure_key: Range(1.0, 1.0),
            scenery_hue_deg: Range(0.0, 0.0),
            scenery_saturation: Range(1.0, 1.0),
            scenery_brightness: Range(1.0, 1.0),
            texture_contrast: Range(1.0, 1.0),
        }
    }
}
