//! Remote device hosts: a byte stream (a serial port with a tracker or a glove, a hidraw
//! node, a VRPN connection, a VMC sender's UDP datagrams) served on Zenoh by `troupe
//! relay`, and read on the simulation host as if it were the port.
//!
//! The relay reads what the device sends and puts it on `<key>/rx` as it arrives, each
//! chunk stamped with its source time; whatever is put on `<key>/tx` (the commands a
//! driver sends to configure or poll its device) is written to the device. The
//! simulation host opens a [`ZenohPort`] on the same key and runs the very driver thread
//! a local device runs: the same decoder, health (`stale` when the relay goes silent or
//! away, `streaming` again when it is back), and `.rec` recording of the raw bytes, so a
//! replay of a relayed device is byte-identical to one of a local device.
//!
//! A chunk on `<key>/rx` (little-endian): `u64` source time in microseconds since the
//! Unix epoch (the relay host's clock), then the bytes read.

use crate::error::NetError;
use crossbeam::channel::{unbounded, Receiver};
use std::io::{ErrorKind, Read, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime, UNIX_EPOCH};
use zenoh::pubsub::Subscriber;
use zenoh::qos::CongestionControl;
use zenoh::{Session, Wait};

/// How long a [`ZenohPort`] read waits for bytes before it reports a timeout, as a
/// serial port opened by the drivers does.
pub const READ_TIMEOUT: Duration = Duration::from_millis(20);

/// The key the device's bytes are put on.
pub fn rx_key(key: &str) -> String {
    format!("{key}/rx")
}

/// The key commands for the device are put on.
pub fn tx_key(key: &str) -> String {
    format!("{key}/tx")
}

/// Microseconds since the Unix epoch, now.
pub fn now_micros() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_micros() as u64)
}

/// One chunk as put on `<key>/rx`.
pub fn encode_chunk(source_micros: u64, bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + bytes.len());
    out.extend_from_slice(&source_micros.to_le_bytes());
    out.extend_from_slice(bytes);
    out
}

/// The source time and the bytes of a chunk; `None` when shorter than its time stamp.
pub fn decode_chunk(chunk: &[u8]) -> Option<(u64, &[u8])> {
    let stamp: [u8; 8] = chunk.get(..8)?.try_into().ok()?;
    Some((u64::from_le_bytes(stamp), &chunk[8..]))
}

/// What a relay did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RelayStats {
    /// Chunks put on `<key>/rx`.
    pub chunks: u64,
    /// Bytes read from the device.
    pub bytes: u64,
    /// Commands written to the device.
    pub commands: u64,
}

/// Serves `port` on `key` until `stop` is set or the port fails; returns what it did.
/// Reads that time out (a serial port opened with a read timeout) are not failures.
pub fn serve<P: Read + Write + Send>(
    session: &Session,
    key: &str,
    port: &mut P,
    stop: &AtomicBool,
) -> Result<RelayStats, NetError> {
    let mut port = Some(port);
    serve_opened(session, key, &mut || Ok(port.take()), false, stop)
}

/// Opens the port with `open` once the simulation host first writes to the device (its
/// driver configuring it), then serves it as [`serve`] does: for a device whose
/// connection has a state the simulation host's driver must see from its start (a VRPN
/// server describes its senders once per connection). `open` gives `None` when asked to
/// stop.
pub fn serve_on_demand<P: Read + Write + Send>(
    session: &Session,
    key: &str,
    open: &mut dyn FnMut() -> Result<Option<P>, NetError>,
    stop: &AtomicBool,
) -> Result<RelayStats, NetError> {
    serve_opened(session, key, open, true, stop)
}

