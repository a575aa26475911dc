//! The glove hand through the grasping automaton (thesis 4.7, with the capture of 6.4.1):
//! a performer's glove gives the *desired* finger values; the automaton moves the fingers
//! toward them but stops each finger DOF at contact, so the virtual fingers never enter an
//! object even when the real hand closes further, and decides when the object is securely
//! grasped (attach: it follows the wrist) or let go (release).
//!
//! Runs inside the `capture` generator every tick, on the posture the capture writes this
//! tick (the device targets over the last tick's posture, then forward kinematics), so
//! the wrist the fingers are checked against is the one the tick will show. Objects the
//! performer holds are moved with that wrist before the check; others are at their last
//! tick's pose. Hold requests go through the writer and are applied after the parallel
//! step (`troupe_scene::holding`); the only cross-actor input, an offer from a giver, and
//! the automaton's state it reports are on the scene's blackboard: the results are
//! identical with any thread count.

use crate::error::{ActionError, Result};
use crate::grasp::{GraspAutomaton, HandDecision};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::sensors::Side;
use troupe_body::{Scope, Transform};
use troupe_scene::holding::HoldRequest;
use troupe_scene::{DofWriter, GeneratorContext, Note, Object};

/// The automaton of one performer's glove hand, with its buffers.
pub struct GloveHand {
    side: Side,
    automaton: Option<GraspAutomaton>,
    wrist: usize,
    q: Vec<f64>,
    globals: Vec<Transform>,
    desired: Vec<(usize, f64)>,
    objects: Vec<Object>,
}

impl GloveHand {
    /// The glove hand `side`.
    pub fn new(side: Side) -> GloveHand {
        GloveHand {
            side,
            automaton: None,
            wrist: 0,
            q: Vec::new(),
            globals: Vec::new(),
            desired: Vec::new(),
            objects: Vec::new(),
        }
    }

    /// Builds the automaton from the posture the action starts in.
    pub fn start(&mut self, ctx: &GeneratorContext) -> Result<()> {
        let a = GraspAutomaton::new(ctx.skeleton, self.side, &ctx.posture.q)?;
        self.wrist = a.model().sensors.wrist;
        self.automaton = Some(a);
        Ok(())
    }

    /// The hand's finger DOFs (those the automaton writes).
    pub fn fingers(&self) -> Scope {
        self.automaton
            .as_ref()
            .map(|a| a.model().sensors.scope)
            .unwrap_or(Scope::EMPTY)
    }

    /// One tick: `target`/`mask` are the device targets. Writes the corrected finger
    /// values within the writer's scope and turns the automaton's decisions into hold
    /// requests, and posts the automaton's state on the blackboard. Returns an error on
    /// inconsistent input (never panics).
    pub fn step(
        &mut self,
        ctx: &GeneratorContext,
        target: &[f64],
        mask: &[bool],
        out: &mut DofWriter,
    ) -> Result<()> {
        let Some(a) = self.automaton.as_mut() else {
            return Err(ActionError::Unfit("glove hand: not started".into()));
        };
        let sk = ctx.skeleton;
        let fingers = a.model().sensors.scope;
        // This tick's posture: the device targets the capture writes, over the last tick.
        self.q.clear();
        self.q.extend_from_slice(&ctx.posture.q);
        let scope = out.scope();
        for d in scope.iter() {
            if mask.get(d).copied().unwrap_or(false) {
                if let Some(&v) = target.get(d) {
                    self.q[d] = sk.dofs()[d].clamp(v);
                }
            }
        }
        self.globals.clear();
        self.globals.resize(sk.joints().len(), Transform::IDENTITY);
        forward_kinematics(sk, &self.q, &mut self.globals);
        self.desired.clear();
        for d in fingers.iter() {
            if mask.get(d).copied().unwrap_or(false) {
                if let Some(&v) = target.get(d) {
                    self.desired.push((d, v));
                }
            }
        }
        // Objects as they will be this tick: what this performer holds follows its joint.
        self.objects.clear();
        self.objects.extend_from_slice(ctx.world.objects);
        for (i, o) in self.objects.iter_mut().enumerate() {
            if let Some(h) = ctx.world.holder(i).filter(|h| h.actor == ctx.actor) {
                if let Some(frame) = self.globals.get(h.joint) {
                    let pose = frame.mul(&h.grip);
                    o.position = pose.translation;
                    o.rotation = pose.rotation.normalize();
                }
            }
        }
        let result = a.update(sk, &self.q, &self.globals, &self.desired, &self.objects)?;
        for &(d, v) in &result.values {
            if scope.contains(d) {
                out.set(d, v);
            }
        }
        match result.decision {
            Some(HandDecision::Attach(o)) => {
                // Taking an object out of another hand is allowed only while it is offered
                // to this performer (`give{to = performer}`); otherwise the scene ignores
                // the request and the holder keeps it.
                let from = match ctx.world.holder(o) {
                    Some(h) if h.actor != ctx.actor => ctx
                        .world
                        .board
                        .may_take(o, ctx.actor, h.actor, ctx.tick)
                        .then_some(h.actor),
                    _ => None,
                };
                out.request(HoldRequest::Attach {
                    object: o,
                    joint: self.wrist,
                    also: None,
                    from,
                });
            }
            Some(HandDecision::Release(o)) => out.request(HoldRequest::Release { object: o }),
            None => {}
        }
        out.post(Note::Hand(result.state));
        Ok(())
    }
}
