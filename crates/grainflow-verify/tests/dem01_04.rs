//! MFIX DEM01–DEM04 end to end: every check passes, and the files have the promised form
//! (CSV headers and row counts, figures, summary). Release only for the full cases; the RK4
//! reference integrator of DEM03 is tested in any profile.

use grainflow_verify::report::{CaseOutcome, SuiteOptions};
use grainflow_verify::{CheckKind, dem01, dem02, dem03, dem04};
use std::path::Path;

/// Runs a case into a fresh temporary folder; returns the outcome and the folder.
fn run(
    f: fn(&Path, &SuiteOptions) -> Result<CaseOutcome, grainflow_verify::VerifyError>,
) -> (CaseOutcome, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = f(dir.path(), &SuiteOptions::default()).expect("case runs and writes");
    (outcome, dir)
}

/// Every asserted check passes, none is skipped, every file written is non-empty, every
/// figure is a PNG with an SVG beside it, and summary.md reports no failure.
fn assert_complete(o: &CaseOutcome, dir: &Path, min_asserted: usize) {
    let failed: Vec<String> = o
        .checks
        .iter()
        .filter(|c| !c.passed())
        .map(|c| format!("{}: {} > {} ({})", c.name, c.error, c.tolerance, c.detail))
        .collect();
    assert!(failed.is_empty(), "{}: failed checks:\n{}", o.name, failed.join("\n"));
    let asserted = o.checks.iter().filter(|c| c.kind == CheckKind::Assert).count();
    assert!(asserted >= min_asserted, "{}: {asserted} asserted checks", o.name);
    assert!(o.checks.iter().all(|c| c.kind != CheckKind::Skipped));
    for f in &o.files {
        assert!(f.starts_with(dir.join(o.name)), "{} outside the case folder", f.display());
        assert!(
            std::fs::metadata(f).map(|m| m.len() > 100).unwrap_or(false),
            "{} missing or empty",
            f.display()
        );
    }
    assert!(!o.figures.is_empty());
    for png in &o.figures {
        assert_eq!(png.extension().and_then(|e| e.to_str()), Some("png"));
        assert!(o.files.contains(png) && o.files.contains(&png.with_extension("svg")));
    }
    let summary = std::fs::read_to_string(dir.join(o.name).join("summary.md")).expect("summary.md");
    assert!(summary.contains(" 0 failed"), "{summary}");
    assert!(!o.notes.is_empty() && o.wall_seconds > 0.0);
}

/// The CSV's header and rows (split on commas).
fn read_csv(dir: &Path, case: &str) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(dir.join(case).join(format!("{case}.csv"))).expect("csv");
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let rows = lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    (header, rows)
}

