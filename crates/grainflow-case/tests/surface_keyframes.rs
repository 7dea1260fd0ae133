//! `[meshes.surface] keyframes`: a surface velocity scaled in time by an MFIX key-frame file.
//! A bead resting on a belt whose speed ramps up by a key-frame table is carried rolling; a
//! table held at 0 is a fixed floor and a table held at 1 the constant belt, bit for bit; the
//! file is in the case hash; bad files and keys are refused with the file's line.

use grainflow::Simulation;
use grainflow::Vec3;
use grainflow::mesh::SurfaceMotion;
use std::path::Path;

/// A 100 mm square at z = 0 (OBJ, counter-clockwise seen from +z: normal +z).
const SQUARE: &str = "v -0.05 -0.05 0\nv 0.05 -0.05 0\nv 0.05 0.05 0\nv -0.05 0.05 0\nf 1 2 3 4\n";

/// Bead: 10 mm, 2600 kg/m³ (m = 1.361e-3 kg); walls k_n = 1e4 N/m, so it rests with the
/// overlap m g/k_n = 1.335e-6 m, where it starts (so it hardly bounces).
const R: f64 = 0.005;
const OVERLAP: f64 = 2600.0 * std::f64::consts::PI / 6.0 * 1e-6 * 9.81 / 1e4;

/// A case in `dir`: the bead on the square, a belt `surface` table (appended after
/// `[meshes.surface]`, or no such table if empty), `files` written beside it.
fn case(dir: &Path, surface: &str, files: &[(&str, &str)], t_stop: f64) -> std::path::PathBuf {
    std::fs::write(dir.join("belt.obj"), SQUARE).expect("write mesh");
    for (name, text) in files {
        std::fs::write(dir.join(name), text).expect("write file");
    }
    let surface = if surface.is_empty() { String::new() } else { format!("[meshes.surface]\n{surface}") };
    let text = format!(
        r#"version = 1
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]
walls = false
[physics]
gravity = [0.0, 0.0, -9.81]
[[phases]]
name = "grain"
diameter = 0.01
density = 2600.0
[[wall_materials]]
name = "rubber"
[contact.particle]
kn = 1.0e4
[contact.wall]
kn = 1.0e4
mu = 0.5
[time]
t_stop = {t_stop}
[[particles.list]]
phase = "grain"
position = [0.0, 0.0, {z}]
[[meshes]]
name = "belt"
file = "belt.obj"
{surface}"#,
        z = R - OVERLAP
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

fn run(path: &Path) -> Simulation {
    let c = grainflow_case::load(path).unwrap_or_else(|e| panic!("valid case: {e}"));
    let mut sim = Simulation::new(c.config, c.particles).expect("set-up");
    sim.run_to_end();
    sim
}

/// The belt (0.1 m/s along x) ramps by the table from rest to full speed over 0.1 s and then
/// holds it (a = 1 m/s²: the friction a rolling bead needs, (2/7)·m·a, is 6 % of μ m g, so it
/// does not slip). A rolling solid sphere on a belt accelerating at a accelerates at (2/7)·a,
/// so at 0.15 s the bead's centre moves at (2/7)·V = 28.6 mm/s and the point touching the belt
/// (v − R ω_y along x) at the belt's V. The tangential spring takes up the force over its
/// period 2π·√(2m/(7 k_t)) ≈ 2.3 ms, and when the ramp starts and stops the bead lags by the
/// spring's stretch: a velocity swing of about (2/7)·a·m/k_t·ω_t ≈ 0.4 mm/s, damped after that
/// — 1 mm/s (1 % of V) bounds it (the run shows 0.2 mm/s). At 0.05 s, in the ramp, the belt
/// is at V/2 and the contact point with it (same bound).
#[test]
fn a_ramped_belt_carries_a_resting_bead_rolling() {
    let dir = tempfile::tempdir().expect("temp dir");
    let kf = "3, 1\nlinear\n! time var1\n0.0 0.0\n0.1 1.0\n0.2 1.0\n";
    let v = 0.1;
    let at = |t_stop: f64| {
        let path = case(
            dir.path(),
            "velocity = [0.1, 0.0, 0.0]\nkeyframes = \"ramp.txt\"\n",
            &[("ramp.txt", kf)],
            t_stop,
        );
        let sim = run(&path);
        let p = sim.particles();
        let (u, w) = (p.velocity[0], p.omega[0]);
        (u, u.x - R * w.y, sim.time())
    };
    let tol = 1e-3;
    let (u, contact, t) = at(0.05);
    assert!((t - 0.05).abs() < 1e-4, "t {t}");
    assert!((contact - v * t / 0.1).abs() < tol, "contact point {contact} at {t}");
    assert!((u.x - 2.0 / 7.0 * v * t / 0.1).abs() < tol, "centre {u:?} at {t}");
    let (u, contact, _) = at(0.15);
    assert!((contact - v).abs() < tol, "contact point {contact}");
    assert!((u.x - 2.0 / 7.0 * v).abs() < tol, "centre {u:?}");
    // Nothing pushes across the belt: y stays at rest to rounding.
    assert!(u.y.abs() < 1e-12, "{u:?}");
}

/// A table held at 0 is a fixed floor, and one held at 1 the constant belt, to the bit: the
/// factor multiplies the velocity by exactly 0 or 1, and the contact sees the same numbers.
#[test]
fn a_table_held_at_zero_or_one_is_the_fixed_floor_or_the_constant_belt_bit_for_bit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let zero = "2, 2\nstep\n! t off on\n0.0 0.0 1.0\n0.05 0.0 1.0\n";
    let state = |surface: &str| {
        let path = case(dir.path(), surface, &[("k.txt", zero)], 0.02);
        let sim = run(&path);
        let p = sim.particles();
        (p.position[0], p.velocity[0], p.omega[0])
    };
    let fixed = state("");
    let held = state("velocity = [0.1, 0.0, 0.0]\nkeyframes = \"k.txt\"\n");
    assert_eq!(held, fixed);
    assert_eq!(fixed.1.x, 0.0);
    let belt = state("velocity = [0.1, 0.0, 0.0]\n");
    let one = state("velocity = [0.1, 0.0, 0.0]\nkeyframes = \"k.txt\"\nkeyframe_column = 2\n");
    assert_eq!(one, belt);
    assert!(belt.1.x > 1e-3, "the belt carries the bead: {:?}", belt.1);
}

