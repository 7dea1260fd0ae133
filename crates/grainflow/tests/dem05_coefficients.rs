//! DEM05's derived contact coefficients and MFIX's time step, from MFIX's DEM05 set-up, against
//! the values MFIX 21.3 derives for it (docs/verification.md, DEM05; at their printed precision) and
//! against the closed-form formulas written out here independently of the engine (to 1e-12,
//! a few hundred ulps: each formula is a handful of roundings).

mod common;

use common::*;
use grainflow::contact::{ContactCoeffs, damping_coefficient};
use grainflow::state::ParticleInit;
use grainflow::{ContactLaw, Integrator, NormalModel, Simulation, TimeStepRule, Vec3, Wall};
use std::f64::consts::PI;

/// Relative agreement of two evaluations of the same closed form (different operation order).
const FORMULA_TOL: f64 = 1e-12;

/// DEM05 as MFIX's deck sets it up (docs/verification.md), with two particles: one impactor (phase 1) and one anvil
/// (phase 2).
fn dem05(normal: NormalModel) -> Simulation {
    let (phases, wall_materials, pair, wall) = match normal {
        NormalModel::LinearSpringDashpot => {
            let mut p = lsd_params(1.72e7, 1.0, 0.092);
            p.kt_fac = 1.48 / 1.72;
            (
                vec![phase("alumina", 0.005, 4000.0), phase("anvil", 0.005, 5000.0)],
                vec![wall_material("anvil", None, None)],
                p,
                p,
            )
        }
        NormalModel::Hertz => {
            let p = hertz_params(1.0, 1.0, 0.092);
            (
                vec![
                    elastic_phase("alumina", 0.005, 4000.0, 380e9, 0.23),
                    elastic_phase("anvil", 0.005, 5000.0, 70e9, 0.25),
                ],
                vec![wall_material("anvil", Some(70e9), Some(0.25))],
                p,
                p,
            )
        }
        NormalModel::Jkr => unreachable!("JKR is not among the laws this test draws"),
    };
    let mut cfg = config(
        ContactLaw::mfix(normal),
        phases,
        wall_materials,
        Wall::domain_box(Vec3::ZERO, Vec3::new(0.5, 0.1, 0.5), 0),
        vec![pair; 3],
        vec![wall; 2],
        Integrator::AdamsBashforth,
        1.0,
    );
    cfg.time_step = TimeStepRule::Mfix { factor: 50.0 };
    cfg.t_stop = 0.0025;
    let init: [ParticleInit; 2] = [
        particle(32, 0, 0.0025, 4000.0, Vec3::new(0.25, 0.0555, 0.25), Vec3::new(0.0, -3.9, 0.0)),
        particle(63, 1, 0.0025, 5000.0, Vec3::new(0.25, 0.0475, 0.25), Vec3::ZERO),
    ];
    simulation(cfg, &init)
}

/// |value − printed| ≤ half a unit of the printed 6th significant digit.
fn assert_printed_6(what: &str, value: f64, printed: f64) {
    let unit = 10f64.powf(printed.abs().log10().floor() - 5.0);
    let diff = (value - printed).abs();
    eprintln!("{what}: {value:.9e} vs printed {printed:e} (|diff| {diff:.3e}, half unit {:.1e})", 0.5 * unit);
    assert!(diff <= 0.5 * unit, "{what}: {value:e} does not round to the printed {printed:e}");
}

fn assert_rel(what: &str, value: f64, expected: f64, tol: f64) {
    let err = rel_err(value, expected);
    assert!(err <= tol, "{what}: {value:e} vs {expected:e}, relative error {err:e} > {tol:e}");
}

fn e_star(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
}

fn g_star(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    let (g1, g2) = (e1 / (2.0 * (1.0 + nu1)), e2 / (2.0 * (1.0 + nu2)));
    1.0 / ((2.0 - nu1) / g1 + (2.0 - nu2) / g2)
}

