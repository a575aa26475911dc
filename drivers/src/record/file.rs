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
//!   'T' u16 stream  u64 tick  u64 taken         at `tick` ticks after the device opened,
//!                                               the scene had taken its readings 0..taken
//!   'C' u16 stream  u64 tick  u64 micros        clock mark: at `tick` ticks after the
//!                                               device opened, the scene played the
//!                                               stream at its receiver clock `micros`
//!                                               (VMC: its jitter buffer's clock)
//!   'M' u64 tick  u32 len  JSON                 a message from outside,
//!                                               {"key","value"}, seen at tick `tick`
//! ```
//!
//! Tick marks make a replay take every reading at the tick the recorded run took it, so
//! the replayed postures are the recorded run's bit for bit; a recording without marks
//! (older files, `troupe devices` tools) is replayed by its times.

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
    /// Device kind: `fob`, `cyberglove`, `spacemouse`, `vrpn` or `vmc`.
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

/// At a tick, a scene took a stream's readings up to (not including) a sequence number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mark {
    /// Stream index.
    pub stream: u16,
    /// Ticks since the device opened.
    pub tick: u64,
    /// Readings taken so far: the stream's readings `0..taken`, in decoding order.
    pub taken: u64,
}

/// At a tick, a scene read a stream's receiver clock (a VMC jitter buffer plays by it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClockMark {
    /// Stream index.
    pub stream: u16,
    /// Ticks since the device opened.
    pub tick: u64,
    /// The receiver clock that tick read, in microseconds on the stream's data clock.
    pub micros: u64,
}

/// A message a scene received from outside (`troupe.subscribe`), with its tick.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedMessage {
    /// The tick whose script phase saw it.
    pub tick: u64,
    /// Its key.
    pub key: String,
    /// Its value.
    pub value: serde_json::Value,
}

/// One chunk of a recording.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// A stream is declared (its index is the count of streams before it).
    Stream(StreamInfo),
    /// Bytes read from a stream's port.
    Data(Chunk),
    /// What a tick took from a stream.
    Mark(Mark),
    /// The receiver clock a tick read for a stream.
    Clock(ClockMark),
    /// A message from outside.
    Message(RecordedMessage),
}

/// A whole recording in memory.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Recording {
    /// Declared streams, by index.
    pub streams: Vec<StreamInfo>,
    /// Data chunks in file order (time order per stream).
    pub chunks: Vec<Chunk>,
    /// Tick marks in file order: which readings each tick took (recordings made by
    /// `troupe run --record-devices`; older ones have none and replay by time).
    pub marks: Vec<Mark>,
    /// Clock marks in file order (VMC streams recorded by `troupe run`).
    pub clocks: Vec<ClockMark>,
    /// Messages from outside, in delivery order.
    pub messages: Vec<RecordedMessage>,
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
        let mut reader = ChunkReader::default();
        let mut recording = Recording::default();
        for item in reader.read(&bytes[MAGIC.len()..])? {
            recording.add(item);
        }
        if reader.pending() > 0 {
            tracing::warn!(
                "device recording truncated at byte {}; using what precedes it",
                MAGIC.len() as u64 + reader.offset
            );
        }
        Ok(recording)
    }

    /// Adds a chunk read by a [`ChunkReader`].
    fn add(&mut self, item: Item) {
        match item {
            Item::Stream(s) => self.streams.push(s),
            Item::Data(c) => self.chunks.push(c),
            Item::Mark(m) => self.marks.push(m),
            Item::Clock(c) => self.clocks.push(c),
            Item::Message(m) => self.messages.push(m),
        }
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

/// Reads chunks from bytes that arrive in pieces (a file at once, or a leader's stream
/// tick by tick); a chunk split between pieces is kept until its end arrives.
#[derive(Debug, Default)]
pub struct ChunkReader {
    buf: Vec<u8>,
    /// Offset of `buf`'s first byte in the whole stream (after the magic), for errors.
    offset: u64,
    streams: u16,
}

impl ChunkReader {
    /// Reads every whole chunk of what has arrived with `bytes`.
    pub fn read(&mut self, bytes: &[u8]) -> Result<Vec<Item>, ParseError> {
        self.buf.extend_from_slice(bytes);
        let mut items = Vec::new();
        let mut i = 0;
        while let Some((item, next)) = self.chunk_at(i)? {
            items.push(item);
            i = next;
        }
        self.buf.drain(..i);
        self.offset += i as u64;
        Ok(items)
    }

    /// Bytes of a chunk not yet whole.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The chunk starting at `i` of the buffer and where the next starts, or `None` when it
    /// has not all arrived.
    fn chunk_at(&mut self, i: usize) -> Result<Option<(Item, usize)>, ParseError> {
        let bytes = &self.buf;
        let Some(&tag) = bytes.get(i) else {
            return Ok(None);
        };
        let offset = (self.offset + i as u64) as usize + MAGIC.len();
        let mut at = i + 1;
        let mut take = |n: usize| -> Option<&[u8]> {
            let s = bytes.get(at..at + n)?;
            at += n;
            Some(s)
        };
        let u16_ = |b: &[u8]| u16::from_le_bytes(b.try_into().unwrap_or_default());
        let u32_ = |b: &[u8]| u32::from_le_bytes(b.try_into().unwrap_or_default()) as usize;
        let u64_ = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap_or_default());
        macro_rules! field {
            ($n:expr) => {
                match take($n) {
                    Some(b) => b,
                    None => return Ok(None),
                }
            };
        }
        let item = match tag {
            b'H' => {
                let index = u16_(field!(2));
                let len = u32_(field!(4));
                let json = field!(len);
                if index != self.streams {
                    return Err(ParseError::OutOfOrder { index, offset });
                }
                let info: StreamInfo = serde_json::from_slice(json)
                    .map_err(|source| ParseError::Header { offset, source })?;
                self.streams += 1;
                Item::Stream(info)
            }
            b'D' => {
                let stream = u16_(field!(2));
                let micros = u64_(field!(8));
                let len = u32_(field!(4));
                let data = field!(len).to_vec();
                if stream >= self.streams {
                    return Err(ParseError::Undeclared { stream, offset });
                }
                Item::Data(Chunk {
                    stream,
                    micros,
                    bytes: data,
                })
            }
            b'T' | b'C' => {
                let stream = u16_(field!(2));
                let tick = u64_(field!(8));
                let value = u64_(field!(8));
                if stream >= self.streams {
                    return Err(ParseError::Undeclared { stream, offset });
                }
                match tag {
                    b'T' => Item::Mark(Mark {
                        stream,
                        tick,
                        taken: value,
                    }),
                    _ => Item::Clock(ClockMark {
                        stream,
                        tick,
                        micros: value,
                    }),
                }
            }
            b'M' => {
                let tick = u64_(field!(8));
                let len = u32_(field!(4));
                let doc: serde_json::Value = serde_json::from_slice(field!(len))
                    .map_err(|source| ParseError::Message { offset, source })?;
                let key = doc["key"]
                    .as_str()
                    .ok_or(ParseError::MessageKey { offset })?;
                Item::Message(RecordedMessage {
                    tick,
                    key: key.to_string(),
                    value: doc.get("value").cloned().unwrap_or_default(),
                })
            }
            tag => return Err(ParseError::UnknownTag { tag, offset }),
        };
        Ok(Some((item, at)))
    }
}
