//! Device drivers for troupe: Flock of Birds and CyberGlove over serial ports, SpaceMouse
//! over HID, emulators on pseudo-terminals, and record/replay of device streams.
//!
//! Protocol facts are those of `shared/reference/devices.md`; thesis sections 2.7, 4.7 and
//! 6.4.1 describe how the devices drive performer actors.

pub mod driver;
pub mod emulator;
pub mod fob;
pub mod gesture;
pub mod glove;
pub mod glove_grasp;
pub mod hid;
pub mod osc;
pub mod performer;
pub mod record;
pub mod space_move;
pub mod spacemouse;
