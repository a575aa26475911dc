//! What can go wrong naming, reaching or reading a VRPN server.

use std::time::Duration;

/// A VRPN name that does not parse, a server that cannot be reached or answers wrongly,
/// or bytes that are not VRPN messages.
#[derive(Debug, thiserror::Error)]
pub enum VrpnError {
    /// A device name not of the form `Device@host[:port]` or `Device@tcp://host:port`.
    #[error(
        "VRPN device name '{name}': {why} (expected Device@host[:port] or Device@tcp://host:port)"
    )]
    Name {
        /// The name given.
        name: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// The host does not resolve to an address.
    #[error("{server}: no address for this host ({source})")]
    Resolve {
        /// `host:port`.
        server: String,
        /// What the resolver said.
        #[source]
        source: std::io::Error,
    },
    /// The TCP connection failed.
    #[error("{server}: connecting: {source}")]
    Connect {
        /// `host:port`.
        server: String,
        /// What the socket said.
        #[source]
        source: std::io::Error,
    },
    /// The server accepted the connection but sent no (whole) cookie in time.
    #[error("{server}: no VRPN cookie within {:.1} s (got {got} of 24 bytes): not a VRPN server, or a stalled one", timeout.as_secs_f64())]
    HandshakeTimeout {
        /// `host:port`.
        server: String,
        /// How long troupe waited.
        timeout: Duration,
        /// Bytes that arrived.
        got: usize,
    },
    /// The server closed the connection during the handshake.
    #[error("{server}: closed the connection during the handshake ({got} of 24 cookie bytes)")]
    HandshakeClosed {
        /// `host:port`.
        server: String,
        /// Bytes that arrived.
        got: usize,
    },
    /// The first bytes are not a VRPN cookie.
    #[error("not a VRPN cookie: '{0}'")]
    Cookie(String),
    /// A VRPN peer of another major version: the protocols differ.
    #[error("the server speaks VRPN major version {major} ({major:02}.{minor:02}); troupe speaks {ours:02}.xx, and major versions do not interoperate")]
    Version {
        /// The peer's major version.
        major: u32,
        /// The peer's minor version.
        minor: u32,
        /// Ours.
        ours: u32,
    },
    /// A header whose length field is shorter than a header or longer than the limit.
    #[error("message header claims {0} bytes (a message has 24 to 65536)")]
    Length(u32),
    /// A datagram that ends inside a message.
    #[error("datagram ends {0} bytes into an incomplete message")]
    Truncated(usize),
    /// Opening or using the sockets failed.
    #[error("{what}: {source}")]
    Io {
        /// What troupe was doing.
        what: String,
        /// What the socket said.
        #[source]
        source: std::io::Error,
    },
}
