//! Broad phase: linked cells with a skin (a Verlet list), rebuilt when any particle has moved
//! more than half the skin since the last build.
//!
//! The list holds every particle pair closer than R_i + R_j + skin and every particle–wall pair
//! closer than R + skin, so between rebuilds no contact can be missed. Each entry carries the
//! contact's tangential history; on a rebuild, entries in contact that persist keep it
//! (matched by the slots of the two particles, or the slot and the wall index), new entries
//! start from zero. When the simulation moves particles to other slots (a re-sort, an
//! insertion or removal), it takes the list's state by particle ids and puts it back under the
//! new slots ([`NeighborList::state`], [`NeighborList::set_state`]), so no history is lost.
//!
//! Each pair also carries a flag: whether it touched at the last force evaluation. A pair's
//! stored history counts only while the flag is set (it is zero otherwise), so the contact test
//! of each step writes one byte per pair instead of clearing the 24-byte history of every pair
//! that does not touch — in a flowing bed most of them.

use crate::boundary::{Images, Periodic};
use crate::math::Vec3;
use crate::state::Particles;
use crate::wall::Wall;
use std::ops::Range;

/// Counters of the neighbour search.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NeighborStats {
    /// Number of builds so far.
    pub builds: u64,
    /// Distance tests made in the last build (O(N) for a bounded density).
    pub distance_checks: u64,
}

/// The Verlet list with its contact histories.
///
/// Pairs are stored as a half list in compressed rows: the partners of slot `a` are the slots
/// `b > a` in `partners[offsets[a]..offsets[a + 1]]`, ascending. Pair `k` (its place in that
/// order) carries its tangential history in `pair_history[k]`, seen from the lower slot `a`,
/// valid while `in_contact[k]` is set (zero otherwise), or, for a law that keeps the history of
/// a pair that came apart (LIGGGHTS's), while it is not zero. This is the order the force loop
/// walks memory in and sums forces in.
#[derive(Debug, Clone, Default)]
pub struct NeighborList {
    skin: f64,
    offsets: Vec<usize>,
    partners: Vec<u32>,
    pair_history: Vec<Vec3>,
    /// Whether each pair touched at the last force evaluation.
    in_contact: Vec<bool>,
    /// Whether a pair that came apart keeps its history (until it touches again) rather than
    /// losing it: through rebuilds, checkpoints and moves between ranks too.
    keep_apart: bool,
    /// Candidate particle–wall pairs (slot, wall index), ordered by slots.
    wall_pairs: Vec<[u32; 2]>,
    wall_history: Vec<Vec3>,
    reference: Vec<Vec3>,
    built: bool,
    stats: NeighborStats,
    /// Periodic axes of the domain (distances by nearest image).
    periodic: Periodic,
    /// Groups of slots whose pairs with each other are left out, one bit a group (particles
    /// that never move: 1; ghosts: 2): a pair is left out when its slots share a bit.
    excluded: Vec<u8>,
    /// The first slot of the ghosts (copies of other ranks' particles), which have no wall
    /// candidates; `None` in one process.
    ghosts_from: Option<usize>,
    // scratch, reused between builds
    cell_count: Vec<u32>,
    cell_of: Vec<u32>,
    sorted: Vec<u32>,
    fresh: Vec<u64>,
}

/// Everything of a [`NeighborList`] that a checkpoint must carry.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NeighborState {
    /// Skin, m.
    pub skin: f64,
    /// Whether the list was built.
    pub built: bool,
    /// Candidate pairs (slots a < b), in list order.
    pub pairs: Vec<[u32; 2]>,
    /// Their tangential histories, seen from slot a.
    pub pair_history: Vec<Vec3>,
    /// Candidate particle–wall pairs (slot, wall).
    pub wall_pairs: Vec<[u32; 2]>,
    /// Their tangential histories.
    pub wall_history: Vec<Vec3>,
    /// Positions at the last build.
    pub reference: Vec<Vec3>,
}

/// The most pairs a list holds: the force stage lists a pair by its index in 31 bits. (At 37
/// bytes a pair — partner, history, contact flag, sort key — a list that long takes 80 GB.)
pub(crate) const MAX_PAIRS: usize = (1 << 31) - 1;

/// Rows whose persisting contacts a rebuild on one thread finds at a time.
const SERIAL_MERGE_ROWS: usize = 4096;

/// On threads, the pairs a thread has found are added to the list's keys once it holds this
/// many (512 KiB).
const HAND_OVER_KEYS: usize = 1 << 16;

/// The sort key of the pair of slots a < b (or of a slot and a wall index).
#[inline]
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    ((a as u64) << 32) | b as u64
}

/// The row offsets (`n` + 1 entries) of the pairs with the given sorted keys.
fn row_offsets(keys: impl Iterator<Item = u64>, n: usize, offsets: &mut Vec<usize>) {
    offsets.clear();
    offsets.resize(n + 1, 0);
    for key in keys {
        offsets[(key >> 32) as usize + 1] += 1;
    }
    for a in 0..n {
        offsets[a + 1] += offsets[a];
    }
}

