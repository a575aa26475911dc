//! Performer actors: actors driven by a Flock of Birds and a CyberGlove through the
//! anatomical converter of thesis 6.4.1.
//!
//! Each tick, before the scripts run, the pre-tick step drains every device's samples into
//! its performer (the latest pose of each bird, the latest glove record), converts them into
//! target DOF values, and fires gesture events. The `capture` action's generator then writes
//! those targets in the same tick, so a sample is in the posture of the tick that follows
//! its arrival: latency is at most one tick.

use crate::driver::{
    self, DeviceHandle, DriverOptions, FobConfig, FobProtocol, GloveConfig, GloveProtocol,
    HealthReport, Mode, Reading,
};
use crate::emulator::bird_pose;
use crate::fob::{Hemisphere, OutputFormat, PositionRange};
use crate::gesture::{GestureSet, GestureTracker};
use crate::glove::{GloveCalibration, GloveLayout};
use crate::glove_grasp::{GloveHand, HandStatus};
use crate::osc::{OscInput, OscListener};
use crate::record::{Recorder, Recording};
use glam::{DMat3, DQuat, DVec3};
use mlua::{Function, Lua, MultiValue, Table, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use troupe_actions::grasp::handover::SharedHandBoard;
use troupe_actions::grasp::HandState;
use troupe_body::ik::{IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::Effector;
use troupe_body::kinematics::{forward_kinematics, solve_joint_angles};
use troupe_body::sensors::Side;
use troupe_body::skeleton::{DofKind, Skeleton};
use troupe_body::transform::Transform;
use troupe_body::Scope;
use troupe_lua::api::{lua_err_message, ActorRef};
use troupe_lua::kinds::{ActionKind, ActionKinds, BuildContext, CommonOptions};
use troupe_lua::LuaSession;
use troupe_scene::action::{ActionSpec, DofWriter, Generator, GeneratorContext, Step};
use troupe_scene::{Input, Scene};

/// The rotation from the Flock's transmitter frame (X forward, Y right, Z down) to the
/// scene's frame (Y up, an actor facing 0° looks along +Z, its right is −X).
pub fn transmitter_to_world() -> DQuat {
    DQuat::from_mat3(&DMat3::from_cols(DVec3::Z, -DVec3::X, -DVec3::Y))
}

/// Joint-name aliases accepted in a performer's bird map.
fn joint_alias(name: &str) -> &str {
    match name {
        "pelvis" | "root" => "HumanoidRoot",
        "head" => "skullbase",
        other => other,
    }
}

/// Thesis 6.4.1's anatomical converter: sensor orientations (and the root sensor's
/// position) to the joint rotations of the template, after a calibration in a known pose.
pub struct AnatomicalConverter {
    skeleton: Arc<Skeleton>,
    frame: DQuat,
    /// (joint, bird address), joints in increasing index order (parents first).
    map: Vec<(usize, u8)>,
    /// Per map entry: an IK solver over the rotation DOFs of the joints without a sensor
    /// between the entry's joint and its nearest mapped ancestor (e.g. shoulder and elbow
    /// for a wrist sensor under a chest sensor), or `None` when the parent is mapped.
    ik: Vec<Option<IkSolver>>,
    /// The previous conversion's IK DOF values: each solve starts from them (continuity,
    /// and a few iterations instead of a solve from rest).
    warm: Option<Vec<f64>>,
    calibration: Option<Calibration>,
}

#[derive(Clone, Debug)]
struct Calibration {
    /// Transmitter origin in the scene frame, estimated at calibration.
    origin: DVec3,
    /// Per map entry: the joint's origin relative to its sensor, in the sensor's frame.
    levers: Vec<DVec3>,
    base_q: Vec<f64>,
    /// Bird pose (world frame) at calibration, per map entry.
    sensor0: Vec<(DVec3, DQuat)>,
    /// Sensor-to-segment offset per map entry: segment = sensor × offset.
    offsets: Vec<DQuat>,
}

impl AnatomicalConverter {
    /// A converter for `map` (joint name → bird address); errors name unknown joints.
    pub fn new(
        skeleton: Arc<Skeleton>,
        map: &[(String, u8)],
        frame: DQuat,
    ) -> Result<AnatomicalConverter, String> {
        let mut m = Vec::new();
        for (name, addr) in map {
            let j = skeleton
                .joint(joint_alias(name))
                .map_err(|_| format!("no joint '{name}' in the template (e.g. pelvis, sacroiliac, vl5, skullbase, r_shoulder, r_elbow, r_wrist)"))?;
            if m.iter().any(|&(jj, _)| jj == j) {
                return Err(format!("joint '{name}' is mapped twice"));
            }
            m.push((j, *addr));
        }
        m.sort_by_key(|&(j, _)| j);
        let mapped: Vec<usize> = m.iter().map(|&(j, _)| j).collect();
        let mut ik = Vec::with_capacity(m.len());
        for &(j, _) in &m {
            let mut dofs = Vec::new();
            let mut a = skeleton.joints()[j].parent;
            while let Some(p) = a {
                if mapped.contains(&p) {
                    break;
                }
                let joint = &skeleton.joints()[p];
                if joint.parent.is_none() {
                    // The root's DOFs move the whole body: never solved for a limb.
                    break;
                }
                dofs.extend(
                    joint
                        .dofs
                        .clone()
                        .filter(|&d| skeleton.dofs()[d].kind == DofKind::Rotation),
                );
                a = joint.parent;
            }
            ik.push(if dofs.is_empty() {
                None
            } else {
                Some(
                    IkSolver::new(
                        &skeleton,
                        dofs,
                        // Warm-started every frame: a few iterations follow the motion; the
                        // cap bounds a tick's cost when a sensor is out of reach.
                        IkOptions {
                            max_iterations: 30,
                            ..IkOptions::default()
                        },
                    )
                    .map_err(|e| e.to_string())?,
                )
            });
        }
        Ok(AnatomicalConverter {
            skeleton,
            frame,
            map: m,
            ik,
            warm: None,
            calibration: None,
        })
    }

    /// Bird addresses the converter needs.
    pub fn birds(&self) -> Vec<u8> {
        self.map.iter().map(|&(_, a)| a).collect()
    }

    /// Whether a calibration has been taken.
    pub fn is_calibrated(&self) -> bool {
        self.calibration.is_some()
    }

    fn world(&self, pose: (DVec3, DQuat)) -> (DVec3, DQuat) {
        (
            self.frame * pose.0,
            (self.frame * pose.1 * self.frame.inverse()).normalize(),
        )
    }

    /// Calibrates: the performer stands in the posture `base_q` (the template's reference
    /// pose at the actor's place) while the birds read `poses`. The sensor-to-segment offset
    /// of each mapped segment is the rotation that takes the sensor's orientation to the
    /// segment's (thesis 6.4.1: "a simple calibration").
    pub fn calibrate(
        &mut self,
        base_q: &[f64],
        poses: &BTreeMap<u8, (DVec3, DQuat)>,
    ) -> Result<(), String> {
        let mut globals = vec![Transform::IDENTITY; self.skeleton.joints().len()];
        forward_kinematics(&self.skeleton, base_q, &mut globals);
        let mut sensor0 = Vec::new();
        let mut offsets = Vec::new();
        for &(j, addr) in &self.map {
            let pose = poses
                .get(&addr)
                .ok_or_else(|| format!("calibration: no sample from bird {addr} yet"))?;
            let (p, q) = self.world(*pose);
            offsets.push(q.inverse() * globals[j].rotation);
            sensor0.push((p, q));
        }
        // Sensors sit close to their joints, so the mean of (joint − sensor) estimates where
        // the transmitter is in the scene; what remains per sensor is its small lever.
        let n = self.map.len().max(1) as f64;
        let origin = self
            .map
            .iter()
            .zip(&sensor0)
            .map(|(&(j, _), s)| globals[j].translation - s.0)
            .sum::<DVec3>()
            / n;
        let levers = self
            .map
            .iter()
            .zip(&sensor0)
            .map(|(&(j, _), s)| s.1.inverse() * (globals[j].translation - (s.0 + origin)))
            .collect();
        self.warm = None;
        self.calibration = Some(Calibration {
            origin,
            levers,
            base_q: base_q.to_vec(),
            sensor0,
            offsets,
        });
        Ok(())
    }

    /// Calibrates for sources that already give segment poses in the scene frame (OSC):
    /// no offset, no lever; the root goes where its pose says.
    pub fn calibrate_direct(&mut self, base_q: &[f64]) {
        let mut globals = vec![Transform::IDENTITY; self.skeleton.joints().len()];
        forward_kinematics(&self.skeleton, base_q, &mut globals);
        let k = self.map.len();
        self.warm = None;
        self.calibration = Some(Calibration {
            origin: DVec3::ZERO,
            levers: vec![DVec3::ZERO; k],
            base_q: base_q.to_vec(),
            sensor0: self
                .map
                .iter()
                .map(|&(j, _)| (globals[j].translation, DQuat::IDENTITY))
                .collect(),
            offsets: vec![DQuat::IDENTITY; k],
        });
    }

    /// Converts the latest bird poses into DOF values: `q` starts from the calibration
    /// posture; the root joint's translation follows its bird's displacement; each mapped
    /// joint's rotation DOFs are solved (parents first) so that its segment has the sensor's
    /// orientation times the offset. Joints without a sensor between a mapped joint and its
    /// nearest mapped ancestor are solved by IK so that the mapped joint reaches its sensor's
    /// position (sensor + lever); other joints keep their calibration values.
    /// Marks the DOFs it set in `mask`. Does nothing before calibration.
    pub fn convert(
        &mut self,
        poses: &BTreeMap<u8, (DVec3, DQuat)>,
        q: &mut [f64],
        mask: &mut [bool],
    ) {
        let Some(cal) = &self.calibration else { return };
        q.copy_from_slice(&cal.base_q);
        let sk = &self.skeleton;
        let mut globals = vec![Transform::IDENTITY; sk.joints().len()];
        for (k, &(j, addr)) in self.map.iter().enumerate() {
            let Some(pose) = poses.get(&addr) else {
                continue;
            };
            let (p, rot) = self.world(*pose);
            let joint = &sk.joints()[j];
            if joint.parent.is_none() {
                // The root follows the bird's displacement since calibration.
                let delta = p - cal.sensor0[k].0;
                for d in joint.dofs.clone() {
                    let dof = &sk.dofs()[d];
                    if dof.kind == DofKind::Translation {
                        q[d] = cal.base_q[d] + dof.axis.dot(delta);
                        mask[d] = true;
                    }
                }
            }
            if let Some(solver) = self.ik[k].as_mut() {
                if let Some(w) = &self.warm {
                    for &d in solver.dofs() {
                        q[d] = w[d];
                    }
                }
                let goal = p + cal.origin + rot * cal.levers[k];
                let task = IkTask::position(
                    Effector {
                        joint: j,
                        point: DVec3::ZERO,
                    },
                    goal,
                );
                if let Err(e) = solver.solve(sk, q, &[task], None, None) {
                    tracing::debug!("performer IK for {}: {e}", joint.name);
                }
                for &d in solver.dofs() {
                    mask[d] = true;
                }
            }
            forward_kinematics(sk, q, &mut globals);
            let target = rot * cal.offsets[k];
            // Rotation DOFs of the joint now, and what they must become:
            // G = X · R(q) and G' = X · R' give R' = R(q) · G⁻¹ · G'.
            let mut r = DQuat::IDENTITY;
            for d in joint.dofs.clone() {
                let dof = &sk.dofs()[d];
                if dof.kind == DofKind::Rotation {
                    r *= DQuat::from_axis_angle(dof.axis, q[d]);
                }
            }
            let wanted = (r * globals[j].rotation.inverse() * target).normalize();
            solve_joint_angles(sk, j, wanted, q);
            for d in joint.dofs.clone() {
                if sk.dofs()[d].kind == DofKind::Rotation {
                    mask[d] = true;
                }
            }
        }
        self.warm = Some(q.to_vec());
    }
}

/// Glove sensors to the template's hand DOFs (`s` = `r_` or `l_`); the 18-sensor glove has
/// no DIJ sensors, so each distal flexion follows two thirds of its PIJ (a usual coupling).
pub fn glove_dof_names(sensor: &str, s: &str) -> Vec<String> {
    let f = |n: &str| vec![format!("{s}{n}")];
    match sensor {
        "thumb_rotation" => f("thumb1_flexion"),
        "thumb_mpj" => f("thumb2_flexion"),
        "thumb_ij" => f("thumb3_flexion"),
        "thumb_index_abduction" => f("thumb1_abduction"),
        "middle_index_abduction" => f("index1_pivot"),
        "ring_middle_abduction" => f("ring1_pivot"),
        "pinky_ring_abduction" => f("pinky1_pivot"),
        "palm_arch" => vec![format!("{s}ring0_flexion"), format!("{s}pinky0_flexion")],
        "wrist_pitch" => f("wrist_flexion"),
        "wrist_yaw" => f("wrist_deviation"),
        other => {
            let (finger, joint) = other.split_once('_').unwrap_or((other, ""));
            let k = match joint {
                "mpj" => 1,
                "pij" => 2,
                "dij" => 3,
                _ => return Vec::new(),
            };
            vec![format!("{s}{finger}{k}_flexion")]
        }
    }
}

/// A nominal glove calibration for a template: each sensor's raw range 1…255 spans its
/// DOF's range from 0 (or its lower limit when 0 is outside) to its upper limit.
pub fn nominal_glove_calibration(
    skeleton: &Skeleton,
    sensors: usize,
    side: &str,
) -> GloveCalibration {
    let mut c = GloveCalibration::nominal(sensors);
    for (i, name) in c.sensors.clone().iter().enumerate() {
        if let Some(d) = glove_dof_names(name, side)
            .first()
            .and_then(|n| skeleton.dof(n).ok())
        {
            let dof = &skeleton.dofs()[d];
            let lo = if dof.min <= 0.0 && dof.max >= 0.0 {
                0.0
            } else {
                dof.min
            };
            let g = (dof.max - lo) / 254.0;
            c.gain[i] = g;
            c.offset[i] = 1.0 - lo / g;
        }
    }
    c
}

/// Where a device's samples come from.
enum Source {
    /// A live driver thread.
    Live(DeviceHandle),
    /// A recording, delivered by scene time (deterministic).
    Replay {
        readings: Vec<(f64, Reading)>,
        next: usize,
        start: f64,
    },
    /// Fed from elsewhere (a glove whose values come over OSC).
    External,
}

impl Source {
    /// Readings due now, with the instant they arrived (live only).
    fn take(&mut self, scene_time: f64) -> Vec<(Reading, Option<Instant>)> {
        match self {
            Source::Live(h) => h
                .drain()
                .into_iter()
                .map(|s| (s.reading, Some(s.arrived)))
                .collect(),
            Source::Replay {
                readings,
                next,
                start,
            } => {
                let t0 = readings.first().map(|r| r.0).unwrap_or(0.0);
                let mut out = Vec::new();
                while *next < readings.len() && readings[*next].0 - t0 <= scene_time - *start + 1e-9
                {
                    out.push((readings[*next].1.clone(), None));
                    *next += 1;
                }
                out
            }
            Source::External => Vec::new(),
        }
    }

    fn health(&self) -> Option<HealthReport> {
        match self {
            Source::Live(h) => Some(h.health.report()),
            Source::Replay { .. } | Source::External => None,
        }
    }
}

struct FobInput {
    source: Source,
    converter: AnatomicalConverter,
    latest: BTreeMap<u8, (DVec3, DQuat)>,
}

struct OscPoses {
    listener: OscListener,
    converter: AnatomicalConverter,
    /// Joint name (as sent) → the converter's pseudo-address.
    joints: Vec<(String, u8)>,
    latest: BTreeMap<u8, (DVec3, DQuat)>,
}

struct GloveInput {
    source: Source,
    calibration: GloveCalibration,
    /// DOF indices per sensor.
    dofs: Vec<Vec<usize>>,
    /// (DIJ DOF, PIJ sensor index) for an 18-sensor glove.
    coupled: Vec<(usize, usize)>,
    latest: Option<Vec<u8>>,
    gestures: Option<GestureTracker>,
    /// The gloved hand.
    side: Side,
}

/// The target a performer's `capture` actions write.
#[derive(Clone, Debug, Default)]
pub struct CaptureTarget {
    /// Target DOF values (whole actor).
    pub q: Vec<f64>,
    /// Which DOFs the devices set.
    pub mask: Vec<bool>,
    /// Arrival of the newest sample used (live devices).
    pub arrived: Option<Instant>,
    /// Tick counter of the pre-tick step that made it.
    pub made: u64,
}

/// One performer.
pub struct Performer {
    /// Name (the actor's).
    pub name: String,
    /// Actor index.
    pub actor: usize,
    skeleton: Arc<Skeleton>,
    fob: Option<FobInput>,
    osc: Option<OscPoses>,
    glove: Option<GloveInput>,
    auto_calibrate: bool,
    calibrate_requested: bool,
    target: Arc<Mutex<CaptureTarget>>,
    gesture_handlers: Vec<Function>,
    /// The glove hand's grasping-automaton state (4.7), when the performer has a glove.
    hand: Option<Arc<Mutex<HandStatus>>>,
}

/// Every performer of a scene, the recorder, and latency measurements.
#[derive(Default)]
pub struct Performers {
    list: Vec<Performer>,
    recorder: Option<Arc<Recorder>>,
    ticks: u64,
    /// Gesture events of the last input phase (handler, performer, new gesture, previous),
    /// called by the director at the start of its script phase.
    gesture_events: Vec<GestureEvent>,
    /// Arrival instants of samples used by the targets made this tick, for latency.
    pending_latency: Vec<Instant>,
    /// Arrival-to-posture latencies (seconds) of every live sample used, measured when the
    /// tick that used it has finished stepping (see [`Performers::end_tick`]).
    pub latencies: Vec<f64>,
}

/// A gesture handler to call: the handler, the performer, the new and the previous gesture.
type GestureEvent = (Function, String, String, Option<String>);

/// Lua app data: the shared performers.
#[derive(Clone)]
pub struct SharedPerformers(pub Arc<Mutex<Performers>>);

impl Performers {
    /// Ends a tick: the samples used this tick are now in a posture; records their latency.
    pub fn end_tick(&mut self) {
        let now = Instant::now();
        for a in self.pending_latency.drain(..) {
            self.latencies.push(now.duration_since(a).as_secs_f64());
        }
    }

    /// The glove's hand targets of a performer as (DOF index, radians): what a grasp
    /// corrector takes instead of letting `capture` write the hand.
    pub fn hand_target(&self, performer: &str) -> Option<Vec<(usize, f64)>> {
        let p = self.list.iter().find(|p| p.name == performer)?;
        let g = p.glove.as_ref()?;
        let t = p.target.lock().ok()?;
        Some(
            g.dofs
                .iter()
                .flatten()
                .copied()
                .chain(g.coupled.iter().map(|c| c.0))
                .filter(|&d| t.mask.get(d).copied().unwrap_or(false))
                .map(|d| (d, t.q[d]))
                .collect(),
        )
    }

    /// The glove hand's grasping-automaton state of a performer (None without a glove).
    pub fn hand_state(&self, performer: &str) -> Option<HandState> {
        let p = self.list.iter().find(|p| p.name == performer)?;
        let s = p.hand.as_ref()?.lock().ok()?.state;
        Some(s)
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

    /// A copy of performer `i`'s capture target.
    pub fn target(&self, i: usize) -> Option<CaptureTarget> {
        self.list.get(i)?.target.lock().ok().map(|t| t.clone())
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
        }
        v
    }

    /// The input phase: drain, convert, note gestures. Returns the gesture events
    /// (handlers, performer name, new, previous) for the script phase to call.
    fn pre_tick(&mut self, scene: &Scene) -> Vec<GestureEvent> {
        self.ticks += 1;
        let mut events = Vec::new();
        let time = scene.time();
        for p in &mut self.list {
            let mut changed = false;
            let mut newest: Option<Instant> = None;
            if let Some(f) = &mut p.fob {
                for (r, at) in f.source.take(time) {
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
                            if let Some((_, a)) = o.joints.iter().find(|(n, _)| *n == joint) {
                                o.latest.insert(*a, (position, rotation));
                                changed = true;
                                newest = newest.max(Some(at));
                            }
                        }
                        OscInput::Glove { performer, raw } if performer == p.name => {
                            osc_glove.push((
                                Reading::Glove(crate::glove::GloveRecord {
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
            if let Some(g) = &mut p.glove {
                let mut readings = g.source.take(time);
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
            if let Some(g) = &p.glove {
                if let Some(raw) = &g.latest {
                    let angles = g.calibration.angles(raw);
                    for (i, dofs) in g.dofs.iter().enumerate() {
                        for &d in dofs {
                            if let Some(&a) = angles.get(i) {
                                q[d] = p.skeleton.dofs()[d].clamp(a);
                                mask[d] = true;
                            }
                        }
                    }
                    for &(d, pij) in &g.coupled {
                        if let Some(&a) = angles.get(pij) {
                            q[d] = p.skeleton.dofs()[d].clamp(a * 2.0 / 3.0);
                            mask[d] = true;
                        }
                    }
                }
            }
            if let Ok(mut t) = p.target.lock() {
                t.q = q;
                t.mask = mask;
                t.arrived = newest.or(t.arrived);
                t.made = self.ticks;
            }
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

/// The `capture` generator: writes the performer's device-driven DOFs within its scope;
/// the glove hand's fingers go through the grasping automaton ([`GloveHand`]).
pub struct Capture {
    target: Arc<Mutex<CaptureTarget>>,
    hand: Option<GloveHand>,
}

impl Generator for Capture {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), String> {
        match &mut self.hand {
            Some(h) => h.start(ctx),
            None => Ok(()),
        }
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let Ok(t) = self.target.lock() else {
            return Step::Failed("capture target lock poisoned".into());
        };
        let scope = out.scope();
        let fingers = self
            .hand
            .as_ref()
            .map(|h| h.fingers())
            .unwrap_or(Scope::EMPTY);
        for d in scope.iter() {
            if t.mask.get(d).copied().unwrap_or(false) && !fingers.contains(d) {
                out.set(d, t.q[d]);
            }
        }
        if let Some(h) = &mut self.hand {
            if let Err(e) = h.step(ctx, &t.q, &t.mask, out) {
                return Step::Failed(format!("capture: {e}"));
            }
        }
        Step::Running
    }
}

/// `actor:capture{ <common options> }` on a performer: follow the devices (runs until
/// cancelled). Default scope: every DOF the devices drive.
fn build_capture(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let t = match args.into_iter().next() {
        Some(Value::Table(t)) => Some(t),
        None | Some(Value::Nil) => None,
        Some(other) => {
            return Err(lua_err_message(format!(
                "capture: expects a table of options, got {}",
                other.type_name()
            )))
        }
    };
    let common = CommonOptions::parse(ctx, "capture", t.as_ref(), &[])?;
    let shared = ctx
        .lua
        .app_data_ref::<SharedPerformers>()
        .ok_or_else(|| lua_err_message("capture: devices are not enabled in this run"))?
        .clone();
    let perf = shared
        .0
        .lock()
        .map_err(|_| lua_err_message("capture: performer lock poisoned"))?;
    let p = perf
        .list
        .iter()
        .find(|p| p.actor == ctx.actor)
        .ok_or_else(|| {
            lua_err_message(
                "capture: this actor is not a performer (create it with troupe.performer)",
            )
        })?;
    let natural = device_scope(p);
    let target = p.target.clone();
    let glove = p
        .glove
        .as_ref()
        .zip(p.hand.clone())
        .map(|(g, status)| (g.side, status));
    drop(perf);
    let spec = common.spec("capture", natural);
    let hand = match glove {
        // The automaton runs when this capture drives the glove hand's fingers.
        Some((side, status)) => {
            let fingers = troupe_body::sensors::HandSensors::new(&ctx.skeleton, side)
                .map_err(|e| lua_err_message(format!("capture: {e}")))?
                .scope;
            if spec.scope.intersection(&fingers).is_empty() {
                None
            } else {
                let board = ctx
                    .lua
                    .app_data_ref::<SharedHandBoard>()
                    .map(|b| b.clone())
                    .ok_or_else(|| lua_err_message("capture: no hand board in this run"))?;
                Some(GloveHand::new(side, board, status))
            }
        }
        None => None,
    };
    let mut spec = spec;
    spec.duration = None;
    Ok((Box::new(Capture { target, hand }), spec))
}

fn device_scope(p: &Performer) -> troupe_body::Scope {
    let mut dofs: Vec<usize> = Vec::new();
    let sk = &p.skeleton;
    let converters = p
        .fob
        .iter()
        .map(|f| &f.converter)
        .chain(p.osc.iter().map(|o| &o.converter));
    for c in converters {
        for &(j, _) in &c.map {
            let joint = &sk.joints()[j];
            for d in joint.dofs.clone() {
                if joint.parent.is_some() && sk.dofs()[d].kind == DofKind::Translation {
                    continue;
                }
                dofs.push(d);
            }
        }
        dofs.extend(c.ik.iter().flatten().flat_map(|s| s.dofs().iter().copied()));
    }
    if let Some(g) = &p.glove {
        dofs.extend(g.dofs.iter().flatten().copied());
        dofs.extend(g.coupled.iter().map(|c| c.0));
    }
    dofs.into_iter().collect()
}

/// Registers the `capture` action kind.
pub fn register(kinds: &mut ActionKinds) {
    kinds.register(ActionKind {
        method: "capture",
        build: build_capture,
    });
}

/// Drains every performer's devices into its capture target (the session's input phase).
struct PerformerInput(SharedPerformers);

impl Input for PerformerInput {
    fn name(&self) -> String {
        "performers".into()
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        let mut performers = self.0 .0.lock().map_err(|_| troupe_scene::Error::Input {
            input: "performers".into(),
            message: "lock poisoned by a panic".into(),
        })?;
        let events = performers.pre_tick(scene);
        performers.gesture_events.extend(events);
        Ok(())
    }
}

/// Installs `troupe.performer` and `troupe.devices.*` on the session's director, the
/// performers' and SpaceMice's inputs on the session, and the script hook that calls
/// gesture handlers. `recorder` records every live device stream (`--record-devices`).
pub fn install(
    session: &mut LuaSession,
    recorder: Option<Arc<Recorder>>,
) -> Result<SharedPerformers, String> {
    let space_recorder = recorder.clone();
    let shared = SharedPerformers(Arc::new(Mutex::new(Performers {
        recorder,
        ..Performers::default()
    })));
    let (director, _) = session.script_and_scene();
    let lua = director.lua();
    lua.set_app_data(shared.clone());
    // Glove hands and offers to them, shared with `give` (troupe-actions).
    if lua.app_data_ref::<SharedHandBoard>().is_none() {
        lua.set_app_data(SharedHandBoard::default());
    }
    install_lua(lua).map_err(|e| format!("installing the device functions: {e}"))?;
    let s = shared.clone();
    director.add_script_hook(Box::new(move |_lua: &Lua| {
        // Take the events and release the lock before calling Lua: a handler may query
        // the performers.
        let events = std::mem::take(
            &mut s
                .0
                .lock()
                .map_err(|_| err("performer lock poisoned"))?
                .gesture_events,
        );
        for (f, name, new, old) in events {
            f.call::<()>((name.clone(), new, old))
                .map_err(|e| err(format!("gesture handler of '{name}': {e}")))?;
        }
        Ok(())
    }));
    session.add_input(Box::new(PerformerInput(shared.clone())));
    // SpaceMice move objects rather than actors; they live in their own module, installed
    // after `troupe.devices` exists.
    crate::space_move::install(session, space_recorder)?;
    Ok(shared)
}

fn err(e: impl std::fmt::Display) -> mlua::Error {
    lua_err_message(e)
}

fn shared(lua: &Lua) -> mlua::Result<SharedPerformers> {
    lua.app_data_ref::<SharedPerformers>()
        .map(|s| s.clone())
        .ok_or_else(|| err("devices are not enabled"))
}

fn base_dir(lua: &Lua) -> PathBuf {
    troupe_lua::scene_dir(lua).unwrap_or_else(|| PathBuf::from("."))
}

fn resolve(lua: &Lua, p: &str) -> PathBuf {
    let path = Path::new(p);
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        base_dir(lua).join(path)
    }
}

fn check_keys(t: &Table, what: &str, known: &[&str]) -> mlua::Result<()> {
    for pair in t.clone().pairs::<Value, Value>() {
        let (k, _) = pair?;
        let name = k.to_string()?;
        if !known.contains(&name.as_str()) {
            return Err(err(format!(
                "{what}: unknown option `{name}` (known: {})",
                known.join(", ")
            )));
        }
    }
    Ok(())
}

fn performer_index(lua: &Lua, who: &Value) -> mlua::Result<usize> {
    let s = shared(lua)?;
    let perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
    let found = match who {
        Value::String(n) => {
            let n = n.to_str()?.to_string();
            perf.list.iter().position(|p| p.name == n)
        }
        Value::UserData(u) => {
            let a = u.borrow::<ActorRef>()?.0;
            perf.list.iter().position(|p| p.actor == a)
        }
        _ => None,
    };
    found.ok_or_else(|| err("not a performer (give the actor or its name)"))
}

fn install_lua(lua: &Lua) -> mlua::Result<()> {
    let troupe: Table = lua.globals().get("troupe")?;
    troupe.set("performer", lua.create_function(lua_performer)?)?;
    let devices = lua.create_table()?;
    devices.set(
        "calibrate",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let mut perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            perf.list[i].calibrate_requested = true;
            Ok(())
        })?,
    )?;
    devices.set(
        "is_calibrated",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            Ok(perf.list[i]
                .fob
                .as_ref()
                .is_none_or(|f| f.converter.is_calibrated()))
        })?,
    )?;
    devices.set(
        "health",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            let p = &perf.list[i];
            let out = lua.create_table()?;
            let reports = [
                ("fob", p.fob.as_ref().map(|f| f.source.health())),
                ("glove", p.glove.as_ref().map(|g| g.source.health())),
                (
                    "osc",
                    p.osc.as_ref().map(|o| Some(o.listener.health.report())),
                ),
            ];
            for (dev, report) in reports {
                let Some(report) = report else { continue };
                out.set(dev, health_table(lua, report)?)?;
            }
            Ok(out)
        })?,
    )?;
    devices.set(
        "hand",
        lua.create_function(|lua, who: Value| {
            // The glove's hand DOF targets by name: what a grasp corrector would consume.
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            let p = &perf.list[i];
            let out = lua.create_table()?;
            let Some(g) = &p.glove else { return Ok(out) };
            let t = p.target.lock().map_err(|_| err("target lock poisoned"))?;
            for d in g
                .dofs
                .iter()
                .flatten()
                .copied()
                .chain(g.coupled.iter().map(|c| c.0))
            {
                if t.mask.get(d).copied().unwrap_or(false) {
                    out.set(p.skeleton.dofs()[d].name.as_str(), t.q[d])?;
                }
            }
            Ok(out)
        })?,
    )?;
    devices.set(
        "hand_state",
        lua.create_function(|lua, (who, hand): (Value, Option<String>)| {
            // The glove hand's grasping automaton (4.7): its state, and the object it
            // touches or holds (nil when free).
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            let p = &perf.list[i];
            let status = p
                .hand
                .as_ref()
                .and_then(|h| h.lock().ok().map(|h| *h))
                .ok_or_else(|| err(format!("hand_state: `{}` has no glove", p.name)))?;
            if let Some(h) = hand {
                let want = Side::parse(&h).map_err(|e| err(format!("hand_state: {e}")))?;
                if want != status.side {
                    return Err(err(format!(
                        "hand_state: `{}` wears the glove on the {} hand, not the {h}",
                        p.name,
                        status.side.name()
                    )));
                }
            }
            let object = match status.state {
                HandState::FreeHand => None,
                HandState::GraspingInProgress(o) | HandState::SecureGrasp(o) => Some(o),
            };
            drop(perf);
            let name = match object {
                Some(o) => troupe_lua::kinds::with_scene(lua, |sc| {
                    sc.objects().get(o).map(|x| x.name.clone())
                })?,
                None => None,
            };
            Ok((status.state.name(), name))
        })?,
    )?;
    devices.set(
        "glove",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            match perf.list[i].glove.as_ref().and_then(|g| g.latest.clone()) {
                Some(raw) => Ok(Value::Table(lua.create_sequence_from(raw)?)),
                None => Ok(Value::Nil),
            }
        })?,
    )?;
    devices.set(
        "on_gesture",
        lua.create_function(|lua, (who, f): (Value, Function)| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let mut perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            perf.list[i].gesture_handlers.push(f);
            Ok(())
        })?,
    )?;
    devices.set(
        "train_gestures",
        lua.create_function(|lua, (who, examples): (Value, Table)| {
            // { name = "file.rec", … }: every glove record of each recording is an example.
            let i = performer_index(lua, &who)?;
            let mut ex = Vec::new();
            for pair in examples.pairs::<String, String>() {
                let (name, file) = pair?;
                let path = resolve(lua, &file);
                let rec = Recording::read(&path).map_err(err)?;
                let s = rec
                    .find("cyberglove")
                    .ok_or_else(|| err(format!("{}: no glove stream", path.display())))?;
                let raws: Vec<Vec<u8>> = rec
                    .readings(s)
                    .map_err(err)?
                    .into_iter()
                    .filter_map(|(_, r)| match r {
                        Reading::Glove(g) => Some(g.raw),
                        _ => None,
                    })
                    .collect();
                ex.push((name, raws));
            }
            ex.sort_by(|a, b| a.0.cmp(&b.0));
            let set = GestureSet::train(&ex).map_err(|e| err(format!("train_gestures: {e}")))?;
            let s = shared(lua)?;
            let mut perf = s.0.lock().map_err(|_| err("performer lock poisoned"))?;
            let g = perf.list[i]
                .glove
                .as_mut()
                .ok_or_else(|| err("train_gestures: this performer has no glove"))?;
            g.gestures = Some(GestureTracker::new(set));
            Ok(())
        })?,
    )?;
    troupe.set("devices", devices)?;
    Ok(())
}

fn opt<T: mlua::FromLua>(t: &Table, key: &str) -> mlua::Result<Option<T>> {
    t.get::<Option<T>>(key)
}

/// `troupe.performer{ name=…, template=…, at=…, facing=…, calibrate="auto"|"manual",
/// devices = { fob = {…}, glove = {…} } }`.
fn lua_performer(lua: &Lua, t: Table) -> mlua::Result<Value> {
    check_keys(
        &t,
        "performer",
        &[
            "name",
            "template",
            "height",
            "mass",
            "at",
            "facing",
            "devices",
            "calibrate",
        ],
    )?;
    let devices: Option<Table> = opt(&t, "devices")?;
    let calibrate: String = opt(&t, "calibrate")?.unwrap_or_else(|| "auto".into());
    if calibrate != "auto" && calibrate != "manual" {
        return Err(err(format!(
            "performer: `calibrate` must be \"auto\" or \"manual\", got \"{calibrate}\""
        )));
    }
    // The actor itself is made by troupe.actor, with the actor options.
    let actor_opts = lua.create_table()?;
    for k in ["name", "template", "height", "mass", "at", "facing"] {
        actor_opts.set(k, t.get::<Value>(k)?)?;
    }
    let troupe: Table = lua.globals().get("troupe")?;
    let make: Function = troupe.get("actor")?;
    let actor_value: Value = make.call(actor_opts)?;
    let Value::UserData(ud) = &actor_value else {
        return Err(err("performer: troupe.actor did not return an actor"));
    };
    let actor = ud.borrow::<ActorRef>()?.0;
    let name: String = t.get("name")?;
    let skeleton = troupe_lua::actor_skeletons(lua)
        .ok_or_else(|| err("no scene"))?
        .get(actor)
        .cloned()
        .ok_or_else(|| err("performer: actor vanished"))?;
    let s = shared(lua)?;
    let recorder =
        s.0.lock()
            .map_err(|_| err("performer lock poisoned"))?
            .recorder
            .clone();
    let scene_time = lua
        .globals()
        .get::<Table>("troupe")?
        .get::<Function>("time")
        .ok()
        .map(|f| f.call::<f64>(()))
        .transpose()?
        .unwrap_or(0.0);
    let mut fob = None;
    let mut osc = None;
    let mut glove = None;
    if let Some(d) = &devices {
        check_keys(d, "performer.devices", &["fob", "glove", "osc"])?;
        if let Some(f) = opt::<Table>(d, "fob")? {
            fob = Some(fob_input(
                lua,
                &f,
                &skeleton,
                &name,
                recorder.clone(),
                scene_time,
            )?);
        }
        if let Some(o) = opt::<Table>(d, "osc")? {
            if fob.is_some() {
                return Err(err(
                    "performer.devices: give `fob` or `osc` poses, not both",
                ));
            }
            osc = Some(osc_input(&o, &skeleton)?);
        }
        if let Some(g) = opt::<Table>(d, "glove")? {
            glove = Some(glove_input(
                lua,
                &g,
                &skeleton,
                &name,
                recorder.clone(),
                scene_time,
            )?);
        }
    }
    let n = skeleton.dof_count();
    let hand = match &glove {
        Some(g) => {
            let board = lua
                .app_data_ref::<SharedHandBoard>()
                .map(|b| b.clone())
                .ok_or_else(|| err("performer: no hand board in this run"))?;
            board
                .0
                .lock()
                .map_err(|_| err("hand board lock poisoned"))?
                .add_hand(actor, g.side);
            Some(Arc::new(Mutex::new(HandStatus {
                state: HandState::FreeHand,
                side: g.side,
            })))
        }
        None => None,
    };
    let performer = Performer {
        name,
        actor,
        skeleton,
        fob,
        osc,
        glove,
        auto_calibrate: calibrate == "auto",
        calibrate_requested: false,
        target: Arc::new(Mutex::new(CaptureTarget {
            q: vec![0.0; n],
            mask: vec![false; n],
            arrived: None,
            made: 0,
        })),
        gesture_handlers: Vec::new(),
        hand,
    };
    s.0.lock()
        .map_err(|_| err("performer lock poisoned"))?
        .list
        .push(performer);
    Ok(actor_value)
}

fn source(
    lua: &Lua,
    t: &Table,
    what: &str,
    kind: &str,
    scene_time: f64,
    live: impl FnOnce(String) -> mlua::Result<DeviceHandle>,
) -> mlua::Result<Source> {
    let port: Option<String> = opt(t, "port")?;
    let replay: Option<String> = opt(t, "replay")?;
    match (port, replay) {
        (Some(p), None) => Ok(Source::Live(live(p)?)),
        (None, Some(r)) => {
            let path = resolve(lua, &r);
            let rec = Recording::read(&path).map_err(|e| err(format!("{what}: {e}")))?;
            let stream: Option<String> = opt(t, "stream")?;
            let s = rec.find(stream.as_deref().unwrap_or(kind)).ok_or_else(|| {
                err(format!(
                    "{what}: {} has no single '{kind}' stream (name one with stream=…)",
                    path.display()
                ))
            })?;
            let readings = rec.readings(s).map_err(|e| err(format!("{what}: {e}")))?;
            Ok(Source::Replay {
                readings,
                next: 0,
                start: scene_time,
            })
        }
        (Some(_), Some(_)) => Err(err(format!("{what}: give `port` or `replay`, not both"))),
        (None, None) => Err(err(format!(
            "{what}: `port` (a serial port) or `replay` (a .rec file) is required"
        ))),
    }
}

fn fob_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    scene_time: f64,
) -> mlua::Result<FobInput> {
    check_keys(
        t,
        "performer.devices.fob",
        &[
            "port",
            "replay",
            "stream",
            "birds",
            "map",
            "format",
            "baud",
            "range",
            "hemisphere",
            "mode",
        ],
    )?;
    let birds: u8 = opt(t, "birds")?.unwrap_or(1);
    if birds == 0 || birds > 14 {
        return Err(err(format!(
            "performer.devices.fob: birds must be 1…14, got {birds}"
        )));
    }
    let map_t: Table = opt(t, "map")?
        .ok_or_else(|| err("performer.devices.fob: `map` (joint = bird address) is required"))?;
    let mut map = Vec::new();
    for pair in map_t.pairs::<String, u8>() {
        let (j, a) = pair?;
        if a == 0 || a > birds {
            return Err(err(format!(
                "performer.devices.fob: map.{j} = {a} is not a bird address 1…{birds}"
            )));
        }
        map.push((j, a));
    }
    let converter = AnatomicalConverter::new(skeleton.clone(), &map, transmitter_to_world())
        .map_err(|e| err(format!("performer.devices.fob: {e}")))?;
    let format = OutputFormat::parse(
        &opt::<String>(t, "format")?.unwrap_or_else(|| "position-quaternion".into()),
    )
    .map_err(err)?;
    if !matches!(
        format,
        OutputFormat::PositionAngles
            | OutputFormat::PositionQuaternion
            | OutputFormat::PositionMatrix
    ) {
        return Err(err(
            "performer.devices.fob: a performer needs a position/orientation format",
        ));
    }
    let mut config = FobConfig::new(birds, format);
    if let Some(r) = opt::<u32>(t, "range")? {
        config.layout.range = PositionRange::parse(&r.to_string()).map_err(err)?;
    }
    if let Some(h) = opt::<String>(t, "hemisphere")? {
        config.hemisphere = Hemisphere::parse(&h).map_err(err)?;
    }
    if let Some(m) = opt::<String>(t, "mode")? {
        config.mode = parse_mode(&m)?;
    }
    let baud: u32 = opt(t, "baud")?.unwrap_or(115_200);
    let src = source(lua, t, "performer.devices.fob", "fob", scene_time, |port| {
        let mut o = DriverOptions::new(&format!("{name}.fob"), &port);
        o.baud = baud;
        Ok(driver::spawn(
            o,
            Box::new(FobProtocol::new(config)),
            recorder,
        ))
    })?;
    Ok(FobInput {
        source: src,
        converter,
        latest: BTreeMap::new(),
    })
}

