//! The house rules of ARCHITECTURE.md that a machine can check, read from the source itself:
//!
//! - the rooms of `src/` form layers along the pipeline (`util`, `error` → `spec` → `world` → `plan` → `sim` →
//!   `sensors` → `dataset` → `cli`), and no file names a room of a later layer;
//! - the files' import graph has no circle (an arrow is a `use` or a path through `crate::`, `super::` or a child
//!   module; a file naming the module file of a folder it sits in is not an arrow, that is a child using its
//!   parent);
//! - no source file is over 800 lines, and every one opens with a `//!` comment;
//! - the planner and the sensors do no IO and start no threads; `src/main.rs` only parses and calls `cli`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, bottom first; a room may use its own layer and the ones before it.
const LAYERS: &[&[&str]] = &[
    &["util", "error"],
    &["spec"],
    &["world"],
    &["plan"],
    &["sim"],
    &["sensors"],
    &["dataset"],
    &["cli", "fuzz"],
];

const MAX_LINES: usize = 800;

/// A source file: its module path (`["sim", "pedestrian", "machine"]`; `[]` for lib.rs) and its text without
/// comments.
struct Source {
    file: String,
    module: Vec<String>,
    code: String,
    text: String,
}

fn sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&root, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|path| {
            let rel = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
            let mut module: Vec<String> = rel.trim_end_matches(".rs").split('/').map(str::to_owned).collect();
            if module.last().is_some_and(|m| m == "mod" || m == "lib") {
                module.pop();
            }
            let text = std::fs::read_to_string(&path).unwrap();
            Source {
                code: strip_comments(&text),
                file: rel,
                module,
                text,
            }
        })
        .collect()
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            walk(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The text without `//` comments (line and doc comments; string literals holding `//` keep their text up to
/// it, which drops no path this test looks for).
fn strip_comments(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn layer_of(room: &str) -> Option<usize> {
    LAYERS.iter().position(|rooms| rooms.contains(&room))
}

/// Every path starting with `crate::`, `super::`, `self::` or a child module the file declares, with `use`
/// groups (`a::{b, c::d}`) expanded, as absolute module paths.
fn references(src: &Source) -> Vec<Vec<String>> {
    let children: BTreeSet<String> = src
        .code
        .lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l
                .strip_prefix("pub(crate) ")
                .or_else(|| l.strip_prefix("pub "))
                .unwrap_or(l);
            let name = l.strip_prefix("mod ")?.strip_suffix(';')?;
            Some(name.trim().to_owned())
        })
        .collect();
    let mut paths: Vec<(String, bool)> = Vec::new();
    // `use` declarations, expanded; `indented` marks a `use` inside an inline module (`mod tests`), whose
    // first `super` is the file's own module.
    let mut rest = src.code.as_str();
    while let Some(i) = find_use(rest) {
        let indented = rest[..i].rsplit('\n').next().is_some_and(|l| l.starts_with(' '));
        let body_start = i + rest[i..].find("use ").unwrap() + 4;
        let end = body_start + rest[body_start..].find(';').unwrap_or(rest.len() - body_start);
        // `a::b as c` names `a::b`: drop each rename (keeping the group's punctuation after it), then the
        // whitespace.
        let words: Vec<&str> = rest[body_start..end].split_whitespace().collect();
        let mut body = String::new();
        let mut k = 0;
        while k < words.len() {
            if words[k] == "as" {
                let after = words.get(k + 1).copied().unwrap_or("");
                body.push_str(after.trim_start_matches(|c: char| c.is_alphanumeric() || c == '_'));
                k += 2;
            } else {
                body.push_str(words[k]);
                k += 1;
            }
        }
        for p in expand(&body) {
            paths.push((p, indented));
        }
        rest = &rest[end..];
    }
    // Paths in code.
    let bytes = src.code.as_bytes();
    for start in ["crate::", "super::"].iter().flat_map(|s| match_indices(&src.code, s)) {
        if start > 0
            && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_' || bytes[start - 1] == b':')
        {
            continue;
        }
        let end = src.code[start..]
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
            .map_or(src.code.len(), |e| start + e);
        paths.push((src.code[start..end].trim_end_matches(':').to_owned(), false));
    }
    for child in &children {
        let needle = format!("{child}::");
        for start in match_indices(&src.code, &needle) {
            if start > 0
                && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_' || bytes[start - 1] == b':')
            {
                continue;
            }
            paths.push((format!("self::{child}"), false));
        }
    }
    paths
        .into_iter()
        .filter_map(|(p, indented)| {
            let segs: Vec<&str> = p.split("::").filter(|s| !s.is_empty()).collect();
            let mut module = src.module.clone();
            let mut k = 0;
            match *segs.first()? {
                "crate" => {
                    module.clear();
                    k = 1;
                }
                "super" | "self" => {
                    let mut first = indented;
                    while k < segs.len() && (segs[k] == "super" || segs[k] == "self") {
                        if segs[k] == "super" && !std::mem::take(&mut first) {
                            module.pop();
                        }
                        k += 1;
                    }
                }
                s if children.contains(s) => {}
                _ => return None,
            }
            module.extend(segs[k..].iter().map(|s| s.to_string()));
            Some(module)
        })
        .collect()
}

fn match_indices(text: &str, needle: &str) -> Vec<usize> {
    text.match_indices(needle).map(|(i, _)| i).collect()
}

/// The start of the next `use` declaration (at a line's start, after optional visibility).
fn find_use(text: &str) -> Option<usize> {
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let t = line.trim_start();
        let t = t
            .strip_prefix("pub(crate) ")
            .or_else(|| t.strip_prefix("pub(super) "))
            .or_else(|| t.strip_prefix("pub "))
            .unwrap_or(t);
        if t.starts_with("use ") {
            return Some(offset + line.find("use ").unwrap());
        }
        offset += line.len();
    }
    None
}

