//! Running a case with its outputs: what `grainflow run` does, without the terminal.
//!
//! The output folder is held by the run ([`crate::outdir`]): locked, tied to the run by its run
//! id, its files listed in `manifest.toml`, an earlier run's results never replaced unless
//! asked (`RunOptions::overwrite`), and `run-info.toml` written when the run starts and again
//! when it ends. Besides the outputs, the loop keeps the run trustworthy:
//! - **checkpoints** (`RunOptions::checkpoint_every`) written atomically to
//!   `out/checkpoint.gfc` (the previous one survives a crash mid-write), from which
//!   [`RunOptions::restart`] continues bit for bit;
//! - **health checks** every [`HEALTH_EVERY`] steps and at every output: a non-finite value, a
//!   particle outside the domain box, a particle moving more than its radius in a step or an
//!   overlap above `[particles] max_overlap` of the smaller radius stops the run with a message
//!   naming the particle, the step, the likely cause (from what happened: the start's state,
//!   an insertion since the last check, a moving mesh, else the step) and a fix,
//!   after writing the last good state (kept at every output and every 10·`HEALTH_EVERY`
//!   steps) to `out/checkpoint-last-good.gfc`;
//! - **interruption**: when the `stop` flag is raised (SIGINT/SIGTERM in the program) the step
//!   in progress finishes, a checkpoint is written and the outputs are closed properly.

use crate::outdir::{FolderError, Intent, OutputFolder, RUN_INFO_FILE, TIMESERIES_FILE};
use crate::output::{
    ResumeError, SeriesRecord, TimeSeriesWriter, Value, cylinder_columns, mesh_columns, rotation_axis,
    snapshot_csv, write_atomic, write_atomic_with,
};
use crate::vtk::{VtkSeries, frame_files, series_files};
use grainflow::surface::Which;
use grainflow::{Diagnostics, Simulation, Vec3};
use grainflow_case::plan::output_every;
use grainflow_case::{Case, OutputSettings};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Steps between health checks (also made at every output).
pub const HEALTH_EVERY: u64 = 100;
/// Most steps taken between two checks for a stop request.
const MAX_STEPS_UNSEEN: u64 = 20;
/// File name of the running checkpoint in the output folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.gfc";
/// File name of the last good state written when a run fails its health check.
pub const LAST_GOOD_FILE: &str = "checkpoint-last-good.gfc";

/// How often to write a checkpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CheckpointEvery {
    /// Every so many steps.
    Steps(u64),
    /// Every so much wall-clock time.
    WallTime(Duration),
}

/// Options of a run beyond the case itself.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Periodic checkpoints (one is always written when a run is interrupted).
    pub checkpoint_every: Option<CheckpointEvery>,
    /// Continue from this checkpoint instead of the case's initial state.
    pub restart: Option<PathBuf>,
    /// Accept a checkpoint written for a different version of the case (e.g. after fixing
    /// the time step that made a run fail); the particles must still match.
    pub accept_changed_case: bool,
    /// Raised from outside (a signal handler) to stop after the current step.
    pub stop: Option<Arc<AtomicBool>>,
    /// Threads of the force stage (None: one). The results do not depend on it.
    pub threads: Option<usize>,
    /// Let the engine run a step on one thread instead when it measures that the threads do
    /// not pay ([`grainflow::Simulation::choose_threads`]).
    pub choose_threads: bool,
    /// Run steps on the threads from this many particles (None: the engine's default,
    /// [`grainflow::forces::MIN_PARALLEL_PARTICLES`]); for tests of the threads on small cases.
    pub parallel_from: Option<usize>,
    /// Largest state (bytes) kept in memory as the last good state; larger ones are kept in
    /// a file (None: [`LAST_GOOD_IN_MEMORY`]).
    pub last_good_in_memory: Option<usize>,
    /// Replace an earlier run's results in the output folder instead of refusing to start.
    pub overwrite: bool,
    /// What `run-info.toml` records of the run's inputs.
    pub provenance: Provenance,
    /// The ranks to spread the run over (None, or one rank: one process). Every rank runs
    /// [`run_case`] with the same case; each writes the same outputs, so all but rank 0 should
    /// be given a folder of their own that is thrown away.
    pub ranks: Option<Arc<dyn grainflow::domain::Comm>>,
}

/// The inputs of a run as the user gave them, recorded in `run-info.toml`.
#[derive(Debug, Clone, Default)]
pub struct Provenance {
    /// The case file (or MFIX deck).
    pub case_file: PathBuf,
    /// MFIX `KEY=VALUE` overrides.
    pub mfix_overrides: Vec<String>,
    /// The `--motion` file of an MFIX deck.
    pub motion_file: Option<PathBuf>,
}

/// What a finished (or interrupted) run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Steps taken in this invocation.
    pub steps: u64,
    /// Step the run started from (0, or the checkpoint's).
    pub start_step: u64,
    /// Δt, s.
    pub dt: f64,
    /// Which time-step rule gave Δt, in words.
    pub time_step_explanation: String,
    /// Outputs written (time-series rows) in this invocation.
    pub outputs: usize,
    /// Steps between outputs.
    pub output_every: u64,
    /// Diagnostics at the start.
    pub first: Diagnostics,
    /// Diagnostics at the end.
    pub last: Diagnostics,
    /// Wall-clock time of the time loop, s.
    pub wall_seconds: f64,
    /// Particle-steps per wall-clock second.
    pub particle_steps_per_second: f64,
    /// Particles at the start and at the end of the run (insertions and outlets change them).
    pub particles: (usize, usize),
    /// Particle-steps taken: the steps times the particles there, summed over the run.
    pub particle_steps: f64,
    /// Threads of the force stage.
    pub threads: usize,
    /// What the engine's choice of threads did ([`RunOptions::choose_threads`]).
    pub thread_report: grainflow::ThreadReport,
    /// Heap bytes of the particles, the neighbour list and the threads' plan at the end.
    pub memory: grainflow::MemoryUse,
    /// True when the run was stopped by the `stop` flag before its end.
    pub interrupted: bool,
    /// The checkpoint written when interrupted or periodically, if any.
    pub checkpoint: Option<PathBuf>,
    /// Wall-clock seconds per stage: neighbour search, walls, pairs, integration (engine) and
    /// output (files), for the time loop.
    pub stages: grainflow::StageTimes,
    /// Wall-clock seconds spent writing output in the time loop.
    pub output_seconds: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// Pairs in the neighbour list at the end (each pair once).
    pub neighbor_pairs: usize,
    /// Neighbour-list builds in this invocation.
    pub neighbor_builds: u64,
    /// The run's id (kept across restarts).
    pub run_id: String,
    /// Spread over ranks: the ranks, and what this rank sent to the others.
    pub ranks: (usize, grainflow::DomainStats),
}

