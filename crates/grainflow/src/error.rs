//! Errors the engine reports when it is set up with values it cannot use.

use thiserror::Error;

/// An engine set-up error. The case-file layer maps these to messages that name the key.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EngineError {
    /// A value is outside its valid range.
    #[error("{what} = {value} is invalid: {valid}")]
    InvalidValue {
        /// Which quantity (e.g. "phase 'glass' diameter").
        what: String,
        /// The offending value, as text.
        value: String,
        /// What would be valid.
        valid: String,
    },
    /// A parameter needed by the chosen contact model was not given.
    #[error("{what} is required by the {model} contact model but was not given")]
    MissingParameter {
        /// Which quantity is missing.
        what: String,
        /// The model that needs it.
        model: String,
    },
    /// A reference to a particle, phase or material that does not exist.
    #[error("{0}")]
    BadReference(String),
}

impl EngineError {
    pub(crate) fn invalid(what: impl Into<String>, value: f64, valid: impl Into<String>) -> Self {
        EngineError::InvalidValue { what: what.into(), value: format!("{value}"), valid: valid.into() }
    }
}
