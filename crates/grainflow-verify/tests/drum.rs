//! The rotating drum's reduced run end to end: every asserted check passes, the files are
//! written with the promised columns, and the run is deterministic. Release only.

use grainflow_verify::CheckKind;
use grainflow_verify::report::SuiteOptions;

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn drum_reduced_run_passes_and_writes_its_tables() {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = grainflow_verify::drum::run_case(dir.path(), &SuiteOptions::default()).expect("runs");
    for c in &outcome.checks {
        println!("{:>7} {:.3e} / {:.3e}  {}  [{}]", c.status(), c.error, c.tolerance, c.name, c.detail);
    }
    let failed: Vec<String> = outcome.checks.iter().filter(|c| !c.passed()).map(|c| c.name.clone()).collect();
    assert!(failed.is_empty(), "failed checks: {failed:?}");
    assert!(outcome.checks.iter().filter(|c| c.kind == CheckKind::Assert).count() >= 4);
    // The Fr sweep is the full version's.
    assert!(outcome.checks.iter().any(|c| c.kind == CheckKind::Skipped));
    let d = dir.path().join("drum");
    let series = std::fs::read_to_string(d.join("drum.csv")).expect("drum.csv");
    assert_eq!(series.lines().next(), Some("froude,t_s,drum_turned_deg,theta_centroid_deg,theta_fit_deg"));
    assert!(series.lines().count() > 300, "{} samples", series.lines().count());
    let angles = std::fs::read_to_string(d.join("drum_angles.csv")).expect("drum_angles.csv");
    assert_eq!(angles.lines().count(), 2, "one Froude number in the reduced run");
    for f in ["drum.png", "drum.svg", "summary.md"] {
        assert!(d.join(f).exists(), "{f} missing");
    }
    // Deterministic: the same run gives the same time series to the bit.
    let again = tempfile::tempdir().expect("temp dir");
    grainflow_verify::drum::run_case(again.path(), &SuiteOptions::default()).expect("runs again");
    let series2 = std::fs::read_to_string(again.path().join("drum/drum.csv")).expect("drum.csv");
    assert_eq!(series, series2, "two runs of the reduced drum differ");
}
