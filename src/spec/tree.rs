//! A YAML document as a tree of nodes that remember where they were written (source and byte span).
//!
//! Loading a spec goes through this tree rather than straight into the typed spec so that every problem can
//! be reported at once, each pointing at its exact key or value, and so that `--set` overrides can be
//! spliced in with spans of their own.

use std::fmt;

use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_saphyr::Spanned;

/// Which text a span points into: the spec file (0) or the n-th `--set` override (n ≥ 1).
pub type SourceId = usize;

/// A byte range in one source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Span {
    /// The source the span points into.
    pub source: SourceId,
    /// Byte offset of the first byte.
    pub offset: usize,
    /// Length in bytes.
    pub len: usize,
}

/// A YAML node with its span.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// The value.
    pub value: Value,
    /// Where the value was written.
    pub span: Span,
}

/// A YAML value (core schema).
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// `null`, `~` or nothing.
    Null,
    /// `true` / `false`.
    Bool(bool),
    /// An integer (wide enough for every i64 and u64).
    Int(i128),
    /// A floating-point number.
    Float(f64),
    /// A string.
    Str(String),
    /// A sequence.
    Seq(Vec<Node>),
    /// A mapping with its keys in document order; keys are strings.
    Map(Vec<(Key, Node)>),
}

/// A mapping key with its span.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    /// The key text.
    pub name: String,
    /// Where the key was written.
    pub span: Span,
}

/// One step of a path into the tree.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum PathSeg {
    /// A mapping key.
    Key(String),
    /// A sequence index.
    Index(usize),
}

/// Formats a path as `crossing.layers.groups.probability` / `dataset.towns[1]`.
pub struct DisplayPath<'a>(pub &'a [PathSeg]);

impl fmt::Display for DisplayPath<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, seg) in self.0.iter().enumerate() {
            match seg {
                PathSeg::Key(k) if i == 0 => write!(f, "{k}")?,
                PathSeg::Key(k) => write!(f, ".{k}")?,
                PathSeg::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

impl Value {
    /// The kind of value, as users read it in a message.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Null => "null",
            Value::Bool(_) => "a boolean",
            Value::Int(_) => "an integer",
            Value::Float(_) => "a number",
            Value::Str(_) => "a string",
            Value::Seq(_) => "a list",
            Value::Map(_) => "a mapping",
        }
    }
}

impl Node {
    /// The child at `key` of a mapping.
    pub fn get(&self, key: &str) -> Option<&Node> {
        match &self.value {
            Value::Map(entries) => entries.iter().rev().find(|(k, _)| k.name == key).map(|(_, v)| v),
            _ => None,
        }
    }

    /// The node at `path`, if every step exists.
    pub fn at(&self, path: &[PathSeg]) -> Option<&Node> {
        let mut node = self;
        for seg in path {
            node = match (seg, &node.value) {
                (PathSeg::Key(k), Value::Map(_)) => node.get(k)?,
                (PathSeg::Index(i), Value::Seq(items)) => items.get(*i)?,
                _ => return None,
            };
        }
        Some(node)
    }

    /// The span of the deepest node on `path` that exists (the root's span if none does).
    pub fn span_at(&self, path: &[PathSeg]) -> Span {
        let mut node = self;
        for seg in path {
            let next = match (seg, &node.value) {
                (PathSeg::Key(k), Value::Map(_)) => node.get(k),
                (PathSeg::Index(i), Value::Seq(items)) => items.get(*i),
                _ => None,
            };
            match next {
                Some(n) => node = n,
                None => break,
            }
        }
        node.span
    }

    /// The span of the key that introduces the node at `path` (for a mapping entry), else the node's span.
    pub fn key_span_at(&self, path: &[PathSeg]) -> Option<Span> {
        let (last, parent) = path.split_last()?;
        let parent = self.at(parent)?;
        match (last, &parent.value) {
            (PathSeg::Key(k), Value::Map(entries)) => entries
                .iter()
                .rev()
                .find(|(key, _)| &key.name == k)
                .map(|(key, _)| key.span),
            _ => self.at(path).map(|n| n.span),
        }
    }