fn num(s: &str) -> f64 {
    s.parse().unwrap_or_else(|_| panic!("not a number: {s}"))
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn dem01_all_checks_pass_and_csv_is_complete() {
    let (o, dir) = run(dem01::run_case);
    assert_complete(&o, dir.path(), 9);
    let (header, rows) = read_csv(dir.path(), "dem01");
    assert_eq!(header, "integrator,kn,en,time,stage,y_analytic,y_sim,v_analytic,v_sim");
    assert_eq!(rows.len(), 38 * 101, "38 runs × 101 output times");
    for integrator in ["euler", "adams_bashforth"] {
        let of: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == integrator).collect();
        assert_eq!(of.len(), 19 * 101, "{integrator}");
        // Each run: 101 outputs at or after k·5e-3 s, within one step of it; stages 1 → 2 → 3.
        for run in of.chunks(101) {
            let (kn, en) = (&run[0][1], &run[0][2]);
            let mut stage = 1;
            for (k, r) in run.iter().enumerate() {
                assert_eq!((&r[1], &r[2]), (kn, en), "one run per 101 rows");
                let t = num(&r[3]);
                assert!(t >= k as f64 * 5e-3 - 1e-12 && t < k as f64 * 5e-3 + 1.5e-3, "{r:?}");
                let s: u32 = r[4].parse().expect("stage");
                assert!(s == stage || s == stage + 1, "{r:?}");
                stage = s;
            }
            assert_eq!(stage, 3, "run {kn} {en} ends in the rebound");
        }
    }
    // MFIX's own number for the first run's time step.
    let dt_check = o.checks.iter().find(|c| c.name.contains("DTSOLID")).expect("time-step check");
    assert!(dt_check.passed() && dt_check.kind == CheckKind::Assert);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn dem02_all_checks_pass_and_csv_is_complete() {
    let (o, dir) = run(dem02::run_case);
    assert_complete(&o, dir.path(), 9);
    let (header, rows) = read_csv(dir.path(), "dem02");
    assert_eq!(header, "kn,en,bounce,height_hard_sphere,height_sim");
    let mut runs: Vec<(String, String)> = rows.iter().map(|r| (r[0].clone(), r[1].clone())).collect();
    runs.dedup();
    assert_eq!(runs.len(), 18, "18 runs, each with at least one bounce");
    let report = dem02::evaluate().expect("runs");
    let expected: usize = report.runs.iter().map(|r| r.heights.len()).sum();
    assert_eq!(rows.len(), expected);
    for (kn, en) in &runs {
        let bounces: Vec<&Vec<String>> = rows.iter().filter(|r| &r[0] == kn && &r[1] == en).collect();
        assert!(!bounces.is_empty() && bounces.len() <= 50, "{kn} {en}: {}", bounces.len());
        for (k, r) in bounces.iter().enumerate() {
            assert_eq!(r[2], (k + 1).to_string(), "bounces numbered 1, 2, …");
            let hard = dem02::hard_sphere_height(num(en), k + 1);
            assert!((num(&r[3]) - hard).abs() <= 1e-9 * hard, "{r:?}");
        }
        // e_n < 1 runs lose their flight within 10 s and record 50 sign changes or stop early;
        // e_n = 1 bounces about 17 times in 10 s (0.57 s of flight each).
        if en == "1" {
            assert!((15..=18).contains(&bounces.len()), "{kn}: {} bounces", bounces.len());
        }
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn dem03_all_checks_pass_and_csv_is_complete() {
    let (o, dir) = run(dem03::run_case);
    assert_complete(&o, dir.path(), 9);
    let (header, rows) = read_csv(dir.path(), "dem03");
    assert_eq!(header, "en,time,y1_ref,y1_sim,y2_ref,y2_sim");
    assert_eq!(rows.len(), 6 * 101, "6 runs × 101 output times");
    for (j, run) in rows.chunks(101).enumerate() {
        assert_eq!(num(&run[0][0]), dem03::RESTITUTIONS[j]);
        for (k, r) in run.iter().enumerate() {
            let t = num(&r[1]);
            assert!(t >= k as f64 * 1e-5 - 1e-15 && t < k as f64 * 1e-5 + 3.3e-6, "{r:?}");
        }
        // The start is the shipped layout, for reference and simulation alike.
        for c in [2, 3] {
            assert!((num(&run[0][c]) - 4.5e-4).abs() < 1e-15);
        }
        for c in [4, 5] {
            assert!((num(&run[0][c]) - 1.35e-3).abs() < 1e-15);
        }
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn dem04_all_checks_pass_and_csv_is_complete() {
    let (o, dir) = run(dem04::run_case);
    assert_complete(&o, dir.path(), 6);
    let (header, rows) = read_csv(dir.path(), "dem04");
    assert_eq!(header, "mu,slip_end_time_norm,velocity_norm,spin_norm");
    assert_eq!(rows.len(), 9);
    for (r, mu) in rows.iter().zip(dem04::FRICTIONS) {
        assert_eq!(num(&r[0]), mu);
        // Close to 2/7, 5/7, 5/7 (the checks hold the exact tolerances); spin_norm is −ω_z·R/u₀,
        // positive for the forward roll.
        assert!((num(&r[1]) - 2.0 / 7.0).abs() < 5e-3, "{r:?}");
        assert!((num(&r[2]) - 5.0 / 7.0).abs() < 2e-3, "{r:?}");
        assert!((num(&r[3]) - 5.0 / 7.0).abs() < 2e-3, "{r:?}");
    }
}

/// Runs in parallel give the same numbers every time.
#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn results_are_deterministic() {
    let a = dem01::evaluate().expect("runs");
    let b = dem01::evaluate().expect("runs");
    assert_eq!(dem01::csv(&a.runs), dem01::csv(&b.runs));
    let a = dem04::evaluate().expect("runs");
    let b = dem04::evaluate().expect("runs");
    assert_eq!(dem04::csv(&a.runs), dem04::csv(&b.runs));
}

// ---- The RK4 reference integrator of DEM03 (any profile) ----

/// y″ = −ω²y, y(0) = 1, y′(0) = 0, integrated to t = 2 with step h: error against cos ωt.
fn oscillator_error(h: f64) -> f64 {
    let w = 2.5;
    let f = |_t: f64, s: &[f64; 2]| [s[1], -w * w * s[0]];
    let y = dem03::rk4_integrate(&f, 0.0, [1.0, 0.0], 2.0, h);
    ((y[0] - (2.0 * w).cos()).powi(2) + (y[1] / w + (2.0 * w).sin()).powi(2)).sqrt()
}

#[test]
fn rk4_converges_at_fourth_order() {
    // Halving h divides the error by 2⁴: observed order 4 ± 0.05.
    for h in [0.04, 0.02, 0.01] {
        let p = (oscillator_error(h) / oscillator_error(h / 2.0)).log2();
        assert!((p - 4.0).abs() < 0.05, "h = {h}: order {p}");
    }
}

#[test]
fn rk4_is_accurate_for_the_harmonic_oscillator() {
    // The RK4 amplification factor is the Taylor series of e^(iωh) to 4th order: the global
    // (phase) error is (ωh)⁴·ω·t/120 to leading order.
    for h in [0.01, 0.002] {
        let e = oscillator_error(h);
        let leading = (2.5 * h).powi(4) * 2.5 * 2.0 / 120.0;
        assert!((e / leading - 1.0).abs() < 0.1, "h = {h}: {e} vs {leading}");
    }
}

#[test]
fn rk4_one_step_matches_the_exponential() {
    // y′ = λy: one step multiplies by 1 + z + z²/2 + z³/6 + z⁴/24, z = λh.
    let f = |_t: f64, s: &[f64; 1]| [-3.0 * s[0]];
    let z: f64 = -3.0 * 0.1;
    let y = dem03::rk4_step(&f, 0.0, &[1.0], 0.1);
    let taylor = 1.0 + z + z * z / 2.0 + z.powi(3) / 6.0 + z.powi(4) / 24.0;
    assert!((y[0] - taylor).abs() < 1e-15);
}
