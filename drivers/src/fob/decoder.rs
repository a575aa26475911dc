//! Ascension Flock of Birds: commands, configuration and record decoding.
//!
//! Every protocol fact here comes from `shared/reference/devices.md`, section "Ascension
//! Flock of Birds (RS-232)"; the comments quote the fact they rely on. The thesis uses the
//! Flock to drive a performer's body (sections 2.7 and 6.4.1).

use serde::{Deserialize, Serialize};

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
    pub fn parse(name: &str) -> Result<OutputFormat, String> {
        OutputFormat::ALL
            .into_iter()
            .find(|f| f.name() == name)
            .ok_or_else(|| {
                let names: Vec<_> = OutputFormat::ALL.iter().map(|f| f.name()).collect();
                format!(
                    "unknown Flock of Birds output format '{name}' (expected one of: {})",
                    names.join(", ")
                )
            })
    }

    fn has_position(self) -> bool {
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
    pub fn parse(name: &str) -> Result<Hemisphere, String> {
        match name {
            "forward" => Ok(Hemisphere::Forward),
            "aft" => Ok(Hemisphere::Aft),
            "upper" => Ok(Hemisphere::Upper),
            "lower" => Ok(Hemisphere::Lower),
            "left" => Ok(Hemisphere::Left),
            "right" => Ok(Hemisphere::Right),
            _ => Err(format!(
                "unknown hemisphere '{name}' (expected forward, aft, upper, lower, left or right)"
            )),
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
    pub fn parse(text: &str) -> Result<PositionRange, String> {
        match text.trim() {
            "36" => Ok(PositionRange::Inches36),
            "72" => Ok(PositionRange::Inches72),
            "144" => Ok(PositionRange::Inches144),
            other => Err(format!(
                "unknown Flock of Birds position range '{other}' (expected 36, 72 or 144 inches)"
            )),
        }
    }
}

/// How the records of a flock are laid out on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RecordLayout {
    /// Output format (the same for every bird).
    pub format: OutputFormat,
    /// Button mode: one button byte after the data words.
    pub button: bool,
    /// Group mode: one address byte at the end of each record.
    pub group: bool,
    /// Position range used to scale positions.
    pub range: PositionRange,
}

impl RecordLayout {
    /// A single bird in the given format, no button byte, 36-inch range.
    pub fn single(format: OutputFormat) -> RecordLayout {
        RecordLayout {
            format,
            button: false,
            group: false,
            range: PositionRange::Inches36,
        }
    }

    /// Bytes per record (reference: "Bytes = 2 × words, +1 if button mode is on, +1
    /// address byte at the end of each record in group mode").
    pub fn record_bytes(&self) -> usize {
        2 * self.format.words() + usize::from(self.button) + usize::from(self.group)
    }
}

/// One decoded bird record, in the device's own frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BirdRecord {
    /// FBB address of the bird (from the address byte in group mode; else the configured one).
    pub address: u8,
    /// Position in metres, when the format has one.
    pub position: Option<[f64; 3]>,
    /// Azimuth (Z), elevation (Y), roll (X) in degrees, when the format has angles.
    pub angles: Option<[f64; 3]>,
    /// Quaternion (w, x, y, z), when the format has one.
    pub quaternion: Option<[f64; 4]>,
    /// The nine matrix elements in the order they arrive, when the format has a matrix.
    pub matrix: Option<[f64; 9]>,
    /// Button byte, in button mode.
    pub button: Option<u8>,
}

/// Metres per inch.
pub const METRES_PER_INCH: f64 = 0.0254;

/// Decodes one data word from its two bytes.
///
/// Reference: "Each word arrives LSB byte first, and the 7 data bits of each byte are
/// packed: `w = (int16)(((b0 & 0x7F) << 1 | b1 << 8) << 1)`".
pub fn decode_word(b0: u8, b1: u8) -> i16 {
    ((((u16::from(b0) & 0x7F) << 1) | (u16::from(b1 & 0x7F) << 8)) << 1) as i16
}

/// Encodes a word as its two bytes (without the phasing bit); the inverse of
/// [`decode_word`] for the 14 significant bits (the two low bits are lost on the wire).
pub fn encode_word(w: i16) -> [u8; 2] {
    let u = (w as u16) >> 2;
    [(u & 0x7F) as u8, ((u >> 7) & 0x7F) as u8]
}

/// Word for a position in metres at a range (inverse of the documented scaling, clamped).
pub fn position_word(metres: f64, range: PositionRange) -> i16 {
    to_word(metres / METRES_PER_INCH / range.inches())
}

/// Word for an angle in degrees (±180 full scale).
pub fn angle_word(degrees: f64) -> i16 {
    to_word(degrees / 180.0)
}

