//! Verification cases for grainflow: each case runs the engine, compares with its analytical
//! or experimental reference, writes CSV files and figures, and reports its checks.

pub mod check;
pub mod chung_ooi;
pub mod dem01;
pub mod dem02;
pub mod dem03;
pub mod dem04;
pub mod dem05;
pub mod drum;
pub mod error;
pub mod jkr;
pub mod kharaz;
pub mod packing;
pub mod plot;
pub mod report;
pub mod rolling;
pub mod silo;
pub mod suite;

pub use check::{Check, CheckKind};
pub use error::VerifyError;