/// Hertz K_n, K_t of DEM05 for pairs 1-1, 1-2 and phase 1–wall: MFIX derives (docs/verification.md, DEM05)
/// 9.45696e9, 1.23421e10; 2.96757e9, 3.82435e9; 4.19677e9, 5.40844e9 (N/m^1.5). With
/// e_n = e_t = 1 all damping is zero; the effective masses are m₁/2, m₁m₂/(m₁+m₂) and m₁.
#[test]
fn dem05_hertz_stiffnesses() {
    let sim = dem05(NormalModel::Hertz);
    let t = sim.coefficients();
    let r = 0.0025;
    let (m1, m2) = (sphere_mass(r, 4000.0), sphere_mass(r, 5000.0));
    let cases: [(&str, &ContactCoeffs, f64, f64, f64, f64, f64); 4] = [
        // (name, coefficients, E*, G*, R*, printed K_n, printed K_t)
        (
            "1-1",
            t.pair(0, 0),
            e_star(380e9, 0.23, 380e9, 0.23),
            g_star(380e9, 0.23, 380e9, 0.23),
            r / 2.0,
            9.45696e9,
            1.23421e10,
        ),
        (
            "1-2",
            t.pair(0, 1),
            e_star(380e9, 0.23, 70e9, 0.25),
            g_star(380e9, 0.23, 70e9, 0.25),
            r / 2.0,
            2.96757e9,
            3.82435e9,
        ),
        (
            "2-1",
            t.pair(1, 0),
            e_star(380e9, 0.23, 70e9, 0.25),
            g_star(380e9, 0.23, 70e9, 0.25),
            r / 2.0,
            2.96757e9,
            3.82435e9,
        ),
        (
            "1-wall",
            t.wall(0, 0),
            e_star(380e9, 0.23, 70e9, 0.25),
            g_star(380e9, 0.23, 70e9, 0.25),
            r,
            4.19677e9,
            5.40844e9,
        ),
    ];
    for (name, c, es, gs, rs, kn_printed, kt_printed) in cases {
        assert_printed_6(&format!("{name} K_n"), c.kn, kn_printed);
        assert_printed_6(&format!("{name} K_t"), c.kt, kt_printed);
        assert_rel(&format!("{name} K_n"), c.kn, 4.0 / 3.0 * es * rs.sqrt(), FORMULA_TOL);
        assert_rel(&format!("{name} K_t"), c.kt, 8.0 * gs * rs.sqrt(), FORMULA_TOL);
        assert_eq!(c.eta_n, 0.0, "{name}: e_n = 1 means no normal damping");
        assert_eq!(c.eta_t, 0.0, "{name}: e_t = 1 means no tangential damping");
        assert_eq!(c.mu, 0.092);
    }
    assert_rel("1-1 m_eff", t.pair(0, 0).m_eff, m1 / 2.0, FORMULA_TOL);
    assert_rel("1-2 m_eff", t.pair(0, 1).m_eff, m1 * m2 / (m1 + m2), FORMULA_TOL);
    assert_rel("1-wall m_eff", t.wall(0, 0).m_eff, m1, FORMULA_TOL);
    // Phase 2 against the wall: same material on both sides, R* = R.
    let c = t.wall(1, 0);
    assert_rel("2-wall K_n", c.kn, 4.0 / 3.0 * e_star(70e9, 0.25, 70e9, 0.25) * r.sqrt(), FORMULA_TOL);
}

/// LSD: k_n = 1.72e7 N/m and k_t = KT_FAC·k_n = 1.48e7 N/m everywhere, no damping at e_n = 1.
#[test]
fn dem05_lsd_stiffnesses() {
    let sim = dem05(NormalModel::LinearSpringDashpot);
    let t = sim.coefficients();
    for (name, c) in [
        ("1-1", t.pair(0, 0)),
        ("1-2", t.pair(0, 1)),
        ("2-2", t.pair(1, 1)),
        ("1-wall", t.wall(0, 0)),
        ("2-wall", t.wall(1, 0)),
    ] {
        assert_eq!(c.kn, 1.72e7, "{name} k_n");
        // 1.48/1.72·1.72e7: two roundings.
        assert_rel(&format!("{name} k_t"), c.kt, 1.48e7, 1e-15);
        assert_eq!(c.eta_n, 0.0, "{name} eta_n");
        assert_eq!(c.eta_t, 0.0, "{name} eta_t");
    }
}

/// MFIX's DTSOLID and step counts (docs/models.md, time step; docs/verification.md, DEM05): LSD 1.733345e-7 s and 14 423 steps,
/// Hertz 7.392195e-9 s and 338 195 steps; TCOLL is the 1-1 pair's (the lightest m_eff and, for
/// Hertz, the stiffest K_n), π/√(K/m_eff) without damping.
#[test]
fn dem05_time_step() {
    let m1 = sphere_mass(0.0025, 4000.0);
    for (normal, dt_printed, steps) in [
        (NormalModel::LinearSpringDashpot, 1.733345e-7f64, 14_423u64),
        (NormalModel::Hertz, 7.392195e-9, 338_195u64),
    ] {
        let sim = dem05(normal);
        let k = sim.coefficients().pair(0, 0).kn;
        let tcoll = PI / (k / (m1 / 2.0)).sqrt();
        let ts = sim.time_step();
        // dt_printed has 7 significant digits: check to half a unit of the 7th.
        let unit7 = 10f64.powf(dt_printed.log10().floor() - 6.0);
        assert!(
            (ts.dt - dt_printed).abs() <= 0.5 * unit7,
            "{normal:?}: DTSOLID {:e} does not round to {dt_printed:e}",
            ts.dt
        );
        assert_rel(&format!("{normal:?} TCOLL"), ts.tcoll.unwrap(), tcoll, FORMULA_TOL);
        assert_rel(&format!("{normal:?} DTSOLID"), ts.dt, tcoll / 50.0, FORMULA_TOL);
        assert_eq!(ts.steps, steps, "{normal:?} step count");
        assert_eq!(sim.total_steps(), steps);
        // The run ends at N·DTSOLID ≥ t_stop, less than one step past it.
        let end = steps as f64 * ts.dt;
        assert!(end >= 0.0025 && end - ts.dt < 0.0025, "{normal:?}: end {end:e}");
    }
}

