//! Case files for grainflow: the TOML case format, MFIX decks and particle files, read and
//! validated. The engine crate never sees TOML; this crate turns a case file into typed engine
//! objects in one place. Running a case and writing its outputs is `grainflow-run`'s.
//!
//! Two stages: [`raw`] mirrors the file (serde, unknown keys rejected); [`case`] validates it
//! into a [`Case`] with SI values and cross-field checks.

pub mod case;
pub mod error;

pub mod input;
pub mod lammps;
pub mod liggghts;
pub mod mfix;
pub mod particles;
pub mod plan;
pub mod raw;
pub mod set;

pub use case::{Bed, Case, OutputSettings, load, load_relayed, load_scoped, load_with, parse, parse_with};
pub use error::CaseError;
pub use set::SetOverride;
