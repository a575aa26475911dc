//! CyberGlove queries (`?G`, `?S`, …): the commands, their replies and the glove's error
//! replies, parsed from the start of a byte stream.
//!
//! Facts from `shared/reference/devices.md`, section "CyberGlove", "Queries".

use crate::cyberglove::decoder::CMD_QUERY;

/// A query the driver can send, with the payload length of its binary reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// `?G`: status byte (bit 0 initialized, bit 1 glove plugged in).
    Status,
    /// `?S`: number of sensors in the hardware.
    SensorsInHardware,
    /// `?N`: number of sensors sampled.
    SensorsSampled,
    /// `?M`: 3-byte sensor mask.
    Mask,
    /// `?R`: right-handed (1) or left (0).
    RightHanded,
    /// `?V`: version text.
    Version,
}

impl Query {
    /// The query letter.
    pub fn letter(self) -> u8 {
        match self {
            Query::Status => b'G',
            Query::SensorsInHardware => b'S',
            Query::SensorsSampled => b'N',
            Query::Mask => b'M',
            Query::RightHanded => b'R',
            Query::Version => b'V',
        }
    }

    /// The bytes to send.
    pub fn command(self) -> [u8; 2] {
        [CMD_QUERY, self.letter()]
    }
}

/// A decoded query reply: `?`, the letter, the payload, a terminating 0x00
/// (reference: "`?G` status (reply `? G st 0`)").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct QueryReply {
    /// The letter echoed.
    pub letter: u8,
    /// Payload bytes between the letter and the terminator.
    pub payload: Vec<u8>,
}

/// Error replies (reference: "`e?` unknown command, `eg` glove not plugged in, `es`
/// sampling too fast").
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GloveError {
    /// `e?`
    #[error("the glove did not understand the command (e?)")]
    UnknownCommand,
    /// `eg`
    #[error("the glove is not plugged into its interface unit (eg)")]
    NotPlugged,
    /// `es`
    #[error("sampling too fast for the baud rate (es)")]
    TooFast,
    /// Any other `e` + letter.
    #[error("glove error '{0}'")]
    Other(char),
}

/// A query reply that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReplyError {
    /// The glove answered with an error reply.
    #[error(transparent)]
    Glove(#[from] GloveError),
    /// Byte 0 is neither `?` nor `e`.
    #[error("query reply starts with 0x{0:02x}, expected '?'")]
    NotAReply(u8),
    /// Byte 1 echoes another query's letter.
    #[error("query reply for '{asked}' answers '{answered}'")]
    WrongLetter {
        /// The letter asked.
        asked: char,
        /// The letter answered.
        answered: char,
    },
    /// The byte after the payload is not the 0x00 terminator.
    #[error("query reply '{letter}' is not terminated by 0x00 (byte {offset})")]
    Unterminated {
        /// The query's letter.
        letter: char,
        /// Offset of the byte that should be 0x00.
        offset: usize,
    },
}

/// Parses an error reply letter.
pub fn error_reply(letter: u8) -> GloveError {
    match letter {
        b'?' => GloveError::UnknownCommand,
        b'g' => GloveError::NotPlugged,
        b's' => GloveError::TooFast,
        c => GloveError::Other(c as char),
    }
}

/// Tries to parse a query reply from the start of `bytes`: returns the reply and the bytes
/// used, `Ok(None)` when more bytes are needed. Fixed-size payloads are read by length
/// (a sensor mask byte may be zero); the version is text up to the terminator.
pub fn parse_query_reply(
    query: Query,
    bytes: &[u8],
) -> Result<Option<(QueryReply, usize)>, ReplyError> {
    if bytes.is_empty() {
        return Ok(None);
    }
    if bytes[0] == b'e' {
        return match bytes.get(1) {
            Some(&c) => Err(ReplyError::Glove(error_reply(c))),
            None => Ok(None),
        };
    }
    if bytes[0] != CMD_QUERY {
        return Err(ReplyError::NotAReply(bytes[0]));
    }
    let Some(&letter) = bytes.get(1) else {
        return Ok(None);
    };
    if letter != query.letter() {
        return Err(ReplyError::WrongLetter {
            asked: query.letter() as char,
            answered: letter as char,
        });
    }
    let fixed = match query {
        Query::Mask => Some(3),
        Query::Version => None,
        _ => Some(1),
    };
    let end = match fixed {
        Some(k) => {
            if bytes.len() < 2 + k + 1 {
                return Ok(None);
            }
            2 + k
        }
        None => match bytes[2..].iter().position(|&b| b == 0) {
            Some(p) => 2 + p,
            None => return Ok(None),
        },
    };
    if bytes[end] != 0 {
        return Err(ReplyError::Unterminated {
            letter: letter as char,
            offset: end,
        });
    }
    Ok(Some((
        QueryReply {
            letter,
            payload: bytes[2..end].to_vec(),
        },
        end + 1,
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_replies() {
        assert_eq!(
            parse_query_reply(Query::Status, &[b'?', b'G', 0x03, 0]).unwrap(),
            Some((
                QueryReply {
                    letter: b'G',
                    payload: vec![3]
                },
                4
            ))
        );
        assert_eq!(
            parse_query_reply(Query::Mask, &[b'?', b'M', 0xFF, 0x00, 0x3F, 0])
                .unwrap()
                .unwrap()
                .0
                .payload,
            vec![0xFF, 0x00, 0x3F]
        );
        assert_eq!(parse_query_reply(Query::Version, b"?V1.2").unwrap(), None);
        assert_eq!(
            parse_query_reply(Query::Version, b"?V1.2\0")
                .unwrap()
                .unwrap()
                .0
                .payload,
            b"1.2".to_vec()
        );
        assert!(parse_query_reply(Query::Status, b"eg")
            .unwrap_err()
            .to_string()
            .contains("not plugged"));
        assert!(parse_query_reply(Query::Status, &[b'?', b'S', 18, 0]).is_err());
    }
}