/// A file that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct OutputError {
    /// The file or folder.
    pub path: PathBuf,
    /// Why.
    pub source: std::io::Error,
}

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The engine refused the set-up.
    #[error("{0}")]
    Engine(#[from] grainflow::EngineError),
    /// Output failed.
    #[error("{0}")]
    Output(#[from] OutputError),
    /// The restart checkpoint could not be read or used.
    #[error("cannot restart from {path}: {message}")]
    Restart {
        /// The checkpoint.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The output folder cannot take this run's outputs (another run holds it, or it holds an
    /// earlier run's results); nothing in it was changed.
    #[error("{0}")]
    Folder(#[from] FolderError),
    /// The run would write more output than any disk holds.
    #[error("{0}")]
    TooMuchOutput(String),
    /// The run went numerically wrong; the last good state was saved.
    #[error("{message}\nThe last good state (step {good_step}) is in {}; fix the case and continue from it with --restart {} --accept-changed-case.", saved.display(), saved.display())]
    Unhealthy {
        /// What went wrong, where, why and what to do.
        message: String,
        /// Step of the saved state.
        good_step: u64,
        /// Where it was saved.
        saved: PathBuf,
    },
}

/// Runs `case` to its end (or until `options.stop` is raised), writing into the folder `out`
/// (see [`crate::outdir`]) `timeseries.csv`, if enabled `snapshots/particles_<step>.csv` at
/// every output (including the first and last step), and if `vtk_interval` is set a VTK
/// series in `vtk/`. `on_progress` is called after every few steps (at most
/// `MAX_STEPS_UNSEEN`), and after the last step, with the simulation: it should be cheap.
pub fn run_case(
    case: Case,
    out: &Path,
    options: &RunOptions,
    mut on_progress: impl FnMut(&Simulation) + Send,
) -> Result<RunSummary, RunError> {
    let (output, domain, hash) = (case.output, case.domain, case.hash.clone());
    let (max_overlap, rebalance) = (case.max_overlap, case.rebalance);
    let mesh_loads = MeshLoads::new(&case);
    let spread = options.ranks.clone().filter(|c| c.size() > 1);
    let mut sim = match (&options.restart, &spread) {
        (None, None) => Simulation::new(case.config, case.particles)?,
        // Each rank sets up from its share of the case's particles, in the file's order: no
        // rank builds a neighbour list of them all. The share handed out by rank 0 (see
        // `crate::share`), or else its run of the particles every rank read (an MFIX deck).
        (None, Some(comm)) if case.particles_are_share => {
            Simulation::new_over_ranks(case.config, case.particles, comm.clone(), rebalance)?
        }
        (None, Some(comm)) => {
            let n = case.particles.len();
            let (r, ranks) = (comm.rank(), comm.size());
            let share: Vec<usize> = (r * n / ranks..(r + 1) * n / ranks).collect();
            let mine = case.particles.gathered(&share);
            drop(case.particles);
            Simulation::new_over_ranks(case.config, mine, comm.clone(), rebalance)?
        }
        (Some(path), _) => {
            restore_case(case.config, case.particles, path, options.accept_changed_case, &hash)?
        }
    };
    // A restart spreads the checkpoint's whole state over the ranks.
    if let (Some(comm), Some(_)) = (spread, &options.restart) {
        sim.decompose(comm, rebalance)?;
    }
    sim.weigh_ranks_by(case.weigh);
    check_output_volume(&sim, &output, mesh_loads.columns.len())?;
    let intent = match &options.restart {
        None => Intent::Fresh,
        Some(path) => Intent::Continue { run_id: sim.run_id(), checkpoint: path },
    };
    let case_file = options.provenance.case_file.display().to_string();
    let mut folder = OutputFolder::claim(out, &intent, options.overwrite, &case_file, &hash)?;
    sim.set_run_id(folder.run_id());
    sim.enable_stage_timing();
    match options.threads {
        Some(t) if options.choose_threads => sim.choose_threads(t)?,
        Some(t) => sim.set_threads(t)?,
        None => {}
    }
    if let Some(n) = options.parallel_from {
        sim.set_parallel_from(n);
    }
    let info = RunInfo {
        options,
        hash: &hash,
        run_id: folder.run_id().to_string(),
        started: crate::outdir::utc_now(),
    };
    folder.record(Path::new(RUN_INFO_FILE))?;
    info.write(out, &sim, "running", None)?;
    // The whole run on the simulation's threads: handing each step over to them on its own
    // costs several microseconds a step.
    let leaving_removed =
        sim.outlets().iter().any(|o| matches!(o.shape, grainflow::insertion::OutletShape::OutsideBox { .. }));
    let health = Health { domain, max_overlap, leaving_removed };
    let result = sim.on_pool(|sim| {
        run_simulation(sim, output, health, &mesh_loads, &hash, &mut folder, options, &mut on_progress)
    });
    let status = match &result {
        Ok(s) if s.interrupted => "interrupted",
        Ok(_) => "completed",
        Err(RunError::Unhealthy { .. }) => "failed: numerical health check",
        Err(_) => "failed",
    };
    let written = info
        .write(out, &sim, status, result.as_ref().ok())
        .and_then(|()| folder.sync().map_err(RunError::from));
    // The run's own error comes first; a failure to record it only if the run went well.
    let summary = result?;
    written?;
    Ok(summary)
}

/// The run of a case (`config`, its initial `particles`, its `hash`) continued from the
/// checkpoint at `path`: one written for this case, or with `accept_changed_case` for any case
/// whose particles the checkpoint still holds (less removed ones, more inserted ones).
pub fn restore_case(
    config: grainflow::SimulationConfig,
    particles: grainflow::Particles,
    path: &Path,
    accept_changed_case: bool,
    hash: &str,
) -> Result<Simulation, RunError> {
    let case_particles = accept_changed_case.then(|| particle_keys(&particles));
    let flow = !(config.insertions.is_empty() && config.outlets.is_empty());
    // The checkpoint holds the particles: the case's initial ones go before it is read (on a
    // large bed they would hold a second copy of the state meanwhile).
    drop(particles);
    let sim = restore(config, path, accept_changed_case, hash)?;
    if let Some(keys) = case_particles {
        same_particles(&keys, &particle_keys(sim.particles()), flow)
            .map_err(|message| RunError::Restart { path: path.to_path_buf(), message })?;
    }
    Ok(sim)
}

/// Reads the checkpoint at `path` for `config`: for the case `hash`, or any case.
fn restore(
    config: grainflow::SimulationConfig,
    path: &Path,
    any_case: bool,
    hash: &str,
) -> Result<Simulation, RunError> {
    let restart_err = |message: String| RunError::Restart { path: path.to_path_buf(), message };
    let meta = std::fs::metadata(path).map_err(|e| restart_err(e.to_string()))?;
    if !meta.is_file() {
        return Err(restart_err("not a regular file (a checkpoint is a file grainflow wrote)".into()));
    }
    let file = std::fs::File::open(path).map_err(|e| restart_err(e.to_string()))?;
    let expected = (!any_case).then_some(hash);
    let reader = std::io::BufReader::with_capacity(1 << 20, file);
    Simulation::restore_from(config, reader, meta.len(), expected).map_err(|e| {
        let hint = if matches!(
            e,
            grainflow::checkpoint::RestoreError::Checkpoint(
                grainflow::checkpoint::CheckpointError::WrongCase { .. }
            )
        ) {
            " (if you changed the case on purpose, add --accept-changed-case)"
        } else {
            ""
        };
        restart_err(format!("{e}{hint}"))
    })
}

/// Each particle's id, phase and radius, by id: what must not change when a changed case
/// continues from a checkpoint.
fn particle_keys(p: &grainflow::Particles) -> Vec<(u32, u32, u64)> {
    let mut keys: Vec<_> = (0..p.len()).map(|i| (p.id[i], p.phase[i], p.radius[i].to_bits())).collect();
    keys.sort_unstable();
    keys
}

/// Why the case's particles and the checkpoint's differ, if they do. With insertions or
/// outlets (`flow`) the checkpoint may hold fewer of the case's particles (removed) and more
/// (inserted, with ids above the case's): each of the case's it holds must be the case's.
fn same_particles(
    case: &[(u32, u32, u64)],
    checkpoint: &[(u32, u32, u64)],
    flow: bool,
) -> Result<(), String> {
    let advice = "--accept-changed-case accepts changed settings (time step, stiffness, outputs), not other particles: restore the case's particle file, or start a fresh run";
    if flow {
        let largest = case.iter().map(|c| c.0).max().unwrap_or(0);
        for k in checkpoint.iter().filter(|k| k.0 <= largest) {
            match case.binary_search_by_key(&k.0, |c| c.0) {
                Ok(i) if case[i].1 == k.1 && case[i].2 == k.2 => {}
                Ok(i) => {
                    return Err(format!(
                        "particle {} is of phase {} with radius {:e} m in the case but of phase {} with radius {:e} m in the checkpoint; {advice}",
                        k.0,
                        case[i].1 + 1,
                        f64::from_bits(case[i].2),
                        k.1 + 1,
                        f64::from_bits(k.2)
                    ));
                }
                Err(_) => return Err(format!("particle {} is missing from the case; {advice}", k.0)),
            }
        }
        return Ok(());
    }
    if case.len() != checkpoint.len() {
        return Err(format!(
            "the checkpoint holds {} particles and the case {}; {advice}",
            checkpoint.len(),
            case.len()
        ));
    }
    for (c, k) in case.iter().zip(checkpoint) {
        if c.0 != k.0 {
            let (missing, id) = if c.0 < k.0 { ("the checkpoint", c.0) } else { ("the case", k.0) };
            return Err(format!("particle {id} is missing from {missing}; {advice}"));
        }
        if c.1 != k.1 || c.2 != k.2 {
            return Err(format!(
                "particle {} is of phase {} with radius {:e} m in the case but of phase {} with radius {:e} m in the checkpoint; {advice}",
                c.0,
                c.1 + 1,
                f64::from_bits(c.2),
                k.1 + 1,
                f64::from_bits(k.2)
            ));
        }
    }
    Ok(())
}

/// Largest output a run may plan to write, bytes.
pub const MAX_OUTPUT_BYTES: f64 = 1e12;
/// Most files a run may plan to write.
pub const MAX_OUTPUT_FILES: f64 = 1e6;

/// Refuses a run whose outputs would fill any disk, estimated from the steps left, the
/// output intervals and the particles (time-series row about 150 bytes and 25 a mesh
/// column, snapshot row about 160, VTK particle about 150 and contact about 100 bytes at two
/// contacts a particle, a moving mesh's triangle about 120 bytes a frame and one file).
fn check_output_volume(
    sim: &Simulation,
    output: &OutputSettings,
    mesh_columns: usize,
) -> Result<(), RunError> {
    let left = sim.total_steps().saturating_sub(sim.step_index()) as f64;
    let n = sim.total_particles() as f64;
    let rows = left / output_every(output.interval, sim.dt(), sim.total_steps()) as f64 + 1.0;
    let frames = output
        .vtk_interval
        .map_or(0.0, |iv| left / output_every(Some(iv), sim.dt(), sim.total_steps()) as f64 + 1.0);
    let snapshot_rows = if output.snapshots { rows } else { 0.0 };
    let moving = sim.meshes().iter().filter(|w| w.motion.moves());
    let moving_triangles = moving.clone().map(|w| w.mesh.triangle_count() as f64).sum::<f64>();
    let mesh_files = if moving.count() > 0 { frames } else { 0.0 };
    let bytes = rows * (150.0 + 25.0 * mesh_columns as f64)
        + snapshot_rows * n * 160.0
        + frames * (n * 350.0 + moving_triangles * 120.0);
    let files = snapshot_rows + 2.0 * frames + mesh_files;
    let gib = bytes / f64::from(1u32 << 30);
    if bytes > MAX_OUTPUT_BYTES || files > MAX_OUTPUT_FILES {
        return Err(RunError::TooMuchOutput(format!(
            "the run would write about {gib:.3e} GiB in {files:.3e} files ({rows:.3e} time-series rows{}{}, {n} particles, {left:.3e} steps); the limits are {:.0} GiB and {MAX_OUTPUT_FILES:.0e} files. Fix: a longer [output] interval{}, or snapshots = false",
            if output.snapshots { " and as many snapshots" } else { "" },
            if frames > 0.0 { format!(", {frames:.3e} VTK frames") } else { String::new() },
            MAX_OUTPUT_BYTES / f64::from(1u32 << 30),
            if frames > 0.0 { " or vtk_interval" } else { "" },
        )));
    }
    Ok(())
}

/// `run-info.toml`: what produced the outputs, so that a result can be traced and reproduced:
/// program version, run id, case file and the hash of everything it read, thread count, time
/// step, steps, and how the run ended.
struct RunInfo<'a> {
    options: &'a RunOptions,
    hash: &'a str,
    run_id: String,
    started: String,
}

impl RunInfo<'_> {
    fn write(
        &self,
        out: &Path,
        sim: &Simulation,
        status: &str,
        summary: Option<&RunSummary>,
    ) -> Result<(), RunError> {
        let q = |s: &str| toml::Value::String(s.to_string()).to_string();
        let p = &self.options.provenance;
        let mut s = format!(
            "# Written by grainflow run; describes the outputs in this folder (their list: manifest.toml).\ngrainflow_version = \"{}\"\nrun_id = {}\ncase_file = {}\ncase_sha256 = {}\nthreads = {}\nstatus = {}\nstarted = {}\n",
            env!("CARGO_PKG_VERSION"),
            q(&self.run_id),
            q(&p.case_file.display().to_string()),
            q(self.hash),
            sim.threads(),
            q(status),
            q(&self.started),
        );
        // Ranks × threads: the threads are each rank's.
        s.push_str(&format!("ranks = {}\n", sim.ranks()));
        if status != "running" {
            s.push_str(&format!("ended = {}\n", q(&crate::outdir::utc_now())));
            if sim.ranks() > 1 {
                // The balance over the run: the slowest rank's work ÷ the mean, and re-cuts.
                let d = sim.domain_stats();
                s.push_str(&format!(
                    "slowest_work_over_mean = {:.4}\nrecuts = {}\nrank_0_seconds_in_mpi = {:.3}\n",
                    d.imbalance(sim.ranks()),
                    d.recuts,
                    d.waited as f64 * 1e-9
                ));
                if let Some(t) = d.time_imbalance(sim.ranks()) {
                    s.push_str(&format!("busiest_time_over_mean = {t:.4}\n"));
                }
            }
        }
        if let Some(r) = &self.options.restart {
            s.push_str(&format!("restarted_from = {}\n", q(&r.display().to_string())));
        }
        if !p.mfix_overrides.is_empty() {
            let list: Vec<String> = p.mfix_overrides.iter().map(|o| q(o)).collect();
            s.push_str(&format!("mfix_overrides = [{}]\n", list.join(", ")));
        }
        if let Some(m) = &p.motion_file {
            s.push_str(&format!("motion_file = {}\n", q(&m.display().to_string())));
        }
        s.push_str(&format!("dt = {:e}\ntotal_steps = {}\n", sim.dt(), sim.total_steps()));
        if let Some(x) = summary {
            s.push_str(&format!(
                "first_step = {}\nlast_step = {}\nwall_seconds = {:.3}\n",
                x.start_step,
                x.start_step + x.steps,
                x.wall_seconds
            ));
        }
        let path = out.join(RUN_INFO_FILE);
        write_atomic(&path, s.as_bytes()).map_err(|source| RunError::Output(OutputError { path, source }))
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError { path: path.to_path_buf(), source }
}

/// States up to this size (bytes) are kept in memory as the last good state; larger ones
/// are kept in a file, so that the copy does not add to the run's memory (about 300 bytes
/// per particle, as much as the simulation itself).
pub const LAST_GOOD_IN_MEMORY: usize = 64 << 20;

/// The last state that passed the health check, written to [`LAST_GOOD_FILE`] only if a
/// later check fails. Small states are kept in memory (one buffer, reused); larger ones are
/// streamed to a hidden file in the output folder (renamed into place on a failure, removed
/// when the run ends otherwise). On ranks each rank keeps its own part of the state (in
/// memory, or in a hidden file of its folder) and the run without its particles: only a
/// failure gathers the whole, on rank 0, which writes it.
struct LastGood<'a> {
    step: u64,
    hash: &'a str,
    out: &'a Path,
    /// The bytes in memory, or None when they are on disk.
    bytes: Option<Vec<u8>>,
    /// On ranks: the run at the kept step without its particles, and this rank's part of it
    /// in memory (None: on disk).
    part: Option<(Simulation, Option<Vec<u64>>)>,
}

impl<'a> LastGood<'a> {
    fn new(
        sim: &mut Simulation,
        hash: &'a str,
        out: &'a Path,
        max_in_memory: usize,
    ) -> Result<Self, OutputError> {
        // On ranks, this rank's part is about its own share of the state.
        let in_memory = sim.checkpoint_size(hash) <= max_in_memory;
        let part = (sim.ranks() > 1).then(|| (sim.skeleton(), in_memory.then(Vec::new)));
        let bytes = (part.is_none() && in_memory).then(Vec::new);
        let mut kept = LastGood { step: 0, hash, out, bytes, part };
        kept.keep(sim)?;
        Ok(kept)
    }

    fn rolling_path(&self) -> PathBuf {
        self.out.join(format!(".{LAST_GOOD_FILE}.rolling"))
    }

    /// Keeps the current state (on ranks, this rank's part). Collective on ranks.
    fn keep(&mut self, sim: &mut Simulation) -> Result<(), OutputError> {
        self.step = sim.step_index();
        let path = self.rolling_path();
        if let Some((skeleton, words)) = &mut self.part {
            *skeleton = sim.skeleton();
            return match words {
                Some(w) => {
                    w.clear();
                    sim.part_into(&mut |x| w.extend_from_slice(x));
                    Ok(())
                }
                None => write_atomic_with(&path, |f| {
                    let mut failed = Ok(());
                    sim.part_into(&mut |x| {
                        if failed.is_ok() {
                            failed =
                                x.iter().try_for_each(|v| std::io::Write::write_all(f, &v.to_le_bytes()));
                        }
                    });
                    failed
                })
                .map_err(io_err(&path)),
            };
        }
        match &mut self.bytes {
            Some(b) => sim.checkpoint_into(self.hash, b),
            None => {
                write_atomic_with(&path, |w| sim.write_checkpoint(self.hash, w)).map_err(io_err(&path))?;
            }
        }
        Ok(())
    }

    /// Writes the kept state to [`LAST_GOOD_FILE`]; returns its step and path. On ranks the
    /// parts are gathered on rank 0, which writes them (collective).
    fn save(&self) -> Result<(u64, PathBuf), OutputError> {
        let saved = self.out.join(LAST_GOOD_FILE);
        if let Some((skeleton, words)) = &self.part {
            let path = self.rolling_path();
            let mine = match words {
                Some(w) => Ok(w.clone()),
                None => std::fs::read(&path).map(|b| {
                    b.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default())).collect()
                }),
            };
            // A part that cannot be read fails this rank alone, which ends every rank.
            let mine = mine.map_err(io_err(&path))?;
            if let Some(whole) = skeleton.whole_from_parts(mine) {
                write_atomic_with(&saved, |w| whole.write_checkpoint(self.hash, w))
                    .map_err(io_err(&saved))?;
            }
            return Ok((self.step, saved));
        }
        match &self.bytes {
            Some(b) => write_atomic(&saved, b).map_err(io_err(&saved))?,
            None => std::fs::rename(self.rolling_path(), &saved).map_err(io_err(&saved))?,
        }
        Ok((self.step, saved))
    }
}

