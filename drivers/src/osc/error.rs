//! What can go wrong binding, resolving or sending OSC.

use std::net::SocketAddr;

/// An OSC socket that cannot be set up or a packet that cannot be sent.
#[derive(Debug, thiserror::Error)]
pub enum OscError {
    /// The listening address cannot be bound.
    #[error("OSC: binding {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: String,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// A socket operation failed.
    #[error("OSC: {0}")]
    Socket(#[source] std::io::Error),
    /// The listener thread could not be started.
    #[error("OSC: starting the thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The target address is not `host:port`.
    #[error("OSC: address {target}: {source}")]
    Address {
        /// The target given.
        target: String,
        /// Why it does not resolve.
        #[source]
        source: std::io::Error,
    },
    /// The target resolves to no address.
    #[error("OSC: address {0} resolves to nothing")]
    Unresolved(String),
    /// A packet could not be encoded.
    #[error("OSC: encoding: {0}")]
    Encode(#[source] rosc::OscError),
    /// A datagram could not be sent.
    #[error("OSC: sending to {target}: {source}")]
    Send {
        /// The target.
        target: SocketAddr,
        /// What the socket said.
        #[source]
        source: std::io::Error,
    },
}
