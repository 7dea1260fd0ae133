//! MFIX decks of the kinds MFIX's own tests and tutorials are: phases told apart by MFIX's
//! matching rule, generated particles, mass inflows and pressure outflows, cyclic and 2-D
//! boxes, version 2.0 particle files, and every blocker reported at once. The decks are
//! written here in MFIX's style (MFIX's own files are not copied).

use grainflow::Simulation;
use grainflow_case::mfix;
use std::path::{Path, PathBuf};

/// Writes `deck` (and the other `files`) into a fresh folder; returns the deck's path.
fn folder(deck: &str, files: &[(&str, &str)]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("mfix.dat");
    std::fs::write(&path, deck).expect("write deck");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("write file");
    }
    (dir, path)
}

fn load(path: &Path, overrides: &[&str]) -> Result<mfix::DeckCase, grainflow_case::CaseError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    mfix::load(path, &o, None)
}

/// The common head of the decks: a 1 m box, LSD contacts, one phase of 0.1 m beads.
const HEAD: &str = "\
RUN_NAME = 'T'
UNITS = 'SI'
RUN_TYPE = 'NEW'
TSTOP = 0.2
DT = 1.0e-3
COORDINATES = 'CARTESIAN'
IMAX = 4  JMAX = 4  KMAX = 4
RO_G0 = 0.0
KN = 1.0e4
KN_W = 1.0e4
MEW = 0.3
MEW_W = 0.3
";

const ONE_PHASE: &str = "\
MMAX = 1
SOLIDS_MODEL(1) = 'DEM'
D_P0(1) = 0.1
RO_S0(1) = 1000.0
DES_EN_INPUT(1) = 0.9
DES_EN_WALL_INPUT(1) = 0.9
";

/// A freely falling deck in MFIX's CGS style: four 20 cm spheres, two phases whose densities
/// differ in the seventh digit (2.600000 and 2.600001 g/cm³) and whose wall restitutions are
/// 0.9 and 1.0.
const FREE_FALL: &str = "\
RUN_NAME = 'FALL'
UNITS = 'CGS'
RUN_TYPE = 'NEW'
TIME = 0.0  TSTOP = 0.5  DT = 1.0d-4
COORDINATES = 'CARTESIAN'
XLENGTH = 120  IMAX = 6
YLENGTH = 120  JMAX = 6
ZLENGTH = 120  KMAX = 6
RO_g0 = 0.0
MMAX = 2
PARTICLES = 4
KN = 5.0d7  MEW = 0.0
KN_W = 5.0d7  MEW_W = 0.0
DES_EN_INPUT(1:2) = 0.9 0.9
DES_EN_INPUT(3) = 0.9
DES_EN_WALL_INPUT = 0.9 1.0
SOLIDS_MODEL(1) = 'DEM'  D_p0(1) = 20.0  RO_s0(1) = 2.600000
SOLIDS_MODEL(2) = 'DEM'  D_p0(2) = 20.0  RO_s0(2) = 2.600001
";

const FREE_FALL_PARTICLES: &str = "\
 30.0 90.0 30.0 10.0 2.600000 0.0 0.0 0.0
 30.0 90.0 90.0 10.0 2.600001 0.0 0.0 0.0
 90.0 90.0 30.0 10.0 2.600000 0.0 0.0 0.0
 90.0 90.0 90.0 10.0 2.600001 0.0 0.0 0.0
";

/// MFIX matches a particle to the first phase equal to it within 1e-15, and only then to the
/// first within a relative 1e-4: the 2.600001 g/cm³ particles are phase 2, whose wall
/// restitution is 1. A phase-2 bounce then keeps its mechanical energy; a phase-1 bounce
/// keeps about e² = 0.81 of it.
#[test]
fn phases_are_told_apart_by_mfix_exact_first_rule() {
    let (_dir, path) = folder(FREE_FALL, &[("particle_input.dat", FREE_FALL_PARTICLES)]);
    let d = load(&path, &[]).expect("deck loads");
    let phases: Vec<u32> = d.case.particles.phase.clone();
    assert_eq!(phases, [0, 1, 0, 1], "2.600000 → phase 1, 2.600001 → phase 2");
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let g = 9.80665;
    // Mechanical energy per unit mass above the height where the sphere touches the floor.
    let energy = |sim: &Simulation| -> Vec<f64> {
        let p = sim.particles();
        (0..p.len()).map(|i| g * (p.position[i].y - 0.1) + 0.5 * p.velocity[i].length_squared()).collect()
    };
    let e0 = energy(&sim);
    let steps = sim.total_steps();
    sim.run_with(steps, |_| {});
    let e1 = energy(&sim);
    for k in 0..4 {
        let ratio = e1[k] / e0[k];
        if phases[k] == 1 {
            // e = 1: no damping, the spring gives back what it took. Symplectic Euler's fall
            // lags the exact one by g·t·dt/2, an energy error of g·t·dt/(2h) over the fall of
            // h = 0.8 m; twice that bounds the fall and the rise after the bounce (0.0032 at
            // this deck's dt = TCOLL/50).
            let (h, dt) = (0.8, sim.dt());
            let tol = 2.0 * g * (2.0 * h / g).sqrt() * dt / (2.0 * h);
            assert!((ratio - 1.0).abs() < tol, "particle {k}: E1/E0 = {ratio}, tolerance {tol}");
        } else {
            // e = 0.9: e² = 0.81 of the impact energy leaves with the sphere; gravity during
            // the 46 ms contact shifts it by a few per cent.
            assert!((ratio - 0.81).abs() < 0.03, "particle {k}: E1/E0 = {ratio}");
        }
    }
}

