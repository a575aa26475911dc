//! The `capture` action (thesis 6.4.1 with 4.7): a performer's actor follows its devices.
//! The session's input phase puts what the devices ask into the scene
//! ([`troupe_scene::InputPose`]); each tick the generator writes those targets within its
//! scope, and the glove hand's fingers go through the grasping automaton ([`glove`]).
//! Nothing is shared with the drivers but the scene itself.

pub mod glove;
#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;

pub use glove::GloveHand;
pub use options::CaptureOptions;

use troupe_body::Scope;
use troupe_scene::{DofWriter, Generator, GeneratorContext, StartError, Step};

/// The `capture` generator: writes the actor's device targets within its scope; the glove
/// hand's fingers go through the grasping automaton when the scope covers them.
pub struct Capture {
    hand: Option<GloveHand>,
}

impl Capture {
    /// A capture; `hand` runs the automaton on a device-driven hand.
    pub fn new(hand: Option<GloveHand>) -> Capture {
        Capture { hand }
    }
}

impl Generator for Capture {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        match &mut self.hand {
            Some(h) => Ok(h.start(ctx)?),
            None => Ok(()),
        }
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        // Before the devices' first samples there is nothing to follow yet.
        let Some(pose) = ctx.world.input_pose(ctx.actor) else {
            return Step::Running;
        };
        let fingers = self
            .hand
            .as_ref()
            .map(|h| h.fingers())
            .unwrap_or(Scope::EMPTY);
        for d in out.scope().iter() {
            if fingers.contains(d) {
                continue;
            }
            if let Some(v) = pose.target(d) {
                out.set(d, v);
            }
        }
        if let Some(h) = &mut self.hand {
            if let Err(e) = h.step(ctx, &pose.q, &pose.mask, out) {
                return Step::Failed(format!("capture: {e}"));
            }
        }
        Step::Running
    }
}
