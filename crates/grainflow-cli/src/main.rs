//! `grainflow`: the command-line program. Thin: it parses arguments, calls the library crates
//! and turns their errors into messages and exit codes (2 = bad input, 1 = failure).

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod check;
mod convert;
mod example;
#[cfg(feature = "mpi")]
mod ranks;
mod run;
mod signals;
mod verify;

/// grainflow — a discrete element method engine for granular flows (MFIX-DEM compatible).
#[derive(Debug, Parser)]
#[command(
    name = "grainflow",
    version,
    about = "grainflow — a discrete element method (DEM) engine for granular flows, MFIX-DEM compatible",
    after_help = "Quick start:\n  grainflow example settling-bed\n  grainflow check settling-bed/case.toml\n  grainflow run settling-bed/case.toml --out settling-bed/out\n  grainflow verify dem05\n\nCase-file keys, units and defaults: docs/case-file.md. Exit codes: 0 success, 1 a verification check or an output failed, 2 bad input."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a case file (TOML, an MFIX deck: mfix.dat, *.mfx, or a LIGGGHTS script: in.*,
    /// *.liggghts) and write its time series and particle snapshots.
    Run(run::RunArgs),
    /// Validate a case file, MFIX deck or LIGGGHTS script as `run` does and print its plan (time step and
    /// steps, outputs, insertions, memory estimate) without running it; exit 0 if it would
    /// run, 2 if it is refused.
    Check(check::CheckArgs),
    /// Translate an MFIX deck (mfix.dat, *.mfx) or a LIGGGHTS script (in.*, *.liggghts) into
    /// the equivalent grainflow case file (TOML, written to standard output).
    Convert(convert::ConvertArgs),
    /// Run verification cases (all, or those named), compare with analytical solutions,
    /// reference codes and experiments; write CSV, figures, summaries and report.html; exit
    /// non-zero if a check fails.
    Verify(verify::VerifyArgs),
    /// Write a ready-to-run example case into a new folder (list them without a name).
    Example(example::ExampleArgs),
}

/// Exit code for input the program cannot use.
pub const EXIT_BAD_INPUT: u8 = 2;

/// The arguments with LIGGGHTS's `-var NAME VALUE` (also `--var`) turned into the `NAME=VALUE`
/// override a script takes, so that a LIGGGHTS command line runs unchanged.
fn arguments() -> Vec<std::ffi::OsString> {
    let mut out = Vec::new();
    let mut args = std::env::args_os();
    while let Some(a) = args.next() {
        if a == "-var" || a == "--var" {
            match (args.next(), args.next()) {
                (Some(name), Some(value)) => {
                    let mut v = name;
                    v.push("=");
                    v.push(value);
                    out.push(v);
                }
                (name, _) => {
                    // Left for the parser to report.
                    out.push(a);
                    out.extend(name);
                }
            }
        } else {
            out.push(a);
        }
    }
    out
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse_from(arguments()) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                    ExitCode::SUCCESS
                }
                _ => ExitCode::from(EXIT_BAD_INPUT),
            };
        }
    };
    match cli.command {
        Command::Run(args) => run::main(args),
        Command::Check(args) => check::main(args),
        Command::Convert(args) => convert::main(args),
        Command::Verify(args) => verify::main(args),
        Command::Example(args) => example::main(args),
    }
}
