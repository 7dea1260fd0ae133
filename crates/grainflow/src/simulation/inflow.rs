//! Particles that come in and go out during a run: the insertions' batches
//! ([`crate::insertion`]), the outlets, and the books of both.
//!
//! Between steps, at the start of a step:
//! 1. **Outlets** catch, at every step, the particles whose centres have left through them
//!    (and, with [`OutletShape::OutsideBox`], those outside the domain box): a particle is
//!    counted by the first outlet it crosses, at the first step it is past it, however fast
//!    it goes and however thin the outlet. The caught particles are removed every
//!    [`DRAIN_EVERY`] steps: removing rearranges the slots (`Simulation::rearrange`), so it is
//!    done in batches, and a caught particle goes on for at most that many steps more
//!    (falling freely below an orifice, or outside the box, where nothing meets it);
//!    [`Simulation::left_through_outlet`] tells the run's checks that it is on its way out.
//! 2. **Insertions** whose batch is due draw their particles (phase and diameter from the
//!    mixture), place them ([`crate::insertion::place::place`]) clear of everything present
//!    (and outside every closed mesh wall that does not hold the region: an obstacle), and
//!    append them with new ids (counting on from the largest id there has been). A region
//!    that is the inside of a moving mesh moves with it. What could not be placed is counted
//!    ([`FlowBooks::missed`]: asked = inserted + missed) and reported in a notice
//!    ([`Simulation::flow_notices`]) when an insertion first misses and each time its
//!    shortfall has doubled since.
//!
//! Every insertion draws from its own stream, seeded by the case; its position in the stream
//! is in the checkpoint, so a restart draws and places what the uninterrupted run would
//! have. Nothing depends on the thread count.
//!
//! **The books.** Masses are counted in integers of a quantum fixed at set-up (2⁻⁶⁰ of the
//! largest particle mass the run can have, rounded to a power of two): each particle's mass
//! is rounded to a whole number of quanta once, so that initial + inserted = present +
//! removed holds exactly, in any order, for counts and masses.

use super::Simulation;
use crate::error::EngineError;
use crate::insertion::place::{Obstacles, place};
use crate::insertion::region::{InsideMesh, Region};
use crate::insertion::{Amount, InsertRng, Insertion, Outlet, OutletShape, Rate, Schedule};
use crate::math::Vec3;
use crate::state::ParticleInit;
use rand::SeedableRng;

/// Particles and their mass, counted exactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Tally {
    /// How many.
    pub count: u64,
    /// Their mass in quanta of the run's books ([`FlowBooks::quantum`]).
    pub units: i128,
}

impl Tally {
    fn add(&mut self, units: i128) {
        self.count += 1;
        self.units += units;
    }

    /// As three words for other ranks: the count, then the units' low and high halves.
    fn words(&self) -> [u64; 3] {
        [self.count, self.units as u128 as u64, (self.units as u128 >> 64) as u64]
    }

    /// Adds a tally given as its [`words`](Self::words).
    fn add_words(&mut self, w: &[u64]) {
        self.count += w[0];
        self.units += (w[1] as u128 | (w[2] as u128) << 64) as i128;
    }
}

/// The mass books of a run: what was there at the start, came in, went out and is there.
#[derive(Debug, Clone, PartialEq)]
pub struct FlowBooks {
    /// The mass of one unit of [`Tally::units`], kg (a power of two).
    pub quantum: f64,
    /// The particles at the start of the run.
    pub initial: Tally,
    /// Inserted since, by each insertion.
    pub inserted: Vec<Tally>,
    /// Removed since, by each outlet.
    pub removed: Vec<Tally>,
    /// There now.
    pub present: Tally,
    /// Added between steps by [`Simulation::insert`] (a user's hook or script).
    pub added: Tally,
    /// Removed between steps by [`Simulation::remove_ids`] or
    /// [`Simulation::remove_where`].
    pub taken: Tally,
    /// Particles each insertion drew but could not place (no room left in its region).
    pub missed: Vec<u64>,
    /// Particles each insertion has drawn so far, placed or not: `asked = inserted + missed`.
    pub asked: Vec<u64>,
    /// Their mass, kg (drawn masses summed in their order, not in quanta).
    pub asked_mass: Vec<f64>,
}

impl FlowBooks {
    /// A tally's mass, kg.
    pub fn mass(&self, t: Tally) -> f64 {
        t.units as f64 * self.quantum
    }

    /// All insertions' tallies together.
    pub fn inserted_total(&self) -> Tally {
        sum(&self.inserted)
    }

    /// All outlets' tallies together.
    pub fn removed_total(&self) -> Tally {
        sum(&self.removed)
    }

    /// True if initial + inserted + added = present + removed + taken, in counts and in mass
    /// units.
    pub fn close(&self) -> bool {
        let (i, r) = (self.inserted_total(), self.removed_total());
        self.initial.count + i.count + self.added.count == self.present.count + r.count + self.taken.count
            && self.initial.units + i.units + self.added.units
                == self.present.units + r.units + self.taken.units
    }
}

fn sum(t: &[Tally]) -> Tally {
    t.iter().fold(Tally::default(), |a, b| Tally { count: a.count + b.count, units: a.units + b.units })
}

