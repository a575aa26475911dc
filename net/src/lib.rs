//! troupe across machines over Zenoh (docs/distributed.md): a scene published tick by
//! tick under one key prefix, in a binary posture layout and JSON for the rest.
//!
//! - [`posture`]: the versioned binary layout of one actor's posture;
//! - [`keys`]: the key expressions under a prefix;
//! - [`relay`]: device byte streams served by `troupe relay` and read as ports;
//! - [`session`]: opening a Zenoh session with explicit endpoints, scouting off;
//! - [`publisher`]: the session observer that publishes without blocking the tick;
//! - [`follow`]: a second troupe replaying the leader's inputs and checking its postures;
//! - [`messages`]: `troupe.subscribe` over the network, into the scene's mailbox;
//! - [`subscriber`]: reading a published scene back (tools, tests, render nodes).
#![warn(missing_docs)]

pub mod error;
pub mod follow;
pub mod keys;
pub mod messages;
pub mod posture;
pub mod publisher;
pub mod relay;
pub mod session;
pub mod subscriber;

pub use error::NetError;
pub use keys::SceneKeys;
pub use messages::MessageInput;
pub use publisher::ScenePublisher;
pub use session::Endpoints;
pub use subscriber::{PoseFeed, PoseMessage};

/// The Zenoh crate this one is built on, for programs that talk to a scene directly.
pub use zenoh;
