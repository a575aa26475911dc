//! Grasping (thesis 4.2–4.3, 4.7): the decision table, grasp frames and planning, hand
//! motion patterns, finger closing against sphere sensors, the grasp/release/place
//! generators and the interactive grasping automaton.

pub mod action;
pub mod automaton;
pub mod body;
pub mod close;
pub mod decision;
pub mod follow;
pub mod handover;
pub mod keep;
#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;
pub mod pattern;
pub mod plan;

pub use action::{Grasp, Release};
pub use automaton::{AutomatonOutput, GraspAutomaton, HandDecision, HandState};
pub use close::HandModel;
pub use decision::{decide, Decision, GraspType};
pub use options::{GraspOptions, Place, ReleaseOptions};
pub use pattern::HandPattern;
pub use plan::{plan_grasp, GraspPlan, HandChoice, HandPlan, PlanOptions};
