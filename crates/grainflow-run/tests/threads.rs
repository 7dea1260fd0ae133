//! Every stage on every thread gives the same bytes: the shipped drum, conical hopper and
//! filled hopper, shortened, run on 1, 2, 3 and 4 threads with the threads used from the first
//! particle on (the engine's threshold lowered), write the same time series, snapshots and VTK
//! frames to the byte. The mesh stage (candidates, contacts, loads), the plane-wall pairs, the
//! neighbour list and its history merge, insertions and outlets all run on the threads there.
//! A nudge of one ulp in gravity changes the bytes, so the comparison can fail.

use grainflow_run::run::{RunOptions, run_case};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// An example's case file with `changes` made, written into `dir` beside copies of the
/// example's other files.
fn example(dir: &Path, name: &str, changes: &[(&str, &str)]) -> PathBuf {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples")).join(name);
    for e in std::fs::read_dir(&root).expect("example folder") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "obj" || x == "csv") {
            std::fs::copy(&p, dir.join(p.file_name().expect("name"))).expect("copy");
        }
    }
    let mut text = std::fs::read_to_string(root.join("case.toml")).expect("example");
    for (from, to) in changes {
        assert!(text.contains(from), "{name}: `{from}` not in the example");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join("case.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

/// Every file of a run's outputs (relative path → bytes), but for those that record how the run
/// went (run-info.toml with its thread count, the manifest, the lock).
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
            } else if !["run-info.toml", "manifest.toml", ".grainflow.lock"].contains(&name.as_str()) {
                files.insert(rel, std::fs::read(&path).expect("read"));
            }
        }
    }
    files
}

/// The outputs of `name` with `changes`, run on `threads` threads.
fn run(name: &str, changes: &[(&str, &str)], threads: usize) -> BTreeMap<PathBuf, Vec<u8>> {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = example(dir.path(), name, changes);
    let options = RunOptions { threads: Some(threads), parallel_from: Some(1), ..RunOptions::default() };
    let out = dir.path().join("out");
    let loaded = grainflow_case::load(&case).expect("case loads");
    let summary = run_case(loaded, &out, &options, |_| {}).expect("runs");
    assert_eq!(summary.threads, threads);
    if threads > 1 {
        let r = summary.thread_report;
        assert!(r.steps_on_pool > 0 && r.steps_on_one == 0 && !r.automatic, "{name}: {r:?}");
    }
    outputs(&out)
}

/// The files that differ between two runs' outputs.
fn differing(a: &BTreeMap<PathBuf, Vec<u8>>, b: &BTreeMap<PathBuf, Vec<u8>>) -> Vec<String> {
    let names: std::collections::BTreeSet<&PathBuf> = a.keys().chain(b.keys()).collect();
    names.into_iter().filter(|k| a.get(*k) != b.get(*k)).map(|k| k.display().to_string()).collect()
}

fn check(name: &str, changes: &[(&str, &str)]) {
    let want = run(name, changes, 1);
    assert!(want.keys().any(|k| k.starts_with("vtk")), "{name}: no VTK frames: {:?}", want.keys());
    for threads in [2, 3, 4] {
        let diff = differing(&want, &run(name, changes, threads));
        assert!(diff.is_empty(), "{name}: 1 and {threads} threads differ in {diff:?}");
    }
}

/// The drum turning at 10 rpm from the start (its ramp cut), 1 267 beads against 6 400
/// triangles: the turning mesh's candidates are kept while the beads turn with it.
#[test]
fn the_drum_gives_the_same_bytes_on_any_thread_count() {
    check(
        "rotating-drum",
        &[
            ("ramp = 0.8", ""),
            ("t_stop = 3.0", "t_stop = 0.06"),
            ("interval = 0.05", "interval = 0.01"),
            ("vtk_interval = 0.05", "vtk_interval = 0.02"),
        ],
    );
}

/// The conical hopper discharging: beads crossing the cone's triangles and leaving.
#[test]
fn the_conical_hopper_gives_the_same_bytes_on_any_thread_count() {
    check(
        "conical-hopper",
        &[
            ("t_stop = 3.5", "t_stop = 0.06"),
            ("interval = 0.05", "interval = 0.01"),
            ("vtk_interval = 0.05", "vtk_interval = 0.02"),
        ],
    );
}

/// The hopper filled by its insertion: batches of beads appended while the mesh stage runs.
#[test]
fn the_filled_hopper_gives_the_same_bytes_on_any_thread_count() {
    check(
        "hopper-fill-discharge",
        &[
            ("t_stop = 3.5", "t_stop = 0.1"),
            ("interval = 0.05", "interval = 0.01"),
            ("vtk_interval = 0.05", "vtk_interval = 0.02"),
        ],
    );
}

/// The comparison sees a change of one ulp in gravity.
#[test]
fn a_nudge_of_one_ulp_changes_the_bytes() {
    let changes = [("t_stop = 3.5", "t_stop = 0.06"), ("vtk_interval = 0.05", "vtk_interval = 0.02")];
    let nudged = [changes[0], changes[1], ("-9.80665]", "-9.806650000000001]")];
    assert_ne!(-9.80665f64, -9.806650000000001f64);
    let diff = differing(&run("conical-hopper", &changes, 1), &run("conical-hopper", &nudged, 2));
    assert!(diff.iter().any(|f| f.starts_with("snapshots")), "{diff:?}");
}
