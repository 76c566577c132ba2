//! Lighting from the weather: sun direction and colour from altitude and azimuth, sky and ambient from
//! cloudiness, night with street lamps and headlights, exponential fog from fog density, rain and wetness.
//! A pure function of the clip's [`WeatherParams`]; every value in linear RGB, scaled so that a mid-grey
//! surface in full noon sun maps near the middle of the 8-bit range after tone mapping.

use glam::Vec3;
use std::ops::Add;

use super::lanes::{F, I, V3, exp_lanes, lanes_from};
use super::round::floor_int;
use crate::spec::types::WeatherParams;

/// The lighting of a clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit vector towards the sun (world frame; may point below the horizon).
    pub sun_dir: Vec3,
    /// Direct sunlight on a surface facing the sun (0 at night).
    pub sun: Vec3,
    /// Ambient light from the sky on an upward surface.
    pub sky_ambient: Vec3,
    /// Ambient light bounced from the ground on a downward surface.
    pub ground_ambient: Vec3,
    /// Sky colour at the zenith.
    pub zenith: Vec3,
    /// Sky colour at the horizon.
    pub horizon: Vec3,
    /// Fog colour.
    pub fog: Vec3,
    /// Fog extinction, 1/m.
    pub fog_per_m: f32,
    /// 0 in daylight, 1 at night: street lamps, headlights and lit windows.
    pub night: f32,
    /// Surface wetness 0–1 (darker surfaces, reflections).
    pub wet: f32,
    /// Rain intensity 0–1 (streaks).
    pub rain: f32,
    /// Wind 0–1 (the streaks' slant).
    pub wind: f32,
    /// Whether the sun casts shadows.
    pub shadows: bool,
}

/// The distance at which the sky is fogged, metres.
pub const SKY_FOG_M: f32 = 1.0e4;

/// Luminous intensity of a street lamp (linear units × m²).
pub const LAMP_INTENSITY: f32 = 16.0;
/// Luminous intensity of a headlamp along its axis (linear units × m²).
pub const HEADLAMP_INTENSITY: f32 = 110.0;

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Lighting {
    /// The same lighting with the sun's and the sky's light (and the sky's and the fog's colours, which are
    /// that light scattered) times `k`; street lamps and headlights are unchanged. `k = 1` changes nothing.
    pub fn with_intensity(self, k: f32) -> Lighting {
        if k == 1.0 {
            return self;
        }
        Lighting {
            sun: self.sun * k,
            sky_ambient: self.sky_ambient * k,
            ground_ambient: self.ground_ambient * k,
            zenith: self.zenith * k,
            horizon: self.horizon * k,
            fog: self.fog * k,
            ..self
        }
    }

    /// The lighting of a weather.
    pub fn from_weather(w: &WeatherParams) -> Lighting {
        let alt = (w.sun_altitude_deg as f32).to_radians();
        let az = (w.sun_azimuth_deg as f32).to_radians();
        let sun_dir = Vec3::new(alt.cos() * az.cos(), alt.cos() * az.sin(), alt.sin()).normalize();
        let cloud = (w.cloudiness_pct as f32 / 100.0).clamp(0.0, 1.0);
        let fog = (w.fog_density_pct as f32 / 100.0).clamp(0.0, 1.0);
        let rain = (w.precipitation_pct as f32 / 100.0).clamp(0.0, 1.0);
        let wet = (w.wetness_pct as f32 / 100.0).max(0.85 * rain).clamp(0.0, 1.0);
        let alt_deg = w.sun_altitude_deg as f32;
        // Daylight fades in from 6° below to 10° above the horizon.
        let day = smoothstep(-6.0, 10.0, alt_deg);
        let night = 1.0 - smoothstep(-4.0, 6.0, alt_deg);
        // Warm, red light low over the horizon; white high up.
        let low = 1.0 - smoothstep(3.0, 30.0, alt_deg);
        let sun_colour = Vec3::new(1.0, 0.95, 0.88).lerp(Vec3::new(1.0, 0.55, 0.28), low);
        let direct = 2.4 * smoothstep(-1.0, 12.0, alt_deg) * (1.0 - 0.9 * cloud) * (1.0 - 0.6 * fog);
        let overcast = Vec3::new(0.62, 0.64, 0.68);
        let blue = Vec3::new(0.16, 0.32, 0.78);
        let sky_day = blue.lerp(overcast, cloud).lerp(Vec3::new(0.9, 0.55, 0.38), 0.55 * low);
        let ambient_day = 0.55 + 0.35 * cloud;
        let moon = Vec3::new(0.010, 0.013, 0.022);
        let sky_ambient = (sky_day * ambient_day * day + moon * (1.0 - day)) * (1.0 - 0.35 * rain);
        let zenith = (sky_day * 0.95 * day + Vec3::new(0.004, 0.006, 0.014) * (1.0 - day)) * (1.0 - 0.4 * rain);
        let horizon_day = Vec3::new(0.48, 0.62, 0.88)
            .lerp(overcast * 1.1, cloud)
            .lerp(Vec3::new(1.0, 0.6, 0.35), low);
        let horizon = horizon_day * day + Vec3::new(0.005, 0.006, 0.011) * (1.0 - day);
        let fog_colour = (Vec3::new(0.62, 0.64, 0.66) * day.max(0.006)).lerp(horizon, 0.3);
        Lighting {
            sun_dir,
            sun: sun_colour * direct,
            sky_ambient,
            ground_ambient: sky_ambient * 0.35,
            zenith,
            horizon,
            fog: fog_colour,
            // 2 % (clear) → visibility of kilometres; 100 % → about 60 m.
            fog_per_m: 0.0002 + 0.05 * fog * fog,
            night,
            wet,
            rain,
            wind: (w.wind_intensity_pct as f32 / 100.0).clamp(0.0, 1.0),
            shadows: direct > 0.05 && alt_deg > 1.0,
        }
    }

    /// The sky's colour through fog at [`SKY_FOG_M`], in every direction, where fog hides the sky entirely: the
    /// fog's colour, bit for bit what `shade::fog(self, self.sky(dir), SKY_FOG_M)` gives, so that a renderer
    /// need not work the sky out (thick fog). `None` where some of the sky shows through.
    ///
    /// Exact because the fog's transmittance `f` at that distance is then so small that `1 − f` rounds to 1
    /// and the sky's share, `sky · f` with the sky at its brightest (its horizon, zenith or ground colour plus
    /// 4.4 suns: glow and disc), is under half a unit in the last place of the fog's colour in each channel.
    pub fn sky_hidden_by_fog(&self) -> Option<Vec3> {
        let f = exp_lanes(F::splat(-self.fog_per_m * SKY_FOG_M)).to_array()[0];
        let brightest =
            self.horizon.max(self.zenith).max(self.ground_ambient).max_element() + 4.4 * self.sun.max_element();
        // Half a unit in the last place of `x` is at least `x · 2⁻²⁵`.
        let hidden =
            1.0 - f == 1.0 && self.fog.min_element() > 0.0 && brightest * f < self.fog.min_element() * 2.0f32.powi(-25);
        hidden.then_some(self.fog)
    }

    /// The sky's colour in the lanes' view directions (unit, world frame), the sun's disc included.
    #[inline(always)]
    pub fn sky(&self, dir: V3) -> V3 {
        let up = dir.z.fast_max(F::ZERO);
        let mut c = V3::lerp(self.horizon, self.zenith, horizon_to_zenith(up));
        let cos_sun = dir.dot_v(self.sun_dir);
        let glowing = cos_sun.simd_gt(F::splat(0.9));
        if glowing.any() {
            let g = ((cos_sun - 0.9) / 0.1).fast_max(F::ZERO);
            let g2 = g * g;
            let g4 = g2 * g2;
            let disc = cos_sun.simd_gt(F::splat(0.9996)).select(F::splat(4.0), F::ZERO);
            let k = glowing.select(F::splat(0.4) * g4 * g4 + disc, F::ZERO);
            c = c.add(V3::splat(self.sun).scale(k));
        }
        let below = dir.z.simd_lt(F::ZERO);
        if below.any() {
            let s = below.select((-dir.z * 4.0).fast_min(F::ONE), F::ZERO);
            c = c.scale(F::ONE - s).add(V3::splat(self.ground_ambient).scale(s));
        }
        c
    }
}

