//! The force stage of a step: every particle–wall and particle–particle contact's force and
//! torque, summed into the particles' accumulators in one fixed order, whatever the number of
//! threads.
//!
//! ## The order of the sums
//! A particle's force is the sum, in this order, of: its wall contacts (in wall-list order);
//! then the pairs (c, b) of the rows c below it, in row order; then its own row's pairs
//! (a, b), in partner order. [`NeighborList`](crate::neighbor::NeighborList) keeps the pairs
//! in rows of the lower slot, so walking the rows in slot order and adding each pair's force
//! to both particles at once gives exactly that order. Floating-point sums depend on their
//! order; keeping it fixed makes the results bit-identical from run to run and for any number
//! of threads.
//!
//! ## Threads
//! The slots are cut into blocks of consecutive rows with about equal pair counts. A pair whose
//! two particles lie in one block is computed by that block's thread, which adds it to both
//! particles directly. A pair (a, b) with b in a later block (a *crossing* pair) is computed
//! first, in a parallel pass, and kept; its block then adds it to a in a's row, and b's block
//! adds it to b before any of its own rows — where the order above puts it, since its row lies
//! below b's block. One block is the serial loop itself. With particles in a spatial order
//! (`[particles] order = "spatial"`) few pairs cross.

use std::ops::Range;

use crate::boundary::Periodic;
use crate::contact::geometry::{ContactGeometry, pair_contact_separation, relative_velocity, wall_contact};
use crate::contact::law::{ContactForce, contact_force, rolling_torque};
use crate::contact::{CoeffTable, ContactCoeffs, ContactLaw, LeverArm, NormalDamping};
use crate::math::Vec3;
use crate::wall::Wall;

/// Below this many particles the force stage runs on one thread (the threads' start-up would
/// cost more than they save). The results do not depend on it.
pub const MIN_PARALLEL_PARTICLES: usize = 2048;

/// Blocks per thread. More blocks would let the threads balance uneven work, at the price of
/// more crossing pairs; on the yardstick cases 4 per thread gained nothing and raised the
/// crossing pairs of the chute to ~20 %, so each thread takes one block.
pub const BLOCKS_PER_THREAD: usize = 1;

/// What one contact adds: the force on the lower slot a (b gets its opposite) and the torques
/// on a and b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairLoad {
    f: Vec3,
    ta: Vec3,
    tb: Vec3,
}

/// Read-only inputs of the force stage.
pub(crate) struct ForceInputs<'a> {
    pub position: &'a [Vec3],
    pub velocity: &'a [Vec3],
    pub omega: &'a [Vec3],
    pub radius: &'a [f64],
    pub mass: &'a [f64],
    pub phase: &'a [u32],
    /// Slots held fixed (empty if none).
    pub held: &'a [bool],
    pub walls: &'a [Wall],
    pub coeffs: &'a CoeffTable,
    pub law: ContactLaw,
    pub periodic: Periodic,
    /// Δt for the tangential springs (0 when the history is not advanced).
    pub dt: f64,
    /// Store the advanced tangential springs.
    pub advance: bool,
    pub offsets: &'a [usize],
    pub partners: &'a [u32],
    pub wall_pairs: &'a [[u32; 2]],
}

/// Outputs of the force stage.
pub(crate) struct ForceOutputs<'a> {
    pub force: &'a mut [Vec3],
    pub torque: &'a mut [Vec3],
    pub pair_history: &'a mut [Vec3],
    pub wall_history: &'a mut [Vec3],
}

/// How the slots are cut into blocks for threads, with the crossing pairs; rebuilt with the
/// neighbour list.
#[derive(Debug, Clone, Default)]
pub(crate) struct ForcePlan {
    /// The neighbour-list build this plan was made for, and the block count asked for.
    made_for: Option<(u64, usize)>,
    /// Rows of each block.
    blocks: Vec<Range<usize>>,
    /// End of each block's wall pairs in the wall list.
    wall_ends: Vec<usize>,
    /// Crossing pairs (row a, pair index k), grouped by block in list order.
    crossing: Vec<(u32, usize)>,
    /// Start of each block's crossing pairs in `crossing` (blocks + 1 entries).
    crossing_start: Vec<usize>,
    /// Crossing pairs arriving at each slot, as indices into `crossing`, in list order:
    /// `incoming[incoming_start[b]..incoming_start[b + 1]]`.
    incoming_start: Vec<usize>,
    incoming: Vec<u32>,
    /// The crossing pairs' loads (None: not in contact).
    loads: Vec<Option<PairLoad>>,
}

