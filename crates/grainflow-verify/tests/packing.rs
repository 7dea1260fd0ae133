//! The poured packing's reduced run end to end: every asserted check passes (φ ≈ 0.64 at
//! μ = 0, falling with μ) and the files are written. Release only.

use grainflow_verify::CheckKind;
use grainflow_verify::report::SuiteOptions;

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn packing_reduced_run_passes_and_writes_its_tables() {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = grainflow_verify::packing::run_case(dir.path(), &SuiteOptions::default()).expect("runs");
    for c in &outcome.checks {
        println!("{:>7} {:.3e} / {:.3e}  {}  [{}]", c.status(), c.error, c.tolerance, c.name, c.detail);
    }
    let d = dir.path().join("packing");
    let table = std::fs::read_to_string(d.join("packing.csv")).expect("packing.csv");
    println!("{table}");
    let failed: Vec<String> = outcome.checks.iter().filter(|c| !c.passed()).map(|c| c.name.clone()).collect();
    assert!(failed.is_empty(), "failed checks: {failed:?}");
    // Two per μ, random close packing at μ = 0, the monotonic fall.
    assert_eq!(outcome.checks.iter().filter(|c| c.kind == CheckKind::Assert).count(), 3 * 2 + 2);
    assert_eq!(table.lines().count(), 4, "three friction coefficients in the reduced run");
    let profiles = std::fs::read_to_string(d.join("packing_profiles.csv")).expect("packing_profiles.csv");
    assert_eq!(profiles.lines().next(), Some("mu,z_over_d,phi"));
    for f in ["packing.png", "packing.svg", "summary.md"] {
        assert!(d.join(f).exists(), "{f} missing");
    }
}
