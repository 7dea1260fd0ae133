//! The simulation: set-up from a [`SimulationConfig`] and the time loop.

use crate::boundary::Periodic;
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{CoeffTable, ContactLaw, ContactParams, ContactSizes};
use crate::error::EngineError;
use crate::forces::source::{self as sources, LoadRun, Sources, View};
use crate::forces::{self, ForcePlan};
use crate::integrate::{self, Integrator};
use crate::material::{Phase, WallMaterial};
use crate::math::Vec3;
use crate::mesh::MeshWall;
use crate::motion::{self, PrescribedMotion, ResolvedMotion};
use crate::neighbor::NeighborList;
use crate::observe::Diagnostics;
use crate::state::Particles;
use crate::timestep::{self, TimeStepChoice, TimeStepRule};
use crate::wall::Wall;

mod choice;
mod inflow;
mod population;
mod ranks;
mod whole;

pub use crate::forces::source::{
    MeshLoad, periodic_cylinder_message, periodic_cylinder_reach, periodic_mesh_message, periodic_mesh_reach,
};
pub use choice::ThreadReport;
pub use inflow::{FlowBooks, Tally};
pub use population::ResortRule;
pub use ranks::{DomainStats, starting_ranks};

/// Standard gravity, m/s² (MFIX's default, along −y).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// The neighbour skin used when none is given: 20 % of the largest radius, m.
pub fn default_skin(max_radius: f64) -> f64 {
    0.2 * max_radius
}

/// The sizes a run's particles take, per phase, from its particles and insertions: what
/// [`ContactSizes::Own`] needs to know at set-up.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSizes {
    /// The phases with the smallest diameter any of their particles has or can be inserted
    /// with (the phase's own where it has none): what the time step is taken from.
    pub smallest: Vec<Phase>,
    /// Some particle has, or can be inserted with, another diameter or density than its
    /// phase's reference: contacts' coefficients then differ from their phases'.
    pub vary: bool,
}

impl RunSizes {
    /// The sizes of `particles` and of those `insertions` bring, for `phases`.
    pub fn of(
        phases: &[Phase],
        particles: &Particles,
        insertions: &[crate::insertion::Insertion],
    ) -> RunSizes {
        RunSizes::over(phases, particles, insertions, whole::Whole(None))
    }

    /// [`of`](Self::of) for every rank's particles of `whole`, from this rank's.
    fn over(
        phases: &[Phase],
        particles: &Particles,
        insertions: &[crate::insertion::Insertion],
        whole: whole::Whole<'_>,
    ) -> RunSizes {
        // A particle made from its phase's diameter and density by another formula may differ
        // in the last bits; 1e-12 is far below any size a distribution would draw.
        let differs = |a: f64, b: f64| (a - b).abs() > 1e-12 * b.abs();
        let mut smallest: Vec<f64> = vec![f64::INFINITY; phases.len()];
        let mut vary = false;
        for i in 0..particles.len() {
            let k = particles.phase[i] as usize;
            let Some(ph) = phases.get(k) else { continue };
            let r = particles.radius[i];
            smallest[k] = smallest[k].min(2.0 * r);
            vary |= differs(r, ph.radius()) || differs(particles.mass[i], ph.mass());
        }
        for part in insertions.iter().flat_map(|ins| &ins.mixture.parts) {
            let k = part.phase as usize;
            let Some(ph) = phases.get(k) else { continue };
            let (lo, hi) = (part.sizes.min_diameter(), part.sizes.max_diameter());
            smallest[k] = smallest[k].min(lo);
            vary |= differs(lo, ph.diameter) || differs(hi, ph.diameter) || differs(part.density, ph.density);
        }
        let (smallest, vary) = (whole.mins(smallest), whole.any(vary));
        let smallest = phases
            .iter()
            .zip(smallest)
            .map(|(ph, d)| Phase { diameter: if d.is_finite() { d } else { ph.diameter }, ..ph.clone() })
            .collect();
        RunSizes { smallest, vary }
    }
}

/// The skin for a law whose formed contacts hold to a pull-off distance `reach` (0 for the
/// others, whose skin is kept): a contact stretched to −`reach` must be in the list when it is
/// rebuilt, so the skin must exceed it. A default skin is raised to twice the reach; a given
/// one at or below it is refused.
fn skin_reaching(skin: f64, given: bool, reach: f64) -> Result<f64, EngineError> {
    if skin > reach || reach == 0.0 {
        Ok(skin)
    } else if given {
        Err(EngineError::invalid(
            "skin",
            skin,
            format!(
                "the neighbour skin must exceed the largest pull-off distance of the contacts, {reach:e} m, so that a contact stretched to it stays in the list"
            ),
        ))
    } else {
        Ok(2.0 * reach)
    }
}

/// Everything the engine needs besides the particles, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Solids phases; particles refer to them by index.
    pub phases: Vec<Phase>,
    /// Wall materials; walls refer to them by index.
    pub wall_materials: Vec<WallMaterial>,
    /// Walls.
    pub walls: Vec<Wall>,
    /// Triangle-mesh walls.
    pub meshes: Vec<MeshWall>,
    /// Cylinder walls (exact, infinite).
    pub cylinders: Vec<crate::wall::Cylinder>,
    /// The contact law.
    pub law: ContactLaw,
    /// Contact inputs per phase pair, in MFIX's upper-triangle order (1-1, 1-2, …, 2-2, …).
    pub pair_params: Vec<ContactParams>,
    /// Contact inputs per phase and wall material: index `phase * n_wall_materials + material`.
    pub wall_params: Vec<ContactParams>,
    /// Time integrator.
    pub integrator: Integrator,
    /// Time-step rule.
    pub time_step: TimeStepRule,
    /// Start time, s.
    pub t_start: f64,
    /// End time, s.
    pub t_stop: f64,
    /// Gravitational acceleration, m/s².
    pub gravity: Vec3,
    /// Neighbour-list skin, m; `None` takes 10 % of the largest particle diameter.
    pub skin: Option<f64>,
    /// Prescribed motion rules.
    pub motion: Vec<PrescribedMotion>,
    /// Periodic axes of the domain box, if any.
    pub periodic: Option<Periodic>,
    /// When the particles are re-sorted along a space-filling curve during the run (results
    /// do not depend on it).
    pub resort: ResortRule,
    /// Particles poured in during the run.
    pub insertions: Vec<crate::insertion::Insertion>,
    /// Where particles leave the run (removed and counted).
    pub outlets: Vec<crate::insertion::Outlet>,
}

