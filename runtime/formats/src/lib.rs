//! troupe's file formats: BVH in and out, glTF in and out, the native `.trk` track file,
//! and retargeting between rigs.

pub mod bvh;
pub mod error;
pub mod gltf;
pub mod retarget;
pub mod rig;
pub mod trk;
pub mod urdf;

pub use error::{Error, Result};
pub use rig::Rig;