impl ForcePlan {
    /// Heap bytes held by the plan.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.blocks.capacity() * size_of::<Range<usize>>()
            + self.crossing.capacity() * size_of::<(u32, usize)>()
            + (self.wall_ends.capacity() + self.crossing_start.capacity() + self.incoming_start.capacity())
                * size_of::<usize>()
            + self.incoming.capacity() * 4
            + self.loads.capacity() * size_of::<Option<PairLoad>>()
    }

    /// Cuts `n` slots into `n_blocks` blocks with about equal pair counts, unless it was done
    /// for this neighbour-list build already.
    pub fn prepare(
        &mut self,
        build: u64,
        n_blocks: usize,
        offsets: &[usize],
        partners: &[u32],
        wall_pairs: &[[u32; 2]],
    ) {
        if self.made_for == Some((build, n_blocks)) {
            return;
        }
        self.made_for = Some((build, n_blocks));
        let n = offsets.len().saturating_sub(1);
        let total = partners.len();
        self.blocks.clear();
        let mut start = 0;
        for t in 1..=n_blocks {
            // The first row whose pairs start at or beyond the block's share of the pairs.
            let end = if t == n_blocks {
                n
            } else {
                let target = total * t / n_blocks;
                offsets.partition_point(|&o| o < target).clamp(start, n)
            };
            self.blocks.push(start..end);
            start = end;
        }
        self.wall_ends.clear();
        self.wall_ends
            .extend(self.blocks.iter().map(|r| wall_pairs.partition_point(|&[i, _]| (i as usize) < r.end)));
        self.crossing.clear();
        self.crossing_start.clear();
        self.incoming_start.clear();
        self.incoming_start.resize(n + 1, 0);
        for rows in &self.blocks {
            self.crossing_start.push(self.crossing.len());
            for a in rows.clone() {
                for k in offsets[a]..offsets[a + 1] {
                    let b = partners[k] as usize;
                    if b >= rows.end {
                        self.crossing.push((a as u32, k));
                        self.incoming_start[b + 1] += 1;
                    }
                }
            }
        }
        self.crossing_start.push(self.crossing.len());
        for b in 0..n {
            self.incoming_start[b + 1] += self.incoming_start[b];
        }
        self.incoming.clear();
        self.incoming.resize(self.crossing.len(), 0);
        let mut fill = self.incoming_start.clone();
        for (c, &(_, k)) in self.crossing.iter().enumerate() {
            let b = partners[k] as usize;
            self.incoming[fill[b]] = c as u32;
            fill[b] += 1;
        }
        self.loads.clear();
        self.loads.resize(self.crossing.len(), None);
    }
}

/// Evaluates every contact into `out` on one thread. With `clock`, returns the seconds spent on
/// the wall contacts (0 otherwise).
pub(crate) fn serial<const HERTZ: bool, const INCREMENTAL: bool>(
    x: &ForceInputs,
    out: ForceOutputs,
    clock: bool,
) -> f64 {
    let n = x.position.len();
    block::<HERTZ, INCREMENTAL>(
        clock,
        x,
        0..n,
        out.force,
        out.torque,
        out.pair_history,
        out.wall_history,
        0,
        Incoming::None,
        &[],
    )
}

