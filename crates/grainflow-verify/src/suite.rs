//! The verification suite: a registry of cases, each run into `DIR/<case>/`, and one HTML
//! report for the whole suite.

use crate::check::Check;
use crate::error::{VerifyError, io_at};
use grainflow::Integrator;
use grainflow_case::Case;
use grainflow_case::output::write_atomic;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Options shared by all cases.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SuiteOptions {
    /// Also run the converged (small time step) variants where a case has them (DEM05).
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

/// A case of the suite.
#[derive(Clone, Copy)]
pub struct CaseEntry {
    /// Name used on the command line and as the output folder.
    pub name: &'static str,
    /// One line for `grainflow verify --list`.
    pub summary: &'static str,
    /// Runs the case, writing into `DIR/<name>/`.
    pub run: fn(&Path, &SuiteOptions) -> Result<CaseOutcome, VerifyError>,
}

/// Every case, in report order.
pub fn cases() -> Vec<CaseEntry> {
    vec![
        CaseEntry {
            name: "dem01",
            summary: "MFIX DEM01: falling particle with one wall collision (LSD), EULER and ADAMS_BASHFORTH, against the three-stage closed form",
            run: crate::dem01::run_case,
        },
        CaseEntry {
            name: "dem02",
            summary: "MFIX DEM02: bouncing particle heights (LSD) against the hard sphere, with the gravity-during-contact bound and the exact soft-sphere contact",
            run: crate::dem02::run_case,
        },
        CaseEntry {
            name: "dem03",
            summary: "MFIX DEM03: two stacked, compressed particles between walls against an RK4 reference, with a step-halving study",
            run: crate::dem03::run_case,
        },
        CaseEntry {
            name: "dem04",
            summary: "MFIX DEM04: ball slipping on a rough floor until it rolls (2/7, 5/7, 5/7)",
            run: crate::dem04::run_case,
        },
        CaseEntry {
            name: "dem05",
            summary: "MFIX DEM05: oblique particle collision, LSD and Hertz, against MFIX's output, theory and Kharaz et al. (2001)",
            run: crate::dem05::run_case,
        },
        CaseEntry {
            name: "chung_ooi",
            summary: "Chung & Ooi (2011) tests 1–8: Hertz–Mindlin impacts against closed forms (Hertz, restitution, gross sliding, spin)",
            run: crate::chung_ooi::run_case,
        },
        CaseEntry {
            name: "rolling_plane",
            summary: "sphere sliding into rolling on a plane: t* = 2u₀/(7μg), v* = (5v₀ + 2Rω₀)/7, then constant speed",
            run: crate::rolling::run_plane,
        },
        CaseEntry {
            name: "rolling_incline",
            summary: "sphere released on an incline: rolls iff tan α ≤ 3.5μ (a = (5/7)g sin α), else slides",
            run: crate::rolling::run_incline,
        },
    ]
}

/// Looks up cases by name; unknown names are an error listing the known ones.
pub fn select(names: &[String]) -> Result<Vec<CaseEntry>, String> {
    let all = cases();
    if names.is_empty() {
        return Ok(all);
    }
    names
        .iter()
        .map(|n| {
            all.iter().find(|c| c.name == n).copied().ok_or_else(|| {
                let known: Vec<&str> = all.iter().map(|c| c.name).collect();
                format!("unknown verification case '{n}'; the cases are {}", known.join(", "))
            })
        })
        .collect()
}

/// Runs the cases (in parallel; each writes its own folder) and returns their outcomes in
/// the order given.
pub fn run(
    entries: &[CaseEntry],
    dir: &Path,
    options: &SuiteOptions,
) -> Result<Vec<CaseOutcome>, VerifyError> {
    entries.par_iter().map(|e| (e.run)(dir, options)).collect()
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

/// `DIR/report.html`: one table of every check with pass/fail, then each case with its notes
/// and figures. Figures are linked relative to DIR, so the folder can be moved as a whole.
pub fn write_report(outcomes: &[CaseOutcome], dir: &Path) -> Result<PathBuf, VerifyError> {
    let total: usize = outcomes.iter().map(|o| o.checks.len()).sum();
    let failed: usize = outcomes.iter().map(|o| o.checks.iter().filter(|c| !c.passed()).count()).sum();
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
img {{ max-width: 100%; border: 1px solid #ddd; margin: 0.5em 0; }}
</style></head><body>
<h1>grainflow verification report</h1>
<p>grainflow {version}: {n} case(s), {total} checks, <span class="{cls}">{failed} failed</span>.</p>
"#,
        version = env!("CARGO_PKG_VERSION"),
        n = outcomes.len(),
        cls = if failed == 0 { "PASS" } else { "FAIL" },
    );
    h.push_str("<table><tr><th>case</th><th>what it verifies</th><th>checks</th><th>failed</th><th>time (s)</th></tr>\n");
    for o in outcomes {
        let f = o.checks.iter().filter(|c| !c.passed()).count();
        let _ = writeln!(
            h,
            r##"<tr><td><a href="#{n}">{n}</a></td><td>{t}</td><td class="num">{c}</td><td class="num {cls}">{f}</td><td class="num">{s:.2}</td></tr>"##,
            n = o.name,
            t = escape(&o.title),
            c = o.checks.len(),
            cls = if f == 0 { "PASS" } else { "FAIL" },
            s = o.wall_seconds
        );
    }
    h.push_str("</table>\n<h2>All checks</h2>\n<table><tr><th>case</th><th>check</th><th>measured error</th><th>tolerance</th><th>status</th><th>detail</th></tr>\n");
    let num = |v: f64| if v.is_nan() { "–".to_string() } else { format!("{v:.4e}") };
    for o in outcomes {
        for c in &o.checks {
            let _ = writeln!(
                h,
                r##"<tr><td><a href="#{case}">{case}</a></td><td>{name}</td><td class="num">{err}</td><td class="num">{tol}</td><td class="{st}">{st}</td><td>{detail}</td></tr>"##,
                case = o.name,
                name = escape(&c.name),
                err = num(c.error),
                tol = num(c.tolerance),
                st = c.status(),
                detail = escape(&c.detail)
            );
        }
    }
    h.push_str("</table>\n");
    for o in outcomes {
        let _ = writeln!(
            h,
            r#"<h2 id="{name}">{name}: {title}</h2><p>{n} checks, {f} failed; {s:.2} s.</p>"#,
            name = o.name,
            title = escape(&o.title),
            n = o.checks.len(),
            f = o.checks.iter().filter(|c| !c.passed()).count(),
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
    }
    h.push_str("</body></html>\n");
    let path = dir.join("report.html");
    write_atomic(&path, h.as_bytes()).map_err(io_at(&path))?;
    Ok(path)
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
