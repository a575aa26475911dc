//! The performers of a scene: each one's devices and capture target, the session input
//! that drains the devices every tick, and the latency of the samples used.
//!
//! Each tick, before the scripts run, the input phase drains every device's samples into
//! its performer (the latest pose of each bird, the latest glove record), converts them into
//! target DOF values, and notes gesture events. The `capture` action's generator then writes
//! those targets in the same tick, so a sample is in the posture of the tick that follows
//! its arrival: latency is at most one tick.

use crate::cyberglove::decoder::GloveRecord;
use crate::device::health::HealthReport;
use crate::device::reading::Reading;
use crate::fob::pose::bird_pose;
use crate::osc::message::OscInput;
use crate::performer::source::{FobInput, GloveInput, OscPoses};
use crate::performer::vrpn::VrpnInput;
use crate::record::writer::Recorder;
use mlua::Function;
use std::sync::{Arc, Mutex};
use std::time::Instant;
use troupe_body::skeleton::Skeleton;
use troupe_body::Scope;
use troupe_scene::{Input, InputPose, Scene};

/// One performer.
pub struct Performer {
    /// Name (the actor's).
    pub name: String,
    /// Actor index.
    pub actor: usize,
    /// The actor's skeleton.
    pub(crate) skeleton: Arc<Skeleton>,
    /// Body poses from a Flock of Birds.
    pub(crate) fob: Option<FobInput>,
    /// Body poses over OSC.
    pub(crate) osc: Option<OscPoses>,
    /// Body poses (and controls) from a VRPN tracker.
    pub(crate) vrpn: Option<VrpnInput>,
    /// The glove hand.
    pub(crate) glove: Option<GloveInput>,
    /// Body poses from a VMC sender.
    pub(crate) vmc: Option<crate::vmc::VmcInput>,
    /// Calibrate as soon as every bird has a sample.
    pub(crate) auto_calibrate: bool,
    /// `troupe.devices.calibrate` asked for a calibration at the next sample.
    pub(crate) calibrate_requested: bool,
    /// The input phase (by count) that last set the performer's pose in the scene.
    pub(crate) made: u64,
    /// Every DOF the devices can drive (the natural scope of `capture`).
    pub(crate) driven: Scope,
    /// `troupe.devices.on_gesture` handlers.
    pub(crate) gesture_handlers: Vec<Function>,
}

impl Performer {
    /// The glove's hand targets in `pose` as (DOF index, radians); none without a glove.
    pub(crate) fn hand_target(&self, pose: &InputPose) -> Vec<(usize, f64)> {
        let Some(g) = &self.glove else {
            return Vec::new();
        };
        g.map
            .all_dofs()
            .filter_map(|d| pose.target(d).map(|v| (d, v)))
            .collect()
    }
}

/// Every performer of a scene, the recorder, and latency measurements.
#[derive(Default)]
pub struct Performers {
    /// The performers, in creation order.
    pub(crate) list: Vec<Performer>,
    /// Records every live device stream (`--record-devices`).
    pub(crate) recorder: Option<Arc<Recorder>>,
    ticks: u64,
    /// Gesture events of the last input phase (handler, performer, new gesture, previous),
    /// called by the director at the start of its script phase.
    pub(crate) gesture_events: Vec<GestureEvent>,
    /// Arrival instants of samples used by the targets made this tick, for latency.
    pending_latency: Vec<Instant>,
    /// Arrival-to-posture latencies (seconds) of every live sample used, measured when the
    /// tick that used it has finished stepping (see [`Performers::end_tick`]).
    pub latencies: Vec<f64>,
}

/// A gesture handler to call: the handler, the performer, the new and the previous gesture.
pub(crate) type GestureEvent = (Function, String, String, Option<String>);

/// Lua app data: the shared performers.
#[derive(Clone)]
pub struct SharedPerformers(pub Arc<Mutex<Performers>>);

impl Performers {
    /// No performers yet; `recorder` records their live device streams.
    pub fn new(recorder: Option<Arc<Recorder>>) -> Performers {
        Performers {
            recorder,
            ..Performers::default()
        }
    }

    /// Ends a tick: the samples used this tick are now in a posture; records their latency.
    pub fn end_tick(&mut self) {
        let now = Instant::now();
        for a in self.pending_latency.drain(..) {
            self.latencies.push(now.duration_since(a).as_secs_f64());
        }
    }