/// The number of particles a batch of `ins` draws, about (from the mixture's mean volume and
/// mass), for the set-up's check.
fn batch_estimate(ins: &Insertion, volume: f64) -> f64 {
    let (v, m) = (ins.mixture.mean_volume(), ins.mixture.mean_mass());
    let of = |t: Target| match t {
        Target::Count(n) => n as f64,
        Target::Volume(x) => x / v,
        Target::Mass(x) => x / m,
    };
    let whole = ins.amount.map(|a| of(total_target(a, volume)));
    let batch = match ins.schedule {
        Schedule::Once { .. } => whole.unwrap_or(0.0),
        Schedule::Rate { rate, every, .. } => match rate {
            Rate::Particles(r) => r * every,
            Rate::Mass(r) => r * every / m,
        },
    };
    whole.map_or(batch, |w| batch.min(w))
}

/// An insertion's progress.
#[derive(Debug, Clone)]
struct Feed {
    rng: InsertRng,
    /// Batches done.
    batches: u64,
    /// What has been drawn so far (placed or not): count, volume (m³), mass (kg).
    drawn: (u64, f64, f64),
    placed: Tally,
    missed: u64,
}

/// What the flow stage keeps.
#[derive(Debug, Clone, Default)]
pub(crate) struct FlowStage {
    insertions: Vec<Insertion>,
    outlets: Vec<Outlet>,
    feeds: Vec<Feed>,
    removed: Vec<Tally>,
    /// The next inserted particle's id.
    next_id: u64,
    /// Particles added between steps ([`Simulation::insert`]), alike on every rank.
    added: Tally,
    /// Particles removed between steps ([`Simulation::remove_ids`]): this rank's.
    taken: Tally,
    /// log₂ of the books' quantum.
    quantum_exp: i32,
    initial: Tally,
    /// The first thing that went wrong in the stage (the run should stop on it).
    pub error: Option<String>,
    /// Particles caught by an outlet (id → outlet), removed at the next drain.
    pending: std::collections::BTreeMap<u32, u32>,
    /// What the run should tell its user (insertions' shortfalls, overlaps of given particles).
    notices: Vec<String>,
    /// Each mesh wall as a solid, found at the first batch: its inside once for a fixed closed
    /// mesh (built again at each batch where it is then for a moving one).
    solids: Option<Vec<Solid>>,
}

/// A mesh wall as an obstacle of insertions.
#[derive(Debug, Clone)]
enum Solid {
    /// Not closed: it has no inside.
    Open,
    /// Closed and fixed: its inside.
    Fixed(std::sync::Arc<InsideMesh>),
    /// Closed and moving.
    Moving,
}

/// The books' quantum for particles up to `largest_mass`: a power of two 2⁻⁶⁰ of it or less.
fn quantum_exponent(largest_mass: f64) -> i32 {
    if largest_mass.is_finite() && largest_mass > 0.0 { largest_mass.log2().ceil() as i32 - 60 } else { -60 }
}

impl FlowStage {
    /// The stage for `insertions` and `outlets`, with the particles present at the start
    /// (`heaviest`: their largest mass, kg; `next_id`: one above their largest id).
    pub(crate) fn new(
        insertions: Vec<Insertion>,
        outlets: Vec<Outlet>,
        (heaviest, next_id): (f64, u64),
        n_phases: usize,
    ) -> Result<FlowStage, EngineError> {
        for ins in &insertions {
            check_insertion(ins, n_phases)?;
        }
        for o in &outlets {
            if let OutletShape::Region(r) = &o.shape {
                r.check().map_err(|e| EngineError::BadReference(format!("outlet '{}': {e}", o.name)))?;
            }
            if let OutletShape::Plane { point, normal } = &o.shape
                && !(point.is_finite() && normal.is_finite() && normal.length_squared() > 0.0)
            {
                return Err(EngineError::BadReference(format!(
                    "outlet '{}': the plane needs a finite point and a non-zero normal",
                    o.name
                )));
            }
        }
        let largest = insertions
            .iter()
            .flat_map(|i| i.mixture.parts.iter())
            .map(|part| part.density * std::f64::consts::FRAC_PI_6 * part.sizes.max_diameter().powi(3))
            .fold(heaviest, f64::max);
        let quantum_exp = quantum_exponent(largest);
        let feeds = insertions
            .iter()
            .map(|i| Feed {
                rng: InsertRng::seed_from_u64(i.seed),
                batches: 0,
                drawn: (0, 0.0, 0.0),
                placed: Tally::default(),
                missed: 0,
            })
            .collect();
        let stage = FlowStage {
            removed: vec![Tally::default(); outlets.len()],
            insertions,
            outlets,
            feeds,
            next_id,
            added: Tally::default(),
            taken: Tally::default(),
            quantum_exp,
            initial: Tally::default(),
            error: None,
            pending: Default::default(),
            notices: Vec::new(),
            solids: None,
        };
        Ok(stage)
    }

    /// Counts the particles present at the start (`masses`: this rank's) over the ranks of
    /// `whole`, exactly (integer quanta).
    pub(super) fn count_initial(&mut self, masses: &[f64], whole: super::whole::Whole<'_>) {
        let t = self.tally(masses.iter().copied());
        let [count, units] = whole.sums([t.count as i128, t.units]);
        self.initial = Tally { count: count as u64, units };
    }

    /// True if the stage has nothing to do.
    pub(crate) fn is_empty(&self) -> bool {
        self.insertions.is_empty() && self.outlets.is_empty()
    }

    /// The largest radius an insertion can bring, m (0 if none).
    pub(crate) fn max_radius(&self) -> f64 {
        self.insertions.iter().map(|i| 0.5 * i.mixture.max_diameter()).fold(0.0, f64::max)
    }

