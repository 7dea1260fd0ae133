//! Time integration (reference: MFIX-DEM model §6, step 3).
//!
//! a = F/m + g and α = T/I are formed from the accumulators filled by the contact stage
//! (as products with 1/m and 1/I). Each function integrates the particle slots of the given
//! runs (ascending, not overlapping); the simulation passes the runs of slots that are not
//! prescribed (prescribed particles are overwritten after the step, so integrating them would
//! be wasted work). On threads, each thread integrates the slots of one block — the blocks of
//! the force stage, pinned to the same threads (the `threads` module) — so a particle's state
//! and accumulators stay in the cache of the core that computes its contacts.

use crate::boundary::Periodic;
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

/// The arrays of a run of particle slots that the integrators read and write. The
/// Adams–Bashforth history is empty unless that integrator runs.
struct Slots<'a> {
    x: &'a mut [Vec3],
    v: &'a mut [Vec3],
    w: &'a mut [Vec3],
    a_prev: &'a mut [Vec3],
    alpha_prev: &'a mut [Vec3],
    f: &'a [Vec3],
    t: &'a [Vec3],
    m: &'a [f64],
    inertia: &'a [f64],
}

impl<'a> Slots<'a> {
    fn of(p: &'a mut Particles, r: Range<usize>) -> Self {
        let history = |h: &'a mut Vec<Vec3>| if h.is_empty() { &mut h[..] } else { &mut h[r.clone()] };
        Slots {
            x: &mut p.position[r.clone()],
            v: &mut p.velocity[r.clone()],
            w: &mut p.omega[r.clone()],
            a_prev: history(&mut p.accel_prev),
            alpha_prev: history(&mut p.alpha_prev),
            f: &p.force[r.clone()],
            t: &p.torque[r.clone()],
            m: &p.mass[r.clone()],
            inertia: &p.inertia[r],
        }
    }

    fn split_at(self, k: usize) -> (Self, Self) {
        fn cut<T>(s: &mut [T], k: usize) -> (&mut [T], &mut [T]) {
            if s.is_empty() { (&mut [], &mut []) } else { s.split_at_mut(k) }
        }
        let (x, x2) = self.x.split_at_mut(k);
        let (v, v2) = self.v.split_at_mut(k);
        let (w, w2) = self.w.split_at_mut(k);
        let (a_prev, a_prev2) = cut(self.a_prev, k);
        let (alpha_prev, alpha_prev2) = cut(self.alpha_prev, k);
        let (f, f2) = self.f.split_at(k);
        let (t, t2) = self.t.split_at(k);
        let (m, m2) = self.m.split_at(k);
        let (inertia, inertia2) = self.inertia.split_at(k);
        (
            Slots { x, v, w, a_prev, alpha_prev, f, t, m, inertia },
            Slots {
                x: x2,
                v: v2,
                w: w2,
                a_prev: a_prev2,
                alpha_prev: alpha_prev2,
                f: f2,
                t: t2,
                m: m2,
                inertia: inertia2,
            },
        )
    }

    /// The slots `r` of these (indices relative to their first slot).
    fn sub(&mut self, r: Range<usize>) -> Slots<'_> {
        fn part<T>(s: &mut [T], r: Range<usize>) -> &mut [T] {
            if s.is_empty() { &mut [] } else { &mut s[r] }
        }
        Slots {
            x: &mut self.x[r.clone()],
            v: &mut self.v[r.clone()],
            w: &mut self.w[r.clone()],
            a_prev: part(self.a_prev, r.clone()),
            alpha_prev: part(self.alpha_prev, r.clone()),
            f: &self.f[r.clone()],
            t: &self.t[r.clone()],
            m: &self.m[r.clone()],
            inertia: &self.inertia[r],
        }
    }

    /// a = F/m + g and α = T/I of slot i.
    #[inline(always)]
    fn accelerations(&self, i: usize, gravity: Vec3) -> (Vec3, Vec3) {
        (self.f[i] * (1.0 / self.m[i]) + gravity, self.t[i] * (1.0 / self.inertia[i]))
    }
}

/// Applies `kernel` to the slots of `runs`, one run at a time, after bringing every slot's
/// position into the periodic box if `wrap` is given (prescribed slots included). With more
/// than one block in `blocks` (consecutive ranges of slots from slot 0 to the last particle),
/// the slots of block i are handled on thread i of the current rayon pool; the result is the
/// same, every particle being updated on its own.
fn for_slots(
    p: &mut Particles,
    runs: &[Range<usize>],
    blocks: &[Range<usize>],
    wrap: Option<Periodic>,
    kernel: impl Fn(Slots) + Sync,
) {
    /// Wraps the positions of `s` (the slots of `block`), then applies the kernel to the parts
    /// of `runs` within `block`.
    fn in_block(
        s: &mut Slots,
        block: &Range<usize>,
        runs: &[Range<usize>],
        wrap: Option<Periodic>,
        kernel: &impl Fn(Slots),
    ) {
        if let Some(per) = wrap {
            s.x.iter_mut().for_each(|x| *x = per.wrap(*x));
        }
        let first = runs.partition_point(|r| r.end <= block.start);
        for r in runs[first..].iter().take_while(|r| r.start < block.end) {
            let (a, b) = (r.start.max(block.start), r.end.min(block.end));
            kernel(s.sub(a - block.start..b - block.start));
        }
    }
    let n = p.len();
    if runs.is_empty() && wrap.is_none() {
        return;
    }
    if blocks.len() < 2 {
        in_block(&mut Slots::of(p, 0..n), &(0..n), runs, wrap, &kernel);
        return;
    }
    let mut parts = Vec::with_capacity(blocks.len());
    let mut rest = Slots::of(p, 0..n);
    for block in blocks {
        let (head, tail) = rest.split_at(block.len());
        parts.push((head, block));
        rest = tail;
    }
    crate::threads::pinned(parts, |_, (mut s, block)| in_block(&mut s, block, runs, wrap, &kernel));
}

