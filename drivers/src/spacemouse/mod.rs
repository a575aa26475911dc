//! The 3Dconnexion SpaceMouse family over USB HID: the device table and report decoding,
//! the protocol the device thread runs, and access through hidapi. The SpaceMouse has no
//! byte-level serial protocol, so no pty emulator: tests feed hand-built reports through a
//! fake port or a `.rec` file.

pub(crate) mod decoder;
pub(crate) mod hid;
pub(crate) mod protocol;

pub use decoder::{
    apply_report, kind_of_report, lookup, ReportError, ReportKind, SpaceMouseState, FULL_SCALE,
    PRODUCTS, VENDORS,
};
pub use hid::{hid_devices, open_spacemouse, read_spacemouse, HidInfo, HidPort};
pub use protocol::SpaceMouseProtocol;
