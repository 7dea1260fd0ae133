//! What the cases share and what the suite reports, at the bottom of the crate's order (cases
//! and the suite depend on it, it on neither): the options and the outcome of a case, its
//! folder and files (CSV, figures, `summary.md`), and the suite's terminal summary and
//! `report.html`.

use crate::check::{Check, CheckKind};
use crate::error::{VerifyError, io_at};
use grainflow::Integrator;
use grainflow_case::Case;
use grainflow_run::output::write_atomic;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Options shared by all cases.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SuiteOptions {
    /// Also run the converged (small time step) variants where a case has them (DEM05), and
    /// the full versions of reduced cases (drum: the Fr sweep; silo: five orifices; packing:
    /// seven friction coefficients).
    pub converged: bool,
    /// Integrator for the converged runs.
    pub integrator: Option<Integrator>,
}

/// What one case produced.
#[derive(Debug, Clone)]
pub struct CaseOutcome {
    /// Short name, e.g. "dem01"; also the folder under DIR.
    pub name: &'static str,
    /// One-line title.
    pub title: String,
    /// Its checks.
    pub checks: Vec<Check>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    /// PNG figures to show in the report.
    pub figures: Vec<PathBuf>,
    /// Paragraphs for the report: what the case shows, how the model departs from the
    /// reference and why.
    pub notes: Vec<String>,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

impl CaseOutcome {
    /// True when every asserted check passed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(Check::passed)
    }
}

/// Reads a case file shipped with the suite; `files` supplies the particle files it names.
pub fn shipped_case(name: &str, text: &str, files: &[(&str, &str)]) -> Result<Case, VerifyError> {
    grainflow_case::parse(text, name, &|file: &str| {
        files.iter().find(|(n, _)| *n == file).map(|(_, t)| t.to_string()).ok_or_else(|| {
            grainflow_case::CaseError::Read {
                path: PathBuf::from(file),
                source: std::io::Error::new(std::io::ErrorKind::NotFound, "not shipped with the case"),
            }
        })
    })
    .map_err(|source| VerifyError::Case { case: name.into(), source })
}

/// Creates `DIR/<name>/` and returns it.
pub fn case_dir(dir: &Path, name: &str) -> Result<PathBuf, VerifyError> {
    let out = dir.join(name);
    std::fs::create_dir_all(&out).map_err(io_at(&out))?;
    Ok(out)
}

/// Writes `text` atomically to `path` and records it in `files`.
pub fn write_file(path: PathBuf, text: &str, files: &mut Vec<PathBuf>) -> Result<(), VerifyError> {
    write_atomic(&path, text.as_bytes()).map_err(io_at(&path))?;
    files.push(path);
    Ok(())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// How many checks of each kind a list holds, and how many asserted ones failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CheckCounts {
    /// Asserted checks.
    pub asserted: usize,
    /// Asserted checks that failed.
    pub failed: usize,
    /// Measurements reported, never failed.
    pub reported: usize,
    /// Checks not run this time.
    pub skipped: usize,
}

impl CheckCounts {
    /// Counts `checks`.
    pub fn of(checks: &[Check]) -> Self {
        let mut n = CheckCounts::default();
        for c in checks {
            match c.kind {
                CheckKind::Assert => {
                    n.asserted += 1;
                    n.failed += usize::from(!c.passed());
                }
                CheckKind::Report => n.reported += 1,
                CheckKind::Skipped => n.skipped += 1,
            }
        }
        n
    }

    /// Adds another count.
    fn add(self, o: CheckCounts) -> Self {
        CheckCounts {
            asserted: self.asserted + o.asserted,
            failed: self.failed + o.failed,
            reported: self.reported + o.reported,
            skipped: self.skipped + o.skipped,
        }
    }

    /// "30 of 30 asserted checks passed, 2 reported, 2 skipped" (the last two only when
    /// there are any).
    pub fn sentence(&self) -> String {
        let mut s = format!("{} of {} asserted checks passed", self.asserted - self.failed, self.asserted);
        if self.reported > 0 {
            let _ = write!(s, ", {} reported only", self.reported);
        }
        if self.skipped > 0 {
            let _ = write!(s, ", {} skipped", self.skipped);
        }
        s
    }
}