impl Drop for LastGood<'_> {
    /// The kept state goes with the run (after a failure it was renamed into place).
    fn drop(&mut self) {
        if self.bytes.is_none() {
            let _ = std::fs::remove_file(self.rolling_path());
        }
    }
}

/// What the run-time health check holds a state to.
#[derive(Debug, Clone, Copy)]
pub struct Health {
    /// The domain box (lower, upper corner), m: no particle may leave it, unless
    /// `leaving_removed` (`[domain] leaving = "remove"`: the outlet "domain" removes them).
    pub domain: (Vec3, Vec3),
    /// Particles leaving the box are removed, not a problem.
    pub leaving_removed: bool,
    /// The largest overlap, as a fraction of the smaller radius (`[particles] max_overlap`).
    pub max_overlap: f64,
}

/// Which state a health check looks at: the run's first (before any step), or one reached by
/// steps since the last check, in which the particles with ids from `fresh_from` on were
/// inserted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Checked {
    /// The state the run starts from (the particle file, seeded particles, batches due at the
    /// start).
    Start,
    /// The steps since the last check.
    Since {
        /// Particles with this id or a higher one were inserted since the last check.
        fresh_from: u32,
    },
}

impl Checked {
    /// For the check after this one: particles with ids above every present one are new.
    pub fn after(sim: &Simulation) -> Checked {
        let top = sim.particles().id.iter().copied().max().map_or(0, |i| i.saturating_add(1));
        Checked::Since { fresh_from: top }
    }
}

