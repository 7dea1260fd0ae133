//! `[[insertions]]` that bring particles from a file at a time, and streams through a face:
//! what comes in, where, when and how fast, with the mass books closed exactly.

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

/// The particles of a file come in at `at` as they are: their positions, diameters and
/// velocities; new ids after the largest; the books count their mass exactly.
#[test]
fn particles_from_a_file_come_in_as_they_are_at_their_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("more.csv"),
        "id,phase,x,y,z,diameter,u,v,w\n\
         7,glass,0.02,0.02,0.02,0.003,0.1,0.0,0.0\n\
         9,glass,0.03,0.02,0.02,0.0015,0.0,-0.2,0.0\n",
    )
    .expect("write particles");
    let case = write_case(dir.path(), "[[insertions]]\nname = \"more\"\nfile = \"more.csv\"\nat = 0.01\n");
    let case = grainflow_case::load(&case).expect("case loads");
    let mut sim = Simulation::new(case.config, case.particles).expect("set-up");
    while sim.time() < 0.01 - 1e-12 {
        sim.step();
        assert_eq!(sim.particles().len(), 1, "nothing before t = 0.01 s (t = {})", sim.time());
    }
    sim.step();
    let p = sim.particles();
    assert_eq!(p.len(), 3, "both file particles at the first step from 0.01 s");
    // The present particle has id 1 (the list's); the new ones follow it, in the file's order.
    let slot = |id: u32| p.id.iter().position(|&i| i == id).expect("id");
    let (a, b) = (slot(2), slot(3));
    // No contact and no gravity: inserted at the start of the step, a particle has moved by
    // its velocity times one step (1e-5 s): 1e-6 and 2e-6 m; velocities are exact.
    let moved = |i: usize, x: [f64; 3]| (p.position[i] - grainflow::Vec3::from_array(x)).length();
    assert!((moved(a, [0.02, 0.02, 0.02]) - 1e-6).abs() < 1e-12);
    assert!((moved(b, [0.03, 0.02, 0.02]) - 2e-6).abs() < 1e-12);
    assert_eq!((2.0 * p.radius[a], 2.0 * p.radius[b]), (0.003, 0.0015));
    assert_eq!(p.velocity[a].to_array(), [0.1, 0.0, 0.0]);
    assert_eq!(p.velocity[b].to_array(), [0.0, -0.2, 0.0]);
    let books = sim.flow_books();
    assert_eq!(books.inserted.iter().map(|t| t.count).sum::<u64>(), 2);
    assert!(books.close(), "inserted = present + removed, exactly: {books:?}");
    // Mass: ρ·π/6·d³ of each, to rounding.
    let m = |d: f64| 2500.0 * std::f64::consts::FRAC_PI_6 * d * d * d;
    let inserted = books.inserted.iter().map(|t| t.units).sum::<i128>() as f64 * books.quantum;
    assert!((inserted - (m(0.003) + m(0.0015))).abs() < 1e-12 * inserted);
}

/// A stream through a disc face: every particle is placed in the column upstream of the face
/// that the stream carries through it in one interval, |v|·every deep, within the disc's
/// radius; and the rate is kept.
#[test]
fn a_stream_through_a_face_places_its_particles_upstream_of_the_face() {
    let dir = tempfile::tempdir().expect("temp dir");
    let extra = r#"
[[insertions]]
name = "stream"
rate = 2000.0
every = 0.005
velocity = [0.0, 0.0, -1.0]
[insertions.region]
kind = "face"
base = [0.02, 0.02, 0.03]
radius = 0.008
[[insertions.phases]]
phase = "glass"
"#;
    let case = grainflow_case::load(&write_case(dir.path(), extra)).expect("case loads");
    let mut sim = Simulation::new(case.config, case.particles).expect("set-up");
    // The first batch comes at the start: 2000/s × 5 ms = 10 particles, in the column
    // z ∈ [0.03, 0.035] (|v|·every = 5 mm, more than a diameter) within 8 mm of the axis.
    let p = sim.particles();
    assert_eq!(p.len(), 11, "the present particle and the first batch");
    for i in 0..p.len() {
        if p.id[i] == 1 {
            continue;
        }
        let x = p.position[i];
        let r = p.radius[i];
        assert!(x.z - r >= 0.03 - 1e-12 && x.z + r <= 0.035 + 1e-12, "z = {}", x.z);
        assert!(((x.x - 0.02).powi(2) + (x.y - 0.02).powi(2)).sqrt() + r <= 0.008 + 1e-12);
        assert_eq!(p.velocity[i].to_array(), [0.0, 0.0, -1.0]);
    }
    // Batch k brings the total to 2000·(k + 1)·0.005: 100 by the batch at 0.045 s.
    while sim.time() < 0.0451 {
        sim.step();
    }
    let books = sim.flow_books();
    assert_eq!(books.inserted[0].count, 100, "{books:?}");
    assert!(books.close());
}

/// A run with an insertion restarts from its checkpoint with a changed case (a later end):
/// the checkpoint's particles are the case's and the inserted ones, which the check of the
/// case's particles accepts; it continues with all of them.
#[test]
fn a_run_with_insertions_restarts_with_a_changed_case() {
    use grainflow_case::run::{CheckpointEvery, RunOptions, run_case};
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
