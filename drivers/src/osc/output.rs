//! Sending OSC over UDP: every actor's joint poses (one bundle per actor per tick) and the
//! tick's action events, as a session observer.
//!
//! | address | arguments |
//! |---|---|
//! | `/troupe/<actor>/<joint>` | `x y z qw qx qy qz` for every joint |
//! | `/troupe/event`           | `actor` (string), `action id` (int), `kind` (string), `status` (string), `time` (float) |

use crate::osc::error::OscError;
use rosc::{OscBundle, OscMessage, OscPacket, OscType};
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use troupe_scene::Scene;

/// Sends actor poses and action events to one UDP address.
pub struct OscSender {
    socket: UdpSocket,
    target: SocketAddr,
}

impl OscSender {
    /// A sender to `target` (`host:port`).
    pub fn new(target: &str) -> Result<OscSender, OscError> {
        let addr = target
            .to_socket_addrs()
            .map_err(|source| OscError::Address {
                target: target.to_string(),
                source,
            })?
            .next()
            .ok_or_else(|| OscError::Unresolved(target.to_string()))?;
        let bind = if addr.is_ipv4() {
            "0.0.0.0:0"
        } else {
            "[::]:0"
        };
        let socket = UdpSocket::bind(bind).map_err(OscError::Socket)?;
        Ok(OscSender {
            socket,
            target: addr,
        })
    }

    /// The packets of one tick: a bundle of joint poses per actor, then one message per event.
    pub fn packets(scene: &Scene, events: &[troupe_scene::Event]) -> Vec<OscPacket> {
        let mut out = Vec::new();
        for (i, actor) in scene.actors().iter().enumerate() {
            let state = &scene.states()[i];
            let content = actor
                .skeleton
                .joints()
                .iter()
                .zip(&state.globals)
                .map(|(j, g)| {
                    let (p, q) = (g.translation, g.rotation);
                    OscPacket::Message(OscMessage {
                        addr: format!("/troupe/{}/{}", actor.name, j.name),
                        args: [p.x, p.y, p.z, q.w, q.x, q.y, q.z]
                            .iter()
                            .map(|v| OscType::Float(*v as f32))
                            .collect(),
                    })
                })
                .collect();
            out.push(OscPacket::Bundle(OscBundle {
                timetag: (0, 1).into(),
                content,
            }));
        }
        for e in events {
            let kind = scene
                .action(e.action)
                .map(|a| a.kind.clone())
                .unwrap_or_default();
            out.push(OscPacket::Message(OscMessage {
                addr: "/troupe/event".into(),
                args: vec![
                    OscType::String(
                        scene
                            .actors()
                            .get(e.actor)
                            .map(|a| a.name.clone())
                            .unwrap_or_default(),
                    ),
                    OscType::Int(e.action.0 as i32),
                    OscType::String(kind),
                    OscType::String(e.status.name().into()),
                    OscType::Float(e.time as f32),
                ],
            }));
        }
        out
    }

    /// Sends one tick's poses and events; returns the datagrams sent.
    pub fn send(&self, scene: &Scene, events: &[troupe_scene::Event]) -> Result<usize, OscError> {
        let mut n = 0;
        for p in OscSender::packets(scene, events) {
            let bytes = rosc::encoder::encode(&p).map_err(OscError::Encode)?;
            self.socket
                .send_to(&bytes, self.target)
                .map_err(|source| OscError::Send {
                    target: self.target,
                    source,
                })?;
            n += 1;
        }
        Ok(n)
    }
}

/// Sends every tick's poses and events over OSC as a session observer. A lost datagram
/// must not end a run: the first failure is logged, the rest are counted.
pub struct OscOut {
    sender: OscSender,
    failures: u64,
}

impl OscOut {
    /// An observer sending to `target` (`host:port`).
    pub fn new(target: &str) -> Result<OscOut, OscError> {
        Ok(OscOut {
            sender: OscSender::new(target)?,
            failures: 0,
        })
    }

    /// Sends that failed so far.
    pub fn failures(&self) -> u64 {
        self.failures
    }
}

impl troupe_scene::Observer for OscOut {
    fn name(&self) -> String {
        format!("--osc-out {}", self.sender.target)
    }

    fn publish(
        &mut self,
        scene: &Scene,
        events: &[troupe_scene::Event],
    ) -> troupe_scene::Result<()> {
        if let Err(e) = self.sender.send(scene, events) {
            if self.failures == 0 {
                tracing::warn!("--osc-out: {e} (further failures are counted)");
            }
            self.failures += 1;
        }
        Ok(())
    }

    fn finish(&mut self, _scene: &Scene) -> troupe_scene::Result<Option<String>> {
        Ok((self.failures > 0).then(|| format!("--osc-out: {} sends failed", self.failures)))
    }
}