    /// Sets the node at `path`, creating mappings on the way; `at` labels created mappings.
    pub fn set(&mut self, path: &[PathSeg], value: Node, at: Span) -> Result<(), String> {
        let Some((first, rest)) = path.split_first() else {
            *self = value;
            return Ok(());
        };
        match (first, &mut self.value) {
            (PathSeg::Key(k), Value::Map(entries)) => {
                if let Some((_, child)) = entries.iter_mut().rev().find(|(key, _)| &key.name == k) {
                    return child.set(rest, value, at);
                }
                let mut child = Node {
                    value: Value::Map(Vec::new()),
                    span: at,
                };
                child.set(rest, value, at)?;
                entries.push((
                    Key {
                        name: k.clone(),
                        span: at,
                    },
                    child,
                ));
                Ok(())
            }
            (PathSeg::Key(_), Value::Null) => {
                self.value = Value::Map(Vec::new());
                self.set(path, value, at)
            }
            (PathSeg::Index(i), Value::Seq(items)) => {
                let len = items.len();
                match items.get_mut(*i) {
                    Some(child) => child.set(rest, value, at),
                    None if *i == len && rest.is_empty() => {
                        items.push(value);
                        Ok(())
                    }
                    None => Err(format!("index {i} is past the end of a list of {len}")),
                }
            }
            (PathSeg::Index(_), other) => Err(format!("cannot index into {}", other.kind())),
            (PathSeg::Key(k), other) => Err(format!("cannot set key `{k}` inside {}", other.kind())),
        }
    }

    /// Removes the node at `path` (a mapping entry or a list item); returns whether it existed.
    pub fn remove(&mut self, path: &[PathSeg]) -> bool {
        let Some((last, parent)) = path.split_last() else {
            return false;
        };
        let mut node = self;
        for seg in parent {
            let next = match (seg, &mut node.value) {
                (PathSeg::Key(k), Value::Map(entries)) => {
                    entries.iter_mut().rev().find(|(key, _)| &key.name == k).map(|(_, v)| v)
                }
                (PathSeg::Index(i), Value::Seq(items)) => items.get_mut(*i),
                _ => None,
            };
            match next {
                Some(n) => node = n,
                None => return false,
            }
        }
        match (last, &mut node.value) {
            (PathSeg::Key(k), Value::Map(entries)) => {
                let before = entries.len();
                entries.retain(|(key, _)| &key.name != k);
                entries.len() != before
            }
            (PathSeg::Index(i), Value::Seq(items)) if *i < items.len() => {
                items.remove(*i);
                true
            }
            _ => false,
        }
    }

    /// Converts the tree to JSON (for typed deserialisation and merging).
    pub fn to_json(&self) -> serde_json::Value {
        match &self.value {
            Value::Null => serde_json::Value::Null,
            Value::Bool(b) => serde_json::Value::Bool(*b),
            Value::Int(i) => match (i64::try_from(*i), u64::try_from(*i)) {
                (Ok(i), _) => serde_json::Value::from(i),
                (_, Ok(u)) => serde_json::Value::from(u),
                _ => serde_json::Number::from_f64(*i as f64).map_or(serde_json::Value::Null, serde_json::Value::Number),
            },
            Value::Float(x) => {
                serde_json::Number::from_f64(*x).map_or(serde_json::Value::Null, serde_json::Value::Number)
            }
            Value::Str(s) => serde_json::Value::String(s.clone()),
            Value::Seq(items) => serde_json::Value::Array(items.iter().map(Node::to_json).collect()),
            Value::Map(entries) => {
                let mut map = serde_json::Map::new();
                for (k, v) in entries {
                    map.insert(k.name.clone(), v.to_json());
                }
                serde_json::Value::Object(map)
            }
        }
    }
}

/// Parses a dotted override path `a.b[2].c` (or `a.b.2.c`).
pub fn parse_path(text: &str) -> Result<Vec<PathSeg>, String> {
    let mut path = Vec::new();
    for part in text.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if name.is_empty() && (path.is_empty() || rest.is_empty()) {
            return Err(format!("empty segment in key path `{text}`"));
        }
        if !name.is_empty() {
            if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
                return Err(format!("`{name}` is not a valid key in key path `{text}`"));
            }
            match name.parse::<usize>() {
                Ok(i) if !path.is_empty() => path.push(PathSeg::Index(i)),
                _ => path.push(PathSeg::Key(name.to_owned())),
            }
        }
        while !rest.is_empty() {
            let close = rest
                .find(']')
                .ok_or_else(|| format!("unclosed `[` in key path `{text}`"))?;
            let index = rest[1..close]
                .parse::<usize>()
                .map_err(|_| format!("`{}` is not a list index in `{text}`", &rest[1..close]))?;
            path.push(PathSeg::Index(index));
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(format!("unexpected `{rest}` in key path `{text}`"));
            }
        }
    }
    Ok(path)
}

/// Parses YAML text into a tree whose spans point into `source`.
pub fn parse(text: &str, source: SourceId) -> Result<Node, serde_saphyr::Error> {
    let mut options = serde_saphyr::Options::default();
    // A duplicate key is an error (reported with its location), never silently dropped.
    options.duplicate_keys = serde_saphyr::DuplicateKeyPolicy::Error;
    let mut budget = serde_saphyr::Budget::default();
    budget.max_events = 200_000;
    budget.max_aliases = 1_000;
    budget.max_anchors = 1_000;
    budget.max_nodes = 100_000;
    budget.max_depth = 64;
    budget.max_total_scalar_bytes = 8 << 20;
    options.budget = Some(budget);
    let raw: RawNode = serde_saphyr::from_str_with_options(text, options)?;
    Ok(raw.into_node(source))
}