/// Brings every position into the periodic box (`blocks` as for the integrators).
pub fn wrap(p: &mut Particles, periodic: Periodic, blocks: &[Range<usize>]) {
    for_slots(p, &[], blocks, Some(periodic), |_| {});
}

/// MFIX's `EULER` step.
pub fn euler(p: &mut Particles, runs: &[Range<usize>], gravity: Vec3, dt: f64, blocks: &[Range<usize>]) {
    for_slots(p, runs, blocks, None, |s| {
        for i in 0..s.x.len() {
            let (a, alpha) = s.accelerations(i, gravity);
            s.v[i] += dt * a;
            s.x[i] += dt * s.v[i];
            s.w[i] += dt * alpha;
        }
    });
}

/// MFIX's `ADAMS_BASHFORTH` step. `first` marks the first step of the run, where the previous
/// accelerations are taken equal to the current ones.
pub fn adams_bashforth(
    p: &mut Particles,
    runs: &[Range<usize>],
    gravity: Vec3,
    dt: f64,
    first: bool,
    blocks: &[Range<usize>],
) {
    let h = 0.5 * dt;
    for_slots(p, runs, blocks, None, |s| {
        for i in 0..s.x.len() {
            let (a, alpha) = s.accelerations(i, gravity);
            let (a_prev, alpha_prev) = if first { (a, alpha) } else { (s.a_prev[i], s.alpha_prev[i]) };
            let v0 = s.v[i];
            let v1 = v0 + h * (3.0 * a - a_prev);
            s.x[i] += h * (v0 + v1);
            s.v[i] = v1;
            s.w[i] += h * (3.0 * alpha - alpha_prev);
            s.a_prev[i] = a;
            s.alpha_prev[i] = alpha;
        }
    });
}

/// Velocity Verlet, first half: kick by Δt/2 with the current accelerations, then drift by Δt.
pub fn verlet_kick_drift(
    p: &mut Particles,
    runs: &[Range<usize>],
    gravity: Vec3,
    dt: f64,
    blocks: &[Range<usize>],
) {
    verlet_pass::<1, true>(p, runs, gravity, dt, blocks, None);
}

/// Velocity Verlet, second half: kick by Δt/2 with the new accelerations; then, with `wrap`,
/// every position brought into the periodic box.
pub fn verlet_kick(
    p: &mut Particles,
    runs: &[Range<usize>],
    gravity: Vec3,
    dt: f64,
    blocks: &[Range<usize>],
    wrap: Option<Periodic>,
) {
    verlet_pass::<1, false>(p, runs, gravity, dt, blocks, wrap);
}

/// The second half kick of one velocity-Verlet step and the first half kick and drift of the
/// next, in one pass, both kicks with the accelerations of the forces in the accumulators:
/// v += (Δt/2)·a twice (the same two roundings as [`verlet_kick`] then
/// [`verlet_kick_drift`]), then x += Δt·v; with `wrap`, every position is brought into the
/// periodic box before the drift, as the step between the two does.
pub fn verlet_kick_kick_drift(
    p: &mut Particles,
    runs: &[Range<usize>],
    gravity: Vec3,
    dt: f64,
    blocks: &[Range<usize>],
    wrap: Option<Periodic>,
) {
    verlet_pass::<2, true>(p, runs, gravity, dt, blocks, wrap);
}

/// `KICKS` half kicks by Δt/2 with the accelerations of the forces in the accumulators, each
/// added on its own, then, with `DRIFT`, x += Δt·v (after the wrap, if any).
fn verlet_pass<const KICKS: usize, const DRIFT: bool>(
    p: &mut Particles,
    runs: &[Range<usize>],
    gravity: Vec3,
    dt: f64,
    blocks: &[Range<usize>],
    wrap: Option<Periodic>,
) {
    let h = 0.5 * dt;
    for_slots(p, runs, blocks, wrap, |s| {
        for i in 0..s.v.len() {
            let (a, alpha) = s.accelerations(i, gravity);
            for _ in 0..KICKS {
                s.v[i] += h * a;
                s.w[i] += h * alpha;
            }
            if DRIFT {
                s.x[i] += dt * s.v[i];
            }
        }
    });
}
