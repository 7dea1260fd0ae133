//! Broad phase: linked cells with a skin (a Verlet list), rebuilt when any particle has moved
//! more than half the skin since the last build.
//!
//! The list holds every particle pair closer than R_i + R_j + skin and every particle–wall pair
//! closer than R + skin, so between rebuilds no contact can be missed. Each entry carries the
//! contact's tangential history; on a rebuild, entries that persist keep it (matched by the
//! stable ids of the particles, and the wall index), new entries start from zero.

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

/// The Verlet list with its contact histories.
#[derive(Debug, Clone, Default)]
pub struct NeighborList {
    skin: f64,
    /// Candidate pairs as particle slots (i, j), with id[i] < id[j], ordered by slots.
    pub pairs: Vec<[u32; 2]>,
    pair_keys: Vec<u64>,
    /// Tangential history of each pair, seen from the lower-id particle.
    pub pair_history: Vec<Vec3>,
    /// Candidate particle–wall pairs (slot, wall index), ordered by slots.
    pub wall_pairs: Vec<[u32; 2]>,
    wall_keys: Vec<u64>,
    /// Tangential history of each particle–wall pair.
    pub wall_history: Vec<Vec3>,
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
    new_pairs: Vec<(u64, [u32; 2])>,
}

/// Everything of a [`NeighborList`] that a checkpoint must carry.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NeighborState {
    /// Skin, m.
    pub skin: f64,
    /// Whether the list was built.
    pub built: bool,
    /// Candidate pairs (slots).
    pub pairs: Vec<[u32; 2]>,
    /// Their (id, id) keys.
    pub pair_keys: Vec<u64>,
    /// Their tangential histories.
    pub pair_history: Vec<Vec3>,
    /// Candidate particle–wall pairs (slot, wall).
    pub wall_pairs: Vec<[u32; 2]>,
    /// Their (id, wall) keys.
    pub wall_keys: Vec<u64>,
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

#[inline]
fn pair_key(id_a: u32, id_b: u32) -> u64 {
    ((id_a as u64) << 32) | id_b as u64
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
            pairs: self.pairs.clone(),
            pair_keys: self.pair_keys.clone(),
            pair_history: self.pair_history.clone(),
            wall_pairs: self.wall_pairs.clone(),
            wall_keys: self.wall_keys.clone(),
            wall_history: self.wall_history.clone(),
            reference: self.reference.clone(),
        }
    }

    /// Restores a checkpointed state; `n` particles and `n_walls` walls must fit it.
    pub fn set_state(&mut self, s: NeighborState, n: usize, n_walls: usize) -> Result<(), String> {
        let lens_ok = s.pairs.len() == s.pair_keys.len()
            && s.pairs.len() == s.pair_history.len()
            && s.wall_pairs.len() == s.wall_keys.len()
            && s.wall_pairs.len() == s.wall_history.len()
            && (s.reference.len() == n || !s.built);
        let in_range = s.pairs.iter().flatten().all(|&i| (i as usize) < n)
            && s.wall_pairs.iter().all(|&[i, w]| (i as usize) < n && (w as usize) < n_walls);
        if !(lens_ok && in_range) {
            return Err("the neighbour list does not fit the particles and walls of the case".into());
        }
        self.skin = s.skin;
        self.built = s.built;
        self.pairs = s.pairs;
        self.pair_keys = s.pair_keys;
        self.pair_history = s.pair_history;
        self.wall_pairs = s.wall_pairs;
        self.wall_keys = s.wall_keys;
        self.wall_history = s.wall_history;
        self.reference = s.reference;
        Ok(())
    }

    /// Counters of the search.
    pub fn stats(&self) -> NeighborStats {
        self.stats
    }

    /// True when the list was never built or a particle moved more than half the skin.
    pub fn needs_rebuild(&self, positions: &[Vec3]) -> bool {
        if !self.built || positions.len() != self.reference.len() {
            return true;
        }
        let lim = 0.25 * self.skin * self.skin;
        let per = self.periodic;
        let periodic = per.any();
        positions.iter().zip(&self.reference).any(|(x, r)| {
            let d = *x - *r;
            let d2 = if periodic { per.min_image(d) } else { d }.length_squared();
            d2 > lim || d2.is_nan()
        })
    }

    /// Rebuilds the list if [`needs_rebuild`](Self::needs_rebuild) says so.
    pub fn update(&mut self, particles: &Particles, walls: &[Wall]) {
        if self.needs_rebuild(&particles.position) {
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
        self.new_pairs.clear();
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
            let mut consider = |i: usize, j: usize, out: &mut Vec<(u64, [u32; 2])>| {
                checks += 1;
                if !excluded.is_empty() && excluded[i] && excluded[j] {
                    return;
                }
                let cut = p.radius[i] + p.radius[j] + skin;
                if per.min_image(p.position[j] - p.position[i]).length_squared() < cut * cut {
                    let (a, b) = if p.id[i] < p.id[j] { (i, j) } else { (j, i) };
                    out.push((pair_key(p.id[a], p.id[b]), [a as u32, b as u32]));
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
                                consider(i as usize, j as usize, &mut self.new_pairs);
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
                                    consider(i as usize, j as usize, &mut self.new_pairs);
                                }
                            }
                        }
                    }
                }
            }
            self.stats.distance_checks += checks;
        }
        renew(&mut self.new_pairs, &mut self.pairs, &mut self.pair_keys, &mut self.pair_history);
    }

    fn build_walls(&mut self, p: &Particles, walls: &[Wall]) {
        self.new_pairs.clear();
        for i in 0..p.len() {
            for (w, wall) in walls.iter().enumerate() {
                self.stats.distance_checks += 1;
                let d = wall.distance(p.position[i]);
                if d < p.radius[i] + self.skin {
                    self.new_pairs.push((pair_key(p.id[i], w as u32), [i as u32, w as u32]));
                }
            }
        }
        renew(&mut self.new_pairs, &mut self.wall_pairs, &mut self.wall_keys, &mut self.wall_history);
    }
}

/// Replaces the entries `(slots, keys, history)` by the `fresh` ones: each takes the history of
/// the old entry with the same key (particle ids, or id and wall), zero if it is new. The
/// result is ordered by slots — the order the force loop then walks memory in.
fn renew(
    fresh: &mut [(u64, [u32; 2])],
    slots: &mut Vec<[u32; 2]>,
    keys: &mut Vec<u64>,
    hist: &mut Vec<Vec3>,
) {
    let mut old: Vec<(u64, Vec3)> = keys.iter().copied().zip(hist.iter().copied()).collect();
    old.sort_unstable_by_key(|e| e.0);
    fresh.sort_unstable_by_key(|e| e.0);
    let mut merged: Vec<([u32; 2], u64, Vec3)> = Vec::with_capacity(fresh.len());
    let mut k = 0;
    for &(key, s) in fresh.iter() {
        while k < old.len() && old[k].0 < key {
            k += 1;
        }
        let h = if k < old.len() && old[k].0 == key { old[k].1 } else { Vec3::ZERO };
        merged.push((s, key, h));
    }
    merged.sort_unstable_by_key(|e| e.0);
    slots.clear();
    keys.clear();
    hist.clear();
    for (s, key, h) in merged {
        slots.push(s);
        keys.push(key);
        hist.push(h);
    }
}
