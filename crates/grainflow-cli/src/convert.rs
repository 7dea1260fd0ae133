//! `grainflow convert DECK [KEY=VALUE ...] [--motion FILE] > case.toml`: writes the grainflow
//! case equivalent to an MFIX deck or a LIGGGHTS script (`-var NAME VALUE`), so that a case
//! can move over for good.

use crate::EXIT_BAD_INPUT;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The MFIX deck (mfix.dat or *.mfx; particle_input.dat is read beside it) or LIGGGHTS
    /// script (in.* or *.liggghts). The case names its particle file relative to itself:
    /// save the TOML beside the deck or script.
    deck: PathBuf,
    /// KEYWORD=VALUE overrides applied after the deck, as on MFIX's command line; for a
    /// script, its variables (NAME=VALUE or -var NAME VALUE).
    #[arg(value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// A TOML file of [[motion]] tables replacing user-defined functions that prescribe
    /// particle motion (CALL_USR = .TRUE.); the rules are written into the case.
    #[arg(long, value_name = "FILE")]
    motion: Option<PathBuf>,
}

pub fn main(args: ConvertArgs) -> ExitCode {
    let origin = args.deck.display().to_string();
    let translated = if grainflow_case::liggghts::is_script(&args.deck) {
        crate::run::script_variables(&args.overrides).and_then(|vars| {
            grainflow_case::liggghts::load_relayed(&args.deck, &vars, &grainflow_case::input::direct)
                .map(|s| (s.case.warnings, grainflow_case::liggghts::to_toml(&s.raw, &origin, &s.notes)))
                .map_err(|e| e.to_string())
        })
    } else {
        grainflow_case::mfix::load(&args.deck, &args.overrides, args.motion.as_deref())
            .map(|d| (d.case.warnings, grainflow_case::mfix::to_toml(&d.raw, &origin, &d.notes)))
            .map_err(|e| e.to_string())
    };
    let (warnings, toml) = match translated {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let toml = match toml {
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
