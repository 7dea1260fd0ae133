//! Verification cases for grainflow: each case runs the engine, compares with its analytical
//! or experimental reference, writes CSV files and figures, and reports its checks.

pub mod plot;