/// MFIX reads the first PARTICLES lines of a longer file; a version 2.0 file gives its own
/// count, phases and columns.
#[test]
fn particle_files_are_read_as_mfix_reads_them() {
    // Two of three lines.
    let deck = format!("{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nPARTICLES = 2\n");
    let three =
        "0.2 0.2 0.2 0.05 1000.0 0 0 0\n0.5 0.5 0.5 0.05 1000.0 0 0 0\n0.8 0.8 0.8 0.05 1000.0 0 0 0\n";
    let (_dir, path) = folder(&deck, &[("particle_input.dat", three)]);
    let d = load(&path, &[]).expect("deck loads");
    assert_eq!(d.case.particles.len(), 2);
    assert_eq!(d.case.particles.position[1].x, 0.5);
    assert!(d.notes.iter().any(|n| n.contains("the first 2 are read")));

    // Version 2.0: phase and diameter read per particle, density and velocity uniform.
    let mut v2 = String::from("Version 2.0\n");
    for k in 2..=18 {
        v2.push_str(&format!("instructions line {k}\n"));
    }
    v2.push_str("Dimension:    3\nParticles:    2\n====\nVariable  Read(T/F)  Default\n====\n");
    v2.push_str("Coordinates:     T\nPhase_ID:        T\nDiameter:        T\nDensity:         F   1000.0\n");
    v2.push_str("Velocity:        F   0.0 -0.5 0.0\nTemperature:     F   293.15\nSpecies:         T\nUser_Scalar:     T\n");
    v2.push_str("====\nx y z phase d\n====\n");
    assert_eq!(v2.lines().count(), 34, "MFIX's data start at line 35");
    v2.push_str("0.3 0.3 0.3 1 0.1\n0.6 0.6 0.6 1 0.08\n");
    let deck = format!("{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nPARTICLES = 7\n");
    let (_dir, path) = folder(&deck, &[("particle_input.dat", &v2)]);
    let d = load(&path, &[]).expect("version 2.0 loads");
    assert_eq!(d.case.particles.len(), 2, "the file's count, not PARTICLES");
    assert_eq!(d.case.particles.radius[1], 0.04);
    assert_eq!(d.case.particles.velocity[0].y, -0.5);
}

/// A subscript range may be on a later subscript, as MFIX reads `IC_V_S(1,1:2)`.
#[test]
fn a_range_on_a_later_subscript_fills_that_subscript() {
    let deck = format!(
        "{HEAD}MMAX = 2\nSOLIDS_MODEL(1:2) = 'DEM' 'DEM'\nD_P0(1:2) = 0.1 0.1\nRO_S0(1:2) = 1000.0 2000.0\n\
         DES_EN_INPUT = 3*0.9\nDES_EN_WALL_INPUT = 2*0.9\nXLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\n\
         GENER_PART_CONFIG = .T.\n\
         IC_X_W(1) = 0.0  IC_X_E(1) = 1.0  IC_Y_S(1) = 0.0  IC_Y_N(1) = 1.0  IC_Z_B(1) = 0.0  IC_Z_T(1) = 1.0\n\
         IC_EP_S(1,1:2) = 0.01 0.02\nIC_V_S(1,1:2) = -0.2 -0.3\n"
    );
    let (_dir, path) = folder(&deck, &[]);
    let d = load(&path, &[]).expect("deck loads");
    let p = &d.case.particles;
    let of = |phase: u32| (0..p.len()).filter(|&i| p.phase[i] == phase).collect::<Vec<_>>();
    let (a, b) = (of(0), of(1));
    // ⌊ε·V/v⌋ of each: V = 1 m³, v = π/6·0.1³.
    let v = std::f64::consts::FRAC_PI_6 * 1e-3;
    assert_eq!((a.len(), b.len()), ((0.01 / v).floor() as usize, (0.02 / v).floor() as usize));
    assert!(a.iter().all(|&i| p.velocity[i].y == -0.2));
    assert!(b.iter().all(|&i| p.velocity[i].y == -0.3));
    // MFIX seeds the second phase above the first.
    let top_a = a.iter().map(|&i| p.position[i].y).fold(f64::MIN, f64::max);
    assert!(b.iter().all(|&i| p.position[i].y > top_a));
}

