//! The force stage of a step: every particle–wall and particle–particle contact's force and
//! torque, summed into the particles' accumulators by sums that do not depend on their order —
//! so the results are the same for any number of threads, any order of the particles in
//! memory, and any split of them into parts.
//!
//! ## The sums
//! Every load is rounded to a multiple of a power-of-two quantum before it is added, so that
//! the sums are exact (fixed-point arithmetic in `f64`s); the quantum follows the largest load
//! of the evaluation before (see the `sum` module). Walls are added first, then the pairs in the order
//! the rows are walked, but any other order gives the same bits. A pair's load is computed once
//! and added to both particles (Newton's third law holds to the bit: the rounding is odd).
//!
//! ## Batches
//! The contacts' loads do not depend on each other, only their sums do. So a block first tests
//! a stretch of its pairs for contact, without branching on the outcome, and lists the touching
//! ones (setting each pair's contact flag; a pair that starts touching starts from zero
//! history); it then gathers their inputs into batches of 16 (one array per component),
//! computes a batch's loads in one loop that compiles to vector instructions, and adds them to
//! the particles in list order — the order above — storing the new histories. The contact
//! law is the same function as for a single contact, written without data-dependent
//! branches: it forms the value of every setting and picks one. So the batch loop is also
//! compiled for the common settings (LAMMPS's two laws, MFIX's) with only the parts of the law
//! they pick (`contact::law::parts`), which spares several square roots and divisions per
//! contact. Where the build does not assume them, AVX2 and AVX-512 copies of the loop are
//! used on processors that have them; they round exactly as scalar code does (no fused
//! multiply–add), so results do not depend on the processor
//! (`lanes::tests::batched_loads_equal_the_scalar_law_on_every_instruction_set`). On beds too
//! large for the processor's caches, the contact test asks a few rows ahead for the data of
//! the particles about to come within the pairs' reach (`detect::prefetch_ahead`).
//!
//! ## Threads
//! The slots are cut into blocks of consecutive rows with about equal work (rows, pairs to
//! test, touching pairs weighted by their larger cost: `ForcePlan::prepare`). A pair whose
//! two particles lie in one block is computed by that block's thread, which adds it to both
//! particles directly. A pair (a, b) with b in a later block (a *crossing* pair) is computed
//! first, in batches as the blocks' own pairs are, in a pass shared evenly over all threads
//! (the crossing pairs all lie in the lower blocks), and kept; its block then adds it to a in a's row, and b's block adds it to b before
//! any of its own rows — where the order above puts it, since its row lies below b's block. One
//! block is the serial loop itself. With particles in a spatial order (`[particles] order =
//! "spatial"`) few pairs cross. Block t always runs on thread t (the `threads` module), so its
//! histories and accumulators stay in one core's cache from step to step.
//!
//! ## Where things are
//! This module is the stage's driver: its inputs and outputs, `serial` and `parallel`, and
//! the walk of one block (walls, arriving crossing pairs, own rows), all generic over the
//! law's normal and tangential sub-model types (`contact::submodel`). `plan` cuts the blocks
//! and lists the crossing pairs; `detect` is the contact test; `lanes` gathers the touching
//! pairs into batches, computes their loads and adds them. The law of one contact, which the
//! batches apply lane by lane, is in `contact::pair`.

mod detect;
mod lanes;
mod plan;
pub(crate) mod source;
mod sum;

use std::ops::Range;

