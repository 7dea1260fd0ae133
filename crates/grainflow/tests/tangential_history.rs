//! The stored tangential displacement integrates the slip velocity once per time step:
//! after k steps of a sticking contact it is s = Σ Δt·v_t ≈ k·Δt·v_t (mfix-dem-model.md §4:
//! "trial s = h + Δt·v_t", one visit per pair per step), whatever the integrator and whether or
//! not a user hook looked at the particles between steps.
//!
//! Set-up: a sphere (R = 1 mm, ρ = 2500 kg/m³) pressed into a wall by δ₀ = 1 µm, sliding along
//! it at v_t = 0.1 m/s, no gravity, μ = 10 (it sticks), LSD k_n = 1e3 N/m with KT_FAC = 1,
//! Δt = 1e-8 s: ω·Δt = √(k/m)·Δt = 1e-4. Over k = 10 steps the contact forces change the slip
//! velocity by a relative O((ω·k·Δt)²) = 1e-6 (tangential spring and the spin it induces) —
//! the normal force does not act along the slip — so s = k·Δt·v_t to a relative 1e-4, the
//! tolerance used.

mod common;

use common::*;
use grainflow::{ContactLaw, Integrator, NormalModel, Simulation, Vec3, Wall};

const DT: f64 = 1e-8;
const VT: f64 = 0.1;
const STEPS: u64 = 10;
const TOL: f64 = 1e-4;

fn sliding_contact(integrator: Integrator) -> Simulation {
    let mut p = lsd_params(1e3, 1.0, 10.0);
    p.kt_fac = 1.0;
    let cfg = config(
        ContactLaw::mfix(NormalModel::LinearSpringDashpot),
        vec![phase("p", 0.002, 2500.0)],
        vec![wall_material("w", None, None)],
        vec![Wall::plane("floor", Vec3::ZERO, Vec3::Y, 0)],
        vec![p],
        vec![p],
        integrator,
        DT,
    );
    let x = Vec3::new(0.0, 1e-3 - 1e-6, 0.0);
    simulation(
        cfg,
        &[particle(1, 0, 1e-3, 2500.0, x, Vec3::new(VT, 0.0, 0.0))],
    )
}

fn stored_slip(sim: &Simulation) -> Vec3 {
    let nl = sim.neighbors();
    assert_eq!(nl.wall_history.len(), 1, "one particle-wall pair");
    nl.wall_history[0]
}

fn check_slip(what: &str, sim: &Simulation) {
    let s = stored_slip(sim);
    let expected = STEPS as f64 * DT * VT;
    eprintln!("{what}: stored slip {s:?}, expected ({expected:e}, 0, 0)");
    assert!(
        rel_err(s.x, expected) <= TOL && s.y.abs() + s.z.abs() <= TOL * expected,
        "{what}: stored tangential displacement {s:?} after {STEPS} steps, expected \
         ({expected:e}, 0, 0) = {STEPS}·Δt·v_t"
    );
}

/// Euler and Adams–Bashforth: one history increment per step.
#[test]
fn history_integrates_slip_once_per_step() {
    for integrator in [Integrator::Euler, Integrator::AdamsBashforth] {
        let mut sim = sliding_contact(integrator);
        for _ in 0..STEPS {
            sim.step();
        }
        check_slip(integrator.name(), &sim);
    }
}

/// Velocity Verlet: the first step evaluates the forces twice (once for the opening
/// half-kick, once after the drift), and `force_loop` advances the tangential history at
/// every evaluation, so after 10 steps s = 11·Δt·v_t (10 % too much).
#[test]
#[ignore = "engine bug: velocity Verlet advances the tangential history twice in its first step (simulation.rs, Simulation::step, VelocityVerlet branch)"]
fn verlet_history_integrates_slip_once_per_step() {
    let mut sim = sliding_contact(Integrator::VelocityVerlet);
    for _ in 0..STEPS {
        sim.step();
    }
    check_slip("velocity_verlet", &sim);
}

/// A user hook that merely borrows the particles mutably (and changes nothing) must not
/// change the physics: Euler and Adams–Bashforth give bit-identical trajectories.
#[test]
fn noop_hook_changes_nothing() {
    for integrator in [Integrator::Euler, Integrator::AdamsBashforth] {
        let mut plain = sliding_contact(integrator);
        let mut hooked = sliding_contact(integrator);
        plain.run_with(STEPS, |_| {});
        hooked.run_with(STEPS, |s| {
            let _ = s.particles_mut();
        });
        assert_eq!(plain.particles(), hooked.particles(), "{integrator:?}");
        assert_eq!(stored_slip(&plain), stored_slip(&hooked), "{integrator:?}");
    }
}

/// Velocity Verlet: `particles_mut` clears `forces_current`, so every following step evaluates
/// the forces twice and the tangential history advances 2·Δt·v_t per step: a hook that does
/// nothing doubles the tangential spring's loading rate (s = 20·Δt·v_t after 10 steps).
#[test]
#[ignore = "engine bug: with velocity Verlet a no-op particles_mut() hook doubles the tangential history increment (simulation.rs, Simulation::step / particles_mut)"]
fn verlet_noop_hook_changes_nothing() {
    let mut plain = sliding_contact(Integrator::VelocityVerlet);
    let mut hooked = sliding_contact(Integrator::VelocityVerlet);
    plain.run_with(STEPS, |_| {});
    hooked.run_with(STEPS, |s| {
        let _ = s.particles_mut();
    });
    eprintln!(
        "stored slip: plain {:?}, hooked {:?}",
        stored_slip(&plain),
        stored_slip(&hooked)
    );
    assert_eq!(stored_slip(&plain), stored_slip(&hooked));
    check_slip("velocity_verlet, hooked", &hooked);
}