/// GENER_PART_CONFIG seeds ⌊ε_s·V/v⌋ particles, V the volume of MFIX's grid cells the IC
/// region covers (its faces moved to the nearest cell faces), on MFIX's hexagonal lattice in
/// the region as given: no two closer than the lattice spacing 1.05 d; when the lattice holds
/// fewer, it holds what MFIX's does.
#[test]
fn generated_particles_are_seeded_as_mfix_seeds_them() {
    let deck = |ep: f64| {
        format!(
            "{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nGENER_PART_CONFIG = .T.\n\
             IC_X_W(2) = 0.1  IC_X_E(2) = 0.9  IC_Y_S(2) = 0.1  IC_Y_N(2) = 0.6  IC_Z_B(2) = 0.1  IC_Z_T(2) = 0.9\n\
             IC_EP_S(2,1) = {ep}\n"
        )
    };
    let v = std::f64::consts::FRAC_PI_6 * 1e-3;
    // On the 4-cell grid (0.25 m cells) the region is [0, 1] × [0, 0.5] × [0, 1]: V = 0.5 m³.
    let (_dir, path) = folder(&deck(0.05), &[]);
    let d = load(&path, &[]).expect("deck loads");
    let p = &d.case.particles;
    assert_eq!(p.len(), (0.05 * 0.5 / v).floor() as usize);
    for i in 0..p.len() {
        let x = p.position[i];
        assert!(x.x > 0.1 && x.x < 0.9 && x.y > 0.1 && x.y < 0.6 && x.z > 0.1 && x.z < 0.9, "{x:?}");
        for j in 0..i {
            assert!((x - p.position[j]).length() >= 1.05 * 0.1 * (1.0 - 1e-12));
        }
    }
    // ε = 0.3 asks for 286; MFIX's lattice of radius R = 0.0525 in the 0.8 × 0.5 × 0.8 m
    // region holds ⌊½⌊(0.8 − R)/R⌋ − 1.5⌋ · ⌊1.5(⌊(0.5 − R)/R⌋ − 1)/√6⌋ ·
    // ⌊(⌊(0.8 − R)/R⌋ − 1)/√3 − ⅓⌋ = 5·4·7 (MFIX's generate_particles_mod.f).
    let (_dir, path) = folder(&deck(0.3), &[]);
    let d = load(&path, &[]).expect("deck loads");
    assert_eq!(d.case.particles.len(), 5 * 4 * 7);
    assert!(d.notes.iter().any(|n| n.contains("MFIX's lattice holds 140 of the 286")), "{:?}", d.notes);
}

/// A mass inflow on the top face and a pressure outflow on the bottom one: the inflow brings
/// ε_s·A·|v|·ρ_s kg/s, the box stays open there, and what crosses the bottom face leaves.
#[test]
fn a_mass_inflow_and_a_pressure_outflow_open_the_box() {
    let deck = format!(
        "{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 2.0  ZLENGTH = 1.0\nPARTICLES = 0\n\
         GRAVITY = 9.81\nTSTOP = 1.0\n\
         BC_TYPE(1) = 'MI'\nBC_X_W(1) = 0.2  BC_X_E(1) = 0.8  BC_Y_S(1) = 2.0  BC_Y_N(1) = 2.0  BC_Z_B(1) = 0.2  BC_Z_T(1) = 0.8\n\
         BC_EP_S(1,1) = 0.2\nBC_V_S(1,1) = -1.0\n\
         BC_TYPE(2) = 'PO'\nBC_X_W(2) = 0.0  BC_X_E(2) = 1.0  BC_Y_S(2) = 0.0  BC_Y_N(2) = 0.0  BC_Z_B(2) = 0.0  BC_Z_T(2) = 1.0\n"
    );
    let (_dir, path) = folder(&deck, &[]);
    let d = load(&path, &[]).expect("deck loads");
    let ins = &d.raw.insertions[0];
    let rate = 0.2 * 0.36 * 1.0 * 1000.0;
    assert!((ins.mass_rate.expect("a mass rate") - rate).abs() < 1e-9 * rate);
    assert_eq!(d.raw.outlets.len(), 1);
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let steps = sim.total_steps();
    sim.run_with(steps, |_| {});
    let books = sim.flow_books();
    // Falling 2 m from rest at the inlet's 1 m/s takes about 0.5 s: by 1 s particles leave.
    assert!(books.removed_total().count > 0, "nothing left through the outflow: {books:?}");
    // The books close: what came in is present or was removed.
    assert!(books.close(), "{books:?}");
    // Inserted mass over 1 s within a layer's worth of the flux (batches come whole: one
    // layer every 2d/|v| = 0.2 s, so the count of batches by 1 s is 5 or 6).
    let m_in = books.mass(books.inserted_total());
    assert!(m_in >= 0.95 * rate && m_in <= 1.25 * rate, "{m_in} kg in, {rate} kg/s");
}

