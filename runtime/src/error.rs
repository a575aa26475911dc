//! The errors the runtime reports at its boundaries.

use thiserror::Error;

/// Everything that can go wrong when building or driving a scene from outside input.
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
    /// An actor name that the scene does not have.
    #[error("unknown actor `{0}`")]
    UnknownActor(String),
    /// An object name that the scene does not have.
    #[error("unknown object `{0}`")]
    UnknownObject(String),
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
    /// A file that does not parse: names the file, the line and what was expected.
    #[error("{file}:{line}: {message}")]
    Parse {
        file: String,
        line: usize,
        message: String,
    },
    /// A file that could not be read or written.
    #[error("{path}: {message}")]
    Io { path: String, message: String },
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

    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl AsRef<std::path::Path>, err: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().display().to_string(),
            message: err.to_string(),
        }
    }
}

/// The runtime's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