/// The first problem of the current state, if any: non-finite values, a particle outside
/// the domain box, a particle moving more than its radius in a step, an overlap beyond
/// `health.max_overlap`. Each message names the likely cause from what happened (`checked`):
/// the start's state, an insertion since the last check, a moving mesh the particle touches,
/// or else the time step (or the stiffness) for the speeds.
pub fn health_problem(sim: &Simulation, health: Health, checked: Checked) -> Option<String> {
    let p = sim.particles();
    let step = sim.step_index();
    let dt = sim.dt();
    if let Some(e) = sim.flow_error() {
        return Some(format!("step {step}: {e}"));
    }
    let cause = Cause::new(sim, checked);
    let (lo, hi) = health.domain;
    // One pass in slot order, without branches, finds whether any particle needs a closer look
    // (one beyond the box may have left through an outlet): most checks find none and need no
    // id order.
    let suspect = |i: usize| {
        let (x, v, w) = (p.position[i], p.velocity[i], p.omega[i]);
        let outside = !health.leaving_removed && (x.cmplt(lo).any() || x.cmpgt(hi).any());
        !(x.is_finite() && v.is_finite() && w.is_finite()) | outside | (v.length() * dt > p.radius[i])
    };
    // A rank looks at its own particles; the ranks then agree on the problem of the lowest id.
    let owned = sim.owned();
    let suspects = (0..owned).fold(false, |any, i| any | suspect(i));
    let first = first_problem(
        sim,
        health,
        &cause,
        suspects.then(|| p.id_order()).into_iter().flatten().filter(|&i| i < owned),
    );
    if let Some(problem) = agree(sim, first.map(|(i, m)| (0.0, p.id[i], m))) {
        return Some(problem);
    }
    let d = sim.diagnostics();
    if d.max_overlap_ratio > health.max_overlap {
        // The contact with the largest overlap (as a fraction of the smaller radius), first
        // in id order among equals.
        let ratio = |c: &grainflow::ContactInfo| {
            let r = match c.other {
                grainflow::ContactPartner::Particle(j) => p.radius[c.particle].min(p.radius[j]),
                _ => p.radius[c.particle],
            };
            c.overlap / r
        };
        let worst = sim
            .contacts()
            .into_iter()
            .max_by(|a, b| ratio(a).total_cmp(&ratio(b)).then(p.id[b.particle].cmp(&p.id[a.particle])));
        let worst = worst.map(|c| {
            let other = match c.other {
                grainflow::ContactPartner::Particle(j) => format!("particle {}", p.id[j]),
                grainflow::ContactPartner::Wall(w) => format!("wall '{}'", sim.walls()[w].name),
                grainflow::ContactPartner::Mesh { mesh, triangle } => {
                    format!("mesh '{}' (triangle {triangle})", sim.meshes()[mesh].mesh.name())
                }
                grainflow::ContactPartner::Cylinder(m) => {
                    format!("cylinder '{}'", sim.cylinders()[m].name)
                }
            };
            let why = cause.of(c.particle, Some(c.other));
            (
                -ratio(&c),
                p.id[c.particle],
                format!(" (particle {} and {other})\u{0}{}", p.id[c.particle], why.unwrap_or_default()),
            )
        });
        let (what, why) = match agree(sim, worst) {
            Some(m) => {
                let (what, why) = m.split_once('\u{0}').unwrap_or((&m, ""));
                (what.to_string(), (!why.is_empty()).then(|| why.to_string()))
            }
            None => (String::new(), None),
        };
        return Some(format!(
            "step {step}: an overlap reached {:.3} of the smaller radius{what}, above the limit [particles] max_overlap = {}. {}",
            d.max_overlap_ratio,
            health.max_overlap,
            why.unwrap_or_else(|| "Likely cause: the contact stiffness is too low for the loads and speeds (or dt too large). Fix: raise k_n (or E), or reduce the impact speeds; check that dt resolves the collision time (t_c/dt ≥ 20). If such overlaps are expected, raise [particles] max_overlap.".into())
        ));
    }
    None
}

