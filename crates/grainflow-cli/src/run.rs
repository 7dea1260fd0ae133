//! `grainflow run CASE.toml [--out DIR]`

use crate::EXIT_BAD_INPUT;
use clap::Args;
use grainflow::Simulation;
use grainflow_case::CaseError;
use grainflow_case::run::{RunError, run_case};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Progress of a run: a bar with particle-steps per second, simulated time and ETA on a
/// terminal; a plain line every 10 % of the run otherwise (logs, batch jobs); nothing with
/// `--quiet`.
enum Progress {
    Quiet,
    Bar { bar: ProgressBar, start: Instant },
    Lines { start: Instant, next_percent: u64 },
}

impl Progress {
    fn new(quiet: bool) -> Self {
        if quiet {
            Progress::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(0);
            let style =
                ProgressStyle::with_template("{bar:40.cyan/blue} {pos}/{len} steps  {msg}  ETA {eta}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style);
            Progress::Bar { bar, start: Instant::now() }
        } else {
            Progress::Lines { start: Instant::now(), next_percent: 10 }
        }
    }

    fn rate(start: &Instant, sim: &Simulation) -> f64 {
        let secs = start.elapsed().as_secs_f64();
        if secs > 0.0 { sim.step_index() as f64 * sim.particles().len() as f64 / secs } else { 0.0 }
    }

    fn update(&mut self, sim: &Simulation) {
        match self {
            Progress::Quiet => {}
            Progress::Bar { bar, start } => {
                bar.set_length(sim.total_steps());
                bar.set_position(sim.step_index());
                bar.set_message(format!(
                    "t = {:.4e} s  {:.3e} particle-steps/s",
                    sim.time(),
                    Self::rate(start, sim)
                ));
            }
            Progress::Lines { start, next_percent } => {
                let percent = 100 * sim.step_index() / sim.total_steps().max(1);
                if percent >= *next_percent {
                    let secs = start.elapsed().as_secs_f64();
                    let eta = secs * (100 - percent) as f64 / percent.max(1) as f64;
                    eprintln!(
                        "{percent:3}%  step {}/{}  t = {:.4e} s  {:.3e} particle-steps/s  ETA {eta:.0} s",
                        sim.step_index(),
                        sim.total_steps(),
                        sim.time(),
                        Self::rate(start, sim)
                    );
                    *next_percent = percent / 10 * 10 + 10;
                }
            }
        }
    }

    fn finish(&self) {
        if let Progress::Bar { bar, .. } = self {
            bar.finish_and_clear();
        }
    }
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The case file (TOML; see docs/case-file.md).
    case: PathBuf,
    /// Output folder: timeseries.csv, snapshots/ and vtk/ are written there.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// No progress bar or progress lines (the summary is still printed).
    #[arg(long, short)]
    quiet: bool,
}

pub fn main(args: RunArgs) -> ExitCode {
    let case = match grainflow_case::load(&args.case) {
        Ok(c) => c,
        Err(e) => {
            // Syntax and read errors name the file already; the others name table and key.
            match e {
                CaseError::Syntax(_) | CaseError::Read { .. } => eprintln!("error: {e}"),
                _ => eprintln!("error: {}: {e}", args.case.display()),
            }
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    for w in &case.warnings {
        eprintln!("warning: {w}");
    }
    let n = case.particles.len();
    let title = if case.title.is_empty() { args.case.display().to_string() } else { case.title.clone() };
    println!("grainflow {}: {title}", env!("CARGO_PKG_VERSION"));
    let mut progress = Progress::new(args.quiet);
    let result = run_case(case, &args.out, |sim| progress.update(sim));
    progress.finish();
    match result {
        Ok(s) => {
            println!("{}", s.time_step_explanation);
            println!(
                "{} particles, {} steps of {:.6e} s to t = {:.6e} s; {} outputs (every {} steps) in {}",
                n,
                s.steps,
                s.dt,
                s.last.time,
                s.outputs,
                s.output_every,
                args.out.display()
            );
            println!(
                "kinetic energy {:.6e} J -> {:.6e} J (translational), {:.6e} J -> {:.6e} J (rotational); {} contacts at the end, max overlap/radius {:.3e}",
                s.first.kinetic_translational,
                s.last.kinetic_translational,
                s.first.kinetic_rotational,
                s.last.kinetic_rotational,
                s.last.contacts,
                s.last.max_overlap_ratio
            );
            println!(
                "wall time {:.3} s, {:.3e} particle-steps/s",
                s.wall_seconds, s.particle_steps_per_second
            );
            ExitCode::SUCCESS
        }
        Err(RunError::Engine(e)) => {
            eprintln!("error: {}: {e}", args.case.display());
            ExitCode::from(EXIT_BAD_INPUT)
        }
        Err(e @ RunError::Output(_)) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