fn osc_input(t: &Table, skeleton: &Arc<Skeleton>) -> mlua::Result<OscPoses> {
    check_keys(t, "performer.devices.osc", &["listen", "joints"])?;
    let listen: String = opt(t, "listen")?
        .ok_or_else(|| err("performer.devices.osc: `listen` (host:port) is required"))?;
    let names: Vec<String> = opt::<Vec<String>>(t, "joints")?
        .ok_or_else(|| err("performer.devices.osc: `joints` (the joint names sent) is required"))?;
    if names.is_empty() || names.len() > 250 {
        return Err(err(
            "performer.devices.osc: `joints` must list 1…250 joints",
        ));
    }
    let joints: Vec<(String, u8)> = names
        .into_iter()
        .enumerate()
        .map(|(i, n)| (n, i as u8 + 1))
        .collect();
    let converter = AnatomicalConverter::new(skeleton.clone(), &joints, DQuat::IDENTITY)
        .map_err(|e| err(format!("performer.devices.osc: {e}")))?;
    let listener =
        OscListener::bind(&listen, 4096).map_err(|e| err(format!("performer.devices.osc: {e}")))?;
    Ok(OscPoses {
        listener,
        converter,
        joints,
        latest: BTreeMap::new(),
    })
}

fn parse_mode(m: &str) -> mlua::Result<Mode> {
    match m {
        "stream" => Ok(Mode::Stream),
        "point" => Ok(Mode::Point),
        other => Err(err(format!(
            "mode must be \"stream\" or \"point\", got \"{other}\""
        ))),
    }
}