/// A cyclic axis is periodic; its faces are no walls.
#[test]
fn cyclic_axes_are_periodic() {
    let deck = format!(
        "{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nCYCLIC_X = .T.\nCYCLIC_Z_PD = .T.\nPARTICLES = 1\n"
    );
    let (_dir, path) = folder(&deck, &[("particle_input.dat", "0.5 0.5 0.5 0.05 1000.0 1.0 0 0\n")]);
    let d = load(&path, &[]).expect("deck loads");
    let periodic = d.raw.domain.as_ref().and_then(|dm| dm.periodic.clone());
    assert_eq!(periodic, Some(vec!["x".to_string(), "z".to_string()]));
}

/// NO_K: MFIX's 2-D DEM, spheres in the plane z = 0; they stay in it exactly.
#[test]
fn a_two_dimensional_deck_stays_in_its_plane() {
    let deck =
        format!("{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0\nNO_K = .T.\nPARTICLES = 3\nTSTOP = 0.5\n");
    let file = "0.3 0.5 0.05 1000.0 0.5 0.0\n0.7 0.52 0.05 1000.0 -0.5 0.0\n0.5 0.2 0.05 1000.0 0.0 0.3\n";
    let (_dir, path) = folder(&deck, &[("particle_input.dat", file)]);
    let d = load(&path, &[]).expect("deck loads");
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let steps = sim.total_steps();
    sim.run_with(steps, |_| {});
    let p = sim.particles();
    for i in 0..p.len() {
        // Exactly: every contact normal and force lies in the plane.
        assert_eq!(p.position[i].z, 0.0);
        assert_eq!(p.velocity[i].z, 0.0);
        assert_eq!((p.omega[i].x, p.omega[i].y), (0.0, 0.0));
    }
}

/// Every blocker of a deck is reported at once, each with its line.
#[test]
fn every_blocker_is_reported_at_once() {
    let deck = format!(
        "{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nPARTICLES = 1\nCALL_USR = .T.\n\
         USE_COHESION = .T.\nRUN_TYPE = 'RESTART_1'\nBC_TYPE(3) = 'NSW'\nBC_X_W(3) = 0.5  BC_X_E(3) = 0.5  BC_Y_S(3) = 0.0  BC_Y_N(3) = 1.0  BC_Z_B(3) = 0.0  BC_Z_T(3) = 1.0\n"
    );
    let (_dir, path) = folder(&deck, &[("particle_input.dat", "0.5 0.5 0.5 0.05 1000.0 0 0 0\n")]);
    let msg = load(&path, &[]).expect_err("refused").to_string();
    for want in ["CALL_USR", "USE_COHESION", "RESTART_1", "BC_TYPE(3)", "4 things"] {
        assert!(msg.contains(want), "lacks {want}:\n{msg}");
    }
    assert!(msg.matches(", line ").count() >= 4, "{msg}");
}

/// A closed cylinder about the z axis, radius `r`, from z = 0 to `h`, as ASCII STL with its
/// normals outwards (as CAD writes a solid).
fn cylinder_stl(r: f64, h: f64, n: usize) -> String {
    let p = |k: usize, z: f64| {
        let a = 2.0 * std::f64::consts::PI * (k % n) as f64 / n as f64;
        [r * a.cos(), r * a.sin(), z]
    };
    let mut s = String::from("solid drum\n");
    let mut facet = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for v in [a, b, c] {
            s.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("endloop\nendfacet\n");
    };
    for k in 0..n {
        let (a0, a1, b0, b1) = (p(k, 0.0), p(k + 1, 0.0), p(k, h), p(k + 1, h));
        facet(a0, a1, b1);
        facet(a0, b1, b0);
        facet([0.0, 0.0, 0.0], a1, a0);
        facet([0.0, 0.0, h], b0, b1);
    }
    s.push_str("endsolid drum\n");
    s
}

