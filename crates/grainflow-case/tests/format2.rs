//! A checkpoint written in format 2 (before run ids) still restarts, and continues exactly as
//! the case run from its start does: `format2/checkpoint-v2.gfc` is `format2/case.toml` at step
//! 6000, written by the build before format 3.

use grainflow_case::run::{RunOptions, run_case};
use std::path::Path;

#[test]
fn a_format_2_checkpoint_continues_as_the_uninterrupted_run() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/format2");
    let case = || grainflow_case::load(&fixture.join("case.toml")).expect("case loads");
    let dir = tempfile::tempdir().expect("temp dir");
    let (full, resumed) = (dir.path().join("full"), dir.path().join("resumed"));
    run_case(case(), &full, &RunOptions::default(), |_| {}).expect("uninterrupted run");
    let restart = RunOptions { restart: Some(fixture.join("checkpoint-v2.gfc")), ..RunOptions::default() };
    let summary = run_case(case(), &resumed, &restart, |_| {}).expect("the format 2 checkpoint restarts");
    assert_eq!(summary.start_step, 6000);
    assert_eq!(summary.run_id.len(), 16, "a format 2 checkpoint has no run id: the restart draws one");
    // The continued rows (from step 6000 on) and the final snapshot equal the uninterrupted
    // run's to the byte: the physics of format 2's state is carried over whole.
    let rows = |d: &Path| std::fs::read_to_string(d.join("timeseries.csv")).expect("time series");
    let (all, cont) = (rows(&full), rows(&resumed));
    let tail: Vec<&str> = cont.lines().skip(1).collect();
    assert!(!tail.is_empty(), "{cont}");
    assert!(all.lines().rev().take(tail.len()).eq(tail.iter().rev().copied()), "{all}\n---\n{cont}");
    let last = format!("snapshots/particles_{:09}.csv", summary.start_step + summary.steps);
    let snap = |d: &Path| std::fs::read(d.join(&last)).expect("final snapshot");
    assert!(snap(&full) == snap(&resumed), "final states differ");
}