/// A running simulation.
#[derive(Debug, Clone)]
pub struct Simulation {
    particles: Particles,
    phases: Vec<Phase>,
    walls: Vec<Wall>,
    /// Everything the particles touch: pairs, plane walls, mesh walls ([`crate::forces::source`]).
    pub(crate) sources: Sources,
    /// Insertions, outlets and their books.
    flow: inflow::FlowStage,
    law: ContactLaw,
    coeffs: CoeffTable,
    integrator: Integrator,
    time_step: TimeStepChoice,
    gravity: Vec3,
    /// Time at step `step_base`: t_start, or the time of a checkpoint restored with another
    /// time step.
    t_base: f64,
    step_base: u64,
    t_stop: f64,
    step: u64,
    neighbors: NeighborList,
    motion: Vec<ResolvedMotion>,
    periodic: Periodic,
    /// Slots held fixed by prescribed motion (empty if none).
    held: Vec<bool>,
    /// The mass all particles have (`.0`, if they have the same) and the mass and moment of
    /// inertia all integrated particles have (`.1`, if they have the same); `None` outside when
    /// not known (the particles were lent out for changes since).
    common: Option<Common>,
    /// Runs of slots that are integrated (every slot not under prescribed motion).
    free: Vec<std::ops::Range<usize>>,
    history_started: bool,
    pub(crate) forces_current: bool,
    /// The caller's name for the run this state belongs to, carried through checkpoints.
    run_id: String,
    /// The caller's record kept with the state in checkpoints (see
    /// [`checkpoint_note`](Simulation::checkpoint_note)).
    note: Vec<u8>,
    /// Velocity Verlet between its drift and the end of the step: the positions are a step
    /// ahead of the clock.
    drifted: bool,
    /// Velocity Verlet within [`advance`](Simulation::advance): the last step's second half
    /// kick (and periodic wrap) is left for the next step's first pass. Never true between
    /// calls of the public methods.
    kick_pending: bool,
    /// Per-stage wall-clock times, when enabled.
    timing: Option<StageTimes>,
    /// Threads of the force stage (None: the calling thread only).
    pool: Option<std::sync::Arc<rayon::ThreadPool>>,
    /// Whether a step runs on the pool ([`choice`]).
    choice: choice::ThreadChoice,
    /// Steps run on the pool only from this many particles.
    parallel_from: usize,
    /// The largest force and torque components of the last force evaluation's loads, from
    /// which the next takes the quanta of its order-free sums (`forces::sum`); `None` before
    /// the first.
    load_peak: Option<forces::Peak>,
    /// The floor of those quanta, from the case (never the particles).
    peak_floor: forces::Peak,
    /// Force evaluations whose loads grew beyond what their quanta sum exactly.
    inexact_sums: u64,
    /// When and how the particles were last re-sorted.
    sort: population::SortState,
    /// The particle count the slot facts (held, free runs, blocks) were derived for.
    slot_count: usize,
    /// This rank's part of a run spread over ranks (`None` in one process).
    domain: Option<Box<ranks::Decomposition>>,
}

impl Simulation {
    /// Checks the inputs, derives the coefficients and the time step, and builds the
    /// neighbour list.
    pub fn new(config: SimulationConfig, particles: Particles) -> Result<Self, EngineError> {
        let mut sim = Simulation::unbuilt(config, particles)?;
        sim.neighbors.build(&sim.particles, &sim.walls);
        // Two particles at the same centre have no contact normal: the force loop would
        // treat them as not touching.
        if let Some((key, x)) = sim.same_centre_pair() {
            return Err(same_centre(key, x));
        }
        // Batches due at the start are in the initial state.
        sim.flow_stage(false)?;
        sim.prepare_mesh_candidates();
        Ok(sim)
    }

    /// [`new`](Self::new) without building the neighbour list: for a restart, whose list comes
    /// from the checkpoint (a large bed would otherwise hold two lists at once).
    pub(crate) fn unbuilt(config: SimulationConfig, particles: Particles) -> Result<Self, EngineError> {
        Ok(Simulation::unbuilt_over(config, particles, whole::Whole(None))?.0)
    }

