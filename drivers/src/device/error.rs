//! What can go wrong opening, configuring or reading a device.
//!
//! The messages are the ones `troupe devices probe` prints and a device's health reports as
//! its last error; tests and `docs/devices.md` quote some of them, so keep their wording.

use crate::cyberglove::query::ReplyError;
use std::io;

/// A device could not be found, opened, configured or read.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// The serial port would not open.
    #[error("opening serial port {path}: {source}")]
    OpenSerial {
        /// The port's path.
        path: String,
        /// Why it would not open.
        #[source]
        source: serialport::Error,
    },
    /// The serial ports could not be listed.
    #[error("listing serial ports: {0}")]
    ListSerial(#[source] serialport::Error),
    /// HID access is unavailable.
    #[error("HID: {0}")]
    Hid(#[from] hidapi::HidError),
    /// A HID device was found but would not open.
    #[error("opening {path}: {source}")]
    OpenHid {
        /// The hidraw path.
        path: String,
        /// Why it would not open.
        #[source]
        source: hidapi::HidError,
    },
    /// Reading a HID device failed.
    #[error("reading {device}: {source}")]
    ReadHid {
        /// The device's model name.
        device: String,
        /// What hidapi said.
        #[source]
        source: hidapi::HidError,
    },
    /// No HID device has the given path.
    #[error("no HID device at {0} (see `troupe devices`)")]
    NoHidDevice(String),
    /// No SpaceMouse is plugged in.
    #[error("no SpaceMouse found (vendors 046d/256f; see `troupe devices`)")]
    NoSpaceMouse,
    /// A device served by a relay (`zenoh = KEY`) could not be reached.
    #[error("relayed device {key}: {message}")]
    Remote {
        /// The key the relay serves.
        key: String,
        /// Why.
        message: String,
    },
    /// A command could not be written.
    #[error("writing {bytes:02x?}: {source}")]
    Write {
        /// The command.
        bytes: Vec<u8>,
        /// What the port said.
        #[source]
        source: io::Error,
    },
    /// Reading the port failed.
    #[error("{0}")]
    Read(#[source] io::Error),
    /// The port closed (the device was unplugged).
    #[error("port closed")]
    Closed,
    /// A reply of a known length did not arrive in time.
    #[error("timed out after {got} of {wanted} reply bytes")]
    Timeout {
        /// Bytes that arrived.
        got: usize,
        /// Bytes the reply has.
        wanted: usize,
    },
    /// The Flock did not answer its status request (EXAMINE VALUE 0x24).
    #[error("flock status (EXAMINE VALUE 0x24): {0}")]
    FlockStatus(#[source] Box<DeviceError>),
    /// A bird of the flock cannot be used.
    #[error("bird {bird} reports status 0x{status:02x}: not accessible or no receiver")]
    BirdUnavailable {
        /// The bird's FBB address, from 1.
        bird: u8,
        /// Its status byte.
        status: u8,
    },
    /// The glove's reply to a query is an error or cannot be read.
    #[error("query ?{letter}: {source}")]
    Query {
        /// The query's letter.
        letter: char,
        /// What was wrong with the reply.
        #[source]
        source: ReplyError,
    },
    /// The glove did not answer a query in time.
    #[error("query ?{letter}: no complete reply within 500 ms (got {got:02x?})")]
    QueryTimeout {
        /// The query's letter.
        letter: char,
        /// The bytes that did arrive.
        got: Vec<u8>,
    },
    /// The glove's interface unit reports no glove.
    #[error("glove not plugged into its interface unit (status {0:02x?})")]
    GloveNotPlugged(Vec<u8>),
    /// The glove samples another number of sensors than configured.
    #[error("the glove samples {sampled} sensors, configured for {configured}")]
    SensorCount {
        /// Sensors the glove reports (`?S`).
        sampled: usize,
        /// Sensors of the configured layout.
        configured: usize,
    },
    /// A VRPN server could not be reached or answered wrongly.
    #[error(transparent)]
    Vrpn(crate::vrpn::error::VrpnError),
}
