//! Ascension Flock of Birds: the command bytes, the settings they carry (output format,
//! hemisphere, report rate, position range) and the FBB commands of group mode.
//!
//! Every protocol fact here comes from `shared/reference/devices.md`, section "Ascension
//! Flock of Birds (RS-232)"; the comments quote the fact they rely on.

use serde::{Deserialize, Serialize};

/// A setting's name given on the command line or in a script that the Flock does not have.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {setting} '{given}' (expected {expected})")]
pub struct UnknownSetting {
    /// Which setting (`Flock of Birds output format`, `hemisphere`, …).
    pub setting: &'static str,
    /// What was given.
    pub given: String,
    /// The names accepted.
    pub expected: String,
}

/// POINT: the device answers one record (reference: "POINT `B` (one record)").
pub const CMD_POINT: u8 = b'B';
/// STREAM: records follow continuously at the report rate (reference: "STREAM `@`").
pub const CMD_STREAM: u8 = b'@';
/// RUN: wakes the flock from SLEEP.
pub const CMD_RUN: u8 = b'F';
/// SLEEP: stops the transmitter; the driver sends it (or POINT) to end streaming.
pub const CMD_SLEEP: u8 = b'G';
/// EXAMINE VALUE, followed by a parameter number.
pub const CMD_EXAMINE: u8 = b'O';
/// CHANGE VALUE, followed by a parameter number and its data.
pub const CMD_CHANGE: u8 = b'P';
/// HEMISPHERE, followed by two data bytes.
pub const CMD_HEMISPHERE: u8 = b'L';
/// FBB RESET.
pub const CMD_FBB_RESET: u8 = b'/';
/// RS232-TO-FBB prefix: `0xF0 + address` sends the next command to one bird.
pub const CMD_TO_FBB: u8 = 0xF0;
/// CHANGE VALUE parameter 0x23: group mode on (1) or off (0).
pub const PARAM_GROUP_MODE: u8 = 0x23;
/// CHANGE VALUE parameter 0x32: FBB AUTO-CONFIG with the number of units.
pub const PARAM_AUTO_CONFIG: u8 = 0x32;
/// EXAMINE VALUE parameter 0x24: per-unit status, one byte per unit.
pub const PARAM_FBB_STATUS: u8 = 0x24;
/// EXAMINE VALUE parameter 0x10: expanded error code.
pub const PARAM_ERROR_CODE: u8 = 0x10;
/// Unit status bit: the unit is accessible on the bus.
pub const STATUS_ACCESSIBLE: u8 = 0x80;
/// Unit status bit: the unit is running (not asleep).
pub const STATUS_RUNNING: u8 = 0x40;
/// Unit status bit: the unit has a receiver (a sensor).
pub const STATUS_RECEIVER: u8 = 0x20;

/// Output format of a bird's records.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputFormat {
    /// Position only (3 words).
    Position,
    /// Angles only (3 words).
    Angles,
    /// Rotation matrix only (9 words).
    Matrix,
    /// Quaternion only (4 words).
    Quaternion,
    /// Position then angles (6 words).
    PositionAngles,
    /// Position then matrix (12 words).
    PositionMatrix,
    /// Position then quaternion (7 words).
    PositionQuaternion,
}

impl OutputFormat {
    /// Every format, in the order of the command table.
    pub const ALL: [OutputFormat; 7] = [
        OutputFormat::Position,
        OutputFormat::Angles,
        OutputFormat::Matrix,
        OutputFormat::Quaternion,
        OutputFormat::PositionAngles,
        OutputFormat::PositionMatrix,
        OutputFormat::PositionQuaternion,
    ];

    /// The one-byte command that selects this format (reference: POSITION `V`, ANGLES `W`,
    /// MATRIX `X`, POSITION/ANGLES `Y`, POSITION/MATRIX `Z`, QUATERNION `\`,
    /// POSITION/QUATERNION `]`).
    pub fn command(self) -> u8 {
        match self {
            OutputFormat::Position => b'V',
            OutputFormat::Angles => b'W',
            OutputFormat::Matrix => b'X',
            OutputFormat::PositionAngles => b'Y',
            OutputFormat::PositionMatrix => b'Z',
            OutputFormat::Quaternion => b'\\',
            OutputFormat::PositionQuaternion => b']',
        }
    }