    fn units(&self, mass: f64) -> i128 {
        (mass * 2f64.powi(-self.quantum_exp)).round() as i128
    }

    fn tally(&self, masses: impl Iterator<Item = f64>) -> Tally {
        let mut t = Tally::default();
        for m in masses {
            t.add(self.units(m));
        }
        t
    }

    /// The flow state as words, for checkpoints.
    pub(crate) fn words(&self) -> Vec<u64> {
        let mut w = vec![self.feeds.len() as u64, self.removed.len() as u64, self.next_id];
        w.push(self.quantum_exp as i64 as u64);
        let tally = |w: &mut Vec<u64>, t: Tally| {
            w.push(t.count);
            w.push(t.units as u128 as u64);
            w.push((t.units as u128 >> 64) as u64);
        };
        tally(&mut w, self.initial);
        for f in &self.feeds {
            let pos = f.rng.get_word_pos();
            w.extend([pos as u64, (pos >> 64) as u64, f.batches, f.drawn.0, f.drawn.1.to_bits()]);
            w.push(f.drawn.2.to_bits());
            tally(&mut w, f.placed);
            w.push(f.missed);
        }
        for &t in &self.removed {
            tally(&mut w, t);
        }
        // The particles caught and not yet removed (a checkpoint without them has none).
        w.push(self.pending.len() as u64);
        w.extend(self.pending.iter().flat_map(|(&id, &o)| [id as u64, o as u64]));
        // Then those added and removed between steps (a checkpoint without them had none).
        w.extend(self.added.words());
        w.extend(self.taken.words());
        w
    }

    /// Restores the flow state of [`words`](Self::words).
    pub(crate) fn set_words(&mut self, w: &[u64]) -> Result<(), String> {
        let (f, o) = (self.feeds.len(), self.removed.len());
        if w.len() < 7 || w[0] != f as u64 || w[1] != o as u64 {
            return Err(format!(
                "the checkpoint has {} insertions and {} outlets, the case {f} and {o}",
                w.first().unwrap_or(&0),
                w.get(1).unwrap_or(&0)
            ));
        }
        let base = 7 + 10 * f + 3 * o;
        let caught = w.get(base).map_or(0, |&n| n as usize);
        // Older checkpoints end before the caught particles, or after them.
        let after_caught = base + 1 + 2 * caught;
        let by_hand = w.len() == after_caught + 6;
        if !(w.len() == base || w.len() == after_caught || by_hand) {
            return Err("the checkpoint's insertion state has the wrong length".into());
        }
        self.pending.clear();
        let caught_words = w.get(base + 1..after_caught.min(w.len())).unwrap_or(&[]);
        for c in caught_words.chunks_exact(2) {
            if c[1] >= o as u64 || c[0] > u32::MAX as u64 {
                return Err("the checkpoint's caught particles name no outlet of the case".into());
            }
            self.pending.insert(c[0] as u32, c[1] as u32);
        }
        let tally = |c: &[u64]| Tally { count: c[0], units: (c[1] as u128 | (c[2] as u128) << 64) as i128 };
        self.next_id = w[2];
        self.quantum_exp = w[3] as i64 as i32;
        self.initial = tally(&w[4..7]);
        for (k, feed) in self.feeds.iter_mut().enumerate() {
            let c = &w[7 + 10 * k..7 + 10 * (k + 1)];
            feed.rng.set_word_pos(c[0] as u128 | (c[1] as u128) << 64);
            feed.batches = c[2];
            feed.drawn = (c[3], f64::from_bits(c[4]), f64::from_bits(c[5]));
            feed.placed = tally(&c[6..9]);
            feed.missed = c[9];
        }
        for (k, t) in self.removed.iter_mut().enumerate() {
            *t = tally(&w[7 + 10 * f + 3 * k..]);
        }
        (self.added, self.taken) = if by_hand {
            (tally(&w[after_caught..]), tally(&w[after_caught + 3..]))
        } else {
            (Tally::default(), Tally::default())
        };
        Ok(())
    }
}

/// A rank's part of the flow state (what it caught and removed): the rest every rank holds
/// alike.
impl FlowStage {
    /// Counts particles of masses `m` added between steps (`added`) or removed (not).
    pub(super) fn count_by_hand(&mut self, m: impl Iterator<Item = f64>, added: bool) {
        let t = self.tally(m);
        let to = if added { &mut self.added } else { &mut self.taken };
        *to = sum(&[*to, t]);
    }

    /// Makes the next inserted particle's id at least `id` + 1.
    pub(super) fn id_used(&mut self, id: u32) {
        self.next_id = self.next_id.max(id as u64 + 1);
    }

    /// The id the next inserted particle takes.
    pub(super) fn next_id(&self) -> u64 {
        self.next_id
    }

    /// This rank's caught particles and its outlets' removals, as words: the caught count,
    /// (id, outlet) pairs, then per outlet its tally's three words.
    pub(super) fn rank_words(&self) -> Vec<u64> {
        let mut w = vec![self.pending.len() as u64];
        w.extend(self.pending.iter().flat_map(|(&id, &o)| [id as u64, o as u64]));
        w.extend(self.removed.iter().flat_map(Tally::words));
        w.extend(self.taken.words());
        w
    }

