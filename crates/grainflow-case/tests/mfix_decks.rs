//! MFIX decks for DEM01–DEM05 (grainflow's own, written in MFIX's style from the case
//! descriptions in tests/mfix_decks/) give the same validated case as the native TOML cases
//! of grainflow-verify and the same particle states, bit for bit; `convert` round-trips; the
//! deck syntax (arrays, repeats, `@( )`, overrides, GUI comments, CGS) does what MFIX does.

use grainflow::{Simulation, SimulationConfig};
use grainflow_case::mfix::{self, DeckCase};
use grainflow_case::{Case, CaseError};
use std::path::{Path, PathBuf};

fn decks() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mfix_decks")
}

fn native(rel: &str) -> Case {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../grainflow-verify/cases").join(rel);
    grainflow_case::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn deck(rel: &str, motion: Option<&str>) -> DeckCase {
    let p = decks().join(rel);
    let m = motion.map(|m| decks().join(m));
    mfix::load(&p, &[], m.as_deref()).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The setups differ by design in two places only: the deck's Verlet skin follows MFIX's
/// FACTOR_RLM (default 1.2: (1.2 − 1) × the largest diameter) and its wall material is named
/// "wall". Checks both, then makes them equal for a field-by-field comparison.
fn comparable(deck: &Case, native: &Case) -> (SimulationConfig, SimulationConfig) {
    let (mut d, mut n) = (deck.config.clone(), native.config.clone());
    let dmax = d.phases.iter().map(|p| p.diameter).fold(0.0, f64::max);
    assert_eq!(d.skin, Some((1.2 - 1.0) * dmax), "FACTOR_RLM's skin");
    assert_eq!(n.skin, None);
    d.skin = None;
    assert_eq!(d.wall_materials.len(), n.wall_materials.len());
    for (dm, nm) in d.wall_materials.iter().zip(n.wall_materials.iter_mut()) {
        assert_eq!(dm.name, "wall");
        nm.name = dm.name.clone();
    }
    // DEM01, 02, 04 name their single phase "ball" in the native case; the deck uses MFIX's
    // phase numbers when the GUI comments give no names.
    for (dp, np) in d.phases.iter().zip(n.phases.iter_mut()) {
        np.name = dp.name.clone();
    }
    (d, n)
}

/// Runs both for `steps` steps and compares every particle's position, velocity and angular
/// velocity bit for bit.
fn same_run(deck: &Case, native: &Case, steps: u64) -> u64 {
    let mut a = Simulation::new(deck.config.clone(), deck.particles.clone()).expect("deck runs");
    let mut b = Simulation::new(native.config.clone(), native.particles.clone()).expect("native runs");
    assert_eq!(a.dt().to_bits(), b.dt().to_bits(), "time step");
    assert_eq!(a.total_steps(), b.total_steps(), "step count");
    a.run_with(steps, |_| {});
    b.run_with(steps, |_| {});
    // By id: the two re-sort their particles at different steps (their skins differ), which
    // moves particles to other slots and changes nothing else.
    let by_id = |s: &Simulation| s.particles().gathered(&s.particles().id_order());
    let (p, q) = (&by_id(&a), &by_id(&b));
    assert_eq!(p.id, q.id);
    for i in 0..p.len() {
        for (what, x, y) in [
            ("position", p.position[i], q.position[i]),
            ("velocity", p.velocity[i], q.velocity[i]),
            ("angular velocity", p.omega[i], q.omega[i]),
        ] {
            assert_eq!(
                x.to_array().map(f64::to_bits),
                y.to_array().map(f64::to_bits),
                "particle {} {what} after {} steps: {x:?} vs {y:?}",
                p.id[i],
                a.step_index()
            );
        }
    }
    a.step_index()
}

fn equivalent(deck_rel: &str, motion: Option<&str>, native_rel: &str, steps: u64) -> (DeckCase, u64) {
    let d = deck(deck_rel, motion);
    let n = native(native_rel);
    let (dc, nc) = comparable(&d.case, &n);
    assert_eq!(dc, nc, "{deck_rel}: configuration differs from {native_rel}");
    assert_eq!(d.case.particles, n.particles, "{deck_rel}: particles differ from {native_rel}");
    assert_eq!(d.case.domain, n.domain);
    let done = same_run(&d.case, &n, steps);
    assert!(done > 0);
    (d, done)
}

#[test]
fn dem01_deck_equals_the_native_case() {
    let (d, _) = equivalent("dem01/mfix.dat", None, "dem01/dem01.toml", u64::MAX);
    // DT = 1.0e-3 s of MFIX's DTSOLID rule: 1.4670332e-3 s (verification-cases.md).
    let sim = Simulation::new(d.case.config.clone(), d.case.particles.clone()).expect("runs");
    assert!((sim.dt() - 1.4670332e-3).abs() < 1e-9, "{}", sim.dt());
    assert_eq!(d.case.output.interval, Some(0.005));
    assert_eq!(d.case.output.vtk_interval, Some(0.005));
    assert_eq!(d.case.title, "DEM01: Freely falling particle with wall collision");
}

#[test]
fn dem02_deck_equals_the_native_case() {
    equivalent("dem02/mfix.dat", None, "dem02/dem02.toml", 20_000);
}

#[test]
fn dem03_deck_equals_the_native_case() {
    let (d, _) = equivalent("dem03/mfix.dat", None, "dem03/dem03.toml", u64::MAX);
    // MFIX does not check initial overlaps; the translation raises grainflow's limit and says so.
    assert!(d.notes.iter().any(|n| n.contains("overlap by 0.200")), "{:#?}", d.notes);
    assert_eq!(d.raw.particles.as_ref().and_then(|p| p.max_initial_overlap), Some(0.21));
}

#[test]
fn dem04_deck_equals_the_native_case() {
    equivalent("dem04/mfix.dat", None, "dem04/dem04.toml", u64::MAX);
}

#[test]
fn dem05_lsd_deck_with_its_motion_file_equals_the_native_case() {
    let (d, steps) = equivalent("dem05/lsd.dat", Some("dem05/motion.toml"), "dem05/lsd.toml", u64::MAX);
    // The whole run: MFIX's DTSOLID = 1.733345e-7 s, 14 423 steps (mfix-dem-model.md §5).
    assert_eq!(steps, 14_423);
    assert!(d.notes.iter().any(|n| n.contains("CALL_USR") && n.contains("--motion")), "{:#?}", d.notes);
}

#[test]
fn dem05_hertz_mfx_with_its_motion_file_equals_the_native_case() {
    let (_, steps) = equivalent("dem05/hertz.mfx", Some("dem05/motion.toml"), "dem05/hertz.toml", u64::MAX);
    // The whole run: MFIX's DTSOLID = 7.392195e-9 s, 338 195 steps (mfix-dem-model.md §5).
    assert_eq!(steps, 338_195);
}

#[test]
fn cgs_deck_equals_the_si_deck() {
    let si = deck("dem03/mfix.dat", None).case;
    let cgs = deck("dem03_cgs/mfix.dat", None);
    let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs());
    let (s, c) = (&si.config, &cgs.case.config);
    assert_eq!(s.phases.len(), c.phases.len());
    for (p, q) in s.phases.iter().zip(&c.phases) {
        assert!(close(p.diameter, q.diameter) && close(p.density, q.density), "{p:?} vs {q:?}");
    }
    for (p, q) in s.pair_params.iter().chain(&s.wall_params).zip(c.pair_params.iter().chain(&c.wall_params)) {
        assert!(close(p.kn.unwrap_or(0.0), q.kn.unwrap_or(0.0)), "{p:?} vs {q:?}");
        assert_eq!((p.kt_fac, p.etat_fac, p.en, p.mu), (q.kt_fac, q.etat_fac, q.en, q.mu));
    }
    assert!(close(s.gravity.y, c.gravity.y) && c.gravity.x == 0.0 && c.gravity.z == 0.0, "{:?}", c.gravity);
    for k in 0..3 {
        assert!(close(si.domain.1.to_array()[k], cgs.case.domain.1.to_array()[k]));
    }
    for i in 0..2 {
        for k in 0..3 {
            assert!(close(
                si.particles.position[i].to_array()[k],
                cgs.case.particles.position[i].to_array()[k]
            ));
        }
        assert!(close(si.particles.mass[i], cgs.case.particles.mass[i]));
    }
    // The particles of a CGS deck are listed inline, converted.
    let raw = cgs.raw.particles.as_ref().expect("particles");
    assert!(raw.file.is_none() && raw.list.len() == 2);
    // And the runs agree to rounding.
    let mut a = Simulation::new(si.config.clone(), si.particles.clone()).expect("runs");
    let mut b = Simulation::new(cgs.case.config.clone(), cgs.case.particles.clone()).expect("runs");
    a.run_to_end();
    b.run_to_end();
    assert_eq!(a.step_index(), b.step_index());
    for i in 0..2 {
        let (y1, y2) = (a.particles().position[i].y, b.particles().position[i].y);
        assert!((y1 - y2).abs() < 1e-12, "{y1} vs {y2}");
    }
}

/// `grainflow convert` writes the translated case as TOML; reading that TOML back gives the
/// same case.
#[test]
fn converted_toml_parses_back_to_the_identical_case() {
    for (rel, motion) in [
        ("dem01/mfix.dat", None),
        ("dem02/mfix.dat", None),
        ("dem03/mfix.dat", None),
        ("dem03_cgs/mfix.dat", None),
        ("dem04/mfix.dat", None),
        ("dem05/lsd.dat", Some("dem05/motion.toml")),
        ("dem05/hertz.mfx", Some("dem05/motion.toml")),
    ] {
        let d = deck(rel, motion);
        let toml = mfix::to_toml(&d.raw, rel, &d.notes).expect("serialises");
        let dir = decks().join(rel).parent().map(Path::to_path_buf).unwrap_or_default();
        let back = grainflow_case::parse(&toml, "converted.toml", &|name: &str| {
            let p = dir.join(name);
            std::fs::read_to_string(&p).map_err(|source| CaseError::Read { path: p, source })
        })
        .unwrap_or_else(|e| panic!("{rel}: the converted case does not parse: {e}\n{toml}"));
        assert_eq!(back.config, d.case.config, "{rel}");
        assert_eq!(back.particles, d.case.particles, "{rel}");
        assert_eq!(back.output, d.case.output, "{rel}");
        assert_eq!(back.domain, d.case.domain, "{rel}");
        assert_eq!(back.title, d.case.title, "{rel}");
        assert!(!toml.contains("[physics]\n\n") && !toml.contains("[neighbor]\n\n"), "empty tables:\n{toml}");
    }
}

fn parse_text(text: &str, overrides: &[&str]) -> Result<DeckCase, CaseError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    mfix::parse(text, "test.dat", &o, None, &|name: &str| match name {
        "particle_input.dat" => Ok("0.5 0.5 0.5 0.05 1000.0 0 0 0\n0.2 0.5 0.5 0.05 2000.0 0 0 0\n".into()),
        other => {
            Err(CaseError::Read { path: other.into(), source: std::io::Error::other("not in this test") })
        }
    })
}

