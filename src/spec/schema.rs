//! The JSON Schema of the spec, generated from the spec types (draft-07, for yaml-language-server).

use schemars::generate::SchemaSettings;

use super::types::Spec;

/// The spec's JSON Schema as a JSON value.
pub fn spec_schema() -> serde_json::Value {
    let generator = SchemaSettings::draft07().into_generator();
    let schema = generator.into_root_schema_for::<Spec>();
    schema.to_value()
}

/// The spec's JSON Schema as pretty-printed text with a trailing newline (the committed file's content).
pub fn spec_schema_text() -> Result<String, crate::error::Error> {
    let mut text = crate::error::to_json(&spec_schema(), true)?;
    text.push('\n');
    Ok(text)
}