    /// Adds a rank's [`rank_words`](Self::rank_words) at the start of `w` to this state;
    /// returns how many words they were.
    pub(super) fn add_rank_words(&mut self, w: &[u64]) -> usize {
        let caught = w[0] as usize;
        for c in w[1..1 + 2 * caught].chunks_exact(2) {
            self.pending.insert(c[0] as u32, c[1] as u32);
        }
        let at = 1 + 2 * caught;
        for (k, t) in self.removed.iter_mut().enumerate() {
            t.add_words(&w[at + 3 * k..]);
        }
        let at = at + 3 * self.removed.len();
        self.taken.add_words(&w[at..]);
        at + 3
    }

    /// Keeps this rank's part of a whole run's flow state: the caught particles among `own`
    /// (sorted ids); the removals on rank 0 only, where they are counted once.
    pub(super) fn keep_rank_part(&mut self, own: &[u32], rank: usize) {
        self.pending.retain(|id, _| own.binary_search(id).is_ok());
        if rank != 0 {
            self.removed.iter_mut().for_each(|t| *t = Tally::default());
            self.taken = Tally::default();
        }
    }

    /// Forgets this rank's part (to add every rank's after).
    pub(super) fn clear_rank_part(&mut self) {
        self.keep_rank_part(&[], 1);
    }

    /// The outlet that caught particle `id`, taken out of this rank's caught particles (it
    /// moves to another rank).
    pub(super) fn take_caught(&mut self, id: u32) -> Option<u32> {
        self.pending.remove(&id)
    }

    /// Particle `id`, which came from another rank, was caught by `outlet` there.
    pub(super) fn put_caught(&mut self, id: u32, outlet: u32) {
        self.pending.insert(id, outlet);
    }
}

/// The engine's checks of an insertion (the case layer names the keys).
fn check_insertion(ins: &Insertion, n_phases: usize) -> Result<(), EngineError> {
    let bad = |what: String| EngineError::BadReference(format!("insertion '{}': {what}", ins.name));
    if let Some(part) = ins.mixture.parts.iter().find(|p| p.phase as usize >= n_phases) {
        return Err(bad(format!("phase index {} but only {n_phases} phases are defined", part.phase)));
    }
    ins.region.check().map_err(|e| bad(e.to_string()))?;
    ins.mixture.check().map_err(|e| bad(e.to_string()))?;
    if !ins.velocity.is_finite() {
        return Err(bad("the velocity must be finite".into()));
    }
    match ins.amount {
        Some(Amount::Count(_)) | None => {}
        Some(Amount::VolumeFraction(f)) if f > 0.0 && f < 1.0 => {}
        Some(Amount::Mass(m)) if m > 0.0 && m.is_finite() => {}
        Some(a) => {
            return Err(bad(format!("{a:?} is not an amount: a fraction in (0, 1) or a positive mass")));
        }
    }
    match ins.schedule {
        Schedule::Once { at } if at.is_finite() => {
            if ins.amount.is_none() {
                return Err(bad("an insertion all at once needs an amount".into()));
            }
        }
        Schedule::Rate { rate, start, every } if start.is_finite() && every.is_finite() && every > 0.0 => {
            let r = match rate {
                Rate::Particles(r) | Rate::Mass(r) => r,
            };
            if !(r.is_finite() && r > 0.0) {
                return Err(bad(format!("the rate must be positive, not {r}")));
            }
        }
        s => return Err(bad(format!("{s:?} is not a schedule: finite times and a positive interval"))),
    }
    if !ins.given.is_empty() {
        if !matches!(ins.schedule, Schedule::Once { .. })
            || ins.amount != Some(Amount::Count(ins.given.len() as u64))
        {
            return Err(bad("given particles are inserted all at once, all of them".into()));
        }
        if ins.given.len() > MAX_BATCH {
            return Err(bad(format!(
                "{} particles given; at most {MAX_BATCH} may come at once",
                ins.given.len()
            )));
        }
        let p = crate::state::Particles::from_init(&ins.given);
        return super::check_particles(&p, n_phases).map_err(|e| bad(e.to_string()));
    }
    let batch = batch_estimate(ins, ins.region.volume());
    if batch.is_nan() || batch > MAX_BATCH as f64 / 2.0 {
        return Err(bad(format!(
            "a batch would hold about {batch:.3e} particles, more than the {:.0e} one batch may hold; lower the amount or the rate, or insert more often",
            MAX_BATCH as f64 / 2.0
        )));
    }
    Ok(())
}

impl Simulation {
    /// The mass books: initial, inserted, removed and present particles, each counted and
    /// weighed exactly (see [`FlowBooks`]). Collective on ranks: every rank must call it.
    pub fn flow_books(&self) -> FlowBooks {
        let st = &self.flow;
        let mut present = st.tally(self.particles.mass[..self.owned()].iter().copied());
        let mut removed = st.removed.clone();
        let mut taken = st.taken;
        if let Some(comm) = self.comm() {
            // Each rank counts its own particles and what its outlets and removals between
            // steps removed; what was inserted or added every rank counts alike (each places
            // every batch, and is given every added particle).
            let mine: Vec<u64> =
                [&present, &taken].into_iter().chain(&removed).flat_map(Tally::words).collect();
            let all = comm.all_gather(&mine);
            for (k, t) in [&mut present, &mut taken].into_iter().chain(&mut removed).enumerate() {
                *t = Tally::default();
                for w in &all {
                    t.add_words(&w[3 * k..]);
                }
            }
        }
        FlowBooks {
            quantum: 2f64.powi(st.quantum_exp),
            initial: st.initial,
            inserted: st.feeds.iter().map(|f| f.placed).collect(),
            removed,
            present,
            added: st.added,
            taken,
            missed: st.feeds.iter().map(|f| f.missed).collect(),
            asked: st.feeds.iter().map(|f| f.drawn.0).collect(),
            asked_mass: st.feeds.iter().map(|f| f.drawn.2).collect(),
        }
    }

