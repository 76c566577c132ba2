//! Domain randomisation per clip (`domain_randomisation`): the clip's draws from its own seed — the sun's
//! direction (into the clip's weather) and how its light, camera, scenery and textures look ([`ClipLook`]).
//! Pure: no IO.

use rand::RngExt;

use super::script::ClipLook;
use super::seeds::clip_rng;
use crate::spec::types::{DomainRandomisation, Range, WeatherParams};

/// The clip's weather and look under `randomisation` (the weather as given and the identity look when it is
/// off: nothing is drawn, so plans without it stay what they were).
pub(super) fn randomise(
    randomisation: &DomainRandomisation,
    weather: WeatherParams,
    clip_seed: u64,
) -> (WeatherParams, ClipLook) {
    if *randomisation == DomainRandomisation::default() {
        return (weather, ClipLook::default());
    }
    let mut rng = clip_rng(clip_seed, "domain randomisation");
    let mut draw = |r: Range| r.min() + (r.max() - r.min()) * rng.random::<f64>();
    let r = randomisation;
    let mut weather = weather;
    weather.sun_azimuth_deg = (weather.sun_azimuth_deg + draw(r.sun_azimuth_offset_deg)).rem_euclid(360.0);
    weather.sun_altitude_deg = (weather.sun_altitude_deg + draw(r.sun_altitude_offset_deg)).clamp(-90.0, 90.0);
    let look = ClipLook {
        light_intensity: draw(r.light_intensity),
        white_balance: [draw(r.white_balance), draw(r.white_balance), draw(r.white_balance)],
        exposure_key: draw(r.exposure_key),
        // Drawn after the light's and the camera's, so that their draws stay what they were before these keys.
        scenery_hue_deg: draw(r.scenery_hue_deg),
        scenery_saturation: draw(r.scenery_saturation),
        scenery_brightness: draw(r.scenery_brightness),
        texture_contrast: draw(r.texture_contrast),
    };
    (weather, look)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::types::WeatherPreset;

    #[test]
    fn off_draws_nothing_and_on_draws_within_the_ranges_per_clip() {
        let weather = WeatherPreset::ClearSunset.params();
        let off = randomise(&DomainRandomisation::default(), weather, 7);
        assert_eq!(off, (weather, ClipLook::default()));
        let on = DomainRandomisation {
            light_intensity: Range(0.5, 1.5),
            sun_azimuth_offset_deg: Range(-90.0, 90.0),
            sun_altitude_offset_deg: Range(-5.0, 5.0),
            white_balance: Range(0.8, 1.2),
            exposure_key: Range(0.7, 1.3),
            scenery_hue_deg: Range(-60.0, 60.0),
            scenery_saturation: Range(0.5, 1.5),
            scenery_brightness: Range(0.8, 1.2),
            texture_contrast: Range(0.0, 2.0),
        };
        let mut looks = Vec::new();
        for seed in 0..50 {
            let (w, look) = randomise(&on, weather, seed);
            assert_eq!((w, look), randomise(&on, weather, seed), "seeded");
            assert!((0.5..=1.5).contains(&look.light_intensity));
            assert!(look.white_balance.iter().all(|g| (0.8..=1.2).contains(g)));
            assert!((0.7..=1.3).contains(&look.exposure_key));
            assert!((-60.0..=60.0).contains(&look.scenery_hue_deg));
            assert!((0.5..=1.5).contains(&look.scenery_saturation));
            assert!((0.8..=1.2).contains(&look.scenery_brightness));
            assert!((0.0..=2.0).contains(&look.texture_contrast));
            assert!((w.sun_altitude_deg - weather.sun_altitude_deg).abs() <= 5.0);
            assert!((0.0..360.0).contains(&w.sun_azimuth_deg));
            looks.push(look.light_intensity);
        }
        looks.sort_by(f64::total_cmp);
        looks.dedup();
        assert_eq!(looks.len(), 50, "every clip draws its own");
        // The light's and camera's draws do not move when the scenery's and textures' ranges are added.
        let light_only = DomainRandomisation {
            scenery_hue_deg: Range(0.0, 0.0),
            scenery_saturation: Range(1.0, 1.0),
            scenery_brightness: Range(1.0, 1.0),
            texture_contrast: Range(1.0, 1.0),
            ..on
        };
        let (w_all, all) = randomise(&on, weather, 3);
        let (w_light, light) = randomise(&light_only, weather, 3);
        assert_eq!(w_all, w_light);
        assert_eq!(
            (all.light_intensity, all.white_balance, all.exposure_key),
            (light.light_intensity, light.white_balance, light.exposure_key)
        );
    }
}