use crate::boundary::Images;
pub(crate) use crate::contact::pair::CommonMass;
use crate::contact::pair::PairLoad;
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{CoeffTable, ContactLaw};
use crate::math::Vec3;
use crate::threads::split_at_ends;
use crate::wall::Wall;
use detect::{Cursor, FOUND, Found, find_contacts, find_wall_contacts};
use lanes::{LANES, Lanes};
pub(crate) use plan::ForcePlan;
pub use plan::{BLOCKS_PER_THREAD, MIN_PARALLEL_PARTICLES};
pub(crate) use sum::{Accumulators, Peak, Quanta, Quantum, max_peak, peak_floor};

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
    /// The mass every particle has, if all have the same, with the effective mass of two of
    /// them ([`CommonMass::of`]): the same for every pair, formed once per evaluation.
    pub common_mass: Option<CommonMass>,
    pub walls: &'a [Wall],
    pub coeffs: &'a CoeffTable,
    pub law: ContactLaw,
    /// The nearest-image rule of the periodic axes.
    pub images: Images,
    /// Δt for the tangential springs (0 when the history is not advanced).
    pub dt: f64,
    /// Store the advanced tangential springs.
    pub advance: bool,
    pub offsets: &'a [usize],
    pub partners: &'a [u32],
    pub wall_pairs: &'a [[u32; 2]],
    /// The quanta of the order-free sums ([`sum`]).
    pub quanta: Quanta,
}

/// Outputs of the force stage.
pub(crate) struct ForceOutputs<'a> {
    pub force: &'a mut [Vec3],
    pub torque: &'a mut [Vec3],
    /// The largest force and torque components of the loads ([`sum`]).
    pub peak: &'a mut Peak,
    pub pair_history: &'a mut [Vec3],
    /// Whether each pair touched at the last evaluation (in), touches now (out).
    pub in_contact: &'a mut [bool],
    pub wall_history: &'a mut [Vec3],
}

/// A crossing pair's load (rounded for the sums: [`sum`]), if in contact.
type CrossingLoad = Option<PairLoad>;

/// Evaluates every contact into `out` on one thread. With `clock`, returns the seconds spent on
/// the wall contacts (0 otherwise).
pub(crate) fn serial<N: NormalSubModel, T: TangentialSubModel>(
    x: &ForceInputs,
    out: ForceOutputs,
    clock: bool,
    scratch: &mut Scratch,
) -> f64 {
    let n = x.position.len();
    let (walls, peak) = block::<N, T>(
        scratch,
        clock,
        x,
        0..n,
        Accumulators { force: out.force, torque: out.torque, peak: [0.0; 2] },
        out.pair_history,
        out.in_contact,
        out.wall_history,
        0,
        Incoming::None,
        &[],
    );
    *out.peak = peak;
    walls
}

/// How long the threads worked in one parallel force evaluation (zero unless clocked).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct ThreadWork {
    /// Seconds the blocks spent on wall contacts, averaged over the blocks.
    pub walls: f64,
    /// Seconds each thread worked on its shares of the two passes, averaged over the threads.
    pub mean: f64,
    /// The same for the slowest thread of each pass, summed over the passes: the passes take
    /// at least this long, since each waits for its slowest thread.
    pub slowest: f64,
}

