//! docs/case-file.md cannot drift from the code: every key of the raw case structures is
//! documented, every documented key is accepted, and every example case file runs through
//! validation.

use std::collections::BTreeSet;

const RAW: &str = include_str!("../src/raw.rs");
const DOC: &str = include_str!("../../../docs/case-file.md");

/// Field names declared as `pub name:` in raw.rs.
fn code_keys() -> BTreeSet<String> {
    RAW.lines()
        .filter_map(|l| l.trim().strip_prefix("pub "))
        .filter_map(|l| l.split_once(':').map(|(name, _)| name.trim().to_string()))
        .filter(|n| n.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
        .collect()
}

/// Keys in the first column of the documentation's tables.
fn doc_keys() -> BTreeSet<String> {
    DOC.lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split_once('`').map(|(k, _)| k.to_string()))
        .collect()
}

#[test]
fn every_case_file_key_is_documented_and_every_documented_key_exists() {
    let code = code_keys();
    let doc = doc_keys();
    // Table names are keys in raw.rs but headings in the documentation.
    let tables = [
        "domain",
        "physics",
        "phases",
        "wall_materials",
        "walls",
        "meshes",
        "cylinders",
        "surface",
        "contact",
        "particle",
        "wall",
        "pairs",
        "time",
        "neighbor",
        "output",
        "parallel",
        "particles",
        "list",
        "motion",
        "params",
        "insertions",
        "outlets",
        "region",
    ];
    let undocumented: Vec<_> =
        code.iter().filter(|k| !doc.contains(*k) && !tables.contains(&k.as_str())).collect();
    assert!(undocumented.is_empty(), "keys without a row in docs/case-file.md: {undocumented:?}");
    let unknown: Vec<_> = doc.iter().filter(|k| !code.contains(*k)).collect();
    assert!(unknown.is_empty(), "documented keys the code does not read: {unknown:?}");
    assert!(code.len() > 40, "the key scan found only {} keys", code.len());
}

#[test]
fn example_cases_validate() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
    let mut n = 0;
    for entry in std::fs::read_dir(root).expect("examples folder") {
        let case = entry.expect("entry").path().join("case.toml");
        if case.exists() {
            grainflow_case::load(&case).unwrap_or_else(|e| panic!("{}: {e}", case.display()));
            n += 1;
        }
    }
    assert!(n >= 2, "only {n} examples");
}

/// Every TOML case shown in the documentation validates and runs to its end.
#[test]
fn case_files_in_the_docs_run() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut found = 0;
    for doc in ["README.md", "docs/tutorial.md", "docs/case-file.md", "docs/models.md"] {
        let text = std::fs::read_to_string(root.join(doc)).expect("doc");
        let mut rest = text.as_str();
        while let Some(start) = rest.find("```toml\n") {
            let body = &rest[start + 8..];
            let end = body.find("```").expect("closed block");
            let case = grainflow_case::parse(&body[..end], doc, &|name: &str| {
                Err(grainflow_case::CaseError::Read {
                    path: name.into(),
                    source: std::io::Error::other("docs cases are self-contained"),
                })
            })
            .unwrap_or_else(|e| panic!("{doc}: a case file does not validate: {e}"));
            let mut sim = grainflow::Simulation::new(case.config, case.particles)
                .unwrap_or_else(|e| panic!("{doc}: {e}"));
            let e0 = sim.diagnostics().total_energy();
            sim.run_to_end();
            // Damped collisions and gravity: the total energy can only go down (a bound that
            // fails on a blow-up, which is what a documentation case must not do).
            let e1 = sim.diagnostics().total_energy();
            assert!(e1.is_finite() && e1 <= e0 * (1.0 + 1e-9) + 1e-12, "{doc}: energy {e0} -> {e1}");
            found += 1;
            rest = &body[end..];
        }
    }
    assert!(found >= 1, "no case file found in the docs");
}
