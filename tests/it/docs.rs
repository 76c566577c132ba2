//! Generated documentation stays in step with the code: README.md's table of diagnostic codes is
//! `error::codes_markdown()` (src/error/codes.rs) (rewrite it with `INSTA_UPDATE=always cargo test`, the project's one update
//! switch), and every code string that appears in the source is registered in `error::CODES`.

use std::path::Path;

use crate::common;
use pedsynth::error::{CODES, codes_markdown};

const START: &str =
    "<!-- diagnostic codes: generated from src/error/codes.rs by `INSTA_UPDATE=always cargo test` -->\n";
const END: &str = "<!-- end of diagnostic codes -->";

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn the_readme_table_of_codes_is_generated_from_the_registry() {
    let path = root().join("README.md");
    let readme = std::fs::read_to_string(&path).expect("README.md");
    let (Some(start), Some(end)) = (readme.find(START), readme.find(END)) else {
        panic!("README.md needs the markers {START:?} and {END:?} around the table of codes");
    };
    let current = &readme[start + START.len()..end];
    let table = codes_markdown();
    if current != table && std::env::var("INSTA_UPDATE").as_deref() == Ok("always") {
        let updated = format!("{}{START}{table}{}", &readme[..start], &readme[end..]);
        std::fs::write(&path, updated).expect("write README.md");
        return;
    }
    assert_eq!(
        current, table,
        "README.md's table of codes is stale: run `INSTA_UPDATE=always cargo test --test docs`"
    );
}

/// Every `pedsynth::<area>::<what>` string literal in `src/` names a registered code.
#[test]
fn every_code_in_the_source_is_registered() {
    let mut found = Vec::new();
    let mut stack = vec![root().join("src")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("src") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).expect("source");
                for (i, _) in text.match_indices("\"pedsynth::") {
                    let rest = &text[i + 1..];
                    let code: String = rest
                        .chars()
                        .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_' || *c == ':')
                        .collect();
                    if code.matches("::").count() == 2 && !code.ends_with(':') {
                        found.push((code, path.display().to_string()));
                    }
                }
            }
        }
    }
    assert!(found.len() >= 30, "the scan finds the codes: {found:?}");
    let unregistered: Vec<_> = found
        .iter()
        .filter(|(code, _)| !CODES.iter().any(|c| c.code == code))
        .collect();
    assert!(
        unregistered.is_empty(),
        "codes used but not registered in error::CODES: {unregistered:?}"
    );
}

/// The text of DATASET.md's section whose heading starts with `heading` (up to the next heading of any level).
fn dataset_md_section<'a>(doc: &'a str, heading: &str) -> &'a str {
    let start = doc
        .find(heading)
        .unwrap_or_else(|| panic!("DATASET.md has no section `{heading}`"));
    let body = &doc[start + heading.len()..];
    let end = body.find("\n#").map_or(body.len(), |e| e + 1);
    &body[..end]
}

#[test]
fn dataset_md_documents_every_arrow_field_the_writer_declares() {
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("DATASET.md")).unwrap();
    let scratch = common::Scratch::new("dataset-md");
    let out = scratch.path().join("quickstart");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("specs/quickstart.yaml");
    let mut overrides = common::NO_SENSORS.to_vec();
    overrides.extend(["traffic.signals.enabled=true", "traffic.cyclists.per_clip=[1, 2]"]);
    let (code, _, stderr) = common::generate(&spec, &overrides, &out, None);
    assert_eq!(code, 0, "{stderr}");
    // Every table as written: (where DATASET.md documents it, its schema).
    let mut schemas = Vec::new();
    for table in pedsynth::dataset::write::tables::TABLES {
        let dir = out.join("tables").join(table);
        let file = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .next()
            .expect("a file per clip")
            .unwrap()
            .path();
        let reader = ParquetRecordBatchReaderBuilder::try_new(std::fs::File::open(&file).unwrap()).unwrap();
        schemas.push((format!("### `{table}`"), reader.schema().clone()));
    }
    // The sensor streams' Parquet files, from the writer's own (empty) batches.
    use pedsynth::dataset::write::{lidar, sensors};
    schemas.push(("### LiDAR".to_owned(), lidar::lidar_batch("", 0, 0, &[]).schema()));
    schemas.push(("| `dvs` |".to_owned(), sensors::dvs_batch(0, &[]).schema()));
    schemas.push(("### `sensors`".to_owned(), sensors::index_batch("", &[]).schema()));
    let mut missing = Vec::new();
    let mut fields = 0;
    for (heading, schema) in &schemas {
        let section = dataset_md_section(&doc, heading);
        for field in schema.fields() {
            fields += 1;
            if !section.contains(&format!("`{}`", field.name())) {
                missing.push(format!("{heading}: `{}`", field.name()));
            }
        }
    }
    assert!(
        schemas.len() == 15 && fields > 200,
        "{} schemas, {fields} fields",
        schemas.len()
    );
    assert!(
        missing.is_empty(),
        "DATASET.md does not document:\n{}",
        missing.join("\n")
    );
}