/// The suite's result for a terminal: one line per case (PASS/FAIL, counts, time), every
/// failed check by name, and the total. The full tables are in each case's `summary.md` and
/// in the report.
pub fn console_summary(outcomes: &[CaseOutcome]) -> String {
    let mut s = String::new();
    let width = outcomes.iter().map(|o| o.name.len()).max().unwrap_or(0);
    let mut total = CheckCounts::default();
    for o in outcomes {
        let n = CheckCounts::of(&o.checks);
        total = total.add(n);
        let _ = writeln!(
            s,
            "{} {:<width$}  {} ({:.2} s)",
            if n.failed == 0 { "PASS" } else { "FAIL" },
            o.name,
            n.sentence(),
            o.wall_seconds
        );
        for c in o.checks.iter().filter(|c| !c.passed()) {
            let _ = writeln!(
                s,
                "       failed: {} (error {:.4e} > tolerance {:.4e})",
                c.name, c.error, c.tolerance
            );
        }
    }
    let _ = writeln!(s, "{} case(s): {}", outcomes.len(), total.sentence());
    s
}

/// `DIR/report.html`, in the order a reader wants it: the verdict and a one-line summary per
/// case, then each case with its notes and figures, and only then its checks in a collapsed
/// table (open when one failed). Figures are linked relative to DIR, so the folder can be
/// moved as a whole.
pub fn write_report(outcomes: &[CaseOutcome], dir: &Path) -> Result<PathBuf, VerifyError> {
    let counts: Vec<CheckCounts> = outcomes.iter().map(|o| CheckCounts::of(&o.checks)).collect();
    let total = counts.iter().fold(CheckCounts::default(), |a, &b| a.add(b));
    let mut h = String::new();
    let _ = write!(
        h,
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>grainflow verification report</title>
<style>
body {{ font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; margin: 2em auto; max-width: 1850px; padding: 0 1em; color: #222; }}
table {{ border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }}
th, td {{ border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: left; vertical-align: top; }}
th {{ background: #f2f2f2; }}
td.num {{ text-align: right; font-family: "DejaVu Sans Mono", monospace; }}
.PASS {{ color: #176b2c; font-weight: bold; }} .FAIL {{ color: #b00020; font-weight: bold; }}
.report, .skipped {{ color: #666; }}
details {{ margin: 0.5em 0 2em 0; }} summary {{ cursor: pointer; font-weight: bold; }}
img {{ max-width: 100%; border: 1px solid #ddd; margin: 0.5em 0; }}
</style></head><body>
<h1>grainflow verification report</h1>
<p class="{cls}">{verdict}</p>
<p>grainflow {version}, {n} case(s): {sentence}.</p>
"#,
        version = env!("CARGO_PKG_VERSION"),
        n = outcomes.len(),
        cls = if total.failed == 0 { "PASS" } else { "FAIL" },
        verdict = if total.failed == 0 {
            "Every asserted check passed.".to_string()
        } else {
            format!("{} asserted check(s) failed.", total.failed)
        },
        sentence = total.sentence(),
    );
    h.push_str("<table><tr><th>case</th><th>what it verifies</th><th>result</th><th>asserted checks passed</th><th>reported only</th><th>skipped</th><th>time (s)</th></tr>\n");
    for (o, n) in outcomes.iter().zip(&counts) {
        let st = if n.failed == 0 { "PASS" } else { "FAIL" };
        let _ = writeln!(
            h,
            r##"<tr><td><a href="#{name}">{name}</a></td><td>{t}</td><td class="{st}">{st}</td><td class="num">{p} / {a}</td><td class="num">{r}</td><td class="num">{k}</td><td class="num">{s:.2}</td></tr>"##,
            name = escape(o.name),
            t = escape(&o.title),
            p = n.asserted - n.failed,
            a = n.asserted,
            r = n.reported,
            k = n.skipped,
            s = o.wall_seconds
        );
    }
    h.push_str("</table>\n");
    let failed: Vec<(&CaseOutcome, &Check)> =
        outcomes.iter().flat_map(|o| o.checks.iter().filter(|c| !c.passed()).map(move |c| (o, c))).collect();
    if !failed.is_empty() {
        h.push_str("<h2>Failed checks</h2>\n");
        check_table(&mut h, failed.into_iter(), true);
    }
    h.push_str(
        "<p>Each check compares a measured error with its tolerance. <i>PASS</i>/<i>FAIL</i>: asserted; \
<i>report</i>: measured and shown, never failed (e.g. a known difference between a model and an experiment); \
<i>skipped</i>: not run this time, the detail says why. The equations and sources of every case are in \
docs/verification.md of the grainflow repository.</p>\n",
    );
    for (o, n) in outcomes.iter().zip(&counts) {
        let st = if n.failed == 0 { "PASS" } else { "FAIL" };
        let _ = writeln!(
            h,
            r#"<h2 id="{name}">{name}: {title}</h2><p><span class="{st}">{st}</span>: {sentence}; {s:.2} s.</p>"#,
            name = escape(o.name),
            title = escape(&o.title),
            sentence = n.sentence(),
            s = o.wall_seconds
        );
        for p in &o.notes {
            let _ = writeln!(h, "<p>{}</p>", escape(p));
        }
        for f in &o.figures {
            let rel = f.strip_prefix(dir).unwrap_or(f);
            let src = rel.to_string_lossy().replace('\\', "/");
            let _ = writeln!(h, r#"<p><img src="{src}" alt="{src}"></p>"#, src = escape(&src));
        }
        let files: Vec<String> = o
            .files
            .iter()
            .map(|f| {
                let rel = f.strip_prefix(dir).unwrap_or(f).to_string_lossy().replace('\\', "/");
                format!(r#"<a href="{0}">{0}</a>"#, escape(&rel))
            })
            .collect();
        let _ = writeln!(h, "<p>Files: {}</p>", files.join(", "));
        let _ = writeln!(
            h,
            "<details{open}><summary>The {k} checks of {name} ({f} failed)</summary>",
            open = if n.failed > 0 { " open" } else { "" },
            k = o.checks.len(),
            name = escape(o.name),
            f = n.failed
        );
        check_table(&mut h, o.checks.iter().map(|c| (o, c)), false);
        h.push_str("</details>\n");
    }
    h.push_str("</body></html>\n");
    let path = dir.join("report.html");
    write_atomic(&path, h.as_bytes()).map_err(io_at(&path))?;
    Ok(path)
}

/// Appends a table of checks; `with_case` adds a column naming (and linking) the case.
fn check_table<'a>(
    h: &mut String,
    checks: impl Iterator<Item = (&'a CaseOutcome, &'a Check)>,
    with_case: bool,
) {
    h.push_str("<table><tr>");
    if with_case {
        h.push_str("<th>case</th>");
    }
    h.push_str(
        "<th>check</th><th>measured error</th><th>tolerance</th><th>status</th><th>detail</th></tr>\n",
    );
    let num = |v: f64| if v.is_nan() { "–".to_string() } else { format!("{v:.4e}") };
    for (o, c) in checks {
        h.push_str("<tr>");
        if with_case {
            let _ = write!(h, r##"<td><a href="#{0}">{0}</a></td>"##, escape(o.name));
        }
        let _ = writeln!(
            h,
            r#"<td>{name}</td><td class="num">{err}</td><td class="num">{tol}</td><td class="{st}">{st}</td><td>{detail}</td></tr>"#,
            name = escape(&c.name),
            err = num(c.error),
            tol = num(c.tolerance),
            st = c.status(),
            detail = escape(&c.detail)
        );
    }
    h.push_str("</table>\n");
}

/// Draws `fig` as `<out>/<stem>.png` and `.svg`, records both in `files`, returns the PNG.
pub fn write_figure(
    out: &Path,
    stem: &str,
    fig: &crate::plot::Figure,
    files: &mut Vec<PathBuf>,
) -> Result<PathBuf, VerifyError> {
    let (png, svg) = (out.join(format!("{stem}.png")), out.join(format!("{stem}.svg")));
    crate::plot::write_figure(fig, &png, &svg)?;
    files.extend([png.clone(), svg]);
    Ok(png)
}

/// Writes a case's usual files into `DIR/<name>/`: `<name>.csv`, the figure `<name>.png` and
/// `.svg`, and `summary.md` with the checks; returns the files written and the PNG.
pub fn write_case_files(
    dir: &Path,
    name: &str,
    title: &str,
    csv: &str,
    fig: &crate::plot::Figure,
    checks: &[Check],
) -> Result<(Vec<PathBuf>, PathBuf), VerifyError> {
    let out = case_dir(dir, name)?;
    let mut files = Vec::new();
    write_file(out.join(format!("{name}.csv")), csv, &mut files)?;
    let png = write_figure(&out, name, fig, &mut files)?;
    write_file(out.join("summary.md"), &summary_markdown(title, checks), &mut files)?;
    Ok((files, png))
}

/// A case's `summary.md`: title, the checks as a table, the count of failures.
pub fn summary_markdown(title: &str, checks: &[Check]) -> String {
    let failed = checks.iter().filter(|c| !c.passed()).count();
    format!(
        "# {title}\n\n{}\n{} checks, {failed} failed.\n",
        crate::check::markdown_table(checks),
        checks.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outcome(name: &'static str, dir: &Path, checks: Vec<Check>) -> CaseOutcome {
        let fig = dir.join(name).join(format!("{name}.png"));
        CaseOutcome {
            name,
            title: format!("case {name} <&>"),
            checks,
            files: vec![fig.clone()],
            figures: vec![fig],
            notes: vec!["what it shows".into()],
            wall_seconds: 0.5,
        }
    }

    /// Two cases, one with a failed check: the report leads with the verdict and the case
    /// summary, shows a case's figure before its check table, collapses the tables (the failed
    /// case's open), lists the failed check near the top, and counts every kind of check.
    #[test]
    fn report_leads_with_summary_and_figures() {
        let dir = tempfile::tempdir().unwrap();
        let good = outcome(
            "good",
            dir.path(),
            vec![
                Check::assert("tight", 1e-9, 1e-6, "fine"),
                Check::report("versus experiment", 0.2, "shown only"),
                Check::skipped("converged", "run with --converged"),
            ],
        );
        let bad = outcome(
            "bad",
            dir.path(),
            vec![Check::assert("loose", 2.0, 1.0, "too far"), Check::assert("ok", 0.0, 1.0, "fine")],
        );
        let path = write_report(&[good, bad], dir.path()).unwrap();
        let h = std::fs::read_to_string(path).unwrap();
        let at = |needle: &str| h.find(needle).unwrap_or_else(|| panic!("{needle} missing from the report"));
        // Totals: 3 asserted checks (one failed), 1 reported, 1 skipped.
        assert!(h.contains("1 asserted check(s) failed."));
        assert!(h.contains("2 of 3 asserted checks passed, 1 reported only, 1 skipped"));
        // Per case: 1/1 and 1/2 asserted checks passed.
        assert!(h.contains(r#"<td class="num">1 / 1</td>"#) && h.contains(r#"<td class="num">1 / 2</td>"#));
        // Order: summary table, failed checks, the first case's figure, then its checks.
        let summary = at("<th>what it verifies</th>");
        let failed = at("<h2>Failed checks</h2>");
        let figure = at(r#"<img src="good/good.png""#);
        let good_checks = at("<summary>The 3 checks of good (0 failed)</summary>");
        assert!(summary < failed && failed < figure && figure < good_checks);
        // Only the failed case's table is open.
        assert!(h.contains("<details><summary>The 3 checks of good"));
        assert!(h.contains("<details open><summary>The 2 checks of bad (1 failed)"));
        // The failed check appears twice: at the top and in its case's table.
        assert_eq!(h.matches("<td>loose</td>").count(), 2);
        // Text from the cases is escaped.
        assert!(h.contains("case good &lt;&amp;&gt;") && !h.contains("case good <&>"));
    }

    /// The terminal summary: one line per case with its verdict, the failed check by name,
    /// and the totals.
    #[test]
    fn console_summary_names_failures() {
        let dir = Path::new("out");
        let s = console_summary(&[
            outcome("good", dir, vec![Check::assert("tight", 0.0, 1.0, "")]),
            outcome("bad", dir, vec![Check::assert("loose", 2.0, 1.0, ""), Check::report("r", 1.0, "")]),
        ]);
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines.len(), 4, "{s}");
        assert!(lines[0].starts_with("PASS good") && lines[0].contains("1 of 1 asserted checks passed"));
        assert!(
            lines[1].starts_with("FAIL bad ")
                && lines[1].contains("0 of 1 asserted checks passed, 1 reported only")
        );
        assert!(lines[2].contains("failed: loose (error 2.0000e0 > tolerance 1.0000e0)"));
        assert_eq!(lines[3], "2 case(s): 1 of 2 asserted checks passed, 1 reported only");
    }
}
