//! What a run will do, before it does it: the time step and the step count, the outputs and
//! how many of each, the insertions and how many particles each brings, and the memory the
//! run needs at its peak. `grainflow check` prints it; `grainflow run` refuses, before
//! anything large is allocated, a case whose plan cannot work:
//!
//! - an insertion at a rate whose batches (`every`) come more often than the steps: batches
//!   are placed at the start of a step, so more than one a step would only be one larger
//!   batch, and `every` far below the step (or an MFIX mass inflow whose `BC_MASSFLOW_S`
//!   drives its layers through in less than a step) would place millions of batches a step;
//! - a run whose memory estimate exceeds the memory limit ([`MemoryLimit`]): by default half
//!   the memory available when the run starts (`MemAvailable` of `/proc/meminfo`), raised
//!   or lowered with `--memory-limit`.
//!
//! ## The memory estimate
//! From the data structures the run holds, per particle (the engine's `Particles`, a
//! structure of arrays, and its neighbour list), per neighbour pair and per mesh triangle,
//! for the most particles the run can hold at once (those at the start and every one the
//! insertions bring, none taken out), plus what the largest set of particles that arrives at
//! once (the particle file, or an insertion's batch) needs while it is drawn, placed and
//! appended ([`estimate`]). The figures are in [`BYTES_STATE`] and the constants beside it;
//! `tests/memory.rs` compares the estimate with the peak resident memory of runs.

use crate::case::Case;
use crate::error::CaseError;
use grainflow::Integrator;
use grainflow::insertion::{Amount, Insertion, Rate, Schedule};
use std::sync::atomic::{AtomicU64, Ordering};

/// Bytes of one particle's state without Adams–Bashforth history (`Particles`: position,
/// velocity, spin, force and torque as three doubles each; radius, mass and moment of inertia;
/// id and phase as 32-bit integers).
pub const BYTES_STATE: f64 = (5 * 24 + 3 * 8 + 2 * 4) as f64;
/// Adams–Bashforth's previous accelerations (linear and angular), per particle.
pub const BYTES_AB_HISTORY: f64 = (2 * 24) as f64;
/// The neighbour list's per-particle arrays: row offset (8), reference position (24), cell
/// of the particle and the sorted order (4 + 4), the rebuild's scratch (8), and the cells
/// (at most eight a particle, 4 bytes each: 32), and the thread plan's share (about 8).
pub const BYTES_NEIGHBOUR_PER_PARTICLE: f64 = (8 + 24 + 4 + 4 + 8 + 32 + 8) as f64;
/// One neighbour pair: the partner (4), the tangential history (24), the touch flag (1),
/// with the list's growth room (up to half again: 1.5 × 29).
pub const BYTES_PER_PAIR: f64 = 1.5 * 29.0;
/// Neighbour pairs per particle in a dense bed (a half list within the sum of the radii and
/// the skin: 5-6 in a poured bed of equal spheres); the estimate takes it for every particle.
pub const PAIRS_PER_PARTICLE: f64 = 7.0;
/// What a particle costs while it arrives with others at once, beyond its state: the drawn
/// phase, diameter and density (24) and its diameter for the placer (8), the particle as a
/// `ParticleInit` (96), and a second copy of its state while the arrays are appended to and
/// re-sorted ([`BYTES_STATE`]). The neighbour list is built after they have arrived.
pub const BYTES_ARRIVING: f64 = (24 + 8 + 96) as f64 + BYTES_STATE;
/// A particle read from a case file's particle list or an MFIX deck's seeded lattice, as the
/// case file's table (`RawParticle`: optional id, phase name, position, velocity, spin and
/// diameter, about 200 bytes with the name's own allocation) before it becomes a particle.
pub const BYTES_LISTED: f64 = 200.0;
/// One mesh triangle with its grid cells, edge topology and candidates (about 300 bytes).
pub const BYTES_PER_TRIANGLE: f64 = 300.0;
/// The program itself, its threads' stacks and the allocator's arenas.
pub const BYTES_BASE: f64 = 64.0 * 1024.0 * 1024.0;

/// The most memory a run may plan to use, and where the figure comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryLimit {
    /// Bytes.
    pub bytes: f64,
    /// Where it comes from.
    pub source: LimitSource,
}

/// Where a [`MemoryLimit`] comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LimitSource {
    /// Half of `MemAvailable` (bytes) in `/proc/meminfo`.
    HalfAvailable(f64),
    /// `--memory-limit`.
    Given,
    /// Nothing to go by (no `/proc/meminfo`): no limit.
    Unknown,
}

