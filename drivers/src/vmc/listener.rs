//! Receiving VMC datagrams over UDP: a thread hands each datagram, as bytes, with its
//! arrival time to the performer over a bounded channel, keeps the health (stale after
//! half a second of silence, streaming again when packets resume), and records the
//! datagrams to `.rec` when asked. Decoding happens in the tick, so a replay decodes the
//! very bytes a live run did.

use crate::device::health::{Health, HealthState};
use crate::osc::OscError;
use crate::record::writer::Recorder;
use crossbeam::channel::{bounded, Receiver, TrySendError};
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A VMC sender silent this long is `stale`.
pub const STALE_AFTER: Duration = Duration::from_millis(500);

/// Datagrams waiting for the tick; a burst beyond this is dropped and counted.
pub const QUEUE: usize = 1024;

/// The kind of a VMC stream in a `.rec` file; each data chunk is one datagram.
pub const REC_KIND: &str = "vmc";

/// A UDP listener thread for VMC datagrams.
pub struct VmcListener {
    /// Datagrams with their arrival time, oldest first.
    pub datagrams: Receiver<(Instant, Vec<u8>)>,
    /// State and counters: samples = datagrams, dropped samples = a full queue.
    pub health: Arc<Health>,
    /// The bound address.
    pub addr: SocketAddr,
    /// When the thread started.
    pub started: Instant,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl VmcListener {
    /// Binds `addr` (`host:port`; port 0 for any) and starts the thread; `record` keeps
    /// every datagram under the stream name `name`.
    pub fn bind(
        addr: &str,
        name: &str,
        record: Option<Arc<Recorder>>,
    ) -> Result<VmcListener, OscError> {
        let socket = UdpSocket::bind(addr).map_err(|source| OscError::Bind {
            addr: addr.to_string(),
            source,
        })?;
        socket
            .set_read_timeout(Some(Duration::from_millis(20)))
            .map_err(OscError::Socket)?;
        let local = socket.local_addr().map_err(OscError::Socket)?;
        let (tx, rx) = bounded(QUEUE);
        let health = Arc::new(Health::new_state(HealthState::Connected));
        let stop = Arc::new(AtomicBool::new(false));
        let stream = record.as_ref().map(|r| {
            let settings = serde_json::json!({ "listen": local.to_string() });
            r.add_stream(name, REC_KIND, settings)
        });
        let (h, s) = (health.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name(format!("vmc {local}"))
            .spawn(move || {
                let mut buf = vec![0u8; 65_507];
                let mut last: Option<Instant> = None;
                while !s.load(Ordering::Acquire) {
                    let n = match socket.recv(&mut buf) {
                        Ok(n) => n,
                        Err(_) => {
                            if last.is_some_and(|t| t.elapsed() > STALE_AFTER) {
                                h.set_state(HealthState::Stale);
                            }
                            continue;
                        }
                    };
                    let now = Instant::now();
                    last = Some(now);
                    if let (Some(r), Some(i)) = (&record, stream) {
                        r.data(i, &buf[..n]);
                    }
                    h.samples.fetch_add(1, Ordering::Relaxed);
                    h.set_state(HealthState::Streaming);
                    if let Err(TrySendError::Full(_)) = tx.try_send((now, buf[..n].to_vec())) {
                        h.dropped_samples.fetch_add(1, Ordering::Relaxed);
                    }
                }
            })
            .map_err(OscError::Thread)?;
        Ok(VmcListener {
            datagrams: rx,
            health,
            addr: local,
            started: Instant::now(),
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for VmcListener {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