fn span_of(loc: &serde_saphyr::Location, source: SourceId) -> Span {
    let span = loc.span();
    Span {
        source,
        offset: span.byte_offset().unwrap_or(0) as usize,
        len: span.byte_len().unwrap_or(0) as usize,
    }
}

/// Deserialisation target: a spanned value.
struct RawNode(Spanned<RawValue>);

enum RawValue {
    Null,
    Bool(bool),
    Int(i128),
    Float(f64),
    Str(String),
    Seq(Vec<RawNode>),
    Map(Vec<(Spanned<RawKey>, RawNode)>),
}

/// A mapping key: any scalar, kept as text.
struct RawKey(Result<String, &'static str>);

impl RawNode {
    fn into_node(self, source: SourceId) -> Node {
        let Spanned { value, referenced, .. } = self.0;
        let span = span_of(&referenced, source);
        let value = match value {
            RawValue::Null => Value::Null,
            RawValue::Bool(b) => Value::Bool(b),
            RawValue::Int(i) => Value::Int(i),
            RawValue::Float(x) => Value::Float(x),
            RawValue::Str(s) => Value::Str(s),
            RawValue::Seq(items) => Value::Seq(items.into_iter().map(|n| n.into_node(source)).collect()),
            RawValue::Map(entries) => Value::Map(
                entries
                    .into_iter()
                    .map(|(k, v)| {
                        let span = span_of(&k.referenced, source);
                        let name = k.value.0.unwrap_or_else(|kind| format!("<{kind}>"));
                        (Key { name, span }, v.into_node(source))
                    })
                    .collect(),
            ),
        };
        Node { value, span }
    }
}

impl<'de> Deserialize<'de> for RawNode {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Spanned::<RawValue>::deserialize(d).map(RawNode)
    }
}

impl<'de> Deserialize<'de> for RawValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(RawVisitor)
    }
}

struct RawVisitor;

impl<'de> Visitor<'de> for RawVisitor {
    type Value = RawValue;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any YAML value")
    }
    fn visit_unit<E: de::Error>(self) -> Result<RawValue, E> {
        Ok(RawValue::Null)
    }
    fn visit_none<E: de::Error>(self) -> Result<RawValue, E> {
        Ok(RawValue::Null)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<RawValue, D::Error> {
        RawValue::deserialize(d)
    }
    fn visit_bool<E: de::Error>(self, b: bool) -> Result<RawValue, E> {
        Ok(RawValue::Bool(b))
    }
    fn visit_i64<E: de::Error>(self, i: i64) -> Result<RawValue, E> {
        Ok(RawValue::Int(i128::from(i)))
    }
    fn visit_u64<E: de::Error>(self, u: u64) -> Result<RawValue, E> {
        Ok(RawValue::Int(i128::from(u)))
    }
    fn visit_i128<E: de::Error>(self, i: i128) -> Result<RawValue, E> {
        Ok(RawValue::Int(i))
    }
    fn visit_u128<E: de::Error>(self, u: u128) -> Result<RawValue, E> {
        Ok(i128::try_from(u).map_or(RawValue::Float(u as f64), RawValue::Int))
    }
    fn visit_f64<E: de::Error>(self, x: f64) -> Result<RawValue, E> {
        Ok(RawValue::Float(x))
    }
    fn visit_str<E: de::Error>(self, s: &str) -> Result<RawValue, E> {
        Ok(RawValue::Str(s.to_owned()))
    }
    fn visit_string<E: de::Error>(self, s: String) -> Result<RawValue, E> {
        Ok(RawValue::Str(s))
    }
    fn visit_bytes<E: de::Error>(self, b: &[u8]) -> Result<RawValue, E> {
        Ok(RawValue::Str(String::from_utf8_lossy(b).into_owned()))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawValue, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element::<RawNode>()? {
            items.push(item);
        }
        Ok(RawValue::Seq(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawValue, A::Error> {
        let mut entries = Vec::new();
        while let Some(key) = map.next_key::<Spanned<RawKey>>()? {
            let value = map.next_value::<RawNode>()?;
            entries.push((key, value));
        }
        Ok(RawValue::Map(entries))
    }
}

impl<'de> Deserialize<'de> for RawKey {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(RawKey(match RawValue::deserialize(d)? {
            RawValue::Str(s) => Ok(s),
            RawValue::Int(i) => Ok(i.to_string()),
            RawValue::Bool(b) => Ok(b.to_string()),
            RawValue::Float(x) => Ok(x.to_string()),
            RawValue::Null => Err("null key"),
            RawValue::Seq(_) => Err("list key"),
            RawValue::Map(_) => Err("mapping key"),
        }))
    }
}
