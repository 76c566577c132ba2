//! Spec language: the typed spec, its YAML loader with pinpointed diagnostics, validation and JSON Schema.
//!
//! Pipeline: `load` parses YAML into a spanned `tree`, applies `--set` overrides, `check`s the tree against the
//! schema generated from `types`, merges it onto the paper's defaults, deserialises the typed spec and runs
//! `validate`. Every problem becomes a `diagnostic` pointing at the exact key or value.
pub mod check;
pub mod diagnostic;
pub mod load;
pub mod not_yet;
pub mod schema;
pub mod tree;
pub mod types;
pub mod validate;

pub use diagnostic::{Problem, SpecErrors};
pub use load::{LoadOptions, LoadedSpec, load_bytes, load_file, spec_hash, to_yaml};
pub use types::Spec;