/// The problem every rank names: of the candidates (a key, lower first, then the particle
/// id, and a message) each rank found, the first. In one process, its own.
fn agree(sim: &Simulation, mine: Option<(f64, u32, String)>) -> Option<String> {
    let Some(comm) = sim.comm() else { return mine.map(|m| m.2) };
    let mut words = Vec::new();
    if let Some((key, id, message)) = &mine {
        words.extend([key.to_bits(), *id as u64]);
        words.extend(message.as_bytes().chunks(8).map(|c| {
            let mut b = [0u8; 8];
            b[..c.len()].copy_from_slice(c);
            u64::from_le_bytes(b)
        }));
        words.push(message.len() as u64);
    }
    comm.all_gather(&words)
        .into_iter()
        .filter(|w| w.len() >= 3)
        .map(|w| {
            let len = w[w.len() - 1] as usize;
            let bytes: Vec<u8> = w[2..w.len() - 1].iter().flat_map(|x| x.to_le_bytes()).take(len).collect();
            (f64::from_bits(w[0]), w[1] as u32, String::from_utf8_lossy(&bytes).into_owned())
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map(|m| m.2)
}

/// The first of `slots` (in id order) with a non-finite state, outside the domain box or moving
/// more than its radius in a step, with its message.
fn first_problem(
    sim: &Simulation,
    health: Health,
    cause: &Cause,
    slots: impl Iterator<Item = usize>,
) -> Option<(usize, String)> {
    let p = sim.particles();
    let (step, dt) = (sim.step_index(), sim.dt());
    let (lo, hi) = health.domain;
    for i in slots {
        let (x, v, w) = (p.position[i], p.velocity[i], p.omega[i]);
        if !(x.is_finite() && v.is_finite() && w.is_finite()) {
            return Some((i, format!(
                "step {step}: particle {} has a non-finite position, velocity or spin. {}",
                p.id[i],
                cause.of(i, None).unwrap_or_else(|| "Likely cause: the time step is too large for the contact stiffness (or a stiffness or density is extreme). Fix: reduce dt (leave it out for MFIX's rule) or lower k_n / E.".into())
            )));
        }
        // A particle that has left through an outlet is removed at the outlets' next drain.
        if !health.leaving_removed && (x.cmplt(lo).any() || x.cmpgt(hi).any()) && !sim.left_through_outlet(i)
        {
            return Some((i, format!(
                "step {step}: particle {} left the domain box at ({:.6e}, {:.6e}, {:.6e}) m with speed {:.3e} m/s. {}",
                p.id[i],
                x.x,
                x.y,
                x.z,
                v.length(),
                cause.of(i, None).unwrap_or_else(|| "Likely cause: it passed through a wall because the time step is too large for its speed and the wall stiffness, or the domain has no walls there. Fix: reduce dt, raise the wall stiffness, or enlarge the domain / add walls.".into())
            )));
        }
        let (speed, r) = (v.length(), p.radius[i]);
        if speed * dt > r {
            let safe = grainflow::timestep::TRAVEL_FRACTION * r / speed;
            return Some((i, format!(
                "step {step}: particle {} moves {:.4e} m in a step (speed {speed:.4e} m/s at dt = {dt:.4e} s), more than its radius {r:.4e} m: in one step it can pass through a mesh sheet, a wall or another particle. {} A safe time step for this speed is dt <= {safe:.4e} s ({} of its radius a step).",
                p.id[i],
                speed * dt,
                cause.of(i, None).unwrap_or_else(|| "Likely cause: the time step is too large for the speeds of the case (an initial or inserted velocity, or a fall from a great height). Fix: reduce dt, or the speeds.".into()),
                grainflow::timestep::TRAVEL_FRACTION
            )));
        }
    }
    None
}

/// The likely cause of a particle's problem when it is not the time step: what happened to it.
struct Cause<'a> {
    sim: &'a Simulation,
    checked: Checked,
}

impl<'a> Cause<'a> {
    fn new(sim: &'a Simulation, checked: Checked) -> Self {
        Cause { sim, checked }
    }

    /// The cause for the particle in slot `i` (and the partner of its contact, if the problem
    /// is a contact), or `None` when nothing but the step and the stiffness is to blame.
    fn of(&self, i: usize, partner: Option<grainflow::ContactPartner>) -> Option<String> {
        let p = self.sim.particles();
        let partner_slot = match partner {
            Some(grainflow::ContactPartner::Particle(j)) => Some(j),
            _ => None,
        };
        match self.checked {
            Checked::Start => {
                return Some(format!(
                    "Likely cause: the state the run starts from (particle {}{}: from the particle file, the seeded particles or an insertion due at the start). Fix: separate the particles or slow them down in the input, or check the insertion's region and the particles already there.",
                    p.id[i],
                    partner_slot.map_or(String::new(), |j| format!(" and particle {}", p.id[j]))
                ));
            }
            Checked::Since { fresh_from } => {
                let fresh: Vec<u32> = [Some(i), partner_slot]
                    .into_iter()
                    .flatten()
                    .map(|k| p.id[k])
                    .filter(|&id| id >= fresh_from)
                    .collect();
                if let Some(id) = fresh.first() {
                    return Some(format!(
                        "Likely cause: particle {id} was inserted within the last {HEALTH_EVERY} steps (by an insertion or an inflow), placed on or against other particles or walls, or with this speed. Fix: check the insertion's region, diameters and velocity against the particles, walls and meshes already there; the time step is not to blame."
                    ));
                }
            }
        }
        // A moving mesh: the contact's own, or any moving mesh the particle touches.
        let meshes = self.sim.meshes();
        let mesh = match partner {
            Some(grainflow::ContactPartner::Mesh { mesh, .. }) => Some(mesh),
            _ => self.sim.contacts().into_iter().find_map(|c| match c.other {
                grainflow::ContactPartner::Mesh { mesh, .. } if c.particle == i => Some(mesh),
                _ => None,
            }),
        }
        .filter(|&m| meshes[m].motion.moves())?;
        let (speed, how) = meshes[mesh].fastest_point_speed();
        let dt = self.sim.dt();
        Some(format!(
            "Likely cause: mesh '{}' moved into particle {}: it is {how}, its fastest point {:.4e} m a step (dt = {dt:.4e} s), {:.3} of the particle's radius. Fix: lower the mesh's speed, or dt to {:.4e} s ({} of the radius a step).",
            meshes[mesh].mesh.name(),
            p.id[i],
            speed * dt,
            speed * dt / p.radius[i],
            grainflow::timestep::TRAVEL_FRACTION * p.radius[i] / speed.max(f64::MIN_POSITIVE),
            grainflow::timestep::TRAVEL_FRACTION
        ))
    }
}

/// The step interval of periodic checkpoints, if they are counted in steps.
fn checkpoint_steps(options: &RunOptions) -> Option<u64> {
    match options.checkpoint_every {
        Some(CheckpointEvery::Steps(n)) => Some(n),
        _ => None,
    }
}

/// The step in an output file's name (`particles_000001200.csv`, `contacts_000001200.vtp`).
fn step_of(name: &str) -> Option<u64> {
    name.rsplit('_').next()?.split('.').next()?.parse().ok()
}

/// Removes the snapshots and VTK frames (particles, contacts, moving meshes) after `step`
/// that an earlier attempt of the run being continued left: the continued run writes its own.
/// Only files the manifest lists are removed, and none reached through a symbolic link.
fn drop_later_frames(folder: &OutputFolder, step: u64) -> Result<(), OutputError> {
    for sub in ["snapshots", "vtk"] {
        let dir = folder.dir().join(sub);
        if std::fs::symlink_metadata(&dir).is_ok_and(|m| m.file_type().is_symlink()) {
            continue;
        }
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            let listed = folder.lists(&Path::new(sub).join(&name));
            if listed
                && step_of(&name).is_some_and(|s| s > step)
                && entry.file_type().is_ok_and(|t| t.is_file())
            {
                let path = entry.path();
                std::fs::remove_file(&path).map_err(io_err(&path))?;
            }
        }
    }
    Ok(())
}

