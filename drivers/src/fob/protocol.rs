//! The Flock of Birds protocol as the device thread runs it: configure a standalone bird or
//! a flock in group mode, poll (POINT) or stream (STREAM), decode records.
//!
//! Command sequences follow `shared/reference/devices.md`, section "Ascension Flock of Birds
//! (RS-232)".

use crate::device::error::DeviceError;
use crate::device::port::{drain, read_exact_timeout, write_all, Port};
use crate::device::protocol::{Mode, Protocol};
use crate::device::reading::Reading;
use crate::fob::commands;
use crate::fob::decoder::{RecordDecoder, RecordLayout};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Flock of Birds configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FobConfig {
    /// Number of birds (1 = standalone; more = group mode over the FBB).
    pub birds: u8,
    /// Record layout (format, button, range; `group` is set from `birds`).
    pub layout: RecordLayout,
    /// Hemisphere.
    pub hemisphere: commands::Hemisphere,
    /// Report rate.
    pub rate: commands::ReportRate,
    /// POINT or STREAM.
    pub mode: Mode,
}

impl FobConfig {
    /// A flock of `birds` in the given format, forward hemisphere, every cycle, streaming.
    pub fn new(birds: u8, format: commands::OutputFormat) -> FobConfig {
        let mut layout = RecordLayout::single(format);
        layout.group = birds > 1;
        FobConfig {
            birds,
            layout,
            hemisphere: commands::Hemisphere::Forward,
            rate: commands::ReportRate::Every,
            mode: Mode::Stream,
        }
    }
}

/// The Flock of Birds protocol.
pub struct FobProtocol {
    config: FobConfig,
    decoder: RecordDecoder,
    /// POINT mode: whether the next request may be sent (the last one was answered).
    poll_due: bool,
    /// POINT mode: when the last request was sent.
    last_poll: Instant,
    /// POINT mode: records still expected for the last request (one per bird).
    awaited: usize,
}

impl FobProtocol {
    /// A protocol for the given configuration.
    pub fn new(config: FobConfig) -> FobProtocol {
        let decoder = RecordDecoder::new(config.layout, 1);
        FobProtocol {
            config,
            decoder,
            poll_due: true,
            last_poll: Instant::now(),
            awaited: 0,
        }
    }
}

impl Protocol for FobProtocol {
    fn kind(&self) -> &'static str {
        "fob"
    }

    fn settings(&self) -> serde_json::Value {
        serde_json::to_value(&self.config).unwrap_or(serde_json::Value::Null)
    }

    fn configure(&mut self, port: &mut dyn Port) -> Result<(), DeviceError> {
        let c = &self.config;
        // Stop an earlier stream (POINT ends STREAM mode) and throw away what is in flight.
        write_all(port, &[commands::CMD_SLEEP])?;
        write_all(port, &[commands::CMD_RUN])?;
        drain(port, Duration::from_millis(60));
        if c.birds > 1 {
            // FBB AUTO-CONFIG with the number of units, then check every unit answers with a
            // receiver (reference: EXAMINE VALUE 0x24 returns per-unit status, 0x80
            // accessible, 0x40 running, 0x20 has a receiver).
            write_all(port, &commands::auto_config_command(c.birds))?;
            write_all(port, &[commands::CMD_EXAMINE, commands::PARAM_FBB_STATUS])?;
            let status = read_exact_timeout(port, usize::from(c.birds), Duration::from_millis(500))
                .map_err(|e| DeviceError::FlockStatus(Box::new(e)))?;
            for (i, s) in status.iter().enumerate() {
                if s & commands::STATUS_ACCESSIBLE == 0 || s & commands::STATUS_RECEIVER == 0 {
                    return Err(DeviceError::BirdUnavailable {
                        bird: i as u8 + 1,
                        status: *s,
                    });
                }
            }
            // Format and hemisphere go to each bird through the RS232-TO-FBB prefix.
            for addr in 1..=c.birds {
                write_all(
                    port,
                    &[commands::CMD_TO_FBB + addr, c.layout.format.command()],
                )?;
                let h = c.hemisphere.data();
                write_all(
                    port,
                    &[
                        commands::CMD_TO_FBB + addr,
                        commands::CMD_HEMISPHERE,
                        h[0],
                        h[1],
                    ],
                )?;
            }
            write_all(port, &commands::group_mode_command(true))?;
        } else {
            // A flock left in group mode by an earlier session would label every bird's
            // records as this one's.
            write_all(port, &commands::group_mode_command(false))?;
            write_all(port, &[c.layout.format.command()])?;
            let h = c.hemisphere.data();
            write_all(port, &[commands::CMD_HEMISPHERE, h[0], h[1]])?;
        }
        write_all(port, &[c.rate.command()])?;
        if c.mode == Mode::Stream {
            write_all(port, &[commands::CMD_STREAM])?;
        }
        // A fresh decoder per connection: the thread adds its counters to the earlier totals.
        self.decoder = RecordDecoder::new(c.layout, 1);
        self.poll_due = true;
        Ok(())
    }

    fn before_read(&mut self, port: &mut dyn Port) -> std::io::Result<()> {
        // One POINT request per answered report (a record from every bird in group mode):
        // a request on every read would pile replies up in the port. A lost reply must
        // not stall polling forever: re-poll after 100 ms.
        if self.config.mode == Mode::Point
            && (self.poll_due || self.last_poll.elapsed() > Duration::from_millis(100))
        {
            port.write_all(&[commands::CMD_POINT])?;
            self.poll_due = false;
            self.awaited = usize::from(self.config.birds.max(1));
            self.last_poll = Instant::now();
        }
        Ok(())
    }

    fn decode(&mut self, bytes: &[u8], out: &mut dyn FnMut(Reading)) {
        let mut records = 0;
        self.decoder.feed(bytes, |r| {
            records += 1;
            out(Reading::Bird(r))
        });
        if records > 0 {
            self.awaited = self.awaited.saturating_sub(records);
            if self.awaited == 0 {
                self.poll_due = true;
            }
        }
    }

    fn counters(&self) -> (u64, u64) {
        let s = self.decoder.stats();
        (s.resyncs, s.dropped_bytes)
    }

    fn stop(&mut self, port: &mut dyn Port) {
        let _ = write_all(port, &[commands::CMD_POINT]);
    }
}
