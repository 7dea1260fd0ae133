//! Runs stopped at any moment and continued from their last checkpoint end with the same files
//! as a run that was never stopped, and their books close: a stop request (SIGTERM in the
//! program: the step finishes, a checkpoint is written) and a crash (SIGKILL: the process ends
//! where it is, its last periodic checkpoint and the rows written since are left), during an
//! insertion and during a discharge through an outlet.

use grainflow_run::run::{CheckpointEvery, RunOptions, run_case};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// An example's case file with its `t_stop` (and anything else in `changes`) replaced, written
/// into `dir` beside copies of the example's other files.
fn example(dir: &Path, name: &str, changes: &[(&str, &str)]) -> PathBuf {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples")).join(name);
    for e in std::fs::read_dir(&root).expect("example folder") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "obj") {
            std::fs::copy(&p, dir.join(p.file_name().expect("name"))).expect("copy mesh");
        }
    }
    let mut text = std::fs::read_to_string(root.join("case.toml")).expect("example");
    for (from, to) in changes {
        assert!(text.contains(from), "{name}: `{from}` not in the example");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("write case");
    path
}

/// Every file of a run's outputs (relative path → bytes), but for those that record how the run
/// went (run-info.toml, the manifest, the lock, checkpoints).
fn outputs(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("folder") {
            let path = e.expect("entry").path();
            let rel = path.strip_prefix(dir).expect("below").to_path_buf();
            let name = rel.to_string_lossy().into_owned();
            if path.is_dir() {
                stack.push(path);
            } else if !["run-info.toml", "manifest.toml", ".grainflow.lock"].contains(&name.as_str())
                && !name.ends_with(".gfc")
            {
                files.insert(rel, std::fs::read(&path).expect("read"));
            }
        }
    }
    files
}

/// How a run is stopped at a step.
#[derive(Debug, Clone, Copy)]
enum Stop {
    /// The stop flag (SIGTERM, SIGINT): a checkpoint at the step it stops at.
    Request,
    /// The process ends at once (SIGKILL): only the last periodic checkpoint is left.
    Crash,
}

/// Runs `case` into `out` (a fresh run, or with `restart` from it), stopped as `stop` says once
/// the run has reached `at` (None: to its end). Returns the step it stopped at.
fn attempt(case: &Path, out: &Path, restart: bool, stop: Option<(u64, Stop)>) -> u64 {
    let flag = Arc::new(AtomicBool::new(false));
    let options = RunOptions {
        checkpoint_every: Some(CheckpointEvery::Steps(700)),
        restart: restart.then(|| out.join("checkpoint.gfc")),
        stop: Some(flag.clone()),
        threads: Some(1),
        ..RunOptions::default()
    };
    let loaded = grainflow_case::load(case).expect("case loads");
    let reached = std::sync::Mutex::new(0);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_case(loaded, out, &options, |sim| {
            *reached.lock().unwrap() = sim.step_index();
            match stop {
                Some((at, Stop::Request)) if sim.step_index() >= at => flag.store(true, Ordering::SeqCst),
                // The run ends where it is: nothing after this point reaches the folder.
                Some((at, Stop::Crash)) if sim.step_index() >= at => {
                    std::panic::resume_unwind(Box::new("crash"))
                }
                _ => {}
            }
        })
    }));
    let step = *reached.lock().unwrap();
    match (result, stop) {
        (Ok(Ok(s)), Some((_, Stop::Request))) if !s.interrupted => panic!("the run ended before step {step}"),
        (Ok(Ok(_)), _) => {}
        (Ok(Err(e)), _) => panic!("run failed at step {step}: {e}"),
        (Err(_), Some((_, Stop::Crash))) => {}
        (Err(e), _) => std::panic::resume_unwind(e),
    }
    step
}

/// The numbers of a time-series column, by its header name.
fn column(series: &str, name: &str) -> Vec<String> {
    let mut lines = series.lines();
    let k = lines.next().expect("header").split(',').position(|c| c == name).expect("column");
    lines.map(|l| l.split(',').nth(k).expect("value").to_string()).collect()
}

