//! The errors of the body model: names a skeleton does not have, values out of range.

use thiserror::Error;

/// Everything that can go wrong when building a body or running its algorithms on outside input.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A joint name that the skeleton does not have.
    #[error("unknown joint `{name}` in skeleton `{skeleton}`")]
    UnknownJoint { name: String, skeleton: String },
    /// A DOF name that the skeleton does not have.
    #[error("unknown DOF `{name}` in skeleton `{skeleton}`")]
    UnknownDof { name: String, skeleton: String },
    /// A scope name (or scope expression term) that means nothing for the skeleton.
    #[error("unknown scope `{name}` in skeleton `{skeleton}` (known scopes: {known})")]
    UnknownScope {
        name: String,
        skeleton: String,
        known: String,
    },
    /// A body template name that does not exist.
    #[error("unknown body template `{name}` (known templates: {known})")]
    UnknownTemplate { name: String, known: String },
    /// A name used twice where names must be unique.
    #[error("{what} `{name}` already exists")]
    Duplicate { what: &'static str, name: String },
    /// A numeric parameter outside its valid range.
    #[error("invalid {what}: {value} ({expected})")]
    InvalidValue {
        what: String,
        value: f64,
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

/// The body model's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
