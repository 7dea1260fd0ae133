//! Contacts between particles of other sizes than their phase's reference: each contact's own
//! R* and effective mass ([`ContactSizes::Own`]) against the closed forms of a head-on impact,
//! the phases' reference ones as MFIX takes them ([`ContactSizes::Phase`]) against the same
//! closed forms with the reference's values, and the time step from the smallest particle.
//!
//! ## Tolerances
//! As in `normal_impact.rs`: with Δt = t_c/N every error of an elastic impact is O((ωΔt)²),
//! ω = π/t_c, and a dashpot adds at most (1 + 1/e)·(η/m*)·Δt; N = 2000 gives 2.5e-6 and, for
//! e = 0.8 and η/m* ≈ 2ω·0.07, about 5e-4. The maximum overlap is sampled on the step grid:
//! (ωΔt)²/8 low at most.

mod common;

use common::*;
use grainflow::contact::{ContactSizes, NormalDamping, damping_coefficient};
use grainflow::{ContactLaw, Integrator, NormalModel, TimeStepRule, Vec3};
use std::f64::consts::PI;

/// Steps per contact time.
const N: f64 = 2000.0;

/// The reference diameter of the one phase, m; the particles are 1.0 and 2.5 mm in radius.
const D_REF: f64 = 0.002;
const RADII: [f64; 2] = [0.001, 0.0025];
const RHO: f64 = 2500.0;
/// Approach speed, m/s.
const V: f64 = 0.5;

/// Runs a head-on impact of the two particles (`sizes`, the law's normal model and damping)
/// with time step `dt`; returns the rebound's relative speed and the largest overlap.
fn impact(law: ContactLaw, params: grainflow::contact::ContactParams, dt: f64) -> (f64, f64) {
    let phases = vec![elastic_phase("glass", D_REF, RHO, 7e7, 0.3)];
    let cfg = config(law, phases, vec![], vec![], vec![params], vec![], Integrator::VelocityVerlet, dt);
    let gap = 1e-6;
    let (ra, rb) = (RADII[0], RADII[1]);
    let init = [
        particle(1, 0, ra, RHO, Vec3::new(-ra - gap / 2.0, 0.0, 0.0), Vec3::new(V / 2.0, 0.0, 0.0)),
        particle(2, 0, rb, RHO, Vec3::new(rb + gap / 2.0, 0.0, 0.0), Vec3::new(-V / 2.0, 0.0, 0.0)),
    ];
    let mut sim = simulation(cfg, &init);
    let mut delta_max: f64 = 0.0;
    let mut touched = false;
    for _ in 0..1_000_000 {
        sim.step();
        let p = sim.particles();
        let overlap = ra + rb - (p.position[1] - p.position[0]).length();
        delta_max = delta_max.max(overlap);
        touched |= overlap > 0.0;
        if touched && overlap < -gap {
            // Particle 2 was given the id 2: slot order is not assumed.
            let v = |id: u32| p.velocity[p.id.iter().position(|&i| i == id).expect("id")].x;
            return (v(2) - v(1), delta_max);
        }
    }
    panic!("the particles did not separate");
}

/// The two particles' masses, kg.
fn masses() -> (f64, f64) {
    (sphere_mass(RADII[0], RHO), sphere_mass(RADII[1], RHO))
}

