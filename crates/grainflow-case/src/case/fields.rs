//! The field helpers every table's validator uses: a required key, a value in its range, a
//! word from a list, a finite vector, and "did you mean" for a misspelt key.

use crate::error::CaseError;
use grainflow::Vec3;
use grainflow::contact::limits::Range;

/// one of the expected keys is close to the unknown one, or the unknown one is the MFIX (or
/// another code's) name of an expected key (`mew` → `mu`).
pub(crate) fn did_you_mean(message: String) -> String {
    let Some(start) = message.find("unknown field `") else { return message };
    let rest = &message[start + 15..];
    let Some(end) = rest.find('`') else { return message };
    let unknown = &rest[..end];
    let Some(list) = rest.find("expected one of ").map(|k| &rest[k + 16..]) else { return message };
    let expected: Vec<&str> = list
        .split(',')
        .map(|w| w.trim().trim_matches(|c: char| c == '`' || c.is_whitespace() || c == '.'))
        .filter(|w| !w.is_empty())
        .collect();
    let alias = ALIASES
        .iter()
        .find(|(a, k)| a.eq_ignore_ascii_case(unknown) && expected.contains(k))
        .map(|(a, k)| (*k, format!(" (`{a}` is its name in MFIX or other codes)")));
    let best = alias
        .or_else(|| crate::error::closest(unknown, expected.iter().copied()).map(|w| (w, String::new())));
    match best {
        Some((w, why)) => format!("{}\ndid you mean `{w}`?{why}", message.trim_end()),
        None => message,
    }
}

/// Names users bring from MFIX decks and other DEM codes, and the case-file key they mean.
const ALIASES: &[(&str, &str)] = &[
    ("mew", "mu"),
    ("mew_w", "mu"),
    ("friction", "mu"),
    ("mew_r", "mu_roll"),
    ("mew_rw", "mu_roll"),
    ("rolling_friction", "mu_roll"),
    ("des_en_input", "en"),
    ("des_en_wall_input", "en"),
    ("restitution", "en"),
    ("e_n", "en"),
    ("des_et_input", "et"),
    ("e_t", "et"),
    ("kn_w", "kn"),
    ("k_n", "kn"),
    ("kt_w_fac", "kt_fac"),
    ("des_etat_fac", "etat_fac"),
    ("des_etat_w_fac", "etat_fac"),
    ("d_p0", "diameter"),
    ("ro_s0", "density"),
    ("rho", "density"),
    ("e_young", "youngs_modulus"),
    ("ew_young", "youngs_modulus"),
    ("young", "youngs_modulus"),
    ("youngs", "youngs_modulus"),
    ("v_poisson", "poisson_ratio"),
    ("vw_poisson", "poisson_ratio"),
    ("poisson", "poisson_ratio"),
    ("nu", "poisson_ratio"),
    ("tstop", "t_stop"),
    ("time", "t_start"),
    ("des_intg_method", "integrator"),
    ("factor_rlm", "skin"),
];

pub(crate) fn require<T>(v: Option<T>, table: &str, key: &str, hint: &str) -> Result<T, CaseError> {
    v.ok_or_else(|| CaseError::missing(table, key, hint))
}

pub(crate) fn check(r: Range, table: &str, key: &str, v: f64) -> Result<f64, CaseError> {
    if r.contains(v) { Ok(v) } else { Err(CaseError::invalid(table, key, v, r.valid)) }
}

pub(crate) fn choose<T: Copy>(
    table: &str,
    key: &str,
    value: Option<&str>,
    default: T,
    words: &[(&str, T)],
) -> Result<T, CaseError> {
    let Some(v) = value else { return Ok(default) };
    words.iter().find(|(w, _)| *w == v).map(|(_, t)| *t).ok_or_else(|| {
        let list: Vec<String> = words.iter().map(|(w, _)| format!("\"{w}\"")).collect();
        CaseError::invalid(table, key, format!("\"{v}\""), format!("must be one of {}", list.join(", ")))
    })
}

pub(crate) fn vec3(a: [f64; 3], table: &str, key: &str) -> Result<Vec3, CaseError> {
    let v = Vec3::from_array(a);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CaseError::invalid(table, key, format!("{a:?}"), "all three components must be finite numbers"))
    }
}
