//! Performer actors: actors driven by a Flock of Birds (or OSC poses, or a VRPN tracker) and a CyberGlove
//! through the anatomical converter of thesis 6.4.1. The session's input phase puts what
//! their devices ask into the scene (`troupe_scene::InputPose`); the `capture` action of
//! troupe-actions makes them follow it.

pub(crate) mod controls;
pub(crate) mod controls_api;
pub(crate) mod converter;
pub(crate) mod glove_map;
pub(crate) mod lua;
pub(crate) mod options;
pub(crate) mod registry;
pub(crate) mod source;
pub(crate) mod vrpn;

pub use converter::{transmitter_to_world, AnatomicalConverter, ConverterError};
pub use glove_map::{glove_dof_names, nominal_glove_calibration, GloveMap};
pub use registry::{median_p99, Performer, Performers, SharedPerformers};
pub use source::SourceError;
