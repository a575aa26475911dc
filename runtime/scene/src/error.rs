//! The errors of building and driving a scene: unknown names, refused actions.

use thiserror::Error;

/// Everything that can go wrong when building or driving a scene from outside input.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// An actor name that the scene does not have.
    #[error("unknown actor `{0}`")]
    UnknownActor(String),
    /// An object name that the scene does not have.
    #[error("unknown object `{0}`")]
    UnknownObject(String),
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
    /// An observer of a session failed (a recording that could not be written).
    #[error("{observer}: {message}")]
    Observer {
        /// The observer (`--record out.trk`).
        observer: String,
        /// What is wrong, or what was expected.
        message: String,
    },
    /// An input of a session failed (a device that vanished, a malformed packet).
    #[error("{input}: {message}")]
    Input {
        /// The input.
        input: String,
        /// What is wrong, or what was expected.
        message: String,
    },
    /// The body model refused a value or a name.
    #[error(transparent)]
    Body(#[from] troupe_body::Error),
    /// A sequence is not valid.
    #[error(transparent)]
    Motion(#[from] troupe_motion::Error),
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

/// The scene crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