/// Evaluates every contact into `out` on the blocks of `plan`, in parallel on the current
/// rayon pool. Bit-identical to [`serial`]. With `clock`, returns the seconds the blocks spent
/// on wall contacts, averaged over the blocks (0 otherwise).
pub(crate) fn parallel<const HERTZ: bool, const INCREMENTAL: bool>(
    x: &ForceInputs,
    plan: &mut ForcePlan,
    out: ForceOutputs,
    clock: bool,
) -> f64 {
    use rayon::prelude::*;
    let blocks = &plan.blocks;
    let pair_ends = || blocks.iter().map(|r| x.offsets[r.end]);
    let slot_ends = || blocks.iter().map(|r| r.end);
    let wall_ends = &plan.wall_ends;

    // Pass 1: the crossing pairs, each block's on its thread.
    {
        let hist = split_at_ends(&mut *out.pair_history, pair_ends());
        let loads = split_at_ends(&mut plan.loads[..], plan.crossing_start[1..].iter().copied());
        let crossing = &plan.crossing;
        let starts = &plan.crossing_start;
        hist.into_par_iter().zip(loads).enumerate().for_each(|(t, (hist, loads))| {
            let k0 = x.offsets[blocks[t].start];
            for (load, &(a, k)) in loads.iter_mut().zip(&crossing[starts[t]..starts[t + 1]]) {
                let b = x.partners[k] as usize;
                *load = pair_load::<HERTZ, INCREMENTAL>(x, a as usize, b, &mut hist[k - k0]);
            }
        });
    }
    // Pass 2: each block's walls, arriving crossing pairs and own rows.
    let force = split_at_ends(&mut *out.force, slot_ends());
    let torque = split_at_ends(&mut *out.torque, slot_ends());
    let hist = split_at_ends(&mut *out.pair_history, pair_ends());
    let whist = split_at_ends(&mut *out.wall_history, wall_ends.iter().copied());
    let incoming =
        Incoming::Crossing { start: &plan.incoming_start, index: &plan.incoming, loads: &plan.loads };
    let crossing_start = &plan.crossing_start;
    let loads = &plan.loads;
    let wall_seconds: f64 = force
        .into_par_iter()
        .zip(torque)
        .zip(hist)
        .zip(whist)
        .enumerate()
        .map(|(t, (((force, torque), hist), whist))| {
            let rows = blocks[t].clone();
            let w0 = if t == 0 { 0 } else { wall_ends[t - 1] };
            block::<HERTZ, INCREMENTAL>(
                clock,
                x,
                rows,
                force,
                torque,
                hist,
                whist,
                w0,
                incoming,
                &loads[crossing_start[t]..crossing_start[t + 1]],
            )
        })
        .sum();
    wall_seconds / blocks.len().max(1) as f64
}

/// Splits `s` at the given ends of consecutive parts (the last end must be `s.len()`).
fn split_at_ends<T>(mut s: &mut [T], ends: impl ExactSizeIterator<Item = usize>) -> Vec<&mut [T]> {
    let mut parts = Vec::with_capacity(ends.len());
    let mut at = 0;
    for end in ends {
        let (head, tail) = s.split_at_mut(end - at);
        parts.push(head);
        s = tail;
        at = end;
    }
    parts
}

/// Crossing pairs that arrive at a block from rows below it.
#[derive(Clone, Copy)]
enum Incoming<'a> {
    None,
    Crossing { start: &'a [usize], index: &'a [u32], loads: &'a [Option<PairLoad>] },
}

