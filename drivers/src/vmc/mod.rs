//! The VMC protocol (Virtual Motion Capture, OSC over UDP; protocol.vmc.info): troupe's
//! actors sent to VRM avatars in Unity, Unreal, Blender and Godot, and VMC senders
//! (trackers, webcams, IMU suits) driving performers.
//!
//! `bones` maps VRM's humanoid bones onto the template's joints; `rig` turns postures into
//! VRM bone poses (Unity's frame, relative to the T-pose) and back; `message` builds and
//! reads the OSC bundles; `output` sends actors (`--vmc-out`, `troupe.vmc_out`);
//! `listener`, `jitter` and `input` receive a stream into a performer (`devices = { vmc
//! = … }`), live (UDP or a relay's key) or replayed; `stream` is a VMC stream in `.rec`
//! and the receiver clock; `emulator` sends a motion file as a VMC stream.

pub mod bones;
pub mod emulator;
pub mod input;
pub mod jitter;
pub mod listener;
pub(crate) mod lua;
pub mod message;
pub mod output;
pub mod rig;
pub mod stream;

pub use bones::{VrmBone, VRM_BONES};
pub use input::{VmcInput, VmcSource};
pub use listener::{Datagram, UdpDatagrams, VmcListener};
pub use message::{frame_bundle, read_datagram, VmcCounters, VmcPacket};
pub use output::{VmcOut, VmcStream, MARIONETTE_PORT};
pub use rig::{VmcPose, VmcRig};