/// The relay loop, the port opened by `open` at once or at the first command.
fn serve_opened<Q: Read + Write>(
    session: &Session,
    key: &str,
    open: &mut dyn FnMut() -> Result<Option<Q>, NetError>,
    on_demand: bool,
    stop: &AtomicBool,
) -> Result<RelayStats, NetError> {
    let declare_err = |what: &'static str, key: String| {
        move |e: zenoh::Error| NetError::Declare {
            what,
            key,
            message: e.to_string(),
        }
    };
    let publisher = session
        .declare_publisher(rx_key(key))
        .congestion_control(CongestionControl::Drop)
        .wait()
        .map_err(declare_err("publisher", rx_key(key)))?;
    let (tx, commands) = unbounded::<Vec<u8>>();
    let _commands = session
        .declare_subscriber(tx_key(key))
        .callback(move |s| {
            let _ = tx.send(s.payload().to_bytes().into_owned());
        })
        .wait()
        .map_err(declare_err("subscriber", tx_key(key)))?;
    let mut stats = RelayStats::default();
    // Room for any UDP datagram (a VMC sender's bundle is a few kilobytes): one read,
    // one chunk, read whole on the simulation host.
    let mut buf = vec![0u8; 65_536];
    let io_err = |e: std::io::Error| NetError::Open(format!("the device on {key}: {e}"));
    if on_demand {
        while commands.is_empty() {
            if stop.load(Ordering::Acquire) {
                return Ok(stats);
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
    let Some(mut port) = open()? else {
        return Ok(stats);
    };
    while !stop.load(Ordering::Acquire) {
        for command in commands.try_iter() {
            port.write_all(&command)
                .and_then(|_| port.flush())
                .map_err(io_err)?;
            stats.commands += 1;
        }
        match port.read(&mut buf) {
            Ok(0) => return Err(NetError::Open(format!("the device on {key} closed"))),
            Ok(n) => {
                let chunk = encode_chunk(now_micros(), &buf[..n]);
                if publisher.put(chunk).wait().is_ok() {
                    stats.chunks += 1;
                    stats.bytes += n as u64;
                }
            }
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => {}
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(io_err(e)),
        }
    }
    Ok(stats)
}

/// A device served by a relay, read and written as a port (`Read + Write`).
pub struct ZenohPort {
    session: Session,
    key: String,
    _subscriber: Subscriber<()>,
    chunks: Receiver<Vec<u8>>,
    /// Bytes of the last chunk not yet read.
    pending: Vec<u8>,
    /// Source time of the newest chunk read (microseconds since the Unix epoch).
    last_source: Arc<AtomicU64>,
    /// Where to note each chunk's delay from its source time to its read, in
    /// microseconds (meaningful when both clocks agree: one machine, or NTP/PTP).
    delays: Option<Arc<Mutex<Vec<u64>>>>,
}

impl ZenohPort {
    /// Subscribes to the relay on `key`. Nothing needs to be there yet: bytes arrive once
    /// a relay serves the key.
    pub fn open(session: &Session, key: &str) -> Result<ZenohPort, NetError> {
        let (tx, chunks) = unbounded();
        let subscriber = session
            .declare_subscriber(rx_key(key))
            .callback(move |s| {
                let _ = tx.send(s.payload().to_bytes().into_owned());
            })
            .wait()
            .map_err(|e| NetError::Declare {
                what: "subscriber",
                key: rx_key(key),
                message: e.to_string(),
            })?;
        Ok(ZenohPort {
            session: session.clone(),
            key: key.to_string(),
            _subscriber: subscriber,
            chunks,
            pending: Vec::new(),
            last_source: Arc::new(AtomicU64::new(0)),
            delays: None,
        })
    }

    /// Notes each chunk's delay from its source time to its read into `delays`
    /// (microseconds).
    pub fn measure_delays(mut self, delays: Arc<Mutex<Vec<u64>>>) -> ZenohPort {
        self.delays = Some(delays);
        self
    }

    /// The source time of the newest chunk read, shared (for latency measurements).
    pub fn last_source_time(&self) -> Arc<AtomicU64> {
        self.last_source.clone()
    }
}

impl Read for ZenohPort {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        while self.pending.is_empty() {
            let chunk = self
                .chunks
                .recv_timeout(READ_TIMEOUT)
                .map_err(|_| std::io::Error::new(ErrorKind::TimedOut, "no bytes from the relay"))?;
            match decode_chunk(&chunk) {
                Some((source, bytes)) => {
                    self.last_source.store(source, Ordering::Relaxed);
                    if let Some(d) = &self.delays {
                        if let Ok(mut d) = d.lock() {
                            d.push(now_micros().saturating_sub(source));
                        }
                    }
                    self.pending = bytes.to_vec();
                }
                None => tracing::debug!("relay {}: a chunk of {} bytes", self.key, chunk.len()),
            }
        }
        let n = buf.len().min(self.pending.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }
}

impl Write for ZenohPort {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.session
            .put(tx_key(&self.key), buf.to_vec())
            .wait()
            .map_err(|e| std::io::Error::other(format!("relay {}: {e}", self.key)))?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chunk_carries_its_source_time() {
        let c = encode_chunk(1_700_000_000_000_123, b"\x01\x02");
        assert_eq!(
            decode_chunk(&c),
            Some((1_700_000_000_000_123, &b"\x01\x02"[..]))
        );
        assert_eq!(decode_chunk(&c[..7]), None);
        assert_eq!(
            decode_chunk(&c[..8]),
            Some((1_700_000_000_000_123, &b""[..]))
        );
    }
}
