//! Chung & Ooi tests 1–8 and the rolling/sliding cases end to end: every asserted check passes
//! and the CSV files have the promised headers and row counts. Release only.

use grainflow_verify::CheckKind;
use grainflow_verify::report::{CaseOutcome, SuiteOptions};
use std::path::Path;

/// Fails with every failed check listed; prints the checks with `--nocapture`.
fn assert_all_pass(outcome: &CaseOutcome) {
    for c in &outcome.checks {
        println!("{:>7} {:.3e} / {:.3e}  {}  [{}]", c.status(), c.error, c.tolerance, c.name, c.detail);
    }
    let failed: Vec<String> = outcome
        .checks
        .iter()
        .filter(|c| !c.passed())
        .map(|c| format!("{}: {} > {} ({})", c.name, c.error, c.tolerance, c.detail))
        .collect();
    assert!(failed.is_empty(), "failed checks:\n{}", failed.join("\n"));
    assert!(outcome.checks.iter().any(|c| c.kind == CheckKind::Assert), "no asserted check");
    assert!(outcome.checks.iter().all(|c| c.kind != CheckKind::Skipped));
    for f in &outcome.files {
        assert!(
            std::fs::metadata(f).map(|m| m.len() > 50).unwrap_or(false),
            "{} missing or empty",
            f.display()
        );
    }
    assert!(!outcome.figures.is_empty(), "no figure");
    for f in &outcome.figures {
        assert!(f.extension().is_some_and(|e| e == "png"), "{} is not a PNG", f.display());
        assert!(f.with_extension("svg").exists(), "{} has no SVG", f.display());
    }
}

/// The header and data rows of a CSV file.
fn csv(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let rows = lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    (header, rows)
}

fn check_table(path: &Path, header: &str, rows: usize) -> Vec<Vec<String>> {
    let (h, r) = csv(path);
    assert_eq!(h, header, "{}", path.display());
    assert_eq!(r.len(), rows, "{}: row count", path.display());
    let columns = header.split(',').count();
    for row in &r {
        assert_eq!(row.len(), columns, "{}: {row:?}", path.display());
    }
    r
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn chung_ooi_all_checks_pass_and_tables_are_complete() {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = grainflow_verify::chung_ooi::run_case(dir.path(), &SuiteOptions::default()).expect("runs");
    assert_eq!(outcome.name, "chung_ooi");
    assert_all_pass(&outcome);
    let d = dir.path().join("chung_ooi");
    let impact = "material,f_max_sim,f_max_analytic,delta_max_sim,delta_max_analytic,contact_time_sim,contact_time_analytic";
    let t1 = check_table(&d.join("test1.csv"), impact, 2);
    assert_eq!(t1.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(), ["glass", "limestone"]);
    let t2 = check_table(&d.join("test2.csv"), impact, 2);
    assert_eq!(t2.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(), ["al_alloy", "mg_alloy"]);
    // 2 materials × 2 clipping choices × e = 0.2 … 1.0.
    let t3 = check_table(&d.join("test3.csv"), "material,clip_attraction,en_input,en_sim", 36);
    for clip in ["false", "true"] {
        for m in ["al_oxide", "cast_iron"] {
            let es: Vec<&str> =
                t3.iter().filter(|r| r[0] == m && r[1] == clip).map(|r| r[2].as_str()).collect();
            assert_eq!(
                es,
                ["0.2", "0.3", "0.4", "0.5", "0.6", "0.7", "0.8", "0.9", "1.0"],
                "{m} clip {clip}"
            );
        }
    }
    check_table(&d.join("test3_mfix_damping.csv"), "material,en_input,en_sim", 18);
    let t4 = check_table(
        &d.join("test4.csv"),
        "material,theta_deg,gross_sliding,en_sim,et_sim,et_sliding,omega_sim,omega_sliding,rebound_angle_sim,rebound_angle_sliding,cp_angle_sim,cp_angle_sliding",
        17,
    );
    let angles: Vec<f64> = t4.iter().map(|r| r[1].parse().expect("angle")).collect();
    assert_eq!(angles, (1..=17).map(|k| 5.0 * k as f64).collect::<Vec<_>>());
    // 2 materials × (0.1 and 0.5 … 21 m/s).
    let t5 = check_table(&d.join("test5.csv"), "material,psi1,psi2_sim,psi2_sliding,omega_norm_sim", 86);
    let psi1: Vec<f64> = t5.iter().filter(|r| r[0] == "steel").map(|r| r[1].parse().expect("psi1")).collect();
    assert!((psi1[0] - 0.1 / 1.5).abs() < 1e-6 && (psi1[42] - 14.0).abs() < 1e-6, "{psi1:?}");
    for t in ["test6", "test6_elastic", "test8", "test8_elastic"] {
        // 2 materials × 41 spins.
        let rows = check_table(&d.join(format!("{t}.csv")), "material,x,beta_sim,beta_sliding", 82);
        let x: Vec<f64> = rows.iter().map(|r| r[1].parse().expect("x")).collect();
        assert!(x.iter().all(|v| v.is_finite() && *v > 0.0), "{t}: {x:?}");
    }
    for t in ["test7", "test7_mfix_lever"] {
        // 2 materials × 7 spins.
        check_table(&d.join(format!("{t}.csv")), "material,omega0,omega_final,vt_final", 14);
    }
    for stem in ["test1", "test2", "test3", "test4", "test5", "test6", "test8"] {
        assert!(d.join(format!("{stem}.png")).exists() && d.join(format!("{stem}.svg")).exists(), "{stem}");
    }
    assert!(d.join("summary.md").exists());
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn rolling_plane_all_checks_pass_and_table_is_complete() {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = grainflow_verify::rolling::run_plane(dir.path(), &SuiteOptions::default()).expect("runs");
    assert_eq!(outcome.name, "rolling_plane");
    assert_all_pass(&outcome);
    let d = dir.path().join("rolling_plane");
    // 3 friction coefficients × 4 spins.
    let rows = check_table(
        &d.join("rolling_plane.csv"),
        "mu,omega0,t_star_sim,t_star_analytic,v_star_sim,v_star_analytic",
        12,
    );
    for r in &rows {
        let v: Vec<f64> = r.iter().map(|x| x.parse().expect("number")).collect();
        assert!(v.iter().all(|x| x.is_finite()), "{r:?}");
        assert!(v[2] > 0.0 && v[4] > 0.0, "{r:?}");
    }
    assert!(d.join("rolling_plane.png").exists() && d.join("rolling_plane.svg").exists());
    assert!(d.join("summary.md").exists());
}

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn rolling_incline_all_checks_pass_and_table_is_complete() {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = grainflow_verify::rolling::run_incline(dir.path(), &SuiteOptions::default()).expect("runs");
    assert_eq!(outcome.name, "rolling_incline");
    assert_all_pass(&outcome);
    let d = dir.path().join("rolling_incline");
    // 12 angles × 3 friction coefficients.
    let rows = check_table(
        &d.join("rolling_incline.csv"),
        "angle_deg,mu,regime,accel_sim,accel_analytic,alpha_sim,alpha_analytic",
        36,
    );
    // Both regimes on both sides of every threshold atan(3.5μ).
    for mu in ["0.1", "0.2", "0.3"] {
        let regimes: Vec<&str> = rows.iter().filter(|r| r[1] == mu).map(|r| r[2].as_str()).collect();
        assert!(regimes.contains(&"rolling") && regimes.contains(&"sliding"), "μ = {mu}: {regimes:?}");
    }
    assert!(d.join("rolling_incline.png").exists() && d.join("rolling_incline.svg").exists());
    assert!(d.join("summary.md").exists());
}