    /// The format a command byte selects, if it is a format command.
    pub fn from_command(byte: u8) -> Option<OutputFormat> {
        OutputFormat::ALL.into_iter().find(|f| f.command() == byte)
    }

    /// Record size in 16-bit words (reference: position 3, angles 3, matrix 9,
    /// quaternion 4, position/angles 6, position/matrix 12, position/quaternion 7).
    pub fn words(self) -> usize {
        match self {
            OutputFormat::Position | OutputFormat::Angles => 3,
            OutputFormat::Matrix => 9,
            OutputFormat::Quaternion => 4,
            OutputFormat::PositionAngles => 6,
            OutputFormat::PositionMatrix => 12,
            OutputFormat::PositionQuaternion => 7,
        }
    }

    /// The name used on the command line (`position-angles`, …).
    pub fn name(self) -> &'static str {
        match self {
            OutputFormat::Position => "position",
            OutputFormat::Angles => "angles",
            OutputFormat::Matrix => "matrix",
            OutputFormat::Quaternion => "quaternion",
            OutputFormat::PositionAngles => "position-angles",
            OutputFormat::PositionMatrix => "position-matrix",
            OutputFormat::PositionQuaternion => "position-quaternion",
        }
    }

    /// Parses a command-line name; the error lists the accepted names.
    pub fn parse(name: &str) -> Result<OutputFormat, UnknownSetting> {
        OutputFormat::ALL
            .into_iter()
            .find(|f| f.name() == name)
            .ok_or_else(|| {
                let names: Vec<_> = OutputFormat::ALL.iter().map(|f| f.name()).collect();
                UnknownSetting {
                    setting: "Flock of Birds output format",
                    given: name.to_string(),
                    expected: format!("one of: {}", names.join(", ")),
                }
            })
    }

    pub(crate) fn has_position(self) -> bool {
        matches!(
            self,
            OutputFormat::Position
                | OutputFormat::PositionAngles
                | OutputFormat::PositionMatrix
                | OutputFormat::PositionQuaternion
        )
    }
}

/// Transmitter hemisphere in which the receivers are assumed to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Hemisphere {
    /// In front of the transmitter (+X), the power-on default.
    Forward,
    /// Behind the transmitter.
    Aft,
    /// Above.
    Upper,
    /// Below.
    Lower,
    /// Left.
    Left,
    /// Right.
    Right,
}

impl Hemisphere {
    /// The two data bytes of the HEMISPHERE command (reference: forward 00 00, aft 00 01,
    /// upper 0C 01, lower 0C 00, left 06 01, right 06 00).
    pub fn data(self) -> [u8; 2] {
        match self {
            Hemisphere::Forward => [0x00, 0x00],
            Hemisphere::Aft => [0x00, 0x01],
            Hemisphere::Upper => [0x0C, 0x01],
            Hemisphere::Lower => [0x0C, 0x00],
            Hemisphere::Left => [0x06, 0x01],
            Hemisphere::Right => [0x06, 0x00],
        }
    }

    /// The hemisphere two HEMISPHERE data bytes select.
    pub fn from_data(data: [u8; 2]) -> Option<Hemisphere> {
        [
            Hemisphere::Forward,
            Hemisphere::Aft,
            Hemisphere::Upper,
            Hemisphere::Lower,
            Hemisphere::Left,
            Hemisphere::Right,
        ]
        .into_iter()
        .find(|h| h.data() == data)
    }

