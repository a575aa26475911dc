//! Receiving VMC datagrams: a thread reads each datagram — from a UDP socket, or from a
//! relay's key (`troupe relay vmc` on the sender's machine) — and hands it, as bytes,
//! with its arrival on the receiver clock, to the performer over a bounded channel; it
//! keeps the health (stale after half a second of silence, streaming again when packets
//! resume), and records the datagrams to `.rec` when asked. Decoding happens in the tick,
//! so a replay decodes the very bytes a live run did; the tick marks which datagrams it
//! took and the clock it played them at (`stream`).

use crate::device::health::{Health, HealthState};
use crate::device::port::Port;
use crate::osc::listener::bind_udp;
use crate::osc::OscError;
use crate::record::writer::Recorder;
use crate::vmc::stream::micros_since;
use crossbeam::channel::{bounded, Receiver, TrySendError};
use std::io::{ErrorKind, Read, Write};
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub use crate::vmc::stream::REC_KIND;

/// A VMC sender silent this long is `stale`.
pub const STALE_AFTER: Duration = Duration::from_millis(500);

/// Datagrams waiting for the tick; a burst beyond this is dropped and counted.
pub const QUEUE: usize = 1024;

/// The largest UDP payload: a read buffer that holds any datagram whole.
pub const MAX_DATAGRAM: usize = 65_507;

/// A UDP socket read one datagram a read (timing out after 20 ms), as a port: what
/// `troupe relay vmc` serves. A VMC sender takes no commands: writes are dropped.
pub struct UdpDatagrams(pub UdpSocket);

impl UdpDatagrams {
    /// Binds `addr` (`host:port`; port 0 for any) with a 20 ms read timeout.
    pub fn bind(addr: &str) -> Result<UdpDatagrams, OscError> {
        bind_udp(addr).map(UdpDatagrams)
    }
}

impl Read for UdpDatagrams {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.0.recv(buf)
    }
}

impl Write for UdpDatagrams {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// One datagram as it arrived.
#[derive(Clone, Debug)]
pub struct Datagram {
    /// Its number in the stream, from 0 (every datagram read, queued or dropped).
    pub seq: u64,
    /// When it arrived.
    pub arrived: Instant,
    /// When it arrived on the receiver clock, in microseconds (the recording's `micros`).
    pub micros: u64,
    /// Its bytes.
    pub bytes: Vec<u8>,
}

/// A listener thread for VMC datagrams.
pub struct VmcListener {
    /// Datagrams, oldest first.
    pub datagrams: Receiver<Datagram>,
    /// State and counters: samples = datagrams, dropped samples = a full queue.
    pub health: Arc<Health>,
    /// Where the datagrams come from: the bound address, or `zenoh:KEY`.
    pub from: String,
    /// The receiver clock's origin: the recording's start when recording, else the
    /// listener's.
    pub origin: Instant,
    /// The recorder and this stream in it, when recording.
    recording: Option<(Arc<Recorder>, u16)>,
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
        let socket = UdpDatagrams::bind(addr)?;
        let local = socket.0.local_addr().map_err(OscError::Socket)?;
        let settings = serde_json::json!({ "listen": local.to_string() });
        VmcListener::start(Box::new(socket), local.to_string(), settings, name, record)
    }

    /// Reads the datagrams a relay serves: `port` gives one datagram a read (a relay's
    /// chunk), timing out when none waits, and never fails for a relay that went away.
    pub fn relayed(
        port: Box<dyn Port>,
        key: &str,
        name: &str,
        record: Option<Arc<Recorder>>,
    ) -> Result<VmcListener, OscError> {
        let settings = serde_json::json!({ "zenoh": key });
        VmcListener::start(port, format!("zenoh:{key}"), settings, name, record)
    }

    fn start(
        mut source: Box<dyn Read + Send>,
        from: String,
        settings: serde_json::Value,
        name: &str,
        record: Option<Arc<Recorder>>,
    ) -> Result<VmcListener, OscError> {
        let (tx, rx) = bounded(QUEUE);
        let health = Arc::new(Health::new_state(HealthState::Connected));
        let stop = Arc::new(AtomicBool::new(false));
        let recording = record.map(|r| {
            let stream = r.add_stream(name, REC_KIND, settings);
            (r, stream)
        });
        let origin = recording
            .as_ref()
            .map_or_else(Instant::now, |(r, _)| r.started());
        let (h, s, rec) = (health.clone(), stop.clone(), recording.clone());
        let thread = std::thread::Builder::new()
            .name(format!("vmc {from}"))
            .spawn(move || {
                let mut buf = vec![0u8; MAX_DATAGRAM];
                let mut last: Option<Instant> = None;
                let mut seq = 0u64;
                while !s.load(Ordering::Acquire) {
                    let n = match source.read(&mut buf) {
                        Ok(n) => n,
                        Err(e) => {
                            if last.is_some_and(|t| t.elapsed() > STALE_AFTER) {
                                h.set_state(HealthState::Stale);
                            }
                            if !matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) {
                                // Not a quiet moment: do not spin on an error.
                                std::thread::sleep(Duration::from_millis(5));
                            }
                            continue;
                        }
                    };
                    let now = Instant::now();
                    let micros = micros_since(origin, now);
                    last = Some(now);
                    if let Some((r, i)) = &rec {
                        r.data_at(*i, micros, &buf[..n]);
                    }
                    h.samples.fetch_add(1, Ordering::Relaxed);
                    h.set_state(HealthState::Streaming);
                    let d = Datagram {
                        seq,
                        arrived: now,
                        micros,
                        bytes: buf[..n].to_vec(),
                    };
                    seq += 1;
                    if let Err(TrySendError::Full(_)) = tx.try_send(d) {
                        h.dropped_samples.fetch_add(1, Ordering::Relaxed);
                    }
                }
            })
            .map_err(OscError::Thread)?;
        Ok(VmcListener {
            datagrams: rx,
            health,
            from,
            origin,
            recording,
            stop,
            thread: Some(thread),
        })
    }

    /// Every datagram waiting, noting in the recording (if any) that `ticks` ticks after
    /// the performer was made the scene had taken them, so a replay takes them then too.
    pub fn drain_at_tick(&self, ticks: u64) -> Vec<Datagram> {
        let taken: Vec<Datagram> = self.datagrams.try_iter().collect();
        if let (Some((r, stream)), Some(last)) = (&self.recording, taken.last()) {
            r.mark(*stream, ticks, last.seq + 1);
        }
        taken
    }

    /// The receiver clock now, in microseconds, noted in the recording (if any) as the
    /// clock of `ticks` ticks after the performer was made.
    pub fn clock_at_tick(&self, ticks: u64) -> u64 {
        let micros = micros_since(self.origin, Instant::now());
        if let Some((r, stream)) = &self.recording {
            r.clock(*stream, ticks, micros);
        }
        micros
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
