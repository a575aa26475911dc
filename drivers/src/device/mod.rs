//! The device framework every driver shares: a thread per device that owns its port,
//! decodes through the device's [`Protocol`], and sends timestamped [`Sample`]s over a
//! bounded channel; a [`Health`] with counters; reconnection with backoff (DESIGN.md,
//! "Drivers").

pub(crate) mod error;
pub(crate) mod health;
pub(crate) mod port;
pub(crate) mod protocol;
pub(crate) mod reading;
pub(crate) mod remote;
pub(crate) mod thread;

pub use error::DeviceError;
pub use health::{Health, HealthReport, HealthState};
pub use port::{open_serial, serial_ports, Port, SerialInfo};
pub use protocol::{Mode, Protocol};
pub use reading::{Reading, Sample};
pub use remote::{RemoteOpen, RemotePorts};
pub use thread::{spawn, spawn_with, DeviceHandle, DriverOptions, Opener};
