//! What a device thread sends: decoded readings with their sequence number and time.

use crate::cyberglove::decoder::GloveRecord;
use crate::fob::decoder::BirdRecord;
use crate::spacemouse::decoder::SpaceMouseState;
use crate::vrpn::decoder::VrpnReading;
use serde::Serialize;
use std::time::Instant;

/// What a device produced.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Reading {
    /// One Flock of Birds record (one bird).
    Bird(BirdRecord),
    /// One CyberGlove record.
    Glove(GloveRecord),
    /// The state of a SpaceMouse after one HID report.
    #[serde(rename = "spacemouse")]
    SpaceMouse(SpaceMouseState),
    /// A report of a device on a VRPN server.
    Vrpn(VrpnReading),
    /// A whole datagram, read in the tick that takes it (a VMC sender's OSC packet).
    Datagram {
        /// The datagram's bytes.
        bytes: Vec<u8>,
    },
}

/// A timestamped reading.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Per-device sequence number, from 0.
    pub seq: u64,
    /// When the bytes that completed the sample were read.
    pub arrived: Instant,
    /// Seconds since the driver started (or, on replay, the recorded time).
    pub time: f64,
    /// The decoded reading.
    pub reading: Reading,
}
