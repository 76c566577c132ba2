//! Loading a spec: bytes → UTF-8 → YAML tree → `--set` overrides → version → structural check → merge onto
//! the paper's defaults → typed spec → semantic validation. Every problem found is returned at once.

use std::path::{Path, PathBuf};

use super::check;
use super::diagnostic::{Problem, Sources, SpecErrors, code};
use super::schema::spec_schema;
use super::tree::{self, DisplayPath, Node, PathSeg, Span, Value};
use super::types::{CameraProfile, SPEC_VERSION, Spec};
use super::validate;

/// How to load a spec.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `--set key.path=value` overrides, applied in order on top of the file.
    pub overrides: Vec<String>,
    /// Accept specs beyond the sanity limits (`--allow-large`).
    pub allow_large: bool,
    /// A profile (`--profile FILE`, e.g. written by `pedsynth calibrate`): a partial spec laid over the spec
    /// before the overrides.
    pub profile: Option<PathBuf>,
}

/// A valid, fully defaulted spec.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedSpec {
    /// The spec with every default filled in.
    pub spec: Spec,
    /// The name the spec was loaded under (its path as given).
    pub name: String,
    /// Directory relative paths in the spec are resolved against.
    pub base_dir: PathBuf,
}

impl LoadedSpec {
    /// blake3 of the canonical JSON of the resolved spec: identifies the spec's content.
    pub fn hash(&self) -> Result<String, crate::error::Error> {
        spec_hash(&self.spec)
    }

    /// The path of an OpenDRIVE file named in the spec, resolved against the spec's directory.
    pub fn resolve_path(&self, relative: &str) -> PathBuf {
        self.base_dir.join(relative)
    }
}

/// blake3 of the canonical JSON of a spec.
pub fn spec_hash(spec: &Spec) -> Result<String, crate::error::Error> {
    let json = crate::error::to_json(spec, false)?;
    Ok(blake3::hash(json.as_bytes()).to_hex().to_string())
}

/// Largest spec file read (specs are a few kilobytes; the YAML budget bounds what a smaller one expands to).
pub const MAX_SPEC_BYTES: u64 = 16 << 20;

/// Loads and validates the spec file at `path` (at most [`MAX_SPEC_BYTES`]); relative paths in it resolve
/// against its directory.
pub fn load_file(path: &Path, options: &LoadOptions) -> Result<LoadedSpec, SpecErrors> {
    let name = path.display().to_string();
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    match crate::util::files::read_capped(path, MAX_SPEC_BYTES) {
        Ok(bytes) => load_bytes(&bytes, &name, &base_dir, options),
        Err(err) => {
            let problem = Problem::new(code::IO, format!("cannot read spec `{name}`: {err}")).help("check the path");
            Err(SpecErrors::new(name, vec![problem], &Sources::default()))
        }
    }
}

