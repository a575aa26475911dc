//! Opening a Zenoh session from troupe's options: explicit endpoints, no multicast
//! scouting (an installation's machines are named, and a test on loopback must not join
//! whatever else runs on the network).

use crate::error::NetError;
use std::time::Duration;
use zenoh::handlers::FifoChannelHandler;
use zenoh::query::Reply;
use zenoh::{Config, Session, Wait};

/// Where a troupe process meets the others.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Endpoints {
    /// Endpoints to connect to (`tcp/10.0.0.5:7447`).
    pub connect: Vec<String>,
    /// Endpoints to listen on (`tcp/0.0.0.0:7447`); none: Zenoh's default for a peer.
    pub listen: Vec<String>,
}

impl Endpoints {
    /// A peer listening on the loopback interface at `port` (0: a free port), for tests
    /// and measurements on one machine.
    pub fn loopback_listener(port: u16) -> Self {
        Self {
            connect: vec![],
            listen: vec![format!("tcp/127.0.0.1:{port}")],
        }
    }

    /// A peer connecting to the loopback listener at `port`, listening on a free loopback
    /// port itself.
    pub fn loopback_peer(port: u16) -> Self {
        Self {
            connect: vec![format!("tcp/127.0.0.1:{port}")],
            listen: vec!["tcp/127.0.0.1:0".into()],
        }
    }

    /// The Zenoh configuration: a peer with these endpoints and scouting off.
    pub fn config(&self) -> Result<Config, NetError> {
        let mut config = Config::default();
        let set = |config: &mut Config, key: &str, value: String| {
            config
                .insert_json5(key, &value)
                .map_err(|e| NetError::Config {
                    what: format!("{key} = {value}"),
                    message: e.to_string(),
                })
        };
        set(&mut config, "mode", "\"peer\"".into())?;
        set(&mut config, "scouting/multicast/enabled", "false".into())?;
        let list = |v: &[String]| serde_json::to_string(v).expect("strings serialize");
        if !self.connect.is_empty() {
            check(&self.connect, "--zenoh-connect")?;
            set(&mut config, "connect/endpoints", list(&self.connect))?;
        }
        if !self.listen.is_empty() {
            check(&self.listen, "--zenoh-listen")?;
            set(&mut config, "listen/endpoints", list(&self.listen))?;
        }
        Ok(config)
    }

    /// Opens a session.
    pub fn open(&self) -> Result<Session, NetError> {
        zenoh::open(self.config()?)
            .wait()
            .map_err(|e| NetError::Open(e.to_string()))
    }
}

/// Refuses endpoints that are not `PROTOCOL/ADDRESS`, naming the option.
fn check(endpoints: &[String], option: &str) -> Result<(), NetError> {
    for e in endpoints {
        if let Err(err) = e.parse::<zenoh::config::EndPoint>() {
            return Err(NetError::Config {
                what: format!("{option} {e}"),
                message: format!("{err} (an endpoint looks like tcp/127.0.0.1:7447)"),
            });
        }
    }
    Ok(())
}

/// Asks the queryables on `key`; their replies arrive on the returned channel until
/// `timeout` has passed.
pub(crate) fn query(
    session: &Session,
    key: &str,
    timeout: Duration,
) -> Result<FifoChannelHandler<Reply>, NetError> {
    session
        .get(key)
        .timeout(timeout)
        .wait()
        .map_err(|e| NetError::Declare {
            what: "query",
            key: key.to_string(),
            message: e.to_string(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_malformed_endpoint_is_named() {
        let e = Endpoints {
            connect: vec!["localhost:7447".into()],
            listen: vec![],
        };
        let err = e.config().unwrap_err().to_string();
        assert!(err.contains("--zenoh-connect localhost:7447"), "{err}");
    }
}