    /// The glove's hand targets of a performer as (DOF index, radians), from its pose in
    /// `scene`: what a grasp corrector takes instead of letting `capture` write the hand.
    pub fn hand_target(&self, performer: &str, scene: &Scene) -> Option<Vec<(usize, f64)>> {
        let p = self.list.iter().find(|p| p.name == performer)?;
        Some(p.hand_target(scene.input_pose(p.actor)?))
    }

    /// The latest raw glove values of a performer.
    pub fn glove_raw(&self, performer: &str) -> Option<Vec<u8>> {
        self.list
            .iter()
            .find(|p| p.name == performer)?
            .glove
            .as_ref()?
            .latest
            .clone()
    }

    /// The input phase (counted from 1) that last set performer `i`'s pose in the scene
    /// (0: none yet); compare with the scene's tick for latency.
    pub fn made(&self, i: usize) -> Option<u64> {
        self.list.get(i).map(|p| p.made)
    }

    /// Health of every live device: (performer, device, report).
    pub fn health(&self) -> Vec<(String, &'static str, HealthReport)> {
        let mut v = Vec::new();
        for p in &self.list {
            if let Some(h) = p.fob.as_ref().and_then(|f| f.source.health()) {
                v.push((p.name.clone(), "fob", h));
            }
            if let Some(h) = p.glove.as_ref().and_then(|g| g.source.health()) {
                v.push((p.name.clone(), "glove", h));
            }
            if let Some(o) = &p.osc {
                v.push((p.name.clone(), "osc", o.listener.health.report()));
            }
            if let Some(h) = p.vrpn.as_ref().and_then(|v| v.health()) {
                v.push((p.name.clone(), "vrpn", h));
            }
            if let Some(h) = p.vmc.as_ref().and_then(|m| m.health()) {
                v.push((p.name.clone(), "vmc", h));
            }
        }
        v
    }

