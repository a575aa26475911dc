//! OSC over UDP (rosc): receive poses and glove values from installation tools, send actor
//! poses and action events out.
//!
//! Addresses (all arguments are floats unless said otherwise; ints are accepted for floats):
//!
//! | direction | address | arguments |
//! |---|---|---|
//! | in  | `/troupe/<performer>/<joint>` | `x y z qw qx qy qz`: the joint's world position (m) and orientation, scene frame |
//! | in  | `/troupe/<performer>/glove`   | one value per glove sensor, raw 1…255 |
//! | out | `/troupe/<actor>/<joint>`     | `x y z qw qx qy qz` for every joint, one bundle per actor per tick |
//! | out | `/troupe/event`               | `actor` (string), `action id` (int), `kind` (string), `status` (string), `time` (float) |

use crate::driver::{Health, HealthState};
use crossbeam::channel::{bounded, Receiver, TrySendError};
use glam::{DQuat, DVec3};
use rosc::{OscBundle, OscMessage, OscPacket, OscType};
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use troupe_scene::Scene;

/// One decoded OSC input.
#[derive(Clone, Debug, PartialEq)]
pub enum OscInput {
    /// A joint's world pose for a performer.
    Pose {
        /// Performer name.
        performer: String,
        /// Joint name (template names, or the aliases `pelvis`, `root`, `head`).
        joint: String,
        /// World position, metres.
        position: DVec3,
        /// World orientation.
        rotation: DQuat,
    },
    /// Raw glove values for a performer.
    Glove {
        /// Performer name.
        performer: String,
        /// Raw values 1…255.
        raw: Vec<u8>,
    },
}

fn number(a: &OscType) -> Option<f64> {
    match a {
        OscType::Float(f) => Some(f64::from(*f)),
        OscType::Double(d) => Some(*d),
        OscType::Int(i) => Some(f64::from(*i)),
        OscType::Long(l) => Some(*l as f64),
        _ => None,
    }
}

/// Decodes one message; the error names the address and what was wrong.
pub fn parse_message(m: &OscMessage) -> Result<OscInput, String> {
    let parts: Vec<&str> = m.addr.trim_start_matches('/').split('/').collect();
    let (performer, what) = match parts.as_slice() {
        ["troupe", p, w] if !p.is_empty() && !w.is_empty() => (p.to_string(), *w),
        _ => {
            return Err(format!(
                "{}: expected /troupe/<performer>/<joint|glove>",
                m.addr
            ))
        }
    };
    let nums: Option<Vec<f64>> = m.args.iter().map(number).collect();
    let nums = nums.ok_or_else(|| format!("{}: arguments must be numbers", m.addr))?;
    if what == "glove" {
        if nums.is_empty() {
            return Err(format!("{}: no glove values", m.addr));
        }
        let raw = nums
            .iter()
            .map(|v| v.round().clamp(1.0, 255.0) as u8)
            .collect();
        return Ok(OscInput::Glove { performer, raw });
    }
    if nums.len() != 7 || nums.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "{}: expected 7 finite numbers x y z qw qx qy qz, got {}",
            m.addr,
            nums.len()
        ));
    }
    let q = DQuat::from_xyzw(nums[4], nums[5], nums[6], nums[3]);
    if q.length() < 1e-6 {
        return Err(format!("{}: zero quaternion", m.addr));
    }
    Ok(OscInput::Pose {
        performer,
        joint: what.to_string(),
        position: DVec3::new(nums[0], nums[1], nums[2]),
        rotation: q.normalize(),
    })
}

/// Decodes a packet (bundles recursively) into inputs; bad messages are counted in `bad`.
pub fn parse_packet(p: &OscPacket, out: &mut Vec<OscInput>, bad: &mut Vec<String>) {
    match p {
        OscPacket::Message(m) => match parse_message(m) {
            Ok(i) => out.push(i),
            Err(e) => bad.push(e),
        },
        OscPacket::Bundle(b) => b.content.iter().for_each(|c| parse_packet(c, out, bad)),
    }
}