/// What a checkpoint records of the outputs beside the state ([`Simulation::checkpoint_note`]):
/// what the time series held before the checkpoint's step, and the flow books at the last row
/// before it (the flow columns of the next row count from there). Written as lines of
/// `key value…`, so that further records are further keys; a reader ignores keys it does not
/// know.
#[derive(Debug, Clone, Default, PartialEq)]
struct RunNote {
    series: Option<SeriesRecord>,
    /// The flow books at the last scheduled row before the step.
    flow: Option<FlowCount>,
}

/// The first line of a [`RunNote`].
const NOTE_SIGNATURE: &str = "grainflow run note 1";

impl RunNote {
    fn encode(&self) -> Vec<u8> {
        let mut s = format!("{NOTE_SIGNATURE}\n");
        if let Some(r) = &self.series {
            s.push_str(&format!("series {} {} {} {}\n", r.rows, r.bytes, r.sha256, u8::from(r.row_at_step)));
        }
        if let Some(f) = &self.flow {
            let (i, r) = (f.inserted, f.removed);
            s.push_str(&format!("flow {} {} {} {} {}\n", i.count, i.units, r.count, r.units, f.missed));
        }
        s.into_bytes()
    }

    /// The note in `bytes` (none: a checkpoint written by another program, or before notes).
    fn decode(bytes: &[u8]) -> Option<RunNote> {
        let text = std::str::from_utf8(bytes).ok()?;
        let mut lines = text.lines();
        if lines.next()? != NOTE_SIGNATURE {
            return None;
        }
        let mut note = RunNote::default();
        for line in lines {
            let f: Vec<&str> = line.split_whitespace().collect();
            match f.as_slice() {
                ["series", rows, bytes, hash, at] => {
                    note.series = Some(SeriesRecord {
                        rows: rows.parse().ok()?,
                        bytes: bytes.parse().ok()?,
                        sha256: hash.to_string(),
                        row_at_step: *at == "1",
                    });
                }
                ["flow", ic, iu, rc, ru, missed] => {
                    let t = |c: &str, u: &str| -> Option<grainflow::Tally> {
                        Some(grainflow::Tally { count: c.parse().ok()?, units: u.parse().ok()? })
                    };
                    note.flow = Some(FlowCount {
                        inserted: t(ic, iu)?,
                        removed: t(rc, ru)?,
                        missed: missed.parse().ok()?,
                    });
                }
                _ => {}
            }
        }
        Some(note)
    }
}

/// The time series' columns of the mesh walls' loads, and how each is measured.
struct MeshLoads {
    /// The column names ([`mesh_columns`]).
    columns: Vec<String>,
    /// Each mesh's point the torque is taken about, m.
    about: Vec<Vec3>,
    /// Each mesh's rotation axis (a point on it, unit direction), if it has one.
    axes: Vec<Option<(Vec3, Vec3)>>,
    /// With insertions or outlets: the flow books at the last rows (the flow columns count
    /// what came, went and was missed since).
    flow: Option<std::sync::Mutex<FlowMarks>>,
}

/// The flow books the flow columns count from: inserted and removed (count, mass units) and
/// the particles the insertions could not place.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct FlowCount {
    inserted: grainflow::Tally,
    removed: grainflow::Tally,
    missed: u64,
}

impl FlowCount {
    fn of(b: &grainflow::FlowBooks) -> FlowCount {
        FlowCount { inserted: b.inserted_total(), removed: b.removed_total(), missed: b.missed.iter().sum() }
    }
}

/// The flow books at the last scheduled row of the time series (`last`, of step `last_step`)
/// and at the one before it (`before`): a checkpoint of step s records those of the last row
/// before s, from which the row of s (if rewritten) and the next rows count.
#[derive(Debug, Clone, Copy, Default)]
struct FlowMarks {
    last: FlowCount,
    last_step: Option<u64>,
    before: FlowCount,
}

/// The time series' columns of the insertions and outlets: what came in and went out since
/// the row before (count and mass, kg), the particles' mass now, kg, and the particles the
/// insertions could not place since the row before.
pub const FLOW_COLUMNS: [&str; 6] =
    ["inserted", "inserted_mass", "removed", "removed_mass", "mass", "missed"];

impl MeshLoads {
    fn new(case: &Case) -> MeshLoads {
        let axes: Vec<_> = case.config.meshes.iter().map(rotation_axis).collect();
        let rotating: Vec<bool> = axes.iter().map(Option::is_some).collect();
        let mut columns = mesh_columns(&case.mesh_names, &rotating);
        let cylinders: Vec<String> = case.config.cylinders.iter().map(|c| c.name.clone()).collect();
        columns.extend(cylinder_columns(&cylinders));
        let flow = !(case.config.insertions.is_empty() && case.config.outlets.is_empty());
        if flow {
            columns.extend(FLOW_COLUMNS.iter().map(|c| c.to_string()));
        }
        MeshLoads { columns, about: case.mesh_torque_about.clone(), axes, flow: flow.then(Default::default) }
    }

    /// The flow columns count from nothing (a fresh run, whose first row counts the insertions
    /// made at its start), from `from` (a restart: the books at the last row kept before the
    /// checkpoint's step, as the checkpoint recorded them), or from the books of `sim` (a
    /// restart whose row of its step was kept, or that starts a series of its own).
    fn start_flow(&self, sim: &Simulation, fresh: bool, from: Option<FlowCount>) {
        if let Some(marks) = &self.flow {
            let b = sim.flow_books();
            let now = FlowCount::of(&b);
            let last = if fresh { Default::default() } else { from.unwrap_or(now) };
            let step = (!fresh && from.is_none()).then(|| sim.step_index());
            *marks.lock().unwrap_or_else(|e| e.into_inner()) =
                FlowMarks { last, last_step: step, before: last };
        }
    }

    /// The flow books at the last scheduled row before `step`, for a checkpoint of `step`.
    fn flow_before(&self, step: u64) -> Option<FlowCount> {
        let m = *self.flow.as_ref()?.lock().unwrap_or_else(|e| e.into_inner());
        Some(if m.last_step == Some(step) { m.before } else { m.last })
    }