const BASE: &str = "
RUN_NAME = 'T'  UNITS = 'SI'  RUN_TYPE = 'NEW'  TSTOP = 0.01  DT = 1e-3
COORDINATES = 'CARTESIAN'  XLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0  IMAX=1 JMAX=1 KMAX=1
RO_G0 = 0.0
MMAX = 2  SOLIDS_MODEL = 2*'DEM'  D_P0 = 2*0.1  RO_S0 = 1000.0 2000.0
PARTICLES = 2
KN = 1.0e4  KN_W = 2.0e4
DES_EN_INPUT = 0.9 0.8 0.7   DES_EN_WALL_INPUT = 0.6 0.5
MEW = 0.3  MEW_W = 0.4
";

#[test]
fn restitution_arrays_follow_mfix_upper_triangle_order() {
    let d = parse_text(BASE, &[]).expect("valid");
    let c = &d.case.config;
    // Pairs 1-1, 1-2, 2-2 in MFIX's order; walls per phase.
    let en: Vec<f64> = c.pair_params.iter().map(|p| p.en).collect();
    assert_eq!(en, vec![0.9, 0.8, 0.7]);
    let enw: Vec<f64> = c.wall_params.iter().map(|p| p.en).collect();
    assert_eq!(enw, vec![0.6, 0.5]);
    assert!(c.pair_params.iter().all(|p| p.kn == Some(1.0e4) && p.mu == 0.3 && p.kt_fac == 2.0 / 7.0));
    assert!(c.wall_params.iter().all(|p| p.kn == Some(2.0e4) && p.mu == 0.4 && p.etat_fac == 0.5));
    assert_eq!(c.integrator, grainflow::Integrator::Euler, "MFIX's default DES_INTG_METHOD");
    assert_eq!(c.time_step, grainflow::TimeStepRule::Mfix { factor: 50.0 });
    assert_eq!(c.gravity, grainflow::Vec3::new(0.0, -9.80665, 0.0), "MFIX's default gravity");
    assert_eq!(d.case.particles.phase, vec![0, 1], "phases matched by diameter and density");
}

