//! The CyberGlove protocol as the device thread runs it: check the glove with `?G` and `?S`,
//! choose the status byte, poll (`G`) or stream (`S`), decode records.
//!
//! Commands and replies follow `shared/reference/devices.md`, section "CyberGlove".

use crate::cyberglove::decoder::{self, GloveDecoder, GloveLayout};
use crate::cyberglove::query::{parse_query_reply, Query};
use crate::device::error::DeviceError;
use crate::device::port::{drain, write_all, Port};
use crate::device::protocol::{Mode, Protocol};
use crate::device::reading::Reading;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// CyberGlove configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GloveConfig {
    /// Record layout; `sensors` is checked against the glove's answer to `?S`.
    pub layout: GloveLayout,
    /// `G` poll or `S` stream.
    pub mode: Mode,
}

/// The CyberGlove protocol.
pub struct GloveProtocol {
    config: GloveConfig,
    decoder: GloveDecoder,
    /// Whether the driver must send a `G` (POINT mode: one outstanding poll at a time).
    poll_due: bool,
    last_poll: Instant,
}

impl GloveProtocol {
    /// A protocol for the given configuration.
    pub fn new(config: GloveConfig) -> GloveProtocol {
        GloveProtocol {
            decoder: GloveDecoder::new(config.layout),
            config,
            poll_due: true,
            last_poll: Instant::now(),
        }
    }
}

/// Sends a query and reads its reply.
pub fn glove_query(port: &mut dyn Port, q: Query) -> Result<Vec<u8>, DeviceError> {
    write_all(port, &q.command())?;
    let start = Instant::now();
    let mut buf = Vec::new();
    let mut chunk = [0u8; 64];
    loop {
        match parse_query_reply(q, &buf) {
            Ok(Some((reply, _))) => return Ok(reply.payload),
            Ok(None) => {}
            Err(source) => {
                return Err(DeviceError::Query {
                    letter: q.letter() as char,
                    source,
                })
            }
        }
        if start.elapsed() > Duration::from_millis(500) {
            return Err(DeviceError::QueryTimeout {
                letter: q.letter() as char,
                got: buf,
            });
        }
        match port.read(&mut chunk) {
            Ok(0) => return Err(DeviceError::Closed),
            Ok(k) => buf.extend_from_slice(&chunk[..k]),
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(DeviceError::Read(e)),
        }
    }
}

impl Protocol for GloveProtocol {
    fn kind(&self) -> &'static str {
        "cyberglove"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.config).unwrap_or(serde_json::Value::Null)
    }

    fn configure(&mut self, port: &mut dyn Port) -> Result<(), DeviceError> {
        // Stop a stream left running by an earlier session, then ask what is there.
        write_all(port, &[decoder::CMD_STOP])?;
        drain(port, Duration::from_millis(60));
        let status = glove_query(port, Query::Status)?;
        // `?G` status: bit0 initialized, bit1 glove plugged in.
        if status.first().is_none_or(|s| s & 0x02 == 0) {
            return Err(DeviceError::GloveNotPlugged(status));
        }
        let sensors = glove_query(port, Query::SensorsSampled)?;
        let n = usize::from(sensors.first().copied().unwrap_or(0));
        if n != self.config.layout.sensors {
            return Err(DeviceError::SensorCount {
                sampled: n,
                configured: self.config.layout.sensors,
            });
        }
        // `u 1` / `u 0`: status byte appended or not (ASCII command, CR-terminated).
        let u: &[u8] = if self.config.layout.status_byte {
            b"u 1\r"
        } else {
            b"u 0\r"
        };
        write_all(port, u)?;
        drain(port, Duration::from_millis(30));
        self.decoder = GloveDecoder::new(self.config.layout);
        self.poll_due = true;
        if self.config.mode == Mode::Stream {
            write_all(port, &[decoder::CMD_STREAM])?;
        }
        Ok(())
    }

    fn before_read(&mut self, port: &mut dyn Port) -> std::io::Result<()> {
        // A lost reply must not stall polling forever: re-poll after 100 ms.
        if self.config.mode == Mode::Point
            && (self.poll_due || self.last_poll.elapsed() > Duration::from_millis(100))
        {
            port.write_all(&[decoder::CMD_POLL])?;
            self.poll_due = false;
            self.last_poll = Instant::now();
        }
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        let mut got = false;
        self.decoder.feed(bytes, |r| {
            got = true;
            out(Reading::Glove(r))
        });
        if got {
            self.poll_due = true;
        }
    }

    fn counters(&self) -> (u64, u64) {
        let s = self.decoder.stats();
        (s.resyncs, s.dropped_bytes)
    }

    fn stop(&mut self, port: &mut dyn Port) {
        let _ = write_all(port, &[decoder::CMD_STOP]);
    }
}
