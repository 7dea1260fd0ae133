//! Verification cases for grainflow: each case runs the engine, compares with its analytical
//! or experimental reference, writes CSV files and figures, and reports its checks.

pub mod check;
pub mod dem05;
pub mod error;
pub mod kharaz;
pub mod plot;

pub use check::{Check, CheckKind};
pub use error::VerifyError;