impl MemoryLimit {
    /// The default: half the memory available now, or no limit where that is not known.
    pub fn default_now() -> MemoryLimit {
        match available_memory() {
            Some(a) => MemoryLimit { bytes: a / 2.0, source: LimitSource::HalfAvailable(a) },
            None => MemoryLimit { bytes: f64::INFINITY, source: LimitSource::Unknown },
        }
    }

    /// A limit given by `--memory-limit`.
    pub fn given(bytes: f64) -> MemoryLimit {
        MemoryLimit { bytes, source: LimitSource::Given }
    }

    /// The limit in words, with how to change it.
    pub fn describe(&self) -> String {
        match self.source {
            LimitSource::HalfAvailable(a) => format!(
                "{} (half the {} of memory available; --memory-limit sets another)",
                show_bytes(self.bytes),
                show_bytes(a)
            ),
            LimitSource::Given => format!("{} (--memory-limit)", show_bytes(self.bytes)),
            LimitSource::Unknown => "none (the available memory is not known)".into(),
        }
    }
}

/// `MemAvailable` of `/proc/meminfo`, bytes.
pub fn available_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// `--memory-limit`'s value: a size such as `8GB`, `8GiB`, `500MB`, `2.5G` or a number of
/// bytes. GB and G are 10⁹ bytes, GiB 2³⁰ (likewise for k, M, T).
pub fn parse_size(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024f64.powi(2),
        "gib" => 1024f64.powi(3),
        "tib" => 1024f64.powi(4),
        _ => return Err(format!("'{s}' is not a size like 8GB, 8GiB or 500MB")),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v * scale),
        _ => Err(format!("'{s}' is not a size like 8GB, 8GiB or 500MB (a positive number and a unit)")),
    }
}

/// A number as a user writes it: plain between 10⁻³ and 10⁴, else in exponent form.
fn num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&x.abs()) {
        let s = format!("{x:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{x:.5e}");
        let (m, e) = s.split_once('e').expect("exponent form");
        let m = if m.contains('.') { m.trim_end_matches('0').trim_end_matches('.') } else { m };
        format!("{m}e{e}")
    }
}

/// Bytes in binary units: "512 B", "3.2 MiB", "1.50 GiB".
pub fn show_bytes(b: f64) -> String {
    let k = 1024.0;
    if !b.is_finite() {
        "unlimited".into()
    } else if b >= k * k * k {
        format!("{:.2} GiB", b / (k * k * k))
    } else if b >= k * k {
        format!("{:.1} MiB", b / (k * k))
    } else if b >= k {
        format!("{:.1} KiB", b / k)
    } else {
        format!("{b:.0} B")
    }
}

/// The limit set for this process (`--memory-limit`, or the default when the first check
/// asks), for the checks made while a case is read (an MFIX deck's seeded lattice, a particle
/// file), which run before any [`Plan`].
static LIMIT_BITS: AtomicU64 = AtomicU64::new(0);
static LIMIT_GIVEN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Sets the process's memory limit (`--memory-limit`); `None` keeps the default.
pub fn set_memory_limit(bytes: Option<f64>) {
    if let Some(b) = bytes {
        LIMIT_BITS.store(b.to_bits(), Ordering::SeqCst);
        LIMIT_GIVEN.store(true, Ordering::SeqCst);
    }
}

/// The process's memory limit: the one set, else the default when first asked (the memory
/// the reading itself takes does not lower it).
pub fn memory_limit() -> MemoryLimit {
    static DEFAULT: std::sync::OnceLock<MemoryLimit> = std::sync::OnceLock::new();
    if LIMIT_GIVEN.load(Ordering::SeqCst) {
        MemoryLimit::given(f64::from_bits(LIMIT_BITS.load(Ordering::SeqCst)))
    } else {
        *DEFAULT.get_or_init(MemoryLimit::default_now)
    }
}

/// Particles of a particle file between two looks at the memory limit while it is read.
pub const READ_CHECK_EVERY: usize = 1 << 16;

/// While a particle file is read: `n` particles so far (a multiple of [`READ_CHECK_EVERY`])
/// must fit the process's memory limit as a run's, or the reading stops at line `line`.
pub(crate) fn check_reading(n: usize, path: &str, line: usize) -> Result<(), CaseError> {
    if n == 0 || !n.is_multiple_of(READ_CHECK_EVERY) {
        return Ok(());
    }
    let bytes = estimate(n as f64, n as f64, 0.0, 0.0, Integrator::Euler).bytes;
    check_memory(bytes, &format!("the {n} particles read so far")).map_err(|message| {
        CaseError::ParticleFile {
            path: path.to_string(),
            line,
            message: format!("{message}; reading stopped"),
        }
    })
}

