//! The documented contact models are the registry's: the case-file reference lists exactly
//! the names of `NormalModel::NAMES` and `TangentialModel::NAMES` (the case layer's tables for
//! `[contact] model` and `tangential` are the registries' `CHOICES`), and docs/models.md
//! describes each.

use grainflow::contact::{NormalModel, TangentialModel};

const CASE_FILE: &str = include_str!("../../../docs/case-file.md");
const MODELS: &str = include_str!("../../../docs/models.md");

/// The quoted names in the "valid" column of the `[contact]` row for `key`.
fn documented_names(key: &str) -> Vec<String> {
    let start = format!("| `{key}` |");
    let rows: Vec<&str> = CASE_FILE.lines().filter(|l| l.starts_with(&start)).collect();
    assert_eq!(rows.len(), 1, "one row for `{key}` in docs/case-file.md: {rows:?}");
    let valid = rows[0].split('|').nth(4).expect("a valid column");
    valid.split(',').map(|w| w.trim().trim_matches('`').trim_matches('"').to_string()).collect()
}

#[test]
fn the_case_file_reference_lists_the_registered_models() {
    assert_eq!(documented_names("model"), NormalModel::NAMES, "[contact] model in docs/case-file.md");
    assert_eq!(
        documented_names("tangential"),
        TangentialModel::NAMES,
        "[contact] tangential in docs/case-file.md"
    );
}

#[test]
fn every_registered_model_is_described_in_the_models_page() {
    for name in NormalModel::NAMES {
        let heading = format!("(`model = \"{name}\"`");
        assert!(
            MODELS.lines().any(|l| l.starts_with("## ") && l.contains(&heading)),
            "docs/models.md has no section for model = \"{name}\""
        );
    }
    for name in TangentialModel::NAMES {
        let setting = format!("`tangential = \"{name}\"`");
        assert!(MODELS.contains(&setting), "docs/models.md does not describe {setting}");
    }
}