/// A UDP listener thread: inputs with their arrival time over a bounded channel.
pub struct OscListener {
    /// Inputs, oldest first.
    pub inputs: Receiver<(Instant, OscInput)>,
    /// Counters: samples = inputs, resyncs = undecodable packets or bad messages.
    pub health: Arc<Health>,
    /// The bound address.
    pub addr: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl OscListener {
    /// Binds `addr` (e.g. `127.0.0.1:9000`, port 0 for any) and starts the thread.
    pub fn bind(addr: &str, capacity: usize) -> Result<OscListener, String> {
        let socket = UdpSocket::bind(addr).map_err(|e| format!("OSC: binding {addr}: {e}"))?;
        socket
            .set_read_timeout(Some(Duration::from_millis(20)))
            .map_err(|e| format!("OSC: {e}"))?;
        let local = socket.local_addr().map_err(|e| format!("OSC: {e}"))?;
        let (tx, rx) = bounded(capacity.max(1));
        let health = Arc::new(Health::new_state(HealthState::Connected));
        let stop = Arc::new(AtomicBool::new(false));
        let (h, s) = (health.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name(format!("osc {local}"))
            .spawn(move || {
                // The largest UDP payload: a bundle with every joint of an actor (what
                // `--osc-out` sends) is several KB, more than rosc's MTU constant.
                let mut buf = vec![0u8; 65_507];
                while !s.load(Ordering::Acquire) {
                    let n = match socket.recv(&mut buf) {
                        Ok(n) => n,
                        Err(_) => continue,
                    };
                    let now = Instant::now();
                    let mut inputs = Vec::new();
                    let mut bad = Vec::new();
                    match rosc::decoder::decode_udp(&buf[..n]) {
                        Ok((_, p)) => parse_packet(&p, &mut inputs, &mut bad),
                        Err(e) => bad.push(format!("undecodable OSC packet: {e}")),
                    }
                    for e in bad {
                        h.resyncs.fetch_add(1, Ordering::Relaxed);
                        h.dropped_bytes.fetch_add(n as u64, Ordering::Relaxed);
                        h.set_error(e);
                    }
                    for i in inputs {
                        h.samples.fetch_add(1, Ordering::Relaxed);
                        h.set_state(HealthState::Streaming);
                        if let Err(TrySendError::Full(_)) = tx.try_send((now, i)) {
                            h.dropped_samples.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                }
            })
            .map_err(|e| format!("OSC: starting the thread: {e}"))?;
        Ok(OscListener {
            inputs: rx,
            health,
            addr: local,
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for OscListener {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Sends actor poses and action events to one UDP address.
pub struct OscSender {
    socket: UdpSocket,
    target: SocketAddr,
}

impl OscSender {
    /// A sender to `target` (`host:port`).
    pub fn new(target: &str) -> Result<OscSender, String> {
        let addr = target
            .to_socket_addrs()
            .map_err(|e| format!("OSC: address {target}: {e}"))?
            .next()
            .ok_or_else(|| format!("OSC: address {target} resolves to nothing"))?;
        let bind = if addr.is_ipv4() {
            "0.0.0.0:0"
        } else {
            "[::]:0"
        };
        let socket = UdpSocket::bind(bind).map_err(|e| format!("OSC: {e}"))?;
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
    pub fn send(&self, scene: &Scene, events: &[troupe_scene::Event]) -> Result<usize, String> {
        let mut n = 0;
        for p in OscSender::packets(scene, events) {
            let bytes = rosc::encoder::encode(&p).map_err(|e| format!("OSC: encoding: {e}"))?;
            self.socket
                .send_to(&bytes, self.target)
                .map_err(|e| format!("OSC: sending to {}: {e}", self.target))?;
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
    pub fn new(target: &str) -> Result<OscOut, String> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(addr: &str, args: Vec<OscType>) -> OscMessage {
        OscMessage {
            addr: addr.into(),
            args,
        }
    }

    #[test]
    fn poses_and_glove_values_parse() {
        let m = msg(
            "/troupe/pat/r_wrist",
            [0.1f32, 1.2, 0.3, 1.0, 0.0, 0.0, 0.0]
                .iter()
                .map(|v| OscType::Float(*v))
                .collect(),
        );
        match parse_message(&m).unwrap() {
            OscInput::Pose {
                performer,
                joint,
                position,
                rotation,
            } => {
                assert_eq!((performer.as_str(), joint.as_str()), ("pat", "r_wrist"));
                assert!((position - DVec3::new(0.1, 1.2, 0.3)).length() < 1e-6);
                assert_eq!(rotation, DQuat::IDENTITY);
            }
            other => panic!("{other:?}"),
        }
        let g = msg(
            "/troupe/pat/glove",
            vec![OscType::Int(3), OscType::Float(300.0), OscType::Int(0)],
        );
        assert_eq!(
            parse_message(&g).unwrap(),
            OscInput::Glove {
                performer: "pat".into(),
                raw: vec![3, 255, 1]
            }
        );
    }

    #[test]
    fn bad_messages_name_the_problem() {
        assert!(parse_message(&msg("/other/x", vec![]))
            .unwrap_err()
            .contains("/troupe/<performer>"));
        assert!(
            parse_message(&msg("/troupe/pat/head", vec![OscType::Float(1.0)]))
                .unwrap_err()
                .contains("7 finite numbers")
        );
        assert!(
            parse_message(&msg("/troupe/pat/head", vec![OscType::String("a".into())]))
                .unwrap_err()
                .contains("numbers")
        );
        let zero: Vec<OscType> = (0..7).map(|_| OscType::Float(0.0)).collect();
        assert!(parse_message(&msg("/troupe/pat/head", zero))
            .unwrap_err()
            .contains("zero quaternion"));
    }

    #[test]
    fn listener_receives_bundles_over_udp_and_counts_garbage() {
        let l = OscListener::bind("127.0.0.1:0", 16).unwrap();
        let s = UdpSocket::bind("127.0.0.1:0").unwrap();
        let pose = OscPacket::Message(msg(
            "/troupe/pat/pelvis",
            [0.0f32, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0]
                .iter()
                .map(|v| OscType::Float(*v))
                .collect(),
        ));
        let bundle = OscPacket::Bundle(OscBundle {
            timetag: (0, 1).into(),
            content: vec![pose.clone(), pose],
        });
        s.send_to(&rosc::encoder::encode(&bundle).unwrap(), l.addr)
            .unwrap();
        s.send_to(b"garbage!", l.addr).unwrap();
        let mut got = Vec::new();
        let start = Instant::now();
        while (got.len() < 2 || l.health.report().resyncs < 1)
            && start.elapsed() < Duration::from_secs(10)
        {
            if let Ok(x) = l.inputs.recv_timeout(Duration::from_millis(20)) {
                got.push(x.1);
            }
        }
        assert_eq!(got.len(), 2);
        assert_eq!(l.health.report().resyncs, 1);
        assert_eq!(l.health.state(), HealthState::Streaming);
    }
}