/// The memory a run needs at its peak, and what it is made of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryEstimate {
    /// Bytes at the peak.
    pub bytes: f64,
    /// The most particles the run holds at once.
    pub particles: f64,
    /// The most particles that arrive at once.
    pub arriving: f64,
    /// Bytes per particle held (state, neighbour list and pairs).
    pub per_particle: f64,
    /// Bytes of the mesh walls.
    pub meshes: f64,
}

/// The peak memory of a run that holds up to `particles` at once, `arriving` of them in one
/// go (a particle file, a batch), `listed` of them read as a case file's list first, with
/// `triangles` mesh triangles: the larger of the run's steady state (every particle with its
/// neighbour list and [`PAIRS_PER_PARTICLE`] pairs) and the moment the largest set arrives
/// (the state of all, the arriving set's [`BYTES_ARRIVING`] and, if listed, its
/// [`BYTES_LISTED`]), plus [`BYTES_BASE`].
pub fn estimate(
    particles: f64,
    arriving: f64,
    listed: f64,
    triangles: f64,
    integrator: Integrator,
) -> MemoryEstimate {
    let state = BYTES_STATE + if integrator == Integrator::AdamsBashforth { BYTES_AB_HISTORY } else { 0.0 };
    let per_particle = state + BYTES_NEIGHBOUR_PER_PARTICLE + PAIRS_PER_PARTICLE * BYTES_PER_PAIR;
    let meshes = triangles * BYTES_PER_TRIANGLE;
    let steady = particles * per_particle;
    let arrival = particles * state + arriving * BYTES_ARRIVING + listed * BYTES_LISTED;
    let bytes = BYTES_BASE + meshes + steady.max(arrival);
    MemoryEstimate { bytes, particles, arriving, per_particle, meshes }
}

/// The memory an MFIX deck's lattice of `sites` particles needs: as listed particles, then
/// as the run's (for the checks while the deck is read).
pub fn seeded_bytes(sites: f64) -> f64 {
    estimate(sites, sites, sites, 0.0, Integrator::Euler).bytes
}

/// The refusal of `needed` bytes over the process's limit, if it is over: the message names
/// what needs it.
pub fn check_memory(needed: f64, what: &str) -> Result<(), String> {
    let limit = memory_limit();
    if needed > limit.bytes {
        return Err(format!(
            "{what} would need about {} of memory, more than the limit {}; see docs/case-file.md, \"Memory\"",
            show_bytes(needed),
            limit.describe()
        ));
    }
    Ok(())
}

/// One insertion's plan.
#[derive(Debug, Clone, PartialEq)]
pub struct InsertionPlan {
    /// Its name.
    pub name: String,
    /// When, in words.
    pub when: String,
    /// Batches within the run.
    pub batches: u64,
    /// Particles it brings within the run, about (from the mixture's mean size and mass).
    pub particles: f64,
    /// Particles of its largest batch, about.
    pub largest_batch: f64,
}

/// The plan of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Δt, s.
    pub dt: f64,
    /// Steps.
    pub steps: u64,
    /// Which rule gave Δt.
    pub time_step_explanation: String,
    /// Start and end time, s.
    pub t_start: f64,
    /// End time, s.
    pub t_stop: f64,
    /// Particles at the start.
    pub particles: usize,
    /// Steps between outputs, time-series rows, snapshots.
    pub output_every: u64,
    /// Time-series rows.
    pub rows: u64,
    /// Particle snapshots (CSV).
    pub snapshots: u64,
    /// VTK frames, and the steps between them.
    pub vtk: Option<(u64, u64)>,
    /// The insertions.
    pub insertions: Vec<InsertionPlan>,
    /// The outlets' names.
    pub outlets: Vec<String>,
    /// The memory at the peak.
    pub memory: MemoryEstimate,
    /// The limit it was held to.
    pub limit: MemoryLimit,
    /// Things the user should know: output intervals below the step, rounded up to it.
    pub warnings: Vec<String>,
}

/// Steps between outputs for an interval: the interval rounded to whole steps (at least 1);
/// no interval gives about 100 outputs over the run. The run loop (`grainflow-run`) writes
/// at these steps; the plan counts them.
pub fn output_every(interval: Option<f64>, dt: f64, total_steps: u64) -> u64 {
    match interval {
        Some(iv) => ((iv / dt).round() as u64).max(1),
        None => total_steps.div_ceil(100).max(1),
    }
}

