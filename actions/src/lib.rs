//! troupe's motion generators, one folder per kind of ACTION: the generator, its options
//! (plain Rust, with `validate()`), and a `lua.rs` that reads those options from a script.
//! [`registry`] lists every kind for the Lua director. Each generator writes only the
//! DOFs of its action's scope.

#![warn(missing_docs)]

pub mod capture;
pub mod dynamics;
pub mod error;
pub mod grasp;
pub mod interact;
pub mod keyframe;
pub mod look_at;
pub mod manipulate;
pub mod reach;
#[cfg(feature = "lua")]
pub mod registry;
pub mod walk;

pub use capture::{Capture, CaptureOptions};
pub use dynamics::{DynamicsGenerator, DynamicsOptions};
pub use error::{ActionError, OptionError};
pub use keyframe::{Keyframe, KeyframeOptions};
pub use look_at::{LookAt, LookAtOptions};
pub use reach::{Reach, ReachOptions, ReachSpec, Reacher, Target};
#[cfg(feature = "lua")]
pub use registry::action_kinds;
pub use walk::{Walk, WalkOptions};
