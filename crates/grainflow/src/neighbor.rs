//! Broad phase: linked cells with a skin (a Verlet list), rebuilt when any particle has moved
//! more than half the skin since the last build.
//!
//! The list holds every particle pair closer than R_i + R_j + skin and every particle–wall pair
//! closer than R + skin, so between rebuilds no contact can be missed. The contacts carry
//! their tangential history; on a rebuild, those that persist keep it (matched by the slots of
//! the two particles, or the slot and the wall index — slots never change during a run), new
//! entries start from zero.
//!
//! Only about one candidate pair in three or four touches, so the pairs' histories are kept
//! apart from the list, for the pairs in contact only ([`PairContacts`]): the force stage
//! streams through a third of the memory it would with one history per candidate pair.

use crate::boundary::Periodic;
use crate::math::Vec3;
use crate::state::Particles;
use crate::wall::Wall;

/// Counters of the neighbour search.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NeighborStats {
    /// Number of builds so far.
    pub builds: u64,
    /// Distance tests made in the last build (O(N) for a bounded density).
    pub distance_checks: u64,
}

/// A pair in contact and its tangential history, seen from its lower slot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairContact {
    /// The pair's index (its place in the list order).
    pub pair: usize,
    /// Its tangential history.
    pub history: Vec3,
}

/// The tangential histories of the pairs in contact at the last force evaluation, ascending
/// by pair index. A pair not listed has zero history.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PairContacts {
    list: Vec<PairContact>,
}

impl PairContacts {
    /// Number of listed contacts.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// True when no contact is listed.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The contacts, ascending by pair.
    pub fn as_slice(&self) -> &[PairContact] {
        &self.list
    }

    /// Empties the list, keeping its memory.
    pub fn clear(&mut self) {
        self.list.clear();
    }

    /// Appends pair `k` (above every pair listed) with history `h`.
    #[inline(always)]
    pub fn push(&mut self, k: usize, h: Vec3) {
        self.list.push(PairContact { pair: k, history: h });
    }

    /// Appends all of `other`'s contacts (which lie above this one's).
    pub fn extend(&mut self, other: &PairContacts) {
        self.list.extend_from_slice(&other.list);
    }

    /// The histories as one entry per pair of a list of `n_pairs` pairs (zero where not
    /// listed).
    pub fn expand(&self, n_pairs: usize) -> Vec<Vec3> {
        let mut all = vec![Vec3::ZERO; n_pairs];
        for c in &self.list {
            all[c.pair] = c.history;
        }
        all
    }

    pub(crate) fn heap_bytes(&self) -> usize {
        self.list.capacity() * std::mem::size_of::<PairContact>()
    }
}

/// A cursor over [`PairContacts`] that finds the history of pairs asked for in ascending
/// order.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ContactCursor<'a> {
    list: &'a [PairContact],
    at: usize,
}

impl<'a> ContactCursor<'a> {
    /// A cursor at the first contact of `c` with pair index ≥ `k0`.
    pub fn new(c: &'a PairContacts, k0: usize) -> Self {
        ContactCursor { list: &c.list, at: c.list.partition_point(|c| c.pair < k0) }
    }

    /// The history of pair `k` (zero if not listed); `k` must not be below the pair asked for
    /// before.
    #[inline(always)]
    pub fn history(&mut self, k: usize) -> Vec3 {
        while self.at < self.list.len() && self.list[self.at].pair < k {
            self.at += 1;
        }
        match self.list.get(self.at) {
            Some(c) if c.pair == k => c.history,
            _ => Vec3::ZERO,
        }
    }
}

