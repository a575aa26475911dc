//! Recording and replaying device streams (`.rec` files).
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

use crate::driver::{FobConfig, FobProtocol, GloveConfig, GloveProtocol, Protocol, Reading};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

/// The magic first line of a `.rec` file.
pub const MAGIC: &[u8; 11] = b"TROUPEREC1\n";

/// A stream declared in a recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StreamInfo {
    /// Device name.
    pub name: String,
    /// Device kind: `fob`, `cyberglove` or `spacemouse`.
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

/// Writes a `.rec` file; shared by the device threads (each call writes one whole chunk).
pub struct Recorder {
    inner: Mutex<RecorderInner>,
    start: Instant,
}

struct RecorderInner {
    out: std::io::BufWriter<std::fs::File>,
    streams: u16,
    error: Option<String>,
}

impl Recorder {
    /// Creates the file and writes the magic.
    pub fn create(path: &Path) -> Result<Recorder, String> {
        let file =
            std::fs::File::create(path).map_err(|e| format!("creating {}: {e}", path.display()))?;
        let mut out = std::io::BufWriter::new(file);
        out.write_all(MAGIC)
            .map_err(|e| format!("writing {}: {e}", path.display()))?;
        Ok(Recorder {
            inner: Mutex::new(RecorderInner {
                out,
                streams: 0,
                error: None,
            }),
            start: Instant::now(),
        })
    }

    /// Declares a stream; returns its index.
    pub fn add_stream(&self, name: &str, kind: &str, settings: serde_json::Value) -> u16 {
        let info = StreamInfo {
            name: name.into(),
            kind: kind.into(),
            settings,
        };
        let json = serde_json::to_vec(&info).unwrap_or_default();
        let Ok(mut g) = self.inner.lock() else {
            return 0;
        };
        let index = g.streams;
        g.streams += 1;
        let mut chunk = vec![b'H'];
        chunk.extend_from_slice(&index.to_le_bytes());
        chunk.extend_from_slice(&(json.len() as u32).to_le_bytes());
        chunk.extend_from_slice(&json);
        g.write(&chunk);
        index
    }

    /// Records bytes read from a stream now.
    pub fn data(&self, stream: u16, bytes: &[u8]) {
        let micros = self.start.elapsed().as_micros() as u64;
        self.data_at(stream, micros, bytes);
    }

    /// Records bytes at a given time (microseconds since the start).
    pub fn data_at(&self, stream: u16, micros: u64, bytes: &[u8]) {
        let Ok(mut g) = self.inner.lock() else { return };
        let mut chunk = Vec::with_capacity(15 + bytes.len());
        chunk.push(b'D');
        chunk.extend_from_slice(&stream.to_le_bytes());
        chunk.extend_from_slice(&micros.to_le_bytes());
        chunk.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        chunk.extend_from_slice(bytes);
        g.write(&chunk);
    }

    /// Flushes to disk; returns the first write error, if any.
    pub fn finish(&self) -> Result<(), String> {
        let mut g = self
            .inner
            .lock()
            .map_err(|_| "recorder lock poisoned".to_string())?;
        if let Err(e) = g.out.flush() {
            g.error.get_or_insert(e.to_string());
        }
        match &g.error {
            Some(e) => Err(format!("writing the device recording: {e}")),
            None => Ok(()),
        }
    }
}

impl RecorderInner {
    fn write(&mut self, chunk: &[u8]) {
        if self.error.is_none() {
            if let Err(e) = self.out.write_all(chunk) {
                self.error = Some(e.to_string());
            }
        }
    }
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
    pub fn read(path: &Path) -> Result<Recording, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("reading {}: {e}", path.display()))?;
        Recording::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Parses `.rec` bytes; errors name the byte offset. A chunk cut short at the end (a
    /// recording interrupted mid-write) ends the recording with a warning instead.
    pub fn parse(bytes: &[u8]) -> Result<Recording, String> {
        if !bytes.starts_with(MAGIC) {
            return Err("not a troupe device recording (missing TROUPEREC1 header)".into());
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
                other => return Err(format!("unknown chunk tag 0x{other:02x} at byte {at}")),
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
                        return Err(format!("stream {index} declared out of order at byte {at}"));
                    }
                    let info: StreamInfo = serde_json::from_slice(&json)
                        .map_err(|e| format!("stream header at byte {at}: {e}"))?;
                    streams.push(info);
                }
                Some(Ok(c)) => {
                    if usize::from(c.stream) >= streams.len() {
                        return Err(format!(
                            "data for undeclared stream {} at byte {at}",
                            c.stream
                        ));
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

    /// A decoder for a stream, built from its recorded settings.
    pub fn protocol(&self, stream: usize) -> Result<Box<dyn Protocol>, String> {
        let info = self
            .streams
            .get(stream)
            .ok_or_else(|| format!("no stream {stream} in the recording"))?;
        protocol_from_settings(&info.kind, &info.settings)
            .map_err(|e| format!("stream '{}' ({}): {e}", info.name, info.kind))
    }

    /// Every reading of a stream with its recorded time in seconds, decoded by the same
    /// decoder a live device uses.
    pub fn readings(&self, stream: usize) -> Result<Vec<(f64, Reading)>, String> {
        let mut p = self.protocol(stream)?;
        let mut out = Vec::new();
        for c in self
            .chunks
            .iter()
            .filter(|c| usize::from(c.stream) == stream)
        {
            let t = c.micros as f64 * 1e-6;
            p.decode(&c.bytes, &mut |r| out.push((t, r)));
        }
        Ok(out)
    }
}

/// Rebuilds a protocol from the settings a driver recorded.
pub fn protocol_from_settings(
    kind: &str,
    settings: &serde_json::Value,
) -> Result<Box<dyn Protocol>, String> {
    match kind {
        "fob" => {
            let c: FobConfig =
                serde_json::from_value(settings.clone()).map_err(|e| e.to_string())?;
            Ok(Box::new(FobProtocol::new(c)))
        }
        "cyberglove" => {
            let c: GloveConfig =
                serde_json::from_value(settings.clone()).map_err(|e| e.to_string())?;
            Ok(Box::new(GloveProtocol::new(c)))
        }
        "spacemouse" => Ok(Box::new(crate::spacemouse::SpaceMouseProtocol::default())),
        other => Err(format!(
            "unknown device kind '{other}' (expected fob, cyberglove or spacemouse)"
        )),
    }
}
