//! A run spread over ranks: each rank holds the particles of its box ([`crate::domain`]) and,
//! after them, ghosts — copies of the other ranks' particles within the list's reach of its
//! box — and steps as one process would, with the same bits.
//!
//! A rank's slots `0..owned` are its own particles, integrated and touching its walls; the
//! ghosts after them only lend their positions and velocities to pairs with an owned
//! particle (pairs of two ghosts are left out of the list). A pair across two ranks is
//! evaluated on both, each adding its load to its own particle: the load is the same bits
//! from either side and the sums are order-free (`forces::sum`), so every particle's force is
//! the one process's. What the sums' quanta, the common mass and the diagnostics depend on is
//! reduced over the ranks exactly (maxima, and integer sums of fixed-point values).
//!
//! Before a force evaluation whose particles moved since (velocity Verlet's drift, or a step
//! within `advance` that nobody looks at), and at the end of the last step of a call, each
//! rank sends its particles' new positions, velocities and spins to the ranks holding them as
//! ghosts, so that between calls every ghost equals its particle. Before every force
//! evaluation the ranks also decide
//! together whether the neighbour list is due (a particle anywhere moved half the skin): if
//! so, the particles that left a box move to its owner with their pair and wall histories
//! (keyed by ids), the ghosts are chosen again and each rank builds its list. The rebuilds fall
//! on the one process's steps.
//! Periodic axes need no shifted images: every rank measures distances by the nearest image
//! of the whole box, as one process does, so a ghost is sent as it is.

use super::{Common, ContactInfo, ContactPartner, ResortRule, Simulation};
use crate::boundary::Periodic;
use crate::domain::{Boxes, Comm, Weigh, Weighted};
use crate::error::EngineError;
use crate::math::Vec3;
use crate::neighbor::{NeighborState, nonzero, pair_key};
use crate::state::{NO_SLOT, ParticleInit, Particles, SlotsById};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

/// This rank's part of a run spread over ranks.
#[derive(Debug, Clone)]
pub(crate) struct Decomposition {
    comm: Arc<dyn Comm>,
    boxes: Boxes,
    /// The first ghost slot: slots below are this rank's particles.
    pub owned: usize,
    /// Per rank: the owned slots it holds as ghosts, in the order it holds them.
    sends: Vec<Vec<u32>>,
    /// Per rank: the ghost slots holding its particles.
    ghosts: Vec<Range<usize>>,
    /// How far from its box a rank needs the other ranks' particles: the list's largest
    /// cut-off, m.
    reach: f64,
    /// Whether particles carry an Adams–Bashforth history.
    history: bool,
    /// What this rank has sent so far.
    stats: DomainStats,
    /// Whether the ghosts lag behind their particles (a step within `advance` left them so:
    /// nobody looks at them before the next evaluation refreshes them).
    stale: bool,
    /// The prescribed-motion rules of every rank's particles, by ids, in the case's order
    /// (which a checkpoint keeps, and in which the rules are applied).
    rules: Vec<RuleById>,
    /// The index in `rules` of each prescribed particle's rule, by id.
    rule_of: HashMap<u32, usize>,
    /// The ids of the leaders, sorted.
    leaders: Vec<u32>,
    /// Re-cut the boxes when the slowest rank's work exceeds the mean by more than this
    /// fraction (none: never).
    threshold: Option<f64>,
    /// The step of the last look at the ranks' work.
    since: u64,
    /// The communicator as timed: its waits are not this rank's work.
    timed: Arc<crate::domain::Timed>,
    /// Whether the ranks' measured times decide the re-cuts ([`Weigh::Time`]).
    by_time: bool,
    /// Over the window of measurement: this rank's busy nanoseconds (its steps less the time
    /// spent in the communicator) and its work summed over the steps.
    busy: u64,
    window_work: u64,
    /// What a unit of this rank's work weighs in a cut: 1, or by measured time
    /// ([`WEIGHT_UNIT`] for a rank as fast as the mean).
    weight: u64,
}

/// A prescribed-motion rule by ids: its particle's and its leader's, and the rule as resolved
/// in one process (its slots stale once spread).
#[derive(Debug, Clone, Copy)]
pub(super) struct RuleById {
    pub(super) id: u32,
    pub(super) leader: Option<u32>,
    pub(super) rule: crate::motion::ResolvedMotion,
}

impl RuleById {
    /// The rule for this rank's slot `slot`: a follower's leader, which may be on another
    /// rank, is given by [`Simulation::apply_motion`].
    fn on_rank(&self, slot: usize) -> crate::motion::ResolvedMotion {
        self.rule.at_slots(slot, None)
    }
}

/// What a rank has sent to the others so far (collectives with itself left out).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DomainStats {
    /// Messages with content, to another rank.
    pub messages: u64,
    /// Bytes of those messages.
    pub bytes: u64,
    /// Particles that moved to another rank.
    pub migrated: u64,
    /// Ghosts sent at rebuilds (a particle to each rank that holds it).
    pub ghosts_sent: u64,
    /// The slowest rank's work and all ranks' (particles and their list partners), each
    /// summed over the steps: their ratio times the ranks is the slowest ÷ mean over the run.
    pub work_slowest: u64,
    pub work_total: u64,
    /// The times the boxes were cut again.
    pub recuts: u64,
    /// Weighing by time: the busiest rank's busy time and all ranks', ns, each summed over
    /// the windows of measurement (their ratio times the ranks is the slowest ÷ mean).
    pub busy_slowest: u64,
    pub busy_total: u64,
    /// The time this rank spent in the communicator (sending, and waiting for the others), ns.
    pub waited: u64,
}

impl DomainStats {
    /// The slowest rank's work ÷ the mean over the run so far (1 if nothing was measured).
    pub fn imbalance(&self, ranks: usize) -> f64 {
        if self.work_total == 0 {
            1.0
        } else {
            self.work_slowest as f64 * ranks as f64 / self.work_total as f64
        }
    }

    /// The busiest rank's measured time ÷ the mean over the windows of measurement, weighing
    /// by time (none without a window).
    pub fn time_imbalance(&self, ranks: usize) -> Option<f64> {
        (self.busy_total > 0).then(|| self.busy_slowest as f64 * ranks as f64 / self.busy_total as f64)
    }
}

/// The weight in a cut by time of a unit of work on a rank as fast as the mean.
const WEIGHT_UNIT: u64 = 1024;
/// The mean busy time of a rank over which the ranks' times are compared, ns: long enough
/// that a few interruptions of a process do not decide a re-cut.
const MEASURED_NANOS: u64 = 200_000_000;

/// What a unit of work weighs in a cut by time on a rank that was busy `mine[0]` ns for
/// `mine[1]` units of work, where all ranks were busy `all[0]` ns for `all[1]`: its time per
/// unit relative to all ranks', in [`WEIGHT_UNIT`]s, within a factor 8 of the mean.
fn time_weight(mine: [u64; 2], all: [u64; 2]) -> u64 {
    let per_unit = |[ns, work]: [u64; 2]| ns as f64 / work.max(1) as f64;
    let relative = per_unit(mine) / per_unit(all).max(f64::MIN_POSITIVE);
    ((WEIGHT_UNIT as f64 * relative).round() as u64).clamp(WEIGHT_UNIT / 8, WEIGHT_UNIT * 8)
}

/// Words of a particle that moves to another rank (without its Adams–Bashforth history).
const MOVING: usize = GHOST + 6;
/// Words of a ghost as first sent, and of its refreshed state.
const GHOST: usize = 14;
const REFRESH: usize = 9;
/// Words of a contact gathered for output.
const CONTACT: usize = 13;