/// The case layer: the table's column, times from the run's start (the file's times are the
/// case's), a turning surface's ω scaled, the key-frame file in the case hash.
#[test]
fn the_table_becomes_the_walls_factor_and_is_in_the_case_hash() {
    let dir = tempfile::tempdir().expect("temp dir");
    let kf = "2 2\nlinear\nheader\n1.0 0.0 5.0\n3.0 1.0 5.0\n";
    let path = case(
        dir.path(),
        "axis = [0.0, 1.0, 0.0]\nomega = 2.0\nkeyframes = \"drum.txt\"\n",
        &[("drum.txt", kf)],
        1.1,
    );
    std::fs::write(&path, std::fs::read_to_string(&path).unwrap().replace("t_stop", "t_start = 1.0\nt_stop"))
        .unwrap();
    let c = grainflow_case::load(&path).expect("valid case");
    let w = &c.config.meshes[0];
    // τ = 0.5 s after the start is t = 1.5 s: a quarter of the way from 0 to 1 (exact).
    let turning = |omega| SurfaceMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Y, omega };
    assert_eq!(w.surface, turning(2.0));
    assert_eq!(w.surface_at(0.5), turning(0.5));
    assert_eq!(w.surface_at(-1.0), turning(0.0));
    assert_eq!(w.surface_at(7.0), turning(2.0));
    // The hash covers the key-frame file's text.
    std::fs::write(dir.path().join("drum.txt"), kf.replace("3.0 1.0", "3.0 2.0")).unwrap();
    let d = grainflow_case::load(&path).expect("valid case");
    assert_ne!(c.hash, d.hash);
    // At τ = 2 s (t = 3 s) the factor is the new last row's 2.
    assert_eq!(d.config.meshes[0].surface_at(2.0), turning(4.0));
}

fn refused(surface: &str, files: &[(&str, &str)], words: &[&str]) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = case(dir.path(), surface, files, 0.01);
    let Err(e) = grainflow_case::load(&path) else { panic!("accepted: {surface}") };
    assert!(matches!(e, grainflow_case::CaseError::Invalid { .. }), "{e:?}");
    let m = e.to_string();
    for w in words {
        assert!(m.contains(w), "`{w}` not in: {m}");
    }
}

#[test]
fn bad_key_frame_files_and_keys_are_refused() {
    let belt = "velocity = [0.1, 0.0, 0.0]\n";
    let good = ("k.txt", "2, 1\nlinear\n!\n0 0\n1 1\n");
    let with = |extra: &str| format!("{belt}keyframes = \"k.txt\"\n{extra}");
    refused(&with(""), &[], &["[surface]", "`keyframes` = \"k.txt\"", "cannot be read"]);
    refused(&with("keyframe_column = 2\n"), &[good], &["column 2", "1 variable"]);
    refused(&with("keyframe_column = 0\n"), &[good], &["`keyframe_column` = 0", "from 1"]);
    refused(&format!("{belt}keyframe_column = 1\n"), &[good], &["without `keyframes`"]);
    refused(&with(""), &[("k.txt", "2, 1\nlinear\n!\n0 0\n1 fast\n")], &["line 5", "`fast`"]);
    refused(&with(""), &[("k.txt", "3, 1\nlinear\n!\n0 0\n1 1\n")], &["declares 3 row(s)"]);
    refused(&with(""), &[("k.txt", "2000000000, 1\nlinear\n!\n0 0\n")], &["line 1", "from 1 to 1000000"]);
    refused(&with(""), &[("k.txt", "2, 1\ncubic\n!\n0 0\n1 1\n")], &["line 2", "`cubic`"]);
}
