//! The assignments of a deck, by keyword and subscript, with typed access that reports bad
//! values with their line.

use super::keywords::{self, Keyword, Ty};
use super::lexer::{self, Assignment, Loc, Sub, Value};
use crate::error::CaseError;
use std::collections::BTreeMap;

/// One assigned element.
#[derive(Debug, Clone)]
pub struct Entry {
    /// The value (`None`: a null value, which leaves the element unset).
    pub value: Option<Value>,
    /// Where it was assigned (the last assignment wins, as in a Fortran namelist).
    pub loc: Loc,
}

/// Everything assigned to one keyword.
#[derive(Debug, Clone)]
pub struct Given {
    /// The keyword's table entry, `None` if unknown.
    pub spec: Option<&'static Keyword>,
    /// Elements by subscript (empty for a scalar).
    pub entries: BTreeMap<Vec<i64>, Entry>,
    /// Where the keyword first appears.
    pub first: Loc,
}

/// A typed value with where it came from, for messages.
#[derive(Debug, Clone)]
pub struct Got<T> {
    /// The value (in the deck's units).
    pub v: T,
    /// Where it was assigned.
    pub loc: Loc,
    /// The keyword with its subscript, e.g. `DES_EN_INPUT(2)`.
    pub key: String,
    /// The value as written.
    pub text: String,
}

/// The deck's assignments.
#[derive(Debug, Default)]
pub struct Deck {
    /// By upper-case keyword.
    pub given: BTreeMap<String, Given>,
    /// Keywords in the order they first appear.
    pub order: Vec<String>,
    /// Elements assigned twice in the deck file itself: (key, first, second).
    pub repeated: Vec<(String, Loc, Loc)>,
}

/// Shows a keyword with its subscript: `KN`, `D_P0(2)`, `BC_UW_S(1,2)`.
pub fn show(key: &str, idx: &[i64]) -> String {
    if idx.is_empty() {
        key.to_string()
    } else {
        let list: Vec<String> = idx.iter().map(|i| i.to_string()).collect();
        format!("{key}({})", list.join(","))
    }
}

impl Deck {
    /// Records an assignment; later ones override earlier ones element by element.
    pub fn assign(&mut self, a: Assignment) -> Result<(), CaseError> {
        let spec = keywords::lookup(&a.key);
        let dims = spec.and_then(|s| s.dims);
        let base = spec.map_or(1, |s| s.base);
        let bad = |valid: String| {
            let written: Vec<String> = a.values.iter().flatten().map(Value::written).collect();
            CaseError::invalid(a.loc.to_string(), subscript_text(&a), written.join(" "), valid)
        };
        let n = a.values.len();
        // The subscripts the values go to.
        let targets: Vec<Vec<i64>> = match (&a.subscript, dims) {
            (None, Some(0)) => {
                if n != 1 {
                    return Err(bad(format!("{} takes one value, found {n}", a.key)));
                }
                vec![vec![]]
            }
            (None, None) if n == 1 => vec![vec![]],
            (None, Some(d)) => (0..n as i64)
                .map(|k| std::iter::once(base + k).chain((1..d).map(|_| base)).collect())
                .collect(),
            (None, None) => (0..n as i64).map(|k| vec![base + k]).collect(),
            (Some(_), Some(0)) => {
                return Err(bad(format!(
                    "{} is a single value and takes no subscript; write `{} = value`",
                    a.key, a.key
                )));
            }
            (Some(subs), d) => {
                if let Some(d) = d
                    && subs.len() != d as usize
                {
                    return Err(bad(format!(
                        "{} takes {d} subscript{}, e.g. {}",
                        a.key,
                        if d == 1 { "" } else { "s" },
                        show(&a.key, &vec![1; d as usize])
                    )));
                }
                // The values run along the subscript that is a range (any one of them, as
                // MFIX reads `BC_U_S(1,1:5)`), else along the first from its index on.
                let ranges: Vec<usize> =
                    (0..subs.len()).filter(|&k| matches!(subs[k], Sub::Range(..))).collect();
                if ranges.len() > 1 {
                    return Err(bad("only one subscript may be a range".into()));
                }
                let along = ranges.first().copied().unwrap_or(0);
                let mut fixed: Vec<i64> = subs
                    .iter()
                    .map(|s| match s {
                        Sub::Index(i) => *i,
                        Sub::Range(i, _) => *i,
                    })
                    .collect();
                if let Sub::Range(i, j) = subs[along] {
                    let room = (j - i + 1) as usize;
                    if n > room {
                        return Err(bad(format!("{n} values for a range of {room} elements")));
                    }
                }
                if let Some(low) = fixed.iter().copied().find(|&i| i < base) {
                    return Err(bad(format!("subscript {low} is below the first element, {base}")));
                }
                let start = fixed[along];
                (0..n as i64)
                    .map(|k| {
                        fixed[along] = start + k;
                        fixed.clone()
                    })
                    .collect()
            }
        };
        let key = a.key.clone();
        if !self.given.contains_key(&key) {
            self.order.push(key.clone());
        }
        let given = self.given.entry(key.clone()).or_insert_with(|| Given {
            spec,
            entries: BTreeMap::new(),
            first: a.loc.clone(),
        });
        for (idx, value) in targets.into_iter().zip(a.values) {
            if value.is_none() {
                continue;
            }
            let entry = Entry { value, loc: a.loc.clone() };
            if let Some(old) = given.entries.insert(idx.clone(), entry)
                && matches!((&old.loc, &a.loc), (Loc::Line { .. }, Loc::Line { .. }))
            {
                self.repeated.push((show(&key, &idx), old.loc, a.loc.clone()));
            }
        }
        Ok(())
    }

