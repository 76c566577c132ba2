//! Golden tests of spec diagnostics: every bad spec in `tests/data/bad_specs/` is rejected with exit code 2,
//! its primary label sits at the line and column its `# expect:` header names, and the rendered report
//! (no colour, 100 columns) equals the golden file in `tests/golden/diagnostics/`.
//! Update the golden files with `INSTA_UPDATE=always cargo test` (then read the diff before committing).

use std::path::{Path, PathBuf};
use std::process::Command;

use pedsynth::spec::{self, LoadOptions, SpecErrors};

const WIDTH: usize = 100;

fn bad_specs() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad_specs");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    files
}

/// The relative path diagnostics are rendered with (no absolute paths in goldens).
fn display_name(path: &Path) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    path.strip_prefix(root).unwrap().to_string_lossy().into_owned()
}

/// `(code, line, column)` from the `# expect: CODE at L:C` header; an empty file expects `empty` at 1:1.
fn expectation(bytes: &[u8]) -> (String, usize, usize) {
    if bytes.is_empty() {
        return ("pedsynth::spec::empty".to_owned(), 1, 1);
    }
    let first = String::from_utf8_lossy(bytes.split(|b| *b == b'\n').next().unwrap()).into_owned();
    let rest = first
        .strip_prefix("# expect: ")
        .expect("bad spec needs an `# expect: CODE at L:C` header");
    let (code, at) = rest.split_once(" at ").unwrap();
    let (line, col) = at.trim().split_once(':').unwrap();
    (code.to_owned(), line.parse().unwrap(), col.parse().unwrap())
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().unwrap().chars().count() + 1;
    (line, col)
}

fn load(path: &Path, overrides: &[&str]) -> Result<spec::LoadedSpec, SpecErrors> {
    let bytes = std::fs::read(path).unwrap();
    let options = LoadOptions {
        overrides: overrides.iter().map(|s| s.to_string()).collect(),
        allow_large: false,
        profile: None,
    };
    // Relative names and directories (tests run in the crate root): no absolute path may reach a golden file.
    let name = display_name(path);
    let base_dir = Path::new(&name).parent().unwrap().to_path_buf();
    spec::load_bytes(&bytes, &name, &base_dir, &options)
}

#[test]
fn every_bad_spec_is_rejected_at_the_right_place() {
    let specs = bad_specs();
    assert!(specs.len() >= 16, "the corpus covers every diagnostic");
    for path in specs {
        let bytes = std::fs::read(&path).unwrap();
        let (code, line, col) = expectation(&bytes);
        let errors = load(&path, &[]).expect_err(&format!("{} must be rejected", path.display()));
        let text = String::from_utf8_lossy(&bytes);
        let found: Vec<(&str, usize, usize)> = errors
            .problems()
            .map(|p| {
                let (l, c) = p
                    .label
                    .as_ref()
                    .map_or((0, 0), |(span, _)| line_col(&text, span.offset));
                (p.code, l, c)
            })
            .collect();
        assert!(
            found.contains(&(code.as_str(), line, col)),
            "{}: expected {code} at {line}:{col}, found {found:?}",
            path.display()
        );
        insta::with_settings!({snapshot_path => "../golden/diagnostics", prepend_module_to_snapshot => false, omit_expression => true}, {
            insta::assert_snapshot!(path.file_stem().unwrap().to_string_lossy().into_owned(), errors.render_plain(WIDTH));
        });
    }
}

#[test]
fn overrides_are_validated_and_named_as_the_culprit() {
    let quickstart = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let errors = load(
        &quickstart,
        &[
            "crossing.target_ratio=2",
            "dataset.fps=thirty",
            "dataset.weathers[0]=clear_nooon",
            "no_equals_sign",
        ],
    )
    .unwrap_err();
    let rendered = errors.render_plain(WIDTH);
    assert_eq!(errors.codes().len(), 4, "{rendered}");
    assert!(rendered.contains("[--set #1:1:23]"), "{rendered}");
    insta::with_settings!({snapshot_path => "../golden/diagnostics", prepend_module_to_snapshot => false, omit_expression => true}, {
        insta::assert_snapshot!("overrides", rendered);
    });
    // A good override changes the value.
    let loaded = load(
        &quickstart,
        &["crossing.target_ratio=0.5", "dataset.weathers=[dawn, night_foggy]"],
    )
    .unwrap();
    assert_eq!(loaded.spec.crossing.target_ratio, 0.5);
    assert_eq!(loaded.spec.dataset.weathers.resolved().len(), 2);
}

#[test]
fn the_cli_exits_2_on_bad_specs_and_0_on_good_ones() {
    let bin = env!("CARGO_BIN_EXE_pedsynth");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for path in bad_specs() {
        let out = Command::new(bin)
            .current_dir(root)
            .arg("validate")
            .arg(display_name(&path))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{}", path.display());
        let stderr = String::from_utf8_lossy(&out.stderr);
        let (code, _, _) = expectation(&std::fs::read(&path).unwrap());
        assert!(
            stderr.contains(&code),
            "{}: stderr lacks {code}:\n{stderr}",
            path.display()
        );
        assert!(out.stdout.is_empty());
    }
    let mut good: Vec<PathBuf> = std::fs::read_dir(root.join("specs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    good.sort();
    let out = Command::new(bin)
        .current_dir(root)
        .arg("validate")
        .args(&good)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), good.len());
    let missing = Command::new(bin)
        .current_dir(root)
        .args(["validate", "specs/no_such_spec.yaml"])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    let bad_args = Command::new(bin).args(["validate", "--no-such-flag"]).output().unwrap();
    assert_eq!(bad_args.status.code(), Some(2));
}
