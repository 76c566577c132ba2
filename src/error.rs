//! The program's one error type, and the registry of every stable diagnostic code.
//!
//! Every failure a command can report is an [`Error`] with a stable code (`pedsynth::<area>::<what>`). Each code
//! belongs to one [`Kind`], which decides the exit code: **2** for bad input (a spec, a plan, a map, an
//! argument, a dataset), **1** for the environment (reading or writing files, disk, permissions). [`CODES`] lists
//! every code with its kind and meaning; README.md's table of codes is generated from it (a test fails when the
//! two drift, and another when a code appears in the source but not here).

use crate::dsl::SpecErrors;
use crate::dsl::diagnostic::code as spec;
use crate::world::WorldError;

/// What kind of failure an error is; decides the exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Bad input: a spec, a plan, a map, an argument or a dataset (exit 2).
    Input,
    /// The environment failed (reading or writing files, disk, permissions), or an internal failure (exit 1).
    Environment,
}

impl Kind {
    /// The process exit code of this kind.
    pub fn exit_code(self) -> i32 {
        match self {
            Kind::Input => crate::commands::exit::INVALID,
            Kind::Environment => crate::commands::exit::FAILURE,
        }
    }
}

/// Codes of the areas beyond the spec language (whose codes are in [`crate::dsl::diagnostic::code`]).
pub mod code {
    /// A spec that cannot be planned (no room for its pedestrians or vehicles in a town, ...).
    pub const PLAN_INFEASIBLE: &str = "pedsynth::plan::infeasible";
    /// A plan file that is not a pedsynth plan (or is malformed).
    pub const PLAN_INVALID: &str = "pedsynth::plan::invalid";
    /// A plan file of a format version this build does not read.
    pub const PLAN_UNSUPPORTED_VERSION: &str = "pedsynth::plan::unsupported_version";
    /// `--only` names a clip the plan does not have.
    pub const PLAN_UNKNOWN_CLIP: &str = "pedsynth::plan::unknown_clip";
    /// `--set` was given with a plan file (overrides apply to specs).
    pub const PLAN_OVERRIDE: &str = "pedsynth::plan::override";
    /// An OpenDRIVE file that is not well-formed XML.
    pub const XODR_SYNTAX: &str = "pedsynth::world::xodr_syntax";
    /// An OpenDRIVE file whose content is unusable.
    pub const XODR_INVALID: &str = "pedsynth::world::xodr_invalid";
    /// An OpenDRIVE file beyond the importer's size caps.
    pub const XODR_TOO_LARGE: &str = "pedsynth::world::xodr_too_large";
    /// A map file that cannot be read.
    pub const WORLD_IO: &str = "pedsynth::world::io";
    /// A town name that is neither built in nor an `.xodr` path.
    pub const UNKNOWN_TOWN: &str = "pedsynth::world::unknown_town";
    /// `generate --out` names a directory that holds something other than a dataset of this spec and plan.
    pub const DATASET_REFUSED: &str = "pedsynth::dataset::refused";
    /// A shard (`--shard I/N` or a cluster engine's environment) that does not exist.
    pub const SHARD_INVALID: &str = "pedsynth::generate::shard";
    /// `pedsynth merge` was given a directory that is not a dataset of the same spec and plan.
    pub const MERGE_MISMATCH: &str = "pedsynth::merge::mismatch";
    /// `pedsynth merge` found clips that no directory has finished.
    pub const MERGE_INCOMPLETE: &str = "pedsynth::merge::incomplete";
    /// `generate --out` names a directory another `generate` is writing into (it holds the lock).
    pub const DATASET_LOCKED: &str = "pedsynth::dataset::locked";
    /// A dataset that cannot be read as a pedsynth dataset (missing or malformed tables or manifest).
    pub const DATASET_INVALID: &str = "pedsynth::dataset::invalid";
    /// Options of `stats --protocol` that the protocol does not define.
    pub const PROTOCOL_OPTIONS: &str = "pedsynth::dataset::protocol_options";
    /// A file or directory that cannot be read.
    pub const IO_READ: &str = "pedsynth::io::read";
    /// A file or directory that cannot be written (disk full, permissions, read-only file system).
    pub const IO_WRITE: &str = "pedsynth::io::write";
    /// Writing to standard output or standard error failed (a closed pipe).
    pub const IO_OUTPUT: &str = "pedsynth::io::output";
    /// Worker threads could not be started.
    pub const IO_THREADS: &str = "pedsynth::io::threads";
    /// A value of pedsynth's own could not be serialised (a bug: please report it).
    pub const INTERNAL_SERIALIZE: &str = "pedsynth::internal::serialize";
}

