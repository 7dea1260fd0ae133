//! The silo's reduced run end to end: every asserted check passes (Beverloo's C and k among
//! them) and the files are written with the promised columns. Release only.

use grainflow_verify::CheckKind;
use grainflow_verify::report::SuiteOptions;

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn silo_reduced_run_passes_and_writes_its_tables() {
    let dir = tempfile::tempdir().expect("temp dir");
    let outcome = grainflow_verify::silo::run_case(dir.path(), &SuiteOptions::default()).expect("runs");
    for c in &outcome.checks {
        println!("{:>7} {:.3e} / {:.3e}  {}  [{}]", c.status(), c.error, c.tolerance, c.name, c.detail);
    }
    let d = dir.path().join("silo");
    let rates = std::fs::read_to_string(d.join("silo_rates.csv")).expect("silo_rates.csv");
    println!("{rates}");
    let failed: Vec<String> = outcome.checks.iter().filter(|c| !c.passed()).map(|c| c.name.clone()).collect();
    assert!(failed.is_empty(), "failed checks: {failed:?}");
    // Four asserted checks per orifice, and C and k.
    assert_eq!(outcome.checks.iter().filter(|c| c.kind == CheckKind::Assert).count(), 3 * 4 + 2);
    assert_eq!(rates.lines().count(), 4, "three orifices in the reduced run");
    let series = std::fs::read_to_string(d.join("silo.csv")).expect("silo.csv");
    assert_eq!(series.lines().next(), Some("orifice_d,t_s,removed_kg,above_floor_kg,fill_height_m"));
    for f in ["silo.png", "silo.svg", "summary.md"] {
        assert!(d.join(f).exists(), "{f} missing");
    }
}
