//! Device drivers for troupe: Flock of Birds and CyberGlove over serial ports, SpaceMouse
//! over HID, VRPN servers over the network, emulators on pseudo-terminals, and record/replay of device streams.
//!
//! Protocol facts are those of `shared/reference/devices.md`; thesis sections 2.7, 4.7 and
//! 6.4.1 describe how the devices drive performer actors.
//!
//! One folder per device (`fob`, `cyberglove`, `spacemouse`: commands, decoder, protocol,
//! emulator), the framework they share (`device`: the thread, its channel, health,
//! reconnection), `emulator` (ptys and motion), `record` (`.rec` files), `osc`, and what
//! the devices drive: `performer` actors and `space_move`'s objects.

#![warn(missing_docs)]

pub mod cyberglove;
pub mod device;
pub mod emulator;
pub mod fob;
pub mod gesture;
pub mod lua;
pub mod osc;
pub mod performer;
pub mod record;
pub mod space_move;
pub mod spacemouse;
pub mod vmc;
pub mod vrpn;