impl Simulation {
    /// Spreads the run over the ranks of `comm`, keeping on this rank the particles of its box
    /// and their ghosts. Every rank must call it with the same simulation (as set up from the
    /// same case), before the first step. At rebuilds the boxes are cut again when the slowest
    /// rank's work exceeds the mean by more than the fraction `rebalance` (none: never).
    pub fn decompose(&mut self, comm: Arc<dyn Comm>, rebalance: Option<f64>) -> Result<(), EngineError> {
        let refuse = |what: &str| {
            Err(EngineError::BadReference(format!("{what} cannot yet run on more than one rank")))
        };
        if self.domain.is_some() {
            return refuse("a run already spread over ranks");
        }
        if self.kick_pending || self.particles.len() != self.slot_count {
            return Err(EngineError::BadReference(
                "internal error: a simulation is spread over ranks between the stages of a step".into(),
            ));
        }
        let counts = comm.all_gather(&[self.particles.len() as u64, self.step]);
        if counts.iter().any(|c| c[..] != counts[0][..]) {
            return Err(EngineError::BadReference(
                "the ranks were given different simulations to spread over them".into(),
            ));
        }
        if !self.neighbors.is_built() {
            self.neighbors.build(&self.particles, &self.walls);
        }
        let boxes = self.cut(comm.size(), None);
        let id = &self.particles.id;
        let rules: Vec<RuleById> = self
            .motion
            .iter()
            .map(|r| RuleById { id: id[r.slot], leader: r.leader.map(|l| id[l]), rule: *r })
            .collect();
        let reach = 2.0 * self.r_max() + self.neighbors.skin();
        self.spread_with(comm, rebalance, (rules, boxes, reach), true);
        Ok(())
    }

    /// Spreads a run set up from each rank's share of the particles ([`Simulation::
    /// new_over_ranks`]): the boxes are cut for the particles as they are spread, and the
    /// particles move to the ranks of their boxes. `rules` are every rank's motion rules by
    /// ids, in the case's order. Collective.
    pub(super) fn spread_share(
        &mut self,
        comm: Arc<dyn Comm>,
        rebalance: Option<f64>,
        rules: Vec<RuleById>,
    ) -> Result<(), EngineError> {
        let boxes = self.cut(comm.size(), Some(&*comm));
        let reach = 2.0 * super::whole::Whole(Some(&*comm)).max(self.r_max()) + self.neighbors.skin();
        self.spread_with(comm, rebalance, (rules, boxes, reach), false);
        Ok(())
    }

    /// Takes this rank's part in `boxes`, with ghosts within `reach` of it (with `initial`,
    /// every rank holds every particle).
    fn spread_with(
        &mut self,
        comm: Arc<dyn Comm>,
        rebalance: Option<f64>,
        (rules, boxes, reach): (Vec<RuleById>, Boxes, f64),
        initial: bool,
    ) {
        let history = !self.particles.accel_prev.is_empty();
        let ranks = comm.size();
        let timed = Arc::new(crate::domain::Timed::new(comm));
        let comm: Arc<dyn Comm> = timed.clone();
        let mut leaders: Vec<u32> = rules.iter().filter_map(|r| r.leader).collect();
        leaders.sort_unstable();
        leaders.dedup();
        self.domain = Some(Box::new(Decomposition {
            comm,
            boxes,
            owned: self.particles.len(),
            sends: vec![Vec::new(); ranks],
            ghosts: vec![0..0; ranks],
            reach,
            history,
            stats: DomainStats::default(),
            stale: false,
            rule_of: rules.iter().enumerate().map(|(k, r)| (r.id, k)).collect(),
            rules,
            leaders,
            threshold: rebalance,
            since: self.step,
            timed,
            by_time: false,
            busy: 0,
            window_work: 0,
            weight: 1,
        }));
        let rank = self.domain.as_ref().map_or(0, |d| d.comm.rank());
        self.redistribute(initial, 0..0);
        // Each rank keeps the caught particles of its own, and rank 0 the outlets' books.
        let mut own: Vec<u32> = self.particles.id[..self.owned()].to_vec();
        own.sort_unstable();
        self.flow.keep_rank_part(&own, rank);
    }

    /// Whether `yes` holds on any rank (`yes` in one process). Collective on ranks.
    pub(super) fn on_any_rank(&self, yes: bool) -> bool {
        match &self.domain {
            None => yes,
            Some(d) => d.comm.all_gather(&[yes as u64]).iter().any(|w| w[0] != 0),
        }
    }

    /// Every rank's particles (ghosts left out) in id order, as (ids, positions, radii), on
    /// every rank; with `near` = (lo, hi, reach), only those whose centres come within reach
    /// and their radius of the box lo..hi (all of them on a periodic run, whose images wrap).
    /// `None` in one process. Collective on ranks.
    #[allow(clippy::type_complexity)]
    pub(super) fn particles_near(
        &self,
        near: Option<(Vec3, Vec3, f64)>,
    ) -> Option<(Vec<u32>, Vec<Vec3>, Vec<f64>)> {
        let d = self.domain.as_ref()?;
        let p = &self.particles;
        let close = |i: usize| match near {
            Some((lo, hi, reach)) if !self.periodic.any() => {
                let r = Vec3::splat(reach + p.radius[i]);
                let x = p.position[i];
                x.cmpge(lo - r).all() && x.cmple(hi + r).all()
            }
            _ => true,
        };
        let mut mine = Vec::new();
        for i in (0..d.owned).filter(|&i| close(i)) {
            mine.extend([p.id[i] as u64, p.radius[i].to_bits()]);
            push_vecs(&mut mine, &[p.position[i]]);
        }
        let mut all: Vec<(u32, Vec3, f64)> = Vec::new();
        for words in d.comm.all_gather(&mine) {
            for w in words.chunks_exact(5) {
                all.push((w[0] as u32, vec_at(w, 2), f64::from_bits(w[1])));
            }
        }
        all.sort_unstable_by_key(|e| e.0);
        Some((
            all.iter().map(|e| e.0).collect(),
            all.iter().map(|e| e.1).collect(),
            all.iter().map(|e| e.2).collect(),
        ))
    }

    /// [`insert`](Simulation::insert) on ranks: every rank checks all of `new` (a refusal is
    /// every rank's), appends those in its box and lays out its slots again, the list built
    /// as one process builds it after an insertion.
    pub(super) fn insert_over_ranks(&mut self, new: &[ParticleInit]) -> Result<(), EngineError> {
        let Some(d) = &self.domain else { return self.append_new(new) };
        self.check_new(new)?;
        let (me, per) = (d.comm.rank(), self.periodic);
        // A particle outside every box (which only a non-finite position is) goes to rank 0.
        let mine: Vec<ParticleInit> =
            new.iter().filter(|q| d.boxes.owner(per.wrap(q.position)).unwrap_or(0) == me).copied().collect();
        let before = self.particles.len();
        self.append_new(&mine)?;
        self.redistribute(false, before..self.particles.len());
        Ok(())
    }

    /// Removes the particles `mine` of this rank's own (ids) and, on every rank, the ghosts
    /// of those the others remove, keeping the slots' layout and the list as it is, as one
    /// process removes them; returns how many were removed over all ranks. Collective.
    pub(super) fn remove_over_ranks(&mut self, mine: &[u32]) -> Result<usize, EngineError> {
        let Some(d) = self.domain.as_mut() else {
            return Err(EngineError::BadReference(
                "internal error: a removal over ranks in one process".into(),
            ));
        };
        let words: Vec<u64> = mine.iter().map(|&id| id as u64).collect();
        let mut gone: Vec<u32> = d.comm.all_gather(&words).into_iter().flatten().map(|w| w as u32).collect();
        if gone.is_empty() {
            return Ok(0);
        }
        gone.sort_unstable();
        // Refused alike on every rank, before anything changes.
        if let Some(id) =
            gone.iter().find(|id| d.rule_of.contains_key(id) || d.leaders.binary_search(id).is_ok())
        {
            return Err(EngineError::BadReference(format!(
                "particle {id} is under prescribed motion (or leads a particle that is): it cannot be removed"
            )));
        }
        let p = &self.particles;
        let n = p.len();
        let order: Vec<usize> = (0..n).filter(|&i| gone.binary_search(&p.id[i]).is_err()).collect();
        let mut new_of = vec![u32::MAX; n];
        for (k, &i) in order.iter().enumerate() {
            new_of[i] = k as u32;
        }
        let before = |s: usize| order.partition_point(|&i| i < s);
        d.owned = before(d.owned);
        for sends in &mut d.sends {
            sends.retain(|&i| new_of[i as usize] != u32::MAX);
            sends.iter_mut().for_each(|i| *i = new_of[*i as usize]);
        }
        for g in &mut d.ghosts {
            *g = before(g.start)..before(g.end);
        }
        let owned = d.owned;
        self.rearrange(&order)?;
        self.neighbors.set_ghosts_from(Some(owned));
        // The remaining particles' forces are those with the removed ones.
        self.forces_current = false;
        Ok(gone.len())
    }