    /// What the flow stage has to tell the run's user so far, oldest first: each insertion's
    /// shortfall when it first misses particles and whenever it has doubled since, and given
    /// particles that come in overlapping present ones. A caller shows those after the ones
    /// it has shown.
    pub fn flow_notices(&self) -> &[String] {
        &self.flow.notices
    }

    /// True if the particle in slot `i` has left through an outlet: caught by one (its
    /// removal waits for the next drain) or past one now. Such a particle may be outside the
    /// domain box.
    pub fn left_through_outlet(&self, i: usize) -> bool {
        let st = &self.flow;
        st.pending.contains_key(&self.particles.id[i])
            || st.outlets.iter().any(|o| o.shape.has_left(self.particles.position[i]))
    }

    /// The insertions of the run.
    pub fn insertions(&self) -> &[Insertion] {
        &self.flow.insertions
    }

    /// The outlets of the run.
    pub fn outlets(&self) -> &[Outlet] {
        &self.flow.outlets
    }

    /// What went wrong in an insertion or an outlet, if anything did: the run should stop
    /// (the steps go on without the failed batch).
    pub fn flow_error(&self) -> Option<&str> {
        self.flow.error.as_deref()
    }

    pub(crate) fn flow_words(&self) -> Vec<u64> {
        self.flow.words()
    }

    pub(crate) fn set_flow_words(&mut self, w: &[u64]) -> Result<(), String> {
        self.flow.set_words(w)
    }

    /// The flow stage at the start of a step (see the [module doc](self)); with `par` on the
    /// thread pool.
    pub(super) fn flow_stage(&mut self, par: bool) -> Result<(), EngineError> {
        if self.flow.is_empty() {
            return Ok(());
        }
        let t = self.time();
        let tolerance = 1e-6 * self.time_step.dt;
        let due: Vec<usize> =
            (0..self.flow.insertions.len()).filter(|&k| self.batch_due(k, t + tolerance)).collect();
        if !self.flow.outlets.is_empty() {
            self.catch_leaving();
        }
        let drain = !self.flow.outlets.is_empty()
            && self.step.is_multiple_of(DRAIN_EVERY)
            && self.on_any_rank(!self.flow.pending.is_empty());
        if due.is_empty() && !drain {
            return Ok(());
        }
        if self.kick_pending {
            self.finish_kick(par);
        }
        if drain {
            self.drain()?;
        }
        for k in due {
            while self.batch_due(k, t + tolerance) {
                self.insert_batch(k)?;
            }
        }
        Ok(())
    }

    /// True if insertion `k` has a batch due at time `t` and something left to insert.
    fn batch_due(&self, k: usize, t: f64) -> bool {
        let (ins, feed) = (&self.flow.insertions[k], &self.flow.feeds[k]);
        if amount_reached(ins.amount, feed.drawn, ins.region.volume()) {
            return false;
        }
        match ins.schedule {
            Schedule::Once { at } => feed.batches == 0 && at <= t,
            Schedule::Rate { start, every, .. } => start + feed.batches as f64 * every <= t,
        }
    }

    /// Catches the particles that are past an outlet now and were not caught before (the
    /// first outlet that has them counts them).
    ///
    /// Outlet after outlet, in their order (a particle past two is the first's), each over
    /// all positions in one tight loop: this runs at every step.
    fn catch_leaving(&mut self) {
        let p = &self.particles;
        // A rank's own particles (its ghosts are caught by their owners).
        let own = &p.position[..self.owned()];
        let FlowStage { outlets, pending, .. } = &mut self.flow;
        for (o, outlet) in outlets.iter().enumerate() {
            let mut catch = |i: usize| {
                pending.entry(p.id[i]).or_insert(o as u32);
            };
            match &outlet.shape {
                // The test of `has_left`, written out so that the loop stays simple.
                &OutletShape::Plane { point, normal } => {
                    for (i, &x) in own.iter().enumerate() {
                        if (x - point).dot(normal) > 0.0 {
                            catch(i);
                        }
                    }
                }
                shape => {
                    for (i, &x) in own.iter().enumerate() {
                        if shape.has_left(x) {
                            catch(i);
                        }
                    }
                }
            }
        }
    }

    /// Removes the particles caught by the outlets, each counted by the outlet that caught it.
    fn drain(&mut self) -> Result<(), EngineError> {
        let p = &self.particles;
        let pending = std::mem::take(&mut self.flow.pending);
        let gone: Vec<(usize, usize)> =
            (0..self.owned()).filter_map(|i| pending.get(&p.id[i]).map(|&o| (i, o as usize))).collect();
        for &(i, o) in &gone {
            let u = self.flow.units(self.particles.mass[i]);
            self.flow.removed[o].add(u);
        }
        if self.comm().is_some() {
            // Every rank removes its own and the ghosts of the others'.
            let ids: Vec<u32> = gone.iter().map(|&(i, _)| self.particles.id[i]).collect();
            return self.remove_over_ranks(&ids).map(|_| ());
        }
        if gone.is_empty() {
            return Ok(());
        }
        let mut leaving = vec![false; p.len()];
        for &(i, _) in &gone {
            leaving[i] = true;
        }
        self.remove_slots_where(|_, i| leaving[i])?;
        Ok(())
    }

