//! Energy conservation of an elastic, frictionless granular gas in a closed box, with gravity.
//!
//! With e_n = 1 and μ = 0 nothing dissipates: kinetic + gravitational + normal-spring energy
//! (`Diagnostics::total_energy`) is a constant of the exact dynamics. The run uses velocity
//! Verlet, the engine's symplectic, time-reversible integrator.
//!
//! ## The bound, and why
//! Between contacts velocity Verlet is exact under constant gravity (the trajectory is a
//! parabola, which the scheme integrates without truncation error), so energy can only be
//! lost or gained in contacts. During an LSD contact the relative motion along the normal is a
//! harmonic oscillator (about an equilibrium shifted by gravity for a wall contact), for which
//! velocity Verlet exactly conserves the shadow energy ½m*v² + ½kδ²·(1 − (ωΔt)²/4): inside a
//! contact the energy deviates by at most (ωΔt)²/4 of the oscillation energy, and the only
//! other error is made in the two steps that straddle the kink of the force law at δ = 0,
//! again O((ωΔt)²) of the oscillation energy and of either sign. So a contact that starts with
//! normal relative speed v_n adds an energy error of at most ε·E_c, with
//! E_c = ½m*v_n² (+ ½m*(g·n)²/ω² for a wall, the energy of the shifted equilibrium) and ε a
//! number of order (ωΔt)² that depends only on ωΔt and on where in a step the contact starts.
//!
//! ε is *measured* here, independently of the many-particle run: single pair impacts
//! (head-on and oblique) and wall impacts (floor, side wall, ceiling, with gravity) at the
//! same Δt, over 32 entry phases spread over one step, taking the largest |E(t) − E(0)|/E_c at
//! any time during or after the contact. The many-particle run then detects every contact as it
//! starts, accumulates ΣE_c, and checks |E(t) − E(0)| ≤ 2·ε·ΣE_c (+ 1e-12·E for rounding) at
//! every step. The factor 2 covers what the calibration does not sample exactly: the supremum
//! over entry phases between the 32 sampled ones (the error is smooth and periodic in the
//! phase, so the sampled maximum is within a few per cent of it), and contacts that overlap in
//! time (a particle touching two others), whose errors add only approximately. The worst case
//! assumed here — all errors of the same sign — is pessimistic, but a genuine leak (any
//! damping: e_n = 0.99 loses 2 % of E_c per contact; a missing or double-counted elastic
//! energy; a wrong gravity term) costs far more than 2ε ≈ 2e-3 of E_c per contact and breaks
//! the bound within the first few contacts.

mod common;

use common::*;
use grainflow::state::ParticleInit;
use grainflow::{ContactLaw, Integrator, NormalModel, Simulation, Vec3, Wall};
use std::collections::HashSet;
use std::f64::consts::PI;

const RADIUS: f64 = 1e-3;
const DENSITY: f64 = 2500.0;
const KN: f64 = 1e3;
/// Box edge, m.
const BOX: f64 = 0.03;
const G: f64 = 9.80665;

fn mass() -> f64 {
    sphere_mass(RADIUS, DENSITY)
}

/// Contact time of a pair (the shortest one), s.
fn tcoll() -> f64 {
    PI * (0.5 * mass() / KN).sqrt()
}

/// The elastic, frictionless gas: one phase, box walls, gravity along −y, velocity Verlet.
fn gas_sim(init: &[ParticleInit], steps_per_tcoll: f64, walls: Vec<Wall>, gravity: Vec3) -> Simulation {
    let p = lsd_params(KN, 1.0, 0.0);
    let mut cfg = config(
        ContactLaw::mfix(NormalModel::LinearSpringDashpot),
        vec![phase("glass", 2.0 * RADIUS, DENSITY)],
        vec![wall_material("steel", None, None)],
        walls,
        vec![p],
        vec![p],
        Integrator::VelocityVerlet,
        tcoll() / steps_per_tcoll,
    );
    cfg.gravity = gravity;
    simulation(cfg, init)
}

fn box_walls() -> Vec<Wall> {
    Wall::domain_box(Vec3::ZERO, Vec3::splat(BOX), 0)
}

/// Tracks contacts by stable ids and accumulates E_c of each one as it starts.
struct ContactLedger {
    pairs: HashSet<(u32, u32)>,
    walls: HashSet<(u32, u32)>,
    started: u64,
    sum_ec: f64,
}

impl ContactLedger {
    fn new() -> Self {
        ContactLedger { pairs: HashSet::new(), walls: HashSet::new(), started: 0, sum_ec: 0.0 }
    }

