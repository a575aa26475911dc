//! The Ascension Flock of Birds on a serial port: commands, record decoding, the protocol
//! the device thread runs, the poses of its records, and an emulator.

pub(crate) mod commands;
pub(crate) mod decoder;
pub(crate) mod emulator;
pub(crate) mod pose;
pub(crate) mod protocol;

pub use commands::*;
pub use decoder::*;
pub use emulator::FobEmulator;
pub use pose::{angles_to_quat, bird_pose, pose_words, quat_to_angles};
pub use protocol::{FobConfig, FobProtocol};
