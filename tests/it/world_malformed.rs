//! Malformed or hostile .xodr input gives errors with the file and a line number, never a panic; a small
//! valid file exercises every geometry type, lane sections, lane offsets and crosswalk objects.

use pedsynth::world::{LaneType, RoadNetwork, WorldError};
use proptest::prelude::*;

fn dir() -> std::path::PathBuf {
    std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/xodr_malformed"))
}

/// (file, expected diagnostic code, expected 1-based line).
const CORPUS: &[(&str, &str, u32)] = &[
    ("empty.xodr", "xodr_syntax", 1),
    ("truncated.xodr", "xodr_syntax", 34),
    ("wrong_root.xodr", "xodr_invalid", 2),
    ("no_roads.xodr", "xodr_invalid", 2),
    ("mismatched_tags.xodr", "xodr_syntax", 5),
    ("missing_geometry.xodr", "xodr_invalid", 4),
    ("geometry_without_shape.xodr", "xodr_invalid", 5),
    ("unknown_shape.xodr", "xodr_invalid", 5),
    ("missing_x.xodr", "xodr_invalid", 5),
    ("nan_coordinate.xodr", "xodr_invalid", 5),
    ("inf_coordinate.xodr", "xodr_invalid", 5),
    ("nan_width.xodr", "xodr_invalid", 10),
    ("absurd_width.xodr", "xodr_invalid", 10),
    ("width_grows_absurd.xodr", "xodr_invalid", 10),
    ("negative_length.xodr", "xodr_invalid", 5),
    ("absurd_road_length.xodr", "xodr_invalid", 3),
    ("absurd_curvature.xodr", "xodr_invalid", 5),
    ("param_poly3_longer_than_its_length.xodr", "xodr_invalid", 5),
    ("bad_lane_id.xodr", "xodr_invalid", 10),
    ("zero_width_only.xodr", "xodr_invalid", 3),
    ("non_numeric_length.xodr", "xodr_invalid", 5),
    ("not_utf8.xodr", "xodr_syntax", 1),
    ("doctype_entity.xodr", "xodr_syntax", 2),
];

fn code_and_line(e: &WorldError) -> (String, u32) {
    let code = miette::Diagnostic::code(e).map(|c| c.to_string()).unwrap_or_default();
    let line = match e {
        WorldError::XodrSyntax { line, .. }
        | WorldError::XodrInvalid { line, .. }
        | WorldError::XodrTooLarge { line, .. } => *line,
        _ => 0,
    };
    (code, line)
}

#[test]
fn every_corpus_file_is_listed() {
    let mut on_disk: Vec<String> = std::fs::read_dir(dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = CORPUS.iter().map(|c| c.0.to_string()).collect();
    listed.sort();
    assert_eq!(on_disk, listed);
}

#[test]
fn malformed_files_give_located_errors() {
    for &(file, code, line) in CORPUS {
        let path = dir().join(file);
        let err = match RoadNetwork::from_xodr_file(&path) {
            Ok(_) => panic!("{file}: loaded without error"),
            Err(e) => e,
        };
        let (c, l) = code_and_line(&err);
        let msg = err.to_string();
        assert_eq!(c, format!("pedsynth::world::{code}"), "{file}: {msg}");
        assert_eq!(l, line, "{file}: {msg}");
        assert!(
            msg.contains(file) && msg.contains(&format!(":{line}:")),
            "{file}: {msg}"
        );
    }
}

#[test]
fn missing_file_is_an_io_error() {
    let e = RoadNetwork::from_xodr_file(&dir().join("does_not_exist.xodr"))
        .err()
        .unwrap();
    assert!(matches!(e, WorldError::Io { .. }), "{e}");
}

#[test]
fn valid_file_with_every_geometry_type() {
    let path = std::path::PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/valid_all_geometries.xodr"
    ));
    let net = RoadNetwork::from_xodr_file(&path).unwrap();
    assert_eq!(net.roads.len(), 1);
    assert_eq!(net.junctions.len(), 1);
    assert_eq!(net.crosswalks.len(), 1);
    assert!(!net.crosswalks[0].synthesized);
    // Lanes: 4 in the first section, 5 in the second.
    assert_eq!(net.lanes.len(), 9);
    let parking = net.lanes.iter().find(|l| l.lane_type == LaneType::Parking).unwrap();
    assert_eq!(parking.section, 1);
    let left = net.lanes.iter().find(|l| l.lane_id == 1 && l.section == 0).unwrap();
    assert!((left.speed_limit_mps - 30.0 * 0.44704).abs() < 1e-9);
    let right = net.lanes.iter().find(|l| l.lane_id == -1 && l.section == 0).unwrap();
    assert!((right.speed_limit_mps - 50.0 / 3.6).abs() < 1e-9);
    // The reference line is continuous across geometry records (the file's x/y were computed for that).
    let c = net.lane_centre_line(
        net.lanes
            .iter()
            .position(|l| l.lane_id == -1 && l.section == 0)
            .unwrap() as u32,
    );
    for w in c.windows(2) {
        assert!((w[1] - w[0]).length() < 2.5, "gap {:?}", w);
    }
    // The lane offset shifts the centre line: at s=1 the right driving lane centre is at t = 0.2 - 1.75.
    let hit = net.lane_at(glam::DVec2::new(1.0, 0.2 - 1.75)).unwrap();
    assert_eq!(hit.lane_id, -1);
    assert!(hit.lateral_offset_m.abs() < 1e-6, "{hit:?}");
    assert!(hit.z_m > 0.0);
}

fn small_valid() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/valid_all_geometries.xodr"
    ))
    .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn mutated_documents_never_panic(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..8), cut in any::<usize>()) {
        let mut bytes = small_valid().into_bytes();
        for (pos, b) in edits {
            let i = pos % bytes.len();
            bytes[i] = b;
        }
        let keep = bytes.len() - cut % (bytes.len() / 4);
        bytes.truncate(keep);
        let text = String::from_utf8_lossy(&bytes);
        let _ = RoadNetwork::from_xodr_str(&text, "mutated.xodr");
    }

    #[test]
    fn numbers_in_attributes_never_panic(x in any::<f64>(), len in any::<f64>(), w in any::<f64>(), k in any::<f64>()) {
        let doc = small_valid()
            .replacen("x=\"0\"", &format!("x=\"{x}\""), 1)
            .replacen("length=\"20\"", &format!("length=\"{len}\""), 1)
            .replacen("a=\"3.5\"", &format!("a=\"{w}\""), 1)
            .replacen("curvEnd=\"0.02\"", &format!("curvEnd=\"{k}\""), 1);
        let _ = RoadNetwork::from_xodr_str(&doc, "numbers.xodr");
    }

    #[test]
    fn arbitrary_text_never_panics(s in "\\PC{0,200}") {
        let _ = RoadNetwork::from_xodr_str(&s, "arbitrary.xodr");
        let wrapped = format!("<OpenDRIVE><road id=\"1\"><planView>{s}</planView></road></OpenDRIVE>");
        let _ = RoadNetwork::from_xodr_str(&wrapped, "arbitrary.xodr");
    }
}
