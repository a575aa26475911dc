//! The errors of reading and writing files: what, where, and what was expected.

use thiserror::Error;

/// Everything that can go wrong reading or writing BVH, glTF, `.trk` or URDF.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
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
    /// A file that does not parse: names the file, the line and what was expected.
    #[error("{file}:{line}: {message}")]
    Parse {
        /// The file.
        file: String,
        /// The line (1-based; 0 when the file as a whole is wrong).
        line: usize,
        /// What is wrong, or what was expected.
        message: String,
    },
    /// A rotation order that is not three distinct axes.
    #[error("bad rotation order `{0}`: three distinct axes of X, Y and Z, e.g. ZXY")]
    RotationOrder(String),
    /// A retargeting map that cannot map a BVH onto a troupe body.
    #[error("retarget map `{map}`: {message}")]
    Retarget {
        /// See the variant.
        map: String,
        /// What is wrong, or what was expected.
        message: String,
    },
    /// A file whose extension names no motion format troupe reads or writes.
    #[error(
        "{path}: cannot read or write motion files with {extension} (use .trk, .bvh, .gltf or .glb)"
    )]
    UnknownFormat {
        /// The path.
        path: String,
        /// Its extension in backquotes, or `no extension`.
        extension: String,
    },
    /// A file whose motion is bound to a body (BVH, glTF), loaded without one.
    #[error("{path}: a {format} motion plays on a body; give the skeleton to load it onto")]
    NeedsBody {
        /// The path.
        path: String,
        /// See the variant.
        format: String,
    },
    /// A file that could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The path.
        path: String,
        /// What is wrong, or what was expected.
        message: String,
    },
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

/// Asserts that parsing `text` failed with an [`Error::Parse`] naming `file`, `line` and a
/// message containing `needle` (for the readers' tests).
#[cfg(test)]
pub(crate) fn assert_parse_error<T: std::fmt::Debug>(
    result: Result<T>,
    text: &str,
    file: &str,
    line: usize,
    needle: &str,
) {
    match result {
        Err(Error::Parse {
            file: f,
            line: l,
            message,
        }) => {
            assert_eq!(f, file);
            assert_eq!(l, line, "{text:?}: {message}");
            assert!(message.contains(needle), "{text:?}: {message}");
        }
        other => panic!("{text:?}: {other:?}"),
    }
}