    /// The input phase: drain, convert, note gestures. Returns the gesture events
    /// (handlers, performer name, new, previous) for the script phase to call.
    fn drain(&mut self, scene: &mut Scene) -> Vec<GestureEvent> {
        self.ticks += 1;
        let mut events = Vec::new();
        let (tick, time) = (scene.tick(), scene.time());
        for p in &mut self.list {
            let mut changed = false;
            let mut newest: Option<Instant> = None;
            if let Some(f) = &mut p.fob {
                for (r, at) in f.source.take(tick, time) {
                    if let Reading::Bird(b) = r {
                        // An all-zero quaternion or matrix decodes, but is no rotation:
                        // such a record is skipped rather than turned into NaN joints.
                        let (position, rotation) = bird_pose(&b);
                        if !(position.is_finite() && rotation.is_finite()) {
                            continue;
                        }
                        f.latest.insert(b.address, (position, rotation));
                        changed = true;
                        newest = newest.max(at);
                    }
                }
                let all = f.converter.birds().iter().all(|a| f.latest.contains_key(a));
                if all
                    && (p.calibrate_requested || (p.auto_calibrate && !f.converter.is_calibrated()))
                {
                    let base = base_posture(scene, p.actor);
                    if let Err(e) = f.converter.calibrate(&base, &f.latest) {
                        tracing::warn!(performer = %p.name, "{e}");
                    }
                    p.calibrate_requested = false;
                }
            }
            if let Some(v) = &mut p.vrpn {
                let (got, at) = v.take(tick, time);
                changed |= got;
                newest = newest.max(at);
                let all = v.converter.birds().iter().all(|a| v.latest.contains_key(a));
                if all
                    && (p.calibrate_requested || (p.auto_calibrate && !v.converter.is_calibrated()))
                {
                    let base = base_posture(scene, p.actor);
                    if let Err(e) = v.converter.calibrate(&base, &v.latest) {
                        tracing::warn!(performer = %p.name, "{e}");
                    }
                    p.calibrate_requested = false;
                }
            }
            let mut osc_glove = Vec::new();
            if let Some(o) = &mut p.osc {
                for (at, input) in o.listener.inputs.try_iter() {
                    match input {
                        OscInput::Pose {
                            performer,
                            joint,
                            position,
                            rotation,
                        } if performer == p.name => {
                            match o.joints.iter().find(|(n, _)| *n == joint) {
                                Some((_, a)) => {
                                    o.latest.insert(*a, (position, rotation));
                                    changed = true;
                                    newest = newest.max(Some(at));
                                }
                                None => {
                                    let listed: Vec<&str> =
                                        o.joints.iter().map(|(n, _)| n.as_str()).collect();
                                    o.listener.refuse(format!(
                                        "/troupe/{performer}/{joint}: '{joint}' is not one of \
                                         the performer's OSC joints ({})",
                                        listed.join(", ")
                                    ));
                                }
                            }
                        }
                        OscInput::Glove { performer, raw } if performer == p.name => {
                            // Values for every sensor of this glove, or none taken.
                            let sensors = p.glove.as_ref().map(|g| g.calibration.sensors.len());
                            if sensors != Some(raw.len()) {
                                o.listener.refuse(match sensors {
                                    Some(n) => format!(
                                        "/troupe/{performer}/glove: {} values for a glove of \
                                         {n} sensors",
                                        raw.len()
                                    ),
                                    None => format!(
                                        "/troupe/{performer}/glove: the performer has no glove"
                                    ),
                                });
                                continue;
                            }
                            osc_glove.push((
                                Reading::Glove(GloveRecord {
                                    command: b'S',
                                    raw,
                                    status: None,
                                }),
                                Some(at),
                            ));
                        }
                        _ => {}
                    }
                }
                if !o.converter.is_calibrated() {
                    o.converter.calibrate_direct(&base_posture(scene, p.actor));
                }
            }
            if let Some(v) = &mut p.vmc {
                let now = &scene.states()[p.actor].q;
                if let Some(played) = v.poll(tick, time, now) {
                    changed = true;
                    newest = newest.max(played.arrived);
                }
            }
            if let Some(g) = &mut p.glove {
                let mut readings = g.source.take(tick, time);
                readings.extend(osc_glove);
                for (r, at) in readings {
                    if let Reading::Glove(rec) = r {
                        if let Some(tr) = &mut g.gestures {
                            if let Some((new, old)) = tr.feed(&rec.raw) {
                                for h in &p.gesture_handlers {
                                    events.push((
                                        h.clone(),
                                        p.name.clone(),
                                        new.clone(),
                                        old.clone(),
                                    ));
                                }
                            }
                        }
                        g.latest = Some(rec.raw);
                        changed = true;
                        newest = newest.max(at);
                    }
                }
            }
            if !changed {
                continue;
            }
            let n = p.skeleton.dof_count();
            let mut q = base_posture(scene, p.actor);
            let mut mask = vec![false; n];
            if let Some(f) = &mut p.fob {
                f.converter.convert(&f.latest, &mut q, &mut mask);
            }
            if let Some(o) = &mut p.osc {
                o.converter.convert(&o.latest, &mut q, &mut mask);
            }
            if let Some(v) = &mut p.vrpn {
                v.converter.convert(&v.latest, &mut q, &mut mask);
            }
            if let Some(v) = &p.vmc {
                v.apply(&mut q, &mut mask);
            }
            if let Some(g) = &p.glove {
                if let Some(raw) = &g.latest {
                    let angles = g.calibration.angles(raw);
                    g.map.apply(&p.skeleton, &angles, &mut q, &mut mask);
                }
            }
            let pose = InputPose {
                q,
                mask,
                driven: p.driven,
            };
            if let Err(e) = scene.set_input_pose(p.actor, pose) {
                tracing::error!(performer = %p.name, "{e}");
            }
            p.made = self.ticks;
            if let Some(a) = newest {
                self.pending_latency.push(a);
            }
        }
        events
    }
}

/// The actor's reference posture for calibration: every DOF zero but its place and facing.
fn base_posture(scene: &Scene, actor: usize) -> Vec<f64> {
    let sk = &scene.actors()[actor].skeleton;
    let now = &scene.states()[actor].q;
    let mut q = vec![0.0; sk.dof_count()];
    for name in ["root_x", "root_z", "root_yaw"] {
        if let Ok(d) = sk.dof(name) {
            q[d] = now[d];
        }
    }
    q
}

/// Drains every performer's devices into its capture target (the session's input phase).
pub(crate) struct PerformerInput(pub(crate) SharedPerformers);

impl Input for PerformerInput {
    fn name(&self) -> String {
        "performers".into()
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        let mut performers = self.0 .0.lock().map_err(|_| troupe_scene::Error::Input {
            input: "performers".into(),
            message: "lock poisoned by a panic".into(),
        })?;
        let events = performers.drain(scene);
        performers.gesture_events.extend(events);
        Ok(())
    }
}

/// Median and 99th percentile of a list of seconds.
pub fn median_p99(v: &[f64]) -> Option<(f64, f64)> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let at = |p: f64| s[((s.len() - 1) as f64 * p).round() as usize];
    Some((at(0.5), at(0.99)))
}