    /// True if the keyword was given at all.
    pub fn has(&self, key: &str) -> bool {
        self.given.get(key).is_some_and(|g| !g.entries.is_empty())
    }

    /// The raw entry of `key` at `idx`.
    pub fn entry(&self, key: &str, idx: &[i64]) -> Option<&Entry> {
        self.given.get(key).and_then(|g| g.entries.get(idx))
    }

    /// Every assigned subscript of `key`.
    pub fn indices(&self, key: &str) -> Vec<Vec<i64>> {
        self.given.get(key).map(|g| g.entries.keys().cloned().collect()).unwrap_or_default()
    }

    fn got<T>(
        &self,
        key: &str,
        idx: &[i64],
        conv: impl Fn(&Value) -> Result<T, String>,
    ) -> Result<Option<Got<T>>, CaseError> {
        let Some(e) = self.entry(key, idx) else { return Ok(None) };
        let Some(value) = &e.value else { return Ok(None) };
        let shown = show(key, idx);
        conv(value)
            .map(|v| Some(Got { v, loc: e.loc.clone(), key: shown.clone(), text: value.written() }))
            .map_err(|valid| CaseError::invalid(e.loc.to_string(), shown, value.written(), valid))
    }

    /// A real value (numbers and `@( )` arithmetic).
    pub fn real(&self, key: &str, idx: &[i64]) -> Result<Option<Got<f64>>, CaseError> {
        self.got(key, idx, to_real)
    }

    /// A whole number.
    pub fn int(&self, key: &str, idx: &[i64]) -> Result<Option<Got<i64>>, CaseError> {
        self.got(key, idx, |v| match v {
            Value::Word(w) => w
                .trim_start_matches('+')
                .parse::<i64>()
                .map_err(|_| format!("`{w}` is not a whole number; write e.g. 3")),
            Value::Expr(e) => {
                let x = lexer::eval_expr(e).map_err(|m| format!("cannot evaluate @({e}): {m}"))?;
                if x.fract() == 0.0 && x.abs() < 9e15 {
                    Ok(x as i64)
                } else {
                    Err(format!("@({e}) = {x} is not a whole number"))
                }
            }
            Value::Str(s) => Err(format!("'{s}' is a string; a whole number is expected, e.g. 3")),
        })
    }

    /// A logical.
    pub fn bool(&self, key: &str, idx: &[i64]) -> Result<Option<Got<bool>>, CaseError> {
        self.got(key, idx, |v| match v {
            Value::Word(w) => match w.to_ascii_uppercase().as_str() {
                ".T." | ".TRUE." | "T" | "TRUE" | ".T" | ".TRUE" => Ok(true),
                ".F." | ".FALSE." | "F" | "FALSE" | ".F" | ".FALSE" => Ok(false),
                _ => Err(format!("`{w}` is not a logical; write .TRUE. or .FALSE. (or .T., .F.)")),
            },
            other => Err(format!("{} is not a logical; write .TRUE. or .FALSE.", other.written())),
        })
    }

    /// A string, upper-cased when `upper` (MFIX compares keyword words case-insensitively).
    pub fn string(&self, key: &str, idx: &[i64], upper: bool) -> Result<Option<Got<String>>, CaseError> {
        self.got(key, idx, |v| match v {
            Value::Str(s) | Value::Word(s) => {
                Ok(if upper { s.trim().to_ascii_uppercase() } else { s.trim().to_string() })
            }
            Value::Expr(e) => Err(format!("@({e}) is arithmetic; a quoted word is expected, e.g. 'DEM'")),
        })
    }

    /// Checks that every value of a typed keyword has its type (so a typo in a keyword that
    /// ends up unused is still reported).
    pub fn check_types(&self) -> Result<(), CaseError> {
        for key in &self.order {
            let Some(g) = self.given.get(key) else { continue };
            let Some(spec) = g.spec else { continue };
            for idx in g.entries.keys() {
                match spec.ty {
                    Ty::Real => self.real(key, idx).map(|_| ())?,
                    Ty::Int => self.int(key, idx).map(|_| ())?,
                    Ty::Bool => self.bool(key, idx).map(|_| ())?,
                    Ty::Str => self.string(key, idx, false).map(|_| ())?,
                    Ty::Any => {}
                }
            }
        }
        Ok(())
    }
}

fn subscript_text(a: &Assignment) -> String {
    match &a.subscript {
        None => a.key.clone(),
        Some(subs) => {
            let parts: Vec<String> = subs
                .iter()
                .map(|s| match s {
                    Sub::Index(i) => i.to_string(),
                    Sub::Range(i, j) => format!("{i}:{j}"),
                })
                .collect();
            format!("{}({})", a.key, parts.join(","))
        }
    }
}

/// A value as a real number.
pub fn to_real(v: &Value) -> Result<f64, String> {
    match v {
        Value::Word(w) => lexer::fortran_number(w).ok_or_else(|| {
            format!("`{w}` is not a number; write e.g. 1.0, 2.5e-3 or 2.5d-3 (or arithmetic: @(1.0/3.0))")
        }),
        Value::Expr(e) => lexer::eval_expr(e).map_err(|m| format!("cannot evaluate @({e}): {m}")),
        Value::Str(s) => Err(format!("'{s}' is a string; a number is expected, e.g. 1.0e4")),
    }
}