/// A drum as MFIX's GUI describes it: the STL placed by the `#!MFIX-GUI geometry` section
/// (translated, normals flipped), particles seeded inside, and the shell turned in place by
/// a key-frame table in the motion file. The seeded particles keep clear of the shell, and the
/// turning shell carries the bed round with it.
#[test]
fn a_drum_from_the_gui_geometry_turns_its_bed() {
    let deck = "\
RUN_NAME = 'DRUM'
UNITS = 'SI'
RUN_TYPE = 'NEW'
TSTOP = 0.4
COORDINATES = 'CARTESIAN'
X_MIN = -0.03  X_MAX = 0.03  Y_MIN = -0.028  Y_MAX = 0.032  Z_MIN = 0.0  Z_MAX = 0.012
IMAX = 6  JMAX = 6  KMAX = 2
CARTESIAN_GRID = .T.
USE_STL = .T.
CALL_USR = .T.
RO_G0 = 0.0
MMAX = 1
SOLIDS_MODEL(1) = 'DEM'
D_P0(1) = 0.004
RO_S0(1) = 2000.0
GENER_PART_CONFIG = .T.
KN = 1.0e3  KN_W = 1.0e3
MEW = 0.3  MEW_W = 0.5
DES_EN_INPUT(1) = 0.8
DES_EN_WALL_INPUT(1) = 0.8
IC_X_W(1) = -0.02  IC_X_E(1) = 0.02  IC_Y_S(1) = -0.018  IC_Y_N(1) = 0.002  IC_Z_B(1) = 0.0  IC_Z_T(1) = 0.012
IC_EP_S(1,1) = 0.4
BC_TYPE(1) = 'CG_NSW'
BC_X_W(1) = -0.03  BC_X_E(1) = 0.03  BC_Y_S(1) = -0.028  BC_Y_N(1) = 0.032  BC_Z_B(1) = 0.0  BC_Z_T(1) = 0.012
#!MFIX-GUI regions_dict = {\"order\": [\"shell\"], \"regions\": {\"shell\":
#!MFIX-GUI   {\"type\": \"STL\", \"geometry_pool\": [\"drum.stl\"]}}}
#!MFIX-GUI geometry = {\"geometry_dict\": {\"drum.stl\": {\"geo_type\": \"stl\",
#!MFIX-GUI   \"filename\": \"${proj_dir}/drum.stl\", \"centerx\": 0.0, \"centery\": 0.0,
#!MFIX-GUI   \"centerz\": 0.006, \"translationy\": 0.002, \"flipnormals\": true}},
#!MFIX-GUI   \"tree\": {\"drum.stl\": []}}
#!MFIX-GUI bc_regions = [[[1], [\"shell\"]]]
";
    let motion = "\
[[walls]]
bc = 1
[walls.surface]
axis = [0.0, 0.0, 1.0]
origin = [0.0, 0.002, 0.0]
omega = 1.0
keyframes = \"data_kf_0001.txt\"
";
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("drum.mfx"), deck).expect("deck");
    std::fs::write(dir.path().join("motion.toml"), motion).expect("motion");
    std::fs::write(dir.path().join("drum.stl"), cylinder_stl(0.028, 0.012, 48)).expect("stl");
    // ω ramps to 10 rad/s over 0.1 s, then holds.
    std::fs::write(dir.path().join("data_kf_0001.txt"), "2, 1\nlinear\n! t omega\n0.0 0.0\n0.1 10.0\n")
        .expect("key frames");
    let d =
        mfix::load(&dir.path().join("drum.mfx"), &[], Some(&dir.path().join("motion.toml"))).expect("loads");
    assert_eq!(d.raw.meshes.len(), 1);
    assert_eq!(d.raw.meshes[0].translate, Some([0.0, 0.002, 0.0]));
    let p = &d.case.particles;
    assert!(p.len() > 20, "{} particles", p.len());
    let centre = grainflow::Vec3::new(0.0, 0.002, 0.0);
    for i in 0..p.len() {
        // Inside the shell (radius 28 mm, the 48-gon's flats at 28·cos(π/48)) by more than
        // MFIX's 1.05 radii.
        let r = ((p.position[i] - centre) * grainflow::Vec3::new(1.0, 1.0, 0.0)).length();
        let flat = 0.028 * (std::f64::consts::PI / 48.0).cos();
        assert!(r < flat - 1.05 * 0.002, "particle {i} at r = {r}");
    }
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let steps = sim.total_steps();
    sim.run_with(steps, |_| {});
    // Angular momentum about the axis per unit mass: positive (the shell's sense) and a good
    // part of rigid rotation at the shell's ω for the bed's spread of radii.
    let q = sim.particles();
    let (mut l, mut rigid) = (0.0, 0.0);
    for i in 0..q.len() {
        let x = q.position[i] - centre;
        l += x.x * q.velocity[i].y - x.y * q.velocity[i].x;
        rigid += 10.0 * (x.x * x.x + x.y * x.y);
    }
    assert!(l > 0.05 * rigid, "L_z = {l}, rigid rotation would give {rigid}");
}

