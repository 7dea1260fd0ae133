//! Errors of the verification runs.

use std::path::PathBuf;

/// Why a verification case could not be run or written (its checks failing is not an error).
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    /// A shipped case file did not validate.
    #[error("shipped case {case}: {source}")]
    Case {
        /// Which case file.
        case: String,
        /// Why.
        source: grainflow_case::CaseError,
    },
    /// The engine refused the set-up.
    #[error("{0}")]
    Engine(#[from] grainflow::EngineError),
    /// Writing output failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Drawing a figure failed.
    #[error("{0}")]
    Plot(#[from] crate::plot::PlotError),
}

/// Maps an io error to [`VerifyError::Io`] for `path`.
pub fn io_at(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> VerifyError + '_ {
    move |source| VerifyError::Io { path: path.to_path_buf(), source }
}
