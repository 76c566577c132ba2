//! Umbrellas in rain (issue 44, item 1): pedestrians hold open umbrellas in rainy weathers only, and an umbrella
//! is scenery-like `Dynamic` with instance 0 in the label streams, so the holder's mask, box and keypoints stay
//! the body's.

use pedsynth::plan::identity::umbrella_share;

use crate::camera::{clip, masks_match_boxes_and_keypoints, spec};

#[test]
fn umbrellas_are_drawn_in_rain_as_dynamic_and_leave_the_holders_masks_boxes_and_keypoints_exact() {
    // Every frame of the first quickstart clip in heavy rain: the masks-in-boxes and keypoints-on-the-body checks of
    // the clear-weather test hold with umbrellas in the picture.
    let report = masks_match_boxes_and_keypoints(&["dataset.weathers=[heavy_rain]"]);
    assert!(
        report.umbrellas >= 1,
        "no pedestrian of the heavy-rain clip holds an umbrella"
    );
    assert!(
        report.dynamic_px >= 1000,
        "{} umbrellas but only {} pixels tagged Dynamic over the clip",
        report.umbrellas,
        report.dynamic_px
    );
    assert_eq!(
        report.dynamic_px_with_instance, 0,
        "umbrella pixels carry an instance id"
    );
    eprintln!(
        "{} umbrellas, {} Dynamic pixels over the clip; {} pedestrian-frames checked",
        report.umbrellas, report.dynamic_px, report.rows
    );
}

#[test]
fn only_rain_brings_umbrellas_and_never_to_children() {
    let umbrellas = |weather: &str| {
        let c = clip(&spec("quickstart.yaml"), &[&format!("dataset.weathers=[{weather}]")]);
        let with = c
            .script
            .pedestrians
            .iter()
            .filter(|p| p.identity.figure.umbrella.is_some())
            .count();
        let children = c.script.pedestrians.iter().filter_map(|p| p.child.as_ref());
        assert!(
            children.clone().all(|k| k.figure.umbrella.is_none()),
            "{weather}: a child holds an umbrella"
        );
        (with, c.script)
    };
    let (dry, _) = umbrellas("wet_noon");
    assert_eq!(dry, 0, "umbrellas in wet_noon (no precipitation)");
    let (wet, _) = umbrellas("heavy_rain");
    assert!(wet >= 1, "no umbrella in heavy rain");
    assert_eq!(umbrella_share(0.0), 0.0);
    assert!((umbrella_share(30.0) - 0.3).abs() < 1e-12 && (umbrella_share(80.0) - 0.6).abs() < 1e-12);
}
