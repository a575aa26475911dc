//! The SpaceMouse as a device-thread protocol: one HID report per read, decoded into the
//! device's accumulated state.

use crate::device::error::DeviceError;
use crate::device::port::Port;
use crate::device::protocol::Protocol;
use crate::device::reading::Reading;
use crate::spacemouse::decoder::{apply_report, kind_of_report, SpaceMouseState};

/// The SpaceMouse as a driver protocol: each read is one HID report; every report that
/// decodes yields the accumulated state. Nothing is sent to the device.
#[derive(Default)]
pub struct SpaceMouseProtocol {
    state: SpaceMouseState,
    /// Reports that did not decode (too short, unknown ID), counted as resyncs.
    bad_reports: u64,
    /// Bytes of those reports.
    bad_bytes: u64,
}

impl Protocol for SpaceMouseProtocol {
    fn kind(&self) -> &'static str {
        "spacemouse"
    }

    fn settings(&self) -> serde_json::Value {
        // The layout is told by each report's length (see `kind_of_report`).
        serde_json::json!({})
    }

    fn configure(&mut self, _port: &mut dyn Port) -> Result<(), DeviceError> {
        // A fresh connection starts at rest: a cap let go while unplugged must not keep
        // moving the object with the last axes seen.
        self.state = SpaceMouseState::default();
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        match apply_report(&mut self.state, kind_of_report(bytes), bytes) {
            Ok(()) => out(Reading::SpaceMouse(self.state)),
            Err(e) => {
                tracing::debug!("spacemouse: {e}");
                self.bad_reports += 1;
                self.bad_bytes += bytes.len() as u64;
            }
        }
    }

    fn counters(&self) -> (u64, u64) {
        (self.bad_reports, self.bad_bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn protocol_tells_layout_by_length_and_counts_bad_reports() {
        let mut p = SpaceMouseProtocol::default();
        let mut got = Vec::new();
        // Wired translation, then a Pro Wireless 13-byte report, then garbage.
        p.decode(&[1, 10, 0, 0, 0, 0, 0], &mut |r| got.push(r));
        p.decode(&[1, 1, 0, 2, 0, 3, 0, 4, 0, 5, 0, 6, 0], &mut |r| {
            got.push(r)
        });
        p.decode(&[7, 1, 2], &mut |r| got.push(r));
        assert_eq!(got.len(), 2);
        let Reading::SpaceMouse(s) = &got[1] else {
            panic!("expected a SpaceMouse reading, got {:?}", got[1]);
        };
        assert_eq!(s.translation, [1, 2, 3]);
        assert_eq!(s.rotation, [4, 5, 6]);
        assert_eq!(p.counters(), (1, 3));
    }
}
