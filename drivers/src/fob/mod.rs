//! The Ascension Flock of Birds on a serial port: commands, record decoding, the protocol
//! the device thread runs, the poses of its records, and an emulator.

pub(crate) mod commands;
pub(crate) mod decoder;
pub(crate) mod emulator;
pub(crate) mod pose;
pub(crate) mod protocol;

pub use commands::{
    auto_config_command, group_mode_command, Hemisphere, OutputFormat, PositionRange, ReportRate,
    UnknownSetting, CMD_CHANGE, CMD_EXAMINE, CMD_FBB_RESET, CMD_HEMISPHERE, CMD_POINT, CMD_RUN,
    CMD_SLEEP, CMD_STREAM, CMD_TO_FBB, PARAM_AUTO_CONFIG, PARAM_ERROR_CODE, PARAM_FBB_STATUS,
    PARAM_GROUP_MODE, STATUS_ACCESSIBLE, STATUS_RECEIVER, STATUS_RUNNING,
};
pub use decoder::{
    angle_word, decode_record, decode_word, encode_record, encode_word, position_word, unit_word,
    BirdRecord, DecodeStats, RecordDecoder, RecordLayout, METRES_PER_INCH,
};
pub use emulator::FobEmulator;
pub use pose::{angles_to_quat, bird_pose, pose_words, quat_to_angles};
pub use protocol::{FobConfig, FobProtocol};
