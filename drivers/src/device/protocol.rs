//! What a device thread asks of a device's protocol: configure after each connection,
//! poll if the device is polled, decode bytes into readings, stop before closing.

use crate::device::error::DeviceError;
use crate::device::port::Port;
use crate::device::reading::Reading;
use serde::{Deserialize, Serialize};

/// A device protocol: configures the device after each connection and decodes its bytes.
pub trait Protocol: Send {
    /// Short device kind (`fob`, `cyberglove`), used in recordings.
    fn kind(&self) -> &'static str;
    /// Settings needed to decode a recording of this device, as JSON.
    fn settings(&self) -> serde_json::Value;
    /// Sends the configuration and starts the data flow; fails with a message naming what
    /// the device answered wrongly.
    fn configure(&mut self, port: &mut dyn Port) -> Result<(), DeviceError>;
    /// Called before each read: a polled device sends its poll command here.
    fn before_read(&mut self, _port: &mut dyn Port) -> std::io::Result<()> {
        Ok(())
    }
    /// Decodes bytes into readings.
    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading));
    /// (resyncs, dropped bytes) so far.
    fn counters(&self) -> (u64, u64);
    /// Stops the data flow before the port closes.
    fn stop(&mut self, _port: &mut dyn Port) {}
}

/// POINT (one record per request) or STREAM (continuous).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// The driver asks for each record.
    Point,
    /// The device sends records continuously.
    Stream,
}
