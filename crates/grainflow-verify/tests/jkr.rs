//! JKR cohesion end to end: `grainflow verify jkr` passes every check against the closed forms
//! and the vendored LAMMPS output; and, with LAMMPS installed (ignored by default:
//! `cargo test --release -p grainflow-verify --test jkr -- --ignored`), LAMMPS run afresh
//! from `bench/lammps/in.jkr_pair.lmp` still writes that output and grainflow still follows it.

use grainflow_verify::jkr::{self, LAMMPS_TOLERANCE};
use grainflow_verify::report::SuiteOptions;
use grainflow_verify::{Check, CheckKind};
use std::path::{Path, PathBuf};
use std::process::Command;

#[test]
fn jkr_case_passes_every_check() {
    let dir = tempfile::tempdir().expect("temp dir");
    let o = jkr::run_case(dir.path(), &SuiteOptions::default()).expect("case runs and writes");
    let failed: Vec<&Check> = o.checks.iter().filter(|c| !c.passed()).collect();
    assert!(failed.is_empty(), "failed: {failed:#?}");
    assert!(o.checks.iter().filter(|c| c.kind == CheckKind::Assert).count() >= 9);
    for f in &o.files {
        assert!(std::fs::metadata(f).map(|m| m.len() > 100).unwrap_or(false), "{} empty", f.display());
    }
}

fn lmp() -> PathBuf {
    let out = Command::new("sh").args(["-c", "command -v lmp"]).output().expect("sh runs");
    assert!(out.status.success(), "lmp not found: install LAMMPS (Debian: apt-get install lammps)");
    PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}

#[test]
#[ignore = "needs LAMMPS (lmp): see README"]
fn jkr_pair_matches_lammps_run_afresh() {
    let lmp = lmp();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench/lammps/in.jkr_pair.lmp");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = Command::new(lmp)
        .current_dir(dir.path())
        .arg("-in")
        .arg(&input)
        .args(["-var", "out", "jkr_pair.txt", "-screen", "none", "-log", "none"])
        .output()
        .expect("lmp runs");
    assert!(out.status.success(), "lmp failed: {}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(dir.path().join("jkr_pair.txt")).expect("LAMMPS output");
    let fresh = jkr::parse_lammps(&text);
    let run = jkr::run().expect("grainflow runs the case");
    // The vendored output is what this LAMMPS writes (another build may differ in the last
    // printed digits: 1e-12 of the scales).
    let vendored = jkr::compare(&fresh, &jkr::parse_lammps(jkr::LAMMPS), run.radius_sum);
    assert_eq!(vendored.unmatched, 0, "{vendored:?}");
    for e in [vendored.sep.0, vendored.velocity.0, vendored.force.0] {
        assert!(e <= 1e-12, "vendored LAMMPS output out of date: {vendored:?}");
    }
    let cmp = jkr::compare(&fresh, &run.rows, run.radius_sum);
    assert_eq!(cmp.unmatched, 0, "{cmp:?}");
    for (what, (e, step)) in [("separation", cmp.sep), ("velocity", cmp.velocity), ("force", cmp.force)] {
        assert!(e <= LAMMPS_TOLERANCE, "{what}: {e:e} at step {step} (tolerance {LAMMPS_TOLERANCE:e})");
    }
}