/// An internal STL surface (`IS_TYPE = 'STL'`, MFIX's `is_NNNN.stl`) is a mesh wall that a
/// motion file turns by `is = N`; a deck's particles overlapping an STL wall at the start are
/// measured and allowed, as MFIX allows them.
#[test]
fn an_internal_stl_surface_turns_by_its_motion_file() {
    let deck = format!(
        "{HEAD}{ONE_PHASE}X_MIN = -0.5  X_MAX = 0.5  Y_MIN = -0.5  Y_MAX = 0.5  Z_MIN = 0.0  Z_MAX = 0.5\n\
         CARTESIAN_GRID = .T.\nUSE_STL = .T.\nCALL_USR = .T.\nPARTICLES = 1\n\
         IS_TYPE(1) = 'STL'\nIS_X_W(1) = -0.5  IS_X_E(1) = 0.5  IS_Y_S(1) = -0.5  IS_Y_N(1) = 0.5  IS_Z_B(1) = 0.0  IS_Z_T(1) = 0.5\n"
    );
    // A paddle: a vertical sheet in the plane y = 0 from x = 0.05 to 0.35.
    let paddle = "solid p\nfacet normal 0 0 0\nouter loop\nvertex 0.05 0 0.05\nvertex 0.35 0 0.05\nvertex 0.35 0 0.45\nendloop\nendfacet\n\
                  facet normal 0 0 0\nouter loop\nvertex 0.05 0 0.05\nvertex 0.35 0 0.45\nvertex 0.05 0 0.45\nendloop\nendfacet\nendsolid p\n";
    let motion = "[[walls]]\nis = 1\n[walls.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nrpm = 60.0\n";
    // The sphere touches the paddle by 0.2 of its radius at the start.
    let (dir, path) = folder(
        &deck,
        &[
            ("particle_input.dat", "0.2 0.04 0.25 0.05 1000.0 0 0 0\n"),
            ("is_0001.stl", paddle),
            ("motion.toml", motion),
        ],
    );
    let d = mfix::load(&path, &[], Some(&dir.path().join("motion.toml"))).expect("loads");
    assert_eq!(d.raw.meshes.len(), 1);
    assert!(d.raw.meshes[0].motion.is_some());
    let limit = d.raw.particles.as_ref().and_then(|p| p.max_initial_overlap).expect("raised");
    assert!((0.2..0.23).contains(&limit), "max_initial_overlap = {limit}");
    // A motion file naming a wall the deck has not is refused with the walls it has.
    std::fs::write(dir.path().join("motion.toml"), motion.replace("is = 1", "is = 2")).expect("write");
    let e = mfix::load(&path, &[], Some(&dir.path().join("motion.toml"))).expect_err("no IS 2").to_string();
    assert!(e.contains("its STL walls are is = 1"), "{e}");
}

/// A square floor at height `y` over [0, `l`]² in x and z, facing +y, as ASCII STL.
fn floor_stl(y: f64, l: f64) -> String {
    let mut s = String::from("solid floor\n");
    for [a, b, c] in [[[0.0, 0.0], [0.0, l], [l, l]], [[0.0, 0.0], [l, l], [l, 0.0]]] {
        s.push_str("facet normal 0 1 0\nouter loop\n");
        for [x, z] in [a, b, c] {
            s.push_str(&format!("vertex {x} {y} {z}\n"));
        }
        s.push_str("endloop\nendfacet\n");
    }
    s.push_str("endsolid floor\n");
    s
}