    /// The row's values, mesh after mesh: the force the particles exert on it at the last
    /// force evaluation, its torque about the mesh's point, and for a mesh with an axis that
    /// torque's component along the axis (about a point of the axis: τ_o = τ_a + (a − o) × F);
    /// then cylinder after cylinder, the same about its origin.
    /// A row on the output schedule (`scheduled`) is the one the next counts from; the extra
    /// row of an interrupted run is not (a restart drops it).
    fn values(&self, sim: &Simulation, scheduled: bool) -> Vec<Value> {
        let mut v: Vec<Value> = Vec::with_capacity(self.columns.len());
        for (m, (&about, axis)) in self.about.iter().zip(&self.axes).enumerate() {
            let load = sim.mesh_load(m, about);
            v.extend(load.force.to_array().map(Value::Real));
            v.extend(load.torque.to_array().map(Value::Real));
            if let Some((origin, direction)) = axis {
                v.push(Value::Real(direction.dot(load.torque + (about - *origin).cross(load.force))));
            }
        }
        for (m, c) in sim.cylinders().iter().enumerate() {
            let load = sim.cylinder_load(m, c.origin);
            v.extend(load.force.to_array().map(Value::Real));
            v.extend(load.torque.to_array().map(Value::Real));
            v.push(Value::Real(c.axis.dot(load.torque)));
        }
        if let Some(marks) = &self.flow {
            let b = sim.flow_books();
            let now = FlowCount::of(&b);
            let mut m = marks.lock().unwrap_or_else(|e| e.into_inner());
            let was = m.last;
            if scheduled {
                *m = FlowMarks { last: now, last_step: Some(sim.step_index()), before: m.last };
            }
            let q = b.quantum;
            let since = |a: grainflow::Tally, b: grainflow::Tally| {
                [Value::Count(a.count - b.count), Value::Real((a.units - b.units) as f64 * q)]
            };
            v.extend(since(now.inserted, was.inserted));
            v.extend(since(now.removed, was.removed));
            v.push(Value::Real(b.mass(b.present)));
            v.push(Value::Count(now.missed - was.missed));
        }
        v
    }
}

#[allow(clippy::too_many_arguments)]
fn run_simulation(
    sim: &mut Simulation,
    output: OutputSettings,
    health: Health,
    mesh_loads: &MeshLoads,
    hash: &str,
    folder: &mut OutputFolder,
    options: &RunOptions,
    on_progress: &mut (dyn FnMut(&Simulation) + Send),
) -> Result<RunSummary, RunError> {
    let OutputSettings { interval, snapshots, vtk_interval } = output;
    let out = folder.dir().to_path_buf();
    let mut output_seconds = 0.0;
    let snap_dir = out.join("snapshots");
    if snapshots {
        std::fs::create_dir_all(&snap_dir).map_err(io_err(&snap_dir))?;
    }
    let start_step = sim.step_index();
    let ts_path = out.join(TIMESERIES_FILE);
    folder.record(Path::new(TIMESERIES_FILE))?;
    // The mesh loads are those of the last force evaluation, which a checkpoint does not
    // hold: a restart of the same case keeps the row its earlier attempt wrote at the
    // checkpoint's step (written before the checkpoint, from the same state) instead of
    // writing it again without them.
    let every = output_every(interval, sim.dt(), sim.total_steps());
    // The output steps: the first, every `every`-th and the last.
    let on_schedule = start_step == 0 || start_step.is_multiple_of(every) || sim.finished();
    let keep_row = !options.accept_changed_case && !mesh_loads.columns.is_empty() && on_schedule;
    // What the checkpoint recorded of the outputs (none for a fresh run, or a checkpoint
    // written before such records).
    let note = options.restart.as_ref().and_then(|_| RunNote::decode(sim.checkpoint_note()));
    let (mut ts, row_kept) = if folder.continues() {
        // The time series is checked before anything in the folder is changed.
        let expected = note.as_ref().and_then(|n| n.series.as_ref());
        let resumed = TimeSeriesWriter::resume(&ts_path, start_step, &mesh_loads.columns, keep_row, expected)
            .map_err(|e| match e {
                ResumeError::Io(e) => RunError::Output(io_err(&ts_path)(e)),
                ResumeError::Changed(message) => {
                    RunError::Restart { path: options.restart.clone().unwrap_or_default(), message }
                }
            })?;
        drop_later_frames(folder, start_step)?;
        resumed
    } else {
        TimeSeriesWriter::create(&ts_path, &mesh_loads.columns)
            .map(|w| (w, false))
            .map_err(io_err(&ts_path))?
    };
    // Rank 0's folder is the user's (the others write into scratch folders): its time series
    // decides whether the restart's first row is written, on every rank.
    let row_kept = agree_with_rank_0(sim, row_kept);
    let flow_from = if folder.continues() && !row_kept { note.as_ref().and_then(|n| n.flow) } else { None };
    mesh_loads.start_flow(sim, options.restart.is_none(), flow_from);
    let mut files = vec![ts_path.clone()];
    let vtk_dir = out.join("vtk");
    let mut vtk = open_vtk(sim, health, folder, &vtk_dir, vtk_interval, start_step)?;
    let vtk_every = vtk.as_ref().map(|(_, k)| *k);
    let checkpoint_path = out.join(CHECKPOINT_FILE);
    // The row and snapshot of an output (`scheduled`: on the output schedule; the extra row
    // of an interrupted run comes without a snapshot, which the uninterrupted run has not:
    // the checkpoint holds that state).
    let emit = |sim: &Simulation,
                ts: &mut TimeSeriesWriter,
                folder: &mut OutputFolder,
                files: &mut Vec<PathBuf>,
                row: bool,
                scheduled: bool|
     -> Result<Diagnostics, RunError> {
        let d = sim.diagnostics();
        if row {
            ts.write(&d, &mesh_loads.values(sim, scheduled)).map_err(io_err(&ts_path))?;
        }
        if snapshots && scheduled {
            let name = format!("particles_{:09}.csv", sim.step_index());
            folder.record(&Path::new("snapshots").join(&name))?;
            let path = snap_dir.join(name);
            // In id order: the file does not depend on how the particles are stored (or spread
            // over ranks).
            write_atomic(&path, snapshot_csv(&sim.gathered_on_rank_0()).as_bytes()).map_err(io_err(&path))?;
            files.push(path);
        }
        Ok(d)
    };
    let write_vtk = |sim: &Simulation,
                     vtk: &mut Option<(VtkSeries, u64)>,
                     folder: &mut OutputFolder,
                     force: bool|
     -> Result<(), RunError> {
        if let Some((series, k)) = vtk.as_mut()
            && (force || sim.step_index().is_multiple_of(*k))
        {
            let (lo, hi) = health.domain;
            let moving = sim.surfaces(lo, hi, Which::Moving);
            for file in frame_files(sim.step_index(), &moving) {
                folder.record(&Path::new("vtk").join(file))?;
            }
            let (particles, contacts) = sim.gathered_on_rank_0_with_contacts();
            series
                .write(sim.step_index(), sim.time(), &particles, &contacts, &moving)
                .map_err(io_err(&vtk_dir))?;
        }
        Ok(())
    };

    // A restart's first state was checked when it was written: only a fresh run's start is
    // the input's.
    let first_check = if start_step == 0 { Checked::Start } else { Checked::after(sim) };
    if let Some(problem) = health_problem(sim, health, first_check) {
        return Err(RunError::Engine(grainflow::EngineError::BadReference(problem)));
    }
    // What a checkpoint of the current step records of the outputs.
    let note = |ts: &TimeSeriesWriter, step: u64| {
        RunNote { series: Some(ts.record_before(step)), flow: mesh_loads.flow_before(step) }.encode()
    };
    sim.set_checkpoint_note(note(&ts, sim.step_index()));
    let mut checked = Checked::after(sim);
    let ranks = sim.ranks() > 1;
    let mut last_good =
        LastGood::new(sim, hash, &out, options.last_good_in_memory.unwrap_or(LAST_GOOD_IN_MEMORY))?;
    // A fresh run writes its initial state; a restarted one continues the output schedule of
    // the run it continues (whose rows up to here were kept), so its files match an
    // uninterrupted run's.
    let (first, mut outputs) = if on_schedule {
        (emit(sim, &mut ts, folder, &mut files, !row_kept, true)?, usize::from(!row_kept))
    } else {
        (sim.diagnostics(), 0)
    };
    // A restart writes the frame of its step only if it is due (the first and last steps
    // always are), as the uninterrupted run did.
    write_vtk(sim, &mut vtk, folder, start_step == 0 || sim.finished())?;
    on_progress(sim);
    let builds_before = sim.neighbors().stats().builds;
    let start = Instant::now();
    let mut last_checkpoint = Instant::now();
    let mut checkpoint = None;
    let mut last = first;
    let mut interrupted = false;
    let n_start = sim.total_particles();
    // Counted at each look at the state, for the steps since the last (a batch inserted or
    // drained within them counts from the look after it).
    let mut particle_steps = 0.0;
    // The steps between two looks at the state are taken in one call (which saves a pass over
    // the particles per step with velocity Verlet): up to the next step that is due for a
    // health check, an output or a checkpoint, and never more than `MAX_STEPS_UNSEEN`, so that
    // progress reports, a stop request and a wall-time checkpoint wait little.
    let periods = [Some(every), Some(HEALTH_EVERY), vtk_every, checkpoint_steps(options)];
    while !sim.finished() {
        let step = sim.step_index();
        let ahead =
            periods.iter().flatten().filter(|&&p| p > 0).fold(MAX_STEPS_UNSEEN, |k, &p| k.min(p - step % p));
        sim.advance(ahead);
        // Collective on ranks: every rank takes each look at the same step.
        particle_steps += (sim.step_index() - step) as f64 * sim.total_particles() as f64;
        let step = sim.step_index();
        let end = sim.finished();
        let output_now = step.is_multiple_of(every) || end;
        if step.is_multiple_of(HEALTH_EVERY) || output_now {
            if let Some(message) = health_problem(sim, health, checked) {
                return Err(unhealthy(message, &last_good, folder, ts, &ts_path));
            }
            checked = Checked::after(sim);
            // Keeping a copy of the state costs a pass over it: refresh it at outputs and
            // every tenth check, not at every check.
            if output_now || step.is_multiple_of(10 * HEALTH_EVERY) {
                sim.set_checkpoint_note(note(&ts, step));
                last_good.keep(sim)?;
            }
        }
        let t_out = Instant::now();
        if output_now {
            last = emit(sim, &mut ts, folder, &mut files, true, true)?;
            outputs += 1;
        }
        write_vtk(sim, &mut vtk, folder, end)?;
        output_seconds += t_out.elapsed().as_secs_f64();
        on_progress(sim);
        let due = match options.checkpoint_every {
            Some(CheckpointEvery::Steps(n)) => n > 0 && step.is_multiple_of(n),
            // On ranks, by rank 0's clock: the ranks write it together.
            Some(CheckpointEvery::WallTime(d)) => agree_with_rank_0(sim, last_checkpoint.elapsed() >= d),
            None => false,
        };
        let stop = stop_requested(sim, options);
        if stop && !end && !output_now {
            // The rows of an interrupted run end at the step it stopped at.
            last = emit(sim, &mut ts, folder, &mut files, true, false)?;
            outputs += 1;
        }
        // With checkpoints on, the last step has one too: a chained restart (a longer t_stop,
        // with --accept-changed-case) goes on from the end, not from an earlier checkpoint.
        let last_checkpoint_due = end && options.checkpoint_every.is_some();
        if ((due || stop) && !end) || last_checkpoint_due {
            // The rows and the list of files up to the checkpoint are on the disk before it is:
            // a restart from it finds them all.
            ts.sync().map_err(io_err(&ts_path))?;
            folder.record(Path::new(CHECKPOINT_FILE))?;
            folder.sync()?;
            sim.set_checkpoint_note(note(&ts, step));
            // On ranks, the whole run gathered on rank 0 (which alone writes it): one file.
            let whole = if ranks { sim.gathered_whole() } else { None };
            if let Some(sim) = if ranks { whole.as_ref() } else { Some(&*sim) } {
                write_atomic_with(&checkpoint_path, |w| sim.write_checkpoint(hash, w))
                    .map_err(io_err(&checkpoint_path))?;
            }
            checkpoint = Some(checkpoint_path.clone());
            last_checkpoint = Instant::now();
        }
        if stop && !end {
            interrupted = true;
            on_progress(sim);
            break;
        }
    }
    let wall = start.elapsed().as_secs_f64();
    ts.finish().map_err(io_err(&ts_path))?;
    if let Some(c) = &checkpoint {
        files.push(c.clone());
    }
    if let Some((series, _)) = &vtk {
        files.extend(series.files().iter().map(|f| vtk_dir.join(f)));
    }
    let steps = sim.step_index() - start_step;
    Ok(RunSummary {
        steps,
        start_step,
        dt: sim.dt(),
        time_step_explanation: sim.time_step().explanation.clone(),
        outputs,
        output_every: every,
        first,
        last,
        wall_seconds: wall,
        particle_steps_per_second: if wall > 0.0 { particle_steps / wall } else { 0.0 },
        particles: (n_start, sim.total_particles()),
        particle_steps,
        threads: sim.threads(),
        thread_report: sim.thread_report(),
        memory: sim.heap_bytes(),
        interrupted,
        checkpoint,
        stages: sim.stage_times().unwrap_or_default(),
        output_seconds,
        files,
        neighbor_pairs: sim.neighbors().pair_count(),
        neighbor_builds: sim.neighbors().stats().builds - builds_before,
        run_id: sim.run_id().to_string(),
        ranks: (sim.ranks(), sim.domain_stats()),
    })
}