impl NeighborList {
    /// An empty list with the given skin (m).
    pub fn new(skin: f64) -> Self {
        NeighborList { skin, ..Default::default() }
    }

    /// An empty list with the given skin (m) for a domain with periodic axes.
    pub fn with_periodic(skin: f64, periodic: Periodic) -> Self {
        NeighborList { skin, periodic, ..Default::default() }
    }

    /// Keeps the history of a pair that came apart, as a law whose history outlives the
    /// contact needs ([`HistoryFrame::kept_apart`](crate::contact::HistoryFrame::kept_apart)).
    pub fn keep_histories_apart(&mut self, keep: bool) {
        self.keep_apart = keep;
    }

    /// Whether pair `k` carries its history: it touched at the last force evaluation, or its
    /// law keeps the history of a pair apart and it has one.
    #[inline]
    fn carries(&self, k: usize) -> bool {
        self.in_contact[k] || (self.keep_apart && nonzero(self.pair_history[k]))
    }

    /// Leaves out the pairs of particles that are both marked (e.g. particles held fixed:
    /// their mutual forces act on nothing that moves). Takes effect at the next build.
    pub fn exclude_pairs_among(&mut self, marked: Vec<bool>) {
        self.excluded =
            if marked.iter().any(|&m| m) { marked.iter().map(|&m| m as u8).collect() } else { Vec::new() };
        self.built = false;
    }

    /// Replaces the marks of [`exclude_pairs_among`](Self::exclude_pairs_among) by groups of
    /// slots, one bit a group (pairs sharing a bit are left out): the same marks under new
    /// slots, or with a rank's ghosts as a second group.
    pub(crate) fn remap_excluded(&mut self, groups: Vec<u8>) {
        self.excluded = if groups.iter().any(|&m| m != 0) { groups } else { Vec::new() };
    }

    /// How far apart in memory the two particles of a pair lie, on average over the list's
    /// pairs (slots): a bed whose order has decayed since it was sorted shows it here.
    pub fn mean_slot_gap(&self) -> f64 {
        let n = self.partners.len();
        if n == 0 {
            return 0.0;
        }
        let total: u64 = self
            .offsets
            .windows(2)
            .enumerate()
            .map(|(a, w)| self.partners[w[0]..w[1]].iter().map(|&b| b as u64 - a as u64).sum::<u64>())
            .sum();
        total as f64 / n as f64
    }

    /// The skin distance, m.
    pub fn skin(&self) -> f64 {
        self.skin
    }

    /// Marks the slots from `from` on as ghosts: they get no wall candidates (their walls are
    /// their own rank's). Takes effect at the next build.
    pub(crate) fn set_ghosts_from(&mut self, from: Option<usize>) {
        self.ghosts_from = from;
    }

    /// True when one of the first `positions.len()` slots moved more than half the skin since
    /// the last build (or the list was never built): a rank's part of the rebuild decision.
    pub(crate) fn any_moved(&self, positions: &[Vec3]) -> bool {
        !self.built || positions.len() > self.reference.len() || {
            let blocks: [Range<usize>; 0] = [];
            let refs = &self.reference[..positions.len()];
            self.moved(positions, refs, &blocks)
        }
    }

    /// The state a checkpoint carries.
    pub fn state(&self) -> NeighborState {
        NeighborState {
            skin: self.skin,
            built: self.built,
            pairs: self.pairs().collect(),
            pair_history: self.pair_history(),
            wall_pairs: self.wall_pairs.clone(),
            wall_history: self.wall_history.clone(),
            reference: self.reference.clone(),
        }
    }