/// `a::{b, c::{d, e}}` → `a::b`, `a::c::d`, `a::c::e` (whitespace and `as` renames already removed).
fn expand(tree: &str) -> Vec<String> {
    let Some(open) = tree.find('{') else {
        return vec![tree.to_owned()];
    };
    let close = tree.rfind('}').unwrap_or(tree.len());
    let (prefix, inner) = (&tree[..open], &tree[open + 1..close]);
    let mut parts = Vec::new();
    let (mut depth, mut current) = (0, String::new());
    for c in inner.chars() {
        match c {
            ',' if depth == 0 => parts.push(std::mem::take(&mut current)),
            '{' => {
                depth += 1;
                current.push(c);
            }
            '}' => {
                depth -= 1;
                current.push(c);
            }
            _ => current.push(c),
        }
    }
    parts.push(current);
    parts
        .iter()
        .filter(|p| !p.is_empty())
        .flat_map(|p| expand(p))
        .map(|p| {
            if p == "self" {
                prefix.trim_end_matches("::").to_owned()
            } else {
                format!("{prefix}{p}")
            }
        })
        .collect()
}

/// The import graph: file → files it names (the longest module prefix of each path that is a file).
fn graph(sources: &[Source]) -> BTreeMap<usize, BTreeSet<usize>> {
    let by_module: BTreeMap<&[String], usize> = sources
        .iter()
        .enumerate()
        .map(|(i, s)| (s.module.as_slice(), i))
        .collect();
    let mut edges: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    for (i, src) in sources.iter().enumerate() {
        for path in references(src) {
            let target = (1..=path.len()).rev().find_map(|n| by_module.get(&path[..n]).copied());
            let Some(t) = target else { continue };
            let is_ancestor = sources[t].module.len() < src.module.len() && src.module.starts_with(&sources[t].module);
            if t != i && !is_ancestor && src.file != "main.rs" {
                edges.entry(i).or_default().insert(t);
            }
        }
    }
    edges
}

#[test]
fn no_file_names_a_room_of_a_later_layer() {
    let mut back = Vec::new();
    let sources = sources();
    for src in &sources {
        let Some(room) = src.module.first() else { continue };
        if src.file == "main.rs" {
            continue;
        }
        let own = layer_of(room).unwrap_or_else(|| panic!("{}: room `{room}` is in no layer of LAYERS", src.file));
        for path in references(src) {
            if let Some(other) = path.first().and_then(|r| layer_of(r))
                && other > own
            {
                back.push(format!("{} -> {}", src.file, path.join("::")));
            }
        }
    }
    back.sort();
    back.dedup();
    assert!(back.is_empty(), "imports from a later stage:\n{}", back.join("\n"));
    // The check sees what it must: the files reach every layer, and a later room is found when named.
    assert!(
        sources
            .iter()
            .filter(|s| s.module.first().is_some_and(|r| r == "cli"))
            .count()
            > 1
    );
    let probe = Source {
        file: "sim/probe.rs".into(),
        module: vec!["sim".into(), "probe".into()],
        code: "use crate::dataset::write::Layout as L;\nfn f() { crate::sensors::observe(); }".into(),
        text: String::new(),
    };
    let named: BTreeSet<String> = references(&probe).iter().map(|p| p[0].clone()).collect();
    assert_eq!(named, BTreeSet::from(["dataset".to_owned(), "sensors".to_owned()]));
}

