//! troupe's motion: sequences of per-DOF Hermite tracks, sampled at run time by the
//! keyframe action, and apart from them the offline tools of thesis chapter 5 that make
//! and edit sequences ([`offline`]).

#![warn(missing_docs)]

pub mod error;
pub mod object_motion;
pub mod offline;
pub mod sequence;

pub use error::{Error, Result};
pub use object_motion::{Hold, ObjectMotion};
pub use sequence::{Interpolation, Key, Sequence, Track};
