//! A VMC stream in a `.rec` file, and the clock its jitter buffer plays by.
//!
//! Each data chunk is one datagram, its `micros` the receiver clock when it arrived (the
//! recording's clock: microseconds since the recording started). A live performer reads
//! that clock in whole microseconds, for arrivals and for the moment each tick plays its
//! buffer (a clock mark), so a replay hands the jitter buffer the very same numbers.

use crate::device::error::DeviceError;
use crate::device::port::Port;
use crate::device::protocol::Protocol;
use crate::device::reading::Reading;
use std::time::Instant;

/// The kind of a VMC stream in a `.rec` file; each data chunk is one datagram.
pub const REC_KIND: &str = "vmc";

/// Seconds on the receiver clock, from its microseconds: the one conversion live and
/// replayed streams share, so both give the jitter buffer bit-identical times.
pub fn clock_seconds(micros: u64) -> f64 {
    micros as f64 * 1e-6
}

/// Whole microseconds from `origin` to `at` (0 for an instant before the origin).
pub fn micros_since(origin: Instant, at: Instant) -> u64 {
    at.saturating_duration_since(origin).as_micros() as u64
}

/// A recorded VMC stream read back: every chunk is one datagram reading (decoded into a
/// pose in the tick that takes it, as a live datagram is). Never opens a device.
#[derive(Default)]
pub struct VmcDatagrams;

impl Protocol for VmcDatagrams {
    fn kind(&self) -> &'static str {
        REC_KIND
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::json!({})
    }

    fn configure(&mut self, _port: &mut dyn Port) -> Result<(), DeviceError> {
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        out(Reading::Datagram {
            bytes: bytes.to_vec(),
        })
    }

    fn counters(&self) -> (u64, u64) {
        (0, 0)
    }
}