/// A registered code: its kind and what it means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeInfo {
    /// The code.
    pub code: &'static str,
    /// The kind every error with this code has.
    pub kind: Kind,
    /// What it means (one line, for README.md's table).
    pub meaning: &'static str,
}

const fn input(code: &'static str, meaning: &'static str) -> CodeInfo {
    CodeInfo {
        code,
        kind: Kind::Input,
        meaning,
    }
}

const fn environment(code: &'static str, meaning: &'static str) -> CodeInfo {
    CodeInfo {
        code,
        kind: Kind::Environment,
        meaning,
    }
}

/// Every diagnostic code the program can report, in README order.
pub const CODES: &[CodeInfo] = &[
    input(spec::YAML_SYNTAX, "the YAML cannot be parsed"),
    input(
        spec::YAML_BUDGET,
        "the YAML is too large or expands too much (alias bombs are rejected in milliseconds)",
    ),
    input(spec::EMPTY, "no YAML document"),
    input(spec::NOT_UTF8, "the file is not UTF-8"),
    input(spec::DUPLICATE_KEY, "a key appears twice in a mapping"),
    input(
        spec::UNKNOWN_KEY,
        "a key the spec language does not know (\"did you mean\")",
    ),
    input(spec::MISSING_KEY, "a required key (`version`) is missing"),
    input(spec::WRONG_TYPE, "a value of the wrong type"),
    input(spec::OUT_OF_RANGE, "a number outside its allowed range"),
    input(spec::EMPTY_RANGE, "a `[min, max]` range with min > max"),
    input(spec::MIX_SUM, "a mix whose shares do not sum to 1 (the sum is shown)"),
    input(
        spec::UNKNOWN_NAME,
        "an unknown weather, town, archetype or split name (\"did you mean\")",
    ),
    input(spec::DUPLICATE_NAME, "a town or weather listed twice"),
    input(
        spec::INVALID_NAME,
        "a name that cannot be used in clip ids and file names",
    ),
    input(
        spec::UNREACHABLE_TARGET,
        "a target crossing ratio that the enabled layers cannot reach (only with `crossing.layers.crosser_allocation` off: the planner meets every target in [0, 1] with it on)",
    ),
    input(spec::UNSUPPORTED_VERSION, "a `version` other than 1"),
    input(
        spec::TOO_LARGE,
        "beyond the sanity limits (clips, image size, estimated bytes); `--allow-large` overrides",
    ),
    input(
        spec::MISSING_FILE,
        "a referenced file (an OpenDRIVE map) does not exist",
    ),
    input(spec::BAD_OVERRIDE, "a malformed `--set`"),
    input(
        spec::NOT_IMPLEMENTED,
        "a key of the spec language whose feature this pedsynth version does not implement yet",
    ),
    input(spec::IO, "the spec file cannot be read"),
    input(
        code::PLAN_INFEASIBLE,
        "the spec cannot be planned (no room for its pedestrians or vehicles near an ego route)",
    ),
    input(code::PLAN_INVALID, "a plan file that is not a pedsynth plan"),
    input(
        code::PLAN_UNSUPPORTED_VERSION,
        "a plan file of a format version this pedsynth does not read",
    ),
    input(code::PLAN_UNKNOWN_CLIP, "`--only` names a clip the plan does not have"),
    input(
        code::PLAN_OVERRIDE,
        "`--set` given with a plan file (overrides apply to specs)",
    ),
    input(code::XODR_SYNTAX, "an OpenDRIVE file that is not well-formed XML"),
    input(code::XODR_INVALID, "an OpenDRIVE file whose content is unusable"),
    input(
        code::XODR_TOO_LARGE,
        "an OpenDRIVE file beyond the importer's size caps",
    ),
    environment(code::WORLD_IO, "a map file that cannot be read"),
    input(
        code::UNKNOWN_TOWN,
        "a town that is neither built in nor an `.xodr` path",
    ),
    input(
        code::DATASET_REFUSED,
        "`--out` holds something other than a dataset of this spec and plan (nothing is written)",
    ),
    input(
        code::SHARD_INVALID,
        "a shard that does not exist (`--shard I/N` with I >= N, or a cluster engine's environment that says so)",
    ),
    input(
        code::MERGE_MISMATCH,
        "`pedsynth merge` was given a directory that is not a dataset of the same spec and plan",
    ),
    input(
        code::MERGE_INCOMPLETE,
        "`pedsynth merge` found clips finished in no directory given (the manifest lists them as pending)",
    ),
    environment(
        code::DATASET_LOCKED,
        "another `pedsynth generate` is writing into `--out` (it holds `.pedsynth.lock`; nothing is written)",
    ),
    input(
        code::DATASET_INVALID,
        "a directory that cannot be read as a pedsynth dataset (missing or malformed manifest or tables)",
    ),
    input(
        code::PROTOCOL_OPTIONS,
        "`stats --protocol` options that the benchmark's sampling does not define (a track shorter than its windows)",
    ),
    environment(code::IO_READ, "a file or directory cannot be read"),
    environment(
        code::IO_WRITE,
        "a file or directory cannot be written (disk full, permissions, read-only file system)",
    ),
    environment(code::IO_OUTPUT, "standard output or standard error cannot be written"),
    environment(code::IO_THREADS, "worker threads cannot be started"),
    environment(
        code::INTERNAL_SERIALIZE,
        "a value of pedsynth's own cannot be serialised (a bug: please report it)",
    ),
];