/// Word for a unit-scaled value (quaternion or matrix element, ±1 full scale).
pub fn unit_word(value: f64) -> i16 {
    to_word(value)
}

fn to_word(fraction: f64) -> i16 {
    (fraction * 32768.0).round().clamp(-32768.0, 32767.0) as i16
}

/// Decodes the data words of one record (already checked for framing).
///
/// Scaling (reference): position = w × range / 32768 inches; angles w × 180 / 32768
/// degrees in the order Zang, Yang, Xang; quaternion q0..q3 = w / 32768; matrix elements
/// w / 32768 (0x7FFF = 0.99996, 0x8000 = −1.0).
pub fn decode_record(layout: &RecordLayout, bytes: &[u8], default_address: u8) -> BirdRecord {
    let words: Vec<f64> = (0..layout.format.words())
        .map(|i| f64::from(decode_word(bytes[2 * i], bytes[2 * i + 1])))
        .collect();
    let scale = 1.0 / 32768.0;
    let mut rec = BirdRecord {
        address: default_address,
        position: None,
        angles: None,
        quaternion: None,
        matrix: None,
        button: None,
    };
    let rest = if layout.format.has_position() {
        let k = layout.range.inches() * scale * METRES_PER_INCH;
        rec.position = Some([words[0] * k, words[1] * k, words[2] * k]);
        &words[3..]
    } else {
        &words[..]
    };
    match layout.format {
        OutputFormat::Angles | OutputFormat::PositionAngles => {
            let k = 180.0 * scale;
            rec.angles = Some([rest[0] * k, rest[1] * k, rest[2] * k]);
        }
        OutputFormat::Quaternion | OutputFormat::PositionQuaternion => {
            rec.quaternion = Some([
                rest[0] * scale,
                rest[1] * scale,
                rest[2] * scale,
                rest[3] * scale,
            ]);
        }
        OutputFormat::Matrix | OutputFormat::PositionMatrix => {
            let mut m = [0.0; 9];
            for (d, s) in m.iter_mut().zip(rest) {
                *d = s * scale;
            }
            rec.matrix = Some(m);
        }
        OutputFormat::Position => {}
    }
    let mut i = 2 * layout.format.words();
    if layout.button {
        rec.button = Some(bytes[i]);
        i += 1;
    }
    if layout.group {
        rec.address = bytes[i];
    }
    rec
}

/// Encodes a record as the device sends it (phasing bit on the first byte).
pub fn encode_record(layout: &RecordLayout, words: &[i16], button: u8, address: u8) -> Vec<u8> {
    let mut out = Vec::with_capacity(layout.record_bytes());
    for w in words.iter().take(layout.format.words()) {
        out.extend_from_slice(&encode_word(*w));
    }
    out.resize(2 * layout.format.words(), 0);
    if layout.button {
        out.push(button & 0x7F);
    }
    if layout.group {
        out.push(address & 0x7F);
    }
    out[0] |= 0x80;
    out
}

/// Counters kept by a [`RecordDecoder`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DecodeStats {
    /// Records decoded.
    pub records: u64,
    /// Times framing was lost and searched for again.
    pub resyncs: u64,
    /// Bytes thrown away while searching for a record start.
    pub dropped_bytes: u64,
}

/// Incremental decoder: feed it bytes as they arrive, it returns whole records.
///
/// Framing relies on the phasing bit (reference: "the most significant bit is set in the
/// first byte of a record only; every other byte has MSB 0"): bytes before a byte with the
/// MSB set are dropped, and a record in which a later byte has its MSB set is abandoned at
/// that byte, which starts the next record (a resync).
#[derive(Clone, Debug)]
pub struct RecordDecoder {
    layout: RecordLayout,
    default_address: u8,
    buf: Vec<u8>,
    stats: DecodeStats,
}

impl RecordDecoder {
    /// A decoder for records laid out as given; `default_address` labels records that carry
    /// no address byte.
    pub fn new(layout: RecordLayout, default_address: u8) -> RecordDecoder {
        RecordDecoder {
            layout,
            default_address,
            buf: Vec::with_capacity(64),
            stats: DecodeStats::default(),
        }
    }

    /// The layout decoded.
    pub fn layout(&self) -> &RecordLayout {
        &self.layout
    }

    /// Counters so far.
    pub fn stats(&self) -> DecodeStats {
        self.stats
    }

    /// Forgets a partial record (after a command that changes the stream).
    pub fn reset(&mut self) {
        self.stats.dropped_bytes += self.buf.len() as u64;
        self.buf.clear();
    }

