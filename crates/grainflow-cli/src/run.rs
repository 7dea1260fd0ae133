//! `grainflow run CASE.toml [--out DIR]`

use crate::EXIT_BAD_INPUT;
use clap::Args;
use grainflow_case::run::{RunError, run_case};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The case file (TOML; see docs/case-file.md).
    case: PathBuf,
    /// Output folder: timeseries.csv and snapshots/ are written there.
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

pub fn main(args: RunArgs) -> ExitCode {
    let case = match grainflow_case::load(&args.case) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    for w in &case.warnings {
        eprintln!("warning: {w}");
    }
    let n = case.particles.len();
    let title = if case.title.is_empty() { args.case.display().to_string() } else { case.title.clone() };
    println!("grainflow {}: {title}", env!("CARGO_PKG_VERSION"));
    match run_case(case, &args.out, |_| {}) {
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