/// The linear spring–dashpot with MFIX's damping rebounds with exactly e_n (no clipping) when
/// η_n is formed from the contact's own effective mass; with the reference's (MFIX), the
/// damping ratio is that of the reference mass at the pair's own mass: ζ = η_ref/(2√(k·m*)),
/// e = exp(−πζ/√(1 − ζ²)).
#[test]
fn a_linear_impact_of_two_sizes_rebounds_with_the_restitution_of_its_own_masses() {
    let (kn, en) = (2000.0, 0.8);
    let (ma, mb) = masses();
    let m_star = ma * mb / (ma + mb);
    let m_ref = sphere_mass(D_REF / 2.0, RHO) / 2.0;
    for (sizes, eta) in [
        (ContactSizes::Own, damping_coefficient(kn, m_star, en)),
        (ContactSizes::Phase, damping_coefficient(kn, m_ref, en)),
    ] {
        let law = ContactLaw { sizes, ..ContactLaw::mfix(NormalModel::LinearSpringDashpot) };
        let zeta = eta / (2.0 * (kn * m_star).sqrt());
        let omega_d = (kn / m_star).sqrt() * (1.0 - zeta * zeta).sqrt();
        let t_c = PI / omega_d;
        let expected = (-PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        let (v_out, _) = impact(law, lsd_params(kn, en, 0.0), t_c / N);
        let e = v_out / V;
        let tol = (PI / N).powi(2) + (1.0 + 1.0 / expected) * (eta / m_star) * t_c / N;
        assert!(rel_err(e, expected) < tol, "{sizes:?}: e = {e}, expected {expected} (tol {tol:e})");
        if sizes == ContactSizes::Own {
            assert!(rel_err(e, en) < tol, "own sizes rebound with e_n = {en}: {e}");
        } else {
            // The reference's mass is not this pair's: MFIX's form rebounds otherwise.
            assert!(rel_err(e, en) > 10.0 * tol, "phase sizes: e = {e}");
        }
    }
}

/// An elastic Hertz impact's largest overlap is δ_max = (15·m*·v²/(16·E*·√R*))^{2/5} (Hertz;
/// Johnson, Contact Mechanics §11.1) with R* and m* of the two particles in contact — or,
/// with MFIX's form, with K_n from the reference's R* (the masses in an elastic impact are the
/// particles' own either way).
#[test]
fn an_elastic_hertz_impact_of_two_sizes_reaches_the_overlap_of_its_own_radii() {
    let (ma, mb) = masses();
    let m_star = ma * mb / (ma + mb);
    let e_star = 7e7 / (2.0 * (1.0 - 0.3 * 0.3));
    let r_star = RADII[0] * RADII[1] / (RADII[0] + RADII[1]);
    let r_ref = D_REF / 4.0;
    for (sizes, r) in [(ContactSizes::Own, r_star), (ContactSizes::Phase, r_ref)] {
        let law = ContactLaw { sizes, ..ContactLaw::mfix(NormalModel::Hertz) };
        let delta_max = (15.0 * m_star * V * V / (16.0 * e_star * r.sqrt())).powf(0.4);
        // t_c ≈ 2.94·δ_max/v (Hertz's contact-time constant, normal_impact.rs).
        let t_c = 2.94328 * delta_max / V;
        let (v_out, delta) = impact(law, hertz_params(1.0, 1.0, 0.0), t_c / N);
        let tol = (PI / N).powi(2);
        assert!(rel_err(v_out, V) < tol, "{sizes:?}: elastic, rebound {v_out}");
        assert!(rel_err(delta, delta_max) < tol, "{sizes:?}: δ_max = {delta:e}, Hertz {delta_max:e}");
    }
}

/// MFIX's rule takes TCOLL over the contacts a run can have: with own sizes, that of the two
/// smallest particles, π/√(k/m* − (η/2m*)²) with m* = m_small/2 and η from it.
#[test]
fn the_time_step_comes_from_the_smallest_particle_with_own_sizes() {
    let (kn, en) = (2000.0, 0.8);
    let m_small = sphere_mass(RADII[0], RHO) / 2.0;
    let m_ref = sphere_mass(D_REF / 2.0, RHO) / 2.0;
    for (sizes, m) in [(ContactSizes::Own, m_small), (ContactSizes::Phase, m_ref)] {
        let law = ContactLaw { sizes, ..ContactLaw::mfix(NormalModel::LinearSpringDashpot) };
        assert_eq!(law.damping, NormalDamping::Mfix);
        let phases = vec![phase("glass", D_REF, RHO)];
        let mut cfg = config(
            law,
            phases,
            vec![],
            vec![],
            vec![lsd_params(kn, en, 0.0)],
            vec![],
            Integrator::Euler,
            1.0,
        );
        cfg.time_step = TimeStepRule::Mfix { factor: 50.0 };
        cfg.t_stop = 1.0;
        let init = [
            particle(1, 0, RADII[0], RHO, Vec3::new(0.0, 0.0, 0.0), Vec3::ZERO),
            particle(2, 0, RADII[1], RHO, Vec3::new(0.01, 0.0, 0.0), Vec3::ZERO),
        ];
        let sim = simulation(cfg, &init);
        let eta = damping_coefficient(kn, m, en);
        let tcoll = PI / (kn / m - (eta / m).powi(2) / 4.0).sqrt();
        let got = sim.time_step().tcoll.expect("MFIX's rule");
        // The same formula in another order: a few roundings.
        assert!(rel_err(got, tcoll) < 1e-13, "{sizes:?}: TCOLL {got:e}, expected {tcoll:e}");
    }
}
