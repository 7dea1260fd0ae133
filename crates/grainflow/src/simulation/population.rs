//! Particles that come and go: insertion, removal and re-sorting between steps.
//!
//! A particle's identity is its id; its slot (its index in the particle arrays) is only where
//! it is stored. Whatever moves particles to other slots goes through
//! [`Simulation::rearrange`], which carries every fact kept by slot along: the contact and
//! wall histories (taken from the neighbour list by slot, put back under the new slots), the
//! prescribed-motion rules, the held particles, the runs of integrated slots, the thread
//! blocks and the common mass. Since the force stage's sums do not depend on their order
//! (`forces::sum`), a run gives the same bits with or without re-sorting, and a particle
//! inserted mid-run moves as one present from the start would.

use super::Simulation;
use crate::error::EngineError;
use crate::forces::ForcePlan;
use crate::math::Vec3;
use crate::motion;
use crate::state::ParticleInit;

/// When the simulation re-sorts its particles along a space-filling curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ResortRule {
    /// Never (the order of the input, or of the set-up's spatial sort, is kept).
    Never,
    /// When the memory order has decayed: at the first step after a neighbour-list build
    /// whose pairs lie, on average, more than twice as far apart in memory as just after the
    /// last sort (and at least 100 steps after it).
    #[default]
    Auto,
    /// Every so many steps.
    Every(u64),
}

/// What [`Simulation::rearrange`] needs to remember between sorts.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct SortState {
    pub rule: ResortRule,
    /// The step of the last sort (or of the start).
    pub last_step: u64,
    /// The mean slot gap of the list's pairs after the last sort (None: not measured yet).
    pub gap_after: Option<f64>,
    /// The neighbour-list build whose gap was last looked at.
    pub build_seen: u64,
    /// Sorts so far.
    pub sorts: u64,
}

impl Simulation {
    /// Moves the particles to new slots: slot `k` takes the particle of slot `order[k]`. A
    /// slot not in `order` is removed with everything of its particle (its contacts' and wall
    /// contacts' histories). `order` must name each slot at most once.
    pub(crate) fn rearrange(&mut self, order: &[usize]) -> Result<(), EngineError> {
        let n_old = self.particles.len();
        const GONE: u32 = u32::MAX;
        let mut new_of = vec![GONE; n_old];
        for (k, &old) in order.iter().enumerate() {
            if old >= n_old || new_of[old] != GONE {
                return Err(EngineError::BadReference(format!(
                    "internal error: slot {old} is named twice or does not exist in a rearrangement"
                )));
            }
            new_of[old] = k as u32;
        }
        if let Some(r) =
            self.motion.iter().find(|r| new_of[r.slot] == GONE || r.leader.is_some_and(|l| new_of[l] == GONE))
        {
            let id =
                self.particles.id[if new_of[r.slot] == GONE { r.slot } else { r.leader.unwrap_or(r.slot) }];
            return Err(EngineError::BadReference(format!(
                "particle {id} is under prescribed motion (or leads a particle that is): it cannot be removed"
            )));
        }
        if self.kick_pending {
            return Err(EngineError::BadReference(
                "internal error: particles rearranged with a half kick pending".into(),
            ));
        }
        // Each contact source takes its part of the neighbour list's state (and its own) into
        // the new slots.
        let mut state = self.neighbors.state();
        self.sources.rearrange(&new_of, &mut state);
        if state.reference.len() == n_old {
            state.reference = order.iter().map(|&i| state.reference[i]).collect();
        } else {
            state.built = false;
        }
        self.particles = self.particles.gathered(order);
        let n = self.particles.len();
        self.neighbors.set_state(state, n, self.walls.len()).map_err(|e| {
            EngineError::BadReference(format!(
                "internal error: the neighbour list does not survive a rearrangement: {e}"
            ))
        })?;
        for r in &mut self.motion {
            r.slot = new_of[r.slot] as usize;
            r.leader = r.leader.map(|l| new_of[l] as usize);
        }
        self.derive_slot_facts();
        Ok(())
    }