    /// Draws, places and inserts the next batch of insertion `k`.
    fn insert_batch(&mut self, k: usize) -> Result<(), EngineError> {
        // Lent out rather than cloned: a mesh region holds every triangle of its mesh.
        let before = self.flow.feeds[k].missed;
        let insertions = std::mem::take(&mut self.flow.insertions);
        let result = self.insert_batch_of(k, &insertions[k]);
        self.flow.insertions = insertions;
        self.notice_missed(k, before);
        result
    }

    /// Inserts insertion `k`'s given particles, `ins` lent out, as they are (new ids).
    fn insert_given(&mut self, k: usize, ins: &Insertion) -> Result<(), EngineError> {
        let mut new = ins.given.clone();
        for p in &mut new {
            p.id = u32::try_from(self.flow.next_id).map_err(|_| {
                EngineError::BadReference(format!(
                    "insertion '{}': particle ids beyond {}",
                    ins.name,
                    u32::MAX
                ))
            })?;
            self.flow.next_id += 1;
        }
        let feed = &mut self.flow.feeds[k];
        feed.batches += 1;
        for p in &new {
            let v = std::f64::consts::FRAC_PI_6 * (2.0 * p.radius).powi(3);
            feed.drawn = (feed.drawn.0 + 1, feed.drawn.1 + v, feed.drawn.2 + p.density * v);
        }
        // On ranks, against every rank's particles (all of them: a given set comes once).
        let near = self.particles_near(None);
        let p = &self.particles;
        let present = match &near {
            Some(n) => (&n.0[..], &n.1[..], &n.2[..]),
            None => (&p.id[..], &p.position[..], &p.radius[..]),
        };
        if let Some(notice) = self.check_given_against_present(ins, &new, present)? {
            self.flow.notices.push(notice);
        }
        self.add_inserted(k, &new)
    }

    /// Appends the particles `new` of insertion `k` (every rank places every batch alike and
    /// keeps those in its box) and counts them in its books.
    fn add_inserted(&mut self, k: usize, new: &[ParticleInit]) -> Result<(), EngineError> {
        let units: Vec<i128> =
            crate::state::Particles::from_init(new).mass.iter().map(|&m| self.flow.units(m)).collect();
        self.insert_uncounted(new)?;
        for u in units {
            self.flow.feeds[k].placed.add(u);
        }
        Ok(())
    }

