//! Long-run health: 2 000 frictional, inelastic particles pour down a tilted box and settle,
//! 10⁵ steps. No particle is lost, nothing turns non-finite, and the energy books close:
//!
//!   input work (gravity, −ΔE_pot) = ΔE_kin + ΔU (springs) + D (dissipated),
//!
//! where the work the contacts absorb is measured independently of the kinetic energy, per
//! particle and step, as W = −Σ (F·v̄ + T·ω̄)·Δt with v̄, ω̄ the averages over the step.
//! For the (symplectic) Euler step this is exactly the kinetic energy the contact forces
//! remove, so the books close up to the potential's discretisation (bounded below) and
//! rounding; the dissipation D = W − U must then never decrease by more than the springs'
//! discretisation error: energy is never created.

mod common;

use common::*;
use grainflow::contact::{ContactLaw, NormalModel};
use grainflow::{Integrator, Simulation, Vec3, Wall};

#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn two_thousand_particles_for_1e5_steps_stay_healthy_and_the_energy_books_close() {
    let (kn, en, mu) = (2000.0, 0.7, 0.5);
    let params = lsd_params(kn, en, mu);
    let lo = Vec3::ZERO;
    let hi = Vec3::new(0.08, 0.12, 0.04);
    let dt = 2e-5;
    let mut cfg = config(
        ContactLaw::mfix(NormalModel::LinearSpringDashpot),
        vec![phase("glass", 0.003, 2500.0)],
        vec![wall_material("steel", None, None)],
        Wall::domain_box(lo, hi, 0),
        vec![params],
        vec![params],
        Integrator::Euler,
        dt,
    );
    // Gravity tilted 30° in x: the grains pour along the floor into the far corner.
    let g = 9.81;
    cfg.gravity = Vec3::new(g * 0.5, -g * 0.75f64.sqrt(), 0.0);
    let mut rng = Rng::new(42);
    let mut init = Vec::new();
    // Loose lattice in the upper-left part of the box, slightly polydisperse.
    let spacing = 0.0036;
    'fill: for j in 0.. {
        for i in 0..12 {
            for k in 0..10 {
                if init.len() == 2000 {
                    break 'fill;
                }
                let x = Vec3::new(
                    0.003 + i as f64 * spacing,
                    0.003 + j as f64 * spacing,
                    0.003 + k as f64 * spacing,
                );
                let r = rng.range(0.0013, 0.0016);
                init.push(particle(init.len() as u32 + 1, 0, r, 2500.0, x, rng.unit() * 0.05));
            }
        }
    }
    assert!(
        init.iter().all(|p| p.position.cmplt(hi - Vec3::splat(0.002)).all()),
        "initial lattice does not fit"
    );
    let mut sim: Simulation = simulation(cfg, &init);
    let n = sim.particles().len();
    let m = |s: &Simulation| s.particles().mass.clone();
    let mass = m(&sim);
    let k_t = sim.coefficients().pair(0, 0).kt;
    let springs = |s: &Simulation| -> f64 {
        // Normal springs (diagnostics) plus tangential springs ½k_t|s|² of the stored histories.
        let nl = s.neighbors();
        let t: f64 =
            nl.pair_history().iter().chain(nl.wall_history()).map(|h| 0.5 * k_t * h.length_squared()).sum();
        s.diagnostics().elastic + t
    };
    let e0 = sim.diagnostics();
    let u0 = springs(&sim);
    let (mut absorbed, mut potential_bound) = (0.0f64, 0.0f64);
    let (mut d_max, mut worst_drop, mut u_max) = (0.0f64, 0.0f64, 0.0f64);
    let steps = 100_000;
    for step in 1..=steps {
        let v0 = sim.particles().velocity.clone();
        let w0 = sim.particles().omega.clone();
        sim.step();
        let p = sim.particles();
        let mut w = 0.0;
        for i in 0..n {
            let vbar = 0.5 * (v0[i] + p.velocity[i]);
            let wbar = 0.5 * (w0[i] + p.omega[i]);
            w -= (p.force[i].dot(vbar) + p.torque[i].dot(wbar)) * dt;
            // Euler's potential step differs from the gravity work it integrates by
            // m·g·(v_{n+1} − v_n)·Δt/2 = m·g·a·Δt²/2: accumulate its bound.
            potential_bound += 0.5 * mass[i] * g * ((p.velocity[i] - v0[i]).length()) * dt;
        }
        absorbed += w;
        if step % 500 == 0 || step == steps {
            for i in 0..n {
                let x = p.position[i];
                assert!(
                    x.is_finite() && p.velocity[i].is_finite() && p.omega[i].is_finite(),
                    "step {step}: particle {} not finite",
                    p.id[i]
                );
                assert!(
                    x.cmpge(lo).all() && x.cmple(hi).all(),
                    "step {step}: particle {} left the box at {x:?}",
                    p.id[i]
                );
            }
            let d = sim.diagnostics();
            let u = springs(&sim);
            u_max = u_max.max(u);
            // Books: ΔE_kin + ΔE_pot + W_absorbed = 0, up to the potential's discretisation and
            // rounding (1e-12 of the energies moved).
            let moved = (e0.potential - d.potential).abs() + e0.kinetic_translational + absorbed.abs();
            let closure = (d.kinetic_translational + d.kinetic_rotational + d.potential)
                - (e0.kinetic_translational + e0.kinetic_rotational + e0.potential)
                + absorbed;
            assert!(
                closure.abs() <= potential_bound + 1e-12 * moved,
                "step {step}: books off by {closure:e} J (bound {potential_bound:e} J)"
            );
            // Dissipation D = W − ΔU never decreases by more than the springs' discretisation:
            // Euler's shadow energy differs from ½kδ² by at most (ωΔt)²/4 of it (ω from the
            // pair's effective mass), i.e. (ωΔt)²/4·U_max.
            let dissipated = absorbed - (u - u0);
            let omega = (kn / (0.5 * mass.iter().copied().fold(f64::INFINITY, f64::min))).sqrt();
            let slack = 0.25 * (omega * dt).powi(2) * u_max;
            worst_drop = worst_drop.max(d_max - dissipated);
            assert!(
                dissipated >= d_max - slack,
                "step {step}: dissipation fell from {d_max:e} to {dissipated:e} J (slack {slack:e})"
            );
            d_max = d_max.max(dissipated);
        }
    }
    let d = sim.diagnostics();
    let input = e0.potential - d.potential;
    // The bed has come to rest: nearly all the potential energy released was dissipated.
    assert!(input > 0.0, "the grains did not fall");
    assert!(
        d.kinetic_translational < 1e-3 * input,
        "still moving: {} J of {input} J",
        d.kinetic_translational
    );
    assert!(d_max > 0.9 * input, "dissipated {d_max:e} J of {input:e} J released");
    eprintln!(
        "input {input:.6e} J, dissipated {d_max:.6e} J, kinetic {:.3e} J, springs {:.3e} J; potential bound {potential_bound:.3e} J; worst dissipation drop {worst_drop:.3e} J; {} contacts",
        d.kinetic_translational + d.kinetic_rotational,
        springs(&sim),
        d.contacts
    );
}
