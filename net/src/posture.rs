//! The binary layout of one actor's posture at one tick, as published on
//! `<prefix>/actors/<name>/pose` (documented in docs/formats.md, "Posture packets").
//!
//! Little-endian, 24-byte header then the DOF values, in the order of the actor's DOF
//! names (served once on `<prefix>/actors/<name>/dofs`):
//!
//! ```text
//! offset size
//!  0     2    magic "TP"
//!  2     1    version (1)
//!  3     1    flags (0; a reader refuses bits it does not know)
//!  4     4    u32 DOF count n
//!  8     8    u64 tick
//! 16     8    f64 scene time, seconds
//! 24     8n   f64 DOF values (radians or metres), as the scene holds them
//! ```
//!
//! Values are the scene's own `f64`s, not rounded to `f32`: a follower compares them bit
//! for bit, and a client checking against a `.trk` file gets exactly what was recorded.

use thiserror::Error;

/// The first two bytes of every posture packet.
pub const MAGIC: [u8; 2] = *b"TP";
/// The layout version this crate writes and reads.
pub const VERSION: u8 = 1;
/// Bytes before the first DOF value.
pub const HEADER_LEN: usize = 24;

/// One actor's posture at one tick.
#[derive(Clone, Debug, PartialEq)]
pub struct Posture {
    /// The tick it was taken at.
    pub tick: u64,
    /// Scene time, seconds.
    pub time: f64,
    /// DOF values in the actor's DOF order.
    pub values: Vec<f64>,
}

/// Why bytes are not a posture packet.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum PostureError {
    /// Fewer bytes than the header or than the values it announces.
    #[error("posture packet of {got} bytes, expected {expected}")]
    Length {
        /// Bytes received.
        got: usize,
        /// Bytes the header (or the header alone) needs.
        expected: usize,
    },
    /// Not starting with "TP".
    #[error("not a posture packet (starts with {0:02x?}, expected \"TP\")")]
    Magic([u8; 2]),
    /// A version this reader does not know.
    #[error("posture packet version {0}, this reader knows version {VERSION}")]
    Version(u8),
    /// Flag bits this reader does not know.
    #[error("posture packet flags {0:#04x} are unknown")]
    Flags(u8),
}

/// Appends the packet of `values` at `tick`, `time` to `out` (cleared first), so a
/// publisher can reuse one buffer per actor.
pub fn encode_into(tick: u64, time: f64, values: &[f64], out: &mut Vec<u8>) {
    out.clear();
    out.reserve(HEADER_LEN + 8 * values.len());
    out.extend_from_slice(&MAGIC);
    out.push(VERSION);
    out.push(0);
    out.extend_from_slice(&(values.len() as u32).to_le_bytes());
    out.extend_from_slice(&tick.to_le_bytes());
    out.extend_from_slice(&time.to_le_bytes());
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// The packet of `values` at `tick`, `time`.
pub fn encode(tick: u64, time: f64, values: &[f64]) -> Vec<u8> {
    let mut out = Vec::new();
    encode_into(tick, time, values, &mut out);
    out
}

/// Reads a packet; refuses wrong magic, versions, flags and lengths.
pub fn decode(bytes: &[u8]) -> Result<Posture, PostureError> {
    if bytes.len() < HEADER_LEN {
        return Err(PostureError::Length {
            got: bytes.len(),
            expected: HEADER_LEN,
        });
    }
    let magic = [bytes[0], bytes[1]];
    if magic != MAGIC {
        return Err(PostureError::Magic(magic));
    }
    if bytes[2] != VERSION {
        return Err(PostureError::Version(bytes[2]));
    }
    if bytes[3] != 0 {
        return Err(PostureError::Flags(bytes[3]));
    }
    let word = |at: usize| -> [u8; 8] { bytes[at..at + 8].try_into().expect("8 bytes") };
    let n = u32::from_le_bytes(bytes[4..8].try_into().expect("4 bytes")) as usize;
    let expected = HEADER_LEN + 8 * n;
    if bytes.len() != expected {
        return Err(PostureError::Length {
            got: bytes.len(),
            expected,
        });
    }
    Ok(Posture {
        tick: u64::from_le_bytes(word(8)),
        time: f64::from_le_bytes(word(16)),
        values: (0..n)
            .map(|i| f64::from_le_bytes(word(HEADER_LEN + 8 * i)))
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_posture_round_trips_bit_for_bit() {
        let values = [
            0.0,
            -0.0,
            1.5,
            f64::MIN_POSITIVE,
            -1e-300,
            std::f64::consts::PI,
        ];
        let bytes = encode(42, 0.42, &values);
        assert_eq!(bytes.len(), HEADER_LEN + 8 * values.len());
        let back = decode(&bytes).unwrap();
        assert_eq!(back.tick, 42);
        assert_eq!(back.time.to_bits(), 0.42f64.to_bits());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.values), bits(&values));
    }

    #[test]
    fn the_header_is_laid_out_as_documented() {
        let bytes = encode(0x0102, 2.0, &[1.0]);
        assert_eq!(&bytes[..4], b"TP\x01\x00");
        assert_eq!(&bytes[4..8], &1u32.to_le_bytes());
        assert_eq!(&bytes[8..16], &0x0102u64.to_le_bytes());
        assert_eq!(&bytes[16..24], &2.0f64.to_le_bytes());
        assert_eq!(&bytes[24..], &1.0f64.to_le_bytes());
    }

    #[test]
    fn bad_packets_are_refused_with_what_is_wrong() {
        let good = encode(1, 0.01, &[1.0, 2.0]);
        assert_eq!(
            decode(&good[..10]),
            Err(PostureError::Length {
                got: 10,
                expected: 24
            })
        );
        assert_eq!(
            decode(&good[..good.len() - 1]),
            Err(PostureError::Length {
                got: 39,
                expected: 40
            })
        );
        let mut bad = good.clone();
        bad[0] = b'X';
        assert_eq!(decode(&bad), Err(PostureError::Magic(*b"XP")));
        let mut bad = good.clone();
        bad[2] = 2;
        assert_eq!(decode(&bad), Err(PostureError::Version(2)));
        let mut bad = good;
        bad[3] = 0x80;
        assert_eq!(decode(&bad), Err(PostureError::Flags(0x80)));
        // A DOF count that would overflow the buffer is a length error, not a panic.
        let mut huge = encode(1, 0.0, &[]);
        huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(decode(&huge), Err(PostureError::Length { .. })));
    }
}