    /// Looks at every candidate pair of the neighbour list (which holds every contact: the
    /// neighbour-search tests check that) and records contacts that have just started.
    fn update(&mut self, sim: &Simulation) {
        let p = sim.particles();
        let g = Vec3::new(0.0, -G, 0.0);
        let nl = sim.neighbors();
        let mut now = HashSet::new();
        for [i, j] in nl.pairs() {
            let (i, j) = (i as usize, j as usize);
            let dx = p.position[j] - p.position[i];
            let d = dx.length();
            if d <= p.radius[i] + p.radius[j] {
                let key = (p.id[i], p.id[j]);
                now.insert(key);
                if !self.pairs.contains(&key) {
                    let m_star = p.mass[i] * p.mass[j] / (p.mass[i] + p.mass[j]);
                    let vn = (p.velocity[i] - p.velocity[j]).dot(dx / d);
                    self.sum_ec += 0.5 * m_star * vn * vn;
                    self.started += 1;
                }
            }
        }
        self.pairs = now;
        let walls = sim.walls();
        let mut now = HashSet::new();
        for &[i, w] in nl.wall_pairs() {
            let (i, wall) = (i as usize, &walls[w as usize]);
            if wall.distance(p.position[i]) <= p.radius[i] {
                let key = (p.id[i], w);
                now.insert(key);
                if !self.walls.contains(&key) {
                    let m = p.mass[i];
                    let vn = p.velocity[i].dot(wall.normal);
                    // Gravity's component pressing towards the wall, and the energy of the
                    // equilibrium it shifts: ½m(g_n)²/ω², ω² = k/m.
                    let gn = g.dot(wall.normal);
                    self.sum_ec += 0.5 * m * vn * vn + 0.5 * m * gn * gn * m / KN;
                    self.started += 1;
                }
            }
        }
        self.walls = now;
    }
}

/// Runs a single contact and returns max |E(t) − E(0)| / E_c over the whole run.
fn single_contact_error(init: &[ParticleInit], walls: Vec<Wall>, gravity: Vec3, n: f64) -> f64 {
    let mut sim = gas_sim(init, n, walls, gravity);
    let e0 = sim.diagnostics().total_energy();
    // (Rounding is ~1e-16 of E(0), far below the ε ~ 1e-3 being measured.)
    let mut ledger = ContactLedger::new();
    ledger.update(&sim);
    let mut worst = 0.0f64;
    // Long enough for the contact to start and end (speeds ≥ 0.05 m/s, gaps ≤ 0.1 mm).
    for _ in 0..(12.0 * n) as usize {
        sim.step();
        ledger.update(&sim);
        worst = worst.max((sim.diagnostics().total_energy() - e0).abs());
    }
    assert_eq!(ledger.started, 1, "exactly one contact in a calibration run");
    worst / ledger.sum_ec
}

/// ε: the largest single-contact relative energy error at `n` steps per pair contact time.
fn calibrate(n: f64) -> f64 {
    let dt = tcoll() / n;
    let mut eps = 0.0f64;
    let phases = 32;
    for k in 0..phases {
        let frac = (k as f64 + 0.5) / phases as f64;
        // Pairs, zero gravity (it acts equally on both): head-on and oblique, several speeds.
        for &(v, b) in &[(1.0, 0.0), (0.3, 0.5), (2.0, 0.9), (0.1, 0.97)] {
            let dir = Vec3::new(1.0, 0.3, -0.2).normalize();
            let side = dir.cross(Vec3::Z).normalize();
            let xa = Vec3::splat(0.01);
            // Impact parameter b·2R; the gap along the approach path is frac·v·Δt.
            let lateral = b * 2.0 * RADIUS;
            let along = ((2.0 * RADIUS).powi(2) - lateral * lateral).sqrt() + frac * v * dt;
            let xb = xa + along * dir + lateral * side;
            let init = [
                particle(1, 0, RADIUS, DENSITY, xa, 0.5 * v * dir),
                particle(2, 0, RADIUS, DENSITY, xb, -0.5 * v * dir),
            ];
            eps = eps.max(single_contact_error(&init, Vec::new(), Vec3::ZERO, n));
        }
        // Walls with gravity: floor (gravity presses), side wall, ceiling (gravity pulls away),
        // slow and fast, normal and oblique.
        for &(normal, v, tangential) in
            &[(Vec3::Y, 1.0, 0.0), (Vec3::Y, 0.05, 0.3), (Vec3::X, 0.5, 0.5), (-Vec3::Y, 1.0, 0.2)]
        {
            let point = Vec3::splat(0.01);
            let t = normal.cross(Vec3::Z).normalize_or(Vec3::X);
            let x = point + (RADIUS + frac * v * dt) * normal;
            let init = [particle(1, 0, RADIUS, DENSITY, x, -v * normal + tangential * t)];
            let wall = vec![Wall::plane("w", point, normal, 0)];
            eps = eps.max(single_contact_error(&init, wall, Vec3::new(0.0, -G, 0.0), n));
        }
    }
    eps
}

