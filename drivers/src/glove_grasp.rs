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
//! step (`troupe_scene::holding`), and the only cross-actor input, an offer from a
//! giver, is stamped by tick: the results are identical with any thread count.

use crate::cyberglove::decoder::{sensor_names, GloveLayout};
use crate::cyberglove::protocol::GloveConfig;
use crate::device::protocol::Mode;
use crate::record::error::RecordError;
use crate::record::writer::Recorder;
use std::sync::{Arc, Mutex};
use troupe_actions::grasp::{GraspAutomaton, HandDecision, HandState};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::sensors::Side;
use troupe_body::{Scope, Transform};
use troupe_scene::holding::HoldRequest;
use troupe_scene::{DofWriter, GeneratorContext, Object};

/// The glove hand cannot run this tick.
#[derive(Debug, thiserror::Error)]
pub enum GloveHandError {
    /// `step` before `start`.
    #[error("glove hand: not started")]
    NotStarted,
    /// The grasping automaton refused its input.
    #[error(transparent)]
    Automaton(#[from] troupe_actions::ActionError),
}

/// A glove script that cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum GloveScriptError {
    /// Neither 18 nor 22 sensors.
    #[error("glove script: sensors must be 18 or 22, got {0}")]
    Sensors(usize),
    /// A rate that is not a positive number.
    #[error("glove script: rate must be > 0 Hz, got {0}")]
    Rate(f64),
    /// No keys, or times that do not increase.
    #[error("glove script: keys must be non-empty with increasing times")]
    Times,
    /// A key with a non-finite time or a closure outside 0…1.
    #[error("glove script: key ({time}, {closure}) needs a finite time and a closure in 0…1")]
    Key {
        /// The key's time (s).
        time: f64,
        /// The key's closure.
        closure: f64,
    },
    /// The glove settings could not be encoded.
    #[error("{0}")]
    Settings(#[from] serde_json::Error),
    /// The recording could not be written.
    #[error(transparent)]
    Record(#[from] RecordError),
}

/// What Lua sees of a glove hand: the automaton's state and the object it concerns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HandStatus {
    /// The automaton's state after the last tick.
    pub state: HandState,
    /// Which hand.
    pub side: Side,
}

/// The automaton of one performer's glove hand, with its buffers.
pub struct GloveHand {
    side: Side,
    status: Arc<Mutex<HandStatus>>,
    automaton: Option<GraspAutomaton>,
    wrist: usize,
    q: Vec<f64>,
    globals: Vec<Transform>,
    desired: Vec<(usize, f64)>,
    objects: Vec<Object>,
}

impl GloveHand {
    /// The glove hand `side`; `status` is where its state is published.
    pub fn new(side: Side, status: Arc<Mutex<HandStatus>>) -> GloveHand {
        GloveHand {
            side,
            status,
            automaton: None,
            wrist: 0,
            q: Vec::new(),
            globals: Vec::new(),
            desired: Vec::new(),
            objects: Vec::new(),
        }
    }

    /// Builds the automaton from the posture the action starts in.
    pub fn start(&mut self, ctx: &GeneratorContext) -> Result<(), GloveHandError> {
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
    /// requests. Returns an error on inconsistent input (never panics).
    pub fn step(
        &mut self,
        ctx: &GeneratorContext,
        target: &[f64],
        mask: &[bool],
        out: &mut DofWriter,
    ) -> Result<(), GloveHandError> {
        let Some(a) = self.automaton.as_mut() else {
            return Err(GloveHandError::NotStarted);
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
                    from,
                });
            }
            Some(HandDecision::Release(o)) => out.request(HoldRequest::Release { object: o }),
            None => {}
        }
        if let Ok(mut s) = self.status.lock() {
            s.state = result.state;
        }
        Ok(())
    }
}

/// Writes a `.rec` file with one 18- or 22-sensor CyberGlove stream (streaming mode) that
/// opens and closes the hand along `keys`: (seconds, closure 0…1) pairs, interpolated
/// linearly, sampled at `rate` Hz. Every finger and thumb sensor reads `1 + 254·closure`
/// (0 to the DOF's upper limit through the nominal calibration); the wrist sensors stay
/// at 1 (wrist straight). A glove performance without hardware, for tests and examples.
pub fn write_glove_script(
    path: &std::path::Path,
    sensors: usize,
    rate: f64,
    keys: &[(f64, f64)],
) -> Result<(), GloveScriptError> {
    if sensors != 18 && sensors != 22 {
        return Err(GloveScriptError::Sensors(sensors));
    }
    if !(rate.is_finite() && rate > 0.0) {
        return Err(GloveScriptError::Rate(rate));
    }
    if keys.is_empty() || keys.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(GloveScriptError::Times);
    }
    if let Some(&(time, closure)) = keys
        .iter()
        .find(|k| !(k.0.is_finite() && (0.0..=1.0).contains(&k.1)))
    {
        return Err(GloveScriptError::Key { time, closure });
    }
    let config = GloveConfig {
        layout: GloveLayout {
            sensors,
            status_byte: false,
        },
        mode: Mode::Stream,
    };
    let settings = serde_json::to_value(config)?;
    let rec = Recorder::create(path)?;
    let stream = rec.add_stream("performer.glove", "cyberglove", settings);
    let names = sensor_names(sensors);
    let closure = |t: f64| {
        let i = keys.partition_point(|k| k.0 <= t);
        match i {
            0 => keys[0].1,
            i if i == keys.len() => keys[i - 1].1,
            i => {
                let (a, b) = (keys[i - 1], keys[i]);
                a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
            }
        }
    };
    let end = keys[keys.len() - 1].0;
    let count = (end * rate).round() as u64;
    for i in 0..=count {
        let t = i as f64 / rate;
        let k = closure(t);
        let mut bytes = vec![b'S'];
        for n in &names {
            let v = if n.starts_with("wrist") {
                1
            } else {
                (1.0 + 254.0 * k).round() as u8
            };
            bytes.push(v);
        }
        bytes.push(0);
        rec.data_at(stream, (t * 1e6).round() as u64, &bytes);
    }
    Ok(rec.finish()?)
}
