//! The last good state of a run that fails its health check is the same whether it was kept
//! in memory (small states) or in a file (large states, so that the copy does not add to the
//! run's memory): the same state to the bit, and it restarts — also on ranks, where each keeps
//! its part in memory or in a file of its own and a failure gathers them. A healthy run leaves
//! no copy behind.

use grainflow_run::run::{LAST_GOOD_FILE, RunError, RunOptions, run_case};
use std::path::Path;

/// The settling-bed example, shortened; with `unstable`, its time step forced 30× above the
/// safe one, so that it blows up within a few hundred steps.
fn case(dir: &Path, unstable: bool) -> grainflow_case::Case {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/settling-bed");
    let mut text = std::fs::read_to_string(format!("{root}/case.toml"))
        .expect("example")
        .replace("particles.csv", &format!("{root}/particles.csv"))
        .replace("t_stop = 0.5", "t_stop = 0.05");
    if unstable {
        text = text.replace("integrator = \"euler\"", "integrator = \"euler\"\ndt = 4e-4\nforce_dt = true");
    }
    let path = dir.join(if unstable { "bad.toml" } else { "good.toml" });
    std::fs::write(&path, text).expect("write case");
    grainflow_case::load(&path).expect("case loads")
}

fn options(max_in_memory: usize) -> RunOptions {
    RunOptions { last_good_in_memory: Some(max_in_memory), ..RunOptions::default() }
}

#[test]
fn last_good_state_kept_in_a_file_equals_the_one_kept_in_memory() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut saved = Vec::new();
    let runs = [
        ("memory", 1, usize::MAX),
        ("file", 1, 0),
        ("2 ranks, memory", 2, usize::MAX),
        ("3 ranks, files", 3, 0),
    ];
    for (name, ranks, max_in_memory) in runs {
        let out = dir.path().join(name);
        let result = on_ranks(ranks, &out, max_in_memory, &|| case(dir.path(), true));
        let Err(RunError::Unhealthy { good_step, saved: path, .. }) = result else {
            panic!("{name}: the forced time step should fail the health check: {result:?}");
        };
        assert_eq!(path, out.join(LAST_GOOD_FILE));
        let rolling: Vec<_> = std::fs::read_dir(&out)
            .expect("out")
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains("rolling"))
            .collect();
        assert!(rolling.is_empty(), "{name}: rolling copy left behind: {rolling:?}");
        saved.push((good_step, std::fs::read(&path).expect("saved state")));
    }
    // The runs have run ids of their own: the states they saved are compared whole.
    let restore = |bytes: &[u8]| {
        grainflow::Simulation::restore(case(dir.path(), true).config, bytes, None).expect("restores")
    };
    let a = restore(&saved[0].1);
    for (k, (step, bytes)) in saved.iter().enumerate().skip(1) {
        let name = runs[k].0;
        assert_eq!(saved[0].0, *step, "{name}: another step kept");
        let b = restore(bytes);
        assert_ne!(a.run_id(), b.run_id());
        assert_eq!(a.step_index(), b.step_index());
        if runs[k].1 == 1 {
            assert!(a.particles() == b.particles(), "{name}: the copies' particles differ");
            assert!(a.neighbors().state() == b.neighbors().state(), "{name}: the copies' contacts differ");
        }
        // Gathered from ranks, the state is in id order: the same particles and contacts.
        let ((pa, ca), (pb, cb)) = (a.in_id_order(), b.in_id_order());
        assert!(pa == pb, "{name}: the copies' particles differ");
        assert_eq!(format!("{ca:?}"), format!("{cb:?}"), "{name}: the copies' contacts differ");
    }
}

/// The run of `case` on `ranks` ranks (threads joined by a `LocalComm`; one: no ranks) into
/// `out` (the other ranks into folders of their own), keeping states up to `max_in_memory`
/// bytes in memory; rank 0's result.
fn on_ranks(
    ranks: usize,
    out: &Path,
    max_in_memory: usize,
    case: &(dyn Fn() -> grainflow_case::Case + Sync),
) -> Result<grainflow_run::run::RunSummary, RunError> {
    if ranks == 1 {
        return run_case(case(), out, &options(max_in_memory), |_| {});
    }
    // Loaded once (the loader writes the case file).
    let case = case();
    let case = &case;
    let comms = grainflow::domain::LocalComm::team(ranks);
    let mut results: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = comms
            .into_iter()
            .enumerate()
            .map(|(r, comm)| {
                let out = if r == 0 { out.to_path_buf() } else { out.with_extension(format!("rank{r}")) };
                s.spawn(move || {
                    let comm: std::sync::Arc<dyn grainflow::domain::Comm> = std::sync::Arc::new(comm);
                    let options = RunOptions { ranks: Some(comm), ..options(max_in_memory) };
                    run_case(case.clone(), &out, &options, |_| {})
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("rank")).collect()
    });
    results.swap_remove(0)
}

#[test]
fn a_healthy_run_leaves_no_copy_of_its_last_good_state() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    run_case(case(dir.path(), false), &out, &options(0), |_| {}).expect("healthy run");
    let names: Vec<String> = std::fs::read_dir(&out)
        .expect("out")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into())
        .collect();
    assert!(names.iter().all(|n| !n.contains("last-good")), "{names:?}");
    assert!(names.contains(&"timeseries.csv".to_string()), "{names:?}");
}