    /// Given particles `new` of `ins` against the particles present: one at a present
    /// particle's centre is an error (the contact has no normal), the largest overlap above
    /// the insertion's limit a notice. Through the nearest periodic image.
    fn check_given_against_present(
        &self,
        ins: &Insertion,
        new: &[ParticleInit],
        (ids, positions, radii): (&[u32], &[Vec3], &[f64]),
    ) -> Result<Option<String>, EngineError> {
        if ids.is_empty() || new.is_empty() {
            return Ok(None);
        }
        let r_max = radii.iter().chain(new.iter().map(|q| &q.radius)).copied().fold(0.0, f64::max);
        let cell = (2.0 * r_max).max(f64::MIN_POSITIVE);
        let key = |x: Vec3| {
            let c = (x / cell).floor();
            (c.x as i64, c.y as i64, c.z as i64)
        };
        let mut grid: std::collections::HashMap<(i64, i64, i64), Vec<usize>> = Default::default();
        for (i, &x) in positions.iter().enumerate() {
            grid.entry(key(self.periodic.wrap(x))).or_default().push(i);
        }
        let images = self.periodic.any();
        let mut worst: Option<(f64, u32, usize)> = None;
        for (j, q) in new.iter().enumerate() {
            let x = self.periodic.wrap(q.position);
            let (cx, cy, cz) = key(x);
            let near = |c: (i64, i64, i64)| grid.get(&c).map_or(&[][..], |v| v.as_slice());
            // On a periodic axis, the cells across the face hold the images' neighbours: all
            // cells are searched then (a given set is inserted once).
            let candidates: Vec<usize> = if images {
                (0..ids.len()).collect()
            } else {
                let mut c = Vec::new();
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            c.extend_from_slice(near((cx + dx, cy + dy, cz + dz)));
                        }
                    }
                }
                c
            };
            for i in candidates {
                let d = self.periodic.nearest(x - positions[i]);
                if d == Vec3::ZERO {
                    return Err(EngineError::BadReference(format!(
                        "insertion '{}': its particle {} (the file's particle {}) comes in at the centre ({:e}, {:e}, {:e}) m of particle {}: their contact has no normal direction; move one of them",
                        ins.name, q.id, ins.given[j].id, q.position.x, q.position.y, q.position.z, ids[i]
                    )));
                }
                let overlap = q.radius + radii[i] - d.length();
                let ratio = overlap / q.radius.min(radii[i]);
                if ratio > ins.max_initial_overlap && worst.is_none_or(|w| ratio > w.0) {
                    worst = Some((ratio, q.id, i));
                }
            }
        }
        Ok(worst.map(|(ratio, id, i)| {
            let t = self.time();
            format!(
                "insertion '{}' at t = {t:.6e} s: its particle {id} overlaps particle {} by {ratio:.3} of the smaller radius (the largest overlap of the file's particles with those present), above max_initial_overlap = {}; the contact starts with a burst of elastic energy",
                ins.name, ids[i], ins.max_initial_overlap
            )
        }))
    }

    /// The mesh wall whose inside `region` is (the same triangles where the mesh was
    /// loaded), if any.
    fn region_mesh(&self, region: &Region) -> Option<usize> {
        let Region::Mesh(inside) = region else { return None };
        (0..self.sources.meshes.walls.len()).find(|&m| {
            let mesh = &self.sources.meshes.walls[m].mesh;
            mesh.name() == inside.name()
                && mesh.triangle_count() == inside.triangle_count()
                && inside.corners().iter().enumerate().all(|(t, c)| mesh.corners(t as u32) == *c)
        })
    }

    /// The triangles of mesh wall `m` where it is now.
    fn mesh_corners_now(&self, m: usize) -> Vec<[Vec3; 3]> {
        let v = self.mesh_vertices(m);
        self.sources.meshes.walls[m].mesh.triangles().iter().map(|t| t.map(|k| v[k as usize])).collect()
    }

    /// The insides of the closed mesh walls that are obstacles to `region` (where they are
    /// now): every closed mesh wall except the one whose inside the region is (`own`) and
    /// those holding the region, a container: a mesh that holds the region's centre and is
    /// not itself within the region's bounds. Meshes whose bounds stay `margin` clear of the
    /// region's are left out (no centre can be inside them).
    fn solids_for(
        &mut self,
        region: &Region,
        own: Option<usize>,
        margin: f64,
    ) -> Vec<std::sync::Arc<InsideMesh>> {
        if self.flow.solids.is_none() {
            let solids = (0..self.sources.meshes.walls.len())
                .map(|m| {
                    let wall = &self.sources.meshes.walls[m];
                    if !wall.mesh.edges().iter().all(|e| e.triangles().len() == 2) {
                        Solid::Open
                    } else if wall.motion.moves() {
                        Solid::Moving
                    } else {
                        let corners = self.mesh_corners_now(m);
                        Solid::Fixed(std::sync::Arc::new(InsideMesh::of_corners(
                            wall.mesh.name(),
                            corners,
                            None,
                        )))
                    }
                })
                .collect();
            self.flow.solids = Some(solids);
        }
        let (rlo, rhi) = region.bounds();
        let centre = 0.5 * (rlo + rhi);
        let mut out = Vec::new();
        for (m, solid) in self.flow.solids.iter().flatten().enumerate() {
            if Some(m) == own {
                continue;
            }
            let inside = match solid {
                Solid::Open => continue,
                Solid::Fixed(inside) => inside.clone(),
                Solid::Moving => std::sync::Arc::new(InsideMesh::of_corners(
                    self.sources.meshes.walls[m].mesh.name(),
                    self.mesh_corners_now(m),
                    None,
                )),
            };
            let (lo, hi) = inside.bounds();
            if lo.cmpgt(rhi + Vec3::splat(margin)).any() || hi.cmplt(rlo - Vec3::splat(margin)).any() {
                continue;
            }
            let within_region = lo.cmpge(rlo).all() && hi.cmple(rhi).all();
            if inside.contains(centre) && !within_region {
                continue;
            }
            out.push(inside);
        }
        out
    }

    /// A notice if insertion `k` missed particles in its last batch (`before` missed before
    /// it): the first time, and when the shortfall has doubled since the last notice.
    fn notice_missed(&mut self, k: usize, before: u64) {
        let feed = &self.flow.feeds[k];
        let after = feed.missed;
        if after == before || (before > 0 && after.ilog2() == before.ilog2()) {
            return;
        }
        let ins = &self.flow.insertions[k];
        let placed_mass = feed.placed.units as f64 * 2f64.powi(self.flow.quantum_exp);
        let t = self.time();
        self.flow.notices.push(format!(
            "insertion '{}' at t = {t:.6e} s: {after} of the {} particles asked so far could not be placed ({:.4e} kg of {:.4e} kg placed): its region has no room for them (full, too small for the diameters, or blocked by walls, meshes or particles); the next notice when the shortfall has doubled",
            ins.name, feed.drawn.0, placed_mass, feed.drawn.2
        ));
    }

    /// [`insert_batch`](Self::insert_batch) with insertion `k`, `ins`, lent out.
    fn insert_batch_of(&mut self, k: usize, ins: &Insertion) -> Result<(), EngineError> {
        if !ins.given.is_empty() {
            return self.insert_given(k, ins);
        }
        let volume = ins.region.volume();
        let target = batch_target(ins, self.flow.feeds[k].batches, volume);
        // Draw until the batch's target is reached.
        let feed = &mut self.flow.feeds[k];
        let mut drawn: Vec<(u32, f64, f64)> = Vec::new();
        // (The set-up's check keeps batches far below `MAX_BATCH`: the cap only bounds memory.)
        while !target.reached(feed.drawn) && !amount_reached(ins.amount, feed.drawn, volume) {
            if drawn.len() >= MAX_BATCH {
                break;
            }
            // The part's own density: two parts of one phase may differ in it.
            let (part, d) = ins.mixture.draw(&mut feed.rng);
            let (phase, density) = (part.phase, part.density);
            let v = std::f64::consts::FRAC_PI_6 * d * d * d;
            feed.drawn.0 += 1;
            feed.drawn.1 += v;
            feed.drawn.2 += density * v;
            drawn.push((phase, d, density));
        }
        feed.batches += 1;
        if drawn.is_empty() {
            return Ok(());
        }
        let diameters: Vec<f64> = drawn.iter().map(|d| d.1).collect();
        // The inside of a moving mesh moves with it: the region where the mesh is now.
        let own = self.region_mesh(&ins.region);
        let moved = own.filter(|&m| self.sources.meshes.walls[m].motion.moves()).map(|m| {
            let inside = InsideMesh::of_corners(
                self.sources.meshes.walls[m].mesh.name(),
                self.mesh_corners_now(m),
                None,
            );
            Region::Mesh(Box::new(inside))
        });
        let region = moved.as_ref().unwrap_or(&ins.region);
        let margin = ins.mixture.max_diameter();
        let triangles = self.mesh_triangles_near(region, margin);
        let solids = self.solids_for(region, own, margin);
        let solids: Vec<&InsideMesh> = solids.iter().map(|s| s.as_ref()).collect();
        let periodic = self.periodic.any().then_some(self.periodic);
        // On ranks, every rank's particles near the region (the placement looks no further
        // than 1.5 new radii and a present one's radius beyond it).
        let (lo, hi) = region.bounds();
        let near = self.particles_near(Some((lo, hi, 2.0 * margin)));
        let p = &self.particles;
        let (positions, radii) = match &near {
            Some(n) => (&n.1[..], &n.2[..]),
            None => (&p.position[..], &p.radius[..]),
        };
        let obstacles = Obstacles {
            positions,
            radii,
            walls: &self.walls,
            cylinders: &self.sources.cylinders.walls,
            triangles: &triangles,
            solids: &solids,
            periodic,
        };
        let centres = place(region, &diameters, &obstacles, &mut self.flow.feeds[k].rng);
        let mut new = Vec::with_capacity(centres.len());
        for (&(phase, d, density), c) in drawn.iter().zip(centres) {
            let Some(mut position) = c else {
                self.flow.feeds[k].missed += 1;
                continue;
            };
            if let Some(z) = ins.plane_z {
                position.z = z;
            }
            let id = u32::try_from(self.flow.next_id).map_err(|_| {
                EngineError::BadReference(format!(
                    "insertion '{}': particle ids beyond {}",
                    ins.name,
                    u32::MAX
                ))
            })?;
            self.flow.next_id += 1;
            new.push(ParticleInit {
                id,
                phase,
                radius: 0.5 * d,
                density,
                position,
                velocity: ins.velocity,
                omega: Vec3::ZERO,
            });
        }
        if new.is_empty() {
            return Ok(());
        }
        self.add_inserted(k, &new)
    }

    /// The mesh walls' triangles, where they are now, whose bounding boxes come within
    /// `margin` of `region`'s.
    fn mesh_triangles_near(&self, region: &Region, margin: f64) -> Vec<[Vec3; 3]> {
        let (lo, hi) = region.bounds();
        let (lo, hi) = (lo - Vec3::splat(margin), hi + Vec3::splat(margin));
        let mut out = Vec::new();
        for m in 0..self.sources.meshes.walls.len() {
            let v = self.mesh_vertices(m);
            for t in self.sources.meshes.walls[m].mesh.triangles() {
                let c = t.map(|k| v[k as usize]);
                let (a, b) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
                if a.cmple(hi).all() && b.cmpge(lo).all() {
                    out.push(c);
                }
            }
        }
        out
    }
}