#[test]
fn overrides_arithmetic_repeats_and_fortran_numbers() {
    let d = parse_text(
        &BASE.replace("KN = 1.0e4", "KN = @( 2.0d3 * (4 + 1) )").replace("MEW = 0.3", "MEW = 3.0D-1"),
        &["TSTOP=0.02", "des_en_input(2)=0.5", "GRAVITY_X = 1.0"],
    )
    .expect("valid");
    let c = &d.case.config;
    assert_eq!(c.pair_params[0].kn, Some(1.0e4));
    assert_eq!(c.pair_params[0].mu, 0.3);
    assert_eq!(c.t_stop, 0.02, "the command line overrides the deck");
    assert_eq!(c.pair_params[1].en, 0.5);
    assert_eq!(c.gravity, grainflow::Vec3::new(1.0, 0.0, 0.0), "a component replaces GRAVITY along −y");
    // Bad overrides are errors naming the argument.
    let e = parse_text(BASE, &["KN"]).expect_err("no =").to_string();
    assert!(e.contains("command-line override `KN`"), "{e}");
    let e = parse_text(BASE, &["KN=abc"]).expect_err("not a number").to_string();
    assert!(e.contains("`KN` = abc") && e.contains("not a number"), "{e}");
}

#[test]
fn ignored_keywords_are_reported_once_and_unknown_ones_with_their_line() {
    let text = format!(
        "{BASE}MU_G0 = 1.8e-5\nLEQ_IT(1) = 20\nLEQ_IT(2) = 20\nIC_EP_G(1) = 1.0\nFOO_BAR = 3\nDES_EN_INPTU = 0.9\n"
    );
    let d = parse_text(&text, &[]).expect("valid");
    let all = d.case.warnings.join("\n");
    assert_eq!(all.matches("LEQ_IT").count(), 1, "{all}");
    assert!(all.contains("ignored, gas phase") && all.contains("MU_G0 (line 10)"), "{all}");
    assert!(all.contains("test.dat, line 14: unknown keyword `FOO_BAR`"), "{all}");
    assert!(all.contains("did you mean `DES_EN_INPUT`?"), "{all}");
    // Irrelevant keywords do not change the case.
    let plain = parse_text(BASE, &[]).expect("valid");
    assert_eq!(plain.case.config, d.case.config);
}

#[test]
fn gravity_follows_mfix_rules() {
    let g = |extra: &str| {
        parse_text(&format!("{BASE}{extra}"), &[]).expect("valid").case.config.gravity.to_array()
    };
    assert_eq!(g("GRAVITY = 0.0"), [0.0; 3]);
    assert_eq!(g("GRAVITY = 5.0"), [0.0, -5.0, 0.0]);
    // All three components zero means "undefined" in MFIX: the default gravity applies.
    let d = parse_text(&format!("{BASE}GRAVITY_X = 0 GRAVITY_Y = 0 GRAVITY_Z = 0"), &[]).expect("valid");
    assert_eq!(d.case.config.gravity.to_array(), [0.0, -9.80665, 0.0]);
    assert!(d.notes.iter().any(|n| n.contains("write GRAVITY = 0.0")), "{:#?}", d.notes);
}
