//! troupe's motion generators. Each module is one kind of ACTION's generator; each
//! generator writes only the DOFs of its action's scope.

pub mod dynamics;
pub mod grasp;
pub mod interact;
pub mod keyframe;
pub mod kinds;
pub mod look_at;
pub mod manipulate;
pub mod reach;
pub mod walk;

pub use dynamics::DynamicsGenerator;
pub use keyframe::Keyframe;
pub use kinds::action_kinds;
pub use look_at::LookAt;
pub use reach::{Reach, ReachSpec, Target};
pub use walk::{Walk, WalkOptions};
