//! Time integration (reference: MFIX-DEM model §6, step 3).
//!
//! a = F/m + g and α = T/I are formed from the accumulators filled by the contact stage
//! (as products with 1/m and 1/I). When every particle has the same mass and moment of inertia
//! (`common`), 1/m and 1/I are formed once for all: the same products to the bit, without two
//! divisions and two loads per particle. Velocity Verlet works on the coordinates as flat
//! arrays, four particles' twelve at a time, in whole vector instructions (the same operations
//! per coordinate as over 3-vectors, so the same bits). Each function integrates the particle
//! slots of the given runs (ascending, not overlapping); the simulation passes the runs of
//! slots that are not prescribed (prescribed particles are overwritten after the step, so
//! integrating them would be wasted work). On threads, each thread integrates the slots of one
//! block — the blocks of the force stage, pinned to the same threads (the `threads` module) —
//! so a particle's state and accumulators stay in the cache of the core that computes its
//! contacts.

use crate::boundary::{FlatWrap, Periodic};
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

/// What every integrator pass takes besides the particles.
#[derive(Debug, Clone, Copy)]
pub struct Pass<'a> {
    /// Runs of slots to integrate (ascending, not overlapping).
    pub runs: &'a [Range<usize>],
    /// Gravity, m/s².
    pub gravity: Vec3,
    /// Time step, s.
    pub dt: f64,
    /// With two or more (consecutive ranges of slots from slot 0 to the last particle), the
    /// slots of block i are integrated on thread i of the current rayon pool.
    pub blocks: &'a [Range<usize>],
    /// The mass and moment of inertia of every particle, if all have the same (see the module's
    /// docs).
    pub common: Option<(f64, f64)>,
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
    /// 1/m and 1/I of every slot, if all particles share them.
    inverses: Option<(f64, f64)>,
}

impl<'a> Slots<'a> {
    fn of(p: &'a mut Particles, r: Range<usize>, inverses: Option<(f64, f64)>) -> Self {
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
            inverses,
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
        let inverses = self.inverses;
        (
            Slots { x, v, w, a_prev, alpha_prev, f, t, m, inertia, inverses },
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
                inverses,
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
            inverses: self.inverses,
        }
    }

    /// Calls `body(self, i, a, α)` for every slot i in order, with a = F/m + g and α = T/I.
    /// One call of `body` in the loop, so that it is inlined; the choice between common
    /// inverses and each slot's own does not change within the loop, so the compiler takes it
    /// out and each loop stays vector code.
    #[inline(always)]
    fn each(&mut self, gravity: Vec3, mut body: impl FnMut(&mut Self, usize, Vec3, Vec3)) {
        let inverses = self.inverses;
        for i in 0..self.v.len() {
            let (inv_m, inv_i) = match inverses {
                Some(common) => common,
                None => (1.0 / self.m[i], 1.0 / self.inertia[i]),
            };
            body(self, i, self.f[i] * inv_m + gravity, self.t[i] * inv_i);
        }
    }
}

/// Applies `kernel` to the slots of the pass's runs, one run at a time, and brings every other
/// slot's position into the periodic box if `wrap` is given (prescribed slots included); the
/// kernel is given `wrap` and must bring its slots' positions into the box before it changes
/// them. With more than one of the pass's blocks, the slots of block i are handled on thread i
/// of the current rayon pool; the result is the same, every particle being updated on its own.
fn for_slots(
    p: &mut Particles,
    pass: &Pass,
    wrap: Option<Periodic>,
    kernel: impl Fn(Slots, Option<Periodic>) + Sync,
) {
    let Pass { runs, blocks, common, .. } = *pass;
    /// Applies the kernel to the parts of `runs` within `block` (`s` its slots), which wraps
    /// their positions first, and wraps the positions of the other slots.
    fn in_block(
        s: &mut Slots,
        block: &Range<usize>,
        runs: &[Range<usize>],
        wrap: Option<Periodic>,
        kernel: &impl Fn(Slots, Option<Periodic>),
    ) {
        let wrap_slots = |s: &mut Slots, r: Range<usize>| {
            if let Some(per) = wrap {
                per.wrap_all(&mut s.x[r]);
            }
        };
        let first = runs.partition_point(|r| r.end <= block.start);
        let mut at = 0;
        for r in runs[first..].iter().take_while(|r| r.start < block.end) {
            let (a, b) = (r.start.max(block.start) - block.start, r.end.min(block.end) - block.start);
            wrap_slots(s, at..a);
            kernel(s.sub(a..b), wrap);
            at = b;
        }
        wrap_slots(s, at..block.len());
    }
    let n = p.len();
    if runs.is_empty() && wrap.is_none() {
        return;
    }
    let inverses = common.map(|(m, inertia)| (1.0 / m, 1.0 / inertia));
    if blocks.len() < 2 {
        in_block(&mut Slots::of(p, 0..n, inverses), &(0..n), runs, wrap, &kernel);
        return;
    }
    let mut parts = crate::threads::Parts::new();
    let mut rest = Slots::of(p, 0..n, inverses);
    for block in blocks {
        let (head, tail) = rest.split_at(block.len());
        parts.push((head, block));
        rest = tail;
    }
    crate::threads::pinned(parts, |_, (mut s, block)| in_block(&mut s, block, runs, wrap, &kernel));
}