    /// [`unbuilt`](Self::unbuilt) from this rank's share of the particles, with the facts of
    /// the whole set reduced over the ranks of `whole`; with them, also every rank's motion
    /// rules by ids, in the case's order.
    fn unbuilt_over(
        config: SimulationConfig,
        particles: Particles,
        whole: whole::Whole<'_>,
    ) -> Result<(Self, Vec<ranks::RuleById>), EngineError> {
        for ph in &config.phases {
            ph.validate()?;
        }
        for wm in &config.wall_materials {
            wm.validate()?;
        }
        if config.phases.is_empty() {
            return Err(EngineError::BadReference("at least one phase is needed".into()));
        }
        if let Some(m) = config.meshes.iter().find(|m| m.material >= config.wall_materials.len()) {
            return Err(EngineError::BadReference(format!(
                "mesh '{}' uses wall material {} but only {} are defined",
                m.mesh.name(),
                m.material,
                config.wall_materials.len()
            )));
        }
        for m in &config.meshes {
            check_mesh_motion(m)?;
        }
        if config.meshes.len() > u32::MAX as usize {
            return Err(EngineError::BadReference("too many meshes".into()));
        }
        for c in &config.cylinders {
            sources::check_cylinder(c, config.wall_materials.len()).map_err(EngineError::BadReference)?;
        }
        for w in &config.walls {
            if w.material >= config.wall_materials.len() {
                return Err(EngineError::BadReference(format!(
                    "wall '{}' uses wall material {} but only {} are defined",
                    w.name,
                    w.material,
                    config.wall_materials.len()
                )));
            }
            if !(w.normal.is_finite() && w.point.is_finite()) {
                return Err(EngineError::BadReference(format!(
                    "wall '{}' needs a finite point and a non-zero normal",
                    w.name
                )));
            }
        }
        whole.agree(check_lengths(&particles))?;
        let mut particles = particles;
        for loads in [&mut particles.force, &mut particles.torque] {
            loads.resize(particles.id.len(), Vec3::ZERO);
        }
        if let Some(id) = whole.repeated_id(&particles.id) {
            return Err(EngineError::BadReference(format!("particle id {id} is used twice")));
        }
        whole.agree(check_each(&particles, config.phases.len()))?;
        if !(config.t_start.is_finite() && config.t_stop.is_finite() && config.t_stop > config.t_start) {
            return Err(EngineError::invalid(
                "t_stop",
                config.t_stop,
                format!("the end time must be finite and after the start time {} s", config.t_start),
            ));
        }
        if !config.gravity.is_finite() {
            return Err(EngineError::BadReference("gravity must be a finite vector in m/s²".into()));
        }
        let sizes = RunSizes::over(&config.phases, &particles, &config.insertions, whole);
        let reference = coeff_table(&config, &config.phases)?;
        // Contacts' own sizes where they differ from the phases' (where they do not, the
        // phases' coefficients are the contacts' own, and cost nothing per contact).
        let own = config.law.sizes == ContactSizes::Own && sizes.vary;
        let fastest = whole.max(timestep::fastest(&particles));
        let time_step = choose_time_step(&config, fastest, &sizes, &reference)?;
        let heaviest = whole.max(particles.mass.iter().copied().fold(0.0, f64::max));
        let next_id = whole.max_u64(particles.id.iter().map(|&i| i as u64 + 1).max().unwrap_or(1));
        let flow = inflow::FlowStage::new(
            config.insertions,
            config.outlets,
            (heaviest, next_id),
            config.phases.len(),
        )?;
        let mut flow = flow;
        flow.count_initial(&particles.mass, whole);
        let r_held = whole.max(particles.max_radius());
        let r_max = r_held.max(flow.max_radius());
        let peak_floor = sum_floor(&config.law, &config.phases, &reference);
        let coeffs =
            if own { reference.per_unit_size(&config.law, &config.phases, r_max) } else { reference };
        let skin = match config.skin {
            Some(s) if s.is_finite() && s >= 0.0 => s,
            Some(s) => {
                return Err(EngineError::invalid(
                    "skin",
                    s,
                    "the neighbour skin must be a length >= 0, in m",
                ));
            }
            None => default_skin(r_max),
        };
        let skin = skin_reaching(skin, config.skin.is_some(), coeffs.reach())?;
        if config.integrator == Integrator::AdamsBashforth && particles.accel_prev.is_empty() {
            particles.accel_prev = vec![Vec3::ZERO; particles.len()];
            particles.alpha_prev = vec![Vec3::ZERO; particles.len()];
        }
        let (motion, rules) = whole.resolve_motion(&config.motion, &particles)?;
        let free = motion::free_runs(&motion, particles.len());
        let periodic = config.periodic.unwrap_or(Periodic::NONE);
        periodic.check(r_max, skin, &config.walls)?;
        if let Some((m, axis, from, to)) =
            sources::periodic_mesh_reach(&config.meshes, &periodic, r_max, config.t_stop - config.t_start)
        {
            let name = config.meshes[m].mesh.name();
            return Err(EngineError::BadReference(sources::periodic_mesh_message(
                name,
                (axis, from, to),
                &periodic,
                r_max,
            )));
        }
        if let Some((c, axis)) = sources::periodic_cylinder_reach(&config.cylinders, &periodic, r_max) {
            return Err(EngineError::BadReference(sources::periodic_cylinder_message(
                &config.cylinders[c],
                axis,
                r_max,
            )));
        }
        let mut neighbors = NeighborList::with_periodic(skin, periodic);
        let held = motion::held(&motion, particles.len());
        neighbors.exclude_pairs_among(held.clone());
        neighbors.keep_histories_apart(config.law.history.kept_apart());
        let held = if held.iter().any(|&h| h) { held } else { Vec::new() };
        let n_particles = particles.len();
        let mut sim = Simulation {
            particles,
            phases: config.phases,
            walls: config.walls,
            sources: Sources {
                planes: sources::Planes,
                pairs: sources::Pairs::default(),
                meshes: sources::Meshes::new(config.meshes, config.t_start),
                cylinders: sources::Cylinders::new(config.cylinders),
            },
            flow,
            law: config.law,
            coeffs,
            integrator: config.integrator,
            time_step,
            gravity: config.gravity,
            t_base: config.t_start,
            step_base: 0,
            t_stop: config.t_stop,
            step: 0,
            neighbors,
            motion,
            periodic,
            held,
            common: None,
            free,
            history_started: false,
            forces_current: false,
            kick_pending: false,
            drifted: false,
            run_id: String::new(),
            note: Vec::new(),
            timing: None,
            pool: None,
            choice: Default::default(),
            parallel_from: forces::MIN_PARALLEL_PARTICLES,
            load_peak: None,
            peak_floor,
            inexact_sums: 0,
            sort: population::SortState { rule: config.resort, ..Default::default() },
            slot_count: n_particles,
            domain: None,
        };
        whole.agree(sim.put_prescribed_last())?;
        Ok((sim, rules))
    }

    /// The particles.
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// The particles, for user hooks that change the state between steps: their values, or
    /// (with [`Particles::push`]) new particles at the end, as [`insert`](Self::insert) adds
    /// them but without its checks. Removing particles or moving them to other slots goes
    /// through [`remove_where`](Self::remove_where) and [`sort_spatially`](Self::sort_spatially).
    pub fn particles_mut(&mut self) -> &mut Particles {
        self.forces_current = false;
        self.common = None;
        &mut self.particles
    }

    /// Hands over the particles' storage and goes on with a copy of it: the state is the
    /// same to the bit, in storage of its own. For a reader that holds views into the
    /// storage (the Python package's arrays): they stay valid, as they were, whatever the
    /// simulation does next.
    pub fn swap_out_particles(&mut self) -> Particles {
        let copy = self.particles.clone();
        std::mem::replace(&mut self.particles, copy)
    }

    /// The phases.
    pub fn phases(&self) -> &[Phase] {
        &self.phases
    }

    /// The walls.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The contact law.
    pub fn law(&self) -> &ContactLaw {
        &self.law
    }

    /// The derived contact coefficients.
    pub fn coefficients(&self) -> &CoeffTable {
        &self.coeffs
    }

    /// The integrator.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// The time step, the step count and why.
    pub fn time_step(&self) -> &TimeStepChoice {
        &self.time_step
    }

    /// Δt, s.
    pub fn dt(&self) -> f64 {
        self.time_step.dt
    }

    /// Steps taken so far.
    pub fn step_index(&self) -> u64 {
        self.step
    }

    /// The caller's name for the run this state belongs to (empty unless set), written into
    /// checkpoints and restored from them: a run continued from a checkpoint keeps it, so its
    /// outputs can be told from another run's.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// Names the run (see [`run_id`](Self::run_id)).
    pub fn set_run_id(&mut self, id: impl Into<String>) {
        self.run_id = id.into();
    }

    /// The caller's record of what lies outside the state (empty unless set): bytes written
    /// into checkpoints with the state and restored from them, untouched by the engine. The
    /// run loop keeps in it what its output files held when the state was taken, so that a
    /// restart can check them and continue their books.
    pub fn checkpoint_note(&self) -> &[u8] {
        &self.note
    }

    /// Sets the record written with the next checkpoints (see
    /// [`checkpoint_note`](Self::checkpoint_note)).
    pub fn set_checkpoint_note(&mut self, note: Vec<u8>) {
        self.note = note;
    }

    /// Steps of the whole run.
    pub fn total_steps(&self) -> u64 {
        self.time_step.steps
    }

    /// True when every step of the run has been taken.
    pub fn finished(&self) -> bool {
        self.step >= self.time_step.steps
    }