/// Outputs of a run of `steps` steps every `every` steps: steps 0, every, 2·every, … and the
/// last step.
fn outputs(steps: u64, every: u64) -> u64 {
    steps / every + 1 + u64::from(!steps.is_multiple_of(every))
}

/// True for the name of an MFIX deck's mass inflow, `bc<N>_<phase>`.
fn is_mfix_inflow(name: &str) -> bool {
    name.strip_prefix("bc")
        .and_then(|r| r.split_once('_'))
        .is_some_and(|(n, _)| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// Particles of a set drawn from `ins`'s mixture by amount `a` (for the plan).
fn amount_particles(ins: &Insertion, a: Amount) -> f64 {
    match a {
        Amount::Count(n) => n as f64,
        Amount::VolumeFraction(f) => f * ins.region.volume() / ins.mixture.mean_volume(),
        Amount::Mass(m) => m / ins.mixture.mean_mass(),
    }
}

/// The insertion `ins` over a run whose steps of `dt` start from `t0` to `t1`; refuses
/// batches more often than the steps.
fn insertion_plan(ins: &Insertion, t0: f64, t1: f64, dt: f64) -> Result<InsertionPlan, CaseError> {
    let table = format!("[[insertions]] '{}'", ins.name);
    let total = ins.amount.map(|a| amount_particles(ins, a));
    match ins.schedule {
        Schedule::Once { at } => {
            let n = if at <= t1 { total.unwrap_or(0.0) } else { 0.0 };
            Ok(InsertionPlan {
                name: ins.name.clone(),
                when: format!("all at once at t = {} s", num(at)),
                batches: u64::from(at <= t1),
                particles: n,
                largest_batch: n,
            })
        }
        Schedule::Rate { rate, start, every } => {
            if every < dt {
                return Err(CaseError::invalid(
                    &table,
                    "every",
                    num(every),
                    format!(
                        "batches {} s apart would come {:.3e} times in a step of dt = {:.4e} s, but a batch is placed at the start of a step, at most one a step; give every >= dt (one batch a step) or longer{}",
                        num(every),
                        dt / every,
                        dt,
                        if is_mfix_inflow(&ins.name) {
                            " (for an MFIX mass inflow: its layer, two diameters deep, must take at least a step to pass, so BC_MASSFLOW_S or the inflow velocity is too large)"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            let per_second = match rate {
                Rate::Particles(r) => r,
                Rate::Mass(r) => r / ins.mixture.mean_mass(),
            };
            let span = (t1 - start.max(t0)).max(0.0);
            let batches = if start <= t1 { (span / every).floor() as u64 + 1 } else { 0 };
            let by_rate = per_second * (batches as f64 * every);
            let particles = total.map_or(by_rate, |t| t.min(by_rate));
            let largest_batch = (per_second * every).min(particles);
            let what = match rate {
                Rate::Particles(r) => format!("{} particles/s", num(r)),
                Rate::Mass(r) => format!("{} kg/s (about {per_second:.4e} particles/s)", num(r)),
            };
            Ok(InsertionPlan {
                name: ins.name.clone(),
                when: format!("at {what} from t = {} s, a batch every {} s", num(start), num(every)),
                batches,
                particles,
                largest_batch,
            })
        }
    }
}

/// Plans the run of `case` and checks it can be run within `limit`: see the
/// [module doc](self).
pub fn plan(case: &Case, limit: MemoryLimit) -> Result<Plan, CaseError> {
    let c = &case.config;
    let step = grainflow::simulation::time_step_of(c, &case.particles)?;
    let (dt, steps) = (step.dt, step.steps);
    // Batches are placed at the start of a step: the last one starts a step before the end.
    let t_last = c.t_start + steps.saturating_sub(1) as f64 * dt + 1e-6 * dt;
    let insertions = c
        .insertions
        .iter()
        .map(|ins| insertion_plan(ins, c.t_start, t_last, dt))
        .collect::<Result<Vec<_>, _>>()?;
    // Output intervals are rounded to whole steps, at least one: below the step, that is
    // said rather than done silently.
    let mut warnings = Vec::new();
    for (key, iv) in [("interval", case.output.interval), ("vtk_interval", case.output.vtk_interval)] {
        if let Some(iv) = iv.filter(|&iv| iv < 0.5 * dt) {
            warnings.push(format!(
                "[output]: `{key}` = {} s is below the time step dt = {dt:.4e} s: rounded up to one step (an output at every step)",
                num(iv)
            ));
        }
    }
    let every = output_every(case.output.interval, dt, steps);
    let rows = outputs(steps, every);
    let vtk = case.output.vtk_interval.map(|iv| {
        let k = output_every(Some(iv), dt, steps);
        (outputs(steps, k), k)
    });
    let n0 = case.particles.len() as f64;
    let brought: f64 = insertions.iter().map(|i| i.particles).sum();
    let arriving = insertions.iter().map(|i| i.largest_batch).fold(n0, f64::max);
    let triangles: f64 = c.meshes.iter().map(|m| m.mesh.triangle_count() as f64).sum();
    let memory = estimate(n0 + brought, arriving, 0.0, triangles, c.integrator);
    if memory.bytes > limit.bytes {
        let per = memory.per_particle;
        let detail = format!(
            "the run would hold up to {:.4e} particles ({:.0} at the start{}) at about {per:.0} bytes each, {:.4e} arriving at once, and needs about {} of memory; the limit is {}. Fix: fewer particles (a shorter run, a lower rate, count or volume fraction), or --memory-limit if the machine has the memory",
            memory.particles,
            n0,
            if insertions.is_empty() { String::new() } else { format!(", {brought:.4e} inserted") },
            memory.arriving,
            show_bytes(memory.bytes),
            limit.describe()
        );
        // Named after what brings the most particles.
        let biggest = insertions.iter().max_by(|a, b| a.particles.total_cmp(&b.particles));
        return Err(match biggest {
            Some(i) if i.particles > n0 => {
                let ins = c.insertions.iter().find(|x| x.name == i.name).expect("planned from it");
                let key = match (ins.schedule, ins.amount) {
                    (Schedule::Rate { rate: Rate::Particles(_), .. }, None) => "rate",
                    (Schedule::Rate { rate: Rate::Mass(_), .. }, None) => "mass_rate",
                    (_, Some(Amount::Count(_))) if !ins.given.is_empty() => "file",
                    (_, Some(Amount::Count(_))) => "count",
                    (_, Some(Amount::VolumeFraction(_))) => "volume_fraction",
                    (_, Some(Amount::Mass(_))) => "mass",
                    _ => "count",
                };
                let value = match (ins.schedule, ins.amount) {
                    (Schedule::Rate { rate: Rate::Particles(r) | Rate::Mass(r), .. }, None) => num(r),
                    (_, Some(Amount::Count(n))) => n.to_string(),
                    (_, Some(Amount::VolumeFraction(f))) => f.to_string(),
                    (_, Some(Amount::Mass(m))) => num(m),
                    _ => String::new(),
                };
                CaseError::invalid(format!("[[insertions]] '{}'", i.name), key, value, detail)
            }
            _ => CaseError::invalid("[particles]", "(the particles)", format!("{n0} particles"), detail),
        });
    }
    Ok(Plan {
        dt,
        steps,
        time_step_explanation: step.explanation,
        t_start: c.t_start,
        t_stop: c.t_stop,
        particles: case.particles.len(),
        output_every: every,
        rows,
        snapshots: if case.output.snapshots { rows } else { 0 },
        vtk,
        insertions,
        outlets: c.outlets.iter().map(|o| o.name.clone()).collect(),
        memory,
        limit,
        warnings,
    })
}

impl Plan {
    /// The plan in words, a line each.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![
            self.time_step_explanation.clone(),
            format!(
                "{} steps of {:.6e} s from t = {} s to t = {} s",
                self.steps,
                self.dt,
                num(self.t_start),
                num(self.t_stop)
            ),
            format!("{} particles at the start", self.particles),
            format!(
                "outputs: {} time-series rows (every {} steps), {} particle snapshots{}",
                self.rows,
                self.output_every,
                self.snapshots,
                match self.vtk {
                    Some((frames, k)) => format!(", {frames} VTK frames (every {k} steps)"),
                    None => ", no VTK frames".into(),
                }
            ),
        ];
        for i in &self.insertions {
            out.push(format!(
                "insertion '{}': {}; {} batch{} in the run, about {:.4e} particles (at most {:.4e} at once)",
                i.name,
                i.when,
                i.batches,
                if i.batches == 1 { "" } else { "es" },
                i.particles,
                i.largest_batch
            ));
        }
        for o in &self.outlets {
            out.push(format!("outlet '{o}'"));
        }
        out.push(format!(
            "memory: about {} at the peak ({:.4e} particles at most, {:.0} bytes each, {:.4e} arriving at once{}); limit {}",
            show_bytes(self.memory.bytes),
            self.memory.particles,
            self.memory.per_particle,
            self.memory.arriving,
            if self.memory.meshes > 0.0 {
                format!(", meshes {}", show_bytes(self.memory.meshes))
            } else {
                String::new()
            },
            self.limit.describe()
        ));
        out
    }
}