#[test]
fn the_import_graph_has_no_circle() {
    let sources = sources();
    let edges = graph(&sources);
    assert!(
        edges.values().map(BTreeSet::len).sum::<usize>() > 300,
        "the graph reads the imports"
    );
    // Depth-first search for a back edge; the circle is reported by its files.
    fn visit(
        v: usize,
        edges: &BTreeMap<usize, BTreeSet<usize>>,
        state: &mut Vec<u8>,
        stack: &mut Vec<usize>,
    ) -> Option<Vec<usize>> {
        state[v] = 1;
        stack.push(v);
        for &w in edges.get(&v).into_iter().flatten() {
            if state[w] == 1 {
                let at = stack.iter().position(|&x| x == w).unwrap();
                return Some(stack[at..].to_vec());
            }
            if state[w] == 0
                && let Some(c) = visit(w, edges, state, stack)
            {
                return Some(c);
            }
        }
        stack.pop();
        state[v] = 2;
        None
    }
    let mut state = vec![0u8; sources.len()];
    for v in 0..sources.len() {
        if state[v] == 0
            && let Some(circle) = visit(v, &edges, &mut state, &mut Vec::new())
        {
            let names: Vec<&str> = circle.iter().map(|&i| sources[i].file.as_str()).collect();
            panic!("a circle of imports: {} -> {}", names.join(" -> "), names[0]);
        }
    }
}

#[test]
fn source_files_are_small_and_say_what_they_are() {
    let mut problems = Vec::new();
    for src in sources() {
        let lines = src.text.lines().count();
        if lines > MAX_LINES {
            problems.push(format!(
                "{}: {lines} lines (at most {MAX_LINES}: split it by job)",
                src.file
            ));
        }
        if !src.text.starts_with("//!") {
            problems.push(format!("{}: does not open with a `//!` comment", src.file));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_planner_and_the_sensors_do_no_io_and_the_planner_starts_no_threads() {
    let io = ["std::fs", "File::", "std::env", "std::net", "Instant::", "SystemTime"];
    let threads = ["std::thread", "rayon"];
    let mut found = Vec::new();
    let mut checked = 0;
    for src in sources() {
        let room = src.module.first().map_or("", String::as_str);
        let words: Vec<&str> = match room {
            "plan" => io.iter().chain(&threads).copied().collect(),
            // A frame's bands and a clip's streams share the rayon pool (ARCHITECTURE.md): no IO, though.
            "sensors" => io.to_vec(),
            _ => continue,
        };
        checked += 1;
        found.extend(
            words
                .iter()
                .filter(|w| src.code.contains(*w))
                .map(|w| format!("{}: {w}", src.file)),
        );
    }
    assert!(checked > 20, "{checked} files checked");
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn main_only_parses_arguments_and_calls_the_cli() {
    let main = sources().into_iter().find(|s| s.file == "main.rs").unwrap();
    for word in [
        "std::fs",
        "pedsynth::world",
        "pedsynth::sim",
        "pedsynth::sensors",
        "pedsynth::plan::",
        "rayon",
        "pedsynth::dataset::generate",
    ] {
        assert!(
            !main.code.contains(word),
            "main.rs uses {word}: move the work into the library"
        );
    }
}

#[test]
fn the_crate_forbids_unsafe_code_and_keeps_crate_items_pub_crate() {
    let sources = sources();
    let text = |file: &str| {
        sources
            .iter()
            .find(|s| s.file == file)
            .map(|s| s.text.as_str())
            .unwrap_or("")
    };
    for file in ["lib.rs", "main.rs"] {
        assert!(
            text(file).contains("#![forbid(unsafe_code)]"),
            "{file}: no #![forbid(unsafe_code)]"
        );
    }
    // With clippy's -D warnings in CI, a `pub` item the crate root cannot reach fails the build.
    assert!(text("lib.rs").contains("#![warn(unreachable_pub)]"));
}

#[test]
fn random_streams_are_seeded_chacha_and_the_plan_and_simulation_use_chacha20() {
    let mut found = Vec::new();
    let mut chacha20 = 0;
    for src in sources() {
        for word in [
            "thread_rng",
            "rand::rng()",
            "from_entropy",
            "from_os_rng",
            "OsRng",
            "StdRng",
            "SmallRng",
        ] {
            if src.code.contains(word) {
                found.push(format!("{}: {word}", src.file));
            }
        }
        if src.module.first().is_some_and(|r| r == "plan" || r == "sim") {
            chacha20 += src.code.matches("ChaCha20Rng").count();
            for word in ["ChaCha8Rng", "ChaCha12Rng"] {
                if src.code.contains(word) {
                    found.push(format!(
                        "{}: {word} (the plan's and the simulation's streams are ChaCha20)",
                        src.file
                    ));
                }
            }
        }
    }
    assert!(chacha20 > 5, "{chacha20} uses of ChaCha20Rng in plan/ and sim/");
    assert!(found.is_empty(), "{}", found.join("\n"));
}