/// The force stage of the rows `rows`: `force`/`torque` are those rows' accumulators,
/// `hist` the histories of their pairs, `whist` those of their wall pairs (starting at wall
/// pair `w0`), `own_crossing` the loads of their crossing pairs in list order. With `clock`,
/// returns the seconds spent on the walls.
#[inline(always)]
fn block<const HERTZ: bool, const INCREMENTAL: bool>(
    clock: bool,
    x: &ForceInputs,
    rows: Range<usize>,
    force: &mut [Vec3],
    torque: &mut [Vec3],
    hist: &mut [Vec3],
    whist: &mut [Vec3],
    w0: usize,
    incoming: Incoming,
    own_crossing: &[Option<PairLoad>],
) -> f64 {
    let t0 = clock.then(std::time::Instant::now);
    let (r0, r1) = (rows.start, rows.end);
    force.fill(Vec3::ZERO);
    torque.fill(Vec3::ZERO);
    // Walls first, as MFIX does.
    for (h, &[i, w]) in whist.iter_mut().zip(&x.wall_pairs[w0..]) {
        if let Some((f, t)) = wall_load::<HERTZ, INCREMENTAL>(x, i as usize, w as usize, h) {
            force[i as usize - r0] += f;
            torque[i as usize - r0] += t;
        }
    }
    let wall_seconds = t0.map_or(0.0, |t| t.elapsed().as_secs_f64());
    // Then the crossing pairs from the rows below this block, in list order.
    if let Incoming::Crossing { start, index, loads } = incoming {
        for b in rows.clone() {
            for &c in &index[start[b]..start[b + 1]] {
                if let Some(l) = loads[c as usize] {
                    force[b - r0] -= l.f;
                    torque[b - r0] += l.tb;
                }
            }
        }
    }
    // Then the rows, in order.
    let k0 = x.offsets[r0];
    let mut crossing = own_crossing.iter();
    for a in rows {
        let (mut fa, mut ta) = (force[a - r0], torque[a - r0]);
        for k in x.offsets[a]..x.offsets[a + 1] {
            let b = x.partners[k] as usize;
            let load = if b < r1 {
                let l = pair_load::<HERTZ, INCREMENTAL>(x, a, b, &mut hist[k - k0]);
                if let Some(l) = l {
                    force[b - r0] -= l.f;
                    torque[b - r0] += l.tb;
                }
                l
            } else {
                crossing.next().copied().flatten()
            };
            if let Some(l) = load {
                fa += l.f;
                ta += l.ta;
            }
        }
        force[a - r0] = fa;
        torque[a - r0] = ta;
    }
    wall_seconds
}

/// The load of pair (a, b), a < b, advancing its tangential history `h`; None (and the
/// history cleared) when they do not touch.
#[inline(always)]
fn pair_load<const HERTZ: bool, const INCREMENTAL: bool>(
    x: &ForceInputs,
    a: usize,
    b: usize,
    h: &mut Vec3,
) -> Option<PairLoad> {
    let law = &x.law;
    let Some(g) = pair_geometry(x, a, b) else {
        *h = Vec3::ZERO;
        return None;
    };
    let c = x.coeffs.pair(x.phase[a] as usize, x.phase[b] as usize);
    let (wa, wb) = (x.omega[a], x.omega[b]);
    let v_r = relative_velocity(&g, x.velocity[a], x.velocity[b], wa, wb);
    let f = law_force::<HERTZ, INCREMENTAL>(x, c, || pair_mass(x.mass, x.held, a, b), &g, v_r, h);
    Some(PairLoad {
        f: f.total(),
        ta: f.torque(torque_lever(law.lever, g.lever_i, g.overlap), g.normal)
            + rolling_torque(c.mu_roll, f.elastic_normal, wa),
        tb: f.torque(torque_lever(law.lever, g.lever_j, g.overlap), g.normal)
            + rolling_torque(c.mu_roll, f.elastic_normal, wb),
    })
}

/// The force and torque of particle i against wall w, advancing the history `h`; None (and
/// the history cleared) when they do not touch.
#[inline(always)]
fn wall_load<const HERTZ: bool, const INCREMENTAL: bool>(
    x: &ForceInputs,
    i: usize,
    w: usize,
    h: &mut Vec3,
) -> Option<(Vec3, Vec3)> {
    let law = &x.law;
    let wall = &x.walls[w];
    let Some(g) = wall_geometry(x.position[i], x.radius[i], wall, law.lever) else {
        *h = Vec3::ZERO;
        return None;
    };
    let c = x.coeffs.wall(x.phase[i] as usize, wall.material);
    let v_r = relative_velocity(&g, x.velocity[i], Vec3::ZERO, x.omega[i], Vec3::ZERO);
    let f = law_force::<HERTZ, INCREMENTAL>(x, c, || x.mass[i], &g, v_r, h);
    Some((f.total(), f.torque(g.lever_i, g.normal) + rolling_torque(c.mu_roll, f.elastic_normal, x.omega[i])))
}