/// Segments of [`HORIZON_TO_ZENITH`].
const GRADIENT_STEPS: usize = 256;

/// The sky's gradient `up^0.6` as a table over `√up` (where it is `(√up)^1.2`, smooth enough for linear
/// interpolation to stay within 10⁻³ of it), so that the sky costs no `powf` per pixel.
static HORIZON_TO_ZENITH: std::sync::LazyLock<[f32; GRADIENT_STEPS + 2]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|i| (i.min(GRADIENT_STEPS) as f64 / GRADIENT_STEPS as f64).powf(1.2) as f32)
});

/// `up^0.6` for `up` in [0, 1], from [`HORIZON_TO_ZENITH`].
#[inline(always)]
fn horizon_to_zenith(up: F) -> F {
    let table = &*HORIZON_TO_ZENITH;
    let s = up.fast_min(F::ONE).sqrt() * GRADIENT_STEPS as f32;
    let i = floor_int(s).max(I::ZERO).min(I::splat(GRADIENT_STEPS as i32));
    let f = s - i.round_float();
    let ia = i.to_array();
    // `lanes_from`, not `array::map`: the latter is sometimes left out of line, and a call spills every vector
    // register of the shading around it.
    let at = |j: usize| lanes_from(|k| table[ia[k] as usize + j]);
    let (a, b) = (at(0), at(1));
    a + (b - a) * f
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::types::WeatherPreset;

    #[test]
    fn night_is_dark_and_noon_is_bright() {
        let noon = Lighting::from_weather(&WeatherPreset::ClearNoon.params());
        let night = Lighting::from_weather(&WeatherPreset::NightClear.params());
        assert!(noon.sun.x > 1.0 && night.sun.length() < 1e-3);
        assert!(night.night > 0.99 && noon.night < 0.01);
        assert!(noon.shadows && !night.shadows);
    }

    #[test]
    fn the_gradient_table_follows_the_power_law() {
        for k in 0..=2000 {
            let up = k as f32 / 2000.0;
            let got = horizon_to_zenith(F::splat(up)).to_array()[0];
            assert!(
                (got - up.powf(0.6)).abs() < 1.0e-3,
                "{up}: {got} against {}",
                up.powf(0.6)
            );
        }
    }
}
