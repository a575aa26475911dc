//! What can go wrong between machines.

use thiserror::Error;

/// An error of troupe's Zenoh side, naming what failed.
#[derive(Debug, Error)]
pub enum NetError {
    /// An endpoint or configuration value Zenoh refused.
    #[error("zenoh configuration {what}: {message}")]
    Config {
        /// The setting (`--zenoh-connect tcp/…`).
        what: String,
        /// Zenoh's reason.
        message: String,
    },
    /// Opening the session failed (an endpoint that cannot be listened on, …).
    #[error("opening the zenoh session: {0}")]
    Open(String),
    /// A key expression that is not valid here.
    #[error("key {key:?}: {message}")]
    Key {
        /// The key or name.
        key: String,
        /// Why it is refused.
        message: String,
    },
    /// Declaring a publisher, subscriber or queryable failed.
    #[error("declaring {what} on {key}: {message}")]
    Declare {
        /// `publisher`, `subscriber` or `queryable`.
        what: &'static str,
        /// The key expression.
        key: String,
        /// Zenoh's reason.
        message: String,
    },
}
