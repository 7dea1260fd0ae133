//! `grainflow`: the command-line program. Thin: it parses arguments, calls the library crates
//! and turns their errors into messages and exit codes (2 = bad input, 1 = failure).

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod run;
mod verify;

/// grainflow — a discrete element method engine for granular flows (MFIX-DEM compatible).
#[derive(Debug, Parser)]
#[command(name = "grainflow", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a case file (TOML) and write its time series and particle snapshots.
    Run(run::RunArgs),
    /// Run a verification case, compare with theory and experiment, write CSV, figures and
    /// a summary; exits non-zero if a check fails.
    Verify(verify::VerifyArgs),
}

/// Exit code for input the program cannot use.
pub const EXIT_BAD_INPUT: u8 = 2;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
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
        Command::Verify(args) => verify::main(args),
    }
}