    /// Simulated time, s: t_0 + steps·Δt.
    pub fn time(&self) -> f64 {
        self.t_base + (self.step - self.step_base) as f64 * self.time_step.dt
    }

    /// The time of the particles' positions: [`time`](Self::time), or a step later between
    /// velocity Verlet's drift and the end of its step (as `time` will then be, to the bit).
    fn positions_time(&self) -> f64 {
        self.t_base + (self.step + u64::from(self.drifted) - self.step_base) as f64 * self.time_step.dt
    }

    /// Force evaluations so far in which a load grew more than a thousandfold over the largest
    /// of the evaluation before, beyond what the order-free sums hold exactly: their results
    /// are correctly rounded but may depend on the order of the particles and the threads
    /// (see `forces::sum`). Zero in a run whose results are independent of both.
    pub fn inexact_sums(&self) -> u64 {
        self.inexact_sums
    }

    /// The neighbour list (with the contact histories).
    pub fn neighbors(&self) -> &NeighborList {
        &self.neighbors
    }

    /// (steps taken, Adams–Bashforth history present, forces of the current state held).
    pub(crate) fn counters(&self) -> (u64, bool, bool) {
        (self.step, self.history_started, self.forces_current)
    }

    /// (the last evaluation's load peaks, force evaluations with inexact sums) for checkpoints.
    pub(crate) fn sums_state(&self) -> (Option<forces::Peak>, u64) {
        (self.load_peak, self.inexact_sums)
    }

    /// Restores what [`sums_state`](Self::sums_state) gave.
    pub(crate) fn set_sums_state(&mut self, peak: Option<forces::Peak>, inexact: u64) {
        self.load_peak = peak;
        self.inexact_sums = inexact;
    }

    /// (current time, Δt, start time of the run's clock) for checkpoints.
    pub(crate) fn timing(&self) -> (f64, f64, f64) {
        (self.time(), self.time_step.dt, if self.step_base == 0 { self.t_base } else { f64::NAN })
    }

    /// The initial positions prescribed particles return to.
    pub(crate) fn motion_anchors(&self) -> Vec<Vec3> {
        motion::anchors(&self.motion)
    }

    /// Applies the dynamic state read from a checkpoint (after `new` built the rest). `timing`
    /// is the checkpoint's (time, Δt, t_start): with the same Δt and start the step count
    /// carries the time exactly; otherwise (the case was changed) the clock is rebased at the
    /// checkpoint's time and the remaining steps are counted anew.
    pub(crate) fn restore_dynamic_state(
        &mut self,
        timing: (f64, f64, f64),
        step: u64,
        history_started: bool,
        forces_current: bool,
        neighbors: crate::neighbor::NeighborState,
        anchors: &[Vec3],
    ) -> Result<(), String> {
        self.neighbors.set_state(neighbors, self.particles.len(), self.walls.len())?;
        motion::set_anchors(&mut self.motion, anchors)?;
        self.step = step;
        let (time, dt, t_start) = timing;
        if dt != self.time_step.dt || t_start != self.t_base {
            self.t_base = time;
            self.step_base = step;
            self.time_step.steps = step + crate::timestep::step_count(self.t_stop - time, self.time_step.dt);
        }
        self.history_started = history_started;
        self.forces_current = forces_current;
        Ok(())
    }

    /// Runs the force stage on `threads` threads (1: on the calling thread only). The results
    /// are bit-identical for every thread count: the sums keep one order (see [`forces`]).
    pub fn set_threads(&mut self, threads: usize) -> Result<(), EngineError> {
        if threads == 0 {
            return Err(EngineError::invalid("threads", 0.0, "the thread count must be at least 1"));
        }
        self.pool = if threads == 1 {
            None
        } else {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(|i| format!("grainflow-{i}"))
                .build()
                .map_err(|e| EngineError::BadReference(format!("cannot start {threads} threads: {e}")))?;
            Some(std::sync::Arc::new(pool))
        };
        self.choice = choice::ThreadChoice::new(false, threads);
        Ok(())
    }

    /// Threads of the force stage.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }

    /// Heap bytes held by the particles, by the neighbour list with the contact histories, and
    /// by the parallel force stage's plan.
    pub fn heap_bytes(&self) -> MemoryUse {
        MemoryUse {
            particles: self.particles.heap_bytes(),
            neighbors: self.neighbors.heap_bytes() + self.sources.heap_bytes(),
            threads: self.sources.pairs.plan.heap_bytes(),
        }
    }

    /// Starts measuring the wall-clock time of each stage (a few clock reads per step).
    pub fn enable_stage_timing(&mut self) {
        self.timing.get_or_insert_with(StageTimes::default);
    }

    /// The stage times so far, if timing is on.
    pub fn stage_times(&self) -> Option<StageTimes> {
        self.timing
    }

    /// Advances one step: contact forces, integration, prescribed motion.
    pub fn step(&mut self) {
        self.on_stages(|sim, par| sim.step_chosen(par, false));
    }

    /// Takes up to `steps` steps (stopping at the end of the run). Between the steps of one
    /// call, velocity Verlet does the second half kick of a step and the first of the next in
    /// one pass (the same arithmetic in the same order as [`step`](Self::step) after
    /// `step`): the state after the call is the same to the bit, with fewer passes over the
    /// particles.
    pub fn advance(&mut self, steps: u64) {
        let steps = steps.min(self.total_steps().saturating_sub(self.step));
        if steps == 0 {
            return;
        }
        self.on_stages(|sim, par| sim.advance_on(steps, par));
    }

    /// Runs `f` on the thread pool if the stages run in parallel (telling it so), else here.
    fn on_stages(&mut self, f: impl FnOnce(&mut Simulation, bool) + Send) {
        match self.pool.clone() {
            Some(pool) if self.parallel() => crate::threads::with_team(&pool, || f(self, true)),
            _ => f(self, false),
        }
    }

    /// `steps` steps (not beyond the end of the run); with `par`, on the current rayon pool.
    fn advance_on(&mut self, steps: u64, par: bool) {
        for i in 0..steps {
            self.step_chosen(par, i + 1 < steps);
        }
        debug_assert!(!self.kick_pending);
    }

    /// Runs `f` with the simulation on its thread pool (directly when it has none). Steps
    /// taken inside run on the pool's threads without each being handed over to them, which
    /// costs several microseconds a step: a caller that takes many steps in a row saves that.
    pub fn on_pool<R: Send>(&mut self, f: impl FnOnce(&mut Simulation) -> R + Send) -> R {
        match self.pool.clone() {
            Some(pool) => crate::threads::with_team(&pool, || f(self)),
            None => f(self),
        }
    }