/// Stops the run at each of `stops` in turn (each attempt continuing from the checkpoint the
/// last one left), then lets it finish: the files must be the uninterrupted run's, and the
/// books must close in the time series: Σ inserted − Σ removed = the particles of the last
/// snapshot (there are none at the start), an exact count.
fn stopped_and_continued(case: &Path, dir: &Path, stops: &[(u64, Stop)]) {
    let full = dir.join("full");
    attempt(case, &full, false, None);
    let reference = outputs(&full);
    let part = dir.join("part");
    for (k, &(at, how)) in stops.iter().enumerate() {
        let reached = attempt(case, &part, k > 0, Some((at, how)));
        assert!(reached >= at, "stopped at {reached}, before {at}");
    }
    // To the end, and once more from the checkpoint of the last step (a chained restart
    // that has nothing left to do).
    let mut resumed = BTreeMap::new();
    for round in ["to the end", "from the end"] {
        attempt(case, &part, true, None);
        resumed = outputs(&part);
        assert_eq!(
            reference.keys().collect::<Vec<_>>(),
            resumed.keys().collect::<Vec<_>>(),
            "{round}: other files"
        );
        for (name, bytes) in &reference {
            assert!(
                bytes == &resumed[name],
                "{round}: {} differs from the uninterrupted run's after stops at {stops:?}:\n{}\n---\n{}",
                name.display(),
                String::from_utf8_lossy(bytes),
                String::from_utf8_lossy(&resumed[name])
            );
        }
    }
    let series = String::from_utf8(resumed[Path::new("timeseries.csv")].clone()).expect("utf-8");
    let total = |name: &str| -> i64 {
        column(&series, name).iter().map(|v| v.parse::<i64>().unwrap_or_else(|_| panic!("{name}: {v}"))).sum()
    };
    let last_snapshot = resumed
        .iter()
        .rfind(|(p, _)| p.starts_with("snapshots"))
        .map(|(_, b)| String::from_utf8_lossy(b).lines().count() as i64 - 1)
        .expect("a snapshot");
    assert_eq!(total("inserted") - total("removed"), last_snapshot, "the books do not close:\n{series}");
    // Zeros have no sign (a −0 is an accident of the roundings, not a measurement).
    for (name, bytes) in resumed.iter().filter(|(p, _)| p.extension().is_some_and(|x| x == "csv")) {
        let text = String::from_utf8_lossy(bytes);
        assert!(!text.split([',', '\n']).any(|v| v == "-0e0"), "{} holds -0e0", name.display());
    }
}

fn options(out: &Path, restart: Option<&str>, accept_changed_case: bool) -> RunOptions {
    RunOptions {
        checkpoint_every: Some(CheckpointEvery::Steps(700)),
        restart: restart.map(|r| out.join(r)),
        accept_changed_case,
        threads: Some(1),
        ..RunOptions::default()
    }
}

fn pour(dir: &Path) -> PathBuf {
    example(dir, "pour-bed", &[("t_stop = 0.8 ", "t_stop = 0.3 "), ("mass = 0.0125 ", "mass = 0.003 ")])
}

/// With checkpoints on, the run's last step has one, so that a chained restart goes on from
/// the end: the checkpoint's step is the run's step count (15 321 steps, not a multiple of 700).
#[test]
fn the_last_step_has_a_checkpoint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = pour(dir.path());
    let out = dir.path().join("out");
    let s = run_case(grainflow_case::load(&case).unwrap(), &out, &options(&out, None, false), |_| {})
        .expect("runs");
    assert_eq!(s.checkpoint.as_deref(), Some(out.join("checkpoint.gfc").as_path()));
    let bytes = std::fs::read(out.join("checkpoint.gfc")).expect("checkpoint");
    let config = grainflow_case::load(&case).unwrap().config;
    let sim = grainflow::Simulation::restore(config, &bytes, None).expect("restores");
    assert_eq!((sim.step_index(), s.start_step + s.steps), (sim.total_steps(), sim.total_steps()));
    assert!(!sim.total_steps().is_multiple_of(700), "the case should end between periodic checkpoints");
}

/// A restart checks the time series against what its checkpoint recorded: an edited row, rows
/// cut off, or a deleted file is refused with a message naming the file, and nothing in the
/// folder changes. A folder moved whole (checkpoint and all) continues, to the same bytes as
/// a run that was never stopped.
#[test]
fn a_restart_refuses_an_edited_cut_or_missing_time_series() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = pour(dir.path());
    let full = dir.path().join("full");
    attempt(&case, &full, false, None);
    let part = dir.path().join("part");
    attempt(&case, &part, false, Some((6200, Stop::Request)));
    let ts = part.join("timeseries.csv");
    let original = std::fs::read_to_string(&ts).expect("rows");
    let cut = original.find("\n5105,").expect("row of step 5105") + 1;
    let second_row = original.find('\n').unwrap() + 1;
    let edits: [(&str, Option<String>, &str); 4] = [
        ("edited", Some(original.replacen(",0,", ",1,", 1)), "with other contents"),
        ("cut", Some(original[..cut].to_string()), "holds 5 rows"),
        (
            "a row deleted",
            Some(format!(
                "{}{}",
                &original[..second_row],
                &original[original[second_row..].find('\n').unwrap() + second_row + 1..]
            )),
            "was changed since the checkpoint",
        ),
        ("deleted", None, "is missing"),
    ];
    for (what, text, want) in edits {
        match &text {
            Some(t) => std::fs::write(&ts, t).unwrap(),
            None => std::fs::remove_file(&ts).unwrap(),
        }
        let before = outputs(&part);
        let r = run_case(
            grainflow_case::load(&case).unwrap(),
            &part,
            &options(&part, Some("checkpoint.gfc"), false),
            |_| {},
        );
        let e = r.err().unwrap_or_else(|| panic!("{what}: the restart went on"));
        let msg = e.to_string();
        assert!(matches!(e, grainflow_run::run::RunError::Restart { .. }), "{what}: {msg}");
        assert!(msg.contains(&ts.display().to_string()) && msg.contains(want), "{what}: {msg}");
        assert!(before == outputs(&part), "{what}: a refused restart changed the folder");
    }
    // Restored and moved whole, the folder continues to the uninterrupted run's files.
    std::fs::write(&ts, &original).unwrap();
    let moved = dir.path().join("moved");
    std::fs::rename(&part, &moved).unwrap();
    attempt(&case, &moved, true, None);
    assert!(outputs(&full) == outputs(&moved), "the moved folder's outputs differ");
}

