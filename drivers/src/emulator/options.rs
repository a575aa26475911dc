//! What an emulator emulates: flock size, range, glove sensors, rate and motion.

use crate::emulator::motion::Motion;
use crate::fob::commands::PositionRange;

/// Emulator settings.
pub struct EmulatorOptions {
    /// Birds in the flock (FoB), ignored by the glove.
    pub birds: u8,
    /// Position range the emulated transmitter has.
    pub range: PositionRange,
    /// Glove sensors (18 or 22).
    pub sensors: usize,
    /// Measurement rate in Hz (FoB ~100 Hz; glove stream rate).
    pub rate_hz: f64,
    /// Motion source.
    pub motion: Motion,
}

impl EmulatorOptions {
    /// Six birds, 36-inch range, an 18-sensor glove, 100 Hz, synthetic motion.
    pub fn new() -> EmulatorOptions {
        EmulatorOptions {
            birds: 6,
            range: PositionRange::Inches36,
            sensors: 18,
            rate_hz: 100.0,
            motion: Motion::Synthetic,
        }
    }
}

impl Default for EmulatorOptions {
    fn default() -> Self {
        EmulatorOptions::new()
    }
}
