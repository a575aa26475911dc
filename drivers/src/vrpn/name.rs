//! VRPN device names as VRPN users write them: `Tracker0@host` (port 3883),
//! `Tracker0@host:3884`, and `Tracker0@tcp://host:3884` (TCP only, no UDP).

use crate::vrpn::error::VrpnError;
use serde::{Deserialize, Serialize};

/// VRPN's well-known port.
pub const DEFAULT_PORT: u16 = 3883;

/// A parsed device name: which device, on which server, over what.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceName {
    /// The device (the server's sender name), e.g. `Tracker0`.
    pub device: String,
    /// The server's host name or address.
    pub host: String,
    /// The server's port.
    pub port: u16,
    /// `tcp://`: every message over TCP; otherwise the server's unreliable messages (the
    /// tracker reports) come over UDP.
    pub tcp_only: bool,
}

impl DeviceName {
    /// Parses `Device@host[:port]` or `Device@tcp://host:port`.
    pub fn parse(name: &str) -> Result<DeviceName, VrpnError> {
        let bad = |why| VrpnError::Name {
            name: name.to_string(),
            why,
        };
        let (device, server) = name.split_once('@').ok_or_else(|| bad("no '@'"))?;
        if device.is_empty() {
            return Err(bad("no device before '@'"));
        }
        if device.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(bad("spaces or control characters in the device"));
        }
        let (tcp_only, server) = match server.split_once("://") {
            None => (false, server),
            Some(("tcp", rest)) => (true, rest),
            Some(_) => return Err(bad("the only scheme is tcp://")),
        };
        // `[::1]:3883` for IPv6 literals; otherwise the last ':' starts the port.
        let (host, port) = if let Some(rest) = server.strip_prefix('[') {
            let (h, after) = rest.split_once(']').ok_or_else(|| bad("no ']'"))?;
            (h, after.strip_prefix(':'))
        } else {
            match server.rsplit_once(':') {
                Some((h, p)) => (h, Some(p)),
                None => (server, None),
            }
        };
        if host.is_empty() {
            return Err(bad("no host after '@'"));
        }
        let port = match port {
            None => DEFAULT_PORT,
            Some(p) => p
                .parse::<u16>()
                .ok()
                .filter(|&p| p != 0)
                .ok_or_else(|| bad("the port is not a number 1…65535"))?,
        };
        Ok(DeviceName {
            device: device.to_string(),
            host: host.to_string(),
            port,
            tcp_only,
        })
    }

    /// `host:port`, for connecting and for messages.
    pub fn server(&self) -> String {
        if self.host.contains(':') {
            format!("[{}]:{}", self.host, self.port)
        } else {
            format!("{}:{}", self.host, self.port)
        }
    }
}

impl std::fmt::Display for DeviceName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let scheme = if self.tcp_only { "tcp://" } else { "" };
        write!(f, "{}@{scheme}{}", self.device, self.server())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_as_vrpn_users_write_them() {
        let n = DeviceName::parse("Tracker0@tracking-pc").unwrap();
        assert_eq!(
            (n.device.as_str(), n.host.as_str()),
            ("Tracker0", "tracking-pc")
        );
        assert_eq!((n.port, n.tcp_only), (3883, false));
        let n = DeviceName::parse("Spin0@127.0.0.1:3999").unwrap();
        assert_eq!((n.port, n.tcp_only), (3999, false));
        let n = DeviceName::parse("Wand@tcp://lab:4000").unwrap();
        assert_eq!((n.host.as_str(), n.port, n.tcp_only), ("lab", 4000, true));
        assert_eq!(n.to_string(), "Wand@tcp://lab:4000");
        let n = DeviceName::parse("T@[::1]:5000").unwrap();
        assert_eq!((n.host.as_str(), n.port), ("::1", 5000));
        assert_eq!(n.server(), "[::1]:5000");
    }

    #[test]
    fn malformed_names_say_what_is_wrong() {
        for (name, why) in [
            ("Tracker0", "no '@'"),
            ("@host", "no device"),
            ("T@", "no host"),
            ("T@host:port", "not a number"),
            ("T@host:0", "not a number"),
            ("T@udp://host:1", "only scheme"),
        ] {
            let e = DeviceName::parse(name).unwrap_err().to_string();
            assert!(e.contains(why) && e.contains(name), "{name}: {e}");
        }
    }
}