    /// Feeds bytes; calls `out` with each complete record.
    pub fn feed(&mut self, bytes: &[u8], mut out: impl FnMut(BirdRecord)) {
        let n = self.layout.record_bytes();
        for &b in bytes {
            if b & 0x80 != 0 {
                if !self.buf.is_empty() {
                    // A record start inside a record: the previous one was truncated.
                    self.stats.resyncs += 1;
                    self.stats.dropped_bytes += self.buf.len() as u64;
                    self.buf.clear();
                }
                self.buf.push(b);
            } else if self.buf.is_empty() {
                // Not in a record: wait for a phasing bit.
                self.stats.dropped_bytes += 1;
                continue;
            } else {
                self.buf.push(b);
            }
            if self.buf.len() == n {
                let rec = decode_record(&self.layout, &self.buf, self.default_address);
                self.buf.clear();
                self.stats.records += 1;
                out(rec);
            }
        }
    }

    /// Feeds bytes and collects the records.
    pub fn feed_collect(&mut self, bytes: &[u8]) -> Vec<BirdRecord> {
        let mut v = Vec::new();
        self.feed(bytes, |r| v.push(r));
        v
    }
}

/// Records per bird in one group-mode report: one record per bird, in address order.
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

    // Byte pairs built by hand from the documented packing: a word w is sent as
    // b0 = (w >> 2) & 0x7F, b1 = (w >> 9) & 0x7F; b0 of the first word carries 0x80.

    #[test]
    fn word_packing_matches_the_manual() {
        // 0x4000 → (w>>2)=0x1000 → b0 = 0x00, b1 = 0x20.
        assert_eq!(decode_word(0x00, 0x20), 0x4000);
        // -1 quarter: 0xC000 → 0x3000 → b0 0x00, b1 0x60.
        assert_eq!(decode_word(0x00, 0x60), -0x4000);
        // The phasing bit is not data.
        assert_eq!(decode_word(0x80, 0x20), 0x4000);
        // Smallest step is 4.
        assert_eq!(decode_word(0x01, 0x00), 4);
        assert_eq!(decode_word(0x7F, 0x7F), -4);
        assert_eq!(decode_word(0x00, 0x40), i16::MIN);
    }

    #[test]
    fn position_angles_decode_exactly() {
        // x = +18 in (half of 36) = 0x4000, y = −9 in = 0xE000, z = 0;
        // azimuth 90° = 0x4000, elevation −45° = 0xE000, roll 0.
        let bytes = [
            0x80, 0x20, // x 0x4000
            0x00, 0x70, // y 0xE000 → 0x3800 → b0 0x00, b1 0x70
            0x00, 0x00, // z
            0x00, 0x20, // az
            0x00, 0x70, // el
            0x00, 0x00, // roll
        ];
        let mut d = RecordDecoder::new(RecordLayout::single(OutputFormat::PositionAngles), 1);
        let recs = d.feed_collect(&bytes);
        assert_eq!(recs.len(), 1);
        let r = &recs[0];
        assert_eq!(r.position, Some([18.0 * 0.0254, -9.0 * 0.0254, 0.0]));
        assert_eq!(r.angles, Some([90.0, -45.0, 0.0]));
        assert_eq!(r.address, 1);
        assert_eq!(r.quaternion, None);
    }

    #[test]
    fn ranges_scale_positions() {
        let bytes = [0x80, 0x20, 0x00, 0x00, 0x00, 0x00];
        for (range, inches) in [
            (PositionRange::Inches36, 18.0),
            (PositionRange::Inches72, 36.0),
            (PositionRange::Inches144, 72.0),
        ] {
            let layout = RecordLayout {
                range,
                ..RecordLayout::single(OutputFormat::Position)
            };
            let r = &RecordDecoder::new(layout, 1).feed_collect(&bytes)[0];
            assert_eq!(r.position, Some([inches * 0.0254, 0.0, 0.0]));
        }
    }

    #[test]
    fn quaternion_and_matrix_decode_exactly() {
        // q = (0.5, -0.5, 0.25, 0): 0x4000, 0xC000, 0x2000, 0.
        let q = [0x80, 0x20, 0x00, 0x60, 0x00, 0x10, 0x00, 0x00];
        let r = &RecordDecoder::new(RecordLayout::single(OutputFormat::Quaternion), 1)
            .feed_collect(&q)[0];
        assert_eq!(r.quaternion, Some([0.5, -0.5, 0.25, 0.0]));
        assert_eq!(r.position, None);
        // Matrix: 0x7FFC (largest on the wire) and 0x8000 = −1.0, rest zero.
        // 0x7FFC → 0x1FFF → b0 0x7F, b1 0x3F.
        let mut m = vec![0xFF, 0x3F, 0x00, 0x40];
        m.extend(std::iter::repeat_n(0u8, 14));
        let r =
            &RecordDecoder::new(RecordLayout::single(OutputFormat::Matrix), 1).feed_collect(&m)[0];
        let e = r.matrix.unwrap();
        assert_eq!(e[0], 32764.0 / 32768.0);
        assert_eq!(e[1], -1.0);
        assert!(e[2..].iter().all(|&v| v == 0.0));
    }

    #[test]
    fn position_quaternion_and_position_matrix_sizes() {
        let pq = RecordLayout::single(OutputFormat::PositionQuaternion);
        assert_eq!(pq.record_bytes(), 14);
        let pm = RecordLayout::single(OutputFormat::PositionMatrix);
        assert_eq!(pm.record_bytes(), 24);
        let mut bytes = vec![0x80; 1];
        bytes.extend(std::iter::repeat_n(0u8, 13));
        bytes[7] = 0x20; // q0 high byte → 0x4000
        let r = &RecordDecoder::new(pq, 1).feed_collect(&bytes)[0];
        assert_eq!(r.position, Some([0.0; 3]));
        assert_eq!(r.quaternion, Some([0.5, 0.0, 0.0, 0.0]));
    }

    #[test]
    fn group_mode_reads_the_address_byte_and_button() {
        let layout = RecordLayout {
            format: OutputFormat::Position,
            button: true,
            group: true,
            range: PositionRange::Inches36,
        };
        assert_eq!(layout.record_bytes(), 8);
        let bytes = [
            0x80, 0x20, 0, 0, 0, 0, 0x01, 0x02, // bird 2, button 1
            0x80, 0x60, 0, 0, 0, 0, 0x00, 0x03, // bird 3
        ];
        let recs = RecordDecoder::new(layout, 1).feed_collect(&bytes);
        assert_eq!(recs.len(), 2);
        assert_eq!((recs[0].address, recs[0].button), (2, Some(1)));
        assert_eq!(recs[1].address, 3);
        assert_eq!(recs[1].position.unwrap()[0], -18.0 * 0.0254);
    }

    #[test]
    fn garbage_and_truncation_resync_on_the_phasing_bit() {
        let layout = RecordLayout::single(OutputFormat::Position);
        let good = [0x80, 0x20, 0, 0, 0, 0];
        let mut stream = vec![0x11, 0x22, 0x33]; // garbage before any record
        stream.extend_from_slice(&[0x80, 0x10, 0x05]); // truncated record
        stream.extend_from_slice(&good);
        stream.extend_from_slice(&good);
        let mut d = RecordDecoder::new(layout, 1);
        // Fed one byte at a time, as a slow port would deliver them.
        let mut recs = Vec::new();
        for b in &stream {
            d.feed(std::slice::from_ref(b), |r| recs.push(r));
        }
        assert_eq!(recs.len(), 2);
        assert!(recs
            .iter()
            .all(|r| r.position == Some([18.0 * 0.0254, 0.0, 0.0])));
        let s = d.stats();
        assert_eq!(s.resyncs, 1);
        assert_eq!(s.dropped_bytes, 6);
        assert_eq!(s.records, 2);
    }

    #[test]
    fn encoding_round_trips_through_the_decoder() {
        let layout = RecordLayout {
            format: OutputFormat::PositionAngles,
            button: false,
            group: true,
            range: PositionRange::Inches72,
        };
        let words = [
            position_word(0.5, PositionRange::Inches72),
            position_word(-0.25, PositionRange::Inches72),
            position_word(1.0, PositionRange::Inches72),
            angle_word(30.0),
            angle_word(-60.0),
            angle_word(179.0),
        ];
        let bytes = encode_record(&layout, &words, 0, 4);
        let r = &RecordDecoder::new(layout, 1).feed_collect(&bytes)[0];
        let p = r.position.unwrap();
        let step = 72.0 * 0.0254 / 8192.0;
        assert!(
            (p[0] - 0.5).abs() <= step && (p[1] + 0.25).abs() <= step && (p[2] - 1.0).abs() <= step
        );
        let a = r.angles.unwrap();
        assert!(
            (a[0] - 30.0).abs() < 0.05 && (a[1] + 60.0).abs() < 0.05 && (a[2] - 179.0).abs() < 0.05
        );
        assert_eq!(r.address, 4);
    }

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
            .contains("position-angles"));
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..512),
                                       fmt in 0usize..7, group: bool, button: bool) {
            let layout = RecordLayout { format: OutputFormat::ALL[fmt], button, group, range: PositionRange::Inches36 };
            let mut d = RecordDecoder::new(layout, 1);
            let recs = d.feed_collect(&bytes);
            let s = d.stats();
            proptest::prop_assert_eq!(s.records as usize, recs.len());
            proptest::prop_assert!(s.dropped_bytes as usize + recs.len() * layout.record_bytes() <= bytes.len());
        }
    }
}
