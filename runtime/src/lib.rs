//! troupe's runtime: the model (skeleton templates, scopes, solids), the per-actor state,
//! actions and their scheduler, blending, kinematics, motion sequences and file formats.
//!
//! Everything here is independent of devices and rendering. Algorithms follow the
//! Model/Data split: an immutable, shared [`Skeleton`] and flat per-actor [`ActorState`].

pub mod action;
pub mod blend;
pub mod bvh;
pub mod compress;
pub mod dynamics;
pub mod error;
pub mod gltf;
pub mod gltf_import;
pub mod holding;
pub mod ik;
pub mod jacobian;
pub mod kinematics;
pub mod linalg;
pub mod lua;
pub mod pacing;
pub mod parallel;
pub mod profile;
pub mod pyramid;
pub mod record;
pub mod retarget;
pub mod scene;
pub mod scheduler;
pub mod scope;
pub mod self_collision;
pub mod sensors;
pub mod seqblend;
pub mod sequence;
pub mod skeleton;
pub mod solid;
pub mod state;
pub mod template;
pub mod timeline;
pub mod transform;
pub mod trk;
pub mod warp;
pub mod world;

pub use action::{
    ActionId, ActionInfo, ActionSpec, DofWriter, Event, Generator, GeneratorContext, Mode, Status,
    Step,
};
pub use error::{Error, Result};
pub use glam;
pub use scene::{ActorDesc, Scene, SceneConfig};
pub use scope::Scope;
pub use sequence::{Key, Sequence, Track};
pub use skeleton::{Dof, DofKind, Joint, Skeleton};
pub use solid::{Shape, Solid};
pub use state::ActorState;
pub use template::{template, templates, Template, TemplateParams};
pub use transform::Transform;
pub use world::{ActorInfo, Object, World};