    /// Derives again everything kept by slot from the particles and the motion rules: the
    /// held slots (and the pairs the neighbour list leaves out), the runs of integrated slots,
    /// the common mass, the thread blocks.
    pub(super) fn derive_slot_facts(&mut self) {
        let n = self.particles.len();
        self.slot_count = n;
        let owned = self.owned();
        let mut held = motion::held(&self.motion, n);
        self.mark_held_ghosts(&mut held);
        // Ghosts (slots from `owned` on) are left out of each other's pairs and never moved.
        let excluded = held.iter().enumerate().map(|(i, &h)| h as u8 | (((i >= owned) as u8) << 1)).collect();
        self.neighbors.remap_excluded(excluded);
        self.held = if held.iter().any(|&h| h) { held } else { Vec::new() };
        self.free = motion::free_runs(&self.motion, owned);
        self.common = None;
        self.sources.pairs.plan = ForcePlan::default();
    }

    /// Adds particles between steps. Each needs an id no particle has, a phase of the case, a positive radius and
    /// density, and finite position, velocity and spin. They are appended in the order given;
    /// an inserted particle moves exactly as one present from the start in the same state
    /// would (with Adams–Bashforth, it takes its first step as the run's first step was
    /// taken). Overlaps with particles or walls are not checked: an overlapping particle is
    /// pushed out by the contact law.
    ///
    /// On ranks every rank must call it with the same particles: each keeps those in its box.
    ///
    /// The books count them as added ([`FlowBooks::added`](crate::simulation::FlowBooks)),
    /// and the case's insertions number their particles after the largest id given here.
    pub fn insert(&mut self, new: &[ParticleInit]) -> Result<(), EngineError> {
        self.insert_uncounted(new)?;
        let masses = crate::state::Particles::from_init(new).mass;
        self.flow.count_by_hand(masses.into_iter(), true);
        if let Some(top) = new.iter().map(|q| q.id).max() {
            self.flow.id_used(top);
        }
        Ok(())
    }

    /// The id a particle added next should take to follow every id so far and come before
    /// those the case's insertions give next (one above the largest).
    pub fn next_free_id(&self) -> u64 {
        self.flow.next_id()
    }

    /// [`insert`](Self::insert), not counted in the books (the insertions count their own).
    pub(super) fn insert_uncounted(&mut self, new: &[ParticleInit]) -> Result<(), EngineError> {
        if self.comm().is_some() { self.insert_over_ranks(new) } else { self.append_new(new) }
    }

    /// Appends the particles `new` (checked) to this rank's slots.
    pub(super) fn append_new(&mut self, new: &[ParticleInit]) -> Result<(), EngineError> {
        if self.kick_pending {
            return Err(EngineError::BadReference(
                "internal error: insertion with a half kick pending".into(),
            ));
        }
        let mut added = self.check_new(new)?;
        let ab = !self.particles.accel_prev.is_empty();
        if ab {
            // No history yet: the first step is taken as the run's first (see `integrate`).
            added.accel_prev = vec![Vec3::splat(f64::NAN); added.len()];
            added.alpha_prev = vec![Vec3::splat(f64::NAN); added.len()];
        }
        let n_old = self.particles.len();
        self.particles.append(&added);
        self.sources.appended(n_old, self.particles.len());
        // The forces held are those of the particles before: evaluated again before they act.
        self.forces_current = false;
        self.derive_slot_facts();
        // On ranks the domain stage lays the slots out (`insert_over_ranks`).
        if self.comm().is_some() { Ok(()) } else { self.put_prescribed_last() }
    }