/// A CGS deck's STL is in centimetres, as every length of the deck (MFIX reads the geometry in
/// the deck's units): a floor at 5 cm holds the bead at 5 cm plus its radius, not at the box
/// floor (issue 38). The bead (1 cm, 2.6 g/cm³, 10.9 g) rests on the floor compressed by
/// m·g/k_n = 2.1e-6 m with KN_W = 5e7 dyne/cm = 5e4 N/m: its centre ends at 0.06 m within
/// 1e-5 m once its bounces (e = 0.5, a 4 cm drop) have died out.
#[test]
fn a_cgs_deck_reads_its_stl_in_centimetres() {
    let deck = "\
RUN_NAME = 'CGS_STL'
UNITS = 'CGS'
RUN_TYPE = 'NEW'
TSTOP = 1.0
COORDINATES = 'CARTESIAN'
XLENGTH = 20.0  YLENGTH = 20.0  ZLENGTH = 20.0
IMAX = 4  JMAX = 4  KMAX = 4
CARTESIAN_GRID = .T.
USE_STL = .T.
RO_G0 = 0.0
MMAX = 1
SOLIDS_MODEL(1) = 'DEM'
D_P0(1) = 2.0
RO_S0(1) = 2.6
PARTICLES = 1
KN = 5.0e7  KN_W = 5.0e7
MEW = 0.3  MEW_W = 0.3
DES_EN_INPUT(1) = 0.5
DES_EN_WALL_INPUT(1) = 0.5
BC_TYPE(1) = 'CG_NSW'
BC_X_W(1) = 0.0  BC_X_E(1) = 20.0  BC_Y_S(1) = 0.0  BC_Y_N(1) = 20.0  BC_Z_B(1) = 0.0  BC_Z_T(1) = 20.0
";
    let (_dir, path) = folder(
        deck,
        &[
            ("particle_input.dat", "10.0 10.0 10.0 1.0 2.6 0.0 0.0 0.0\n"),
            ("geometry_0001.stl", &floor_stl(5.0, 20.0)),
        ],
    );
    let d = load(&path, &[]).expect("deck loads");
    assert_eq!(d.raw.meshes[0].scale, Some(0.01), "cm → m");
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let steps = sim.total_steps();
    sim.run_with(steps, |_| {});
    let y = sim.particles().position[0].y;
    let m = 2600.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-6;
    let rest = 0.06 - m * 9.80665 / 5.0e4;
    assert!((y - rest).abs() < 1e-5, "the bead rests at y = {y} m, the floor holds it at {rest} m");
}

/// `PARTICLES = 0` with `GENER_PART_CONFIG`: no particle file, the IC regions are seeded
/// (docs/mfix-decks.md); ⌊ε·V/v⌋ = ⌊0.01·1/(π/6·0.1³)⌋ = 19 particles in the 1 m³ box.
#[test]
fn no_particle_file_with_generated_particles_is_accepted() {
    let deck = format!(
        "{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nPARTICLES = 0\nGENER_PART_CONFIG = .T.\n\
         IC_X_W(1) = 0.0  IC_X_E(1) = 1.0  IC_Y_S(1) = 0.0  IC_Y_N(1) = 1.0  IC_Z_B(1) = 0.0  IC_Z_T(1) = 1.0\n\
         IC_EP_S(1,1) = 0.01\n"
    );
    let (_dir, path) = folder(&deck, &[]);
    let d = load(&path, &[]).expect("PARTICLES = 0 with GENER_PART_CONFIG loads");
    let v = std::f64::consts::FRAC_PI_6 * 1e-3;
    assert_eq!(d.case.particles.len(), (0.01 / v).floor() as usize);
}

/// A fully periodic box has no walls: a particle across a cyclic face overlaps nothing, so
/// no wall overlap is reported and the initial-overlap limit stays grainflow's own (MFIX's
/// homogeneous-cooling-system deck is fully periodic; issue 38).
#[test]
fn a_fully_periodic_deck_reports_no_wall_overlap() {
    let deck = format!(
        "{HEAD}{ONE_PHASE}XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nCYCLIC_X = .T.\nCYCLIC_Y = .T.\nCYCLIC_Z = .T.\n\
         GRAVITY = 0.0\nPARTICLES = 2\n"
    );
    // The first straddles the x faces (its centre 0.02 m from x = 0, radius 0.05 m).
    let file = "0.02 0.5 0.5 0.05 1000.0 0 0 0\n0.5 0.5 0.5 0.05 1000.0 0 0 0\n";
    let (_dir, path) = folder(&deck, &[("particle_input.dat", file)]);
    let d = load(&path, &[]).expect("deck loads");
    assert!(d.notes.iter().all(|n| !n.contains("overlap")), "{:#?}", d.notes);
    assert_eq!(d.raw.particles.as_ref().and_then(|p| p.max_initial_overlap), None);
}