    /// The number of this rank's own particles (slots `0..owned()`; ghosts follow): all of
    /// them in one process.
    pub fn owned(&self) -> usize {
        self.domain.as_ref().map_or(self.particles.len(), |d| d.owned)
    }

    /// The triangles of the meshes this rank bins (over ranks, the fixed meshes' near its box
    /// alone), summed over the meshes.
    pub fn binned_triangles(&self) -> usize {
        self.sources.meshes.binned_triangles()
    }

    /// What this rank has sent to the others so far (zeros in one process).
    pub fn domain_stats(&self) -> DomainStats {
        self.domain
            .as_ref()
            .map_or_else(DomainStats::default, |d| DomainStats { waited: d.timed.nanos(), ..d.stats })
    }

    /// What decides the re-cuts of a run spread over ranks (see [`Weigh`]); work by default.
    /// Every rank must call it alike.
    pub fn weigh_ranks_by(&mut self, weigh: Weigh) {
        if let Some(d) = self.domain.as_mut() {
            d.by_time = weigh == Weigh::Time;
        }
    }

    /// The communicator of a run spread over ranks (`None` in one process): for callers that
    /// must agree across the ranks (which problem to report, say). Collective calls on it must
    /// be made by every rank at the same point.
    pub fn comm(&self) -> Option<&Arc<dyn Comm>> {
        self.domain.as_ref().map(|d| &d.comm)
    }

    /// The particles of every rank (ghosts left out). Collective.
    pub fn total_particles(&self) -> usize {
        match &self.domain {
            None => self.particles.len(),
            Some(d) => d.comm.all_gather(&[d.owned as u64]).iter().map(|w| w[0] as usize).sum(),
        }
    }

    /// The ranks the run is spread over (1 in one process).
    pub fn ranks(&self) -> usize {
        self.domain.as_ref().map_or(1, |d| d.comm.size())
    }

    /// Every rank's particles (ghosts left out) in id order, on every rank: what outputs
    /// write, the same however the run is spread. Collective: every rank must call it.
    pub fn gathered_in_id_order(&self) -> Particles {
        self.gathered(true)
    }

    /// [`gathered_in_id_order`](Self::gathered_in_id_order) on rank 0 alone (the others get
    /// none): what output files are written from, without a copy of every particle on every
    /// rank. Collective.
    pub fn gathered_on_rank_0(&self) -> Particles {
        self.gathered(false)
    }

    /// The particles in id order, on every rank or (`everyone` false) on rank 0 alone.
    fn gathered(&self, everyone: bool) -> Particles {
        let p = &self.particles;
        let all = match &self.domain {
            None => p.clone(),
            Some(d) => {
                let mut mine = Vec::with_capacity(d.owned * d.moving());
                for i in 0..d.owned {
                    d.push_moving(&mut mine, p, i);
                }
                let mut all = Particles::default();
                for words in d.to(everyone, mine) {
                    let mut at = 0;
                    while at < words.len() {
                        d.read_moving(&words, &mut at, &mut all);
                    }
                }
                all
            }
        };
        all.gathered(&all.id_order())
    }

    /// [`in_id_order`](Simulation::in_id_order) over every rank: the particles and the
    /// contacts of the whole run in id order, on every rank (a contact's slots are those of
    /// the returned particles). Collective: every rank must call it.
    pub fn gathered_in_id_order_with_contacts(&self) -> (Particles, Vec<ContactInfo>) {
        self.gathered_with_contacts(true)
    }

    /// [`gathered_in_id_order_with_contacts`](Self::gathered_in_id_order_with_contacts) on
    /// rank 0 alone (the others get none). Collective.
    pub fn gathered_on_rank_0_with_contacts(&self) -> (Particles, Vec<ContactInfo>) {
        self.gathered_with_contacts(false)
    }

    fn gathered_with_contacts(&self, everyone: bool) -> (Particles, Vec<ContactInfo>) {
        let Some(d) = &self.domain else { return self.in_id_order() };
        let all = self.gathered(everyone);
        let p = &self.particles;
        let mut mine = Vec::new();
        for c in self.contacts() {
            let (kind, a, b) = match c.other {
                ContactPartner::Wall(w) => (0, w as u64, 0),
                ContactPartner::Mesh { mesh, triangle } => (1, mesh as u64, triangle as u64),
                ContactPartner::Cylinder(m) => (2, m as u64, 0),
                ContactPartner::Particle(j) => (3, p.id[j] as u64, 0),
            };
            mine.extend([p.id[c.particle] as u64, kind, a, b]);
            push_vecs(&mut mine, &[c.point, c.normal]);
            mine.extend([c.overlap.to_bits(), c.normal_force.to_bits(), c.tangential_force.to_bits()]);
        }
        let slot = |id: u64| all.id.binary_search(&(id as u32)).unwrap_or(usize::MAX);
        let mut contacts = Vec::new();
        for words in d.to(everyone, mine) {
            for w in words.chunks_exact(CONTACT) {
                let other = match w[1] {
                    0 => ContactPartner::Wall(w[2] as usize),
                    1 => ContactPartner::Mesh { mesh: w[2] as usize, triangle: w[3] as usize },
                    2 => ContactPartner::Cylinder(w[2] as usize),
                    _ => ContactPartner::Particle(slot(w[2])),
                };
                contacts.push(ContactInfo {
                    particle: slot(w[0]),
                    other,
                    point: vec_at(w, 4),
                    normal: vec_at(w, 7),
                    overlap: f64::from_bits(w[10]),
                    normal_force: f64::from_bits(w[11]),
                    tangential_force: f64::from_bits(w[12]),
                });
            }
        }
        contacts.sort_unstable_by_key(super::contact_order);
        (all, contacts)
    }

    /// The boxes of `ranks` ranks for the particles as they are, weighted by 1 + their
    /// partners in the list; the outer faces pushed to infinity on axes that do not wrap, so
    /// that every particle has an owner. With `comm`, each rank cuts its own particles with
    /// the others (collective); without, the particles held here (every rank's, alike).
    fn cut(&self, ranks: usize, comm: Option<&dyn Comm>) -> Boxes {
        let p = &self.particles;
        let per = self.periodic;
        let n = if comm.is_some() { self.owned() } else { p.len() };
        let mut work = vec![1u64; n];
        for [a, b] in self.neighbors.pairs() {
            for s in [a as usize, b as usize] {
                if s < n {
                    work[s] += 1;
                }
            }
        }
        let weight = self.domain.as_ref().filter(|_| comm.is_some()).map_or(1, |d| d.weight);
        let items: Vec<Weighted> = (0..n)
            .map(|i| Weighted {
                position: per.wrap(p.position[i]),
                work: work[i] * weight,
                id: p.id[i] as u64,
            })
            .filter(|w| w.position.is_finite())
            .collect();
        boxes_for(&items, per, ranks, comm)
    }
}

/// The rank each of a run's particles, all held here, starts on: the boxes the ranks cut for
/// them at their set-up ([`Simulation::new_over_ranks`]), every particle weighing alike; above
/// 2²⁰ particles, boxes cut for an even sample of them (within a few particles of those: the
/// set-up moves those few). Handing the particles out so spares them the first migration.
pub fn starting_ranks(p: &Particles, periodic: Option<Periodic>, ranks: usize) -> Vec<u32> {
    let per = periodic.unwrap_or_default();
    let stride = p.len().div_ceil(1 << 20).max(1);
    let items: Vec<Weighted> = (0..p.len())
        .step_by(stride)
        .map(|i| Weighted { position: per.wrap(p.position[i]), work: 1, id: p.id[i] as u64 })
        .filter(|w| w.position.is_finite())
        .collect();
    let boxes = boxes_for(&items, per, ranks, None);
    drop(items);
    p.position.iter().map(|&x| boxes.owner(per.wrap(x)).unwrap_or(0) as u32).collect()
}

