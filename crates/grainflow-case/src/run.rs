//! Running a case with its outputs: what `grainflow run` does, without the terminal.

use crate::case::{Case, OutputSettings};
use crate::output::{TimeSeriesWriter, snapshot_csv, write_atomic};
use crate::vtk::VtkSeries;
use grainflow::Vec3;
use grainflow::{Diagnostics, Simulation};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What a finished run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Steps taken.
    pub steps: u64,
    /// Δt, s.
    pub dt: f64,
    /// Which time-step rule gave Δt, in words.
    pub time_step_explanation: String,
    /// Outputs written (time-series rows).
    pub outputs: usize,
    /// Steps between outputs.
    pub output_every: u64,
    /// Diagnostics at the start and at the end.
    pub first: Diagnostics,
    /// Diagnostics at the end.
    pub last: Diagnostics,
    /// Wall-clock time of the time loop, s.
    pub wall_seconds: f64,
    /// Particle-steps per wall-clock second.
    pub particle_steps_per_second: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// A failure while running: only output can fail once a case is valid.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct OutputError {
    /// The file or folder.
    pub path: PathBuf,
    /// Why.
    pub source: std::io::Error,
}

/// Steps between outputs for an interval: the interval rounded to whole steps (at least 1);
/// no interval gives about 100 outputs over the run.
pub fn output_every(interval: Option<f64>, dt: f64, total_steps: u64) -> u64 {
    match interval {
        Some(iv) => ((iv / dt).round() as u64).max(1),
        None => total_steps.div_ceil(100).max(1),
    }
}

/// Runs `case` to its end, writing `out/timeseries.csv`, if enabled
/// `out/snapshots/particles_<step>.csv` at every output (including the first and last step),
/// and if `vtk_interval` is set a VTK series in `out/vtk/`. `on_progress` is called about a
/// thousand times over the run, and after the last step, with the simulation.
pub fn run_case(
    case: Case,
    out: &Path,
    mut on_progress: impl FnMut(&Simulation),
) -> Result<RunSummary, RunError> {
    let (output, domain) = (case.output, case.domain);
    let sim = Simulation::new(case.config, case.particles)?;
    run_simulation(sim, output, domain, out, &mut on_progress)
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
}

fn run_simulation(
    mut sim: Simulation,
    output: OutputSettings,
    domain: (Vec3, Vec3),
    out: &Path,
    on_progress: &mut dyn FnMut(&Simulation),
) -> Result<RunSummary, RunError> {
    let OutputSettings { interval, snapshots, vtk_interval } = output;
    let io_err = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputError { path, source }
    };
    std::fs::create_dir_all(out).map_err(io_err(out))?;
    let snap_dir = out.join("snapshots");
    if snapshots {
        std::fs::create_dir_all(&snap_dir).map_err(io_err(&snap_dir))?;
    }
    let ts_path = out.join("timeseries.csv");
    let mut ts = TimeSeriesWriter::create(&ts_path).map_err(io_err(&ts_path))?;
    let every = output_every(interval, sim.dt(), sim.total_steps());
    let mut files = vec![ts_path.clone()];
    let vtk_dir = out.join("vtk");
    let mut vtk = match vtk_interval {
        Some(iv) => Some((
            VtkSeries::create(&vtk_dir, sim.walls(), domain.0, domain.1).map_err(io_err(&vtk_dir))?,
            output_every(Some(iv), sim.dt(), sim.total_steps()),
        )),
        None => None,
    };
    let mut write_vtk = |sim: &Simulation, force: bool| -> Result<(), OutputError> {
        if let Some((series, k)) = vtk.as_mut() {
            if force || sim.step_index() % *k == 0 {
                series
                    .write(sim.step_index(), sim.time(), sim.particles(), &sim.contacts())
                    .map_err(io_err(&vtk_dir))?;
            }
        }
        Ok(())
    };
    let progress_every = sim.total_steps().div_ceil(1000).max(1);
    let mut outputs = 0;
    let emit = |sim: &Simulation,
                ts: &mut TimeSeriesWriter,
                files: &mut Vec<PathBuf>|
     -> Result<Diagnostics, OutputError> {
        let d = sim.diagnostics();
        ts.write(&d).map_err(io_err(&ts_path))?;
        if snapshots {
            let path = snap_dir.join(format!("particles_{:09}.csv", sim.step_index()));
            write_atomic(&path, snapshot_csv(sim.particles()).as_bytes()).map_err(io_err(&path))?;
            files.push(path);
        }
        Ok(d)
    };
    let first = emit(&sim, &mut ts, &mut files)?;
    write_vtk(&sim, true)?;
    outputs += 1;
    on_progress(&sim);
    let start = Instant::now();
    let mut last = first;
    while !sim.finished() {
        sim.step();
        let end = sim.finished();
        if sim.step_index() % every == 0 || end {
            last = emit(&sim, &mut ts, &mut files)?;
            outputs += 1;
        }
        write_vtk(&sim, end)?;
        if sim.step_index() % progress_every == 0 || end {
            on_progress(&sim);
        }
    }
    let wall = start.elapsed().as_secs_f64();
    ts.finish().map_err(io_err(&ts_path))?;
    if vtk.is_some() {
        files.push(vtk_dir.join("particles.pvd"));
        files.push(vtk_dir.join("contacts.pvd"));
        files.push(vtk_dir.join("walls.vtp"));
    }
    let steps = sim.step_index();
    Ok(RunSummary {
        steps,
        dt: sim.dt(),
        time_step_explanation: sim.time_step().explanation.clone(),
        outputs,
        output_every: every,
        first,
        last,
        wall_seconds: wall,
        particle_steps_per_second: if wall > 0.0 {
            (steps as f64) * (sim.particles().len() as f64) / wall
        } else {
            0.0
        },
        files,
    })
}