/// Evaluates every contact into `out` on the blocks of `plan`, in parallel on the current
/// rayon pool, block t on thread t (see [`crate::threads`]). Bit-identical to [`serial`]. With
/// `clock`, returns how long the threads worked (zero otherwise).
pub(crate) fn parallel<N: NormalSubModel, T: TangentialSubModel>(
    x: &ForceInputs,
    plan: &mut ForcePlan,
    out: ForceOutputs,
    clock: bool,
) -> ThreadWork {
    let since = |t0: Option<std::time::Instant>| t0.map_or(0.0, |t| t.elapsed().as_secs_f64());
    let blocks = &plan.blocks;
    let pair_ends = || blocks.iter().map(|r| x.offsets[r.end]);
    let slot_ends = || blocks.iter().map(|r| r.end);
    let wall_ends = &plan.wall_ends;

    // Pass 1: the crossing pairs, shared out evenly over the threads (they all lie in the rows
    // of the lower blocks). The list is in pair order, so each share's pairs lie in one stretch
    // of the histories, from the end of the previous share's stretch.
    let crossing_busy = {
        let crossing = &plan.crossing;
        let shares = rayon::current_num_threads().max(1);
        let cuts: crate::threads::Parts<usize> = (1..=shares).map(|t| crossing.len() * t / shares).collect();
        let stretch_end = |c: usize| crossing.get(c).map_or(x.partners.len(), |&(_, k)| k);
        let hist = split_at_ends(&mut *out.pair_history, cuts.iter().map(|&c| stretch_end(c)));
        let flags = split_at_ends(&mut *out.in_contact, cuts.iter().map(|&c| stretch_end(c)));
        let loads = split_at_ends(&mut plan.loads[..], cuts.iter().copied());
        let parts = hist.into_iter().zip(flags).zip(loads);
        crate::threads::pinned(parts, |t, ((hist, flags), loads)| {
            let t0 = clock.then(std::time::Instant::now);
            let c0 = if t == 0 { 0 } else { cuts[t - 1] };
            let k0 = if t == 0 { 0 } else { stretch_end(c0) };
            let mut lanes = Lanes::new();
            if let Some(c) = x.coeffs.uniform_pair() {
                lanes.input.fill_coeffs(c);
            }
            for (pairs, loads) in crossing[c0..cuts[t]].chunks(LANES).zip(loads.chunks_mut(LANES)) {
                lanes.crossing_loads::<N, T>(x, pairs, k0, hist, flags, loads);
            }
            (since(t0), lanes.peak())
        })
    };
    // Pass 2: each block's walls, arriving crossing pairs and own rows.
    let force = split_at_ends(&mut *out.force, slot_ends());
    let torque = split_at_ends(&mut *out.torque, slot_ends());
    let hist = split_at_ends(&mut *out.pair_history, pair_ends());
    let flags = split_at_ends(&mut *out.in_contact, pair_ends());
    let whist = split_at_ends(&mut *out.wall_history, wall_ends.iter().copied());
    let incoming =
        Incoming::Crossing { start: &plan.incoming_start, index: &plan.incoming, loads: &plan.loads };
    let crossing_start = &plan.crossing_start;
    let loads = &plan.loads;
    if plan.scratch.len() != blocks.len() {
        plan.scratch.resize_with(blocks.len(), Scratch::fresh);
    }
    let parts = force.into_iter().zip(torque).zip(hist).zip(flags).zip(whist).zip(plan.scratch.iter_mut());
    let block_times =
        crate::threads::pinned(parts, |t, (((((force, torque), hist), flags), whist), scratch)| {
            let rows = blocks[t].clone();
            let w0 = if t == 0 { 0 } else { wall_ends[t - 1] };
            let t0 = clock.then(std::time::Instant::now);
            let (walls, peak) = block::<N, T>(
                scratch,
                clock,
                x,
                rows,
                Accumulators { force, torque, peak: [0.0; 2] },
                hist,
                flags,
                whist,
                w0,
                incoming,
                &loads[crossing_start[t]..crossing_start[t + 1]],
            );
            (walls, since(t0), peak)
        });
    // The peaks are maxima: the same whichever thread found them.
    *out.peak =
        block_times.iter().map(|b| b.2).chain(crossing_busy.iter().map(|c| c.1)).fold([0.0; 2], max_peak);
    let walls = block_times.iter().map(|b| b.0).sum::<f64>() / block_times.len().max(1) as f64;
    let crossing = per_thread(crossing_busy.len(), |i| crossing_busy[i].0);
    let blocks = per_thread(block_times.len(), |i| block_times[i].1);
    ThreadWork { walls, mean: crossing.0 + blocks.0, slowest: crossing.1 + blocks.1 }
}

/// The mean and the largest over the threads of the current rayon pool of the seconds each
/// thread worked, from the seconds `part(i)` of each of `n` parts (part i runs on thread i mod
/// T: see [`crate::threads::pinned`]).
fn per_thread(n: usize, part: impl Fn(usize) -> f64) -> (f64, f64) {
    let threads = rayon::current_num_threads().clamp(1, n.max(1));
    let of = |t: usize| (t..n).step_by(threads).map(&part).sum::<f64>();
    let total: f64 = (0..n).map(&part).sum();
    (total / threads as f64, (0..threads).map(of).fold(0.0, f64::max))
}

