//! A checkpoint written in format 9, before the contact sources wrote their own sections in
//! the sources' order (format 10), still restarts and continues to the byte as the case run from
//! its start does: `format9/checkpoint-v9.gfc` is `format9/case.toml` at step 2000 (written by
//! the build before format 10, with `--set time.t_stop=0.2`), when beads lie against the rod
//! (a cylinder), the plate (a mesh), the floor (a plane wall) and each other. The physics did
//! not change with the format, so every row after the checkpoint must be the same bytes.

use grainflow_run::run::{RunOptions, run_case};
use std::path::Path;

#[test]
fn a_format_9_checkpoint_continues_as_the_uninterrupted_run() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/format9");
    let case = || grainflow_case::load(&fixture.join("case.toml")).expect("case loads");
    let dir = tempfile::tempdir().expect("temp dir");
    let (full, resumed) = (dir.path().join("full"), dir.path().join("resumed"));
    let one = RunOptions { threads: Some(1), ..RunOptions::default() };
    run_case(case(), &full, &one, |_| {}).expect("uninterrupted run");
    // The checkpoint's case had t_stop = 0.2: another case hash.
    let restart =
        RunOptions { restart: Some(fixture.join("checkpoint-v9.gfc")), accept_changed_case: true, ..one };
    let summary = run_case(case(), &resumed, &restart, |_| {}).expect("the format 9 checkpoint restarts");
    assert_eq!(summary.start_step, 2000);
    let rows = |d: &Path| std::fs::read_to_string(d.join("timeseries.csv")).expect("time series");
    let (all, cont) = (rows(&full), rows(&resumed));
    let head = all.lines().next().expect("header");
    let cols = |name: &str| head.split(',').position(|c| c == name).unwrap_or_else(|| panic!("no {name}"));
    let (rod, plate) = (cols("cylinder_rod_fz"), cols("mesh_plate_fz"));
    // The rows from step 2100 on (the restart's first row, at 2000, holds the mesh and
    // cylinder loads as zeros: they are not checkpointed).
    let after = |s: &str| -> Vec<String> {
        s.lines()
            .skip(1)
            .filter(|l| l.split(',').next().and_then(|v| v.parse::<u64>().ok()) > Some(2000))
            .map(str::to_string)
            .collect()
    };
    let (want, got) = (after(&all), after(&cont));
    assert_eq!(want.len(), 10, "rows after step 2000");
    // The state had contacts of every kind: the rod and the plate carry loads after the restart.
    let value =
        |l: &str, k: usize| l.split(',').nth(k).and_then(|v| v.parse::<f64>().ok()).expect("a number");
    assert!(want.iter().all(|l| value(l, plate) != 0.0) && want.iter().any(|l| value(l, rod) != 0.0));
    for (a, b) in want.iter().zip(&got) {
        assert_eq!(a, b, "a continued row differs from the uninterrupted run's");
    }
}
