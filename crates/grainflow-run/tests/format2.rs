//! A checkpoint written in format 2 (before run ids) still restarts, and continues exactly as
//! the case run from its start does: `format2/checkpoint-v2.gfc` is `format2/case.toml` at step
//! 6000, written by the build before format 3.

use grainflow_run::run::{RunOptions, run_case};
use std::path::Path;

#[test]
fn a_format_2_checkpoint_continues_as_the_uninterrupted_run() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/format2");
    let case = || grainflow_case::load(&fixture.join("case.toml")).expect("case loads");
    let dir = tempfile::tempdir().expect("temp dir");
    let (full, resumed) = (dir.path().join("full"), dir.path().join("resumed"));
    run_case(case(), &full, &RunOptions::default(), |_| {}).expect("uninterrupted run");
    // The case gained `sizes = "phase"` after the checkpoint was written: the default of that
    // build, so the same run, but another case file to the checkpoint's hash.
    let restart = RunOptions {
        restart: Some(fixture.join("checkpoint-v2.gfc")),
        accept_changed_case: true,
        ..RunOptions::default()
    };
    let summary = run_case(case(), &resumed, &restart, |_| {}).expect("the format 2 checkpoint restarts");
    assert_eq!(summary.start_step, 6000);
    assert_eq!(summary.run_id.len(), 16, "a format 2 checkpoint has no run id: the restart draws one");
    // The sums of the force stage changed after format 2 (they no longer depend on their
    // order: `forces::sum`), so the run that wrote the checkpoint and today's build part at the
    // level of the rounding of those sums, 2⁻⁴² of the largest load a step. The continued rows
    // (from step 6000 on) must agree with today's uninterrupted run to well within what the
    // bed's settling could hide: the energies to 1e-6 relative (a wrong velocity, history or
    // step count read from the checkpoint shows at the first row at the 1e-2 level or more).
    let rows = |d: &Path| std::fs::read_to_string(d.join("timeseries.csv")).expect("time series");
    let (all, cont) = (rows(&full), rows(&resumed));
    let parse = |s: &str| -> Vec<Vec<f64>> {
        s.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect()
    };
    let (all, cont) = (parse(&all), parse(&cont));
    assert!(!cont.is_empty());
    let tail = &all[all.len() - cont.len()..];
    let mut worst = 0.0f64;
    for (a, b) in tail.iter().zip(&cont) {
        assert_eq!(a[0], b[0], "steps of the rows");
        for (x, y) in a.iter().zip(b).skip(1) {
            if x.is_finite() && y.is_finite() && x.abs() > 1e-300 {
                worst = worst.max((x - y).abs() / x.abs());
            }
        }
    }
    eprintln!("largest relative difference of the continued rows: {worst:e}");
    assert!(worst < 1e-6, "continued rows differ from the uninterrupted run by {worst:e}");
}
