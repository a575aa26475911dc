//! What can go wrong writing, reading or replaying a `.rec` recording.

use std::path::PathBuf;

/// A `.rec` file that cannot be written, read or decoded; every error names the file or
/// the stream.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file could not be created.
    #[error("creating {}: {source}", path.display())]
    Create {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// Writing the file failed (the first write error of the recording).
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The file could not be read.
    #[error("reading {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a well-formed recording.
    #[error("{}: {source}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where and what.
        #[source]
        source: ParseError,
    },
    /// Another thread panicked while writing the recording.
    #[error("recorder lock poisoned")]
    Poisoned,
    /// A stream index past the declared streams.
    #[error("no stream {0} in the recording")]
    NoStream(usize),
    /// A stream whose settings do not rebuild a decoder.
    #[error("stream '{name}' ({kind}): {source}")]
    Stream {
        /// The stream's device name.
        name: String,
        /// Its device kind.
        kind: String,
        /// Why its decoder cannot be built.
        #[source]
        source: KindError,
    },
}

/// Bytes that are not a well-formed recording; each error names the byte offset.
#[derive(Debug, thiserror::Error)]
pub enum ParseError {
    /// The file does not start with the magic line.
    #[error("not a troupe device recording (missing TROUPEREC1 header)")]
    NoMagic,
    /// A chunk starts with a tag other than `H`, `D`, `T` or `M`.
    #[error("unknown chunk tag 0x{tag:02x} at byte {offset}")]
    UnknownTag {
        /// The tag byte.
        tag: u8,
        /// Where the chunk starts.
        offset: usize,
    },
    /// A stream declared with an index other than the next one.
    #[error("stream {index} declared out of order at byte {offset}")]
    OutOfOrder {
        /// The declared index.
        index: u16,
        /// Where the header starts.
        offset: usize,
    },
    /// A stream header whose JSON is not `{"name","kind","settings"}`.
    #[error("stream header at byte {offset}: {source}")]
    Header {
        /// Where the header starts.
        offset: usize,
        /// What the JSON parser said.
        #[source]
        source: serde_json::Error,
    },
    /// Data for a stream not declared before it.
    #[error("data for undeclared stream {stream} at byte {offset}")]
    Undeclared {
        /// The stream index.
        stream: u16,
        /// Where the chunk starts.
        offset: usize,
    },
    /// A recorded message that is not JSON.
    #[error("message at byte {offset}: {source}")]
    Message {
        /// Where the chunk starts.
        offset: usize,
        /// What the JSON parser said.
        #[source]
        source: serde_json::Error,
    },
    /// A recorded message without a `key` string.
    #[error("message at byte {offset}: no \"key\" (a string)")]
    MessageKey {
        /// Where the chunk starts.
        offset: usize,
    },
}

/// A recorded device kind and settings that do not make a decoder.
#[derive(Debug, thiserror::Error)]
pub enum KindError {
    /// The settings do not fit the kind's configuration.
    #[error("{0}")]
    Settings(#[from] serde_json::Error),
    /// No driver has this kind.
    #[error("unknown device kind '{0}' (expected fob, cyberglove, spacemouse or vrpn)")]
    Unknown(String),
}
