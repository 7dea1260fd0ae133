//! Runs of cases with `[[insertions]]` and `[[outlets]]` to their outputs: a restart with a
//! changed case, the time series' count of the particles that found no room, and a stream
//! through an outlet that runs to its end (the books themselves: grainflow-case's
//! `tests/insertions.rs`).

use grainflow::Simulation;
use std::path::Path;

/// A closed 40 mm box without gravity, one glass phase of 2 mm, one particle present, and the
/// `extra` tables.
fn write_case(dir: &Path, extra: &str) -> std::path::PathBuf {
    let text = format!(
        r#"version = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [0.04, 0.04, 0.04]
[physics]
gravity = [0.0, 0.0, 0.0]
[[phases]]
name = "glass"
diameter = 0.002
density = 2500.0
[contact.particle]
kn = 1.0e3
en = 0.9
[contact.wall]
kn = 1.0e3
en = 0.9
[time]
t_stop = 0.05
dt = 1.0e-5
[[particles.list]]
phase = "glass"
position = [0.005, 0.005, 0.005]
{extra}
"#
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

/// A run with an insertion restarts from its checkpoint with a changed case (a later end):
/// the checkpoint's particles are the case's and the inserted ones, which the check of the
/// case's particles accepts; it continues with all of them.
#[test]
fn a_run_with_insertions_restarts_with_a_changed_case() {
    use grainflow_run::run::{CheckpointEvery, RunOptions, run_case};
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = "[[insertions]]\nname = \"pour\"\nrate = 2000.0\nevery = 0.005\n[insertions.region]\nkind = \"box\"\nmin = [0.0, 0.0, 0.02]\nmax = [0.04, 0.04, 0.04]\n[[insertions.phases]]\nphase = \"glass\"\n";
    let path = write_case(dir.path(), extra);
    let text = std::fs::read_to_string(&path).expect("case").replace("t_stop = 0.05", "t_stop = 0.02");
    std::fs::write(&path, text).expect("write");
    let first = RunOptions { checkpoint_every: Some(CheckpointEvery::Steps(1000)), ..RunOptions::default() };
    let out = dir.path().join("out");
    let s = run_case(grainflow_case::load(&path).expect("case"), &out, &first, |_| {}).expect("first run");
    assert!(s.particles.1 > s.particles.0, "{:?}", s.particles);
    let checkpoint = s.checkpoint.expect("a checkpoint");
    let text = std::fs::read_to_string(&path).expect("case").replace("t_stop = 0.02", "t_stop = 0.03");
    std::fs::write(&path, text).expect("write");
    let again = RunOptions {
        restart: Some(checkpoint),
        accept_changed_case: true,
        overwrite: true,
        ..RunOptions::default()
    };
    let r = run_case(grainflow_case::load(&path).expect("case"), &out, &again, |_| {})
        .expect("the changed case restarts");
    // The checkpoint of the last step (t = 0.02 s: with checkpoints on, the last step has
    // one) holds the particles the first run ended with; the restart runs on to 0.03 s.
    assert_eq!(r.particles.0, s.particles.1, "the restart starts with the checkpoint's particles");
    assert_eq!(r.start_step, s.start_step + s.steps, "it starts where the first run ended");
    assert!(r.particles.1 > s.particles.1, "and goes on inserting: {:?} {:?}", r.particles, s.particles);
}

/// Issue 38, items 10: 100 beads asked into a box that has room for at most 3 of them
/// (24 × 2.4 × 2.4 mm for 2 mm beads: at most 0.4 mm of offset across, so centres along
/// the box at least √(1 − 2·0.2²) = 0.959 d apart within 5 mm: three at most). The books give
/// asked = inserted + missed exactly, a notice names the insertion and its shortfall, and the
/// run's time series carries the missed count.
#[test]
fn particles_that_find_no_room_are_counted_reported_and_in_the_time_series() {
    use grainflow_run::run::{RunOptions, run_case};
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = r#"
[[insertions]]
name = "crowd"
count = 100
[insertions.region]
kind = "box"
min = [0.01, 0.01, 0.01]
max = [0.017, 0.0124, 0.0124]
[[insertions.phases]]
phase = "glass"
"#;
    let path = write_case(dir.path(), extra);
    let case = grainflow_case::load(&path).expect("case loads");
    let sim = Simulation::new(case.config, case.particles).expect("set-up");
    let b = sim.flow_books();
    assert_eq!(b.asked[0], 100);
    assert_eq!(b.inserted[0].count + b.missed[0], 100, "{b:?}");
    assert!((1..=3).contains(&b.inserted[0].count), "{b:?}");
    let notices = sim.flow_notices().join("\n");
    let expect = format!("insertion 'crowd' at t = 0.000000e0 s: {} of the 100 particles asked", b.missed[0]);
    assert!(notices.contains(&expect), "{notices}");
    assert_eq!(sim.flow_notices().len(), 1);

    let text = std::fs::read_to_string(&path).expect("case").replace("t_stop = 0.05", "t_stop = 0.001");
    std::fs::write(&path, text).expect("write");
    let out = dir.path().join("out");
    run_case(grainflow_case::load(&path).expect("case"), &out, &RunOptions::default(), |_| {}).expect("runs");
    let series = std::fs::read_to_string(out.join(grainflow_run::outdir::TIMESERIES_FILE)).expect("series");
    let mut lines = series.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = header.iter().position(|&c| c == "missed").expect("a missed column");
    let missed: f64 =
        lines.map(|l| l.split(',').nth(col).expect("value").parse::<f64>().expect("number")).sum();
    assert_eq!(missed, b.missed[0] as f64, "the column's sum is the books' count");
}

/// The stream of the outlet tests: 2000 beads/s of 2 mm falling at 1 m/s (no gravity, no
/// contact between them: they all move alike) from a face at z = 35 mm, in a box open at
/// the bottom.
const STREAM: &str = r#"
[[insertions]]
name = "stream"
rate = 2000.0
every = 0.005
velocity = [0.0, 0.0, -1.0]
[insertions.region]
kind = "face"
base = [0.02, 0.02, 0.035]
radius = 0.008
[[insertions.phases]]
phase = "glass"
"#;

/// `write_case` with the domain's bottom face open, ending at `t_stop`.
fn open_bottom_case(dir: &Path, extra: &str, t_stop: f64) -> std::path::PathBuf {
    let path = write_case(dir, extra);
    let text = std::fs::read_to_string(&path)
        .expect("case")
        .replace(
            "max = [0.04, 0.04, 0.04]\n",
            "max = [0.04, 0.04, 0.04]\nwalls = [\"x_min\", \"x_max\", \"y_min\", \"y_max\", \"z_max\"]\n",
        )
        .replace("t_stop = 0.05", &format!("t_stop = {t_stop}"));
    std::fs::write(&path, text).expect("write");
    path
}

/// Issue 38, item 24: an outlet on an open face with the default `leaving = "stop"` catches
/// every particle that crosses it, at any step between the outlets' drains and the run's
/// health checks: a stream through it for 10 000 steps runs to its end, the books close
/// exactly, and no particle present at the end is below the face by more than the ten steps
/// (1e-4 m at 1 m/s) a caught particle goes on for before it is removed.
#[test]
fn an_outlet_on_an_open_face_catches_every_particle_that_crosses_it() {
    use grainflow_run::run::{RunOptions, run_case};
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = format!(
        "{STREAM}\n[[outlets]]\nname = \"floor\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, -1.0]\n"
    );
    let path = open_bottom_case(dir.path(), &extra, 0.1);
    let case = grainflow_case::load(&path).expect("case loads");
    let out = dir.path().join("out");
    let s = run_case(case, &out, &RunOptions::default(), |_| {}).expect("the stream runs to its end");
    assert!(s.steps >= 10_000);
    // Batches at 0, 5, …, 95 ms bring 2000 × 0.1 = 200 beads (the last at 95 ms); those
    // placed in the column [35, 40] mm (|v|·every = 5 mm, more than two diameters) come through the
    // face within 40 ms: at least the 12 batches up to 55 ms are out by 0.1 s.
    let case = grainflow_case::load(&path).expect("case loads");
    let mut sim = Simulation::new(case.config, case.particles).expect("set-up");
    sim.advance(sim.total_steps());
    let b = sim.flow_books();
    assert_eq!(b.inserted[0].count, 200, "{b:?}");
    assert!(b.close(), "initial + inserted = present + removed: {b:?}");
    assert!(b.removed[0].count >= 120, "{b:?}");
    let p = sim.particles();
    assert!(
        p.position.iter().all(|x| x.z >= -1e-4 - 1e-9),
        "a particle below the face for more than 10 steps"
    );
}
