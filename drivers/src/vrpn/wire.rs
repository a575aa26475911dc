//! VRPN's bytes on the wire (`Format_Of_Protocol.txt` of VRPN 07.38): the version cookie
//! both peers send first, and the message every later exchange is made of — a 24-byte
//! header of big-endian 32-bit fields (total length, timestamp seconds and microseconds,
//! sender, type, padding) and a payload padded to 8 bytes.

use crate::vrpn::error::VrpnError;

/// The cookie troupe sends: VRPN 07.38, no remote logging, padded to 24 bytes.
pub const COOKIE: &[u8; 24] = b"vrpn: ver. 07.38  0\0\0\0\0\0";
/// The major version troupe speaks; a peer of another major version is refused.
pub const MAJOR: u32 = 7;
/// Bytes of a message header (five fields and a padding word).
pub const HEADER_LEN: usize = 24;
/// The largest message troupe accepts (VRPN's own receive buffer is 64 KiB).
pub const MAX_MESSAGE: usize = 65_536;
/// Messages are padded to this many bytes.
pub const ALIGN: usize = 8;

/// System message types (negative), as the protocol numbers them.
pub mod system {
    /// Names a sender id: payload `u32 len+1`, the name, NUL.
    pub const SENDER_DESCRIPTION: i32 = -1;
    /// Names a type id, laid out like a sender description.
    pub const TYPE_DESCRIPTION: i32 = -2;
    /// "Send unreliable messages to this UDP port" (the sender field), host in the payload.
    pub const UDP_DESCRIPTION: i32 = -3;
    /// A remote logging request.
    pub const LOG_DESCRIPTION: i32 = -4;
    /// Marks a dropped connection in logs; never sent over the wire.
    pub const DISCONNECT: i32 = -5;
}

/// The version a peer's cookie announces: `(major, minor)`.
pub fn check_cookie(bytes: &[u8]) -> Result<(u32, u32), VrpnError> {
    let shown = String::from_utf8_lossy(&bytes[..bytes.len().min(COOKIE.len())])
        .trim_end_matches('\0')
        .to_string();
    let bad = || VrpnError::Cookie(shown.clone());
    let rest = bytes.strip_prefix(b"vrpn: ver. ").ok_or_else(bad)?;
    let digits = |b: &[u8]| -> Option<u32> {
        (b.len() == 2 && b.iter().all(u8::is_ascii_digit))
            .then(|| u32::from(b[0] - b'0') * 10 + u32::from(b[1] - b'0'))
    };
    let major = rest.get(0..2).and_then(digits).ok_or_else(bad)?;
    if rest.get(2) != Some(&b'.') {
        return Err(bad());
    }
    let minor = rest.get(3..5).and_then(digits).ok_or_else(bad)?;
    if major != MAJOR {
        return Err(VrpnError::Version {
            major,
            minor,
            ours: MAJOR,
        });
    }
    Ok((major, minor))
}

/// A message's header fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Header and unpadded payload, in bytes.
    pub len: u32,
    /// Source time: seconds.
    pub sec: u32,
    /// Source time: microseconds.
    pub usec: u32,
    /// The sender id (the port, for a UDP description).
    pub sender: i32,
    /// The type id (negative: a system message).
    pub kind: i32,
}

impl Header {
    /// Reads a header; `None` when fewer than 24 bytes are given.
    pub fn parse(b: &[u8]) -> Option<Header> {
        let word = |i: usize| -> Option<u32> {
            Some(u32::from_be_bytes(
                b.get(4 * i..4 * i + 4)?.try_into().ok()?,
            ))
        };
        if b.len() < HEADER_LEN {
            return None;
        }
        Some(Header {
            len: word(0)?,
            sec: word(1)?,
            usec: word(2)?,
            sender: word(3)? as i32,
            kind: word(4)? as i32,
        })
    }

    /// Payload bytes without padding; an error when the length field lies.
    pub fn payload_len(&self) -> Result<usize, VrpnError> {
        let len = self.len as usize;
        if !(HEADER_LEN..=MAX_MESSAGE).contains(&len) {
            return Err(VrpnError::Length(self.len));
        }
        Ok(len - HEADER_LEN)
    }

    /// Bytes the whole message takes on the wire (header and padded payload).
    pub fn wire_len(&self) -> Result<usize, VrpnError> {
        Ok(HEADER_LEN + padded(self.payload_len()?))
    }

    /// The timestamp in seconds.
    pub fn time(&self) -> f64 {
        f64::from(self.sec) + f64::from(self.usec) * 1e-6
    }
}

/// `n` rounded up to a multiple of [`ALIGN`].
pub fn padded(n: usize) -> usize {
    n.div_ceil(ALIGN) * ALIGN
}

