//! Structural check of a spec tree against the spec's JSON Schema: unknown keys (with "did you mean"), wrong
//! types and unknown enum names, every one reported with its span. Runs before typed deserialisation so that
//! all structural problems are found in one pass.

use serde_json::Value as Json;

use super::diagnostic::{Problem, code, suggestion};
use super::tree::{Node, PathSeg, Value};

/// Keys an earlier version of the spec language had at another place: (old path, new path).
pub const MOVED: &[(&str, &str)] = &[("output.lidar_encoding", "sensors.lidar.format")];

/// A structural problem and the path of the offending node (`None` when nothing should be pruned).
pub type Found = (Option<Vec<PathSeg>>, Problem);

/// Checks `node` against the root `schema`. Returns each problem with the path of the offending node, so
/// the loader can prune it and still validate the rest of the spec.
pub fn check(node: &Node, schema: &Json) -> Vec<Found> {
    let checker = Checker { root: schema };
    let mut path = Vec::new();
    let mut found = Vec::new();
    checker.check(node, schema, &mut path, &mut found);
    found
}

struct Checker<'s> {
    root: &'s Json,
}

impl<'s> Checker<'s> {
    /// Follows `$ref` and single-element `allOf` wrappers.
    fn resolve(&self, mut schema: &'s Json) -> &'s Json {
        for _ in 0..32 {
            if let Some(r) = schema.get("$ref").and_then(Json::as_str) {
                let name = r.trim_start_matches("#/definitions/");
                match self.root.get("definitions").and_then(|d| d.get(name)) {
                    Some(s) => schema = s,
                    None => return schema,
                }
            } else if let Some(all) = schema.get("allOf").and_then(Json::as_array)
                && all.len() == 1
            {
                schema = &all[0];
            } else {
                return schema;
            }
        }
        schema
    }

    fn check(&self, node: &Node, schema: &'s Json, path: &mut Vec<PathSeg>, problems: &mut Vec<Found>) {
        let schema = self.resolve(schema);
        if let Some(alternatives) = schema
            .get("anyOf")
            .or_else(|| schema.get("oneOf"))
            .and_then(Json::as_array)
        {
            self.check_alternatives(node, alternatives, path, problems);
            return;
        }
        if let Some(constant) = schema.get("const") {
            self.check_names(node, std::slice::from_ref(constant), path, problems);
            return;
        }
        if let Some(names) = schema.get("enum").and_then(Json::as_array) {
            self.check_names(node, names, path, problems);
            return;
        }
        let Some(types) = schema.get("type") else {
            return;
        };
        let types: Vec<&str> = match types {
            Json::String(t) => vec![t.as_str()],
            Json::Array(ts) => ts.iter().filter_map(Json::as_str).collect(),
            _ => return,
        };
        if !types.iter().any(|t| type_matches(t, &node.value)) {
            problems.push((Some(path.clone()), wrong_type(node, &types, path)));
            return;
        }
        match &node.value {
            Value::Map(entries) => self.check_map(node, entries, schema, path, problems),
            Value::Seq(items) => self.check_seq(node, items, schema, path, problems),
            _ => {}
        }
    }

    fn check_map(
        &self,
        node: &Node,
        entries: &[(super::tree::Key, Node)],
        schema: &'s Json,
        path: &mut Vec<PathSeg>,
        problems: &mut Vec<Found>,
    ) {
        let properties = schema.get("properties").and_then(Json::as_object);
        let additional = schema.get("additionalProperties");
        let known: Vec<&str> = properties
            .map(|p| p.keys().map(String::as_str).collect())
            .unwrap_or_default();
        for (key, value) in entries {
            path.push(PathSeg::Key(key.name.clone()));
            if let Some(prop) = properties.and_then(|p| p.get(&key.name)) {
                self.check(value, prop, path, problems);
            } else {
                match additional {
                    Some(Json::Bool(false)) => {
                        let parent = super::tree::DisplayPath(&path[..path.len() - 1]).to_string();
                        let place = if parent.is_empty() {
                            "at the top level".to_owned()
                        } else {
                            format!("in `{parent}`")
                        };
                        let full = super::tree::DisplayPath(&path[..]).to_string();
                        let help = match MOVED.iter().find(|(old, _)| *old == full) {
                            Some((_, new)) => format!("this key moved: write `{new}` instead"),
                            None => suggestion(&key.name, &known),
                        };
                        problems.push((
                            Some(path.clone()),
                            Problem::new(code::UNKNOWN_KEY, format!("unknown key `{}` {place}", key.name))
                                .at(key.span, "unknown key")
                                .help(help),
                        ));
                    }
                    Some(extra @ Json::Object(_)) => self.check(value, extra, path, problems),
                    _ => {}
                }
            }
            path.pop();
        }
        if let Some(required) = schema.get("required").and_then(Json::as_array) {
            for name in required.iter().filter_map(Json::as_str) {
                if !entries.iter().any(|(k, _)| k.name == name) {
                    let here = super::tree::DisplayPath(path).to_string();
                    let place = if here.is_empty() {
                        "the spec".to_owned()
                    } else {
                        format!("`{here}`")
                    };
                    problems.push((
                        None,
                        Problem::new(
                            code::MISSING_KEY,
                            format!("{place} is missing the required key `{name}`"),
                        )
                        .at(node.span, format!("`{name}` is missing here"))
                        .help(format!("add `{name}:`")),
                    ));
                }
            }
        }
    }

    fn check_seq(
        &self,
        node: &Node,
        items: &[Node],
        schema: &'s Json,
        path: &mut Vec<PathSeg>,
        problems: &mut Vec<Found>,
    ) {
        let min = schema.get("minItems").and_then(Json::as_u64);
        let max = schema.get("maxItems").and_then(Json::as_u64);
        let len = items.len() as u64;
        if min.is_some_and(|m| len < m) || max.is_some_and(|m| len > m) {
            let expected = match (min, max) {
                (Some(a), Some(b)) if a == b => format!("exactly {a}"),
                (Some(a), Some(b)) => format!("{a} to {b}"),
                (Some(a), None) => format!("at least {a}"),
                (None, Some(b)) => format!("at most {b}"),
                (None, None) => unreachable!(),
            };
            let what = if min == Some(2) && max == Some(2) {
                " ([min, max])"
            } else {
                ""
            };
            problems.push((
                Some(path.clone()),
                Problem::new(
                    code::WRONG_TYPE,
                    format!(
                        "`{}` needs {expected} items{what}, found {len}",
                        super::tree::DisplayPath(path)
                    ),
                )
                .at(node.span, format!("{len} items")),
            ));
            return;
        }
        match schema.get("items") {
            Some(Json::Array(tuple)) => {
                for (i, (item, item_schema)) in items.iter().zip(tuple).enumerate() {
                    path.push(PathSeg::Index(i));
                    self.check(item, item_schema, path, problems);
                    path.pop();
                }
            }
            Some(item_schema @ Json::Object(_)) => {
                for (i, item) in items.iter().enumerate() {
                    path.push(PathSeg::Index(i));
                    self.check(item, item_schema, path, problems);
                    path.pop();
                }
            }
            _ => {}
        }
    }

    fn check_names(&self, node: &Node, names: &[Json], path: &[PathSeg], problems: &mut Vec<Found>) {
        let names: Vec<&str> = names.iter().filter_map(Json::as_str).collect();
        match &node.value {
            Value::Str(s) if names.contains(&s.as_str()) => {}
            Value::Str(s) => problems.push((Some(path.to_vec()), unknown_name(node, s, &names, path))),
            _ => problems.push((Some(path.to_vec()), wrong_type(node, &["string"], path))),
        }
    }

    /// A value matching any alternative is fine. Otherwise report against the alternative of the node's
    /// kind, or one "unknown name" error that lists the names of every string alternative.
    fn check_alternatives(
        &self,
        node: &Node,
        alternatives: &'s [Json],
        path: &mut Vec<PathSeg>,
        problems: &mut Vec<Found>,
    ) {
        let mut best: Option<Vec<Found>> = None;
        for alt in alternatives {
            let mut scratch = Vec::new();
            self.check(node, alt, path, &mut scratch);
            if scratch.is_empty() {
                return;
            }
            let same_kind = self.accepts_kind(alt, &node.value);
            if same_kind && best.is_none() {
                best = Some(scratch);
            }
        }
        if let Value::Str(s) = &node.value {
            let names: Vec<&str> = alternatives.iter().flat_map(|a| self.names_of(a)).collect();
            if !names.is_empty() {
                problems.push((Some(path.clone()), unknown_name(node, s, &names, path)));
                return;
            }
        }
        match best {
            Some(found) => problems.extend(found),
            None => {
                let kinds: Vec<&str> = alternatives.iter().flat_map(|a| self.kinds_of(a)).collect();
                problems.push((Some(path.clone()), wrong_type(node, &kinds, path)));
            }
        }
    }

    /// The string constants an alternative accepts.
    fn names_of(&self, schema: &'s Json) -> Vec<&'s str> {
        let schema = self.resolve(schema);
        if let Some(c) = schema.get("const").and_then(Json::as_str) {
            return vec![c];
        }
        if let Some(e) = schema.get("enum").and_then(Json::as_array) {
            return e.iter().filter_map(Json::as_str).collect();
        }
        if let Some(alts) = schema
            .get("anyOf")
            .or_else(|| schema.get("oneOf"))
            .and_then(Json::as_array)
        {
            return alts.iter().flat_map(|a| self.names_of(a)).collect();
        }
        Vec::new()
    }

    /// The JSON types an alternative accepts.
    fn kinds_of(&self, schema: &'s Json) -> Vec<&'s str> {
        let schema = self.resolve(schema);
        if schema.get("const").is_some() || schema.get("enum").is_some() {
            return vec!["string"];
        }
        if let Some(alts) = schema
            .get("anyOf")
            .or_else(|| schema.get("oneOf"))
            .and_then(Json::as_array)
        {
            return alts.iter().flat_map(|a| self.kinds_of(a)).collect();
        }
        match schema.get("type") {
            Some(Json::String(t)) => vec![t.as_str()],
            Some(Json::Array(ts)) => ts.iter().filter_map(Json::as_str).collect(),
            _ => Vec::new(),
        }
    }

    fn accepts_kind(&self, schema: &'s Json, value: &Value) -> bool {
        self.kinds_of(schema).iter().any(|t| type_matches(t, value))
    }
}

fn type_matches(t: &str, value: &Value) -> bool {
    match (t, value) {
        ("null", Value::Null) | ("boolean", Value::Bool(_)) | ("string", Value::Str(_)) => true,
        ("integer", Value::Int(_)) => true,
        ("integer", Value::Float(x)) => x.fract() == 0.0 && x.abs() < 9.0e15,
        ("number", Value::Int(_) | Value::Float(_)) => true,
        ("array", Value::Seq(_)) | ("object", Value::Map(_)) => true,
        _ => false,
    }
}

fn type_word(t: &str) -> &str {
    match t {
        "null" => "null",
        "boolean" => "a boolean",
        "string" => "a string",
        "integer" => "an integer",
        "number" => "a number",
        "array" => "a list",
        "object" => "a mapping",
        other => other,
    }
}

fn wrong_type(node: &Node, expected: &[&str], path: &[PathSeg]) -> Problem {
    let mut words: Vec<&str> = expected.iter().map(|t| type_word(t)).collect();
    words.dedup();
    let expected = match words.as_slice() {
        [] => "another value".to_owned(),
        [one] => (*one).to_owned(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    };
    let found = match &node.value {
        Value::Str(s) => format!("the string `{s}`"),
        other => other.kind().to_owned(),
    };
    Problem::new(
        code::WRONG_TYPE,
        format!("`{}` must be {expected}, found {found}", super::tree::DisplayPath(path)),
    )
    .at(node.span, format!("expected {expected}"))
}

fn unknown_name(node: &Node, name: &str, names: &[&str], path: &[PathSeg]) -> Problem {
    let what = match path.iter().rev().find_map(|s| {
        if let PathSeg::Key(k) = s {
            Some(k.as_str())
        } else {
            None
        }
    }) {
        Some("towns") => "town",
        Some("weathers") => "weather",
        Some(key) if key.ends_with("split") || path.iter().any(|s| s == &PathSeg::Key("splits".into())) => "split",
        _ => "value",
    };
    Problem::new(
        code::UNKNOWN_NAME,
        format!("unknown {what} `{name}` at `{}`", super::tree::DisplayPath(path)),
    )
    .at(node.span, format!("unknown {what}"))
    .help(suggestion(name, names))
}
