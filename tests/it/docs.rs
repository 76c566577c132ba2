//! Generated documentation stays in step with the code: README.md's table of diagnostic codes is
//! `error::codes_markdown()` (rewrite it with `INSTA_UPDATE=always cargo test`, the project's one update
//! switch), and every code string that appears in the source is registered in `error::CODES`.

use std::path::Path;

use pedsynth::error::{CODES, codes_markdown};

const START: &str = "<!-- diagnostic codes: generated from src/error.rs by `INSTA_UPDATE=always cargo test` -->\n";
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