/// `--accept-changed-case` keeps the time series up to the checkpoint (docs/case-file.md):
/// the continued file starts with the earlier run's rows before the checkpoint's step, byte
/// for byte. A changed case whose columns differ cannot continue the file: refused, naming it,
/// and the rows are kept.
#[test]
fn a_changed_case_keeps_the_rows_before_its_checkpoint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = pour(dir.path());
    let out = dir.path().join("out");
    attempt(&case, &out, false, Some((6200, Stop::Request)));
    let ts = out.join("timeseries.csv");
    let before = std::fs::read_to_string(&ts).expect("rows");
    let kept = &before[..before.find("\n6200,").expect("the interrupted run's last row") + 1];
    assert_eq!(kept.lines().count(), 1 + 7, "header and the rows of steps 0 to 6 126");
    // Changed settings, the same columns: the rows before the checkpoint are kept.
    let text = std::fs::read_to_string(&case).unwrap();
    let changed = dir.path().join("changed.toml");
    std::fs::write(&changed, text.replace("en = 0.7", "en = 0.6")).unwrap();
    run_case(
        grainflow_case::load(&changed).unwrap(),
        &out,
        &options(&out, Some("checkpoint.gfc"), true),
        |_| {},
    )
    .expect("continues");
    let after = std::fs::read_to_string(&ts).unwrap();
    assert!(after.starts_with(kept) && after.len() > kept.len(), "{after}");
}

/// A changed case whose time-series columns differ (a mesh renamed: its load columns are named
/// after it) cannot continue the file: refused, naming the file and the columns, and the
/// rows are kept as they were.
#[test]
fn a_changed_case_with_other_columns_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = example(
        dir.path(),
        "hopper-fill-discharge",
        &[("t_stop = 3.5 ", "t_stop = 0.2 "), ("count = 3000 ", "count = 400 ")],
    );
    let out = dir.path().join("out");
    attempt(&case, &out, false, Some((2500, Stop::Request)));
    let ts = out.join("timeseries.csv");
    let before = std::fs::read_to_string(&ts).expect("rows");
    let renamed = dir.path().join("renamed.toml");
    let text = std::fs::read_to_string(&case).unwrap();
    std::fs::write(&renamed, text.replacen("name = \"gate\"", "name = \"slide gate\"", 1)).unwrap();
    let r = run_case(
        grainflow_case::load(&renamed).unwrap(),
        &out,
        &options(&out, Some("checkpoint.gfc"), true),
        |_| {},
    );
    let msg = r.expect_err("refused").to_string();
    assert!(
        msg.contains(&ts.display().to_string())
            && msg.contains("mesh_gate_fx")
            && msg.contains("mesh_slide_gate_fx"),
        "{msg}"
    );
    assert_eq!(std::fs::read_to_string(&ts).unwrap(), before);
}

/// The pour-bed example, shortened (0.3 s, 270 beads): stopped while beads are being poured
/// in (batches every 0.02 s = 1 021 steps, as the outputs, up to step 3 063; checkpoints every
/// 700 steps: the stops fall between a batch, an output and a checkpoint in every order, and
/// on a batch's step), and once the pour has ended.
#[test]
fn a_pour_stopped_at_any_moment_continues_to_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = example(
        dir.path(),
        "pour-bed",
        &[("t_stop = 0.8 ", "t_stop = 0.3 "), ("mass = 0.0125 ", "mass = 0.003 ")],
    );
    let stops = [
        (1500, Stop::Request),
        (2042, Stop::Crash),
        (2800, Stop::Request),
        (3063, Stop::Crash),
        (4100, Stop::Crash),
        (6200, Stop::Request),
        (13000, Stop::Crash),
    ];
    stopped_and_continued(&case, dir.path(), &stops);
}