/// The boxes of `ranks` ranks for `items` (see [`Simulation::cut`]).
fn boxes_for(items: &[Weighted], per: Periodic, ranks: usize, comm: Option<&dyn Comm>) -> Boxes {
    let (mut lo, mut hi) =
        items.iter().fold((Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)), |(l, h), w| {
            (l.min(w.position), h.max(w.position))
        });
    if let Some(comm) = comm {
        let mut mine = Vec::with_capacity(6);
        push_vecs(&mut mine, &[lo, hi]);
        for w in comm.all_gather(&mine) {
            (lo, hi) = (lo.min(vec_at(&w, 0)), hi.max(vec_at(&w, 3)));
        }
    }
    if !lo.is_finite() || !hi.is_finite() {
        (lo, hi) = (Vec3::ZERO, Vec3::ZERO);
    }
    for k in 0..3 {
        if per.axes[k] {
            lo[k] = per.lo[k];
            hi[k] = per.hi[k];
        }
    }
    let mut boxes = match comm {
        None => crate::domain::bisect(lo, hi, items, ranks),
        Some(comm) => crate::domain::bisect_over(lo, hi, items, ranks, &mut |counts| {
            let all = comm.all_gather(&counts);
            (0..counts.len()).map(|k| all.iter().map(|c| c[k]).sum()).collect()
        }),
    };
    let far = |v: f64, edge: f64, sign: f64| if v == edge { sign * f64::INFINITY } else { v };
    for b in &mut boxes.boxes {
        for k in (0..3).filter(|&k| !per.axes[k]) {
            b[0][k] = far(b[0][k], lo[k], -1.0);
            b[1][k] = far(b[1][k], hi[k], 1.0);
        }
    }
    for k in (0..3).filter(|&k| !per.axes[k]) {
        boxes.domain[0][k] = f64::NEG_INFINITY;
        boxes.domain[1][k] = f64::INFINITY;
    }
    boxes
}

impl Simulation {
    /// The domain stage before a force evaluation: the ranks decide together whether the list
    /// is due; if so the particles move to their boxes' ranks and the lists are built again,
    /// else the ghosts take their owners' new state.
    pub(super) fn domain_stage(&mut self) {
        let Some(d) = self.domain.as_ref() else { return };
        let moved = self.neighbors.any_moved(&self.particles.position[..d.owned]);
        let due = d.comm.all_gather(&[moved as u64]).iter().any(|w| w[0] != 0);
        if due {
            self.balance();
            self.redistribute(false, 0..0);
        } else if self.drifted || d.stale {
            // The particles moved since the ghosts were last refreshed (velocity Verlet's
            // drift, or a step whose end left them behind).
            self.refresh_ghosts();
        }
    }

    /// At a rebuild, before the particles move: each rank's work (its particles and their
    /// partners in the list, over the steps since the last rebuild) is recorded, and if the
    /// slowest rank's exceeds the mean by more than the threshold the boxes are cut again, for
    /// the particles as they are (they then move to their new boxes). Collective.
    fn balance(&mut self) {
        let Some(d) = self.domain.as_ref() else { return };
        let owned = d.owned;
        let mut work = owned as u64;
        for [a, b] in self.neighbors.pairs() {
            work += ((a as usize) < owned) as u64 + ((b as usize) < owned) as u64;
        }
        let steps = self.step - d.since;
        let window_work = d.window_work + steps * work;
        let all = d.comm.all_gather(&[work, d.busy, window_work]);
        let sum_max =
            |k: usize| (all.iter().map(|w| w[k]).sum::<u64>(), all.iter().map(|w| w[k]).max().unwrap_or(0));
        let ((total, slowest), (busy, busiest), (total_window, _)) = (sum_max(0), sum_max(1), sum_max(2));
        let ranks = all.len() as u64;
        // A window of measured time closes once the ranks were busy long enough on average.
        let measured = d.by_time && busy >= MEASURED_NANOS * ranks;
        let over = |most: u64, sum: u64, t: f64| (most * ranks) as f64 > (1.0 + t) * sum as f64;
        let recut = d.threshold.is_some_and(|t| {
            if d.by_time { measured && over(busiest, busy, t) } else { over(slowest, total, t) }
        });
        // By time, a unit of work weighs as this rank's time per unit relative to all ranks'.
        let weight = (recut && d.by_time).then(|| {
            let mine = &all[d.comm.rank()];
            time_weight([mine[1], mine[2]], [busy, total_window])
        });
        let comm = d.comm.clone();
        let step = self.step;
        if let (Some(w), Some(d)) = (weight, self.domain.as_mut()) {
            d.weight = w;
        }
        let boxes = recut.then(|| self.cut(ranks as usize, Some(&*comm)));
        let Some(d) = self.domain.as_mut() else { return };
        d.since = step;
        d.stats.work_slowest += steps * slowest;
        d.stats.work_total += steps * total;
        // Counting work, no window is kept.
        (d.busy, d.window_work) = if measured || !d.by_time { (0, 0) } else { (d.busy, window_work) };
        if measured {
            d.stats.busy_slowest += busiest;
            d.stats.busy_total += busy;
        }
        if let Some(boxes) = boxes {
            d.boxes = boxes;
            d.stats.recuts += 1;
        }
    }

    /// Adds a step's time less its waits to this rank's busy time.
    pub(super) fn count_busy(&mut self, from: Option<(std::time::Instant, u64)>) {
        if let (Some((t, waited)), Some(d)) = (from, self.domain.as_mut()) {
            let spent = t.elapsed().as_nanos() as u64;
            d.busy += spent.saturating_sub(d.timed.nanos() - waited);
        }
    }

    /// When this step starts, for [`count_busy`](Self::count_busy).
    pub(super) fn busy_from(&self) -> Option<(std::time::Instant, u64)> {
        self.domain.as_ref().map(|d| (std::time::Instant::now(), d.timed.nanos()))
    }

    /// Cuts the boxes again for the particles as they are; they move to their new boxes at
    /// the next rebuild. Collective.
    pub(super) fn cut_again(&mut self) {
        let Some(comm) = self.domain.as_ref().map(|d| d.comm.clone()) else { return };
        let boxes = self.cut(comm.size(), Some(&*comm));
        if let Some(d) = self.domain.as_mut() {
            d.boxes = boxes;
        }
    }

    /// Marks the ghosts of held particles in `held` (slots of this rank).
    pub(super) fn mark_held_ghosts(&self, held: &mut [bool]) {
        if let Some(d) = self.domain.as_ref().filter(|d| !d.rules.is_empty()) {
            for (i, h) in held.iter_mut().enumerate().skip(d.owned) {
                *h = d.rule_of.get(&self.particles.id[i]).is_some_and(|&k| !d.rules[k].rule.follows());
            }
        }
    }

    /// Puts the prescribed particles where their rules say, at rest ([`crate::motion::apply`]);
    /// returns whether that changed any (on this rank). Spread over ranks with rules that
    /// follow a leader, every rank gathers the leaders' positions from their owners and
    /// replays all the rules in the case's order, as one process applies them (a leader
    /// under a rule that comes first is where that rule put it); each then puts its own.
    /// Collective then.
    pub(super) fn apply_motion(&mut self) -> bool {
        let Some(d) = self.domain.as_ref().filter(|d| !d.leaders.is_empty()) else {
            return crate::motion::apply(&self.motion, &mut self.particles);
        };
        let p = &self.particles;
        let mut mine = Vec::new();
        for i in (0..d.owned).filter(|&i| d.leaders.binary_search(&p.id[i]).is_ok()) {
            mine.push(p.id[i] as u64);
            push_vecs(&mut mine, &[p.position[i]]);
        }
        let mut at: Vec<(u32, Vec3)> = d
            .comm
            .all_gather(&mine)
            .iter()
            .flat_map(|w| w.chunks_exact(4))
            .map(|w| (w[0] as u32, vec_at(w, 1)))
            .collect();
        at.sort_unstable_by_key(|e| e.0);
        let mut target = Vec::with_capacity(d.rules.len());
        for r in &d.rules {
            let lead = r.leader.and_then(|l| at.binary_search_by_key(&l, |e| e.0).ok()).map(|k| at[k].1);
            let x = r.rule.target(lead.unwrap_or(r.rule.anchor()));
            if let Ok(k) = at.binary_search_by_key(&r.id, |e| e.0) {
                at[k].1 = x;
            }
            target.push(x);
        }
        let mut changed = false;
        for r in &self.motion {
            let k = d.rule_of[&self.particles.id[r.slot]];
            changed |= crate::motion::put(&mut self.particles, r.slot, target[k]);
        }
        changed
    }

