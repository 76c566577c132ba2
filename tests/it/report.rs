//! `pedsynth report` (issue 45): one HTML page that loads nothing from elsewhere, with every plot's title, an
//! inline SVG per plot and a labelled sample per weather; a second dataset beside the first; the same bytes
//! on a re-run; bad input refused with exit code 2. (CI renders the page in headless Chromium:
//! tests/report_browser.py.)

use crate::common;

use std::path::Path;

use pedsynth::dataset::report::{SAMPLES_TITLE, TITLES};

fn report(args: &[&Path]) -> (Option<i32>, String, String) {
    let mut argv: Vec<&std::ffi::OsStr> = vec!["report".as_ref(), args[0].as_os_str()];
    if args.len() == 3 {
        argv.extend(["--compare".as_ref(), args[2].as_os_str()]);
    }
    argv.extend(["--out".as_ref(), args[1].as_os_str()]);
    common::pedsynth(&argv)
}

#[test]
fn a_report_is_one_offline_page_with_every_plot_and_a_sample_per_weather() {
    let tmp = common::Scratch::new("report");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let small_rgb = [
        "sensors.rgb.width_px=320",
        "sensors.rgb.height_px=180",
        "sensors.depth.enabled=false",
        "sensors.semantic.enabled=false",
        "sensors.instance.enabled=false",
        "sensors.dvs.enabled=false",
        "sensors.lidar.enabled=false",
        "dataset.clip_duration_s=[4, 4]",
    ];
    let (code, _, stderr) = common::generate(&spec, &small_rgb, &a, None);
    assert_eq!(code, 0, "{stderr}");
    let mut other = common::NO_SENSORS.to_vec();
    other.extend(["dataset.seed=8", "crossing.target_ratio=0.8"]);
    let (code, _, stderr) = common::generate(&spec, &other, &b, None);
    assert_eq!(code, 0, "{stderr}");

    let out = tmp.path().join("report.html");
    let (code, stdout, stderr) = report(&[&a, &out, &b]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout.contains("report of quickstart against quickstart (compared)"),
        "{stdout}"
    );
    let html = std::fs::read_to_string(&out).expect("report");
    let doc = roxmltree::Document::parse_with_options(
        &html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..roxmltree::ParsingOptions::default()
        },
    )
    .expect("the page is well-formed XML (XHTML syntax)");
    let headings: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("h2"))
        .map(|n| n.text().unwrap_or_default().to_owned())
        .collect();
    let mut want: Vec<String> = TITLES.iter().map(|t| (*t).to_owned()).collect();
    want.push(SAMPLES_TITLE.to_owned());
    assert_eq!(headings, want);
    let svgs: Vec<_> = doc.descendants().filter(|n| n.tag_name().name() == "svg").collect();
    assert_eq!(svgs.len(), TITLES.len());
    // Each plot shows both datasets (a legend entry per series), and the crossing-ratio plot the targets.
    for svg in &svgs {
        let text: String = svg.descendants().filter_map(|n| n.text()).collect();
        assert!(text.contains("quickstart (compared)"), "{text}");
    }
    // The datasets' targets differ (0.6 and 0.8): one target series each.
    assert!(html.contains("quickstart target") && html.contains("quickstart (compared) target"));
    // One labelled sample per weather of the dataset with RGB (a PNG data URI that decodes), none for the other.
    let images: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("img")).collect();
    assert_eq!(images.len(), 1);
    let src = images[0].attribute("src").expect("src");
    let png = src.strip_prefix("data:image/png;base64,").expect("a PNG data URI");
    use base64::Engine as _;
    let bytes = base64::engine::general_purpose::STANDARD.decode(png).expect("base64");
    assert!(bytes.starts_with(b"\x89PNG"));
    assert!(html.contains("(no PNG RGB frames)"));
    // Nothing from elsewhere: no script, no link, no URL but the SVG namespace.
    assert!(!html.contains("<script") && !html.contains("<link"));
    assert_eq!(
        html.matches("http").count(),
        html.matches("http://www.w3.org/2000/svg").count()
    );
    // The same bytes again; no path of the machine in them.
    let again = tmp.path().join("again.html");
    let (code, _, stderr) = report(&[&a, &again, &b]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(std::fs::read(&again).expect("again") == html.as_bytes());
    assert!(!html.contains(tmp.path().to_str().expect("utf-8")));

    // Bad input: a second "dataset" that is not one, an unfinished dataset.
    let (code, _, stderr) = report(&[&a, &tmp.path().join("x.html"), &tmp.path().join("nowhere")]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not a pedsynth dataset"), "{stderr}");
    let manifest = b.join("manifest.json");
    let text = std::fs::read_to_string(&manifest).expect("manifest");
    std::fs::write(
        &manifest,
        text.replacen("\"status\": \"done\"", "\"status\": \"pending\"", 1),
    )
    .expect("write");
    let (code, _, stderr) = report(&[&b, &tmp.path().join("y.html")]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("not generated yet"), "{stderr}");
    assert!(!tmp.path().join("y.html").exists());
}

/// `--compare` with real annotations (JAAD's train split, ../shared/real): the real data's boxes, crossing
/// ratio, time in view before crossing and benchmark windows beside the dataset's, the simulation-only plots
/// marked absent for it, and the crossing ratio in the table the one `calibrate`'s reader gives.
#[test]
#[ignore = "reads JAAD's annotations in ../shared/real"]
fn a_report_compares_a_dataset_with_real_annotations() {
    let tmp = common::Scratch::new("report-real");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let ds = tmp.path().join("ds");
    let (code, _, stderr) = common::generate(&spec, &common::NO_SENSORS, &ds, None);
    assert_eq!(code, 0, "{stderr}");
    let real = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/real/jaad_trainval");
    let out = tmp.path().join("report.html");
    let (code, stdout, stderr) = common::pedsynth(&[
        "report".as_ref(),
        ds.as_os_str(),
        "--compare".as_ref(),
        real.as_os_str(),
        "--real-splits".as_ref(),
        "train".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("against real: jaad_trainval"), "{stdout}");
    let html = std::fs::read_to_string(&out).expect("report");
    // Every plot has the real series in its legend; four plots say the real data do not have them.
    let legends = html.matches("real: jaad_trainval</text>").count()
        + html.matches("real: jaad_trainval achieved</text>").count();
    assert_eq!(legends, TITLES.len(), "a legend entry per plot");
    assert_eq!(html.matches("real: jaad_trainval: not in real annotations").count(), 4);
    // The table's achieved crossing ratio of the real data is calibrate's reader's crossers / tracks.
    let videos = pedsynth::dataset::calibrate::read_real(
        &real,
        pedsynth::dataset::calibrate::Format::Table,
        &["train".to_owned()],
    )
    .expect("reads");
    let tracks: Vec<_> = videos.iter().flat_map(|v| &v.tracks).collect();
    let crossers = tracks.iter().filter(|t| t.crosser).count();
    let want = format!("<td>{:.3}</td></tr>", crossers as f64 / tracks.len() as f64);
    let row = html
        .lines()
        .find(|l| l.starts_with("<tr><th>crossing ratio (achieved)"))
        .expect("the row");
    assert!(row.ends_with(&want), "{row} vs {want}");
    assert!(!html.contains(tmp.path().to_str().expect("utf-8")));
}
