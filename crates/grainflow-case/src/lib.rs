//! Case files for grainflow: the TOML case format, particle files, and the writers of
//! `grainflow run`'s output. The engine crate never sees TOML; this crate turns a case file
//! into typed engine objects in one place.
//!
//! Two stages: [`raw`] mirrors the file (serde, unknown keys rejected); [`case`] validates it
//! into a [`Case`] with SI values and cross-field checks.

pub mod case;
pub mod error;

pub mod input;
pub mod lammps;
pub mod mfix;
pub mod outdir;
pub mod output;
pub mod particles;
pub mod plan;
pub mod raw;
pub mod run;
pub mod set;
pub mod vtk;

pub use case::{Case, OutputSettings, load, load_with, parse, parse_with};
pub use error::CaseError;
pub use set::SetOverride;