    /// Whether prescribed motion moved a particle on any rank, given whether it did on this
    /// one (every rank then evaluates the forces again, or none).
    pub(super) fn moved_on_any_rank(&self, moved: bool) -> bool {
        match self.domain.as_ref().filter(|d| !d.rules.is_empty()) {
            Some(d) => d.comm.all_gather(&[moved as u64]).iter().any(|w| w[0] != 0),
            None => moved,
        }
    }

    /// At the end of a step: the ghosts take their owners' new state, so that between steps
    /// (for diagnostics, contacts and the next evaluation) every ghost equals its particle.
    /// With `more` (another step of the same `advance` follows, which nobody looks at before),
    /// they are only marked as lagging, for the next evaluation to refresh.
    pub(super) fn end_of_step_ghosts(&mut self, more: bool) {
        match self.domain.as_mut() {
            Some(d) if more => d.stale = true,
            Some(_) => self.refresh_ghosts(),
            None => {}
        }
    }

    /// Sends every rank the new positions, velocities and spins of the ghosts it holds of
    /// this rank's particles, and takes this rank's ghosts' from their owners.
    fn refresh_ghosts(&mut self) {
        let Some(d) = self.domain.as_mut() else { return };
        d.stale = false;
        let p = &mut self.particles;
        let out = d
            .sends
            .iter()
            .map(|slots| {
                let mut w = Vec::with_capacity(slots.len() * REFRESH);
                for &i in slots {
                    let i = i as usize;
                    push_vecs(&mut w, &[p.position[i], p.velocity[i], p.omega[i]]);
                }
                w
            })
            .collect();
        for (words, slots) in d.exchange(out).iter().zip(&d.ghosts) {
            for (k, i) in slots.clone().enumerate() {
                let w = &words[k * REFRESH..(k + 1) * REFRESH];
                p.position[i] = vec_at(w, 0);
                p.velocity[i] = vec_at(w, 3);
                p.omega[i] = vec_at(w, 6);
            }
        }
    }

    /// The wall histories of the list that are not zero, as (id, wall, history, slot).
    fn histories_by_id_of_walls(&self) -> Vec<(u32, u32, Vec3, u32)> {
        let (p, nl) = (&self.particles, &self.neighbors);
        nl.wall_pairs()
            .iter()
            .zip(nl.wall_history())
            .filter(|(_, h)| nonzero(**h))
            .map(|(&[i, w], &h)| (p.id[i as usize], w, h, i))
            .collect()
    }

    /// The whole run as one process would hold it, on rank 0 (`None` on the others; in one
    /// process a copy): every rank's particles in id order with their pair, wall and other
    /// sources' histories, the list built afresh. What a checkpoint of a run over ranks is
    /// written from; restored on any number of ranks it goes on with the same bits.
    /// Collective: every rank must call it.
    pub fn gathered_whole(&self) -> Option<Simulation> {
        if self.domain.is_none() {
            return Some(self.clone());
        }
        let mut mine = Vec::new();
        self.part_into(&mut |w| mine.extend_from_slice(w));
        self.whole_from_parts(mine)
    }

    /// This rank's part of the whole run, as [`whole_from_parts`](Self::whole_from_parts)
    /// takes it, a few words at a time into `emit` (so that it can go to a file without a
    /// copy in memory): its particles, and the histories of their contacts by ids —
    /// `[particles, particle words.., pairs, pair words.., walls, wall words.., flow words..,
    /// per source: length, records..]`. A pair across two ranks comes from both, the same
    /// bits. Nothing in one process.
    pub fn part_into(&self, emit: &mut dyn FnMut(&[u64])) {
        let Some(d) = &self.domain else { return };
        let (owned, p) = (d.owned, &self.particles);
        emit(&[owned as u64]);
        let mut buf = Vec::with_capacity(4096);
        let flush = |buf: &mut Vec<u64>, emit: &mut dyn FnMut(&[u64]), at_least: usize| {
            if buf.len() >= at_least {
                emit(buf);
                buf.clear();
            }
        };
        for i in 0..owned {
            d.push_moving(&mut buf, p, i);
            flush(&mut buf, emit, 4000);
        }
        flush(&mut buf, emit, 0);
        // Twice over the list (a count, then the pairs), rather than a copy of the pairs.
        let mine = |&([a, b], _): &([u32; 2], Vec3)| (a as usize) < owned || (b as usize) < owned;
        emit(&[self.neighbors.each_pair_with_history().filter(mine).count() as u64]);
        for ([a, b], h) in self.neighbors.each_pair_with_history().filter(mine) {
            let (ids, _, h) = by_ids(p, [a, b], h);
            push_history(&mut buf, ids, h);
            flush(&mut buf, emit, 4000);
        }
        flush(&mut buf, emit, 0);
        let walls: Vec<_> =
            self.histories_by_id_of_walls().into_iter().filter(|w| (w.3 as usize) < owned).collect();
        buf.push(walls.len() as u64);
        for &(id, w, h, _) in &walls {
            push_history(&mut buf, [id, w], h);
        }
        buf.extend(self.flow.rank_words());
        for (words, records) in self.sources.carry() {
            let kept: Vec<&[u64]> =
                records.chunks_exact(words.max(1)).filter(|r| (r[0] as usize) < owned).collect();
            buf.push((kept.len() * words) as u64);
            for r in kept {
                buf.push(p.id[r[0] as usize] as u64);
                buf.extend_from_slice(&r[1..]);
            }
        }
        emit(&buf);
    }

    /// A copy of this simulation without its particles, list and per-slot facts: what
    /// [`whole_from_parts`](Self::whole_from_parts) needs of the run at a step (its time,
    /// books, motion rules and settings), kept beside the parts of that step at little cost.
    pub fn skeleton(&mut self) -> Simulation {
        let particles = std::mem::take(&mut self.particles);
        let light = self.neighbors.emptied();
        let neighbors = std::mem::replace(&mut self.neighbors, light);
        let held = std::mem::take(&mut self.held);
        let bare = self.clone();
        (self.particles, self.neighbors, self.held) = (particles, neighbors, held);
        bare
    }