/// A 2-D deck (NO_K) with a mass inflow: MFIX's face is a segment of the plane z = 0 and its
/// area the segment's width times ZLENGTH, the depth of MFIX's one layer of cells. The inflow
/// brings ε_s·w·ZLENGTH·|v|·ρ_s = 0.1·0.6·0.1·1·1000 = 6 kg/s, and every particle it brings
/// lies exactly in the plane z = 0 and stays in it bit for bit (contacts between centres in
/// one plane push only in it): z, w and the x, y spin are exactly 0. The books close
/// (inserted = present + removed through the bottom outflow).
#[test]
fn a_two_dimensional_mass_inflow_feeds_in_its_plane() {
    let deck = format!(
        "{HEAD}MMAX = 1\nSOLIDS_MODEL(1) = 'DEM'\nD_P0(1) = 0.05\nRO_S0(1) = 1000.0\nDES_EN_INPUT(1) = 0.9\nDES_EN_WALL_INPUT(1) = 0.9\n\
         XLENGTH = 1.0  YLENGTH = 2.0  ZLENGTH = 0.1\nNO_K = .T.\nPARTICLES = 0\nTSTOP = 1.0\n\
         BC_TYPE(1) = 'MI'\nBC_X_W(1) = 0.2  BC_X_E(1) = 0.8  BC_Y_S(1) = 2.0  BC_Y_N(1) = 2.0\n\
         BC_EP_S(1,1) = 0.1\nBC_V_S(1,1) = -1.0\n\
         BC_TYPE(2) = 'PO'\nBC_X_W(2) = 0.0  BC_X_E(2) = 1.0  BC_Y_S(2) = 0.0  BC_Y_N(2) = 0.0\n"
    );
    let (_dir, path) = folder(&deck, &[]);
    let d = load(&path, &[]).expect("a 2-D mass inflow loads");
    let rate = d.raw.insertions[0].mass_rate.expect("a mass rate");
    assert!((rate - 6.0).abs() < 1e-12, "{rate} kg/s");
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let steps = sim.total_steps();
    let mut seen = 0usize;
    sim.run_with(steps, |s| {
        let p = s.particles();
        for i in 0..p.len() {
            assert_eq!(p.position[i].z, 0.0, "particle {} out of the plane", p.id[i]);
            assert_eq!(p.velocity[i].z, 0.0, "particle {}: w", p.id[i]);
            assert_eq!([p.omega[i].x, p.omega[i].y], [0.0, 0.0], "particle {}: spin", p.id[i]);
        }
        seen = seen.max(p.len());
    });
    let books = sim.flow_books();
    assert!(books.close(), "{books:?}");
    assert!(seen > 0 && books.removed_total().count > 0, "{books:?}");
}

/// The same inflow into a closed box, 4 s: 367 particles pile into a bed on the floor. A bed
/// in a plane is unstable out of it under its own weight: with centres placed to within 2e-13
/// m of z = 0 (the placement's margin), the offsets grew to 5e-9 m by 1.4 s and to most of a
/// diameter by 2.1 s, and 305 of the 367 particles left through the open z faces. Placed
/// exactly in the plane (`plane_z`), every particle stays at z = 0 bit for bit and none leaves.
#[test]
fn a_two_dimensional_bed_fed_by_a_mass_inflow_stays_in_its_plane() {
    let deck = format!(
        "{HEAD}MMAX = 1\nSOLIDS_MODEL(1) = 'DEM'\nD_P0(1) = 0.05\nRO_S0(1) = 1000.0\nDES_EN_INPUT(1) = 0.9\nDES_EN_WALL_INPUT(1) = 0.9\n\
         XLENGTH = 1.0  YLENGTH = 2.0  ZLENGTH = 0.1\nNO_K = .T.\nPARTICLES = 0\n\
         BC_TYPE(1) = 'MI'\nBC_X_W(1) = 0.2  BC_X_E(1) = 0.8  BC_Y_S(1) = 2.0  BC_Y_N(1) = 2.0\n\
         BC_EP_S(1,1) = 0.1\nBC_V_S(1,1) = -1.0\n"
    )
    .replace("TSTOP = 0.2", "TSTOP = 4.0");
    let (_dir, path) = folder(&deck, &[]);
    let d = load(&path, &[]).expect("a 2-D mass inflow loads");
    assert_eq!(d.case.config.insertions[0].plane_z, Some(0.0));
    let mut sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("set-up");
    let steps = sim.total_steps();
    sim.run_with(steps, |s| {
        let p = s.particles();
        for i in 0..p.len() {
            assert_eq!(p.position[i].z, 0.0, "particle {} out of the plane at t = {}", p.id[i], s.time());
        }
    });
    let books = sim.flow_books();
    assert!(books.close(), "{books:?}");
    assert!(books.inserted_total().count > 300, "{books:?}");
    assert_eq!(books.removed_total().count, 0, "{books:?}");
}

/// MFIX's poly_dem_inlet_outlet (legacy_tests/dem-tests, vendored unchanged) is a 2-D deck
/// with a mass inflow, which now translates; what stops it is its gas: a density of 1.3e-30
/// g/cm³ but a Wen–Yu drag with μ_g = 1.8e-4 P, which still drags the particles. The message
/// names the drag.
#[test]
fn poly_dem_inlet_outlet_is_refused_for_its_drag() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mfix_decks/poly_dem_inlet_outlet/mfix.dat");
    let e = load(&p, &[]).expect_err("refused").to_string();
    assert!(e.contains("RO_G0") && e.contains("'WEN_YU'") && e.contains("MU_G0 = 1.8d-4"), "{e}");
    assert!(e.contains("still drags the particles"), "{e}");
    assert!(!e.contains("2-D run (NO_K) is not supported"), "{e}");
}
