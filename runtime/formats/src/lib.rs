//! troupe's file formats: the native `.trk` track file, BVH and glTF in and out, URDF
//! out, retargeting BVH motion onto troupe bodies, and the one [`Rig`] type the skeletal
//! formats share.
//!
//! Callers that hold a path choose nothing themselves: [`load_sequences`] /
//! [`load_sequence`] and [`save_sequences`] pick the format by extension ([`dispatch`]).

#![warn(missing_docs)]

pub mod bvh;
pub mod character;
pub mod dispatch;
pub mod error;
pub mod gltf;
pub mod retarget;
pub mod rig;
pub mod trk;
pub mod urdf;

pub use dispatch::{
    load_sequence, load_sequences, save_character, save_dressed_recording, save_recording,
    save_rig, save_sequences, save_skinned, Format,
};
pub use error::{Error, Result};
pub use rig::Rig;
