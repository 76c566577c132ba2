//! Keys of the spec language whose feature this pedsynth version does not implement yet.
//!
//! They stay in the spec language (so that specs written for a later version, and the paper's set-up, read
//! without "unknown key"), but a value that would change what is generated is never silently ignored:
//! [`check`] reports `pedsynth::spec::not_implemented` at every such key whose value differs from the default.
//! A sensor's `enabled: false` is honoured (nothing is written), so it is not reported. A test walks every leaf
//! of the spec language and proves that each one changes the plan or the output, changes validation (the
//! limits), or is listed here.

use serde_json::Value as Json;

use super::diagnostic::{Problem, code};
use super::tree::{Node, parse_path};
use super::types::Spec;

/// A key (or a whole section) not implemented yet, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotYet {
    /// The key's path (`traffic.emergency`: every key under it).
    pub path: &'static str,
    /// What is missing, for the diagnostic.
    pub why: &'static str,
}

/// Every key not implemented yet.
pub const NOT_YET: &[NotYet] = &[];

/// Reports every not-yet key of `spec` whose value differs from the default; `tree` (the user's YAML)
/// locates it.
pub fn check(spec: &Spec, tree: &Node, problems: &mut Vec<Problem>) {
    let (Ok(actual), Ok(default)) = (serde_json::to_value(spec), serde_json::to_value(Spec::default())) else {
        return;
    };
    for entry in NOT_YET {
        let Ok(path) = parse_path(entry.path) else { continue };
        let mut a = &actual;
        let mut d = &default;
        for seg in &path {
            let super::tree::PathSeg::Key(k) = seg else { break };
            a = &a[k.as_str()];
            d = &d[k.as_str()];
        }
        let mut differing = Vec::new();
        differing_leaves(a, d, entry.path.to_owned(), &mut differing);
        for leaf in differing {
            let span = tree.span_at(&parse_path(&leaf).unwrap_or_default());
            problems.push(
                Problem::new(
                    code::NOT_IMPLEMENTED,
                    format!("`{leaf}` is not implemented yet: {}", entry.why),
                )
                .at(span, "no effect in this version")
                .help("remove the key (or keep its default) until a pedsynth version implements it"),
            );
        }
    }
}

/// The paths of the leaves under `path` where `actual` differs from `default`, except a sensor's
/// `enabled: false` (honoured: nothing is written).
fn differing_leaves(actual: &Json, default: &Json, path: String, out: &mut Vec<String>) {
    match (actual, default) {
        (Json::Object(a), Json::Object(d)) => {
            for (k, v) in a {
                differing_leaves(v, d.get(k).unwrap_or(&Json::Null), format!("{path}.{k}"), out);
            }
        }
        _ if actual == default => {}
        (Json::Bool(false), _) if path.ends_with(".enabled") => {}
        _ => out.push(path),
    }
}
