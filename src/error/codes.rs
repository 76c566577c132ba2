//! The registry of every stable diagnostic code (`pedsynth::<area>::<what>`), each with its [`Kind`], which
//! decides the exit code. README.md's table of codes is generated from [`CODES`] (a test fails when the two
//! drift, and another when a code appears in the source but not here).

use super::Kind;

/// Stable diagnostic codes of the spec language; tests pin them.
pub mod spec {
    /// The YAML could not be parsed.
    pub const YAML_SYNTAX: &str = "pedsynth::spec::yaml_syntax";
    /// The YAML exceeds the parser's budget (alias bombs, deep nesting, huge documents).
    pub const YAML_BUDGET: &str = "pedsynth::spec::yaml_budget";
    /// The file holds no YAML document.
    pub const EMPTY: &str = "pedsynth::spec::empty";
    /// The file is not UTF-8.
    pub const NOT_UTF8: &str = "pedsynth::spec::not_utf8";
    /// A mapping key appears twice.
    pub const DUPLICATE_KEY: &str = "pedsynth::spec::duplicate_key";
    /// A key the spec language does not know.
    pub const UNKNOWN_KEY: &str = "pedsynth::spec::unknown_key";
    /// A required key is missing.
    pub const MISSING_KEY: &str = "pedsynth::spec::missing_key";
    /// A value of the wrong type.
    pub const WRONG_TYPE: &str = "pedsynth::spec::wrong_type";
    /// A number outside its allowed range.
    pub const OUT_OF_RANGE: &str = "pedsynth::spec::out_of_range";
    /// A `[min, max]` range with min > max.
    pub const EMPTY_RANGE: &str = "pedsynth::spec::empty_range";
    /// A mix whose shares do not sum to 1.
    pub const MIX_SUM: &str = "pedsynth::spec::mix_sum";
    /// An unknown weather, town, archetype, profile or other name.
    pub const UNKNOWN_NAME: &str = "pedsynth::spec::unknown_name";
    /// A name used twice where names must be unique.
    pub const DUPLICATE_NAME: &str = "pedsynth::spec::duplicate_name";
    /// A name that is not a valid identifier.
    pub const INVALID_NAME: &str = "pedsynth::spec::invalid_name";
    /// A target crossing ratio the enabled layers cannot reach.
    pub const UNREACHABLE_TARGET: &str = "pedsynth::spec::unreachable_target";
    /// A spec language version this build does not understand.
    pub const UNSUPPORTED_VERSION: &str = "pedsynth::spec::unsupported_version";
    /// A spec beyond the sanity limits.
    pub const TOO_LARGE: &str = "pedsynth::spec::too_large";
    /// A referenced file that does not exist or cannot be read.
    pub const MISSING_FILE: &str = "pedsynth::spec::missing_file";
    /// A malformed `--set` override.
    pub const BAD_OVERRIDE: &str = "pedsynth::spec::bad_override";
    /// A key whose feature this pedsynth version does not implement yet (accepted by the schema so that specs
    /// written for a later version get a clear message rather than "unknown key").
    pub const NOT_IMPLEMENTED: &str = "pedsynth::spec::not_implemented";
    /// The spec file cannot be read.
    pub const IO: &str = "pedsynth::spec::io";
}

/// Codes of the areas beyond the spec language (whose codes are in [`spec`]).
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
    /// Real annotations given to `pedsynth calibrate` that cannot be read or used (missing files, wrong layout,
    /// an empty split).
    pub const REAL_INVALID: &str = "pedsynth::calibrate::real_invalid";
    /// Options of `stats --protocol` that the protocol does not define.
    pub const PROTOCOL_OPTIONS: &str = "pedsynth::dataset::protocol_options";
    /// Options of `export` that its format cannot use (a keyframe rate of 0 Hz, a clip the dataset does not have).
    pub const EXPORT_OPTIONS: &str = "pedsynth::dataset::export_options";
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
        code::REAL_INVALID,
        "real annotations `calibrate` cannot use (missing files, wrong layout, an empty split, too few boxes)",
    ),
    input(
        code::PROTOCOL_OPTIONS,
        "`stats --protocol` options that the benchmark's sampling does not define (a track shorter than its windows)",
    ),
    input(
        code::EXPORT_OPTIONS,
        "`export` options that its format cannot use (a keyframe rate of 0 Hz, a clip the dataset does not have)",
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