/// The working memory of a block's force stage: the batch lanes and the lists of touching
/// pairs. Kept from one evaluation to the next where one block does all the work, so that a
/// small system's step does not spend its time clearing them.
pub(crate) struct Scratch {
    lanes: Lanes,
    found: [Found; FOUND],
    found_walls: [usize; FOUND],
}

impl Scratch {
    /// A cleared scratch.
    fn fresh() -> Scratch {
        Scratch { lanes: Lanes::new(), found: [Found::default(); FOUND], found_walls: [0; FOUND] }
    }

    /// A cleared scratch on the heap, to be kept.
    pub(crate) fn new() -> Box<Scratch> {
        Box::new(Scratch::fresh())
    }
}

/// A copy starts afresh: the scratch holds nothing between evaluations that is needed.
impl Clone for Scratch {
    fn clone(&self) -> Self {
        Scratch::fresh()
    }
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Scratch")
    }
}

/// Crossing pairs that arrive at a block from rows below it.
#[derive(Clone, Copy)]
enum Incoming<'a> {
    None,
    Crossing { start: &'a [u32], index: &'a [u32], loads: &'a [CrossingLoad] },
}

/// The force stage of the rows `rows`: `acc` holds those rows' accumulators,
/// `hist` and `in_contact` the histories and contact flags of their pairs, `whist` the
/// histories of their wall pairs (starting at wall pair `w0`), `own_crossing` the loads of
/// their crossing pairs in list order. Returns the seconds spent on the walls (with `clock`;
/// 0 otherwise) and the peaks of the loads.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn block<N: NormalSubModel, T: TangentialSubModel>(
    scratch: &mut Scratch,
    clock: bool,
    x: &ForceInputs,
    rows: Range<usize>,
    mut acc: Accumulators,
    hist: &mut [Vec3],
    in_contact: &mut [bool],
    whist: &mut [Vec3],
    w0: usize,
    incoming: Incoming,
    own_crossing: &[CrossingLoad],
) -> (f64, Peak) {
    let t0 = clock.then(std::time::Instant::now);
    let (r0, r1) = (rows.start, rows.end);
    acc.force.fill(Vec3::ZERO);
    acc.torque.fill(Vec3::ZERO);
    // Walls first, as MFIX does: the touching wall pairs listed, then their loads computed a
    // batch at a time and added in list order.
    let Scratch { lanes, found, found_walls } = scratch;
    lanes.clear_peaks();
    let wall_pairs = &x.wall_pairs[w0..w0 + whist.len()];
    let mut at = 0;
    while at < wall_pairs.len() {
        let n = find_wall_contacts::<N>(x, wall_pairs, &mut at, whist, found_walls);
        for group in found_walls[..n].chunks(LANES) {
            lanes.add_wall_loads::<N, T>(x, r0, wall_pairs, group, &mut acc, whist);
        }
    }
    let wall_seconds = t0.map_or(0.0, |t| t.elapsed().as_secs_f64());
    acc.note_peak(lanes.peak());
    // Then the crossing pairs from the rows below this block, in list order.
    if let Incoming::Crossing { start, index, loads } = incoming {
        for b in rows.clone() {
            for &c in &index[start[b] as usize..start[b + 1] as usize] {
                if let Some(l) = loads[c as usize] {
                    acc.add::<true>(b - r0, l.f, l.tb);
                }
            }
        }
    }
    // Then the rows, in order, a stretch at a time: first the contact test of the stretch's
    // pairs, which lists the touching ones; then their loads, computed a batch at a time and
    // added in list order.
    let mut cursor = Cursor { a: r0, k: x.offsets[r0] };
    let mut crossing = own_crossing.iter();
    if let Some(c) = x.coeffs.uniform_pair() {
        lanes.input.fill_coeffs(c);
    }
    while cursor.a < r1 {
        let n = find_contacts::<N>(x, r0..r1, [&*acc.force, &*acc.torque], &mut cursor, in_contact, found);
        for group in found[..n].chunks(LANES) {
            lanes.add_loads::<N, T>(x, r0..r1, group, &mut crossing, &mut acc, hist);
        }
    }
    acc.note_peak(lanes.peak());
    (wall_seconds, acc.peak)
}
