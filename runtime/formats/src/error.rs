//! The errors of reading and writing files: what, where, and what was expected.

use thiserror::Error;

/// Everything that can go wrong reading or writing BVH, glTF, `.trk` or URDF.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
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
    /// The body model refused what the file describes.
    #[error(transparent)]
    Body(#[from] troupe_body::Error),
    /// A sequence in the file is not valid.
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

    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl AsRef<std::path::Path>, err: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().display().to_string(),
            message: err.to_string(),
        }
    }
}

/// The formats crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