/// `n_particles` non-overlapping particles at random positions in the box with random
/// velocities (each component uniform in ±`speed`) and random spins.
fn random_gas(n_particles: usize, speed: f64, seed: u64) -> Vec<ParticleInit> {
    let mut rng = Rng::new(seed);
    let mut init: Vec<ParticleInit> = Vec::with_capacity(n_particles);
    let lo = Vec3::splat(RADIUS * 1.01);
    let hi = Vec3::splat(BOX - RADIUS * 1.01);
    while init.len() < n_particles {
        let x = rng.in_box(lo, hi);
        if init.iter().all(|q| (q.position - x).length() > 2.0 * RADIUS * 1.01) {
            let v = Vec3::new(rng.range(-speed, speed), rng.range(-speed, speed), rng.range(-speed, speed));
            let mut q = particle(init.len() as u32 + 1, 0, RADIUS, DENSITY, x, v);
            q.omega = 100.0 * rng.unit();
            init.push(q);
        }
    }
    init
}

/// Runs the gas and checks the bound at every step; returns (max |ΔE|/bound, max |ΔE|/E₀,
/// contacts).
fn run_gas(n_particles: usize, steps: usize, n: f64, eps: f64, seed: u64) -> (f64, f64, u64) {
    let init = random_gas(n_particles, 0.6, seed);
    let mut sim = gas_sim(&init, n, box_walls(), Vec3::new(0.0, -G, 0.0));
    let d0 = sim.diagnostics();
    let e0 = d0.total_energy();
    // Floating-point rounding: the energy sums ~4N terms (ε·4N ≈ 1e-13 relative at N = 300)
    // and the state takes ~1e-16 relative per step, a random walk of ≈ 3e-14 over 1e5 steps;
    // 1e-12 of the energy's terms covers both with a margin.
    let rounding =
        1e-12 * (d0.kinetic_translational + d0.kinetic_rotational + d0.potential.abs() + d0.elastic);
    let mut ledger = ContactLedger::new();
    ledger.update(&sim);
    let (mut worst_ratio, mut worst_rel) = (0.0f64, 0.0f64);
    for step in 0..steps {
        sim.step();
        ledger.update(&sim);
        let d = sim.diagnostics();
        let err = (d.total_energy() - e0).abs();
        let bound = 2.0 * eps * ledger.sum_ec + rounding;
        assert!(
            err <= bound,
            "step {step}: |E - E0| = {err:e} J exceeds 2·eps·ΣE_c = {bound:e} J \
             (E0 = {e0:e} J, {} contacts so far)",
            ledger.started
        );
        worst_ratio = worst_ratio.max(err / bound.max(f64::MIN_POSITIVE));
        worst_rel = worst_rel.max(err / e0);
    }
    // Friction is off, so the spins never change.
    for (w, q) in sim.particles().omega.iter().zip(&init) {
        assert_eq!(*w, q.omega);
    }
    (worst_ratio, worst_rel, ledger.started)
}

/// The calibration itself: ε is of order (ωΔt)² as the shadow-energy argument says, and it
/// falls as Δt² (a factor 4 per halving of Δt, allowing ±30 % for the phase sampling).
#[test]
fn single_contact_energy_error_is_second_order() {
    let e50 = calibrate(50.0);
    let e100 = calibrate(100.0);
    let w = PI / 50.0; // ω_pair·Δt at 50 steps per contact time
    eprintln!("eps(50) = {e50:e} = {:.3}·(ωΔt)², eps(100) = {e100:e}", e50 / (w * w));
    assert!(e50 > 0.0 && e50 <= w * w, "eps(50) = {e50:e} vs (ωΔt)² = {:e}", w * w);
    let ratio = e50 / e100;
    assert!((2.8..=5.2).contains(&ratio), "eps(50)/eps(100) = {ratio}");
}

/// 250 particles, Δt = t_coll/50 (MFIX's default factor), about 2 400 contacts.
#[test]
fn elastic_gas_conserves_energy() {
    let n = 50.0;
    let eps = calibrate(n);
    let (ratio, rel, contacts) = run_gas(250, 20_000, n, eps, 7);
    eprintln!("eps = {eps:e}; {contacts} contacts; max |dE|/bound = {ratio:.3}, max |dE|/E0 = {rel:e}");
    assert!(contacts >= 100, "too few contacts ({contacts}) to test anything");
}

/// 300 particles for longer (tens of thousands of contacts), at two time steps.
#[test]
#[cfg_attr(debug_assertions, ignore = "expensive: run with --release")]
fn elastic_gas_conserves_energy_long() {
    for (n, steps) in [(50.0, 200_000), (200.0, 400_000)] {
        let eps = calibrate(n);
        let (ratio, rel, contacts) = run_gas(300, steps, n, eps, 11);
        eprintln!(
            "N = {n}: eps = {eps:e}; {contacts} contacts; max |dE|/bound = {ratio:.3}, max |dE|/E0 = {rel:e}"
        );
        assert!(contacts >= 2000);
    }
}