/// The registry entry of `code`.
pub fn code_info(code: &str) -> Option<&'static CodeInfo> {
    CODES.iter().find(|c| c.code == code)
}

/// README.md's table of diagnostic codes (generated; a test keeps README.md in step).
pub fn codes_markdown() -> String {
    let mut out = String::from("| code | exit | meaning |\n|---|---|---|\n");
    for c in CODES {
        out.push_str(&format!("| `{}` | {} | {} |\n", c.code, c.kind.exit_code(), c.meaning));
    }
    out
}

/// The JSON text of `value` (pretty-printed with `pretty`). A failure is an error, never an empty text.
pub fn to_json<T: serde::Serialize + ?Sized>(value: &T, pretty: bool) -> Result<String, Error> {
    let result = if pretty {
        serde_json::to_string_pretty(value)
    } else {
        serde_json::to_string(value)
    };
    result.map_err(|e| Error::new(code::INTERNAL_SERIALIZE, format!("cannot serialise to JSON: {e}")))
}

/// An error any command can report.
#[derive(Debug)]
pub enum Error {
    /// A spec with problems, rendered with the lines of the spec they point at.
    Spec(SpecErrors),
    /// A road network that cannot be loaded.
    World(WorldError),
    /// Any other failure.
    Other {
        /// Stable code (registered in [`CODES`]).
        code: &'static str,
        /// What went wrong, naming the file or value concerned.
        message: String,
        /// How to fix it.
        help: Option<String>,
    },
    /// Several errors (e.g. `validate` of several specs), reported together.
    Many(Vec<Error>),
}

impl Error {
    /// An error with a registered `code` and a message.
    pub fn new(code: &'static str, message: impl Into<String>) -> Error {
        Error::Other {
            code,
            message: message.into(),
            help: None,
        }
    }

    /// The same error with a hint on how to fix it.
    pub fn help(self, help: impl Into<String>) -> Error {
        match self {
            Error::Other { code, message, .. } => Error::Other {
                code,
                message,
                help: Some(help.into()),
            },
            other => other,
        }
    }