    /// The whole run as one process would hold it, on rank 0 (`None` on the others), from
    /// every rank's part of it (`mine`: this rank's, from [`part_into`](Self::part_into) at
    /// the step of this simulation or of its [`skeleton`](Self::skeleton)). Collective.
    pub fn whole_from_parts(&self, mine: Vec<u64>) -> Option<Simulation> {
        let Some(d) = &self.domain else { return Some(self.clone()) };
        let (me, ranks) = (d.comm.rank(), d.comm.size());
        let mut out = vec![Vec::new(); ranks];
        out[0] = mine;
        let got = d.comm.exchange(out);
        if me != 0 {
            return None;
        }
        let mut all = Particles::default();
        let mut table: HashMap<[u32; 2], Vec3> = HashMap::new();
        let mut wall_table: Vec<(u32, u32, Vec3)> = Vec::new();
        let mut records: Vec<Vec<u64>> = Vec::new();
        let mut flow = self.flow.clone();
        flow.clear_rank_part();
        for words in &got {
            let mut at = 1;
            for _ in 0..words[0] {
                d.read_moving(words, &mut at, &mut all);
            }
            for k in 0..words[at] as usize {
                let (ids, h) = read_history(&words[at + 1 + 5 * k..]);
                table.entry(ids).or_insert(h);
            }
            at += 1 + 5 * words[at] as usize;
            for k in 0..words[at] as usize {
                let ([id, w], h) = read_history(&words[at + 1 + 5 * k..]);
                wall_table.push((id, w, h));
            }
            at += 1 + 5 * words[at] as usize;
            at += flow.add_rank_words(&words[at..]);
            for k in 0.. {
                if at == words.len() {
                    break;
                }
                let len = words[at] as usize;
                if records.len() <= k {
                    records.push(Vec::new());
                }
                records[k].extend_from_slice(&words[at + 1..at + 1 + len]);
                at += 1 + len;
            }
        }
        let all = all.gathered(&all.id_order());
        let slot = |id: u32| all.id.binary_search(&id).expect("a gathered particle") as u32;
        let mut list = NeighborState { skin: self.neighbors.skin(), built: false, ..Default::default() };
        // In id order, so that the whole does not depend on how the run was spread.
        let mut table: Vec<_> = table.into_iter().collect();
        table.sort_unstable_by_key(|e| e.0);
        for (ids, h) in table {
            list.pairs.push([slot(ids[0]), slot(ids[1])]);
            list.pair_history.push(h);
        }
        wall_table.sort_unstable_by_key(|e| (e.0, e.1));
        for (id, w, h) in wall_table {
            list.wall_pairs.push([slot(id), w]);
            list.wall_history.push(h);
        }
        // In the case's order: a checkpoint lists the rules' anchors so.
        let motion =
            d.rules.iter().map(|r| r.rule.at_slots(slot(r.id) as usize, r.leader.map(|l| slot(l) as usize)));
        let mut whole = self.clone();
        whole.flow = flow;
        whole.motion = motion.collect();
        whole.domain = None;
        let n = all.len();
        whole.particles = all;
        whole.common = None;
        let broken =
            |e: String| panic!("internal error: the gathered histories do not fit the particles: {e}");
        whole.neighbors.set_state(list, n, whole.walls.len()).unwrap_or_else(broken);
        whole.sources.take_carried(&whole.particles.id, &records).unwrap_or_else(broken);
        whole.derive_slot_facts();
        whole.neighbors.set_ghosts_from(None);
        whole.neighbors.build_on(&whole.particles, &whole.walls, false);
        // As one process keeps them (and a restart lays them out): the held particles last.
        whole.put_prescribed_last().unwrap_or_else(|e| broken(e.to_string()));
        whole.common();
        Some(whole)
    }

    /// Moves every particle to the rank of its box with its pair and wall histories (and the
    /// outlet that caught it), chooses the ghosts again and builds the list. With `initial`,
    /// every rank holds every particle (the set-up's), so none has to travel; `extra` are
    /// slots after the ghosts that are this rank's own too (particles just inserted).
    fn redistribute(&mut self, initial: bool, extra: Range<usize>) {
        let Some(mut d) = self.domain.take() else { return };
        let (me, ranks) = (d.comm.rank(), d.comm.size());
        let per = self.periodic;
        let owned_before = if initial { self.particles.len() } else { d.owned };
        // Whether this rank lays its own particles out along the space-filling curve again
        // (the results do not depend on their order): at the start, then as the rule says.
        let resort = self.sort.rule != ResortRule::Never && (initial || self.resort_due());
        let cell = self.cell_size();
        let p = &self.particles;
        // Each own slot's rank; a ghost's is none.
        const NONE: usize = usize::MAX;
        let dest: Vec<usize> = (0..p.len())
            .map(|i| {
                if i < owned_before || extra.contains(&i) {
                    d.boxes.owner_near(per.wrap(p.position[i]), me).unwrap_or(me)
                } else {
                    NONE
                }
            })
            .collect();
        let leaves = |i: usize| dest[i] != me && dest[i] != NONE;
        // Only the histories that travel need their particles' ids.
        let walls = self.histories_by_id_of_walls();
        // The other sources' histories, by ids, kept here or sent with their particles.
        let carried = self.sources.carry();
        let mut kept_records: Vec<Vec<u64>> = vec![Vec::new(); carried.len()];
        let mut sent_records: Vec<Vec<Vec<u64>>> = vec![vec![Vec::new(); carried.len()]; ranks];
        for (k, (words, records)) in carried.iter().enumerate() {
            for r in records.chunks_exact((*words).max(1)) {
                let slot = r[0] as usize;
                let to = match dest[slot] {
                    NONE => continue,
                    r if r == me => &mut kept_records[k],
                    r => &mut sent_records[r][k],
                };
                to.push(p.id[slot] as u64);
                to.extend_from_slice(&r[1..]);
            }
        }
        // The histories that arrive with particles, by ids (pairs, then walls).
        let mut arrived: Vec<([u32; 2], Vec3)> = Vec::new();
        let mut wall_arrived: Vec<(u32, u32, Vec3)> = Vec::new();
        let kept: Vec<usize> = (0..p.len()).filter(|&i| dest[i] == me).collect();
        let old_ids = p.id.clone();
        let mut outgoing = None;
        if !initial {
            // The particles that left this box, each followed by its histories.
            let mut out: Vec<Vec<u64>> = vec![Vec::new(); ranks];
            let mut count = vec![0usize; ranks];
            let mut caught: Vec<Vec<u64>> = vec![Vec::new(); ranks];
            for i in (0..p.len()).filter(|&i| leaves(i)) {
                d.push_moving(&mut out[dest[i]], p, i);
                count[dest[i]] += 1;
                d.stats.migrated += 1;
                if let Some(o) = self.flow.take_caught(p.id[i]) {
                    caught[dest[i]].extend([p.id[i] as u64, o as u64]);
                }
            }
            let mut histories: Vec<Vec<u64>> = vec![Vec::new(); ranks];
            self.neighbors.for_pairs_with_history(leaves, |[a, b], h| {
                let mut sent = usize::MAX;
                for s in [a as usize, b as usize] {
                    if leaves(s) && dest[s] != sent {
                        sent = dest[s];
                        let (ids, _, h) = by_ids(p, [a, b], h);
                        push_history(&mut histories[sent], ids, h);
                    }
                }
            });
            let mut wall_words: Vec<Vec<u64>> = vec![Vec::new(); ranks];
            for &(id, w, h, i) in &walls {
                if leaves(i as usize) {
                    push_history(&mut wall_words[dest[i as usize]], [id, w], h);
                }
            }
            for r in 0..ranks {
                let (pw, ww) = (std::mem::take(&mut histories[r]), std::mem::take(&mut wall_words[r]));
                let o = &mut out[r];
                let particles = std::mem::take(o);
                o.push(count[r] as u64);
                o.extend(particles);
                o.push((pw.len() / 5) as u64);
                o.extend(pw);
                o.push((ww.len() / 5) as u64);
                o.extend(ww);
                o.push((caught[r].len() / 2) as u64);
                o.append(&mut caught[r]);
                for records in std::mem::take(&mut sent_records[r]) {
                    o.push(records.len() as u64);
                    o.extend(records);
                }
            }
            outgoing = Some(out);
        }
        // The particles that stay, kept in place: the set is never held twice over.
        let mut next = std::mem::take(&mut self.particles);
        next.keep_slots(&kept.iter().map(|&i| i as u32).collect::<Vec<_>>());
        if let Some(out) = outgoing {
            for words in d.exchange(out) {
                if words.is_empty() {
                    continue;
                }
                let mut at = 1;
                for _ in 0..words[0] {
                    d.read_moving(&words, &mut at, &mut next);
                }
                let n_pairs = words[at] as usize;
                at += 1;
                for k in 0..n_pairs {
                    arrived.push(read_history(&words[at + 5 * k..]));
                }
                at += 5 * n_pairs;
                let n_walls = words[at] as usize;
                at += 1;
                for k in 0..n_walls {
                    let ([id, w], h) = read_history(&words[at + 5 * k..]);
                    wall_arrived.push((id, w, h));
                }
                at += 5 * n_walls;
                let n_caught = words[at] as usize;
                for c in words[at + 1..at + 1 + 2 * n_caught].chunks_exact(2) {
                    self.flow.put_caught(c[0] as u32, c[1] as u32);
                }
                at += 1 + 2 * n_caught;
                for records in &mut kept_records {
                    let len = words[at] as usize;
                    records.extend_from_slice(&words[at + 1..at + 1 + len]);
                    at += 1 + len;
                }
            }
        }
        // Each kept slot's new one (what the sources take).
        let mut new_of = vec![NO_SLOT; dest.len()];
        for (k, &i) in kept.iter().enumerate() {
            new_of[i] = k as u32;
        }
        if resort {
            let order = super::population::morton_order(&next.position, &next.id, cell);
            next = next.gathered(&order);
            let mut at = vec![NO_SLOT; order.len()];
            for (k, &i) in order.iter().enumerate() {
                at[i] = k as u32;
            }
            for s in new_of.iter_mut().filter(|s| **s != NO_SLOT) {
                *s = at[*s as usize];
            }
            self.sorted_now();
        }
        // The ghosts: each own particle to every rank whose box lies within reach.
        let owned = next.len();
        let mut near = Vec::new();
        let mut sends = vec![Vec::new(); ranks];
        let mut out: Vec<Vec<u64>> = vec![Vec::new(); ranks];
        for i in 0..owned {
            near.clear();
            d.boxes.ghost_ranks(per.wrap(next.position[i]), d.reach, me, &per, &mut near);
            near.sort_unstable_by_key(|e| e.0);
            near.dedup_by_key(|e| e.0);
            for &(r, _) in near.iter().filter(|e| e.0 != me) {
                sends[r].push(i as u32);
                push_ghost(&mut out[r], &next, i);
                d.stats.ghosts_sent += 1;
            }
        }
        let mut ghosts = vec![0..0; ranks];
        for (r, words) in d.exchange(out).into_iter().enumerate() {
            let start = next.len();
            for w in words.chunks_exact(GHOST) {
                read_ghost(w, &mut next, d.history);
            }
            ghosts[r] = start..next.len();
        }
        // The list's state under the new slots; pairs of two ghosts are left out. Unless laid
        // out again, the kept particles keep their order, so their pairs stay in list order:
        // a stable sort puts the few others among them, and keeps the pair held here before
        // one that arrived (the same bits: both ranks evaluated it).
        let slot_of = SlotsById::new(&next.id);
        // Every old slot's new one: the kept as above, the others by id, if held here again
        // (as a ghost, or one that left and came back).
        let mut new_of_old = new_of.clone();
        for (i, s) in new_of_old.iter_mut().enumerate().filter(|(_, s)| **s == NO_SLOT) {
            *s = slot_of.get(old_ids[i]);
        }
        let mut keyed: Vec<(u64, Vec3)> =
            Vec::with_capacity(self.neighbors.pair_contact_count() + arrived.len());
        let mut keep = |a: u32, b: u32, h: Vec3| {
            if a != NO_SLOT && b != NO_SLOT && ((a as usize) < owned || (b as usize) < owned) {
                keyed.push(if a < b { (pair_key(a, b), h) } else { (pair_key(b, a), -h) });
            }
        };
        self.neighbors.for_pairs_with_history(
            |_| true,
            |[a, b], h| {
                keep(new_of_old[a as usize], new_of_old[b as usize], h);
            },
        );
        for &([a, b], h) in &arrived {
            keep(slot_of.get(a), slot_of.get(b), h);
        }
        keyed.sort_by_key(|e| e.0);
        keyed.dedup_by_key(|e| e.0);
        let mut list = NeighborState { skin: self.neighbors.skin(), built: false, ..Default::default() };
        list.pairs = keyed.iter().map(|&(k, _)| [(k >> 32) as u32, k as u32]).collect();
        list.pair_history = keyed.into_iter().map(|e| e.1).collect();
        let walls_kept =
            walls.iter().filter(|w| dest[w.3 as usize] == me).map(|w| (new_of_old[w.3 as usize], w.1, w.2));
        let walls_arrived = wall_arrived.iter().map(|&(id, w, h)| (slot_of.get(id), w, h));
        for (i, w, h) in walls_kept.chain(walls_arrived).filter(|w| w.0 != NO_SLOT) {
            list.wall_pairs.push([i, w]);
            list.wall_history.push(h);
        }
        let n = next.len();
        next.force.resize(n, Vec3::ZERO);
        next.torque.resize(n, Vec3::ZERO);
        self.particles = next;
        if let Err(e) = self.neighbors.set_state(list, n, self.walls.len()) {
            // The state was made from a valid list: only a defect can break it.
            panic!("internal error: the ranks' histories do not fit the particles: {e}");
        }
        (d.owned, d.sends, d.ghosts, d.stale) = (owned, sends, ghosts, false);
        self.motion = (0..owned)
            .filter_map(|i| d.rule_of.get(&self.particles.id[i]).map(|&k| d.rules[k].on_rank(i)))
            .collect();
        // Fixed meshes bin the triangles near this box (periodic axes whole).
        let [mut lo, mut hi] = d.boxes.boxes[me];
        for k in (0..3).filter(|&k| per.axes[k]) {
            (lo[k], hi[k]) = (f64::NEG_INFINITY, f64::INFINITY);
        }
        self.sources.meshes.bin_near([lo, hi]);
        self.domain = Some(d);
        // The particles that stayed keep what the sources found for them (mesh candidates).
        self.sources.redistributed(&new_of, n);
        if let Err(e) = self.sources.take_carried(&self.particles.id, &kept_records) {
            // The records were made from valid histories: only a defect can break them.
            panic!("internal error: the ranks' wall histories do not fit the particles: {e}");
        }
        self.derive_slot_facts();
        self.neighbors.set_ghosts_from(Some(owned));
        self.neighbors.build_on(&self.particles, &self.walls, false);
        // The common mass is found now, by every rank at once.
        self.common();
    }
}