    /// Restores a checkpointed state; `n` particles and `n_walls` walls must fit it. Pairs
    /// stored the other way round (b < a) are turned, with their history negated (the history
    /// seen from the other particle); the list is put in its order.
    pub fn set_state(&mut self, s: NeighborState, n: usize, n_walls: usize) -> Result<(), String> {
        let lens_ok = s.pairs.len() == s.pair_history.len()
            && s.wall_pairs.len() == s.wall_history.len()
            && (s.reference.len() == n || !s.built);
        let in_range = s.pairs.iter().all(|&[a, b]| (a as usize) < n && (b as usize) < n && a != b)
            && s.wall_pairs.iter().all(|&[i, w]| (i as usize) < n && (w as usize) < n_walls);
        if !(lens_ok && in_range) {
            return Err("the neighbour list does not fit the particles and walls of the case".into());
        }
        if s.pairs.len() > MAX_PAIRS {
            return Err(format!(
                "the neighbour list holds {} pairs; at most {MAX_PAIRS} are supported",
                s.pairs.len()
            ));
        }
        let mut walls: Vec<(u64, Vec3)> =
            s.wall_pairs.iter().zip(&s.wall_history).map(|(&[i, w], &h)| (pair_key(i, w), h)).collect();
        walls.sort_unstable_by_key(|e| e.0);
        let twice = || Err("the neighbour list holds a pair twice".to_string());
        if walls.windows(2).any(|w| w[0].0 == w[1].0) {
            return twice();
        }
        // A checkpoint lists the pairs in list order: taken as they are, the histories moved
        // rather than copied (a large bed's list is the largest part of its state).
        let keys = || s.pairs.iter().map(|&[a, b]| pair_key(a, b));
        let in_order = s.pairs.iter().all(|&[a, b]| a < b) && keys().zip(keys().skip(1)).all(|(k, l)| k < l);
        if in_order {
            row_offsets(keys(), n, &mut self.offsets);
            self.partners = s.pairs.iter().map(|&[_, b]| b).collect();
            drop(s.pairs);
            // A zero history is the same as no contact (bit for bit: a negative zero is kept).
            self.in_contact = s.pair_history.iter().map(|&h| nonzero(h)).collect();
            self.pair_history = s.pair_history;
        } else {
            let mut pairs: Vec<(u64, Vec3)> = s
                .pairs
                .iter()
                .zip(&s.pair_history)
                .map(|(&[a, b], &h)| if a < b { (pair_key(a, b), h) } else { (pair_key(b, a), -h) })
                .collect();
            pairs.sort_unstable_by_key(|e| e.0);
            if pairs.windows(2).any(|w| w[0].0 == w[1].0) {
                return twice();
            }
            row_offsets(pairs.iter().map(|e| e.0), n, &mut self.offsets);
            self.partners = pairs.iter().map(|e| e.0 as u32).collect();
            self.pair_history = pairs.iter().map(|e| e.1).collect();
            self.in_contact = pairs.iter().map(|e| nonzero(e.1)).collect();
        }
        self.skin = s.skin;
        self.built = s.built;
        self.wall_pairs = walls.iter().map(|e| [(e.0 >> 32) as u32, e.0 as u32]).collect();
        self.wall_history = walls.iter().map(|e| e.1).collect();
        self.reference = s.reference;
        Ok(())
    }

    /// Whether the list has been built.
    pub fn is_built(&self) -> bool {
        self.built
    }

    /// Positions at the last build.
    pub fn reference(&self) -> &[Vec3] {
        &self.reference
    }

    /// Number of particle pairs in the list.
    pub fn pair_count(&self) -> usize {
        self.partners.len()
    }

