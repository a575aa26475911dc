//! VRPN as a device protocol: after each connection it describes troupe's own senders and
//! its ping type, pings the device every second as VRPN's own clients do (the server
//! answers with a pong), and drops a connection on which nothing at all has arrived for
//! [`SILENCE_LIMIT`]; it decodes the stream of whole messages the connection reads — live,
//! or from a `.rec` recording of that stream.

use crate::device::error::DeviceError;
use crate::device::port::{write_all, Port};
use crate::device::protocol::Protocol;
use crate::device::reading::Reading;
use crate::vrpn::connection::{now as now_timestamp, DatagramCounters};
use crate::vrpn::decoder::{types, Decoder};
use crate::vrpn::name::DeviceName;
use crate::vrpn::wire::{encode, name_payload, system, Framer};
use serde::{Deserialize, Serialize};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often troupe pings the device.
pub const PING_PERIOD: Duration = Duration::from_secs(1);
/// A connection on which nothing (no report, no pong) arrived for this long is dropped and
/// made again: the server is stalled, or its host is gone without closing the connection.
pub const SILENCE_LIMIT: Duration = Duration::from_secs(3);

/// What a VRPN stream needs to be decoded again: the device and the other senders read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VrpnConfig {
    /// The device name as given (`Tracker0@host`).
    pub device: String,
    /// Every sender whose reports are decoded: the device, and any button or analog
    /// device read over the same connection.
    pub senders: Vec<String>,
}

impl VrpnConfig {
    /// Reads the tracker `name` and, on the same server, the `extra` senders (button or
    /// analog devices served under other names).
    pub fn new(name: &DeviceName, extra: &[String]) -> VrpnConfig {
        let mut senders = vec![name.device.clone()];
        for s in extra {
            if !senders.contains(s) {
                senders.push(s.clone());
            }
        }
        VrpnConfig {
            device: name.to_string(),
            senders,
        }
    }
}

/// The VRPN protocol over a [`VrpnPort`](crate::vrpn::VrpnPort) (or a recording of one).
pub struct VrpnProtocol {
    config: VrpnConfig,
    decoder: Decoder,
    framer: Framer,
    datagrams: Arc<DatagramCounters>,
    /// Streams that could not be framed (a recording whose lengths lie).
    framing_errors: u64,
    framing_bytes: u64,
    /// When the last ping went out and the last message came in (live connections only).
    last_ping: Option<Instant>,
    last_heard: Option<Instant>,
}

/// troupe's type id for pings, in its own descriptions.
const PING_TYPE: i32 = 0;

impl VrpnProtocol {
    /// A protocol for `config`; `datagrams` are the counters its connections share.
    pub fn new(config: VrpnConfig, datagrams: Arc<DatagramCounters>) -> VrpnProtocol {
        VrpnProtocol {
            decoder: Decoder::new(config.senders.clone()),
            config,
            framer: Framer::default(),
            datagrams,
            framing_errors: 0,
            framing_bytes: 0,
            last_ping: None,
            last_heard: None,
        }
    }
}

impl Protocol for VrpnProtocol {
    fn kind(&self) -> &'static str {
        "vrpn"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.config).unwrap_or_default()
    }

    fn configure(&mut self, port: &mut dyn Port) -> Result<(), DeviceError> {
        // Ids are per connection; counters are per connection (the thread sums them).
        self.decoder = Decoder::new(self.config.senders.clone());
        self.framer.clear();
        self.framing_errors = 0;
        self.framing_bytes = 0;
        self.datagrams.dropped.store(0, Ordering::Relaxed);
        self.datagrams.dropped_bytes.store(0, Ordering::Relaxed);
        let (sec, usec) = now_timestamp();
        let mut out = Vec::new();
        for (id, s) in self.config.senders.iter().enumerate() {
            out.extend(encode(
                sec,
                usec,
                id as i32,
                system::SENDER_DESCRIPTION,
                &name_payload(s),
            ));
        }
        out.extend(encode(
            sec,
            usec,
            PING_TYPE,
            system::TYPE_DESCRIPTION,
            &name_payload(types::PING),
        ));
        self.last_ping = None;
        self.last_heard = Some(Instant::now());
        write_all(port, &out)
    }

    fn before_read(&mut self, port: &mut dyn Port) -> std::io::Result<()> {
        let now = Instant::now();
        if self.last_heard.is_some_and(|t| now - t > SILENCE_LIMIT) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                format!(
                    "nothing from the server for {} s (not even a pong)",
                    SILENCE_LIMIT.as_secs()
                ),
            ));
        }
        if self.last_ping.is_none_or(|t| now - t >= PING_PERIOD) {
            // Sender 0 is the device (VrpnConfig::new puts it first): its server object
            // answers.
            let (sec, usec) = now_timestamp();
            port.write_all(&encode(sec, usec, 0, PING_TYPE, &[]))?;
            self.last_ping = Some(now);
        }
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        self.framer.push(bytes);
        if self.last_heard.is_some() && !bytes.is_empty() {
            self.last_heard = Some(Instant::now());
        }
        loop {
            match self.framer.next_message() {
                Ok(Some(m)) => self.decoder.decode(&m, &mut |r| out(Reading::Vrpn(r))),
                Ok(None) => break,
                Err(e) => {
                    // Only a recording can get here (a live port frames before): what
                    // follows cannot be framed, so it is dropped.
                    tracing::debug!("VRPN stream dropped: {e}");
                    self.framing_errors += 1;
                    self.framing_bytes += self.framer.pending() as u64;
                    self.framer.clear();
                    break;
                }
            }
        }
    }

    /// (messages that could not be used: malformed, undescribed, bad datagrams, framing
    /// losses; their bytes).
    fn counters(&self) -> (u64, u64) {
        let c = self.decoder.counters();
        (
            c.malformed
                + c.undescribed
                + self.framing_errors
                + self.datagrams.dropped.load(Ordering::Relaxed),
            c.malformed_bytes
                + self.framing_bytes
                + self.datagrams.dropped_bytes.load(Ordering::Relaxed),
        )
    }
}
