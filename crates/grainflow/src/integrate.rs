//! Time integration (reference: MFIX-DEM model §6, step 3).
//!
//! a = F/m + g and α = T/I are formed from the accumulators filled by the contact stage
//! (as products with 1/m and 1/I). Each function integrates the particle slots in
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

/// Particles per piece of work when integrating on several threads.
const CHUNK: usize = 4096;

/// MFIX's `EULER` step. With `parallel`, on the current rayon pool (the result is the same:
/// every particle is updated on its own).
pub fn euler(p: &mut Particles, r: Range<usize>, gravity: Vec3, dt: f64, parallel: bool) {
    let kernel = |x: &mut [Vec3],
                  v: &mut [Vec3],
                  w: &mut [Vec3],
                  f: &[Vec3],
                  t: &[Vec3],
                  m: &[f64],
                  inertia: &[f64]| {
        for i in 0..x.len() {
            let (a, alpha) = (f[i] * (1.0 / m[i]) + gravity, t[i] * (1.0 / inertia[i]));
            v[i] += dt * a;
            x[i] += dt * v[i];
            w[i] += dt * alpha;
        }
    };
    let (x, v, w) = (&mut p.position[r.clone()], &mut p.velocity[r.clone()], &mut p.omega[r.clone()]);
    let (f, t, m, inertia) = (&p.force[r.clone()], &p.torque[r.clone()], &p.mass[r.clone()], &p.inertia[r]);
    if parallel {
        use rayon::prelude::*;
        (
            x.par_chunks_mut(CHUNK),
            v.par_chunks_mut(CHUNK),
            w.par_chunks_mut(CHUNK),
            f.par_chunks(CHUNK),
            t.par_chunks(CHUNK),
            m.par_chunks(CHUNK),
            inertia.par_chunks(CHUNK),
        )
            .into_par_iter()
            .for_each(|(x, v, w, f, t, m, inertia)| kernel(x, v, w, f, t, m, inertia));
    } else {
        kernel(x, v, w, f, t, m, inertia);
    }
}

/// MFIX's `ADAMS_BASHFORTH` step. `first` marks the first step of the run, where the previous
/// accelerations are taken equal to the current ones.
pub fn adams_bashforth(
    p: &mut Particles,
    r: Range<usize>,
    gravity: Vec3,
    dt: f64,
    first: bool,
    parallel: bool,
) {
    let h = 0.5 * dt;
    let kernel = |x: &mut [Vec3],
                  v: &mut [Vec3],
                  w: &mut [Vec3],
                  ap: &mut [Vec3],
                  alp: &mut [Vec3],
                  f: &[Vec3],
                  t: &[Vec3],
                  m: &[f64],
                  inertia: &[f64]| {
        for i in 0..x.len() {
            let a = f[i] * (1.0 / m[i]) + gravity;
            let alpha = t[i] * (1.0 / inertia[i]);
            let (a_prev, alpha_prev) = if first { (a, alpha) } else { (ap[i], alp[i]) };
            let v0 = v[i];
            let v1 = v0 + h * (3.0 * a - a_prev);
            x[i] += h * (v0 + v1);
            v[i] = v1;
            w[i] += h * (3.0 * alpha - alpha_prev);
            ap[i] = a;
            alp[i] = alpha;
        }
    };
    let (x, v, w) = (&mut p.position[r.clone()], &mut p.velocity[r.clone()], &mut p.omega[r.clone()]);
    let (ap, alp) = (&mut p.accel_prev[r.clone()], &mut p.alpha_prev[r.clone()]);
    let (f, t, m, inertia) = (&p.force[r.clone()], &p.torque[r.clone()], &p.mass[r.clone()], &p.inertia[r]);
    if parallel {
        use rayon::prelude::*;
        (
            x.par_chunks_mut(CHUNK),
            v.par_chunks_mut(CHUNK),
            w.par_chunks_mut(CHUNK),
            ap.par_chunks_mut(CHUNK),
            alp.par_chunks_mut(CHUNK),
            f.par_chunks(CHUNK),
            t.par_chunks(CHUNK),
            m.par_chunks(CHUNK),
            inertia.par_chunks(CHUNK),
        )
            .into_par_iter()
            .for_each(|(x, v, w, ap, alp, f, t, m, inertia)| kernel(x, v, w, ap, alp, f, t, m, inertia));
    } else {
        kernel(x, v, w, ap, alp, f, t, m, inertia);
    }
}

/// Velocity Verlet, first half: kick by Δt/2 with the current accelerations, then drift by Δt.
pub fn verlet_kick_drift(p: &mut Particles, r: Range<usize>, gravity: Vec3, dt: f64, parallel: bool) {
    let h = 0.5 * dt;
    let kernel = |x: &mut [Vec3],
                  v: &mut [Vec3],
                  w: &mut [Vec3],
                  f: &[Vec3],
                  t: &[Vec3],
                  m: &[f64],
                  inertia: &[f64]| {
        for i in 0..x.len() {
            let (a, alpha) = (f[i] * (1.0 / m[i]) + gravity, t[i] * (1.0 / inertia[i]));
            v[i] += h * a;
            w[i] += h * alpha;
            x[i] += dt * v[i];
        }
    };
    let (x, v, w) = (&mut p.position[r.clone()], &mut p.velocity[r.clone()], &mut p.omega[r.clone()]);
    let (f, t, m, inertia) = (&p.force[r.clone()], &p.torque[r.clone()], &p.mass[r.clone()], &p.inertia[r]);
    if parallel {
        use rayon::prelude::*;
        (
            x.par_chunks_mut(CHUNK),
            v.par_chunks_mut(CHUNK),
            w.par_chunks_mut(CHUNK),
            f.par_chunks(CHUNK),
            t.par_chunks(CHUNK),
            m.par_chunks(CHUNK),
            inertia.par_chunks(CHUNK),
        )
            .into_par_iter()
            .for_each(|(x, v, w, f, t, m, inertia)| kernel(x, v, w, f, t, m, inertia));
    } else {
        kernel(x, v, w, f, t, m, inertia);
    }
}

/// Velocity Verlet, second half: kick by Δt/2 with the new accelerations.
pub fn verlet_kick(p: &mut Particles, r: Range<usize>, gravity: Vec3, dt: f64, parallel: bool) {
    let h = 0.5 * dt;
    let kernel = |v: &mut [Vec3], w: &mut [Vec3], f: &[Vec3], t: &[Vec3], m: &[f64], inertia: &[f64]| {
        for i in 0..v.len() {
            let (a, alpha) = (f[i] * (1.0 / m[i]) + gravity, t[i] * (1.0 / inertia[i]));
            v[i] += h * a;
            w[i] += h * alpha;
        }
    };
    let (v, w) = (&mut p.velocity[r.clone()], &mut p.omega[r.clone()]);
    let (f, t, m, inertia) = (&p.force[r.clone()], &p.torque[r.clone()], &p.mass[r.clone()], &p.inertia[r]);
    if parallel {
        use rayon::prelude::*;
        (
            v.par_chunks_mut(CHUNK),
            w.par_chunks_mut(CHUNK),
            f.par_chunks(CHUNK),
            t.par_chunks(CHUNK),
            m.par_chunks(CHUNK),
            inertia.par_chunks(CHUNK),
        )
            .into_par_iter()
            .for_each(|(v, w, f, t, m, inertia)| kernel(v, w, f, t, m, inertia));
    } else {
        kernel(v, w, f, t, m, inertia);
    }
}