/// The law's force for a contact with coefficients `c`, whose damping is scaled by the
/// contact's effective mass `m_eff` when the law asks for it; advances the history `h` when
/// the step stores it.
#[inline(always)]
fn law_force<const HERTZ: bool, const INCREMENTAL: bool>(
    x: &ForceInputs,
    c: &ContactCoeffs,
    m_eff: impl FnOnce() -> f64,
    g: &ContactGeometry,
    v_r: Vec3,
    h: &mut Vec3,
) -> ContactForce {
    let law = &x.law;
    let c = if law.damping.per_particle_mass() { scaled_damping(c, law.damping, m_eff()) } else { *c };
    let mut hn = *h;
    let f = contact_force::<HERTZ, INCREMENTAL>(
        law.history,
        law.clip_attraction,
        law.coulomb,
        &c,
        g,
        v_r,
        &mut hn,
        x.dt,
    );
    if x.advance {
        *h = hn;
    }
    f
}

/// Effective mass of the particles in slots i and j: m_i m_j/(m_i + m_j), or the other one's
/// mass if one of them is held fixed (as LAMMPS does for frozen particles).
#[inline(always)]
pub(crate) fn pair_mass(mass: &[f64], held: &[bool], i: usize, j: usize) -> f64 {
    if !held.is_empty() {
        if held[i] {
            return mass[j];
        }
        if held[j] {
            return mass[i];
        }
    }
    mass[i] * mass[j] / (mass[i] + mass[j])
}

/// The coefficients with damping that depends on the contact's masses applied: ×m_eff
/// (`MassVelocity`), ×√m_eff (`Tsuji`); unchanged otherwise.
#[inline(always)]
pub(crate) fn scaled_damping(c: &ContactCoeffs, damping: NormalDamping, m_eff: f64) -> ContactCoeffs {
    let s = match damping {
        NormalDamping::MassVelocity => m_eff,
        NormalDamping::Tsuji => m_eff.sqrt(),
        NormalDamping::Mfix | NormalDamping::ExactRestitution => return *c,
    };
    ContactCoeffs { eta_n: c.eta_n * s, eta_t: c.eta_t * s, ..*c }
}

/// Pair geometry of slots a, b with the law's lever arm, if they touch.
#[inline(always)]
fn pair_geometry(x: &ForceInputs, a: usize, b: usize) -> Option<ContactGeometry> {
    pair_geometry_of(x.position, x.radius, a, b, x.law.lever, &x.periodic)
}

/// Pair geometry of slots i, j with lever arm `lever`, if they touch.
#[inline(always)]
pub(crate) fn pair_geometry_of(
    position: &[Vec3],
    radius: &[f64],
    i: usize,
    j: usize,
    lever: LeverArm,
    per: &Periodic,
) -> Option<ContactGeometry> {
    let d = position[j] - position[i];
    let d = if per.any() { per.min_image(d) } else { d };
    let mut g = pair_contact_separation(d, radius[i], radius[j])?;
    if lever != LeverArm::RadicalPlane {
        (g.lever_i, g.lever_j) = (radius[i], radius[j]);
    }
    Some(g)
}

/// The lever of the tangential force's torque: the geometry's lever, less half the overlap
/// for LAMMPS's `pair granular` convention.
#[inline(always)]
pub(crate) fn torque_lever(lever: LeverArm, geometric: f64, overlap: f64) -> f64 {
    if lever == LeverArm::LammpsGranular { geometric - 0.5 * overlap } else { geometric }
}

/// Geometry of a particle at `x` with radius `r` against a wall with the law's lever arm, if
/// they touch.
#[inline(always)]
pub(crate) fn wall_geometry(x: Vec3, r: f64, wall: &Wall, lever: LeverArm) -> Option<ContactGeometry> {
    let mut g = wall_contact(x, r, wall.point, wall.normal)?;
    if lever != LeverArm::RadicalPlane {
        g.lever_i = r;
    }
    Some(g)
}
