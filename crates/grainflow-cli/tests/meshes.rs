//! `[[meshes]]` in a case file, run as a user would: a particle dropped onto a two-triangle
//! floor, the same drop onto a plane wall, and the input the program refuses (exit 2).

use std::path::Path;
use std::process::{Command, Output};

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

/// Half the floor's side, m.
const HALF: f64 = 0.05;
/// Particle radius, m (diameter 0.01 m in the case).
const R: f64 = 0.005;
/// Particle mass, kg: 2600 kg/m³ · π d³/6.
const MASS: f64 = 2600.0 * std::f64::consts::PI / 6.0 * 1e-6;
const G: f64 = 9.80665;

/// The floor z = 0 over [−HALF, HALF]², as two triangles wound counter-clockwise seen from
/// above (normals +z), their shared diagonal through the origin where the particle lands.
fn floor() -> [[[f64; 3]; 3]; 2] {
    let (a, b, c, d) = ([-HALF, -HALF, 0.0], [HALF, -HALF, 0.0], [HALF, HALF, 0.0], [-HALF, HALF, 0.0]);
    [[a, b, c], [a, c, d]]
}

fn ascii_stl(triangles: &[[[f64; 3]; 3]]) -> String {
    let mut s = String::from("solid floor\n");
    for t in triangles {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for v in t {
            s.push_str(&format!("      vertex {:e} {:e} {:e}\n", v[0], v[1], v[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s + "endsolid floor\n"
}

/// A binary STL: 80-byte header, the count, 50 bytes a facet (normal, corners, attribute).
fn binary_stl(triangles: &[[[f64; 3]; 3]]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        b.extend_from_slice(&[0u8; 12]);
        for v in t {
            for x in v {
                b.extend_from_slice(&(*x as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

/// The drop: one particle from z = 0.05 m, gravity −z, no box walls; `floor` is the table
/// (`[[meshes]]` or `[[walls]]`) that holds it, `particle_z` its start height.
fn case(floor: &str, particle_z: f64) -> String {
    format!(
        r#"version = 1
[domain]
min = [{lo}, {lo}, -0.01]
max = [{hi}, {hi}, 0.1]
walls = false

[physics]
gravity = [0.0, 0.0, -9.80665]

[[phases]]
name = "grain"
diameter = 0.01
density = 2600.0

[contact]
model = "lsd"

[contact.particle]
kn = 1.0e5

[contact.wall]
kn = 1.0e5
en = 0.9

[time]
t_stop = 0.15
dt = 2.0e-6

[output]
interval = 2.0e-5
snapshots = false

[[particles.list]]
phase = "grain"
position = [0.0, 0.0, {particle_z}]

{floor}
"#,
        lo = -HALF,
        hi = HALF,
    )
}

const MESH: &str = "[[meshes]]\nname = \"floor\"\nfile = \"floor.stl\"\n";

fn run(dir: &Path, text: &str) -> Output {
    std::fs::write(dir.join("case.toml"), text).expect("write case");
    grainflow()
        .arg("run")
        .arg(dir.join("case.toml"))
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .expect("runs")
}

/// The time series' rows (step, time, kinetic_translational, kinetic_rotational, potential,
/// elastic, contacts, max_overlap_ratio).
fn series(dir: &Path) -> Vec<Vec<f64>> {
    let ts = std::fs::read_to_string(dir.join("out/timeseries.csv")).expect("time series");
    assert!(ts.starts_with("step,time,kinetic_translational,kinetic_rotational,potential,"), "{ts:.80}");
    ts.lines().skip(1).map(|l| l.split(',').map(|f| f.parse().expect("number")).collect()).collect()
}

/// The particle's height from the potential energy −m·g·x = m·g·z.
fn heights(rows: &[Vec<f64>]) -> Vec<f64> {
    rows.iter().map(|r| r[4] / (MASS * G)).collect()
}

#[test]
fn a_two_triangle_floor_holds_a_dropped_particle_and_it_rebounds() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("floor.stl"), ascii_stl(&floor())).expect("write mesh");
    let out = run(dir.path(), &case(MESH, 0.05));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let z = heights(&series(dir.path()));
    // Output every 2e-5 s over 0.15 s: 7 500 rows after the initial one.
    assert!(z.len() > 7000, "{} rows", z.len());
    assert!((z[0] - 0.05).abs() < 1e-12, "start {}", z[0]);
    let lowest = z.iter().copied().fold(f64::INFINITY, f64::min);
    // It lands at v = √(2 g · 0.045 m) = 0.9395 m/s; the linear spring of k = 1e5 N/m on
    // m = 1.361e-3 kg (ω = √(k/m) = 8571 rad/s) compresses by at most v/ω = 1.10e-4 m = 0.022 R
    // (a little less with the damping of e_n = 0.9). Sampled every 10 steps, ω·Δt/2 = 0.086 rad
    // from the deepest point at worst, the sampled overlap is above 0.99 of the true one. So
    // the lowest centre lies between R(1 − 0.04) (the floor holds it) and R(1 − 0.01) (it did
    // touch the floor, not stop short of it).
    assert!(lowest > R * (1.0 - 0.04), "lowest centre {lowest} m: the particle sank into the floor");
    assert!(lowest < R * (1.0 - 0.01), "lowest centre {lowest} m: the particle never touched the floor");
    // It leaves the floor at 0.9 × 0.9395 = 0.8456 m/s at t = √(2 · 0.045/g) + π/ω = 0.0962 s;
    // 0.0538 s later, at t_stop, it is at R + 0.8456·0.0538 − g·0.0538²/2 = 0.0363 m, still
    // rising. 2 mm (about 5 %) covers the gravity during the contact, which MFIX's damping
    // formula for e_n leaves out.
    let last = *z.last().expect("rows");
    assert!(last > lowest + 0.02, "final height {last} m, lowest {lowest} m: no rebound");
    assert!((last - 0.0363).abs() < 2e-3, "final height {last} m, expected about 0.0363 m");
}

#[test]
fn a_mesh_floor_and_a_plane_wall_give_the_same_time_series() {
    let mesh_dir = tempfile::tempdir().expect("temp dir");
    // Binary this time: the corners (±0.05, 0) widen from f32 to the same mesh up to the f32
    // rounding of 0.05, which only moves the floor's edges, far from the particle at the centre.
    std::fs::write(mesh_dir.path().join("floor.stl"), binary_stl(&floor())).expect("write mesh");
    let out = run(mesh_dir.path(), &case(MESH, 0.05));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let plane_dir = tempfile::tempdir().expect("temp dir");
    let plane = "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n";
    let out = run(plane_dir.path(), &case(plane, 0.05));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (m, p) = (series(mesh_dir.path()), series(plane_dir.path()));
    assert_eq!(m.len(), p.len());
    let mut touching = 0;
    for (a, b) in m.iter().zip(&p) {
        assert_eq!(a[0], b[0], "steps");
        // The library computes a face contact of a flat mesh as a plane's to about 1e-12
        // relative; 1e-9 leaves room for that to grow over the 75 000 steps, while a contact
        // counted twice at the seam (twice the force) or missed would differ at order 1.
        let (ka, kb) = (a[2], b[2]);
        assert!(
            (ka - kb).abs() <= 1e-9 * ka.abs().max(kb.abs()),
            "t = {}: kinetic energy {ka} on the mesh, {kb} on the plane",
            a[1]
        );
        // The mesh contact is counted as the plane's (the `contacts` column).
        assert_eq!(a[6], b[6], "t = {}: contacts on the mesh {}, on the plane {}", a[1], a[6], b[6]);
        touching += (b[6] > 0.0) as usize;
    }
    // The contact lasts π/ω = 3.7e-4 s: some 18 rows at 2e-5 s. The comparison must have
    // covered it, or it proved nothing about the mesh.
    assert!(touching >= 10, "only {touching} rows in contact");
}

/// A refused case: exit 2, no panic, and a message with every one of `expect`.
fn refused(dir: &Path, text: &str, expect: &[&str]) {
    let out = run(dir, text);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for e in expect {
        assert!(stderr.contains(e), "expected `{e}` in: {stderr}");
    }
}

#[test]
fn bad_mesh_input_exits_2_with_its_message() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    std::fs::write(d.join("floor.stl"), ascii_stl(&floor())).expect("write mesh");
    // The mesh file does not exist.
    refused(
        d,
        &case("[[meshes]]\nname = \"floor\"\nfile = \"nowhere.stl\"\n", 0.05),
        &["[[meshes]] 'floor': `file`: nowhere.stl: cannot read it"],
    );
    // Garbage bytes named .stl: neither a binary STL's size nor an ASCII STL's `solid`.
    std::fs::write(d.join("garbage.stl"), b"\x89PNG\r\n\x1a\n not a mesh at all \x00\x01\x02")
        .expect("write");
    refused(
        d,
        &case("[[meshes]]\nname = \"floor\"\nfile = \"garbage.stl\"\n", 0.05),
        &["[[meshes]] 'floor': `file`: garbage.stl: not an STL file"],
    );
    // A material that no [[wall_materials]] table declares (only the implicit "wall" exists).
    refused(
        d,
        &case(&format!("{MESH}material = \"steel\"\n"), 0.05),
        &["[[meshes]] 'floor'", "`material` = \"steel\" is invalid", "not a wall material", "\"wall\""],
    );
    // A scale of zero or below.
    for scale in ["0.0", "-1.0"] {
        refused(
            d,
            &case(&format!("{MESH}scale = {scale}\n"), 0.05),
            &["[[meshes]] 'floor'", &format!("`scale` = {}", scale.trim_end_matches(".0")), "positive"],
        );
    }
    // Moved 5 m up: wholly above the domain's top at z = 0.1 m.
    refused(
        d,
        &case(&format!("{MESH}translate = [0.0, 0.0, 5.0]\n"), 0.05),
        &["mesh 'floor' lies outside the domain"],
    );
    // Centre 2 mm above the floor: overlap 3 mm = 0.6 of the radius, above the default 0.05.
    refused(d, &case(MESH, 0.002), &["particle 1 at", "overlaps mesh 'floor'", "0.600 of its radius"]);
    // A key the table does not have.
    refused(d, &case(&format!("{MESH}colour = \"red\"\n"), 0.05), &["unknown field `colour`"]);
}

/// Issue 38: a mesh whose fastest point moves more than a tenth of the smallest radius in a
/// step is refused at set-up, naming the mesh, its speed and the safe step 0.1·r/v. The sheet
/// moving at 1 000 m/s and the fin turning at 3·10⁴ rad/s both ran and exited 0, the particle
/// passed through.
#[test]
fn a_mesh_moving_too_far_in_a_step_is_refused_with_a_safe_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    std::fs::write(d.join("floor.stl"), ascii_stl(&floor())).expect("write mesh");
    // The sheet at 1 000 m/s: 2 mm a step of 2e-6 s, 0.4 of the 5 mm radius.
    let (v, dt) = (1000.0, 2.0e-6);
    let safe = 0.1 * R / v;
    refused(
        d,
        &case(&format!("{MESH}[meshes.motion]\nkind = \"translate\"\nvelocity = [0.0, 0.0, {v:e}]\n"), 0.05),
        &[
            "[[meshes]] 'floor': motion: mesh 'floor' is translating at 1.0000e3 m/s",
            "its fastest point moves at 1.0000e3 m/s, 2.0000e-3 m in a step of dt = 2.0000e-6 s",
            "0.400 of the smallest particle radius 5.0000e-3 m, above the limit of 0.1",
            &format!("a safe time step is dt <= {safe:.4e} s"),
            "force_dt = true",
        ],
    );
    // The floor as a fin turning about z through its centre: its corners, HALF·√2 from the
    // axis, are its fastest points, at ω·HALF·√2 (the closed form; the engine takes the
    // largest vertex distance, so both agree to rounding, far inside the 5 digits printed).
    let omega = 3.0e4;
    let speed = omega * HALF * std::f64::consts::SQRT_2;
    refused(
        d,
        &case(
            &format!("{MESH}[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nomega = {omega:e}\n"),
            0.05,
        ),
        &[
            &format!(
                "turning at 3.0000e4 rad/s with a vertex {:.4e} m from the axis",
                HALF * std::f64::consts::SQRT_2
            ),
            &format!("its fastest point moves at {speed:.4e} m/s, {:.4e} m in a step", speed * dt),
            &format!("a safe time step is dt <= {:.4e} s", 0.1 * R / speed),
        ],
    );
    // Within the limit the same mesh runs: 0.01 m/s moves it 2e-8 m a step, 4e-6 of the
    // radius.
    let c =
        case(&format!("{MESH}[meshes.motion]\nkind = \"translate\"\nvelocity = [0.0, 0.0, -0.01]\n"), 0.05);
    std::fs::write(d.join("slow.toml"), c.replace("t_stop = 0.15", "t_stop = 0.0001")).expect("write case");
    let out = grainflow()
        .arg("run")
        .arg(d.join("slow.toml"))
        .arg("--out")
        .arg(d.join("slow"))
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

/// Issue 38: a bead at 1 000 m/s moves 1 cm in a step of 1e-5 s, twice its radius, through the
/// fixed floor below it; the run exited 0. The health check now stops it, naming the particle,
/// its travel and the safe step 0.1·r/v = 5e-7 s, and since the speed is in the input it says
/// so.
#[test]
fn a_particle_moving_more_than_its_radius_in_a_step_stops_the_run() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    std::fs::write(d.join("floor.stl"), ascii_stl(&floor())).expect("write mesh");
    let text = case(MESH, 0.05).replace("dt = 2.0e-6", "dt = 1.0e-5").replace(
        "position = [0.0, 0.0, 0.05]",
        "position = [0.0, 0.0, 0.05]\nvelocity = [0.0, 0.0, -1000.0]",
    );
    refused(
        d,
        &text,
        &[
            "particle 1 moves 1.0000e-2 m in a step (speed 1.0000e3 m/s at dt = 1.0000e-5 s), more than its radius 5.0000e-3 m",
            "Likely cause: the state the run starts from (particle 1",
            &format!("A safe time step for this speed is dt <= {:.4e} s", 0.1 * R / 1000.0),
        ],
    );
}