/// Brings every position into the periodic box (`blocks` as for the integrators).
pub fn wrap(p: &mut Particles, periodic: Periodic, blocks: &[Range<usize>]) {
    let pass = Pass { runs: &[], gravity: Vec3::ZERO, dt: 0.0, blocks, common: None };
    for_slots(p, &pass, Some(periodic), |_, _| {});
}

/// MFIX's `EULER` step.
pub fn euler(p: &mut Particles, pass: &Pass) {
    let Pass { gravity, dt, .. } = *pass;
    for_slots(p, pass, None, |mut s, _| {
        s.each(gravity, |s, i, a, alpha| {
            s.v[i] += dt * a;
            s.x[i] += dt * s.v[i];
            s.w[i] += dt * alpha;
        });
    });
}

/// MFIX's `ADAMS_BASHFORTH` step. `first` marks the first step of the run, where the previous
/// accelerations are taken equal to the current ones.
pub fn adams_bashforth(p: &mut Particles, pass: &Pass, first: bool) {
    let (gravity, h) = (pass.gravity, 0.5 * pass.dt);
    for_slots(p, pass, None, |mut s, _| {
        s.each(gravity, |s, i, a, alpha| {
            // A particle without a history yet (inserted since: NaN) takes its first step as
            // every particle took the run's first.
            let fresh = first || s.a_prev[i].x.is_nan();
            let (a_prev, alpha_prev) = if fresh { (a, alpha) } else { (s.a_prev[i], s.alpha_prev[i]) };
            let v0 = s.v[i];
            let v1 = v0 + h * (3.0 * a - a_prev);
            s.x[i] += h * (v0 + v1);
            s.v[i] = v1;
            s.w[i] += h * (3.0 * alpha - alpha_prev);
            s.a_prev[i] = a;
            s.alpha_prev[i] = alpha;
        });
    });
}

/// Velocity Verlet, first half: kick by Δt/2 with the current accelerations, then drift by Δt.
pub fn verlet_kick_drift(p: &mut Particles, pass: &Pass) {
    verlet_pass::<1, true>(p, pass, None);
}

/// Velocity Verlet, second half: kick by Δt/2 with the new accelerations; then, with `wrap`,
/// every position brought into the periodic box.
pub fn verlet_kick(p: &mut Particles, pass: &Pass, wrap: Option<Periodic>) {
    verlet_pass::<1, false>(p, pass, wrap);
}

/// The second half kick of one velocity-Verlet step and the first half kick and drift of the
/// next, in one pass, both kicks with the accelerations of the forces in the accumulators:
/// v += (Δt/2)·a twice (the same two roundings as [`verlet_kick`] then
/// [`verlet_kick_drift`]), then x += Δt·v; with `wrap`, every position is brought into the
/// periodic box before the drift, as the step between the two does.
pub fn verlet_kick_kick_drift(p: &mut Particles, pass: &Pass, wrap: Option<Periodic>) {
    verlet_pass::<2, true>(p, pass, wrap);
}