/// Loads and validates a spec from bytes; `name` labels diagnostics and `base_dir` resolves relative paths.
pub fn load_bytes(bytes: &[u8], name: &str, base_dir: &Path, options: &LoadOptions) -> Result<LoadedSpec, SpecErrors> {
    let mut sources = Sources::default();
    let text = match std::str::from_utf8(bytes) {
        Ok(text) => text,
        Err(err) => {
            let lossy = String::from_utf8_lossy(bytes).into_owned();
            sources.add(name, lossy);
            let offset = err.valid_up_to();
            let problem = Problem::new(code::NOT_UTF8, "the spec is not valid UTF-8")
                .at(
                    Span {
                        source: 0,
                        offset,
                        len: err.error_len().unwrap_or(1).min(3),
                    },
                    "invalid byte here",
                )
                .help("save the file as UTF-8");
            return Err(SpecErrors::new(name, vec![problem], &sources));
        }
    };
    sources.add(name, text);
    let fail = |problems: Vec<Problem>, sources: &Sources| Err(SpecErrors::new(name, problems, sources));

    let mut root = match tree::parse(text, 0) {
        Ok(root) => root,
        Err(err) => return fail(vec![yaml_problem(&err, text, 0)], &sources),
    };
    if matches!(root.value, Value::Null) {
        let problem = Problem::new(code::EMPTY, "the spec is empty")
            .at(
                Span {
                    source: 0,
                    offset: 0,
                    len: 0,
                },
                "no YAML document here",
            )
            .help("a spec needs at least `version: 1`; see specs/quickstart.yaml");
        return fail(vec![problem], &sources);
    }

    // A malformed override is reported and skipped; the rest of the spec is still validated.
    let mut problems = Vec::new();
    if let Some(path) = &options.profile {
        match read_profile(path, &mut sources) {
            Ok(profile) => overlay(&mut root, profile, None),
            Err(problem) => problems.push(*problem),
        }
    }
    for (i, text) in options.overrides.iter().enumerate() {
        let id = sources.add(format!("--set #{}", i + 1), text.clone());
        if let Err(problem) = apply_override(&mut root, text, id) {
            problems.push(*problem);
        }
    }

    apply_camera_profile(&mut root);
    if let Some(problem) = check_version(&root) {
        return fail(vec![problem], &sources);
    }
    // Structural problems are reported, and the offending nodes pruned (a list as a whole, since removing
    // one item would shift its siblings' paths) so the rest of the spec is still validated.
    let mut pruned = Vec::new();
    for (path, problem) in check::check(&root, &spec_schema()) {
        problems.push(problem);
        if let Some(mut path) = path {
            if let Some(index) = path.iter().rposition(|s| matches!(s, PathSeg::Index(_))) {
                path.truncate(index);
            }
            // A mix missing one of its keys would also fail its sum check: prune the whole mix.
            if path.len() >= 2 && matches!(&path[path.len() - 2], PathSeg::Key(k) if is_mix_key(k)) {
                path.pop();
            }
            pruned.push(path);
        }
    }
    pruned.sort();
    pruned.dedup();
    for path in pruned.iter().rev() {
        if !path.is_empty() {
            root.remove(path);
        }
    }

    let mut merged = match serde_json::to_value(Spec::default()) {
        Ok(defaults) => defaults,
        Err(e) => {
            let problem = Problem::new(
                code::IO,
                format!("internal error: cannot serialise the spec's defaults: {e}"),
            );
            return fail(vec![problem], &sources);
        }
    };
    merge(&mut merged, root.to_json(), None);
    let spec: Spec = match serde_json::from_value(merged) {
        Ok(spec) => spec,
        Err(err) => {
            let problem = Problem::new(
                code::WRONG_TYPE,
                format!("the spec does not match the spec language: {err}"),
            )
            .at(root.span, "in this document")
            .help("run `pedsynth schema` to see the spec language");
            return fail(vec![problem], &sources);
        }
    };
    if pruned.iter().any(Vec::is_empty) {
        return fail(problems, &sources);
    }
    validate::validate(&spec, &root, base_dir, options.allow_large, &mut problems);
    if !problems.is_empty() {
        return fail(problems, &sources);
    }
    Ok(LoadedSpec {
        spec,
        name: name.to_owned(),
        base_dir: base_dir.to_path_buf(),
    })
}

/// Serialises a spec as YAML (the fully defaulted form when given a loaded spec).
pub fn to_yaml(spec: &Spec) -> Result<String, crate::error::Error> {
    serde_saphyr::to_string(spec).map_err(|e| {
        crate::error::Error::new(
            crate::error::code::INTERNAL_SERIALIZE,
            format!("cannot serialise the spec as YAML: {e}"),
        )
    })
}

/// Deep-merges `user` onto `base`. Mappings merge key by key, except mixes (a key `mix` or `*_mix`), which,
/// like lists and scalars, are replaced as a whole.
fn merge(base: &mut serde_json::Value, user: serde_json::Value, key: Option<&str>) {
    let is_mix = key.is_some_and(is_mix_key);
    match (base, user) {
        (serde_json::Value::Object(base), serde_json::Value::Object(user)) if !is_mix => {
            for (k, v) in user {
                match base.get_mut(&k) {
                    Some(slot) => merge(slot, v, Some(&k)),
                    None => {
                        base.insert(k, v);
                    }
                }
            }
        }
        (base, user) => *base = user,
    }
}