impl Simulation {
    /// The load a wall takes from its contacts' loads on this rank's particles (see
    /// [`wall_load_terms`](crate::forces::source::wall_load_terms)), summed over every rank
    /// when spread over ranks (collective then).
    pub(crate) fn wall_load_over_ranks(
        &self,
        parts: &[(Vec3, Vec3, Vec3)],
        about: Vec3,
    ) -> crate::forces::source::MeshLoad {
        use crate::forces::source::{wall_load, wall_load_terms};
        use crate::observe::order_free_sum;
        let t = wall_load_terms(parts, about);
        wall_load(match &self.domain {
            None => t.each_ref().map(|v| order_free_sum(v)),
            Some(d) => d.order_free_sums(t.each_ref().map(|v| &v[..])),
        })
    }
}

impl Decomposition {
    /// Every rank's `mine`, by rank: on every rank, or (`everyone` false) on rank 0 alone (the
    /// others get empty lists).
    fn to(&self, everyone: bool, mine: Vec<u64>) -> Vec<Vec<u64>> {
        if everyone {
            return self.comm.all_gather(&mine);
        }
        let mut out = vec![Vec::new(); self.comm.size()];
        out[0] = mine;
        self.comm.exchange(out)
    }

    /// [`Comm::exchange`], counted.
    fn exchange(&mut self, out: Vec<Vec<u64>>) -> Vec<Vec<u64>> {
        let me = self.comm.rank();
        for (r, w) in out.iter().enumerate() {
            if r != me && !w.is_empty() {
                self.stats.messages += 1;
                self.stats.bytes += 8 * w.len() as u64;
            }
        }
        self.comm.exchange(out)
    }

    /// Words of a moving particle.
    fn moving(&self) -> usize {
        MOVING + if self.history { 6 } else { 0 }
    }

    /// Appends particle `i` of `p` with everything it carries: its ghost's words, then its
    /// accumulators and Adams–Bashforth history.
    fn push_moving(&self, out: &mut Vec<u64>, p: &Particles, i: usize) {
        push_ghost(out, p, i);
        push_vecs(out, &[p.force[i], p.torque[i]]);
        if self.history {
            push_vecs(out, &[p.accel_prev[i], p.alpha_prev[i]]);
        }
    }

