//! A VRPN client, written from VRPN 07.38's `Format_Of_Protocol.txt` and sources: any
//! tracker, button or analog device a VRPN server serves (`Tracker0@tracking-pc`) becomes
//! a device of troupe, with the same thread, health, reconnection and `.rec` recording as
//! the serial devices.
//!
//! `name` parses device names, `wire` the cookie and message framing, `decoder` the
//! descriptions and report payloads, `connection` the TCP/UDP sockets, `protocol` the
//! device protocol the thread drives; `spawn` starts a client.

pub(crate) mod connection;
pub(crate) mod decoder;
pub(crate) mod error;
pub(crate) mod name;
pub(crate) mod protocol;
pub mod wire;

pub use connection::{DatagramCounters, VrpnPort};
pub use decoder::{types, DecodeCounters, Decoder, VrpnReading};
pub use error::VrpnError;
pub use name::{DeviceName, DEFAULT_PORT};
pub use protocol::{VrpnConfig, VrpnProtocol};

use crate::device::thread::{spawn_with, DeviceHandle, DriverOptions, Opener};
use crate::record::writer::Recorder;
use std::sync::Arc;
use std::time::Duration;

/// How long connecting and the cookie exchange may take before the attempt fails (and
/// the thread retries with backoff).
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(2);

/// The longest wait between connection attempts: a refused TCP connection costs nothing,
/// so a restarted server is found again within half a second.
pub const BACKOFF_MAX: Duration = Duration::from_millis(500);

/// A VRPN client's driver options: named `name` (logs and recordings), stale after 250 ms
/// without a report, retrying every 50 ms doubling up to [`BACKOFF_MAX`], never giving up.
pub fn driver_options(name: &str, device: &str) -> DriverOptions {
    DriverOptions {
        backoff_max: BACKOFF_MAX,
        ..DriverOptions::new(name, device)
    }
}

/// Starts a client thread for `config` (its device and other senders); `options` name it
/// and set staleness and backoff; `handshake` bounds each connection attempt.
pub fn spawn(
    config: VrpnConfig,
    options: DriverOptions,
    handshake: Duration,
    recorder: Option<Arc<Recorder>>,
) -> Result<DeviceHandle, VrpnError> {
    let name = DeviceName::parse(&config.device)?;
    let counters = Arc::new(DatagramCounters::default());
    let c = counters.clone();
    let opener: Opener = Box::new(move |_| {
        let port = VrpnPort::connect(&name, handshake, c.clone())?;
        Ok(Box::new(port) as Box<dyn crate::device::port::Port>)
    });
    Ok(spawn_with(
        options,
        Box::new(VrpnProtocol::new(config, counters)),
        recorder,
        opener,
    ))
}

/// Starts a client thread for `config` whose connection is opened by `opener` (a server
/// reached through `troupe relay vrpn`, whose relay made the TCP connection and cookie
/// exchange); `options` name it and set staleness and backoff.
pub fn spawn_through(
    config: VrpnConfig,
    options: DriverOptions,
    recorder: Option<Arc<Recorder>>,
    opener: Opener,
) -> DeviceHandle {
    let counters = Arc::new(DatagramCounters::default());
    spawn_with(
        options,
        Box::new(VrpnProtocol::new(config, counters)),
        recorder,
        opener,
    )
}
