//! `grainflow check CASE [--set KEY=VALUE]…`: validates a case (TOML, an MFIX deck or a
//! LIGGGHTS script) as `grainflow run` does and prints its plan (time step and steps,
//! outputs, insertions, memory) without running it.

use crate::EXIT_BAD_INPUT;
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The case file: TOML (docs/case-file.md), an MFIX deck, `*.dat` or `*.mfx`, or a
    /// LIGGGHTS script, `in.*` or `*.liggghts`.
    case: PathBuf,
    /// MFIX decks: KEYWORD=VALUE overrides applied after the deck; LIGGGHTS scripts: their
    /// variables, NAME=VALUE or -var NAME VALUE (as `grainflow run`).
    #[arg(value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// MFIX decks only: a TOML file of [[motion]] tables (as `grainflow run`).
    #[arg(long, value_name = "FILE")]
    motion: Option<PathBuf>,
    /// TOML case files only: set a key by its dotted path (as `grainflow run --set`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// The memory limit the plan is held to (as `grainflow run --memory-limit`).
    #[arg(long, value_name = "SIZE", value_parser = grainflow_case::plan::parse_size)]
    memory_limit: Option<f64>,
}

pub fn main(args: CheckArgs) -> ExitCode {
    let _stop = crate::signals::install();
    grainflow_case::plan::set_memory_limit(args.memory_limit);
    let case = match crate::run::load_and_warn(
        &args.case,
        &args.overrides,
        args.motion.as_deref(),
        &args.set,
        &grainflow_case::input::direct,
    ) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let plan = match grainflow_case::plan::plan(&case, grainflow_case::plan::memory_limit()) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {}: {e}", args.case.display());
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    let title = if case.title.is_empty() { args.case.display().to_string() } else { case.title.clone() };
    println!("grainflow {} check: {title}: the case is valid; nothing was run", env!("CARGO_PKG_VERSION"));
    for line in plan.lines() {
        println!("{line}");
    }
    ExitCode::SUCCESS
}