/// The damping formula inverts the linear oscillator's restitution: with
/// ζ = η/(2√(K·M)), e = exp(−πζ/√(1 − ζ²)) must give back the input e (a different formula,
/// not a re-evaluation of the same one). Rounding: the composition loses a few ulps of ln e,
/// relative 1e-13 of e here.
#[test]
fn damping_coefficient_inverts_restitution() {
    for &e in &[1.0, 0.99, 0.9, 0.7, 0.5, 0.3, 0.1, 0.01] {
        for &(k, m) in &[(1.72e7, 2.6e-4), (1e4, 10.89), (1.0, 1.0)] {
            let eta = damping_coefficient(k, m, e);
            let zeta = eta / (2.0 * (k * m).sqrt());
            let back = (-PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
            assert!((back - e).abs() <= 1e-13, "e = {e}: got back {back}");
        }
    }
    // e = 0: critical damping.
    assert_rel("critical", damping_coefficient(4.0, 9.0, 0.0), 12.0, 1e-15);
}

/// MFIX's rule with damping and unequal phases (docs/models.md, time step; docs/verification.md, DEM05): TCOLL is the minimum
/// over the *phase pairs* of π/√(k_n/m_eff − (η_n/m_eff)²/4) — the wall contacts, made much
/// stiffer here, are not included — and DTSOLID = TCOLL/DTSOLID_FACTOR; factors below 10 are
/// rejected. Expected values from the formulas written out here (η from the model document).
#[test]
fn mfix_time_step_with_damping_ignores_walls() {
    let phases = vec![phase("a", 0.004, 3000.0), phase("b", 0.006, 2000.0)];
    let (ma, mb) = (sphere_mass(0.002, 3000.0), sphere_mass(0.003, 2000.0));
    // (k_n, e_n) for 1-1, 1-2, 2-2, and m_eff of each.
    let pairs = [(1e5, 0.9, ma / 2.0), (3e5, 0.3, ma * mb / (ma + mb)), (2e5, 0.6, mb / 2.0)];
    let eta = |k: f64, m: f64, e: f64| {
        let l: f64 = e.ln();
        2.0 * (k * m).sqrt() * l.abs() / (PI * PI + l * l).sqrt()
    };
    let tcoll = pairs
        .iter()
        .map(|&(k, e, m)| PI / (k / m - (eta(k, m, e) / m).powi(2) / 4.0).sqrt())
        .fold(f64::INFINITY, f64::min);
    let build = |factor: f64| {
        let mut cfg = config(
            ContactLaw::mfix(NormalModel::LinearSpringDashpot),
            phases.clone(),
            vec![wall_material("w", None, None)],
            Wall::domain_box(Vec3::ZERO, Vec3::ONE, 0),
            pairs.iter().map(|&(k, e, _)| lsd_params(k, e, 0.3)).collect(),
            vec![lsd_params(1e9, 0.5, 0.3); 2],
            Integrator::Euler,
            1.0,
        );
        cfg.time_step = TimeStepRule::Mfix { factor };
        cfg.t_stop = 0.01;
        Simulation::new(
            cfg,
            grainflow::Particles::from_init(&[particle(1, 0, 0.002, 3000.0, Vec3::splat(0.5), Vec3::ZERO)]),
        )
    };
    let sim = build(20.0).expect("valid");
    let ts = sim.time_step();
    assert_rel("TCOLL", ts.tcoll.unwrap(), tcoll, FORMULA_TOL);
    assert_rel("DTSOLID", ts.dt, tcoll / 20.0, FORMULA_TOL);
    let steps = ts.steps as f64;
    assert!(steps * ts.dt >= 0.01 && (steps - 1.0) * ts.dt < 0.01);
    assert!(build(10.0).is_ok());
    assert!(build(9.9).is_err(), "DTSOLID_FACTOR below 10 must be rejected");
}
