//! The run loop of grainflow and its outputs: what `grainflow run` does, without the terminal.
//! A case comes from `grainflow-case`, which only reads and validates; this crate runs it
//! ([`run::run_case`]) into an output folder ([`outdir`]) with the time series and snapshots
//! ([`output`]), VTK series ([`vtk`]) and checkpoints.
//!
//! ```no_run
//! use grainflow_run::run::{RunOptions, run_case};
//!
//! let case = grainflow_case::load("case.toml".as_ref())?;
//! let summary = run_case(case, "out".as_ref(), &RunOptions::default(), |_| {})?;
//! println!("{} steps", summary.steps);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod outdir;
pub mod output;
pub mod relay;
pub mod run;
pub mod share;
pub mod vtk;