/// `yes` on one process; on ranks, rank 0's `yes` on every rank.
fn agree_with_rank_0(sim: &Simulation, yes: bool) -> bool {
    match sim.comm() {
        Some(comm) => comm.all_gather(&[yes as u64])[0][0] != 0,
        None => yes,
    }
}

/// Whether the run was asked to stop; on ranks, whether any rank was (so that they stop
/// together, at the step the first of them was told to).
fn stop_requested(sim: &Simulation, options: &RunOptions) -> bool {
    let stop = options.stop.as_ref().is_some_and(|s| s.load(Ordering::SeqCst));
    match sim.comm() {
        Some(comm) => comm.all_gather(&[stop as u64]).iter().any(|w| w[0] != 0),
        None => stop,
    }
}

/// The error of a run that failed its health check with `message`: the last good state saved
/// and the time series closed.
fn unhealthy(
    message: String,
    kept: &LastGood,
    folder: &mut OutputFolder,
    ts: TimeSeriesWriter,
    ts_path: &Path,
) -> RunError {
    let saved =
        folder.record(Path::new(LAST_GOOD_FILE)).map_err(RunError::from).and_then(|()| Ok(kept.save()?));
    if let Err(e) = ts.finish() {
        return RunError::Output(io_err(ts_path)(e));
    }
    match saved {
        Ok((good_step, saved)) => RunError::Unhealthy { message, good_step, saved },
        Err(e) => e,
    }
}

/// The VTK series of a run that writes one (`vtk_interval`), with the files it records, and
/// its output period in steps.
fn open_vtk(
    sim: &Simulation,
    health: Health,
    folder: &mut OutputFolder,
    vtk_dir: &Path,
    vtk_interval: Option<f64>,
    start_step: u64,
) -> Result<Option<(VtkSeries, u64)>, RunError> {
    Ok(match vtk_interval {
        Some(iv) => {
            let (lo, hi) = health.domain;
            let surfaces = sim.surfaces(lo, hi, Which::All);
            for f in series_files(&surfaces) {
                folder.record(&Path::new("vtk").join(f))?;
            }
            // A series of another run is not continued (its frames were removed).
            let from = if folder.continues() { start_step } else { 0 };
            let series = VtkSeries::resume(vtk_dir, &surfaces, from).map_err(io_err(vtk_dir))?;
            Some((series, output_every(Some(iv), sim.dt(), sim.total_steps())))
        }
        None => None,
    })
}
