//! The errors of motion sequences and the offline tools that edit them.

use thiserror::Error;

/// Everything that can go wrong when building, sampling or editing sequences.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A name used twice where names must be unique.
    #[error("{what} `{name}` already exists")]
    Duplicate {
        /// What kind of thing (`actor`, `object`, `track`).
        what: &'static str,
        /// The name.
        name: String,
    },
    /// A numeric parameter outside its valid range.
    #[error("invalid {what}: {value} ({expected})")]
    InvalidValue {
        /// The parameter.
        what: String,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: String,
    },
    /// Anything else a caller asked for that cannot be done, with the reason.
    #[error("{0}")]
    Invalid(String),
}

impl Error {
    /// Shorthand for [`Error::InvalidValue`].
    pub fn invalid_value(what: impl Into<String>, value: f64, expected: impl Into<String>) -> Self {
        Error::InvalidValue {
            what: what.into(),
            value,
            expected: expected.into(),
        }
    }
}

/// The motion crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
