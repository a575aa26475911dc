//! The CyberGlove (Virtual Technologies) on a serial port: record decoding, queries, the
//! protocol the device thread runs, per-user calibration, and an emulator.

pub(crate) mod calibration;
pub(crate) mod decoder;
pub(crate) mod emulator;
pub(crate) mod protocol;
pub(crate) mod query;
pub(crate) mod script;

pub use calibration::{CalibrationError, GloveCalibration};
pub use decoder::{
    sensor_names, GloveDecoder, GloveLayout, GloveRecord, GloveStats, CMD_POLL, CMD_QUERY,
    CMD_STOP, CMD_STREAM, SENSORS_22,
};
pub use emulator::GloveEmulator;
pub use protocol::{glove_query, GloveConfig, GloveProtocol};
pub use query::{error_reply, parse_query_reply, GloveError, Query, QueryReply, ReplyError};
pub use script::{write_glove_script, GloveScriptError};
