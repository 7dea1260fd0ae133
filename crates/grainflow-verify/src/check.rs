//! Checks: a measured error against a tolerance, with pass/fail, and their report as Markdown.

/// Whether a check decides the outcome or is only reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CheckKind {
    /// Must pass.
    Assert,
    /// Reported, never failed (e.g. a known model-versus-experiment deviation).
    Report,
    /// Not run in this invocation (e.g. needs `--converged`).
    Skipped,
}

/// One check of a verification case.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// What is checked, in words.
    pub name: String,
    /// The largest error measured (in the unit of `tolerance`).
    pub error: f64,
    /// The tolerance on `error`.
    pub tolerance: f64,
    /// How the error is measured and where the worst case is.
    pub detail: String,
    /// Assert, report only, or skipped.
    pub kind: CheckKind,
}

impl Check {
    /// An asserted check.
    pub fn assert(name: impl Into<String>, error: f64, tolerance: f64, detail: impl Into<String>) -> Self {
        Check { name: name.into(), error, tolerance, detail: detail.into(), kind: CheckKind::Assert }
    }

    /// A reported-only measurement.
    pub fn report(name: impl Into<String>, error: f64, detail: impl Into<String>) -> Self {
        Check {
            name: name.into(),
            error,
            tolerance: f64::NAN,
            detail: detail.into(),
            kind: CheckKind::Report,
        }
    }

    /// A check not run this time, with the reason.
    pub fn skipped(name: impl Into<String>, why: impl Into<String>) -> Self {
        Check {
            name: name.into(),
            error: f64::NAN,
            tolerance: f64::NAN,
            detail: why.into(),
            kind: CheckKind::Skipped,
        }
    }

    /// True unless an asserted check failed (NaN errors fail).
    pub fn passed(&self) -> bool {
        match self.kind {
            CheckKind::Assert => self.error <= self.tolerance,
            CheckKind::Report | CheckKind::Skipped => true,
        }
    }

    /// "PASS", "FAIL", "report" or "skipped".
    pub fn status(&self) -> &'static str {
        match self.kind {
            CheckKind::Assert if self.passed() => "PASS",
            CheckKind::Assert => "FAIL",
            CheckKind::Report => "report",
            CheckKind::Skipped => "skipped",
        }
    }
}

/// The checks as a Markdown table.
pub fn markdown_table(checks: &[Check]) -> String {
    let mut s =
        String::from("| check | measured error | tolerance | status | detail |\n|---|---|---|---|---|\n");
    for c in checks {
        let num = |v: f64| {
            if v.is_nan() { "–".to_string() } else { format!("{v:.4e}") }
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            c.name,
            num(c.error),
            num(c.tolerance),
            c.status(),
            c.detail.replace('|', "\\|")
        ));
    }
    s
}