/// The hopper-fill-discharge example, shortened (600 beads, the gate opening at 0.1 s, 0.5 s
/// in all; batches every 408 steps up to step 816, beads leaving from about step 4 000 to the
/// end): stopped while the hopper fills and while the beads discharge through the outlet.
#[test]
fn a_discharge_stopped_at_any_moment_continues_to_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = example(
        dir.path(),
        "hopper-fill-discharge",
        &[
            ("t_stop = 3.5 ", "t_stop = 0.5 "),
            ("count = 3000 ", "count = 600 "),
            ("start = 0.6 ", "start = 0.1 "),
            ("stop = 0.7 ", "stop = 0.2 "),
        ],
    );
    let stops = [
        (300, Stop::Request),
        (600, Stop::Crash),
        (1800, Stop::Crash),
        (4700, Stop::Request),
        (5600, Stop::Crash),
        (6500, Stop::Crash),
        (7300, Stop::Request),
        (8600, Stop::Crash),
    ];
    stopped_and_continued(&case, dir.path(), &stops);
}

/// The pour into a layer too thin for its batches (the region 2.5 mm tall for beads up to
/// 2.4 mm, 640 beads asked a batch, twice what one layer of the 4 cm square holds), so that
/// every batch misses some: the `missed` column, like the others, continues across stops to
/// the uninterrupted run's bytes (the checkpoint's note carries the missed count of the row
/// before its step).
#[test]
fn a_pour_that_misses_continues_its_missed_column_to_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = example(
        dir.path(),
        "pour-bed",
        &[
            ("t_stop = 0.8 ", "t_stop = 0.1 "),
            ("mass = 0.0125 ", "mass = 0.01 "),
            ("rate = 4000.0 ", "rate = 32000.0 "),
            ("min = [0.0, 0.0, 0.06]", "min = [0.0, 0.0, 0.0775]"),
        ],
    );
    let stops = [(700, Stop::Request), (1500, Stop::Crash), (2042, Stop::Request), (3100, Stop::Crash)];
    stopped_and_continued(&case, dir.path(), &stops);
    let series = std::fs::read_to_string(dir.path().join("full/timeseries.csv")).expect("series");
    let missed: u64 = column(&series, "missed").iter().map(|v| v.parse::<u64>().expect("a count")).sum();
    assert!(missed > 0, "no batch missed, so the test tests nothing:\n{series}");
}

/// Beads poured into a turning drum made of a `[[cylinders]]` wall (its ends the box's faces),
/// stopped and continued: the cylinder contacts' springs are in the checkpoints, so the files
/// (the drum's load columns and its VTK tube among them) are the uninterrupted run's.
#[test]
fn a_drum_of_a_cylinder_stopped_at_any_moment_continues_to_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = dir.path().join("drum.toml");
    std::fs::write(
        &case,
        r#"version = 1
title = "Beads poured into a turning drum"
[domain]
min = [-0.03, -0.03, -0.008]
max = [0.03, 0.03, 0.008]
[physics]
gravity = [0.0, -9.80665, 0.0]
[[phases]]
name = "glass"
diameter = 0.003
density = 2500.0
youngs_modulus = 5.0e6
poisson_ratio = 0.3
[[wall_materials]]
name = "steel"
youngs_modulus = 5.0e6
poisson_ratio = 0.3
[[cylinders]]
name = "drum"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
radius = 0.025
side = "inside"
material = "steel"
rpm = 20.0
[contact]
model = "hertz"
[contact.particle]
en = 0.7
et = 0.7
mu = 0.5
[contact.wall]
en = 0.7
et = 0.7
mu = 0.5
[time]
t_stop = 0.2
integrator = "velocity_verlet"
[output]
interval = 0.01
vtk_interval = 0.04
[[insertions]]
name = "fill"
rate = 3000.0
every = 0.02
count = 150
[insertions.region]
kind = "box"
min = [-0.012, -0.005, -0.006]
max = [0.012, 0.012, 0.006]
[[insertions.phases]]
phase = "glass"
"#,
    )
    .expect("write case");
    // 5 448 steps; batches at steps 0, 545 and 1 090; checkpoints every 700 steps.
    let stops = [(600, Stop::Request), (1700, Stop::Crash), (4500, Stop::Request)];
    stopped_and_continued(&case, dir.path(), &stops);
    let series = std::fs::read_to_string(dir.path().join("part/timeseries.csv")).expect("series");
    let header = series.lines().next().expect("header");
    assert!(header.contains(",cylinder_drum_fx,") && header.contains(",cylinder_drum_t_axis,"), "{header}");
    // The beads lie on the drum by the end: it carries their weight (a load along −y).
    let fy: f64 = column(&series, "cylinder_drum_fy").last().expect("a row").parse().expect("a number");
    assert!(fy < 0.0, "the drum carries no weight at the end: {fy}");
    assert!(dir.path().join("part/vtk/cylinders.vtp").exists());
}
