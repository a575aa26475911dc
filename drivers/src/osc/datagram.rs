//! Decoding one UDP datagram as one whole OSC packet, or refusing it whole.
//!
//! rosc's `decode_udp` stops reading a bundle at its first element that does not decode
//! and returns the elements before it: a datagram cut short (or with a lying element
//! size) would be partly applied. A sender's datagram is one frame, so troupe takes all
//! of it or none: every element size must fit the bytes left, every message must decode
//! to its last byte, and nothing may follow the packet.

use rosc::{OscBundle, OscPacket, OscTime};

/// How deep bundles may nest. OSC sets no limit; senders nest one or two deep, and a
/// limit keeps a 64 KB datagram of nested headers from recursing thousands of times.
pub const MAX_BUNDLE_DEPTH: usize = 16;

/// The bundle header: `#bundle` and its NUL, padded to 8 bytes.
const BUNDLE_TAG: &[u8; 8] = b"#bundle\0";

/// A datagram that is not one whole OSC packet; the message says what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("undecodable OSC packet: {0}")]
pub struct DatagramError(pub String);

/// The OSC packet `bytes` holds, or an error when any part of it does not decode.
pub fn decode_datagram(bytes: &[u8]) -> Result<OscPacket, DatagramError> {
    packet(bytes, 0).map_err(DatagramError)
}

fn packet(bytes: &[u8], depth: usize) -> Result<OscPacket, String> {
    let Some(rest) = bytes.strip_prefix(BUNDLE_TAG) else {
        return message(bytes);
    };
    if depth >= MAX_BUNDLE_DEPTH {
        return Err(format!("bundles nested deeper than {MAX_BUNDLE_DEPTH}"));
    }
    let (tag, mut rest) = rest
        .split_at_checked(8)
        .ok_or("a bundle shorter than its time tag")?;
    let word = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    let timetag = OscTime {
        seconds: word(&tag[..4]),
        fractional: word(&tag[4..]),
    };
    let mut content = Vec::new();
    while !rest.is_empty() {
        let (size, tail) = rest
            .split_at_checked(4)
            .ok_or_else(|| format!("{} stray bytes at the end of a bundle", rest.len()))?;
        let size = i32::from_be_bytes([size[0], size[1], size[2], size[3]]);
        // OSC element sizes are multiples of 4 and must fit what is left.
        let fits = usize::try_from(size)
            .ok()
            .filter(|&s| s > 0 && s % 4 == 0 && s <= tail.len());
        let Some(size) = fits else {
            return Err(format!(
                "a bundle element of {size} bytes with {} bytes left",
                tail.len()
            ));
        };
        let (element, tail) = tail.split_at(size);
        content.push(packet(element, depth + 1)?);
        rest = tail;
    }
    Ok(OscPacket::Bundle(OscBundle { timetag, content }))
}

/// A message that decodes to its last byte.
fn message(bytes: &[u8]) -> Result<OscPacket, String> {
    match rosc::decoder::decode_udp(bytes) {
        Ok(([], p @ OscPacket::Message(_))) => Ok(p),
        Ok((rest, _)) => Err(format!("{} bytes after a message", rest.len())),
        Err(e) => Err(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rosc::{OscMessage, OscType};

    fn msg(addr: &str, v: f32) -> OscPacket {
        OscPacket::Message(OscMessage {
            addr: addr.into(),
            args: vec![OscType::Float(v)],
        })
    }

    fn bundle(content: Vec<OscPacket>) -> OscPacket {
        OscPacket::Bundle(OscBundle {
            timetag: (0, 1).into(),
            content,
        })
    }

    fn encode(p: &OscPacket) -> Vec<u8> {
        rosc::encoder::encode(p).unwrap()
    }

    #[test]
    fn whole_packets_decode_nested_bundles_included() {
        let p = bundle(vec![
            msg("/a", 1.0),
            bundle(vec![bundle(vec![msg("/b", 2.0)])]),
        ]);
        assert_eq!(decode_datagram(&encode(&p)), Ok(p));
        assert_eq!(
            decode_datagram(&encode(&msg("/c", 3.0))),
            Ok(msg("/c", 3.0))
        );
        assert_eq!(
            decode_datagram(&encode(&bundle(vec![]))),
            Ok(bundle(vec![]))
        );
    }

    #[test]
    fn a_bundle_cut_anywhere_is_refused_whole() {
        let messages = [msg("/first", 1.0), msg("/second", 2.0), msg("/third", 3.0)];
        let bytes = encode(&bundle(messages.to_vec()));
        // OSC bundles carry no total length: a cut exactly between elements (or right
        // after the header) is a shorter bundle, whole. Any other cut must be refused.
        let mut boundaries = vec![16];
        for m in &messages {
            boundaries.push(boundaries.last().unwrap() + 4 + encode(m).len());
        }
        // rosc alone returns the elements before the cut (the fault this guards against).
        let cut = &bytes[..bytes.len() - 6];
        let Ok((_, OscPacket::Bundle(partial))) = rosc::decoder::decode_udp(cut) else {
            panic!("rosc refused the cut bundle: the test no longer shows the fault");
        };
        assert_eq!(partial.content.len(), 2);
        for n in 0..bytes.len() {
            let got = decode_datagram(&bytes[..n]);
            match boundaries.iter().position(|&b| b == n) {
                Some(k) => assert_eq!(got, Ok(bundle(messages[..k].to_vec())), "cut at {n}"),
                None => assert!(got.is_err(), "cut at {n}: {got:?}"),
            }
        }
    }

    #[test]
    fn lying_sizes_trailing_bytes_and_deep_nesting_are_refused() {
        let m = encode(&msg("/VMC/Ext/OK", 1.0));
        let with_size = |size: i32| {
            let mut b = BUNDLE_TAG.to_vec();
            b.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1]);
            b.extend_from_slice(&size.to_be_bytes());
            b.extend_from_slice(&m);
            b
        };
        assert!(decode_datagram(&with_size(m.len() as i32)).is_ok());
        for size in [100_000, -8, 0, 3, m.len() as i32 - 4] {
            let e = decode_datagram(&with_size(size)).unwrap_err();
            assert!(e.to_string().contains("undecodable OSC packet"), "{e}");
        }
        let mut trailing = encode(&msg("/a", 1.0));
        trailing.extend_from_slice(&[0, 0, 0, 0]);
        assert!(decode_datagram(&trailing).is_err());
        let mut deep = msg("/VMC/Ext/OK", 1.0);
        for _ in 0..MAX_BUNDLE_DEPTH {
            deep = bundle(vec![deep]);
        }
        assert!(decode_datagram(&encode(&deep)).is_ok());
        let e = decode_datagram(&encode(&bundle(vec![deep]))).unwrap_err();
        assert!(e.0.contains("nested deeper than 16"), "{e}");
        assert!(decode_datagram(b"").is_err());
        assert!(decode_datagram(b"\xff\xfe garbage").is_err());
    }
}