/// Whether a key names a mix (replaced as a whole when merging onto the defaults).
fn is_mix_key(key: &str) -> bool {
    key == "mix" || key.ends_with("_mix")
}

fn check_version(root: &Node) -> Option<Problem> {
    let node = root.get("version")?;
    match node.value {
        Value::Int(v) if v == i128::from(SPEC_VERSION) => None,
        Value::Int(_) | Value::Float(_) | Value::Str(_) => Some(
            Problem::new(
                code::UNSUPPORTED_VERSION,
                format!("unsupported spec version; this pedsynth reads version {SPEC_VERSION}"),
            )
            .at(node.span, "unsupported version")
            .help(format!(
                "write `version: {SPEC_VERSION}`, or use the pedsynth release that reads this version"
            )),
        ),
        _ => None, // a wrong type is reported by the structural check
    }
}

/// Reads and parses a profile file; its nodes' spans point into a source of its own.
fn read_profile(path: &Path, sources: &mut Sources) -> Result<Node, Box<Problem>> {
    let label = format!("profile {}", path.display());
    let bytes = crate::util::files::read_capped(path, MAX_SPEC_BYTES).map_err(|err| {
        Box::new(
            Problem::new(code::IO, format!("cannot read profile `{}`: {err}", path.display()))
                .help("check the path given to --profile"),
        )
    })?;
    let Ok(text) = String::from_utf8(bytes) else {
        return Err(Box::new(
            Problem::new(
                code::NOT_UTF8,
                format!("profile `{}` is not valid UTF-8", path.display()),
            )
            .help("save the file as UTF-8"),
        ));
    };
    let id = sources.add(label, text.clone());
    let node = tree::parse(&text, id).map_err(|err| Box::new(yaml_problem(&err, &text, id)))?;
    match node.value {
        Value::Map(_) | Value::Null => Ok(node),
        _ => Err(Box::new(
            Problem::new(
                code::WRONG_TYPE,
                format!("profile `{}` must be a mapping of spec keys", path.display()),
            )
            .at(node.span, "not a mapping")
            .help("a profile is a partial spec, e.g. `sensors: {rgb: {profile: jaad}}`"),
        )),
    }
}

/// Lays `over` onto `base`: mappings merge key by key (a mix, like a list or a scalar, is replaced whole), and
/// `over`'s values win.
fn overlay(base: &mut Node, over: Node, key: Option<&str>) {
    let is_mix = key.is_some_and(is_mix_key);
    match (&mut base.value, over.value) {
        (Value::Map(entries), Value::Map(over_entries)) if !is_mix => {
            for (k, v) in over_entries {
                match entries.iter_mut().rev().find(|(existing, _)| existing.name == k.name) {
                    Some((_, slot)) => overlay(slot, v, Some(&k.name)),
                    None => entries.push((k, v)),
                }
            }
        }
        (_, Value::Null) if key.is_none() => {}
        (_, value) => *base = Node { value, span: over.span },
    }
}

/// Fills in the keys of `sensors.rgb.profile`'s camera preset that `sensors.rgb` does not set itself (an
/// unknown profile name is left to the structural check).
fn apply_camera_profile(root: &mut Node) {
    let path = [
        PathSeg::Key("sensors".into()),
        PathSeg::Key("rgb".into()),
        PathSeg::Key("profile".into()),
    ];
    let Some(node) = root.at(&path) else { return };
    let Value::Str(name) = &node.value else { return };
    let Ok(profile) = serde_json::from_value::<CameraProfile>(serde_json::Value::String(name.clone())) else {
        return;
    };
    let span = node.span;
    for (key, value) in profile.preset() {
        let Ok(mut key_path) = tree::parse_path(key) else {
            continue;
        };
        key_path.splice(0..0, path[..2].iter().cloned());
        if root.at(&key_path).is_some() {
            continue;
        }
        if let Ok(mut value) = tree::parse(value, span.source) {
            value.span = span;
            // Cannot fail: the path's parents are mappings or absent (a non-mapping `mount` keeps its own
            // value, reported by the structural check).
            let _ = root.set(&key_path, value, span);
        }
    }
}