/// The Verlet list with its contact histories.
///
/// Pairs are stored as a half list in compressed rows: the partners of slot `a` are the slots
/// `b > a` in `partners[offsets[a]..offsets[a + 1]]`, ascending. Pair `k` is its place in
/// that order; the pairs in contact carry their tangential history in [`PairContacts`],
/// seen from the lower slot `a`. This is the order the force loop walks memory in and sums
/// forces in.
#[derive(Debug, Clone, Default)]
pub struct NeighborList {
    skin: f64,
    offsets: Vec<usize>,
    partners: Vec<u32>,
    contacts: PairContacts,
    /// The next force evaluation's contacts (kept to reuse its memory).
    next_contacts: PairContacts,
    /// Candidate particle–wall pairs (slot, wall index), ordered by slots.
    wall_pairs: Vec<[u32; 2]>,
    wall_history: Vec<Vec3>,
    reference: Vec<Vec3>,
    built: bool,
    stats: NeighborStats,
    /// Periodic axes of the domain (distances by nearest image).
    periodic: Periodic,
    /// Slots whose pairs with each other are left out (particles that never move).
    excluded: Vec<bool>,
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

const HALF_SHELL: [(i64, i64, i64); 13] = [
    (1, 0, 0),
    (-1, 1, 0),
    (0, 1, 0),
    (1, 1, 0),
    (-1, -1, 1),
    (0, -1, 1),
    (1, -1, 1),
    (-1, 0, 1),
    (0, 0, 1),
    (1, 0, 1),
    (-1, 1, 1),
    (0, 1, 1),
    (1, 1, 1),
];

/// The sort key of the pair of slots a < b (or of a slot and a wall index).
#[inline]
fn pair_key(a: u32, b: u32) -> u64 {
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

    /// Leaves out the pairs of particles that are both marked (e.g. particles held fixed:
    /// their mutual forces act on nothing that moves). Takes effect at the next build.
    pub fn exclude_pairs_among(&mut self, marked: Vec<bool>) {
        self.excluded = if marked.iter().any(|&m| m) { marked } else { Vec::new() };
        self.built = false;
    }

    /// The skin distance, m.
    pub fn skin(&self) -> f64 {
        self.skin
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
        let mut pairs: Vec<(u64, Vec3)> = s
            .pairs
            .iter()
            .zip(&s.pair_history)
            .map(|(&[a, b], &h)| if a < b { (pair_key(a, b), h) } else { (pair_key(b, a), -h) })
            .collect();
        pairs.sort_unstable_by_key(|e| e.0);
        let mut walls: Vec<(u64, Vec3)> =
            s.wall_pairs.iter().zip(&s.wall_history).map(|(&[i, w], &h)| (pair_key(i, w), h)).collect();
        walls.sort_unstable_by_key(|e| e.0);
        if pairs.windows(2).any(|w| w[0].0 == w[1].0) || walls.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err("the neighbour list holds a pair twice".into());
        }
        self.skin = s.skin;
        self.built = s.built;
        row_offsets(pairs.iter().map(|e| e.0), n, &mut self.offsets);
        self.partners = pairs.iter().map(|e| e.0 as u32).collect();
        // A zero history is no contact (bit for bit: a negative zero is kept).
        self.contacts.clear();
        for (k, e) in pairs.iter().enumerate() {
            if e.1.to_array().iter().any(|v| v.to_bits() != 0) {
                self.contacts.push(k, e.1);
            }
        }
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
    /// pairs not in contact at the last force evaluation).
    pub fn pair_history(&self) -> Vec<Vec3> {
        self.contacts.expand(self.partners.len())
    }

    /// The pairs in contact at the last force evaluation with their histories.
    pub fn pair_contacts(&self) -> &PairContacts {
        &self.contacts
    }

    /// Sets the tangential history of pair `k` (for tests and hooks that set a contact's
    /// state); a zero history removes the pair from the contacts.
    pub fn set_pair_history(&mut self, k: usize, h: Vec3) {
        assert!(k < self.partners.len(), "pair {k} is not in the list");
        let c = &mut self.contacts.list;
        let at = c.partition_point(|c| c.pair < k);
        let listed = at < c.len() && c[at].pair == k;
        match (listed, h == Vec3::ZERO) {
            (true, true) => {
                c.remove(at);
            }
            (true, false) => c[at].history = h,
            (false, false) => c.insert(at, PairContact { pair: k, history: h }),
            (false, true) => {}
        }
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

    /// The parts the force loop needs at once: (offsets, partners, pair contacts, the next
    /// evaluation's pair contacts to fill, wall pairs, wall histories). The filled contacts
    /// take over with [`commit_contacts`](Self::commit_contacts).
    #[allow(clippy::type_complexity)]
    pub(crate) fn split_mut(
        &mut self,
    ) -> (&[usize], &[u32], &PairContacts, &mut PairContacts, &[[u32; 2]], &mut [Vec3]) {
        (
            &self.offsets,
            &self.partners,
            &self.contacts,
            &mut self.next_contacts,
            &self.wall_pairs,
            &mut self.wall_history,
        )
    }

    /// Makes the contacts filled in by the force stage (see [`split_mut`](Self::split_mut))
    /// the current ones.
    pub(crate) fn commit_contacts(&mut self) {
        std::mem::swap(&mut self.contacts, &mut self.next_contacts);
    }

    /// Heap bytes held by the list and its scratch space.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.offsets.capacity() * size_of::<usize>()
            + self.partners.capacity() * 4
            + self.contacts.heap_bytes()
            + self.next_contacts.heap_bytes()
            + (self.wall_history.capacity() + self.reference.capacity()) * size_of::<Vec3>()
            + self.wall_pairs.capacity() * 8
            + self.excluded.capacity()
            + (self.cell_count.capacity() + self.cell_of.capacity() + self.sorted.capacity()) * 4
            + self.fresh.capacity() * 8
    }

    /// Counters of the search.
    pub fn stats(&self) -> NeighborStats {
        self.stats
    }

    /// True when the list was never built or a particle moved more than half the skin. With
    /// `parallel`, checked on the current rayon pool.
    pub fn needs_rebuild(&self, positions: &[Vec3], parallel: bool) -> bool {
        if !self.built || positions.len() != self.reference.len() {
            return true;
        }
        let lim = 0.25 * self.skin * self.skin;
        let per = self.periodic;
        let periodic = per.any();
        let moved = |(x, r): (&Vec3, &Vec3)| {
            let d = *x - *r;
            let d2 = if periodic { per.min_image(d) } else { d }.length_squared();
            d2 > lim || d2.is_nan()
        };
        if parallel {
            use rayon::prelude::*;
            positions.par_iter().zip(&self.reference).with_min_len(4096).any(moved)
        } else {
            positions.iter().zip(&self.reference).any(moved)
        }
    }

    /// Rebuilds the list if [`needs_rebuild`](Self::needs_rebuild) says so.
    pub fn update(&mut self, particles: &Particles, walls: &[Wall], parallel: bool) {
        if self.needs_rebuild(&particles.position, parallel) {
            self.build(particles, walls);
        }
    }

    /// Rebuilds the list now, keeping the history of persisting entries.
    pub fn build(&mut self, p: &Particles, walls: &[Wall]) {
        self.stats.builds += 1;
        self.stats.distance_checks = 0;
        self.reference.clear();
        self.reference.extend_from_slice(&p.position);
        self.built = true;
        self.build_pairs(p);
        self.build_walls(p, walls);
    }

    fn build_pairs(&mut self, p: &Particles) {
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
            let excluded = &self.excluded;
            let mut checks = 0u64;
            let mut consider = |i: usize, j: usize, out: &mut Vec<u64>| {
                checks += 1;
                if !excluded.is_empty() && excluded[i] && excluded[j] {
                    return;
                }
                let cut = p.radius[i] + p.radius[j] + skin;
                if per.min_image(p.position[j] - p.position[i]).length_squared() < cut * cut {
                    let (a, b) = if i < j { (i, j) } else { (j, i) };
                    out.push(pair_key(a as u32, b as u32));
                }
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
            for cz in 0..nz {
                for cy in 0..ny {
                    for cx in 0..nx {
                        let c = cx + nx * (cy + ny * cz);
                        let own = &sorted[start[c] as usize..start[c + 1] as usize];
                        for (k, &i) in own.iter().enumerate() {
                            for &j in &own[k + 1..] {
                                consider(i as usize, j as usize, &mut self.fresh);
                            }
                        }
                        for (dx, dy, dz) in HALF_SHELL {
                            let (Some(ox), Some(oy), Some(oz)) = (
                                wrap_axis(cx as i64 + dx, nx, 0),
                                wrap_axis(cy as i64 + dy, ny, 1),
                                wrap_axis(cz as i64 + dz, nz, 2),
                            ) else {
                                continue;
                            };
                            let o = ox + nx * (oy + ny * oz);
                            let other = &sorted[start[o] as usize..start[o + 1] as usize];
                            for &i in own {
                                for &j in other {
                                    consider(i as usize, j as usize, &mut self.fresh);
                                }
                            }
                        }
                    }
                }
            }
            self.stats.distance_checks += checks;
        }
        self.fresh.sort_unstable();
        self.renew_pairs(n);
    }

    /// Replaces the pairs by the sorted `fresh` keys: each contact moves to the new place of
    /// its pair, and is dropped if the pair left the list (both lists are in (a, b) order, so
    /// one merge pass finds them). Done in place: a contact's new place in the contacts is never
    /// behind its old one.
    fn renew_pairs(&mut self, n: usize) {
        let (mut a_old, mut k, mut kept) = (0usize, 0usize, 0usize);
        let c = &mut self.contacts.list;
        let mut next = 0;
        for (f, &key) in self.fresh.iter().enumerate() {
            if next == c.len() {
                break;
            }
            while k < self.partners.len() {
                while self.offsets[a_old + 1] <= k {
                    a_old += 1;
                }
                let old_key = pair_key(a_old as u32, self.partners[k]);
                if old_key < key {
                    k += 1;
                    continue;
                }
                if old_key == key {
                    while next < c.len() && c[next].pair < k {
                        next += 1;
                    }
                    if next < c.len() && c[next].pair == k {
                        c[kept] = PairContact { pair: f, history: c[next].history };
                        kept += 1;
                        next += 1;
                    }
                    k += 1;
                }
                break;
            }
        }
        c.truncate(kept);
        let len = self.fresh.len();
        row_offsets(self.fresh.iter().copied(), n, &mut self.offsets);
        self.partners.clear();
        self.partners.reserve_exact(len);
        self.partners.extend(self.fresh.iter().map(|&key| key as u32));
        // The pairs of the next build are about as many; the scratch is not kept meanwhile.
        self.fresh = Vec::new();
    }

    fn build_walls(&mut self, p: &Particles, walls: &[Wall]) {
        let mut fresh = Vec::new();
        for i in 0..p.len() {
            for (w, wall) in walls.iter().enumerate() {
                self.stats.distance_checks += 1;
                let d = wall.distance(p.position[i]);
                if d < p.radius[i] + self.skin {
                    fresh.push([i as u32, w as u32]);
                }
            }
        }
        // Both lists are in (slot, wall) order: one merge pass carries the histories over.
        let mut history = Vec::with_capacity(fresh.len());
        let mut k = 0;
        for pair in &fresh {
            while k < self.wall_pairs.len() && self.wall_pairs[k] < *pair {
                k += 1;
            }
            let same = k < self.wall_pairs.len() && self.wall_pairs[k] == *pair;
            history.push(if same { self.wall_history[k] } else { Vec3::ZERO });
        }
        self.wall_pairs = fresh;
        self.wall_history = history;
    }
}