fn glove_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    scene_time: f64,
) -> mlua::Result<GloveInput> {
    check_keys(
        t,
        "performer.devices.glove",
        &[
            "port",
            "replay",
            "stream",
            "hand",
            "sensors",
            "calibration",
            "gestures",
            "baud",
            "mode",
            "osc",
        ],
    )?;
    let side = match opt::<String>(t, "hand")?.as_deref() {
        None | Some("right") => "r_",
        Some("left") => "l_",
        Some(o) => {
            return Err(err(format!(
                "performer.devices.glove: hand must be \"right\" or \"left\", got \"{o}\""
            )))
        }
    };
    let sensors: usize = opt(t, "sensors")?.unwrap_or(18);
    if sensors != 18 && sensors != 22 {
        return Err(err(format!(
            "performer.devices.glove: sensors must be 18 or 22, got {sensors}"
        )));
    }
    let calibration = match opt::<String>(t, "calibration")? {
        Some(f) => {
            let c = GloveCalibration::load(&resolve(lua, &f)).map_err(err)?;
            if c.sensors.len() != sensors {
                return Err(err(format!(
                    "{f}: calibration for {} sensors, glove has {sensors}",
                    c.sensors.len()
                )));
            }
            c
        }
        None => nominal_glove_calibration(skeleton, sensors, side),
    };
    let names = crate::glove::sensor_names(sensors);
    let dofs: Vec<Vec<usize>> = names
        .iter()
        .map(|n| {
            glove_dof_names(n, side)
                .iter()
                .filter_map(|d| skeleton.dof(d).ok())
                .collect()
        })
        .collect();
    let mut coupled = Vec::new();
    if sensors == 18 {
        for finger in ["index", "middle", "ring", "pinky"] {
            let pij = names.iter().position(|n| *n == format!("{finger}_pij"));
            if let (Some(p), Ok(d)) = (pij, skeleton.dof(&format!("{side}{finger}3_flexion"))) {
                coupled.push((d, p));
            }
        }
    }
    let gestures = match opt::<String>(t, "gestures")? {
        Some(f) => Some(GestureTracker::new(
            GestureSet::load(&resolve(lua, &f)).map_err(err)?,
        )),
        None => None,
    };
    let mode = parse_mode(&opt::<String>(t, "mode")?.unwrap_or_else(|| "stream".into()))?;
    let baud: u32 = opt(t, "baud")?.unwrap_or(115_200);
    let config = GloveConfig {
        layout: GloveLayout {
            sensors,
            status_byte: false,
        },
        mode,
    };
    // `osc = true`: the values arrive as /troupe/<performer>/glove over the performer's
    // OSC listener.
    let src = if opt::<bool>(t, "osc")?.unwrap_or(false) {
        Source::External
    } else {
        source(
            lua,
            t,
            "performer.devices.glove",
            "cyberglove",
            scene_time,
            |port| {
                let mut o = DriverOptions::new(&format!("{name}.glove"), &port);
                o.baud = baud;
                Ok(driver::spawn(
                    o,
                    Box::new(GloveProtocol::new(config)),
                    recorder,
                ))
            },
        )?
    };
    Ok(GloveInput {
        source: src,
        calibration,
        dofs,
        coupled,
        latest: None,
        gestures,
        side: if side == "l_" {
            Side::Left
        } else {
            Side::Right
        },
    })
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

/// A device's health as a Lua table (`troupe.devices.health`): its state and counters, or
/// `state = "replay"` for a replayed device or a glove fed over OSC (`None`).
pub(crate) fn health_table(lua: &Lua, report: Option<HealthReport>) -> mlua::Result<Table> {
    let t = lua.create_table()?;
    match report {
        Some(h) => {
            t.set("state", h.state.name())?;
            t.set("samples", h.samples)?;
            t.set("resyncs", h.resyncs)?;
            t.set("dropped_bytes", h.dropped_bytes)?;
            t.set("dropped_samples", h.dropped_samples)?;
            t.set("connections", h.connections)?;
            t.set("error", h.last_error)?;
        }
        None => t.set("state", "replay")?,
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::TemplateParams;

    fn adult() -> Arc<Skeleton> {
        let t = troupe_body::template("adult").unwrap();
        Arc::new(
            t.instantiate(TemplateParams {
                height: t.default_height,
                mass: t.default_mass,
            })
            .unwrap(),
        )
    }

    #[test]
    fn converter_turns_and_moves_segments_with_their_sensors() {
        let sk = adult();
        let n = sk.dof_count();
        let frame = transmitter_to_world();
        // Transmitter X forward maps to the scene's +Z, Z down to −Y.
        assert!((frame * DVec3::X - DVec3::Z).length() < 1e-12);
        assert!((frame * DVec3::Z + DVec3::Y).length() < 1e-12);
        let map = [("pelvis".to_string(), 1u8), ("skullbase".to_string(), 2u8)];
        let mut c = AnatomicalConverter::new(sk.clone(), &map, frame).unwrap();
        let (p1, q1) = (DVec3::new(0.5, 0.1, 0.2), DQuat::from_rotation_z(0.3));
        let (p2, q2) = (DVec3::new(0.5, 0.1, -0.5), DQuat::from_rotation_x(-0.2));
        let mut poses = BTreeMap::from([(1, (p1, q1)), (2, (p2, q2))]);
        let base = vec![0.0; n];
        c.calibrate(&base, &poses).unwrap();
        let mut g0 = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &base, &mut g0);

        // Unmoved sensors give the calibration posture.
        let (mut q, mut mask) = (vec![1.0; n], vec![false; n]);
        c.convert(&poses, &mut q, &mut mask);
        assert!(
            q.iter().all(|v| v.abs() < 1e-9),
            "calibration pose reproduced"
        );

        // The pelvis bird turns 20° about the transmitter's Z (down) and moves 10 cm
        // forward; the head bird nods 0.15 rad about the transmitter's Y.
        let turn = DQuat::from_rotation_z(0.35);
        let nod = DQuat::from_rotation_y(0.15);
        poses.insert(1, (p1 + DVec3::new(0.1, 0.0, 0.0), turn * q1));
        poses.insert(2, (p2, nod * q2));
        c.convert(&poses, &mut q, &mut mask);
        assert!((q[sk.dof("root_z").unwrap()] - 0.1).abs() < 1e-12);
        assert!(q[sk.dof("root_x").unwrap()].abs() < 1e-12);
        let mut g = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &q, &mut g);
        let w = |r: DQuat| frame * r * frame.inverse();
        let root = sk.joint("HumanoidRoot").unwrap();
        assert!(g[root].rotation.angle_between(w(turn) * g0[root].rotation) < 1e-6);
        // A yaw about the transmitter's down axis is a turn about the scene's −Y.
        assert!((q[sk.dof("root_yaw").unwrap()] + 0.35).abs() < 1e-6);
        let head = sk.joint("skullbase").unwrap();
        assert!(g[head].rotation.angle_between(w(nod) * g0[head].rotation) < 1e-4);
        assert!(mask[sk.dof("root_yaw").unwrap()] && !mask[sk.dof("r_elbow_flexion").unwrap()]);
    }

    #[test]
    fn joints_without_a_sensor_follow_by_ik() {
        let sk = adult();
        let n = sk.dof_count();
        let frame = transmitter_to_world();
        let map = [
            ("pelvis".to_string(), 1u8),
            ("vl5".to_string(), 2u8),
            ("r_wrist".to_string(), 3u8),
        ];
        let mut c = AnatomicalConverter::new(sk.clone(), &map, frame).unwrap();
        let base = vec![0.0; n];
        let mut g0 = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &base, &mut g0);
        // Birds placed at their joints (transmitter 1 m behind the scene origin).
        let to_tx = |p: DVec3| frame.inverse() * (p + DVec3::new(0.0, 0.0, 1.0));
        let mut poses: BTreeMap<u8, (DVec3, DQuat)> = map
            .iter()
            .map(|(name, a)| {
                let j = sk.joint(joint_alias(name)).unwrap();
                (*a, (to_tx(g0[j].translation), DQuat::IDENTITY))
            })
            .collect();
        c.calibrate(&base, &poses).unwrap();
        // The wrist bird rises 15 cm and comes 10 cm forward; nothing else moves.
        let wrist = sk.joint("r_wrist").unwrap();
        let goal = g0[wrist].translation + DVec3::new(0.0, 0.15, 0.10);
        poses.insert(3, (to_tx(goal), DQuat::IDENTITY));
        let (mut q, mut mask) = (vec![0.0; n], vec![false; n]);
        c.convert(&poses, &mut q, &mut mask);
        let mut g = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &q, &mut g);
        assert!(
            (g[wrist].translation - goal).length() < 1e-3,
            "wrist at {} not {}",
            g[wrist].translation,
            goal
        );
        let elbow = sk.dof("r_elbow_flexion").unwrap();
        assert!(mask[elbow] && q[elbow].abs() > 0.05, "the elbow bends (IK)");
        assert!(q[sk.dof("root_x").unwrap()].abs() < 1e-12, "the root stays");
    }

    #[test]
    fn calibration_needs_every_mapped_bird() {
        let sk = adult();
        let mut c = AnatomicalConverter::new(
            sk.clone(),
            &[("pelvis".into(), 1), ("r_wrist".into(), 2)],
            DQuat::IDENTITY,
        )
        .unwrap();
        let poses = BTreeMap::from([(1, (DVec3::ZERO, DQuat::IDENTITY))]);
        let e = c.calibrate(&vec![0.0; sk.dof_count()], &poses).unwrap_err();
        assert!(e.contains("bird 2"), "{e}");
        assert!(
            AnatomicalConverter::new(sk, &[("tail".into(), 1)], DQuat::IDENTITY)
                .map(|_| ())
                .unwrap_err()
                .contains("'tail'")
        );
    }

    #[test]
    fn glove_sensors_map_to_hand_dofs() {
        let sk = adult();
        for sensors in [18, 22] {
            for name in crate::glove::sensor_names(sensors) {
                let dofs = glove_dof_names(name, "r_");
                assert!(!dofs.is_empty(), "{name} maps to a DOF");
                for d in dofs {
                    assert!(sk.dof(&d).is_ok(), "{name} → {d} exists in the template");
                }
            }
        }
        let c = nominal_glove_calibration(&sk, 18, "r_");
        let d = &sk.dofs()[sk.dof("r_index1_flexion").unwrap()];
        let a = c.angles(&[1, 1, 1, 1, 1, 255]);
        assert!(
            a[4].abs() < 1e-12
                && (a[5] - sk.dofs()[sk.dof("r_index2_flexion").unwrap()].max).abs() < 1e-12
        );
        assert!(d.max > 0.0);
    }
}
