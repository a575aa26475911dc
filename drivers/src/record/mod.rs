//! Recording device streams to `.rec` files while they run, and replaying them through the
//! decoders a live device uses.

pub(crate) mod error;
pub(crate) mod feed;
pub(crate) mod file;
pub(crate) mod replay;
pub(crate) mod writer;

pub use error::{KindError, ParseError, RecordError};
pub use feed::{DeviceReplay, RecordMessages, ReplayedMessages};
pub use file::{
    Chunk, ChunkReader, ClockMark, Item, Mark, RecordedMessage, Recording, StreamInfo, MAGIC,
};
pub use replay::protocol_from_settings;
pub use writer::Recorder;
