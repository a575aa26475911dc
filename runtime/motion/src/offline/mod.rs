//! Offline tools over whole sequences (thesis chapter 5): they run before or after a
//! scene, never inside a tick.

pub mod blend;
pub mod compress;
pub mod pyramid;
pub mod warp;