    /// Every pair (a, b) of slots, a < b, in list order (pair k is the k-th).
    pub fn pairs(&self) -> impl Iterator<Item = [u32; 2]> + '_ {
        self.offsets
            .windows(2)
            .enumerate()
            .flat_map(move |(a, w)| self.partners[w[0]..w[1]].iter().map(move |&b| [a as u32, b]))
    }

    /// Row offsets: the pairs of slot a are `offsets()[a]..offsets()[a + 1]` (n + 1 entries,
    /// or none before the first build).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// The partner slot b of each pair, in list order.
    pub fn partners(&self) -> &[u32] {
        &self.partners
    }

    /// Tangential history of each pair, seen from the lower slot, in list order (zero for the
    /// pairs not in contact at the last force evaluation, unless the law keeps it apart).
    pub fn pair_history(&self) -> Vec<Vec3> {
        self.pair_histories().collect()
    }

    /// [`pair_history`](Self::pair_history) without a copy.
    pub fn pair_histories(&self) -> impl ExactSizeIterator<Item = Vec3> + '_ {
        (0..self.pair_history.len()).map(|k| if self.carries(k) { self.pair_history[k] } else { Vec3::ZERO })
    }

    /// The pairs whose history is not zero, as (slots a < b, the history seen from a), in
    /// list order.
    /// This list's settings and counts without its pairs, histories or scratch (not built).
    pub(crate) fn emptied(&self) -> NeighborList {
        NeighborList {
            skin: self.skin,
            stats: self.stats,
            periodic: self.periodic,
            ghosts_from: self.ghosts_from,
            keep_apart: self.keep_apart,
            ..Default::default()
        }
    }

    /// Calls `f` with each pair that carries a non-zero history (in contact, or apart under a
    /// law that keeps it) of which `wanted` holds for
    /// either slot, by slots, in list order (the slots are tested before the history is read).
    pub(crate) fn for_pairs_with_history(
        &self,
        wanted: impl Fn(usize) -> bool,
        mut f: impl FnMut([u32; 2], Vec3),
    ) {
        for a in 0..self.offsets.len().saturating_sub(1) {
            let (start, end, a_wanted) = (self.offsets[a], self.offsets[a + 1], wanted(a));
            for k in start..end {
                let b = self.partners[k];
                if (a_wanted || wanted(b as usize)) && self.carries(k) && nonzero(self.pair_history[k]) {
                    f([a as u32, b], self.pair_history[k]);
                }
            }
        }
    }

    /// The pairs that carry a non-zero history, by slots, in list order.
    pub(crate) fn each_pair_with_history(&self) -> impl Iterator<Item = ([u32; 2], Vec3)> + '_ {
        self.offsets.windows(2).enumerate().flat_map(move |(a, w)| {
            (w[0]..w[1]).filter_map(move |k| {
                let h = self.pair_history[k];
                (self.carries(k) && nonzero(h)).then(|| ([a as u32, self.partners[k]], h))
            })
        })
    }

    /// Number of pairs that touched at the last force evaluation (or carry a history).
    pub fn pair_contact_count(&self) -> usize {
        self.in_contact.iter().filter(|&&c| c).count()
    }

    /// Sets the tangential history of pair `k` (for tests and hooks that set a contact's
    /// state).
    pub fn set_pair_history(&mut self, k: usize, h: Vec3) {
        self.pair_history[k] = h;
        self.in_contact[k] = nonzero(h);
    }

    /// Candidate particle–wall pairs (slot, wall index), ordered by slots.
    pub fn wall_pairs(&self) -> &[[u32; 2]] {
        &self.wall_pairs
    }

    /// Tangential history of each particle–wall pair.
    pub fn wall_history(&self) -> &[Vec3] {
        &self.wall_history
    }

    /// Mutable wall histories.
    pub fn wall_history_mut(&mut self) -> &mut [Vec3] {
        &mut self.wall_history
    }

    /// The parts the force loop needs at once: (offsets, partners, pair histories, pairs'
    /// contact flags, wall pairs, wall histories).
    #[allow(clippy::type_complexity)]
    pub(crate) fn split_mut(
        &mut self,
    ) -> (&[usize], &[u32], &mut [Vec3], &mut [bool], &[[u32; 2]], &mut [Vec3]) {
        (
            &self.offsets,
            &self.partners,
            &mut self.pair_history,
            &mut self.in_contact,
            &self.wall_pairs,
            &mut self.wall_history,
        )
    }

    /// Heap bytes held by the list and its scratch space.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.offsets.capacity() * size_of::<usize>()
            + self.partners.capacity() * 4
            + self.in_contact.capacity()
            + (self.pair_history.capacity() + self.wall_history.capacity() + self.reference.capacity())
                * size_of::<Vec3>()
            + self.wall_pairs.capacity() * 8
            + self.excluded.capacity()
            + (self.cell_count.capacity() + self.cell_of.capacity() + self.sorted.capacity()) * 4
            + self.fresh.capacity() * 8
    }

    /// Counters of the search.
    pub fn stats(&self) -> NeighborStats {
        self.stats
    }

    /// True when the list was never built or a particle moved more than half the skin. With two
    /// or more `blocks` (consecutive ranges of slots from slot 0 to the last particle), the
    /// slots of block i are checked on thread i of the current rayon pool.
    pub fn needs_rebuild(&self, positions: &[Vec3], blocks: &[Range<usize>]) -> bool {
        if !self.built || positions.len() != self.reference.len() {
            return true;
        }
        self.moved(positions, &self.reference, blocks)
    }

    /// Whether a particle of `positions` moved more than half the skin from `refs`; with two or
    /// more `blocks`, on the current rayon pool.
    fn moved(&self, positions: &[Vec3], refs: &[Vec3], blocks: &[Range<usize>]) -> bool {
        let lim = 0.25 * self.skin * self.skin;
        // Per axis, the distance to the nearest image: min(|d|, L − |d|) on a periodic axis
        // (positions lie in the box, so |d| < L), |d| on the others (L = ∞).
        let l = self.periodic.lengths().to_array();
        let axes = self.periodic.axes;
        let period = Vec3::from_array(std::array::from_fn(|k| if axes[k] { l[k] } else { f64::INFINITY }));
        // The particles that moved too far (or whose position is not a number) are counted,
        // not searched for: without an early exit the loop has no branch and runs as vector
        // code.
        let moved = |xs: &[Vec3], refs: &[Vec3]| {
            xs.iter()
                .zip(refs)
                .map(|(x, r)| {
                    let a = (*x - *r).abs();
                    let d2 = a.min(period - a).length_squared();
                    (d2 > lim) as usize | d2.is_nan() as usize
                })
                .sum::<usize>()
                > 0
        };
        if blocks.len() < 2 {
            moved(positions, refs)
        } else {
            crate::threads::pinned(blocks, |_, b| moved(&positions[b.clone()], &refs[b.clone()]))
                .contains(&true)
        }
    }

    /// Rebuilds the list if [`needs_rebuild`](Self::needs_rebuild) says so; with two or more
    /// `blocks`, checks and rebuilds on the current rayon pool.
    pub fn update(&mut self, particles: &Particles, walls: &[Wall], blocks: &[Range<usize>]) {
        if self.needs_rebuild(&particles.position, blocks) {
            self.build_on(particles, walls, blocks.len() > 1);
        }
    }

    /// Rebuilds the list now, keeping the history of persisting entries.
    pub fn build(&mut self, p: &Particles, walls: &[Wall]) {
        self.build_on(p, walls, false);
    }

    /// [`build`](Self::build); with `parallel`, the pairs are found and sorted on the current
    /// rayon pool (the list is the same).
    pub(crate) fn build_on(&mut self, p: &Particles, walls: &[Wall], parallel: bool) {
        self.stats.builds += 1;
        self.stats.distance_checks = 0;
        self.reference.clear();
        self.reference.extend_from_slice(&p.position);
        self.built = true;
        self.build_pairs(p, parallel);
        self.build_walls(p, walls, parallel);
    }

    fn build_pairs(&mut self, p: &Particles, parallel: bool) {
        let n = p.len();
        self.fresh.clear();
        self.fresh.reserve(self.partners.len() + self.partners.len() / 8);
        if n >= 2 {
            let skin = self.skin;
            let per = self.periodic;
            let (mut lo, mut hi) = (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY));
            for x in &p.position {
                if x.is_finite() {
                    let x = per.wrap(*x);
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
            if !lo.is_finite() {
                lo = Vec3::ZERO;
                hi = Vec3::ZERO;
            }
            // Periodic axes are binned over the whole box, in whole cells that tile it.
            let (mut lo_a, mut hi_a) = (lo.to_array(), hi.to_array());
            for k in 0..3 {
                if per.axes[k] {
                    lo_a[k] = per.lo.to_array()[k];
                    hi_a[k] = per.hi.to_array()[k];
                }
            }
            let (lo, extent) = (Vec3::from_array(lo_a), Vec3::from_array(hi_a) - Vec3::from_array(lo_a));
            // A hair above the largest cut-off, so that rounding in the cell index of a point
            // on a cell boundary can never put two particles closer than the cut-off into
            // non-adjacent cells.
            let mut cell = (2.0 * p.max_radius() + skin) * (1.0 + 1e-6);
            let max_cells = (8 * n).max(1024) as f64;
            let count = |c: f64| -> [f64; 3] {
                let e = extent.to_array();
                std::array::from_fn(|k| {
                    if per.axes[k] {
                        // At least 3 cells (the set-up guarantees L ≥ 3 cut-offs).
                        (e[k] / c).floor().max(3.0)
                    } else {
                        (e[k] / c).floor() + 1.0
                    }
                })
            };
            let mut dims = count(cell);
            if dims.iter().product::<f64>() > max_cells {
                cell *= (dims.iter().product::<f64>() / max_cells).cbrt();
                dims = count(cell);
                while dims.iter().product::<f64>() > max_cells {
                    cell *= 1.25;
                    dims = count(cell);
                }
            }
            let [nx, ny, nz] = dims.map(|d| d as usize);
            let n_cells = nx * ny * nz;
            // Cell side per axis: the box divided evenly on periodic axes.
            let e = extent.to_array();
            let inv: [f64; 3] =
                std::array::from_fn(|k| if per.axes[k] { dims[k] / e[k] } else { 1.0 / cell });
            let lo_a = lo.to_array();
            let coord = |x: f64, k: usize, m: usize| (((x - lo_a[k]) * inv[k]) as usize).min(m - 1);
            // Counting sort of the particles by cell.
            self.cell_count.clear();
            self.cell_count.resize(n_cells + 1, 0);
            self.cell_of.clear();
            for x in &p.position {
                let x = per.wrap(*x);
                let c = coord(x.x, 0, nx) + nx * (coord(x.y, 1, ny) + ny * coord(x.z, 2, nz));
                self.cell_of.push(c as u32);
                self.cell_count[c + 1] += 1;
            }
            for c in 0..n_cells {
                self.cell_count[c + 1] += self.cell_count[c];
            }
            self.sorted.clear();
            self.sorted.resize(n, 0);
            {
                let mut fill = self.cell_count.clone();
                for (i, &c) in self.cell_of.iter().enumerate() {
                    self.sorted[fill[c as usize] as usize] = i as u32;
                    fill[c as usize] += 1;
                }
            }
            let start = &self.cell_count;
            let sorted = &self.sorted;
            let search = PairSearch {
                position: &p.position,
                radius: &p.radius,
                excluded: &self.excluded,
                skin,
                images: per.images(),
            };
            let wrap_axis = |o: i64, m: usize, k: usize| -> Option<usize> {
                if o >= 0 && o < m as i64 {
                    Some(o as usize)
                } else if per.axes[k] {
                    Some(o.rem_euclid(m as i64) as usize)
                } else {
                    None
                }
            };
            let cell = |ox: usize, oy: usize, oz: usize| {
                let c = ox + nx * (oy + ny * oz);
                &sorted[start[c] as usize..start[c + 1] as usize]
            };
            // The slots of the cells cx − 1 ..= cx + 1 of row (cy, cz) (cy, cz possibly out of
            // range: no cells then), as up to three slices of `sorted`. Cells next to each other
            // along x are next to each other in `sorted`, so the row is one slice unless it
            // wraps around a periodic x axis or is cut by the box's edge.
            let row_of_three = |cx: usize, cy: i64, cz: i64| -> [&[u32]; 3] {
                let (Some(oy), Some(oz)) = (wrap_axis(cy, ny, 1), wrap_axis(cz, nz, 2)) else {
                    return [&[]; 3];
                };
                if cx >= 1 && cx + 1 < nx {
                    let row = nx * (oy + ny * oz);
                    return [&sorted[start[row + cx - 1] as usize..start[row + cx + 2] as usize], &[], &[]];
                }
                [-1, 0, 1].map(|dx| wrap_axis(cx as i64 + dx, nx, 0).map_or(&[][..], |ox| cell(ox, oy, oz)))
            };
            // The pairs of the cells of layer cz with their half shells (the cell itself, the
            // next cell along x, the row of three at y + 1 and the three rows of three at z + 1),
            // into `out`; returns the distance tests made.
            let layer = |cz: usize, out: &mut Keys| -> u64 {
                let mut checks = 0u64;
                for cy in 0..ny {
                    for cx in 0..nx {
                        let own = cell(cx, cy, cz);
                        if own.is_empty() {
                            continue;
                        }
                        // The partners in the cell itself and in the next one along x: one
                        // slice of `sorted`, the rest of the cell's and the next cell's slots,
                        // unless the box ends there or x wraps around.
                        if cx + 1 < nx {
                            let c = cx + nx * (cy + ny * cz);
                            let (s0, s2) = (start[c] as usize, start[c + 2] as usize);
                            for (k, &i) in own.iter().enumerate() {
                                search.row(i, &sorted[s0 + k + 1..s2], out);
                                checks += (s2 - s0 - k - 1) as u64;
                            }
                        } else {
                            let next = wrap_axis(nx as i64, nx, 0).map_or(&[][..], |ox| cell(ox, cy, cz));
                            for (k, &i) in own.iter().enumerate() {
                                search.row(i, &own[k + 1..], out);
                                search.row(i, next, out);
                                checks += (own.len() - k - 1 + next.len()) as u64;
                            }
                        }
                        let (y, z) = (cy as i64, cz as i64);
                        for (dy, dz) in [(1, 0), (-1, 1), (0, 1), (1, 1)] {
                            for other in
                                row_of_three(cx, y + dy, z + dz).into_iter().filter(|o| !o.is_empty())
                            {
                                for &i in own {
                                    search.row(i, other, out);
                                }
                                checks += (own.len() * other.len()) as u64;
                            }
                        }
                    }
                }
                checks
            };
            if parallel {
                // The keys go into the list in any order (it is sorted below): each thread
                // hands its pairs over a bufferful at a time, so that the pairs found but not
                // yet handed over stay a small part of the list (collecting every layer's
                // pairs first would hold a second copy of its keys).
                let keys = std::sync::Mutex::new(std::mem::take(&mut self.fresh));
                let hand_over = |buf: &mut Keys| {
                    keys.lock().unwrap_or_else(|e| e.into_inner()).extend_from_slice(buf.found());
                    buf.used = 0;
                };
                self.stats.distance_checks += crate::threads::in_runs(nz, |layers| {
                    let mut buf = Keys::default();
                    let mut checks = 0u64;
                    for cz in layers {
                        checks += layer(cz, &mut buf);
                        if buf.used >= HAND_OVER_KEYS {
                            hand_over(&mut buf);
                        }
                    }
                    hand_over(&mut buf);
                    checks
                })
                .into_iter()
                .sum::<u64>();
                self.fresh = keys.into_inner().unwrap_or_else(|e| e.into_inner());
            } else {
                let mut buf = Keys { keys: std::mem::take(&mut self.fresh), used: 0 };
                for cz in 0..nz {
                    self.stats.distance_checks += layer(cz, &mut buf);
                }
                buf.keys.truncate(buf.used);
                self.fresh = buf.keys;
            }
        }
        // The keys are distinct: any sort gives the same list. Within a team of threads
        // (`threads::team`) the pool's other threads wait in the team's loop, not rayon's, so
        // rayon's parallel sort would run on this thread alone: the plain sort is used.
        if parallel && !crate::threads::on_team() {
            use rayon::prelude::*;
            self.fresh.par_sort_unstable();
        } else {
            self.fresh.sort_unstable();
        }
        self.renew_pairs(p, parallel);
    }

    /// Replaces the pairs by the sorted `fresh` keys: each takes the history of the same pair
    /// in the old list if that was in contact (both are in (a, b) order, so one merge pass
    /// finds it), zero if new. Under a law that keeps histories apart, a pair takes its
    /// history if it carries one and its spheres overlap at `p`'s positions, as LIGGGHTS's
    /// rebuild does.
    ///
    /// Done in place, so that a rebuild needs no second copy of the histories: the histories
    /// of persisting contacts are first packed to the front of the buffer (in order), then
    /// spread backwards to their new places (a packed entry never lies behind its new place).
    /// With `parallel`, the persisting pairs are found on the current rayon pool.
    fn renew_pairs(&mut self, p: &Particles, parallel: bool) {
        let n = p.len();
        let overlap = Overlap { position: &p.position, radius: &p.radius, periodic: self.periodic };
        assert!(
            self.fresh.len() <= MAX_PAIRS,
            "{} particle pairs within the neighbour cut-off: at most {MAX_PAIRS} are supported",
            self.fresh.len()
        );
        let mut persists = vec![0u64; self.fresh.len().div_ceil(64)];
        // Of those, the pairs that touched (a pair apart may carry its history).
        let mut touched = vec![0u64; self.fresh.len().div_ceil(64)];
        let mut kept = 0usize;
        // The persisting pairs, found a run of rows at a time (a pair's old entry lies in its
        // row) as (fresh index, old index) in list order, then their histories packed in that
        // order: on the current rayon pool all runs at once, else one after the other (so that
        // only one run's list is held).
        let mut pack = |found: Vec<(u32, u32)>, hist: &mut Vec<Vec3>, in_contact: &[bool]| {
            for (f, k) in found {
                hist[kept] = hist[k as usize];
                kept += 1;
                persists[f as usize / 64] |= 1 << (f % 64);
                touched[f as usize / 64] |= (in_contact[k as usize] as u64) << (f % 64);
            }
        };
        let mut history = std::mem::take(&mut self.pair_history);
        if parallel && n > 0 {
            let found = crate::threads::in_runs(n, |rows| self.persisting_in(rows, &history, &overlap));
            found.into_iter().for_each(|f| pack(f, &mut history, &self.in_contact));
        } else {
            for a in (0..n).step_by(SERIAL_MERGE_ROWS) {
                let rows = a..(a + SERIAL_MERGE_ROWS).min(n);
                let f = self.persisting_in(rows, &history, &overlap);
                pack(f, &mut history, &self.in_contact);
            }
        }
        self.pair_history = history;
        let len = self.fresh.len();
        // Exact growth: an amortised doubling would leave up to twice the history allocated.
        self.pair_history.reserve_exact(len.saturating_sub(self.pair_history.len()));
        self.pair_history.resize(len, Vec3::ZERO);
        self.in_contact.clear();
        self.in_contact.reserve_exact(len);
        self.in_contact.resize(len, false);
        let mut src = kept;
        for f in (0..len).rev() {
            let persisting = persists[f / 64] >> (f % 64) & 1 == 1;
            self.pair_history[f] = if persisting {
                src -= 1;
                self.pair_history[src]
            } else {
                Vec3::ZERO
            };
            self.in_contact[f] = touched[f / 64] >> (f % 64) & 1 == 1;
        }
        row_offsets(self.fresh.iter().copied(), n, &mut self.offsets);
        self.partners.clear();
        self.partners.reserve_exact(len);
        self.partners.extend(self.fresh.iter().map(|&key| key as u32));
        // Kept for the next build, which finds about as many pairs. Freed and allocated again
        // at every build, they made the peak memory grow with the rebuilds (the allocator
        // kept what they left behind): the 1 000 000-particle bed peaked at 318 MiB after its
        // first steps and at 365 MiB after five rebuilds; 338 MiB with the keys kept.
        self.fresh.clear();
    }

    /// The fresh pairs of rows `rows` whose history in the old list (`history`, taken out of
    /// it while the histories are packed) goes on, as (index in `fresh`,
    /// index in the old list), in list order: those in contact; under a law that keeps
    /// histories apart, those that carry one and overlap now.
    fn persisting_in(&self, rows: Range<usize>, history: &[Vec3], overlap: &Overlap) -> Vec<(u32, u32)> {
        let fresh = &self.fresh;
        let n_old = self.offsets.len().saturating_sub(1);
        let f0 = fresh.partition_point(|&key| key < pair_key(rows.start as u32, 0));
        let f1 = fresh.partition_point(|&key| key < pair_key(rows.end as u32, 0));
        let (k1, mut a_old) =
            (self.offsets.get(rows.end.min(n_old)).copied().unwrap_or(0), rows.start.min(n_old));
        let mut k = self.offsets.get(a_old).copied().unwrap_or(0);
        let mut out = Vec::new();
        for (f, &key) in fresh.iter().enumerate().take(f1).skip(f0) {
            while k < k1 {
                while self.offsets[a_old + 1] <= k {
                    a_old += 1;
                }
                let old_key = pair_key(a_old as u32, self.partners[k]);
                if old_key < key {
                    k += 1;
                    continue;
                }
                if old_key == key {
                    let goes_on = if self.keep_apart {
                        (self.in_contact[k] || nonzero(history[k]))
                            && overlap.of(a_old, self.partners[k] as usize)
                    } else {
                        self.in_contact[k]
                    };
                    if goes_on {
                        out.push((f as u32, k as u32));
                    }
                    k += 1;
                }
                break;
            }
        }
        out
    }

    /// The wall pairs found afresh, each with the history of the same pair in the old list
    /// (zero if new); with `parallel`, runs of slots are searched on the current rayon pool and
    /// joined in slot order (the list is the same).
    fn build_walls(&mut self, p: &Particles, walls: &[Wall], parallel: bool) {
        let n = self.ghosts_from.unwrap_or(p.len()).min(p.len());
        self.stats.distance_checks += (n * walls.len()) as u64;
        let (old, old_history, skin) = (&self.wall_pairs, &self.wall_history, self.skin);
        let find = |slots: Range<usize>| {
            let mut fresh = Vec::new();
            for i in slots {
                for (w, wall) in walls.iter().enumerate() {
                    if wall.distance(p.position[i]) < p.radius[i] + skin {
                        fresh.push([i as u32, w as u32]);
                    }
                }
            }
            // Both lists are in (slot, wall) order: one merge pass carries the histories over.
            let mut history = Vec::with_capacity(fresh.len());
            let mut k = fresh.first().map_or(0, |first| old.partition_point(|q| q < first));
            for pair in &fresh {
                while k < old.len() && old[k] < *pair {
                    k += 1;
                }
                let same = k < old.len() && old[k] == *pair;
                history.push(if same { old_history[k] } else { Vec3::ZERO });
            }
            (fresh, history)
        };
        let (fresh, history) = if parallel && !walls.is_empty() {
            let found = crate::threads::in_runs(n, find);
            let mut fresh = Vec::with_capacity(found.iter().map(|f| f.0.len()).sum());
            let mut history = Vec::with_capacity(fresh.capacity());
            for (f, h) in found {
                fresh.extend_from_slice(&f);
                history.extend_from_slice(&h);
            }
            (fresh, history)
        } else {
            find(0..n)
        };
        self.wall_pairs = fresh;
        self.wall_history = history;
    }
}

