//! The read-only view of a scene that generators see: every actor and object as they were
//! at the end of the previous tick.

use std::sync::Arc;
pub use troupe_body::object::Object;
use troupe_body::skeleton::Skeleton;
use troupe_body::state::ActorState;
use troupe_body::template::TemplateParams;

/// What does not change about an actor during a run.
#[derive(Clone, Debug)]
pub struct ActorInfo {
    /// Unique name in the scene.
    pub name: String,
    /// Template name.
    pub template: String,
    /// Template parameters.
    pub params: TemplateParams,
    /// The shared skeleton.
    pub skeleton: Arc<Skeleton>,
}

/// The scene at the end of the previous tick.
pub struct World<'a> {
    /// Scene time of that tick.
    pub time: f64,
    /// Every actor's fixed description, by actor index.
    pub actors: &'a [ActorInfo],
    /// Every actor's state, by actor index.
    pub states: &'a [ActorState],
    /// Every object, by object index.
    pub objects: &'a [Object],
    /// Who holds each object, by object index (see [`crate::holding`]).
    pub holders: &'a [Option<crate::holding::Holder>],
    /// The objects held, in object order, each with its holder.
    pub held: &'a [(usize, crate::holding::Holder)],
    /// What actions told one another up to the previous tick (see [`crate::blackboard`]).
    pub board: &'a crate::blackboard::Blackboard,
    /// What devices ask of each actor this tick, by actor index (see
    /// [`crate::input_pose`]); empty or `None` for actors no device drives.
    pub input_poses: &'a [Option<crate::input_pose::InputPose>],
    /// Walls and the walkable floor (see [`crate::space`]).
    pub space: &'a troupe_nav::Space,
    /// Per object: forced obstacle or not, `None` for "when it stands on the floor".
    pub obstacle_flags: &'a [Option<bool>],
    /// Every actor's floor position, velocity and radius, and the obstacles' footprints,
    /// as of the previous tick (see [`troupe_nav::Crowd`]).
    pub crowd: &'a troupe_nav::Crowd,
    /// Per actor: whether it has a walk that has not ended (pending, running or stopping),
    /// as of the start of this tick: a body whose root is still slow as it sets off, or
    /// turns on the spot, is walking all the same. Empty when nobody walks.
    pub walking: &'a [bool],
}

impl World<'_> {
    /// Whether actor `actor` has a walk that has not ended (see [`World::walking`]).
    pub fn walks(&self, actor: usize) -> bool {
        self.walking.get(actor).copied().unwrap_or(false)
    }

    /// The index of the actor called `name`.
    pub fn actor_index(&self, name: &str) -> Option<usize> {
        self.actors.iter().position(|a| a.name == name)
    }

    /// The index of the object called `name`.
    pub fn object_index(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }

    /// What devices ask of actor `actor`, if a device drives it.
    pub fn input_pose(&self, actor: usize) -> Option<&crate::input_pose::InputPose> {
        self.input_poses.get(actor).and_then(Option::as_ref)
    }

    /// Who holds object `object`, if anyone.
    pub fn holder(&self, object: usize) -> Option<crate::holding::Holder> {
        self.holders.get(object).copied().flatten()
    }
}
