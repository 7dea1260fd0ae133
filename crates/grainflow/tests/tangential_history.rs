//! The stored tangential displacement integrates the slip velocity once per time step:
//! after k steps of a sticking contact it is s = Σ Δt·v_t ≈ k·Δt·v_t (docs/models.md, tangential spring:
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
    simulation(cfg, &[particle(1, 0, 1e-3, 2500.0, x, Vec3::new(VT, 0.0, 0.0))])
}

fn stored_slip(sim: &Simulation) -> Vec3 {
    let nl = sim.neighbors();
    assert_eq!(nl.wall_history().len(), 1, "one particle-wall pair");
    nl.wall_history()[0]
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
fn verlet_noop_hook_changes_nothing() {
    let mut plain = sliding_contact(Integrator::VelocityVerlet);
    let mut hooked = sliding_contact(Integrator::VelocityVerlet);
    plain.run_with(STEPS, |_| {});
    hooked.run_with(STEPS, |s| {
        let _ = s.particles_mut();
    });
    eprintln!("stored slip: plain {:?}, hooked {:?}", stored_slip(&plain), stored_slip(&hooked));
    assert_eq!(stored_slip(&plain), stored_slip(&hooked));
    check_slip("velocity_verlet, hooked", &hooked);
}

/// Oblique frictional impacts, particle–wall and particle–particle: while in contact the
/// stored displacement is loaded (non-zero); once the contact has ended — the pair still in
/// the neighbour list, within the skin — it is exactly zero again (docs/models.md, tangential spring:
/// "reset to zero when contact ends"), so a later contact starts from zero.
#[test]
fn history_is_reset_when_contact_ends() {
    for integrator in [Integrator::Euler, Integrator::AdamsBashforth, Integrator::VelocityVerlet] {
        let p = lsd_params(1e3, 0.8, 0.3);
        let mut cfg = config(
            ContactLaw::mfix(NormalModel::LinearSpringDashpot),
            vec![phase("p", 0.002, 2500.0)],
            vec![wall_material("w", None, None)],
            vec![Wall::plane("floor", Vec3::ZERO, Vec3::Y, 0)],
            vec![p],
            vec![p],
            integrator,
            2e-6,
        );
        cfg.skin = Some(2e-4);
        let v = Vec3::new(0.3, -0.2, 0.1);
        let init = [
            // Towards the floor, 1 µm away.
            particle(1, 0, 1e-3, 2500.0, Vec3::new(0.0, 1.001e-3, 0.0), v),
            // An oblique pair, far above the floor, 1 µm apart.
            particle(2, 0, 1e-3, 2500.0, Vec3::new(0.0, 0.01, 0.0), v),
            particle(3, 0, 1e-3, 2500.0, Vec3::new(0.0, 0.01 - 2.001e-3, 0.0), -v),
        ];
        let mut sim = simulation(cfg, &init);
        let (mut loaded_wall, mut loaded_pair) = (false, false);
        let (mut checked_wall, mut checked_pair) = (0, 0);
        for _ in 0..2000 {
            sim.step();
            let p = sim.particles();
            let nl = sim.neighbors();
            for (k, &[i, _]) in nl.wall_pairs().iter().enumerate() {
                let gap = p.position[i as usize].y - p.radius[i as usize];
                if gap < 0.0 {
                    loaded_wall |= nl.wall_history()[k] != Vec3::ZERO;
                } else if loaded_wall && gap > 1e-6 {
                    // Separated (by more than a step's travel) after a loaded contact.
                    assert_eq!(nl.wall_history()[k], Vec3::ZERO, "{integrator:?} wall");
                    checked_wall += 1;
                }
            }
            for (k, [i, j]) in nl.pairs().enumerate() {
                let (i, j) = (i as usize, j as usize);
                let gap = (p.position[j] - p.position[i]).length() - p.radius[i] - p.radius[j];
                if gap < 0.0 {
                    loaded_pair |= nl.pair_history()[k] != Vec3::ZERO;
                } else if loaded_pair && gap > 1e-6 {
                    assert_eq!(nl.pair_history()[k], Vec3::ZERO, "{integrator:?} pair");
                    checked_pair += 1;
                }
            }
        }
        assert!(
            loaded_wall && loaded_pair,
            "{integrator:?}: contacts never loaded ({loaded_wall}, {loaded_pair})"
        );
        assert!(
            checked_wall > 0 && checked_pair > 0,
            "{integrator:?}: no step checked after separation ({checked_wall}, {checked_pair})"
        );
    }
}

/// A pair that touches again after a contact, with no rebuild of the neighbour list between the
/// two (so the spring of the first contact is still stored beside the pair), starts the second
/// contact from a zero spring (docs/models.md, tangential spring: "reset to zero when contact ends"): the
/// run is bit-identical to one started afresh, with no stored spring, from the state between
/// the two contacts. Set-up: a sphere (R = 1 mm, ρ = 2500 kg/m³) falling under gravity onto a
/// held one right below it and bouncing on it, drifting sideways at 5 mm/s (so each contact
/// loads the tangential spring); LSD k_n = 1e3 N/m, e = 0.5, μ = 0.3, Δt = 5 µs; the skin
/// (0.4 mm) keeps the list from being rebuilt between the bounces (asserted).
#[test]
fn a_second_contact_starts_from_a_zero_spring() {
    use grainflow::state::ParticleInit;
    use grainflow::{MotionRule, PrescribedMotion};
    for integrator in [Integrator::Euler, Integrator::VelocityVerlet] {
        let make = |init: &[ParticleInit]| {
            let p = lsd_params(1e3, 0.5, 0.3);
            let mut cfg = config(
                ContactLaw::mfix(NormalModel::LinearSpringDashpot),
                vec![phase("p", 0.002, 2500.0)],
                vec![],
                vec![],
                vec![p],
                vec![],
                integrator,
                5e-6,
            );
            cfg.gravity = Vec3::new(0.0, -9.81, 0.0);
            cfg.skin = Some(4e-4);
            cfg.motion = vec![PrescribedMotion { particle: 1, rule: MotionRule::Hold }];
            simulation(cfg, init)
        };
        let touching = |sim: &Simulation| {
            let p = sim.particles();
            (p.position[1] - p.position[0]).length() < p.radius[0] + p.radius[1]
        };
        let mut sim = make(&[
            particle(1, 0, 1e-3, 2500.0, Vec3::ZERO, Vec3::ZERO),
            particle(2, 0, 1e-3, 2500.0, Vec3::new(0.0, 2.001e-3, 0.0), Vec3::new(5e-3, -0.05, 0.0)),
        ]);
        // Through the first contact, to the first step after it.
        let mut steps = 0;
        let mut step_while = |sim: &mut Simulation, touch: bool| {
            while touching(sim) == touch {
                sim.step();
                steps += 1;
                assert!(steps < 20_000, "{integrator:?}: the bounce never came");
            }
        };
        step_while(&mut sim, false);
        step_while(&mut sim, true);
        let builds = sim.neighbors().stats().builds;
        let p = sim.particles();
        let between: Vec<ParticleInit> = (0..2)
            .map(|i| ParticleInit {
                id: p.id[i],
                phase: p.phase[i],
                radius: p.radius[i],
                density: 2500.0,
                position: p.position[i],
                velocity: p.velocity[i],
                omega: p.omega[i],
            })
            .collect();
        let mover = between.iter().find(|q| q.id == 2).expect("particle 2");
        assert!(mover.omega != Vec3::ZERO, "{integrator:?}: the first contact loaded no spring");
        let mut fresh = make(&between);
        // The second contact, side by side, to its end.
        let (mut second, mut ended) = (false, false);
        for _ in 0..20_000 {
            sim.step();
            fresh.step();
            let (a, b) = (sim.particles(), fresh.particles());
            assert_eq!(
                (&a.position, &a.velocity, &a.omega),
                (&b.position, &b.velocity, &b.omega),
                "{integrator:?}: the second contact differs from one without a stored spring"
            );
            if touching(&sim) && !second {
                second = true;
                assert_eq!(sim.neighbors().stats().builds, builds, "{integrator:?}: the list was rebuilt");
            }
            if second && !touching(&sim) {
                ended = true;
                break;
            }
        }
        assert!(second && ended, "{integrator:?}: no second contact ({second}, {ended})");
    }
}