    /// True when the stages may run on the thread pool: it has one, and particles enough
    /// (a step then asks [`choice`] whether they do).
    fn parallel(&self) -> bool {
        self.pool.is_some() && self.particles.len() >= self.parallel_from
    }

    /// The periodic wrap, if any axis is periodic.
    fn wrap(&self) -> Option<Periodic> {
        self.periodic.any().then_some(self.periodic)
    }

    /// One step; with `par`, on the current rayon pool if the choice of threads says so
    /// ([`choice`]), the step timed for it.
    fn step_chosen(&mut self, par: bool, defer: bool) {
        if !par {
            if self.pool.is_some() {
                self.choice.record_unpooled();
            }
            return self.step_on(false, defer);
        }
        let pool = self.choice.use_pool(self.step, self.particles.len());
        let start = std::time::Instant::now();
        self.step_on(pool, defer);
        self.choice.record(pool, start.elapsed().as_secs_f64(), self.step);
    }

    /// One step; with `par`, the per-particle stages use the current rayon pool. With `defer`
    /// (velocity Verlet only), the second half kick and the periodic wrap are left pending for
    /// the next step.
    fn step_on(&mut self, par: bool, defer: bool) {
        if self.particles.len() != self.slot_count {
            // Particles were pushed through `particles_mut`.
            self.adopt_pushed();
        }
        if let Err(e) = self.flow_stage(par) {
            self.flow.error.get_or_insert(e.to_string());
        }
        self.resort_if_due(par);
        let busy_from = self.busy_from();
        let start = self.timing.map(|t| (std::time::Instant::now(), t));
        let dt = self.time_step.dt;
        let g = self.gravity;
        let n = self.particles.len();
        match self.integrator {
            Integrator::Euler => {
                self.evaluate_forces(true, par);
                let common = self.common_mass_and_inertia();
                let blocks = thread_blocks(&self.sources.pairs.plan, par, n);
                let pass = integrate::Pass { runs: &self.free, gravity: g, dt, blocks, common };
                integrate::euler(&mut self.particles, &pass);
            }
            Integrator::AdamsBashforth => {
                self.evaluate_forces(true, par);
                let first = !self.history_started;
                let common = self.common_mass_and_inertia();
                let blocks = thread_blocks(&self.sources.pairs.plan, par, n);
                let pass = integrate::Pass { runs: &self.free, gravity: g, dt, blocks, common };
                integrate::adams_bashforth(&mut self.particles, &pass, first);
            }
            Integrator::VelocityVerlet => {
                if self.kick_pending && !self.forces_current {
                    // Prescribed motion moved particles: the pending kick takes the forces
                    // of the last evaluation, before they are evaluated again.
                    self.finish_kick(par);
                }
                if !self.forces_current {
                    // Forces of the current state for the first half kick; the tangential
                    // springs advance once per step, in the evaluation after the drift.
                    self.evaluate_forces(false, par);
                }
                let common = self.common_mass_and_inertia();
                let blocks = thread_blocks(&self.sources.pairs.plan, par, n);
                let pass = integrate::Pass { runs: &self.free, gravity: g, dt, blocks, common };
                if self.kick_pending {
                    let wrap = self.wrap();
                    integrate::verlet_kick_kick_drift(&mut self.particles, &pass, wrap);
                    self.kick_pending = false;
                } else {
                    integrate::verlet_kick_drift(&mut self.particles, &pass);
                }
                self.drifted = true;
                self.evaluate_forces(true, par);
                if defer {
                    self.kick_pending = true;
                } else {
                    let blocks = thread_blocks(&self.sources.pairs.plan, par, n);
                    let pass = integrate::Pass { runs: &self.free, gravity: g, dt, blocks, common };
                    integrate::verlet_kick(&mut self.particles, &pass, None);
                }
            }
        }
        self.history_started = true;
        // Prescribed motion that moves a particle after this evaluation makes the forces stale:
        // they are evaluated again before the next half kick. Particles held at rest where they
        // are change nothing, and the forces of this step stay those of the state. (It moves
        // prescribed slots only, which the pending kick and the wrap after it leave alone or
        // wrap as they would have here.)
        let moved = self.apply_motion();
        let moved = self.moved_on_any_rank(moved);
        self.forces_current = !moved;
        if !self.kick_pending
            && let Some(per) = self.wrap()
        {
            integrate::wrap(&mut self.particles, per, thread_blocks(&self.sources.pairs.plan, par, n));
        }
        if self.domain.is_some() {
            let t = self.timing.map(|_| std::time::Instant::now());
            self.end_of_step_ghosts(defer);
            if let (Some(t), Some(times)) = (t, self.timing.as_mut()) {
                times.domain += t.elapsed().as_secs_f64();
            }
        }
        self.step += 1;
        self.drifted = false;
        self.count_busy(busy_from);
        if let (Some((t0, before)), Some(now)) = (start, self.timing.as_mut()) {
            // Whatever the step spent outside the force stages is integration.
            let forces = (now.neighbor - before.neighbor)
                + (now.walls - before.walls)
                + (now.pairs - before.pairs)
                + (now.meshes - before.meshes);
            now.integrate += (t0.elapsed().as_secs_f64() - forces).max(0.0);
        }
    }

    /// Takes in particles pushed through `particles_mut` since the slot facts were derived.
    fn adopt_pushed(&mut self) {
        let n = self.particles.len();
        let p = &mut self.particles;
        if !p.accel_prev.is_empty() {
            p.accel_prev.resize(n, Vec3::splat(f64::NAN));
            p.alpha_prev.resize(n, Vec3::splat(f64::NAN));
        }
        self.forces_current = false;
        self.derive_slot_facts();
    }

    /// The pending second half kick and periodic wrap, on their own.
    fn finish_kick(&mut self, par: bool) {
        let n = self.particles.len();
        let common = self.common_mass_and_inertia();
        let blocks = thread_blocks(&self.sources.pairs.plan, par, n);
        let (gravity, dt, wrap) = (self.gravity, self.time_step.dt, self.wrap());
        let pass = integrate::Pass { runs: &self.free, gravity, dt, blocks, common };
        integrate::verlet_kick(&mut self.particles, &pass, wrap);
        self.kick_pending = false;
    }

    /// Takes up to `steps` steps (stopping at the end of the run), calling `hook` after each
    /// one — the place for user code between steps (MFIX's UDFs).
    pub fn run_with(&mut self, steps: u64, mut hook: impl FnMut(&mut Simulation)) {
        for _ in 0..steps {
            if self.finished() {
                break;
            }
            self.step();
            hook(self);
        }
    }

    /// Runs to the end without hooks.
    pub fn run_to_end(&mut self) {
        self.advance(self.total_steps().saturating_sub(self.step));
    }

