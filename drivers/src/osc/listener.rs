//! Receiving OSC over UDP: a listener thread decodes packets into inputs with their arrival
//! time and sends them over a bounded channel, counting what it cannot decode.

use crate::device::health::{Health, HealthState};
use crate::osc::datagram::decode_datagram;
use crate::osc::error::OscError;
use crate::osc::message::{parse_packet, OscInput};
use crossbeam::channel::{bounded, Receiver, TrySendError};
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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

/// Binds a UDP socket on `addr` (`host:port`, port 0 for any) whose reads time out after
/// 20 ms, so a listener thread notices a stop request and a silent sender.
pub fn bind_udp(addr: &str) -> Result<UdpSocket, OscError> {
    let socket = UdpSocket::bind(addr).map_err(|source| OscError::Bind {
        addr: addr.to_string(),
        source,
    })?;
    socket
        .set_read_timeout(Some(Duration::from_millis(20)))
        .map_err(OscError::Socket)?;
    Ok(socket)
}

impl OscListener {
    /// Binds `addr` (e.g. `127.0.0.1:9000`, port 0 for any) and starts the thread.
    pub fn bind(addr: &str, capacity: usize) -> Result<OscListener, OscError> {
        let socket = bind_udp(addr)?;
        let local = socket.local_addr().map_err(OscError::Socket)?;
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
                    let mut undecodable = None;
                    // A datagram that is not whole is refused whole, never partly applied.
                    match decode_datagram(&buf[..n]) {
                        Ok(p) => parse_packet(&p, &mut inputs, &mut bad),
                        Err(e) => undecodable = Some(e.to_string()),
                    }
                    let errors = bad.iter().map(|e| e.to_string()).chain(undecodable);
                    for e in errors {
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
            .map_err(OscError::Thread)?;
        Ok(OscListener {
            inputs: rx,
            health,
            addr: local,
            stop,
            thread: Some(thread),
        })
    }

    /// Counts an input its performer cannot use (a joint it does not listen for, a glove
    /// message of another size) as a resync, with `error` as the last error.
    pub fn refuse(&self, error: String) {
        self.health.resyncs.fetch_add(1, Ordering::Relaxed);
        self.health.set_error(error);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::osc::message::tests::msg;
    use rosc::{OscBundle, OscPacket, OscType};

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
        let bytes = rosc::encoder::encode(&bundle).unwrap();
        s.send_to(&bytes, l.addr).unwrap();
        // Cut inside its second pose: refused whole, its first pose is not taken.
        s.send_to(&bytes[..bytes.len() - 8], l.addr).unwrap();
        s.send_to(b"garbage!", l.addr).unwrap();
        let mut got = Vec::new();
        let start = Instant::now();
        while l.health.report().resyncs < 2 && start.elapsed() < Duration::from_secs(10) {
            if let Ok(x) = l.inputs.recv_timeout(Duration::from_millis(20)) {
                got.push(x.1);
            }
        }
        got.extend(l.inputs.try_iter().map(|x| x.1));
        assert_eq!(got.len(), 2);
        assert_eq!(l.health.report().resyncs, 2);
        assert_eq!(l.health.state(), HealthState::Streaming);
    }
}