    /// Parses a command-line name (`forward`, `aft`, `upper`, `lower`, `left`, `right`).
    pub fn parse(name: &str) -> Result<Hemisphere, UnknownSetting> {
        match name {
            "forward" => Ok(Hemisphere::Forward),
            "aft" => Ok(Hemisphere::Aft),
            "upper" => Ok(Hemisphere::Upper),
            "lower" => Ok(Hemisphere::Lower),
            "left" => Ok(Hemisphere::Left),
            "right" => Ok(Hemisphere::Right),
            _ => Err(UnknownSetting {
                setting: "hemisphere",
                given: name.to_string(),
                expected: "forward, aft, upper, lower, left or right".into(),
            }),
        }
    }
}

/// Report rate divisor: a record every 1, 2, 8 or 32 measurement cycles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ReportRate {
    /// Every cycle (`Q`).
    Every,
    /// Every second cycle (`R`).
    Half,
    /// Every eighth cycle (`S`).
    Eighth,
    /// Every 32nd cycle (`T`).
    ThirtySecond,
}

impl ReportRate {
    /// The command byte (reference: report rate `Q`/`R`/`S`/`T` = every, ÷2, ÷8, ÷32).
    pub fn command(self) -> u8 {
        match self {
            ReportRate::Every => b'Q',
            ReportRate::Half => b'R',
            ReportRate::Eighth => b'S',
            ReportRate::ThirtySecond => b'T',
        }
    }

    /// The divisor of the measurement rate.
    pub fn divisor(self) -> u32 {
        match self {
            ReportRate::Every => 1,
            ReportRate::Half => 2,
            ReportRate::Eighth => 8,
            ReportRate::ThirtySecond => 32,
        }
    }

    /// The rate a command byte selects.
    pub fn from_command(byte: u8) -> Option<ReportRate> {
        match byte {
            b'Q' => Some(ReportRate::Every),
            b'R' => Some(ReportRate::Half),
            b'S' => Some(ReportRate::Eighth),
            b'T' => Some(ReportRate::ThirtySecond),
            _ => None,
        }
    }
}

/// Full-scale position range in inches: 36 by default, 72 with the position scaling
/// parameter set, 144 with the extended range transmitter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PositionRange {
    /// ±36 inches (914.4 mm), the default.
    Inches36,
    /// ±72 inches.
    Inches72,
    /// ±144 inches (extended range transmitter).
    Inches144,
}

impl PositionRange {
    /// The range in inches.
    pub fn inches(self) -> f64 {
        match self {
            PositionRange::Inches36 => 36.0,
            PositionRange::Inches72 => 72.0,
            PositionRange::Inches144 => 144.0,
        }
    }

    /// Parses 36, 72 or 144.
    pub fn parse(text: &str) -> Result<PositionRange, UnknownSetting> {
        match text.trim() {
            "36" => Ok(PositionRange::Inches36),
            "72" => Ok(PositionRange::Inches72),
            "144" => Ok(PositionRange::Inches144),
            other => Err(UnknownSetting {
                setting: "Flock of Birds position range",
                given: other.to_string(),
                expected: "36, 72 or 144 inches".into(),
            }),
        }
    }
}

/// CHANGE VALUE GROUP MODE (0x23): on, every bird's records end with its address byte.
pub fn group_mode_command(on: bool) -> [u8; 3] {
    [CMD_CHANGE, PARAM_GROUP_MODE, u8::from(on)]
}

/// FBB AUTO-CONFIG for `units` units.
pub fn auto_config_command(units: u8) -> [u8; 3] {
    [CMD_CHANGE, PARAM_AUTO_CONFIG, units]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_tables() {
        assert_eq!(OutputFormat::PositionAngles.command(), 0x59);
        assert_eq!(OutputFormat::PositionMatrix.command(), 0x5A);
        assert_eq!(OutputFormat::Quaternion.command(), 0x5C);
        assert_eq!(OutputFormat::PositionQuaternion.command(), 0x5D);
        assert_eq!(Hemisphere::Upper.data(), [0x0C, 0x01]);
        assert_eq!(Hemisphere::from_data([0x06, 0x00]), Some(Hemisphere::Right));
        assert!(OutputFormat::parse("position-euler")
            .unwrap_err()
            .to_string()
            .contains("position-angles"));
    }
}