    /// Contact forces and torques from the current state into the accumulators, advancing the
    /// tangential springs by one step (this is the force evaluation of a step).
    pub fn compute_forces(&mut self) {
        self.evaluate_forces(true, self.parallel());
    }

    /// Contact forces and torques into the accumulators. With `advance_history` the tangential
    /// springs take this step's increment (s = h + Δt·v_t) and store it; without, the forces
    /// are those of the stored springs as they are (s = h), and nothing is stored — so
    /// evaluating the same state again gives the same forces and leaves the history alone.
    /// With `par`, on the current rayon pool.
    fn evaluate_forces(&mut self, advance_history: bool, par: bool) {
        let t0 = self.timing.map(|_| std::time::Instant::now());
        let blocks = thread_blocks(&self.sources.pairs.plan, par, self.particles.len());
        if self.domain.is_some() {
            let t = self.timing.map(|_| std::time::Instant::now());
            self.domain_stage();
            if let (Some(t), Some(times)) = (t, self.timing.as_mut()) {
                times.domain += t.elapsed().as_secs_f64();
            }
        } else {
            self.neighbors.update(&self.particles, &self.walls, blocks);
        }
        if let (Some(t0), Some(t)) = (t0, self.timing.as_mut()) {
            t.neighbor += t0.elapsed().as_secs_f64();
        }
        // The first evaluation takes its quanta from the loads of the state as it is (the
        // stored springs not advanced, nothing stored): every later one from the one before.
        if self.load_peak.is_none() {
            self.force_stage(false, par);
            self.inexact_sums = 0;
        }
        self.force_stage(advance_history, par);
    }

    /// The force stage for the simulation's law (see [`evaluate_forces`](Self::evaluate_forces)).
    fn force_stage(&mut self, advance_history: bool, par: bool) {
        crate::with_submodels!(self.law, |N, T| self.force_loop::<N, T>(advance_history, par))
    }

    /// The mass every particle has and the moment of inertia every particle has, each if all
    /// have the same (to the bit); found once and kept until the particles are lent out for
    /// changes.
    fn common(&mut self) -> Common {
        let (p, free) = (&self.particles, &self.free);
        /// The value all of `a` have, to the bit, if they have one.
        fn same(mut a: impl Iterator<Item = f64>) -> Option<f64> {
            let x = a.next()?;
            a.all(|y| y.to_bits() == x.to_bits()).then_some(x)
        }
        let owned = self.domain.as_ref().map_or(p.len(), |d| d.owned);
        let domain = &self.domain;
        *self.common.get_or_insert_with(|| {
            let slots = || free.iter().flat_map(|r| r.clone());
            let free_mass = same(slots().map(|i| p.mass[i]));
            let free_inertia = same(slots().map(|i| p.inertia[i]));
            let common = (same(p.mass[..owned].iter().copied()), free_mass.zip(free_inertia));
            match domain {
                Some(d) => d.common_over_ranks(common, owned == 0, free.is_empty()),
                None => common,
            }
        })
    }

    /// The mass and moment of inertia of every integrated particle (every one not under
    /// prescribed motion), if all have the same: the integration then multiplies by one
    /// inverse of each instead of dividing for each particle.
    fn common_mass_and_inertia(&mut self) -> Option<(f64, f64)> {
        self.common().1
    }

    /// The force stage for one law; with `par`, on the thread pool: every contact source's
    /// loads, in their order.
    fn force_loop<N: NormalSubModel, T: TangentialSubModel>(&mut self, advance_history: bool, par: bool) {
        let common_mass = self.common().0.map(forces::CommonMass::of);
        let peak_before = self.load_peak.unwrap_or([0.0; 2]);
        let quanta = forces::Quanta::new(peak_before, self.peak_floor);
        let (time, r_max, owned) = (self.positions_time(), self.r_max(), self.owned());
        let mut run = LoadRun {
            particles: &mut self.particles,
            neighbors: &mut self.neighbors,
            held: &self.held,
            walls: &self.walls,
            coeffs: &self.coeffs,
            law: self.law,
            periodic: self.periodic,
            common_mass,
            pool: self.pool.as_deref().filter(|_| par),
            quanta,
            advance: advance_history,
            dt: self.time_step.dt,
            time,
            r_max,
            owned,
            peak: [0.0; 2],
            times: self.timing.as_mut(),
        };
        self.sources.loads::<N, T>(&mut run);
        let peak = self.domain.as_ref().map_or(run.peak, |d| d.largest_peak(run.peak));
        if quanta.exceeded_by(peak) {
            self.inexact_sums += 1;
        }
        self.load_peak = Some(peak);
    }

    /// The largest radius a particle of the run has or can be inserted with, m.
    fn r_max(&self) -> f64 {
        self.particles.max_radius().max(self.flow.max_radius())
    }