/// One message: its header and its (unpadded) payload.
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    /// The header.
    pub header: Header,
    /// The payload without padding.
    pub payload: Vec<u8>,
}

/// Encodes a message with the given time, sender, type and payload.
pub fn encode(sec: u32, usec: u32, sender: i32, kind: i32, payload: &[u8]) -> Vec<u8> {
    let len = (HEADER_LEN + payload.len()) as u32;
    let mut out = Vec::with_capacity(HEADER_LEN + padded(payload.len()));
    for w in [len, sec, usec, sender as u32, kind as u32, 0] {
        out.extend_from_slice(&w.to_be_bytes());
    }
    out.extend_from_slice(payload);
    out.resize(HEADER_LEN + padded(payload.len()), 0);
    out
}

/// A name description's payload (sender or type): `u32 len+1`, the name, NUL.
pub fn name_payload(name: &str) -> Vec<u8> {
    let mut p = ((name.len() + 1) as u32).to_be_bytes().to_vec();
    p.extend_from_slice(name.as_bytes());
    p.push(0);
    p
}

/// Splits a byte stream into whole messages, whatever the pieces it arrives in.
#[derive(Debug, Default)]
pub struct Framer {
    buf: Vec<u8>,
}

impl Framer {
    /// Appends bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes waiting for the rest of their message.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The next whole message, `Ok(None)` when it has not all arrived, or an error when a
    /// header's length lies (the stream cannot be framed any further: the caller drops it).
    pub fn next_message(&mut self) -> Result<Option<Message>, VrpnError> {
        let Some(header) = Header::parse(&self.buf) else {
            return Ok(None);
        };
        let payload_len = header.payload_len()?;
        let wire = header.wire_len()?;
        if self.buf.len() < wire {
            return Ok(None);
        }
        let payload = self.buf[HEADER_LEN..HEADER_LEN + payload_len].to_vec();
        self.buf.drain(..wire);
        Ok(Some(Message { header, payload }))
    }

    /// Forgets what is buffered (a new connection).
    pub fn clear(&mut self) {
        self.buf.clear();
    }
}

/// Splits one UDP datagram into whole messages; an error when a length lies or the
/// datagram ends inside a message.
pub fn split_datagram(datagram: &[u8]) -> Result<Vec<Message>, VrpnError> {
    let mut framer = Framer::default();
    framer.push(datagram);
    let mut out = Vec::new();
    while let Some(m) = framer.next_message()? {
        out.push(m);
    }
    if framer.pending() > 0 {
        return Err(VrpnError::Truncated(framer.pending()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_message_round_trips_with_its_padding() {
        let bytes = encode(5, 250_000, 2, 7, b"abc");
        assert_eq!(bytes.len(), 32);
        assert_eq!(&bytes[0..4], &27u32.to_be_bytes());
        let mut f = Framer::default();
        f.push(&bytes[..10]);
        assert!(f.next_message().unwrap().is_none());
        f.push(&bytes[10..]);
        let m = f.next_message().unwrap().unwrap();
        assert_eq!(m.payload, b"abc");
        assert_eq!((m.header.sender, m.header.kind), (2, 7));
        assert_eq!(m.header.time(), 5.25);
        assert_eq!(f.pending(), 0);
    }

    #[test]
    fn cookies_of_the_same_major_version_pass_and_others_are_refused() {
        assert_eq!(check_cookie(COOKIE).unwrap(), (7, 38));
        assert_eq!(
            check_cookie(b"vrpn: ver. 07.35  0\0\0\0\0\0").unwrap(),
            (7, 35)
        );
        let e = check_cookie(b"vrpn: ver. 06.02  0\0\0\0\0\0").unwrap_err();
        assert!(e.to_string().contains("major version 6"), "{e}");
        let e = check_cookie(b"HTTP/1.1 400 Bad Request").unwrap_err();
        assert!(e.to_string().contains("not a VRPN cookie"), "{e}");
    }

    #[test]
    fn lying_lengths_and_cut_datagrams_are_errors() {
        let mut m = encode(0, 0, 0, 0, b"12345678");
        m[0..4].copy_from_slice(&3u32.to_be_bytes());
        assert!(split_datagram(&m).is_err());
        m[0..4].copy_from_slice(&u32::MAX.to_be_bytes());
        assert!(split_datagram(&m).is_err());
        let ok = encode(0, 0, 0, 0, b"12345678");
        assert!(matches!(
            split_datagram(&ok[..30]),
            Err(VrpnError::Truncated(30))
        ));
        assert_eq!(split_datagram(&[ok.clone(), ok].concat()).unwrap().len(), 2);
    }
}