/// `KICKS` half kicks by Δt/2 with the accelerations of the forces in the accumulators, each
/// added on its own, then, with `DRIFT`, x += Δt·v (after the wrap, if any).
fn verlet_pass<const KICKS: usize, const DRIFT: bool>(
    p: &mut Particles,
    pass: &Pass,
    wrap: Option<Periodic>,
) {
    let Pass { gravity, dt, .. } = *pass;
    for_slots(p, pass, wrap, |mut s, wrap| match s.inverses {
        Some(common) => flat_verlet::<KICKS, DRIFT>(&mut s, |_| common, gravity, dt, wrap),
        None => {
            let (m, inertia) = (s.m, s.inertia);
            flat_verlet::<KICKS, DRIFT>(&mut s, |k| (1.0 / m[k], 1.0 / inertia[k]), gravity, dt, wrap)
        }
    });
}

/// Coordinates handled at once by the flat loops: four particles' three.
const FLAT: usize = 12;

/// [`verlet_pass`]'s kicks and drift of the slots `s` (`inverses(k)`: 1/m and 1/I of its k-th
/// slot), on the coordinates as one flat array each (x, y, z of the first slot, then of the
/// next, ...): per slot, a = F·(1/m) + g and α = T·(1/I), the kicks v += (Δt/2)·a and
/// ω += (Δt/2)·α, then x += Δt·v, after the wrap — the products and sums of a loop over
/// 3-vectors, coordinate by coordinate, so the same bits; but in loops over four particles'
/// coordinates at a time, which the compiler makes whole vector instructions of.
fn flat_verlet<const KICKS: usize, const DRIFT: bool>(
    s: &mut Slots,
    inverses: impl Fn(usize) -> (f64, f64),
    gravity: Vec3,
    dt: f64,
    wrap: Option<Periodic>,
) {
    let h = 0.5 * dt;
    let g = gravity.to_array();
    let g12: [f64; FLAT] = std::array::from_fn(|j| g[j % 3]);
    let (f, t): (&[f64], &[f64]) = (bytemuck::cast_slice(s.f), bytemuck::cast_slice(s.t));
    let v: &mut [f64] = bytemuck::cast_slice_mut(&mut *s.v);
    let w: &mut [f64] = bytemuck::cast_slice_mut(&mut *s.w);
    let x: &mut [f64] = bytemuck::cast_slice_mut(&mut *s.x);
    // Per coordinate: the kicks of the velocity, then the drift with the kicked velocity.
    let translate = |v: &mut f64, x: &mut f64, f: f64, inv_m: f64, g: f64| {
        let a = f * inv_m + g;
        for _ in 0..KICKS {
            *v += h * a;
        }
        if DRIFT {
            *x += dt * *v;
        }
    };
    let flat_wrap = wrap.map(|per| FlatWrap::of(&per));
    let n = v.len() / FLAT * FLAT;
    let (v_head, v_tail) = v.split_at_mut(n);
    let (x_head, x_tail) = x.split_at_mut(n);
    // The inverses of the four slots of group c.
    let four = |c: usize| -> [(f64, f64); 4] { std::array::from_fn(|k| inverses(4 * c + k)) };
    for (c, ((vc, xc), fc)) in
        v_head.chunks_exact_mut(FLAT).zip(x_head.chunks_exact_mut(FLAT)).zip(f.chunks_exact(FLAT)).enumerate()
    {
        if let Some(fw) = &flat_wrap {
            fw.wrap_four(xc);
        }
        let inv = four(c);
        for j in 0..FLAT {
            translate(&mut vc[j], &mut xc[j], fc[j], inv[j / 3].0, g12[j]);
        }
    }
    if let Some(fw) = &flat_wrap {
        fw.wrap_each(x_tail);
    }
    for (j, (v, x)) in v_tail.iter_mut().zip(x_tail).enumerate() {
        translate(v, x, f[n + j], inverses((n + j) / 3).0, g[j % 3]);
    }
    let rotate = |w: &mut f64, t: f64, inv_i: f64| {
        let alpha = t * inv_i;
        for _ in 0..KICKS {
            *w += h * alpha;
        }
    };
    let (w_head, w_tail) = w.split_at_mut(n);
    for (c, (wc, tc)) in w_head.chunks_exact_mut(FLAT).zip(t.chunks_exact(FLAT)).enumerate() {
        let inv = four(c);
        for j in 0..FLAT {
            rotate(&mut wc[j], tc[j], inv[j / 3].1);
        }
    }
    for (j, w) in w_tail.iter_mut().enumerate() {
        rotate(w, t[n + j], inverses((n + j) / 3).1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::ParticleInit;

    /// 37 equal spheres with scattered velocities, spins, forces and torques (so that every
    /// product and sum rounds), in a periodic box.
    fn particles() -> Particles {
        let init: Vec<ParticleInit> = (0..37u32)
            .map(|k| {
                let s = f64::from(k);
                ParticleInit {
                    id: k + 1,
                    phase: 0,
                    radius: 0.0013,
                    density: 2630.0,
                    position: Vec3::new(0.01 * (s * 0.37).sin(), 0.003 * s, 0.02 + 1e-4 * s * s),
                    velocity: Vec3::new((s * 1.3).cos(), -0.2 * s, 0.7),
                    omega: Vec3::new(3.0 * s, -(s * 0.9).sin(), 11.0),
                }
            })
            .collect();
        let mut p = Particles::from_init(&init);
        // Out of the periodic box along x of the test below: slot 5 (integrated, in a group of
        // four), 11 (held, between the runs) and 36 (integrated, the last of its run, after
        // its groups of four), so that the wraps change them.
        p.position[5].x = 0.0213;
        p.position[11].x = -0.0207;
        p.position[36].x = 0.0608;
        for (k, (f, t)) in p.force.iter_mut().zip(&mut p.torque).enumerate() {
            let s = k as f64;
            *f = Vec3::new(1e-3 * (s * 0.7).sin(), -2e-4 * s, 3e-3 / (1.0 + s));
            *t = Vec3::new(-1e-7 * s, 2e-7 * (s * 0.4).cos(), 5e-8);
        }
        p
    }

    /// One integrator step.
    type Step<'a> = &'a dyn Fn(&mut Particles, &Pass);

    fn bits(p: &Particles) -> Vec<u64> {
        [&p.position, &p.velocity, &p.omega, &p.accel_prev, &p.alpha_prev]
            .iter()
            .flat_map(|v| v.iter().flat_map(|x| x.to_array()))
            .map(f64::to_bits)
            .collect()
    }

    /// Velocity Verlet written for one particle at a time over 3-vectors, as its equations
    /// read: every position wrapped, then per slot of the runs a = F·(1/m) + g, α = T·(1/I),
    /// `kicks` half kicks and, with `drift`, x += Δt·v. The reference for the flat loops.
    fn verlet_reference(
        p: &mut Particles,
        runs: &[Range<usize>],
        g: Vec3,
        dt: f64,
        kicks: usize,
        drift: bool,
        wrap: Option<Periodic>,
    ) {
        if let Some(per) = wrap {
            p.position.iter_mut().for_each(|x| *x = per.wrap(*x));
        }
        for i in runs.iter().flat_map(|r| r.clone()) {
            let (a, alpha) = (p.force[i] * (1.0 / p.mass[i]) + g, p.torque[i] * (1.0 / p.inertia[i]));
            for _ in 0..kicks {
                p.velocity[i] += 0.5 * dt * a;
                p.omega[i] += 0.5 * dt * alpha;
            }
            if drift {
                p.position[i] += dt * p.velocity[i];
            }
        }
    }

    /// The velocity-Verlet passes over flat coordinates give the bits of the reference over
    /// 3-vectors: with a common mass and without (masses that differ from slot to slot), on
    /// one block and on two, with and without the periodic wrap, for runs of slots whose
    /// lengths are no multiple of four (the last few slots of a run go one by one).
    #[test]
    fn flat_verlet_gives_the_bits_of_one_particle_at_a_time() {
        let mut p0 = particles();
        let per = Periodic {
            lo: Vec3::new(-0.02, 0.0, 0.0),
            hi: Vec3::new(0.02, 0.2, 0.5),
            axes: [true, false, false],
        };
        let runs = [0..11, 12..37];
        let (g, dt) = (Vec3::new(0.3, 0.0, -9.81), 2e-6);
        let common = Some((p0.mass[0], p0.inertia[0]));
        let mut unequal = p0.clone();
        for (k, (m, i)) in unequal.mass.iter_mut().zip(&mut unequal.inertia).enumerate() {
            let s = 1.0 + 0.01 * k as f64;
            (*m, *i) = (*m * s, *i * s * s);
        }
        for (p, common) in [(&mut p0, common), (&mut unequal, None)] {
            for blocks in [&[][..], &[0..20, 20..37][..]] {
                let pass = Pass { runs: &runs, gravity: g, dt, blocks, common };
                for (kicks, drift, wrap) in
                    [(1, true, None), (1, false, Some(per)), (2, true, Some(per)), (2, true, None)]
                {
                    let (mut flat, mut reference) = (p.clone(), p.clone());
                    match (kicks, drift) {
                        (1, true) => verlet_kick_drift(&mut flat, &pass),
                        (1, false) => verlet_kick(&mut flat, &pass, wrap),
                        _ => verlet_kick_kick_drift(&mut flat, &pass, wrap),
                    }
                    verlet_reference(&mut reference, &runs, g, dt, kicks, drift, wrap);
                    let what = format!(
                        "common {:?}, blocks {blocks:?}, {kicks} kicks, drift {drift}, wrap {}",
                        common.is_some(),
                        wrap.is_some()
                    );
                    assert_ne!(bits(&flat), bits(p), "{what}: nothing changed");
                    assert_eq!(bits(&flat), bits(&reference), "{what}");
                }
            }
        }
    }

    /// With every particle's mass and moment of inertia the same, forming 1/m and 1/I once for
    /// all must give every integrator the bits of forming them per particle: the products are
    /// the same numbers (F·(1/m) with the same 1/m), so any difference is a defect. Runs of
    /// slots with a gap (a held particle) and two blocks, as on threads, included; and positions
    /// outside the periodic box, which the passes with the wrap must bring in.
    #[test]
    fn common_inverses_give_the_bits_of_per_particle_ones() {
        let p0 = particles();
        let common = Some((p0.mass[0], p0.inertia[0]));
        assert!(p0.mass.iter().chain(&p0.inertia).all(|&x| x.is_finite() && x > 0.0));
        let (g, dt) = (Vec3::new(0.3, 0.0, -9.81), 2e-6);
        let per = Periodic {
            lo: Vec3::new(-0.02, 0.0, 0.0),
            hi: Vec3::new(0.02, 0.2, 0.5),
            axes: [true, false, false],
        };
        let runs = [0..11, 12..37];
        let steps: [Step; 6] = [
            &|p, pass| euler(p, pass),
            &|p, pass| adams_bashforth(p, pass, true),
            &|p, pass| adams_bashforth(p, pass, false),
            &|p, pass| verlet_kick_drift(p, pass),
            &|p, pass| verlet_kick(p, pass, Some(per)),
            &|p, pass| verlet_kick_kick_drift(p, pass, Some(per)),
        ];
        for (k, step) in steps.iter().enumerate() {
            for blocks in [&[][..], &[0..20, 20..37][..]] {
                let (mut a, mut b) = (p0.clone(), p0.clone());
                if k == 2 {
                    // Adams–Bashforth after its first step reads the previous accelerations.
                    a.accel_prev = a.force.clone();
                    a.alpha_prev = a.torque.clone();
                    b.accel_prev = b.force.clone();
                    b.alpha_prev = b.torque.clone();
                } else if k == 1 {
                    a.accel_prev = vec![Vec3::ZERO; a.len()];
                    a.alpha_prev = vec![Vec3::ZERO; a.len()];
                    b.accel_prev = a.accel_prev.clone();
                    b.alpha_prev = a.alpha_prev.clone();
                }
                let pass = |common| Pass { runs: &runs, gravity: g, dt, blocks, common };
                step(&mut a, &pass(None));
                step(&mut b, &pass(common));
                assert_ne!(bits(&a), bits(&p0), "integrator {k} changed nothing");
                assert_eq!(bits(&a), bits(&b), "integrator {k}, blocks {blocks:?}");
                if k >= 4 {
                    // Wrapped before the drift, if any: within the drift's reach of the box.
                    let reach = dt * a.velocity.iter().map(|v| v.x.abs()).fold(0.0, f64::max);
                    let (lo, hi) = (per.lo.x - reach, per.hi.x + reach);
                    assert!(a.position.iter().all(|x| x.x >= lo && x.x < hi), "integrator {k}: not wrapped");
                }
            }
        }
    }
}