    /// What the contact sources read of the state, at the time `time` of the positions.
    fn view(&self, time: f64) -> View<'_> {
        View {
            particles: &self.particles,
            law: self.law,
            coeffs: &self.coeffs,
            periodic: self.periodic,
            held: &self.held,
            neighbors: &self.neighbors,
            walls: &self.walls,
            time,
            r_max: self.r_max(),
            owned: self.owned(),
        }
    }

    /// Finds the mesh candidates of the current state if they are not current, so that the
    /// contacts and diagnostics of a state not yet evaluated (a new or a restored simulation)
    /// include its mesh contacts (see [`sources::Meshes::prepare`]).
    pub(crate) fn prepare_mesh_candidates(&mut self) {
        let (time, r_max, owned) = (self.time(), self.r_max(), self.owned());
        let v = View {
            particles: &self.particles,
            law: self.law,
            coeffs: &self.coeffs,
            periodic: self.periodic,
            held: &self.held,
            neighbors: &self.neighbors,
            walls: &self.walls,
            time,
            r_max,
            owned,
        };
        self.sources.meshes.prepare(&v);
    }

    /// Every contact of the current state with its forces, as the next force evaluation would
    /// see them without advancing the tangential springs (for output: force chains): the
    /// contact sources' in their order.
    pub fn contacts(&self) -> Vec<ContactInfo> {
        self.sources.contact_infos(&self.view(self.time()))
    }

    /// [`contacts`](Self::contacts) and the particles, both in the order of the particles'
    /// ids (the contacts by the ids of their particle, then of their partner, walls first):
    /// what outputs write, the same however the particles are stored. A contact's slots are
    /// those of the returned particles.
    pub fn in_id_order(&self) -> (Particles, Vec<ContactInfo>) {
        let p = &self.particles;
        let order = p.id_order();
        let mut new_of = vec![0usize; p.len()];
        for (k, &i) in order.iter().enumerate() {
            new_of[i] = k;
        }
        let mut contacts = self.contacts();
        for c in &mut contacts {
            c.particle = new_of[c.particle];
            if let ContactPartner::Particle(j) = c.other {
                c.other = ContactPartner::Particle(new_of[j]);
            }
        }
        contacts.sort_unstable_by_key(contact_order);
        (p.gathered(&order), contacts)
    }

    /// Energies, contacts and overlaps of the current state.
    ///
    /// The sums do not depend on the order the particles are stored in
    /// ([`crate::observe::order_free_sum`]).
    pub fn diagnostics(&self) -> Diagnostics {
        use crate::observe::order_free_sum;
        let p = &self.particles;
        let mut d = Diagnostics { time: self.time(), step: self.step, ..Default::default() };
        let n = self.owned();
        let per = |f: &dyn Fn(usize) -> f64| (0..n).map(f).collect::<Vec<f64>>();
        let kinetic = per(&|i| 0.5 * p.mass[i] * p.velocity[i].length_squared());
        let rotational = per(&|i| 0.5 * p.inertia[i] * p.omega[i].length_squared());
        let potential = per(&|i| -(p.mass[i] * self.gravity.dot(p.position[i])));
        let mut elastic = Vec::new();
        self.sources.diagnose(&self.view(self.time()), &mut |(delta, r_min, energy)| {
            d.contacts += 1;
            elastic.push(energy);
            d.max_overlap_ratio = d.max_overlap_ratio.max(delta / r_min);
        });
        match &self.domain {
            None => {
                d.kinetic_translational = order_free_sum(&kinetic);
                d.kinetic_rotational = order_free_sum(&rotational);
                d.potential = order_free_sum(&potential);
                d.elastic = order_free_sum(&elastic);
            }
            Some(domain) => {
                let [k, r, u, e] = domain.order_free_sums([&kinetic, &rotational, &potential, &elastic]);
                (d.kinetic_translational, d.kinetic_rotational, d.potential, d.elastic) = (k, r, u, e);
                (d.contacts, d.max_overlap_ratio) = domain.count_and_max(d.contacts, d.max_overlap_ratio);
            }
        }
        d
    }
}

pub(crate) fn check_mesh_motion(m: &MeshWall) -> Result<(), EngineError> {
    use crate::mesh::{MeshMotion, SurfaceMotion};
    let unit = |a: Vec3| a.is_finite() && (a.length() - 1.0).abs() < 1e-12;
    let ok = match m.motion {
        MeshMotion::Fixed => true,
        MeshMotion::Translate { velocity } => velocity.is_finite(),
        MeshMotion::Rotate { origin, axis, omega, ramp } => {
            origin.is_finite() && unit(axis) && omega.is_finite() && ramp.is_finite() && ramp >= 0.0
        }
        MeshMotion::Oscillate { amplitude, frequency } => {
            amplitude.is_finite() && frequency.is_finite() && frequency >= 0.0
        }
    } && m.window.is_valid()
        && match m.surface {
            SurfaceMotion::None => true,
            SurfaceMotion::Translate { velocity } => velocity.is_finite(),
            SurfaceMotion::Rotate { origin, axis, omega } => {
                origin.is_finite() && unit(axis) && omega.is_finite()
            }
        };
    if ok {
        Ok(())
    } else {
        Err(EngineError::BadReference(format!(
            "mesh '{}' has a motion with a non-finite value, an axis that is not a unit vector, a negative ramp or frequency, or a window that does not start at or after the run's start and stop after its start",
            m.mesh.name()
        )))
    }
}

/// Wall-clock seconds spent in each stage of the step, when timing is on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Neighbour search (rebuild checks and rebuilds).
    pub neighbor: f64,
    /// Particle–wall contacts (plane and cylinder walls).
    pub walls: f64,
    /// Particle–particle contacts.
    pub pairs: f64,
    /// Particle–mesh-wall contacts.
    pub meshes: f64,
    /// Integration, prescribed motion, periodic wrapping.
    pub integrate: f64,
    /// On threads: the seconds each thread worked in the force stage (walls and pairs),
    /// averaged over the threads. The rest of the stage's time is waiting: for the slowest
    /// thread, then for the threads to start and finish ([`threads_slowest`](Self::threads_slowest)).
    pub threads_mean: f64,
    /// On threads: the seconds the slowest thread of each parallel pass of the force stage
    /// worked, summed over the passes. The stage took at least this long; `threads_slowest −
    /// threads_mean` is the time the other threads waited for it.
    pub threads_slowest: f64,
    /// Spread over ranks: the domain stage (ghosts refreshed, particles moved and the ranks'
    /// agreements, each including the wait for the other ranks), also counted in the stage it
    /// falls in (neighbour search or integration).
    pub domain: f64,
}

/// Heap bytes of the simulation's parts.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MemoryUse {
    /// Particle state.
    pub particles: usize,
    /// Neighbour list, contact histories (mesh contacts' and the meshes' triangle grids
    /// included) and their scratch space.
    pub neighbors: usize,
    /// Blocks and crossing pairs of the parallel force stage.
    pub threads: usize,
}

/// The other side of a contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactPartner {
    /// A particle slot.
    Particle(usize),
    /// A wall index.
    Wall(usize),
    /// A mesh wall's index and the triangle that owns the contact.
    Mesh { mesh: usize, triangle: usize },
    /// A cylinder wall's index.
    Cylinder(usize),
}

/// One contact of the current state, for output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactInfo {
    /// Slot of the particle the normal points from.
    pub particle: usize,
    /// The other particle, or the wall.
    pub other: ContactPartner,
    /// Contact point (on the radical plane, or on the wall), m.
    pub point: Vec3,
    /// Unit normal from `particle` towards the other.
    pub normal: Vec3,
    /// Overlap, m.
    pub overlap: f64,
    /// Magnitude of the normal force, N.
    pub normal_force: f64,
    /// Magnitude of the tangential force, N.
    pub tangential_force: f64,
}

/// The blocks by which the per-particle stages share the `n` slots out over the threads: the
/// force stage's ([`ForcePlan::blocks_for`]), so that each particle is integrated on the thread
/// that computes its contacts; none (one thread) without `par` or before the first plan.
/// The order of contacts in outputs: by particle, then walls, meshes, cylinders and particles,
/// each by its index.
fn contact_order(c: &ContactInfo) -> (usize, u8, usize, usize) {
    match c.other {
        ContactPartner::Wall(w) => (c.particle, 0, w, 0),
        ContactPartner::Mesh { mesh, triangle } => (c.particle, 1, mesh, triangle),
        ContactPartner::Cylinder(m) => (c.particle, 2, m, 0),
        ContactPartner::Particle(j) => (c.particle, 3, j, 0),
    }
}

/// The mass all particles have, if they have the same; the mass and moment of inertia all
/// integrated particles have, if they have the same.
type Common = (Option<f64>, Option<(f64, f64)>);

