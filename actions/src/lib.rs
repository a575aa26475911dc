//! troupe's motion generators. Each module is one kind of ACTION's generator; each
//! generator writes only the DOFs of its action's scope.

pub mod keyframe;

pub use keyframe::Keyframe;