    /// The particles `new` checked as [`insert`](Self::insert) takes them: ids unused, and
    /// valid states.
    pub(super) fn check_new(&self, new: &[ParticleInit]) -> Result<crate::state::Particles, EngineError> {
        let mut ids: Vec<u32> = self.particles.id.iter().chain(new.iter().map(|q| &q.id)).copied().collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(EngineError::BadReference(format!("particle id {} is used twice", w[0])));
        }
        let added = crate::state::Particles::from_init(new);
        super::check_particles(&added, self.phases.len())?;
        if let Some(q) = new.iter().find(|q| !(q.density.is_finite() && q.density > 0.0)) {
            return Err(EngineError::invalid(
                format!("particle {} density", q.id),
                q.density,
                "a density must be positive, in kg/m³",
            ));
        }
        Ok(added)
    }

    /// Slots `order` with the particles under prescribed motion moved after the others, each
    /// group in its order: the integrated slots are then one run, which the integrators take
    /// in one loop (no result depends on the slots).
    fn prescribed_last(&self, mut order: Vec<usize>) -> Vec<usize> {
        if self.motion.is_empty() {
            return order;
        }
        let mut prescribed = vec![false; self.particles.len()];
        for r in &self.motion {
            prescribed[r.slot] = true;
        }
        order.sort_by_key(|&s| prescribed[s]);
        order
    }

    /// Moves the particles under prescribed motion after the others, if they are not there.
    pub(super) fn put_prescribed_last(&mut self) -> Result<(), EngineError> {
        if self.free.len() <= 1 && self.free.first().is_none_or(|r| r.start == 0) {
            return Ok(());
        }
        let order = self.prescribed_last((0..self.particles.len()).collect());
        self.rearrange(&order)
    }

    /// Removes the particles with the given ids between steps (with their contacts'
    /// histories); returns how many there were. Particles under prescribed motion cannot be
    /// removed. On ranks every rank must call it with the same ids.
    /// The books count them as taken ([`FlowBooks::taken`](crate::simulation::FlowBooks)).
    pub fn remove_ids(&mut self, ids: &[u32]) -> Result<usize, EngineError> {
        let mut gone: Vec<u32> = ids.to_vec();
        gone.sort_unstable();
        if self.comm().is_some() {
            let p = &self.particles;
            let mine: Vec<usize> =
                (0..self.owned()).filter(|&i| gone.binary_search(&p.id[i]).is_ok()).collect();
            let masses: Vec<f64> = mine.iter().map(|&i| p.mass[i]).collect();
            let mine: Vec<u32> = mine.iter().map(|&i| p.id[i]).collect();
            let removed = self.remove_over_ranks(&mine)?;
            self.flow.count_by_hand(masses.into_iter(), false);
            return Ok(removed);
        }
        self.remove_where(|p, i| gone.binary_search(&p.id[i]).is_ok())
    }

    /// Removes the particles (slots `i` of the particle arrays) for which `leaving` is true,
    /// between steps; returns how many. The books count them as taken.
    pub fn remove_where(
        &mut self,
        mut leaving: impl FnMut(&crate::state::Particles, usize) -> bool,
    ) -> Result<usize, EngineError> {
        let p = &self.particles;
        let marked: Vec<bool> = (0..p.len()).map(|i| leaving(p, i)).collect();
        let masses: Vec<f64> = (0..self.owned()).filter(|&i| marked[i]).map(|i| p.mass[i]).collect();
        let removed = self.remove_slots_where(|_, i| marked[i])?;
        self.flow.count_by_hand(masses.into_iter(), false);
        Ok(removed)
    }

    /// [`remove_where`](Self::remove_where), not counted in the books (the outlets count their
    /// own).
    pub(super) fn remove_slots_where(
        &mut self,
        mut leaving: impl FnMut(&crate::state::Particles, usize) -> bool,
    ) -> Result<usize, EngineError> {
        let n = self.particles.len();
        let order: Vec<usize> = (0..n).filter(|&i| !leaving(&self.particles, i)).collect();
        let removed = n - order.len();
        if removed > 0 {
            self.rearrange(&order)?;
            // The remaining particles' forces are those with the removed ones.
            self.forces_current = false;
        }
        Ok(removed)
    }

    /// Sets when the particles are re-sorted during the run (see [`ResortRule`]).
    pub fn set_resort(&mut self, rule: ResortRule) {
        self.sort.rule = rule;
    }

    /// Re-sorts done so far.
    pub fn resorts(&self) -> u64 {
        self.sort.sorts
    }

    /// Sorts the particles along a space-filling curve (Morton order of cells of the
    /// neighbour cut-off's size, ties by id), so that particles near each other in space are
    /// near each other in memory; particles under prescribed motion after the others. The
    /// results of the run do not change.
    pub fn sort_spatially(&mut self) -> Result<(), EngineError> {
        let order = morton_order(&self.particles.position, &self.particles.id, self.cell_size());
        self.rearrange(&self.prescribed_last(order))?;
        self.sorted_now();
        Ok(())
    }

    /// The side of the cells the sort orders by: the neighbour cut-off of the largest
    /// particles.
    pub(super) fn cell_size(&self) -> f64 {
        let c = 2.0 * self.particles.max_radius() + self.neighbors.skin();
        if c.is_finite() && c > 0.0 { c } else { 1.0 }
    }

    /// Re-sorts if the rule says it is time (between steps). On ranks each rank lays its own
    /// particles out at neighbour-list rebuilds instead (see `redistribute`).
    pub(super) fn resort_if_due(&mut self, par: bool) {
        if self.domain.is_none() && self.resort_due() {
            if self.kick_pending {
                self.finish_kick(par);
            }
            // Cannot fail: a permutation of every slot keeps every rule's particle.
            let _ = self.sort_spatially();
        }
    }

    /// Whether the rule says it is time to re-sort (looking at the last neighbour-list build
    /// once).
    pub(super) fn resort_due(&mut self) -> bool {
        match self.sort.rule {
            ResortRule::Never => false,
            ResortRule::Every(k) => k > 0 && self.step >= self.sort.last_step + k,
            ResortRule::Auto => {
                let builds = self.neighbors.stats().builds;
                if builds == self.sort.build_seen || !self.neighbors.is_built() {
                    false
                } else {
                    self.sort.build_seen = builds;
                    let gap = self.neighbors.mean_slot_gap();
                    match self.sort.gap_after {
                        None => {
                            self.sort.gap_after = Some(gap);
                            false
                        }
                        Some(g0) => gap > 2.0 * g0.max(1.0) && self.step >= self.sort.last_step + 100,
                    }
                }
            }
        }
    }

    /// Notes a sort done now.
    pub(super) fn sorted_now(&mut self) {
        self.sort.last_step = self.step;
        self.sort.gap_after = None;
        self.sort.sorts += 1;
    }
}

/// The slots in Morton (Z-curve) order of the cells of side `cell` their positions lie in,
/// ties broken by id: a function of the positions and ids alone.
pub(super) fn morton_order(x: &[Vec3], id: &[u32], cell: f64) -> Vec<usize> {
    let lo = x.iter().fold(Vec3::splat(f64::INFINITY), |m, p| m.min(*p));
    // 21 bits a coordinate: 2 million cells along each axis.
    let coord = |v: f64, l: f64| (((v - l) / cell).floor().clamp(0.0, (1 << 21) as f64 - 1.0)) as u64;
    let spread = |mut v: u64| {
        v &= 0x1f_ffff;
        v = (v | v << 32) & 0x001f_0000_0000_ffff;
        v = (v | v << 16) & 0x001f_0000_ff00_00ff;
        v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
        v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
        v = (v | v << 2) & 0x1249_2492_4924_9249;
        v
    };
    let mut keys: Vec<(u64, u32, usize)> = x
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let m = spread(coord(p.x, lo.x)) | spread(coord(p.y, lo.y)) << 1 | spread(coord(p.z, lo.z)) << 2;
            (m, id[i], i)
        })
        .collect();
    keys.sort_unstable();
    keys.into_iter().map(|k| k.2).collect()
}
