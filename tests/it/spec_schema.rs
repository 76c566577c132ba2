//! The committed JSON Schema (`schemas/pedsynth-spec.schema.json`) equals `pedsynth schema`, accepts every
//! spec in `specs/` and rejects unknown keys, checked with an independent validator (the `jsonschema` crate).
//! Rewrite the committed schema with `INSTA_UPDATE=always cargo test` (the project's one update switch).

use std::path::{Path, PathBuf};

use pedsynth::spec::{schema, tree};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn validator() -> jsonschema::Validator {
    jsonschema::draft7::new(&schema::spec_schema()).expect("the schema is valid draft-07")
}

fn yaml_to_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap();
    tree::parse(&text, 0).unwrap().to_json()
}

#[test]
fn committed_schema_is_current() {
    let path = root().join("schemas/pedsynth-spec.schema.json");
    let generated = schema::spec_schema_text().expect("schema");
    if std::env::var("INSTA_UPDATE").as_deref() == Ok("always") {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "schemas/pedsynth-spec.schema.json is stale: run `INSTA_UPDATE=always cargo test --test spec_schema`"
    );
    let json: serde_json::Value = serde_json::from_str(&committed).unwrap();
    assert_eq!(json["$schema"], "http://json-schema.org/draft-07/schema#");
}

#[test]
fn schema_accepts_every_shipped_spec() {
    let validator = validator();
    let mut specs: Vec<PathBuf> = std::fs::read_dir(root().join("specs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    specs.sort();
    assert!(specs.len() >= 4);
    for path in specs {
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("# yaml-language-server: $schema=../schemas/pedsynth-spec.schema.json"),
            "{}",
            path.display()
        );
        let errors: Vec<String> = validator
            .iter_errors(&yaml_to_json(&path))
            .map(|e| e.to_string())
            .collect();
        assert!(errors.is_empty(), "{}: {errors:?}", path.display());
    }
}

#[test]
fn schema_rejects_unknown_keys_and_names() {
    let validator = validator();
    for bad in [
        "unknown_key.yaml",
        "many_problems.yaml",
        "unknown_names.yaml",
        "wrong_type.yaml",
    ] {
        let json = yaml_to_json(&root().join("tests/data/bad_specs").join(bad));
        assert!(!validator.is_valid(&json), "{bad} should be rejected by the schema");
    }
    let custom_weather_typo =
        serde_json::json!({"version": 1, "dataset": {"weathers": [{"name": "x", "fog_densty_pct": 3}]}});
    assert!(!validator.is_valid(&custom_weather_typo));
    let custom_weather =
        serde_json::json!({"version": 1, "dataset": {"weathers": [{"name": "x", "fog_density_pct": 3}]}});
    assert!(validator.is_valid(&custom_weather));
    assert!(
        !validator.is_valid(&serde_json::json!({"dataset": {}})),
        "version is required"
    );
}
