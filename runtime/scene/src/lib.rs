//! troupe's scene: actors and objects, their actions and the scheduler that admits,
//! steps and blends them tick by tick, the world snapshot generators read, holding, and
//! the observers that record a run.

#![warn(missing_docs)]

pub mod action;
pub mod blackboard;
pub mod blend;
pub mod bodies;
pub mod collision;
pub mod error;
pub mod holding;
pub mod input_pose;
pub mod mailbox;
pub mod pacing;
pub mod parallel;
pub mod playback;
pub mod profile;
pub mod record;
pub mod scene;
pub mod scheduler;
pub mod session;
pub mod space;
pub mod tally;
pub mod timeline;
pub mod world;

pub use action::{
    ActionId, ActionInfo, ActionSpec, DofWriter, Ending, Event, Generator, GeneratorContext, Mode,
    StartError, Status, Step,
};
pub use blackboard::{Blackboard, HandState, Note, Notes, Offer, SignalId};
pub use error::{Error, Result};
pub use input_pose::InputPose;
pub use mailbox::{Mailbox, Message};
pub use scene::{ActorDesc, Scene, SceneConfig};
pub use session::{Input, NoScript, Observer, ObserverHandle, RunLimit, Script, Session};
pub use world::{ActorInfo, Object, World};
