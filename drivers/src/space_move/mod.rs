//! Moving a scene object with a SpaceMouse: the mover (deflection to velocity, frames,
//! integration, the input phase) and its Lua API.

pub(crate) mod lua;
pub(crate) mod mover;

pub use mover::{
    deadzoned, device_to_scene, integrate, velocity, MoveOptions, SharedSpaceMice, SpaceMice,
};