/// Applies one `key.path=value` override; the value is YAML.
fn apply_override(root: &mut Node, text: &str, source: usize) -> Result<(), Box<Problem>> {
    let whole = Span {
        source,
        offset: 0,
        len: text.len(),
    };
    let Some(eq) = text.find('=') else {
        let problem = Problem::new(code::BAD_OVERRIDE, "an override must look like `key.path=value`")
            .at(whole, "no `=` here")
            .help("e.g. --set crossing.target_ratio=0.5");
        return Err(Box::new(problem));
    };
    let key_span = Span {
        source,
        offset: 0,
        len: eq,
    };
    let path = tree::parse_path(&text[..eq]).map_err(|msg| {
        let problem = Problem::new(code::BAD_OVERRIDE, msg)
            .at(key_span, "bad key path")
            .help("e.g. --set crossing.target_ratio=0.5");
        Box::new(problem)
    })?;
    let value_text = &text[eq + 1..];
    let value_span = Span {
        source,
        offset: eq + 1,
        len: value_text.len(),
    };
    let mut value = match tree::parse(value_text, source) {
        Ok(value) => value,
        Err(err) => {
            let mut problem = yaml_problem(&err, value_text, source);
            if let Some((span, _)) = problem.label.as_mut() {
                span.offset += eq + 1;
            }
            return Err(Box::new(problem));
        }
    };
    shift_spans(&mut value, eq + 1);
    if matches!(value.value, Value::Null) && value_text.trim().is_empty() {
        value.span = value_span;
    }
    root.set(&path, value, key_span).map_err(|msg| {
        let message = format!("cannot apply override to `{}`: {msg}", DisplayPath(&path));
        Box::new(Problem::new(code::BAD_OVERRIDE, message).at(key_span, "here"))
    })
}

fn shift_spans(node: &mut Node, by: usize) {
    node.span.offset += by;
    match &mut node.value {
        Value::Seq(items) => items.iter_mut().for_each(|n| shift_spans(n, by)),
        Value::Map(entries) => {
            for (k, v) in entries {
                k.span.offset += by;
                shift_spans(v, by);
            }
        }
        _ => {}
    }
}

/// Turns a YAML parser error into a problem with a span.
fn yaml_problem(err: &serde_saphyr::Error, text: &str, source: usize) -> Problem {
    let location = err.location();
    let span = location.map(|loc| {
        let span = loc.span();
        let offset = match span.byte_offset() {
            Some(o) if (o as usize) <= text.len() => o as usize,
            _ => offset_of(text, loc.line() as usize, loc.column() as usize),
        };
        Span {
            source,
            offset,
            len: span
                .byte_len()
                .map_or(1, |l| l as usize)
                .min(text.len().saturating_sub(offset)),
        }
    });
    let (code, message, help) = match err.without_snippet() {
        serde_saphyr::Error::DuplicateMappingKey { key, .. } => (
            code::DUPLICATE_KEY,
            format!("duplicate key `{}`", key.as_deref().unwrap_or("?")),
            "a key may appear once in a mapping; remove one of them",
        ),
        other if matches!(other, serde_saphyr::Error::Budget { .. }) || other.render().contains("budget breached") => (
            code::YAML_BUDGET,
            "the YAML is too large or expands too much (an alias bomb?)".to_owned(),
            "specs are small documents: avoid deep nesting and repeated aliases",
        ),
        other => {
            let rendered = other.render();
            let message = match rendered.rfind(" at line ") {
                Some(i) => rendered[..i].to_owned(),
                None => rendered,
            };
            (
                code::YAML_SYNTAX,
                format!("YAML syntax error: {message}"),
                "fix the YAML syntax; check indentation, brackets and quotes",
            )
        }
    };
    let mut problem = Problem::new(code, message).help(help);
    if let Some(span) = span {
        problem = problem.at(span, "here");
    }
    problem
}

/// Byte offset of a 1-based line and column (in characters).
fn offset_of(text: &str, line: usize, column: usize) -> usize {
    let line_start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    let rest = &text[line_start.min(text.len())..];
    let col: usize = rest.chars().take(column.saturating_sub(1)).map(char::len_utf8).sum();
    (line_start + col).min(text.len())
}
