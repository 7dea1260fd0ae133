//! `grainflow convert DECK [KEY=VALUE ...] [--motion FILE] > case.toml`: writes the grainflow
//! case equivalent to an MFIX deck, so that a case can move over for good.

use crate::EXIT_BAD_INPUT;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The MFIX deck (mfix.dat or *.mfx); particle_input.dat is read beside it. The case
    /// names that file relative to itself: save the TOML beside the deck.
    deck: PathBuf,
    /// KEYWORD=VALUE overrides applied after the deck, as on MFIX's command line.
    #[arg(value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// A TOML file of [[motion]] tables replacing user-defined functions that prescribe
    /// particle motion (CALL_USR = .TRUE.); the rules are written into the case.
    #[arg(long, value_name = "FILE")]
    motion: Option<PathBuf>,
}

pub fn main(args: ConvertArgs) -> ExitCode {
    let deck = match grainflow_case::mfix::load(&args.deck, &args.overrides, args.motion.as_deref()) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    for w in &deck.case.warnings {
        eprintln!("warning: {w}");
    }
    let toml = match grainflow_case::mfix::to_toml(&deck.raw, &args.deck.display().to_string(), &deck.notes) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(toml.as_bytes()).and_then(|_| out.flush()) {
        eprintln!("error: cannot write the case to standard output: {e}");
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}