/// Keys of pairs found, written into `keys[..used]`; `keys` beyond that is room already
/// filled, so that a key can be written before it is known whether it is kept.
#[derive(Default)]
struct Keys {
    keys: Vec<u64>,
    used: usize,
}

impl Keys {
    /// The keys found.
    fn found(&self) -> &[u64] {
        &self.keys[..self.used]
    }

    /// Room for `m` more keys after the ones found. The buffer grows by what is missing (plus
    /// a little), within the capacity reserved for it where that suffices.
    #[inline(always)]
    fn room(&mut self, m: usize) -> &mut [u64] {
        if self.keys.len() < self.used + m {
            self.keys.resize(self.used + m + 256, 0);
        }
        &mut self.keys[self.used..self.used + m]
    }
}

/// What the pair search reads: the particles, the cut-off's skin, the nearest-image rule and
/// the slots whose pairs with each other are left out (empty if none).
struct PairSearch<'a> {
    position: &'a [Vec3],
    radius: &'a [f64],
    excluded: &'a [u8],
    skin: f64,
    images: Images,
}

impl PairSearch<'_> {
    /// Appends to `out` the key of every pair (i, j), j in `others`, closer than
    /// R_i + R_j + skin (and not left out). Without a branch on the outcome, which no predictor
    /// could guess: each key is written into the next place, which only a pair within the
    /// cut-off keeps.
    #[inline(always)]
    fn row(&self, i: u32, others: &[u32], out: &mut Keys) {
        let (xi, ri) = (self.position[i as usize], self.radius[i as usize]);
        let room = out.room(others.len());
        let mut n = 0;
        let ex_i = self.excluded.get(i as usize).copied().unwrap_or(0);
        for &j in others {
            let cut = ri + self.radius[j as usize] + self.skin;
            let d = self.images.nearest(self.position[j as usize] - xi);
            let left_out = (ex_i & self.excluded.get(j as usize).copied().unwrap_or(0)) != 0;
            let within = (d.length_squared() < cut * cut) & !left_out;
            room[n] = pair_key(i.min(j), i.max(j));
            n += within as usize;
        }
        out.used += n;
    }
}

/// The touch test of a rebuild (for a law that keeps histories apart): the force loop's.
struct Overlap<'a> {
    position: &'a [Vec3],
    radius: &'a [f64],
    periodic: Periodic,
}

impl Overlap<'_> {
    /// Whether the spheres of slots a and b touch, by nearest image.
    fn of(&self, a: usize, b: usize) -> bool {
        let d = self.periodic.nearest(self.position[b] - self.position[a]);
        crate::contact::geometry::pair_touching(d.length_squared(), self.radius[a], self.radius[b])
    }
}

/// True unless every component of `h` is +0.0 (a negative zero counts as a value): whether a
/// stored history is a contact.
pub(crate) fn nonzero(h: Vec3) -> bool {
    h.to_array().iter().any(|v| v.to_bits() != 0)
}
