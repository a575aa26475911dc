//! Ascension Flock of Birds: the record layout on the wire, the packing of data words,
//! and a decoder that frames records out of a byte stream and resynchronizes on loss.
//!
//! Every protocol fact here comes from `shared/reference/devices.md`, section "Ascension
//! Flock of Birds (RS-232)"; the comments quote the fact they rely on. The thesis uses the
//! Flock to drive a performer's body (sections 2.7 and 6.4.1).

use crate::fob::commands::{OutputFormat, PositionRange};
use serde::{Deserialize, Serialize};

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