/// Outlets remove the particles that have left through them every this many steps (each
/// removal moves the particles to new slots, which costs about a neighbour-list build).
pub const DRAIN_EVERY: u64 = 10;

/// The most particles one batch may draw (a guard against an amount or rate that would take
/// gigabytes: 10⁷ particles are about 2 GB of state).
const MAX_BATCH: usize = 10_000_000;

/// What a batch draws up to: the insertion's total so far must reach the count, volume or mass.
#[derive(Debug, Clone, Copy)]
enum Target {
    Count(u64),
    Volume(f64),
    Mass(f64),
}

impl Target {
    fn reached(self, (n, v, m): (u64, f64, f64)) -> bool {
        match self {
            Target::Count(c) => n >= c,
            Target::Volume(x) => v >= x,
            Target::Mass(x) => m >= x,
        }
    }
}

/// True if the insertion has drawn its whole amount.
fn amount_reached(amount: Option<Amount>, drawn: (u64, f64, f64), volume: f64) -> bool {
    amount.is_some_and(|a| total_target(a, volume).reached(drawn))
}

fn total_target(a: Amount, volume: f64) -> Target {
    match a {
        Amount::Count(n) => Target::Count(n),
        Amount::VolumeFraction(f) => Target::Volume(f * volume),
        Amount::Mass(m) => Target::Mass(m),
    }
}

/// Batch `k`'s target: the amount for an insertion all at once; for a rate, what the rate
/// gives by the end of the batch's interval, capped by the amount. A rate in particles and
/// an amount in mass or volume (or the other way round) each stop the batch.
fn batch_target(ins: &Insertion, k: u64, volume: f64) -> Target {
    let whole = ins.amount.map(|a| total_target(a, volume));
    match ins.schedule {
        Schedule::Once { .. } => whole.unwrap_or(Target::Count(0)),
        Schedule::Rate { rate, every, .. } => {
            let by = (k + 1) as f64 * every;
            let rate_target = match rate {
                Rate::Particles(r) => Target::Count((r * by).round() as u64),
                Rate::Mass(r) => Target::Mass(r * by),
            };
            match (whole, rate_target) {
                (Some(Target::Count(a)), Target::Count(b)) => Target::Count(a.min(b)),
                (Some(Target::Mass(a)), Target::Mass(b)) => Target::Mass(a.min(b)),
                // Different kinds: the rate's target; the whole amount stops the drawing too
                // (`amount_reached`).
                (_, t) => t,
            }
        }
    }
}
