//! `grainflow verify [CASE ...] [--out DIR] [--list] [--converged] [--integrator NAME]`

use crate::EXIT_BAD_INPUT;
use clap::{Args, ValueEnum};
use grainflow::Integrator;
use grainflow_verify::suite::{self, SuiteOptions};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// Cases to run (default: all); see --list.
    cases: Vec<String>,
    /// List the cases, one line each, and exit.
    #[arg(long)]
    list: bool,
    /// Output folder: each case writes DIR/<case>/, the suite writes DIR/report.html.
    #[arg(long, default_value = "results")]
    out: PathBuf,
    /// Also run the converged and full variants (DEM05: both models again at dt = 2.5e-9 s,
    /// about 5 000 steps per contact, separating the model from MFIX's coarse time stepping;
    /// drum: Fr = 1e-4, 1e-3, 1e-2 over half a revolution each instead of Fr = 1e-2 only;
    /// silo: five orifices from 5 to 15 d instead of three; packing: seven friction
    /// coefficients instead of three).
    #[arg(long)]
    converged: bool,
    /// Integrator of the converged runs (MFIX's own runs keep the case's integrator).
    #[arg(long, value_enum, requires = "converged")]
    integrator: Option<IntegratorName>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum IntegratorName {
    Euler,
    AdamsBashforth,
    VelocityVerlet,
}

pub fn main(args: VerifyArgs) -> ExitCode {
    if args.list {
        for c in suite::cases() {
            println!("{:<12} {}", c.name, c.summary);
        }
        return ExitCode::SUCCESS;
    }
    let entries = match suite::select(&args.cases) {
        Ok(e) => e,
        Err(msg) => {
            eprintln!("error: {msg}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let options = SuiteOptions {
        converged: args.converged,
        integrator: args.integrator.map(|i| match i {
            IntegratorName::Euler => Integrator::Euler,
            IntegratorName::AdamsBashforth => Integrator::AdamsBashforth,
            IntegratorName::VelocityVerlet => Integrator::VelocityVerlet,
        }),
    };
    let outcomes = match suite::run(&entries, &args.out, &options) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let report = match suite::write_report(&outcomes, &args.out) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    // One line per case (and each failed check); every check's table is in the report.
    print!("{}", suite::console_summary(&outcomes));
    let failed: Vec<&str> = outcomes.iter().filter(|o| !o.passed()).map(|o| o.name).collect();
    println!("report, with every check's table and the figures: {}", report.display());
    if failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        eprintln!("error: verification failed in {} (see the checks marked FAIL)", failed.join(", "));
        ExitCode::FAILURE
    }
}
