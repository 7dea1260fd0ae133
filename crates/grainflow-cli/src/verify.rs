//! `grainflow verify dem05 [--out DIR] [--converged] [--integrator NAME]`

use clap::{Args, ValueEnum};
use grainflow::Integrator;
use grainflow_verify::dem05;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// The case to verify.
    #[arg(value_enum)]
    case: CaseName,
    /// Output folder; results go to DIR/<case>/.
    #[arg(long, default_value = "results")]
    out: PathBuf,
    /// Also rerun both models with a much smaller time step (2.5e-9 s, about 5 000 steps per
    /// contact), to separate the model from MFIX's coarse time stepping, and run the checks
    /// that need it.
    #[arg(long)]
    converged: bool,
    /// Integrator of the converged runs (MFIX's own runs always use the case's
    /// Adams–Bashforth).
    #[arg(long, value_enum, requires = "converged")]
    integrator: Option<IntegratorName>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum CaseName {
    /// MFIX DEM05: oblique particle collision (LSD and Hertz, wall and particle).
    Dem05,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum IntegratorName {
    Euler,
    AdamsBashforth,
    VelocityVerlet,
}

pub fn main(args: VerifyArgs) -> ExitCode {
    let CaseName::Dem05 = args.case;
    let options = dem05::Options {
        converged: args.converged,
        integrator: args.integrator.map(|i| match i {
            IntegratorName::Euler => Integrator::Euler,
            IntegratorName::AdamsBashforth => Integrator::AdamsBashforth,
            IntegratorName::VelocityVerlet => Integrator::VelocityVerlet,
        }),
    };
    let result = dem05::evaluate(options).and_then(|report| {
        let files = dem05::write(&report, &args.out)?;
        Ok((report, files))
    });
    match result {
        Ok((report, files)) => {
            print!("{}", dem05::summary_markdown(&report));
            println!("\nwritten:");
            for f in files {
                println!("  {}", f.display());
            }
            if report.passed() {
                ExitCode::SUCCESS
            } else {
                eprintln!("error: DEM05 verification failed (see the checks marked FAIL)");
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
