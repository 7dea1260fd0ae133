//! Time integration (reference: MFIX-DEM model §6, step 3).
//!
//! a = F/m + g and α = T/I are formed from the accumulators filled by the contact stage
//! (as products with the stored 1/m and 1/I). Each function integrates the particle slots in
//! `range`; the simulation passes the runs of slots that are not prescribed (prescribed
//! particles are overwritten after the step, so integrating them would be wasted work).

use crate::math::Vec3;
use crate::state::Particles;
use std::ops::Range;

/// The time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// MFIX `EULER` (its default): v ← v + Δt·a; x ← x + Δt·v (the new v); ω ← ω + Δt·α.
    /// This is the symplectic (semi-implicit) Euler method.
    Euler,
    /// MFIX `ADAMS_BASHFORTH`: v⁺ = v + (Δt/2)(3a − a_prev); x⁺ = x + (Δt/2)(v + v⁺);
    /// ω⁺ = ω + (Δt/2)(3α − α_prev). On the first step a_prev = a, α_prev = α.
    AdamsBashforth,
    /// Velocity Verlet (kick–drift–kick): v += (Δt/2)·a; x += Δt·v; forces; v += (Δt/2)·a.
    /// The contact forces see the half-step velocity.
    VelocityVerlet,
}

impl Integrator {
    /// The name used in case files.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Euler => "euler",
            Integrator::AdamsBashforth => "adams_bashforth",
            Integrator::VelocityVerlet => "velocity_verlet",
        }
    }
}

#[inline(always)]
fn accelerations(p: &Particles, i: usize, gravity: Vec3) -> (Vec3, Vec3) {
    (p.force[i] * p.inv_mass[i] + gravity, p.torque[i] * p.inv_inertia[i])
}

/// MFIX's `EULER` step.
pub fn euler(p: &mut Particles, range: Range<usize>, gravity: Vec3, dt: f64) {
    for i in range {
        let (a, alpha) = accelerations(p, i, gravity);
        p.velocity[i] += dt * a;
        p.position[i] += dt * p.velocity[i];
        p.omega[i] += dt * alpha;
    }
}

/// MFIX's `ADAMS_BASHFORTH` step. `first` marks the first step of the run, where the previous
/// accelerations are taken equal to the current ones.
pub fn adams_bashforth(p: &mut Particles, range: Range<usize>, gravity: Vec3, dt: f64, first: bool) {
    let h = 0.5 * dt;
    let r = range;
    // Slicing every array to the range up front lets the compiler drop the bounds checks.
    let (force, torque) = (&p.force[r.clone()], &p.torque[r.clone()]);
    let (inv_m, inv_i) = (&p.inv_mass[r.clone()], &p.inv_inertia[r.clone()]);
    let x = &mut p.position[r.clone()];
    let v = &mut p.velocity[r.clone()];
    let w = &mut p.omega[r.clone()];
    let a_prev = &mut p.accel_prev[r.clone()];
    let alpha_prev = &mut p.alpha_prev[r];
    for i in 0..force.len() {
        let a = force[i] * inv_m[i] + gravity;
        let alpha = torque[i] * inv_i[i];
        let (ap, alp) = if first { (a, alpha) } else { (a_prev[i], alpha_prev[i]) };
        let v0 = v[i];
        let v1 = v0 + h * (3.0 * a - ap);
        x[i] += h * (v0 + v1);
        v[i] = v1;
        w[i] += h * (3.0 * alpha - alp);
        a_prev[i] = a;
        alpha_prev[i] = alpha;
    }
}

/// Velocity Verlet, first half: kick by Δt/2 with the current accelerations, then drift by Δt.
pub fn verlet_kick_drift(p: &mut Particles, range: Range<usize>, gravity: Vec3, dt: f64) {
    let h = 0.5 * dt;
    for i in range {
        let (a, alpha) = accelerations(p, i, gravity);
        p.velocity[i] += h * a;
        p.omega[i] += h * alpha;
        p.position[i] += dt * p.velocity[i];
    }
}

/// Velocity Verlet, second half: kick by Δt/2 with the new accelerations.
pub fn verlet_kick(p: &mut Particles, range: Range<usize>, gravity: Vec3, dt: f64) {
    let h = 0.5 * dt;
    for i in range {
        let (a, alpha) = accelerations(p, i, gravity);
        p.velocity[i] += h * a;
        p.omega[i] += h * alpha;
    }
}