    /// Reads a particle written by [`push_moving`](Self::push_moving) at `*at` into `p`.
    fn read_moving(&self, w: &[u64], at: &mut usize, p: &mut Particles) {
        let w = &w[*at..*at + self.moving()];
        *at += self.moving();
        read_ghost_state(w, p);
        p.force.push(vec_at(w, 14));
        p.torque.push(vec_at(w, 17));
        if self.history {
            p.accel_prev.push(vec_at(w, 20));
            p.alpha_prev.push(vec_at(w, 23));
        }
    }

    /// The largest of every rank's `peak`.
    pub fn largest_peak(&self, peak: crate::forces::Peak) -> crate::forces::Peak {
        let all = self.comm.all_gather(&[peak[0].to_bits(), peak[1].to_bits()]);
        all.iter()
            .fold([0.0; 2], |m, w| crate::forces::max_peak(m, [f64::from_bits(w[0]), f64::from_bits(w[1])]))
    }

    /// The common masses of one process from every rank's (`empty`: it has no particles,
    /// `no_free`: none it integrates, which leave the answer to the others).
    pub fn common_over_ranks(&self, c: Common, empty: bool, no_free: bool) -> Common {
        let opt =
            |v: Option<f64>, skip: bool| if skip { [2, 0] } else { v.map_or([0, 0], |x| [1, x.to_bits()]) };
        let (m, fi) = (opt(c.0, empty), c.1);
        let (f, i) = (opt(fi.map(|v| v.0), no_free), opt(fi.map(|v| v.1), no_free));
        let all = self.comm.all_gather(&[m[0], m[1], f[0], f[1], i[0], i[1]]);
        let same = |k: usize| -> Option<f64> {
            let given: Vec<&Vec<u64>> = all.iter().filter(|w| w[k] != 2).collect();
            let first = given.first()?;
            given.iter().all(|w| w[k] == 1 && w[k + 1] == first[k + 1]).then(|| f64::from_bits(first[k + 1]))
        };
        (same(0), same(2).zip(same(4)))
    }

    /// [`crate::observe::order_free_sum`] of each set of values, over every rank's values:
    /// the one process's sums to the bit.
    pub fn order_free_sums<const K: usize>(&self, sets: [&[f64]; K]) -> [f64; K] {
        // First the largest magnitude, the count and the plain sum of each set on each rank.
        let mut mine = Vec::with_capacity(4 * K);
        for v in sets {
            let largest = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let nan = v.iter().any(|x| x.is_nan());
            mine.extend([largest.to_bits(), v.len() as u64, nan as u64, v.iter().sum::<f64>().to_bits()]);
        }
        let all = self.comm.all_gather(&mine);
        let mut scales = [None; K];
        let mut totals = [0.0; K];
        for (k, scale) in scales.iter_mut().enumerate() {
            let largest = all.iter().fold(0.0f64, |m, w| m.max(f64::from_bits(w[4 * k])));
            let len: u64 = all.iter().map(|w| w[4 * k + 1]).sum();
            let nan = all.iter().any(|w| w[4 * k + 2] != 0);
            if largest == 0.0 || !largest.is_finite() || nan {
                // The plain sum, as one process takes it: its value does not depend on the
                // order here (zeros, infinities, NaN); ranks without values are left out.
                totals[k] =
                    all.iter().filter(|w| w[4 * k + 1] > 0).map(|w| f64::from_bits(w[4 * k + 3])).sum();
            } else {
                let e = largest.log2().ceil() as i32 + 1;
                let bits = (len as f64 + 1.0).log2().ceil() as i32;
                *scale = Some(2f64.powi(126 - bits - e));
            }
        }
        let mut fixed = Vec::with_capacity(2 * K);
        for (v, scale) in sets.iter().zip(&scales) {
            let t: i128 = scale.map_or(0, |s| v.iter().map(|&x| (x * s).round() as i128).sum());
            fixed.extend([t as u64, (t >> 64) as u64]);
        }
        let all = self.comm.all_gather(&fixed);
        for (k, scale) in scales.iter().enumerate() {
            if let Some(s) = scale {
                let t: i128 =
                    all.iter().map(|w| (w[2 * k] as u128 | (w[2 * k + 1] as u128) << 64) as i128).sum();
                totals[k] = t as f64 / s;
            }
        }
        totals
    }

    /// The contacts counted on every rank, and the largest overlap ratio of any.
    pub fn count_and_max(&self, contacts: usize, ratio: f64) -> (usize, f64) {
        let all = self.comm.all_gather(&[contacts as u64, ratio.to_bits()]);
        let count = all.iter().map(|w| w[0] as usize).sum();
        (count, all.iter().fold(0.0f64, |m, w| m.max(f64::from_bits(w[1]))))
    }
}

fn push_vecs(out: &mut Vec<u64>, vs: &[Vec3]) {
    for v in vs {
        out.extend([v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]);
    }
}

fn vec_at(w: &[u64], k: usize) -> Vec3 {
    Vec3::new(f64::from_bits(w[k]), f64::from_bits(w[k + 1]), f64::from_bits(w[k + 2]))
}

/// A pair's history by ids: (the ids, lower first; the slots in that order; the history seen
/// from the lower id), given the slots and the history seen from the first.
fn by_ids(p: &Particles, [a, b]: [u32; 2], h: Vec3) -> ([u32; 2], [u32; 2], Vec3) {
    let (ia, ib) = (p.id[a as usize], p.id[b as usize]);
    if ia < ib { ([ia, ib], [a, b], h) } else { ([ib, ia], [b, a], -h) }
}

/// Appends a ghost's first state: what pairs read of it.
fn push_ghost(out: &mut Vec<u64>, p: &Particles, i: usize) {
    out.extend([
        p.id[i] as u64,
        p.phase[i] as u64,
        p.radius[i].to_bits(),
        p.mass[i].to_bits(),
        p.inertia[i].to_bits(),
    ]);
    push_vecs(out, &[p.position[i], p.velocity[i], p.omega[i]]);
}

/// Reads a ghost written by [`push_ghost`], with zero accumulators and history.
fn read_ghost(w: &[u64], p: &mut Particles, history: bool) {
    read_ghost_state(w, p);
    p.force.push(Vec3::ZERO);
    p.torque.push(Vec3::ZERO);
    if history {
        p.accel_prev.push(Vec3::ZERO);
        p.alpha_prev.push(Vec3::ZERO);
    }
}

/// Appends to `p` the fields [`push_ghost`] wrote (the first [`GHOST`] words of `w`).
fn read_ghost_state(w: &[u64], p: &mut Particles) {
    p.id.push(w[0] as u32);
    p.phase.push(w[1] as u32);
    p.radius.push(f64::from_bits(w[2]));
    p.mass.push(f64::from_bits(w[3]));
    p.inertia.push(f64::from_bits(w[4]));
    p.position.push(vec_at(w, 5));
    p.velocity.push(vec_at(w, 8));
    p.omega.push(vec_at(w, 11));
}

fn push_history(out: &mut Vec<u64>, ids: [u32; 2], h: Vec3) {
    out.extend([ids[0] as u64, ids[1] as u64]);
    push_vecs(out, &[h]);
}

fn read_history(w: &[u64]) -> ([u32; 2], Vec3) {
    ([w[0] as u32, w[1] as u32], vec_at(w, 2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_unit_of_work_weighs_as_its_ranks_time_per_unit_over_the_mean() {
        // Two ranks of equal work, one busy 2 s, the other 1 s: 4/3 and 2/3 of the mean time
        // per unit.
        let all = [3_000_000_000, 2_000];
        assert_eq!(time_weight([2_000_000_000, 1_000], all), 1365);
        assert_eq!(time_weight([1_000_000_000, 1_000], all), 683);
        // As fast as the mean: a unit. Beyond a factor 8 either way (a rank with almost no
        // work, whose time is its overheads; one that measured no time): the bounds.
        assert_eq!(time_weight([1_500_000_000, 1_000], all), WEIGHT_UNIT);
        assert_eq!(time_weight([1_500_000_000, 10], all), 8 * WEIGHT_UNIT);
        assert_eq!(time_weight([0, 1_000], all), WEIGHT_UNIT / 8);
        assert_eq!(time_weight([1_000, 0], all), WEIGHT_UNIT / 8);
    }
}