    /// A failure to read `path`.
    pub fn read(path: &std::path::Path, err: impl std::fmt::Display) -> Error {
        Error::new(code::IO_READ, format!("cannot read {}: {err}", path.display()))
    }

    /// A failure to write `path`.
    pub fn write(path: &std::path::Path, err: impl std::fmt::Display) -> Error {
        Error::new(code::IO_WRITE, format!("cannot write {}: {err}", path.display()))
    }

    /// A failure to write to standard output or standard error.
    pub fn output(err: impl std::fmt::Display) -> Error {
        Error::new(code::IO_OUTPUT, format!("cannot write the output: {err}"))
    }

    /// The error's code (the first one's, for several).
    pub fn code(&self) -> &'static str {
        match self {
            Error::Spec(e) => e.codes().first().copied().unwrap_or(spec::IO),
            Error::World(e) => match e {
                WorldError::XodrSyntax { .. } => code::XODR_SYNTAX,
                WorldError::XodrInvalid { .. } => code::XODR_INVALID,
                WorldError::XodrTooLarge { .. } => code::XODR_TOO_LARGE,
                WorldError::Io { .. } => code::WORLD_IO,
                WorldError::UnknownTown { .. } => code::UNKNOWN_TOWN,
            },
            Error::Other { code, .. } => code,
            Error::Many(errors) => errors.first().map_or(code::IO_OUTPUT, Error::code),
        }
    }

    /// The error's kind: the environment's if any part is an environment failure, else the input's.
    pub fn kind(&self) -> Kind {
        match self {
            Error::Many(errors) if errors.iter().any(|e| e.kind() == Kind::Environment) => Kind::Environment,
            Error::Many(_) => Kind::Input,
            other => code_info(other.code()).map_or(Kind::Environment, |c| c.kind),
        }
    }

    /// The error rendered for a terminal (no colour, fixed width), ending with a newline.
    pub fn render(&self) -> String {
        match self {
            Error::Spec(e) => e.render_plain(crate::commands::DIAGNOSTIC_WIDTH),
            Error::World(e) => crate::commands::render_diagnostic(e),
            Error::Other { code, message, help } => {
                let mut out = format!("{code}\n\n  × {message}\n");
                if let Some(help) = help {
                    out.push_str(&format!("  help: {help}\n"));
                }
                out
            }
            Error::Many(errors) => errors.iter().map(Error::render).collect(),
        }
    }
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Spec(e) => write!(f, "{} problem(s) in spec {}", e.problems.len(), e.name),
            Error::World(e) => write!(f, "{e}"),
            Error::Other { message, .. } => f.write_str(message),
            Error::Many(errors) => {
                for (i, e) in errors.iter().enumerate() {
                    if i > 0 {
                        f.write_str("; ")?;
                    }
                    write!(f, "{e}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for Error {}

impl From<SpecErrors> for Error {
    fn from(e: SpecErrors) -> Self {
        Error::Spec(e)
    }
}

impl From<WorldError> for Error {
    fn from(e: WorldError) -> Self {
        Error::World(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_well_formed() {
        let mut seen = std::collections::BTreeSet::new();
        for c in CODES {
            assert!(seen.insert(c.code), "{} listed twice", c.code);
            let parts: Vec<&str> = c.code.split("::").collect();
            assert!(
                parts.len() == 3
                    && parts[0] == "pedsynth"
                    && parts[1..].iter().all(|p| !p.is_empty()
                        && p.chars()
                            .all(|ch| ch.is_ascii_lowercase() || ch == '_' || ch.is_ascii_digit())),
                "{}",
                c.code
            );
        }
    }

    #[test]
    fn the_kind_decides_the_exit_code() {
        assert_eq!(Error::new(code::IO_WRITE, "disk full").kind().exit_code(), 1);
        assert_eq!(Error::new(code::PLAN_INVALID, "not a plan").kind().exit_code(), 2);
        let many = Error::Many(vec![
            Error::new(code::PLAN_INVALID, "a"),
            Error::new(code::IO_READ, "b"),
        ]);
        assert_eq!(many.kind(), Kind::Environment);
    }
}
