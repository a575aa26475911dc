//! Dynamics generators (thesis chapter 3): `simulate` (passive forward dynamics, e.g.
//! falling), `servo` (PD servos toward a posture or another actor's posture, fig. 3-7) and
//! `track` (closed-loop tracking of a sequence with inverse dynamics, fig. 3-4).
//!
//! Each action runs its own [`Simulation`] of the whole body, started from the actor's
//! posture: the DOFs of its scope are integrated from forces, the others are prescribed
//! and follow the actor's posture tick by tick (an arm servo moves on a body that other
//! actions place). The root is simulated as a floating base only by `simulate`, and only
//! when the scope holds all six root DOFs; `servo` and `track` never move the root.

use mlua::{Lua, MultiValue, Table, Value};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use troupe_body::dynamics::contact::ContactParams;
use troupe_body::dynamics::{Control, Gains, SimParams, Simulation};
use troupe_body::glam::DVec3;
use troupe_body::{Scope, Skeleton};
use troupe_lua::api::{load_sequence, lua_err_message, ActorRef, SequenceRef};
use troupe_lua::kinds::args::{opt_bool, opt_number, opt_table_arg, vec3};
use troupe_lua::kinds::{ActionKind, ActionKinds, BuildContext, CommonOptions};
use troupe_motion::sequence::{Key, Track as SeqTrack};
use troupe_motion::Sequence;
use troupe_scene::{ActionSpec, DofWriter, Generator, GeneratorContext, Scene, Step};

/// Per-DOF joint torques of the dynamics actions, recorded tick by tick on request
/// (`troupe run --record-torques FILE.trk`, thesis fig. 3-9). Install it on a director's
/// Lua state before the scene starts its actions: every dynamics action built afterwards
/// logs, each tick, the joint forces it applied over the tick (their mean over the
/// sub-steps; see `Simulation::mean_torques`) on the DOFs it simulates. Thread-safe; the
/// result does not depend on the scheduler's thread count (entries are keyed by actor,
/// DOF and tick; when two dynamics actions drive one DOF in the same tick their torques
/// add).
#[derive(Clone, Debug, Default)]
pub struct TorqueLog(Arc<Mutex<TorqueEntries>>);

/// Per (actor, DOF), per tick: (time, torque).
type TorqueEntries = BTreeMap<(usize, usize), BTreeMap<u64, (f64, f64)>>;

impl TorqueLog {
    /// An empty log.
    pub fn new() -> TorqueLog {
        TorqueLog::default()
    }

    /// Makes the dynamics actions built on `lua` log into this log.
    pub fn install(&self, lua: &Lua) {
        lua.set_app_data(self.clone());
    }

