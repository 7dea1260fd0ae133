//! docs/mfix-decks.md cannot drift from the keyword table in the code: every keyword the code
//! knows is documented, and every keyword the documentation's tables list is known.

use grainflow_case::mfix::keywords::{KEYWORDS, Role, lookup};

const DOC: &str = include_str!("../../../docs/mfix-decks.md");

/// Backticked upper-case keywords in a table cell, subscripts removed: `D_P0(m)` → D_P0.
fn keywords_in(cell: &str) -> Vec<String> {
    cell.split('`')
        .skip(1)
        .step_by(2)
        .map(|w| w.split('(').next().unwrap_or("").to_string())
        .filter(|w| {
            w.len() > 1
                && w.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_' || c == '*')
                && w.chars().next().is_some_and(|c| c.is_ascii_uppercase())
        })
        .collect()
}

/// The keyword cells of the documentation's tables: first column of the used/checked and
/// refused tables, second column of the ignored table.
fn documented() -> Vec<(String, &'static str)> {
    let mut section = "";
    let mut out = Vec::new();
    for line in DOC.lines() {
        if let Some(h) = line.strip_prefix("## ") {
            section = match h {
                "Used and checked keywords" => "used",
                "Ignored keywords" => "ignored",
                "Refused keywords" => "refused",
                _ => "",
            };
            continue;
        }
        if section.is_empty() || !line.starts_with("| ") || line.starts_with("|---") {
            continue;
        }
        let cells: Vec<&str> = line.split('|').collect();
        let cell = if section == "ignored" { cells.get(2) } else { cells.get(1) };
        for k in keywords_in(cell.copied().unwrap_or("")) {
            out.push((k, section));
        }
    }
    out
}

#[test]
fn every_keyword_of_the_code_is_documented_in_its_role() {
    let doc = documented();
    assert!(doc.len() > 200, "the table scan found only {} keywords", doc.len());
    let mut missing = Vec::new();
    for k in KEYWORDS {
        let section = match k.role {
            Role::Used | Role::Checked => "used",
            Role::Ignored(_) => "ignored",
            Role::Refused(..) => "refused",
        };
        if !doc.iter().any(|(name, s)| name == k.name && *s == section) {
            missing.push(format!("{} ({section})", k.name));
        }
    }
    assert!(missing.is_empty(), "keywords without a row in their table of docs/mfix-decks.md: {missing:?}");
}

#[test]
fn every_documented_keyword_is_known() {
    let unknown: Vec<String> = documented()
        .into_iter()
        .filter(|(k, _)| !KEYWORDS.iter().any(|kw| kw.name == k) && lookup(k).is_none())
        .map(|(k, s)| format!("{k} ({s})"))
        .collect();
    assert!(unknown.is_empty(), "documented keywords the code does not know: {unknown:?}");
}
