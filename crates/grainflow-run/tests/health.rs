//! The run's health checks on a case with `[[meshes]]`: a stop names its likely cause from what
//! happened (the start's state, an insertion since the last check, a moving mesh, else the
//! contact stiffness and the step).

use std::path::Path;

/// A case in `dir` with one particle high above z = 0 and the given `[[meshes]]` (and other)
/// tables; `extra` is appended as written.
fn write_case(dir: &Path, extra: &str) -> std::path::PathBuf {
    let text = format!(
        r#"version = 1
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]
walls = false
[[phases]]
name = "grain"
diameter = 0.01
density = 2600.0
[[wall_materials]]
name = "steel"
[[wall_materials]]
name = "glass"
[contact.particle]
kn = 1.0e4
[contact.wall]
kn = 1.0e4
[time]
t_stop = 0.001
[[particles.list]]
phase = "grain"
position = [0.0, 0.0, 0.05]
{extra}
"#
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

/// A 100 mm square in the file's x-y plane, corners at 0 and 100 (millimetres), as one OBJ
/// quad (split into two triangles) wound counter-clockwise seen from +z.
const SQUARE_MM: &str = "# square\nv 0 0 0\nv 100 0 0\nv 100 100 0\nv 0 100 0\nf 1 2 3 4\n";

/// Issue 38: run-time stops blamed the time step when the input was at fault. The cause is
/// now named from what happened; here the state's overlap (0.4 of the radius, allowed at the
/// start by `max_initial_overlap = 0.5`) is checked against a limit of 0.3.
#[test]
fn health_stops_name_the_likely_cause() {
    use grainflow_run::run::{Checked, Health, health_problem};
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let load = |extra: &str| {
        let path = write_case(
            dir.path(),
            &format!("[particles]\nmax_initial_overlap = 0.5\nmax_overlap = 0.5\n{extra}"),
        );
        let c = grainflow_case::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let domain = c.domain;
        (grainflow::Simulation::new(c.config, c.particles).unwrap_or_else(|e| panic!("{e}")), domain)
    };
    // Particle 2 (radius 0.005 m) 0.008 m above particle 1: overlap 0.002 m = 0.4 r.
    let (sim, domain) = load("[[particles.list]]\nphase = \"grain\"\nposition = [0.0, 0.0, 0.058]\n");
    let health = Health { domain, leaving_removed: false, max_overlap: 0.3 };
    let at = |checked| health_problem(&sim, health, checked).expect("the overlap is above 0.3");
    // Overlap 2e-3 m of the smaller radius 5e-3 m: 0.400 (exact to rounding).
    let m = at(Checked::Start);
    assert!(m.contains("an overlap reached 0.400 of the smaller radius (particle 1 and particle 2)"), "{m}");
    assert!(m.contains("Likely cause: the state the run starts from (particle 1 and particle 2"), "{m}");
    let m = at(Checked::Since { fresh_from: 2 });
    assert!(m.contains("Likely cause: particle 2 was inserted within the last 100 steps"), "{m}");
    assert!(m.contains("the time step is not to blame"), "{m}");
    // Neither inserted since nor at the start: the stiffness and the step.
    let m = at(Checked::Since { fresh_from: 3 });
    assert!(m.contains("Likely cause: the contact stiffness is too low"), "{m}");
    // A plate moving at 0.5 m/s, 0.002 m under particle 1's centre: overlap 0.003 m = 0.6 r,
    // allowed at the start by max_initial_overlap = 0.7, checked against 0.5.
    let plate = "[[meshes]]\nname = \"plate\"\nfile = \"square.obj\"\nscale = 1e-3\ntranslate = [-0.05, -0.05, 0.048]\n\
                 [meshes.motion]\nkind = \"translate\"\nvelocity = [0.0, 0.0, 0.5]\n";
    let path = write_case(
        dir.path(),
        &format!("[particles]\nmax_initial_overlap = 0.7\nmax_overlap = 0.7\n{plate}"),
    );
    let c = grainflow_case::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let domain = c.domain;
    let sim = grainflow::Simulation::new(c.config, c.particles).unwrap_or_else(|e| panic!("{e}"));
    let health = Health { domain, leaving_removed: false, max_overlap: 0.5 };
    let m = health_problem(&sim, health, Checked::Since { fresh_from: 2 }).expect("0.6 is above 0.5");
    assert!(m.contains("(particle 1 and mesh 'square.obj'"), "{m}");
    let travel = 0.5 * sim.dt();
    for part in [
        "Likely cause: mesh 'square.obj' moved into particle 1: it is translating at 5.0000e-1 m/s"
            .to_string(),
        format!("its fastest point {travel:.4e} m a step"),
        format!("{:.3} of the particle's radius", travel / 0.005),
        format!("or dt to {:.4e} s", 0.1 * 0.005 / 0.5),
    ] {
        assert!(m.contains(&part), "'{part}' not in: {m}");
    }
}