    /// The log installed on `lua`, if any.
    fn installed(lua: &Lua) -> Option<TorqueLog> {
        lua.app_data_ref::<TorqueLog>().map(|l| l.clone())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, TorqueEntries> {
        // A panic while holding the lock leaves plain data: keep using it.
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds `torque` (N·m, or N for a translation) on DOF `dof` of actor `actor` at tick
    /// `tick` (scene time `time`).
    pub fn record(&self, actor: usize, dof: usize, tick: u64, time: f64, torque: f64) {
        let mut entries = self.lock();
        let e = entries
            .entry((actor, dof))
            .or_default()
            .entry(tick)
            .or_insert((time, 0.0));
        e.1 += torque;
    }

    /// Whether nothing was logged.
    pub fn is_empty(&self) -> bool {
        self.lock().is_empty()
    }

    /// Number of (actor, DOF, tick) entries.
    pub fn len(&self) -> usize {
        self.lock().values().map(|t| t.len()).sum()
    }

    /// One sequence per actor that has torques (named after the actor, in actor order),
    /// one track per DOF named after it, one key per tick: values in N·m (N for a
    /// translation), `meta quantity torque`.
    pub fn sequences(&self, scene: &Scene) -> Vec<Sequence> {
        let entries = self.lock();
        let mut set: Vec<Sequence> = Vec::new();
        let mut current: Option<usize> = None;
        for (&(actor, dof), ticks) in entries.iter() {
            let Some(info) = scene.actors().get(actor) else {
                continue;
            };
            if current != Some(actor) {
                current = Some(actor);
                let mut seq = Sequence::new(info.name.clone());
                seq.meta.insert("quantity".into(), "torque".into());
                seq.meta.insert(
                    "units".into(),
                    "N·m for rotation DOFs, N for translation DOFs".into(),
                );
                seq.meta
                    .insert("rate".into(), scene.config().rate.to_string());
                seq.meta.insert("template".into(), info.template.clone());
                seq.meta
                    .insert("source".into(), "troupe run --record-torques".into());
                set.push(seq);
            }
            let keys: Vec<Key> = ticks.values().map(|&(t, v)| Key::new(t, v)).collect();
            let name = info.skeleton.dofs()[dof].name.clone();
            if let (Ok(track), Some(seq)) = (SeqTrack::new(name, keys), set.last_mut()) {
                // One track per DOF: adding cannot clash.
                let _ = seq.add_track(track);
            }
        }
        set
    }
}

/// What a servo follows.
#[derive(Clone, Debug, PartialEq)]
pub enum ServoTarget {
    /// Fixed desired values (DOF index, value); other DOFs keep their starting value.
    Posture(Vec<(usize, f64)>),
    /// Another actor's posture (and velocities), read each tick.
    Actor(usize),
}

/// What drives a dynamics action's simulated DOFs.
#[derive(Clone, Debug)]
pub enum Drive {
    /// Nothing: gravity, contact, limits and damping only.
    Passive,
    /// PD servos (eq. 4-1) toward a target.
    Servo {
        /// The target.
        target: ServoTarget,
        /// Gains per unit inertia.
        gains: Gains,
        /// Add the inverse-dynamics gravity torques.
        gravity_compensation: bool,
    },
    /// Closed-loop tracking of a sequence.
    Track {
        /// The sequence.
        sequence: Arc<Sequence>,
        /// Gains per unit inertia.
        gains: Gains,
    },
}

/// A dynamics action's generator.
pub struct DynamicsGenerator {
    drive: Drive,
    scope: Scope,
    params: SimParams,
    push: Option<(DVec3, DVec3, f64)>,
    finish_at_rest: bool,
    sim: Option<Simulation>,
    tracks: Vec<(usize, usize)>,
    desired: Vec<f64>,
    desired_qd: Vec<f64>,
    desired_qdd: Vec<f64>,
    at_rest_for: f64,
    torques: Option<TorqueLog>,
}

impl DynamicsGenerator {
    /// A generator simulating `scope` under `drive` with `params`. `push` applies a force
    /// and torque at the centre of mass for a while from the start; `finish_at_rest` ends
    /// the action once the body has stayed still for half a second.
    pub fn new(
        skeleton: &Skeleton,
        drive: Drive,
        scope: Scope,
        params: SimParams,
        push: Option<(DVec3, DVec3, f64)>,
        finish_at_rest: bool,
    ) -> troupe_scene::Result<DynamicsGenerator> {
        params.validate()?;
        let mut tracks = Vec::new();
        if let Drive::Track { sequence, .. } = &drive {
            for (i, t) in sequence.tracks().iter().enumerate() {
                tracks.push((skeleton.dof(t.dof())?, i));
            }
        }
        let n = skeleton.dof_count();
        Ok(DynamicsGenerator {
            drive,
            scope,
            params,
            push,
            finish_at_rest,
            sim: None,
            tracks,
            desired: vec![0.0; n],
            desired_qd: vec![0.0; n],
            desired_qdd: vec![0.0; n],
            at_rest_for: 0.0,
            torques: None,
        })
    }

    /// Logs the joint torques of every tick into `log`.
    pub fn log_torques(mut self, log: Option<TorqueLog>) -> DynamicsGenerator {
        self.torques = log;
        self
    }

    fn fill_desired(&mut self, ctx: &GeneratorContext) -> Result<(), String> {
        let posture = ctx.posture;
        match &self.drive {
            Drive::Passive => {}
            Drive::Servo { target, .. } => match target {
                ServoTarget::Posture(_) => {}
                ServoTarget::Actor(i) => {
                    let state = ctx
                        .world
                        .states
                        .get(*i)
                        .ok_or_else(|| format!("servo: no actor #{i}"))?;
                    for k in 0..self.desired.len() {
                        if self.scope.contains(k) {
                            self.desired[k] = state.q[k];
                            self.desired_qd[k] = state.qd[k];
                        }
                    }
                }
            },
            Drive::Track { sequence, .. } => {
                let t = sequence.start() + ctx.local_time.min(sequence.duration());
                let h = 1e-3;
                for &(k, i) in &self.tracks {
                    let track = &sequence.tracks()[i];
                    self.desired[k] = track.value(t);
                    self.desired_qd[k] = track.velocity(t);
                    self.desired_qdd[k] =
                        (track.velocity(t + h) - track.velocity(t - h)) / (2.0 * h);
                }
            }
        }
        // DOFs outside the scope are prescribed from the actor's posture.
        if let Some(sim) = &mut self.sim {
            for k in 0..posture.q.len() {
                if sim.is_prescribed(k) {
                    sim.set_prescribed(k, posture.q[k], posture.qd[k]);
                }
            }
        }
        Ok(())
    }
}

impl Generator for DynamicsGenerator {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), String> {
        let n = ctx.skeleton.dof_count();
        let root = ctx.skeleton.joints()[0].dofs.clone();
        let dynamic: Vec<bool> = (0..n)
            .map(|k| {
                self.scope.contains(k)
                    && (matches!(self.drive, Drive::Passive) || !root.contains(&k))
            })
            .collect();
        let mut sim = Simulation::new(
            ctx.skeleton,
            &ctx.posture.q,
            &ctx.posture.qd,
            &dynamic,
            self.params,
        )
        .map_err(|e| e.to_string())?;
        if let Some((force, torque, duration)) = self.push {
            sim.push(force, torque, duration);
        }
        self.desired.copy_from_slice(&ctx.posture.q);
        if let Drive::Servo {
            target: ServoTarget::Posture(values),
            ..
        } = &self.drive
        {
            for &(k, v) in values {
                self.desired[k] = v;
            }
        }
        self.sim = Some(sim);
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        if let Err(e) = self.fill_desired(ctx) {
            return Step::Failed(e);
        }
        let Some(sim) = &mut self.sim else {
            return Step::Failed("dynamics: not started".into());
        };
        let control = match &self.drive {
            Drive::Passive => Control::Passive,
            Drive::Servo {
                gains,
                gravity_compensation,
                ..
            } => Control::Servo {
                q: &self.desired,
                qd: &self.desired_qd,
                gains: *gains,
                gravity_compensation: *gravity_compensation,
            },
            Drive::Track { gains, .. } => Control::Track {
                q: &self.desired,
                qd: &self.desired_qd,
                qdd: &self.desired_qdd,
                gains: *gains,
            },
        };
        if let Err(e) = sim.advance(ctx.dt, &control) {
            return Step::Failed(e.to_string());
        }
        let q = sim.q();
        for k in self.scope.iter() {
            if !sim.is_prescribed(k) {
                out.set(k, q[k]);
            }
        }
        if let Some(log) = &self.torques {
            let tau = sim.mean_torques();
            for k in self.scope.iter() {
                if !sim.is_prescribed(k) {
                    log.record(ctx.actor, k, ctx.tick, ctx.time, tau[k]);
                }
            }
        }
        match &self.drive {
            Drive::Track { sequence, .. } if ctx.local_time >= sequence.duration() => {
                return Step::Finished
            }
            Drive::Passive if self.finish_at_rest => {
                let (kinetic, _) = sim.energy();
                if kinetic < 1e-3 * sim.model().total_mass() {
                    self.at_rest_for += ctx.dt;
                } else {
                    self.at_rest_for = 0.0;
                }
                if self.at_rest_for >= 0.5 {
                    return Step::Finished;
                }
            }
            _ => {}
        }
        Step::Running
    }
}

/// Registers `simulate`, `servo` and `track`.
pub fn register(kinds: &mut ActionKinds) {
    kinds.register(ActionKind {
        method: "simulate",
        build: build_simulate,
    });
    kinds.register(ActionKind {
        method: "servo",
        build: build_servo,
    });
    kinds.register(ActionKind {
        method: "track",
        build: build_track,
    });
}

const SIM_OPTIONS: [&str; 6] = [
    "gravity",
    "floor",
    "damping",
    "small_time_step",
    "time_step",
    "limits",
];

fn sim_params(t: Option<&Table>, method: &str, damping: f64) -> mlua::Result<SimParams> {
    let mut p = SimParams {
        damping,
        ..SimParams::default()
    };
    let Some(t) = t else { return Ok(p) };
    let g: Value = t.get("gravity")?;
    if !g.is_nil() {
        p.gravity = vec3(&g, &format!("{method}: gravity"))?;
    }
    if opt_bool(t, method, "floor")? == Some(false) {
        p.floor = None;
    } else {
        p.floor = Some(ContactParams::default());
    }
    if let Some(l) = opt_bool(t, method, "limits")? {
        p.joint_limits = l;
    }
    if let Some(d) = opt_number(t, method, "damping")? {
        p.damping = d;
    }
    if let Some(s) = opt_number(t, method, "small_time_step")? {
        p.small_time_step = s;
    }
    if let Some(s) = opt_number(t, method, "time_step")? {
        p.time_step = s;
    }
    p.validate()
        .map_err(|e| lua_err_message(format!("{method}: {e}")))?;
    Ok(p)
}

fn gains(t: Option<&Table>, method: &str) -> mlua::Result<Gains> {
    let mut g = Gains::default();
    if let Some(t) = t {
        if let Some(kp) = opt_number(t, method, "kp")? {
            g.kp = kp;
            g.kd = 2.0 * kp.max(0.0).sqrt();
        }
        if let Some(kd) = opt_number(t, method, "kd")? {
            g.kd = kd;
        }
    }
    g.validate()
        .map_err(|e| lua_err_message(format!("{method}: {e}")))?;
    Ok(g)
}

fn extras(own: &[&'static str]) -> Vec<&'static str> {
    let mut v = SIM_OPTIONS.to_vec();
    v.extend_from_slice(own);
    v
}

/// `actor:simulate{ scope, duration, gravity, floor, damping, limits, push, … }`.
fn build_simulate(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let opts = opt_table_arg("simulate", args)?;
    let common = CommonOptions::parse(ctx, "simulate", opts.as_ref(), &extras(&["push"]))?;
    let params = sim_params(opts.as_ref(), "simulate", 2.0)?;
    let mut push = None;
    if let Some(t) = &opts {
        match t.get::<Value>("push")? {
            Value::Nil => {}
            Value::Table(p) => {
                let read = |k: &str| -> mlua::Result<DVec3> {
                    let v: Value = p.get(k)?;
                    if v.is_nil() {
                        Ok(DVec3::ZERO)
                    } else {
                        vec3(&v, &format!("simulate: push.{k}"))
                    }
                };
                let duration = opt_number(&p, "simulate", "duration")?.unwrap_or(0.1);
                if !(duration.is_finite() && duration >= 0.0) {
                    return Err(lua_err_message("simulate: push.duration must be ≥ 0"));
                }
                push = Some((read("force")?, read("torque")?, duration));
            }
            other => {
                return Err(lua_err_message(format!(
                    "simulate: option `push` must be a table {{force, torque, duration}}, got {}",
                    other.type_name()
                )))
            }
        }
    }
    let scope = common.scope.unwrap_or_else(|| ctx.skeleton.all());
    let generator = DynamicsGenerator::new(
        &ctx.skeleton,
        Drive::Passive,
        scope,
        params,
        push,
        common.duration.is_none(),
    )
    .map_err(|e| lua_err_message(format!("simulate: {e}")))?
    .log_torques(TorqueLog::installed(ctx.lua));
    Ok((Box::new(generator), common.spec("simulate", scope)))
}

/// `actor:servo{ target = {dof = value, …} or actor, kp, kd, gravity_compensation, … }`.
fn build_servo(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let opts = opt_table_arg("servo", args)?;
    let common = CommonOptions::parse(
        ctx,
        "servo",
        opts.as_ref(),
        &extras(&["target", "kp", "kd", "gravity_compensation"]),
    )?;
    let t = opts
        .as_ref()
        .ok_or_else(|| lua_err_message("servo: `target` is required"))?;
    let skel = &ctx.skeleton;
    let body = skel.scope("body").unwrap_or_else(|_| {
        skel.all()
            .difference(&Scope::range(skel.joints()[0].dofs.clone()))
    });
    let (target, natural) = match t.get::<Value>("target")? {
        Value::Table(values) => {
            let mut list = Vec::new();
            for pair in values.pairs::<String, f64>() {
                let (name, v) = pair.map_err(|e| {
                    lua_err_message(format!(
                        "servo: target must be {{dof_name = number, …}}: {e}"
                    ))
                })?;
                if !v.is_finite() {
                    return Err(lua_err_message(format!(
                        "servo: target `{name}` is not finite"
                    )));
                }
                let k = skel
                    .dof(&name)
                    .map_err(|e| lua_err_message(format!("servo: target: {e}")))?;
                list.push((k, skel.dofs()[k].clamp(v)));
            }
            list.sort_by_key(|(k, _)| *k);
            let natural: Scope = list.iter().map(|(k, _)| *k).collect();
            (ServoTarget::Posture(list), natural.intersection(&body))
        }
        Value::UserData(u) => {
            let other = u
                .borrow::<ActorRef>()
                .map_err(|_| lua_err_message("servo: target must be a posture table or an actor"))?
                .0;
            let same = ctx.with_scene(|s| {
                let o = &s.actors()[other].skeleton;
                o.dof_count() == skel.dof_count()
                    && o.dofs()
                        .iter()
                        .zip(skel.dofs())
                        .all(|(a, b)| a.name == b.name)
            })?;
            if !same {
                return Err(lua_err_message(
                    "servo: the target actor must have the same DOFs (same template topology)",
                ));
            }
            (ServoTarget::Actor(other), body)
        }
        Value::Nil => return Err(lua_err_message("servo: `target` is required")),
        other => {
            return Err(lua_err_message(format!(
                "servo: target must be a posture table or an actor, got {}",
                other.type_name()
            )))
        }
    };
    let drive = Drive::Servo {
        target,
        gains: gains(Some(t), "servo")?,
        gravity_compensation: opt_bool(t, "servo", "gravity_compensation")?.unwrap_or(true),
    };
    let params = sim_params(Some(t), "servo", 0.0)?;
    let scope = common.scope.unwrap_or(natural);
    let generator = DynamicsGenerator::new(skel, drive, scope, params, None, false)
        .map_err(|e| lua_err_message(format!("servo: {e}")))?
        .log_torques(TorqueLog::installed(ctx.lua));
    Ok((Box::new(generator), common.spec("servo", scope)))
}

/// `actor:track{ sequence = seq_or_path, kp, kd, … }`.
fn build_track(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let opts = opt_table_arg("track", args)?;
    let common = CommonOptions::parse(
        ctx,
        "track",
        opts.as_ref(),
        &extras(&["sequence", "kp", "kd"]),
    )?;
    let t = opts
        .as_ref()
        .ok_or_else(|| lua_err_message("track: `sequence` is required"))?;
    let sequence = match t.get::<Value>("sequence")? {
        Value::String(path) => load_sequence(ctx.lua, &path.to_str()?, Some(&ctx.skeleton))?,
        Value::UserData(u) => u
            .borrow::<SequenceRef>()
            .map_err(|_| lua_err_message("track: `sequence` must be a sequence or a file path"))?
            .0
            .clone(),
        other => {
            return Err(lua_err_message(format!(
                "track: `sequence` must be a sequence or a file path, got {}",
                other.type_name()
            )))
        }
    };
    let skel = &ctx.skeleton;
    let root = Scope::range(skel.joints()[0].dofs.clone());
    let mut natural = Scope::EMPTY;
    for track in sequence.tracks() {
        let k = skel
            .dof(track.dof())
            .map_err(|e| lua_err_message(format!("track: {e}")))?;
        natural.insert(k);
    }
    let scope = common.scope.unwrap_or(natural).difference(&root);
    if scope.is_empty() {
        return Err(lua_err_message(
            "track: nothing to track (the sequence's DOFs on the scope, root excluded)",
        ));
    }
    let drive = Drive::Track {
        sequence,
        gains: gains(Some(t), "track")?,
    };
    let params = sim_params(Some(t), "track", 0.0)?;
    let generator = DynamicsGenerator::new(skel, drive, scope, params, None, false)
        .map_err(|e| lua_err_message(format!("track: {e}")))?
        .log_torques(TorqueLog::installed(ctx.lua));
    Ok((Box::new(generator), common.spec("track", scope)))
}
