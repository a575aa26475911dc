//! The `.rec` file format and reading it: device streams recorded as raw bytes.
//!
//! A `.rec` file keeps the raw bytes each device sent, with the time they arrived, rather than
//! decoded samples: replay then runs the very decoder a live device runs (resyncs included),
//! a recording can be served again by an emulator on a pseudo-terminal, and a decoder fix
//! applies to old recordings. The format (little-endian):
//!
//! ```text
//! "TROUPEREC1\n"                                  magic, 11 bytes
//! then chunks, each starting with a tag byte:
//!   'H' u16 stream  u32 len  JSON               a stream: {"name","kind","settings"}
//!   'D' u16 stream  u64 micros  u32 len  bytes  bytes read from that stream's port,
//!                                               `micros` after the recording started
//! ```

use crate::record::error::{ParseError, RecordError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The magic first line of a `.rec` file.
pub const MAGIC: &[u8; 11] = b"TROUPEREC1\n";

/// A stream declared in a recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StreamInfo {
    /// Device name.
    pub name: String,
    /// Device kind: `fob`, `cyberglove`, `spacemouse` or `vrpn`.
    pub kind: String,
    /// The driver settings needed to decode it.
    pub settings: serde_json::Value,
}

/// One chunk of recorded bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Chunk {
    /// Stream index.
    pub stream: u16,
    /// Microseconds since the recording started.
    pub micros: u64,
    /// The bytes.
    pub bytes: Vec<u8>,
}

/// A whole recording in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// Declared streams, by index.
    pub streams: Vec<StreamInfo>,
    /// Data chunks in file order (time order per stream).
    pub chunks: Vec<Chunk>,
}

impl Recording {
    /// Reads and checks a `.rec` file.
    pub fn read(path: &Path) -> Result<Recording, RecordError> {
        let bytes = std::fs::read(path).map_err(|source| RecordError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Recording::parse(&bytes).map_err(|source| RecordError::Parse {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Parses `.rec` bytes; errors name the byte offset. A chunk cut short at the end (a
    /// recording interrupted mid-write) ends the recording with a warning instead.
    pub fn parse(bytes: &[u8]) -> Result<Recording, ParseError> {
        if !bytes.starts_with(MAGIC) {
            return Err(ParseError::NoMagic);
        }
        let mut streams = Vec::new();
        let mut chunks = Vec::new();
        let mut i = MAGIC.len();
        let take = |i: &mut usize, n: usize| -> Option<&[u8]> {
            let s = bytes.get(*i..*i + n)?;
            *i += n;
            Some(s)
        };
        while i < bytes.len() {
            let at = i;
            let tag = bytes[i];
            i += 1;
            let parsed = match tag {
                b'H' => (|| {
                    let index = u16::from_le_bytes(take(&mut i, 2)?.try_into().ok()?);
                    let len = u32::from_le_bytes(take(&mut i, 4)?.try_into().ok()?) as usize;
                    let json = take(&mut i, len)?;
                    Some(Err((index, json.to_vec())))
                })(),
                b'D' => (|| {
                    let stream = u16::from_le_bytes(take(&mut i, 2)?.try_into().ok()?);
                    let micros = u64::from_le_bytes(take(&mut i, 8)?.try_into().ok()?);
                    let len = u32::from_le_bytes(take(&mut i, 4)?.try_into().ok()?) as usize;
                    let data = take(&mut i, len)?;
                    Some(Ok(Chunk {
                        stream,
                        micros,
                        bytes: data.to_vec(),
                    }))
                })(),
                tag => return Err(ParseError::UnknownTag { tag, offset: at }),
            };
            match parsed {
                None => {
                    tracing::warn!(
                        "device recording truncated at byte {at}; using what precedes it"
                    );
                    break;
                }
                Some(Err((index, json))) => {
                    if usize::from(index) != streams.len() {
                        return Err(ParseError::OutOfOrder { index, offset: at });
                    }
                    let info: StreamInfo = serde_json::from_slice(&json)
                        .map_err(|source| ParseError::Header { offset: at, source })?;
                    streams.push(info);
                }
                Some(Ok(c)) => {
                    if usize::from(c.stream) >= streams.len() {
                        return Err(ParseError::Undeclared {
                            stream: c.stream,
                            offset: at,
                        });
                    }
                    chunks.push(c);
                }
            }
        }
        Ok(Recording { streams, chunks })
    }

    /// The index of the stream named `name`, or of the only stream of a kind.
    pub fn find(&self, name_or_kind: &str) -> Option<usize> {
        self.streams
            .iter()
            .position(|s| s.name == name_or_kind)
            .or_else(|| {
                let of_kind: Vec<_> = (0..self.streams.len())
                    .filter(|&i| self.streams[i].kind == name_or_kind)
                    .collect();
                (of_kind.len() == 1).then(|| of_kind[0])
            })
    }
}
