//! Writing a `.rec` file while devices run: each device thread declares its stream and
//! appends the bytes it reads, one whole chunk per call; the scene marks what each tick
//! took (and, for a VMC stream, the receiver clock it played at) and records the messages
//! it received. A tap keeps a copy of the chunks written
//! since it was last taken (what a Zenoh leader sends its followers each tick).

use crate::record::error::RecordError;
use crate::record::file::{StreamInfo, MAGIC};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// Writes a `.rec` file; shared by the device threads (each call writes one whole chunk).
pub struct Recorder {
    inner: Mutex<RecorderInner>,
    start: Instant,
    path: PathBuf,
}

struct RecorderInner {
    /// The file, if recording to one.
    out: Option<std::io::BufWriter<std::fs::File>>,
    /// Chunks written since the tap was last taken, if tapped.
    tap: Option<Vec<u8>>,
    streams: u16,
    /// The first write error; later chunks are not written.
    error: Option<std::io::Error>,
}

impl Recorder {
    /// Creates the file and writes the magic.
    pub fn create(path: &Path) -> Result<Recorder, RecordError> {
        let file = std::fs::File::create(path).map_err(|source| RecordError::Create {
            path: path.to_path_buf(),
            source,
        })?;
        let mut out = std::io::BufWriter::new(file);
        out.write_all(MAGIC).map_err(|source| RecordError::Write {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Recorder {
            inner: Mutex::new(RecorderInner {
                out: Some(out),
                tap: None,
                streams: 0,
                error: None,
            }),
            start: Instant::now(),
            path: path.to_path_buf(),
        })
    }

    /// A recorder that writes no file, only its tap (see [`Recorder::tap`]).
    pub fn tap_only() -> Recorder {
        Recorder {
            inner: Mutex::new(RecorderInner {
                out: None,
                tap: Some(Vec::new()),
                streams: 0,
                error: None,
            }),
            start: Instant::now(),
            path: PathBuf::new(),
        }
    }

    /// From now on, keeps a copy of every chunk until [`Recorder::take_tap`].
    pub fn tap(&self) {
        if let Ok(mut g) = self.inner.lock() {
            g.tap.get_or_insert_with(Vec::new);
        }
    }

    /// The chunks written since the last call (without the magic); empty when not tapped.
    pub fn take_tap(&self) -> Vec<u8> {
        self.inner
            .lock()
            .ok()
            .and_then(|mut g| g.tap.as_mut().map(std::mem::take))
            .unwrap_or_default()
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

    /// Notes that `tick` ticks after the stream's device opened, the scene had taken its
    /// readings `0..taken`.
    pub fn mark(&self, stream: u16, tick: u64, taken: u64) {
        self.tick_chunk(b'T', stream, tick, taken);
    }

    /// Notes that `tick` ticks after the stream's device opened, the scene read the
    /// stream's receiver clock at `micros` (on the clock of its data chunks).
    pub fn clock(&self, stream: u16, tick: u64, micros: u64) {
        self.tick_chunk(b'C', stream, tick, micros);
    }

    /// Writes a chunk `tag u16 stream u64 tick u64 value` (a tick or clock mark).
    fn tick_chunk(&self, tag: u8, stream: u16, tick: u64, value: u64) {
        let Ok(mut g) = self.inner.lock() else { return };
        let mut chunk = Vec::with_capacity(19);
        chunk.push(tag);
        chunk.extend_from_slice(&stream.to_le_bytes());
        chunk.extend_from_slice(&tick.to_le_bytes());
        chunk.extend_from_slice(&value.to_le_bytes());
        g.write(&chunk);
    }

    /// When the recording started: the origin of its data chunks' `micros`.
    pub fn started(&self) -> Instant {
        self.start
    }

    /// Records a message from outside that the script phase of `tick` saw.
    pub fn message(&self, tick: u64, key: &str, value: &serde_json::Value) {
        let json = serde_json::json!({"key": key, "value": value}).to_string();
        let Ok(mut g) = self.inner.lock() else { return };
        let mut chunk = Vec::with_capacity(13 + json.len());
        chunk.push(b'M');
        chunk.extend_from_slice(&tick.to_le_bytes());
        chunk.extend_from_slice(&(json.len() as u32).to_le_bytes());
        chunk.extend_from_slice(json.as_bytes());
        g.write(&chunk);
    }

    /// Flushes to disk; returns the first write error, if any (once: the error is taken).
    pub fn finish(&self) -> Result<(), RecordError> {
        let mut g = self.inner.lock().map_err(|_| RecordError::Poisoned)?;
        if let Some(Err(e)) = g.out.as_mut().map(|o| o.flush()) {
            g.error.get_or_insert(e);
        }
        match g.error.take() {
            Some(source) => Err(RecordError::Write {
                path: self.path.clone(),
                source,
            }),
            None => Ok(()),
        }
    }
}

impl RecorderInner {
    fn write(&mut self, chunk: &[u8]) {
        if let Some(tap) = &mut self.tap {
            tap.extend_from_slice(chunk);
        }
        if let (None, Some(out)) = (&self.error, &mut self.out) {
            if let Err(e) = out.write_all(chunk) {
                self.error = Some(e);
            }
        }
    }
}