fn thread_blocks(plan: &ForcePlan, par: bool, n: usize) -> &[std::ops::Range<usize>] {
    if par { plan.blocks_for(n) } else { &[] }
}

/// The time step [`Simulation::new`] takes for `config` and `particles`: for planning a run
/// before it is built.
pub fn time_step_of(config: &SimulationConfig, particles: &Particles) -> Result<TimeStepChoice, EngineError> {
    let sizes = RunSizes::of(&config.phases, particles, &config.insertions);
    choose_time_step(config, timestep::fastest(particles), &sizes, &coeff_table(config, &config.phases)?)
}

/// The coefficient table of `config`'s law and walls for `phases` (the case's, or sized as
/// the run's smallest particles).
fn coeff_table(config: &SimulationConfig, phases: &[Phase]) -> Result<CoeffTable, EngineError> {
    CoeffTable::build(&config.law, phases, &config.wall_materials, &config.pair_params, &config.wall_params)
}

/// The time step of a run: from the smallest sizes its particles take when contacts have
/// their own sizes and these vary, else from the phases' (`reference` is their table).
fn choose_time_step(
    config: &SimulationConfig,
    fastest: f64,
    sizes: &RunSizes,
    reference: &CoeffTable,
) -> Result<TimeStepChoice, EngineError> {
    let speed = timestep::speed_of(fastest, &config.insertions, &config.meshes);
    let span = config.t_stop - config.t_start;
    if config.law.sizes == ContactSizes::Own && sizes.vary {
        let table = coeff_table(config, &sizes.smallest)?;
        timestep::choose(config.time_step, &config.law, &sizes.smallest, &table, span, &speed)
    } else {
        timestep::choose(config.time_step, &config.law, &config.phases, reference, span, &speed)
    }
}

/// The floor of the force stage's quanta for a case (see `forces::sum`), from its reference
/// force: the largest normal force of any contact at an overlap of the largest reference
/// radius, k_n·R^p with the normal model's force exponent p (JKR's floor ignores its
/// cohesion).
fn sum_floor(law: &ContactLaw, phases: &[Phase], coeffs: &CoeffTable) -> forces::Peak {
    let r = phases.iter().map(|p| p.radius()).fold(0.0, f64::max);
    let (power, _) = law.normal.exponents();
    let kn = coeffs.all().map(|c| c.kn).fold(0.0, f64::max);
    forces::peak_floor(kn * r.powf(power), r)
}

/// Whether particle arrays may start a run with `n_phases` phases: arrays of one length, ids
/// used once, known phases, positive finite radii, masses and moments of inertia, finite
/// positions and velocities. [`Simulation::new`] checks it first.
pub fn check_particles(p: &Particles, n_phases: usize) -> Result<(), EngineError> {
    check_lengths(p)?;
    let mut ids: Vec<u32> = p.id.clone();
    ids.sort_unstable();
    if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
        return Err(EngineError::BadReference(format!("particle id {} is used twice", w[0])));
    }
    check_each(p, n_phases)
}

impl Simulation {
    /// The pair of the list at one centre with the smallest ids, if any: the ids as one key
    /// (the lower in the upper half) and the centre.
    fn same_centre_pair(&self) -> Option<(u64, Vec3)> {
        let (x, id) = (&self.particles.position, &self.particles.id);
        self.neighbors
            .pairs()
            .filter(|&[i, j]| x[i as usize] == x[j as usize])
            .map(|[i, j]| {
                let (a, b) = (id[i as usize].min(id[j as usize]), id[i as usize].max(id[j as usize]));
                ((a as u64) << 32 | b as u64, x[i as usize])
            })
            .min_by_key(|e| e.0)
    }
}

/// Two particles, ids `a` and `b` in `key` (a above b), have the same centre `x`.
fn same_centre(key: u64, x: Vec3) -> EngineError {
    let (a, b) = (key >> 32, key & 0xffff_ffff);
    EngineError::BadReference(format!(
        "particles {a} and {b} have the same centre ({:e}, {:e}, {:e}) m: their contact has no normal direction; move one of them",
        x.x, x.y, x.z
    ))
}

/// Whether the particle arrays all have one length.
fn check_lengths(p: &Particles) -> Result<(), EngineError> {
    let n = p.len();
    let lens = [
        p.phase.len(),
        p.radius.len(),
        p.mass.len(),
        p.inertia.len(),
        p.position.len(),
        p.velocity.len(),
        p.omega.len(),
    ];
    // Loads and the Adams–Bashforth history may be left out (zero).
    let history_ok = [p.force.len(), p.torque.len(), p.accel_prev.len(), p.alpha_prev.len()]
        .iter()
        .all(|&l| l == n || l == 0);
    if lens.iter().any(|&l| l != n) || !history_ok {
        return Err(EngineError::BadReference("particle arrays have different lengths".into()));
    }
    Ok(())
}

/// Whether each particle has a known phase, positive finite size, mass and moment of inertia,
/// and a finite state (the first that has not is named).
fn check_each(p: &Particles, n_phases: usize) -> Result<(), EngineError> {
    for i in 0..p.len() {
        let id = p.id[i];
        if p.phase[i] as usize >= n_phases {
            return Err(EngineError::BadReference(format!(
                "particle {id} has phase index {} but only {n_phases} phases are defined",
                p.phase[i]
            )));
        }
        if !(p.radius[i].is_finite() && p.radius[i] > 0.0) {
            return Err(EngineError::invalid(
                format!("particle {id} radius"),
                p.radius[i],
                "a radius must be positive, in m",
            ));
        }
        if !(p.mass[i].is_finite() && p.mass[i] >= f64::MIN_POSITIVE) {
            return Err(EngineError::invalid(
                format!("particle {id} mass"),
                p.mass[i],
                format!(
                    "the mass must be a positive finite number in kg (radius {:e} m); a density that is not positive, or a radius and density beyond what double precision can hold (not SI units?), give this",
                    p.radius[i]
                ),
            ));
        }
        if !(p.inertia[i].is_finite() && p.inertia[i] >= f64::MIN_POSITIVE) {
            return Err(EngineError::invalid(
                format!("particle {id} moment of inertia"),
                p.inertia[i],
                format!(
                    "the moment of inertia 0.4·m·r² (m = {:e} kg, r = {:e} m) must be a positive finite number; are the radius and density in SI units?",
                    p.mass[i], p.radius[i]
                ),
            ));
        }
        if !(p.position[i].is_finite() && p.velocity[i].is_finite() && p.omega[i].is_finite()) {
            return Err(EngineError::BadReference(format!(
                "particle {id} has a non-finite position, velocity or angular velocity"
            )));
        }
    }
    Ok(())
}
