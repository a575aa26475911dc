//! troupe's body model: the immutable, shared [`Skeleton`] built from a body template,
//! the flat per-actor [`ActorState`], and the pure algorithms over them (forward
//! kinematics, Jacobians, IK, self-collision, sensors, dynamics) and the skin that
//! covers the body.
//!
//! It follows Pinocchio's Model/Data split: a skeleton never changes once built, and every
//! algorithm reads it and writes only the state or workspace it is given.

#![warn(missing_docs)]

pub mod character;
pub mod collision;
pub mod dynamics;
pub mod error;
pub mod ik;
pub mod jacobian;
pub mod kinematics;
pub mod linalg;
pub mod math;
pub mod object;
pub mod scope;
pub mod self_collision;
pub mod sensors;
pub mod skeleton;
pub mod skin;
pub mod solid;
pub mod state;
pub mod template;
pub mod transform;

pub use character::{Character, Dressing};
pub use error::{Error, Result};
pub use glam;
pub use object::Object;
pub use scope::Scope;
pub use skeleton::{Dof, DofKind, Joint, Skeleton};
pub use skin::Skin;
pub use solid::{Shape, Solid};
pub use state::ActorState;
pub use template::{template, templates, Template, TemplateParams};
pub use transform::Transform;
