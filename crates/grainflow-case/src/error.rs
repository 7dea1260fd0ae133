//! Errors in case files and particle files. Every message names where the problem is (table
//! and key, or file and line), the value, and what would be valid.

use std::path::PathBuf;
use thiserror::Error;

/// A problem with the user's input.
#[derive(Debug, Error)]
pub enum CaseError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The TOML itself is malformed, or a key is unknown or of the wrong type.
    #[error("{0}")]
    Syntax(String),
    /// A required key is missing.
    #[error("{table}: missing required key `{key}` ({hint})")]
    Missing {
        /// The table, e.g. `[time]`.
        table: String,
        /// The key.
        key: String,
        /// What it means and its unit.
        hint: String,
    },
    /// A value is outside its valid range or not one of the accepted words.
    #[error("{table}: `{key}` = {value} is invalid: {valid}")]
    Invalid {
        /// The table, e.g. `[contact.particle]`.
        table: String,
        /// The key.
        key: String,
        /// The value as written.
        value: String,
        /// What would be valid.
        valid: String,
    },
    /// A line of a particle file is malformed.
    #[error("{path}, line {line}: {message}")]
    ParticleFile {
        /// The file.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong and what is expected.
        message: String,
    },
    /// A `[[meshes]]` file that cannot be read or is not a usable mesh; the mesh error's
    /// message names the file and, where it can, the line or triangle at fault.
    #[error("{table}: `file`: {source}")]
    Mesh {
        /// The table, e.g. `[[meshes]] 'floor'`.
        table: String,
        /// What is wrong with the file.
        source: Box<grainflow::mesh::MeshError>,
    },
    /// Particles and walls are placed so that the run cannot start well (outside the domain,
    /// behind a wall, overlapping too much).
    #[error("{0}")]
    Geometry(String),
    /// The engine refused the set-up.
    #[error("{0}")]
    Engine(#[from] grainflow::EngineError),
    /// Several things stop an MFIX deck from running; each is reported, in the deck's order.
    #[error("{}", blockers_text(.0))]
    Blockers(Vec<CaseError>),
}

fn blockers_text(list: &[CaseError]) -> String {
    let mut s = format!(
        "{} thing{} in this input grainflow cannot run:",
        list.len(),
        if list.len() == 1 { "" } else { "s" }
    );
    for (k, e) in list.iter().enumerate() {
        s.push_str(&format!("\n  {}. {e}", k + 1));
    }
    s
}

impl CaseError {
    pub(crate) fn invalid(
        table: impl Into<String>,
        key: impl Into<String>,
        value: impl ToString,
        valid: impl Into<String>,
    ) -> Self {
        CaseError::Invalid {
            table: table.into(),
            key: key.into(),
            value: value.to_string(),
            valid: valid.into(),
        }
    }

    pub(crate) fn missing(table: impl Into<String>, key: impl Into<String>, hint: impl Into<String>) -> Self {
        CaseError::Missing { table: table.into(), key: key.into(), hint: hint.into() }
    }
}

/// The candidate closest to `unknown` for a "did you mean" (case-insensitive
/// Damerau-Levenshtein distance at most `max(2, len/4)` of the candidate). Ties go to the
/// candidate sharing more of the start (Jaro-Winkler), so `mew` suggests `mu`, not `en`.
pub(crate) fn closest<'a>(unknown: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let u = unknown.to_ascii_lowercase();
    let mut best: Option<(usize, f64, &'a str)> = None;
    for c in candidates {
        let l = c.to_ascii_lowercase();
        let d = strsim::damerau_levenshtein(&u, &l);
        if d > 2.max(c.len() / 4) || d >= u.len().max(1) {
            continue;
        }
        let jw = strsim::jaro_winkler(&u, &l);
        if best.is_none_or(|(bd, bj, _)| d < bd || (d == bd && jw > bj)) {
            best = Some((d, jw, c));
        }
    }
    best.map(|b| b.2)
}

#[cfg(test)]
mod tests {
    #[test]
    fn closest_prefers_the_shared_start() {
        let keys = ["kn", "kt_fac", "etat_fac", "en", "et", "mu", "mu_roll", "gamma_n", "gamma_t"];
        assert_eq!(super::closest("mew", keys), Some("mu"));
        assert_eq!(super::closest("kt_fca", keys), Some("kt_fac"));
        // Nothing near: no suggestion.
        assert_eq!(super::closest("colour", keys), None);
    }
}
