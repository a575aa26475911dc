//! The errors of loading and running Lua scenes.

use thiserror::Error;

/// Everything that can go wrong when loading a scene script or setting up its director.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A script that does not load or run, with Lua's message (file, line, traceback).
    #[error("{0}")]
    Script(String),
    /// Anything else asked of the director that cannot be done, with the reason.
    #[error("{0}")]
    Invalid(String),
    /// A file that could not be read.
    #[error("{path}: {message}")]
    Io {
        /// The path.
        path: String,
        /// What is wrong, or what was expected.
        message: String,
    },
    /// The scene refused what the script asked.
    #[error(transparent)]
    Scene(#[from] troupe_scene::Error),
    /// A file the script named did not read.
    #[error(transparent)]
    Formats(#[from] troupe_formats::Error),
}

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl AsRef<std::path::Path>, err: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().display().to_string(),
            message: err.to_string(),
        }
    }
}

/// The Lua bridge's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
