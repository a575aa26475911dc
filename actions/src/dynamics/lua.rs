//! `actor:simulate{…}`, `actor:servo{…}` and `actor:track{…}` in Lua: reads
//! [`DynamicsOptions`].

use super::options::gains;
use super::{Drive, DynamicsOptions, Push, ServoTarget};
use mlua::{MultiValue, Table, Value};
use troupe_body::dynamics::contact::ContactParams;
use troupe_body::dynamics::SimParams;
use troupe_body::glam::DVec3;
use troupe_lua::api::{load_sequence, ActorRef, SequenceRef};
use troupe_lua::args::{actor_arg, check_keys, err, opt_bool, opt_number, opt_table_arg, vec3};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// The simulation options every dynamics kind takes.
const SIM_OPTIONS: [&str; 6] = [
    "gravity",
    "floor",
    "damping",
    "small_time_step",
    "time_step",
    "limits",
];

/// The simulation options and then a kind's own.
fn extras(own: &[&'static str]) -> Vec<&'static str> {
    let mut v = SIM_OPTIONS.to_vec();
    v.extend_from_slice(own);
    v
}

/// Reads the simulation options over `p` (the kind's defaults).
fn sim_params(t: Option<&Table>, method: &str, mut p: SimParams) -> mlua::Result<SimParams> {
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
    Ok(p)
}

/// Makes the generator of `options` (once valid) on the simulated scope, and its spec.
fn build(
    ctx: &BuildContext,
    m: &str,
    common: &CommonOptions,
    options: &DynamicsOptions,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let scope = options
        .scope(&ctx.skeleton, common.scope)
        .map_err(|e| err(m, e))?;
    let generator = options
        .generator(&ctx.skeleton, scope)
        .map_err(|e| err(m, e))?;
    Ok((Box::new(generator), common.spec(m, scope)))
}

/// `actor:simulate{ scope, duration, gravity, floor, damping, limits, push, … }`.
pub fn build_simulate(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "simulate";
    let opts = opt_table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, opts.as_ref(), &extras(&["push"]))?;
    let mut options = DynamicsOptions::new(Drive::Passive);
    options.params = sim_params(opts.as_ref(), m, options.params)?;
    options.finish_at_rest = common.duration.is_none();
    if let Some(t) = &opts {
        match t.get::<Value>("push")? {
            Value::Nil => {}
            Value::Table(p) => {
                check_keys(&p, "simulate: push", &["force", "torque", "duration"])?;
                let read = |k: &str| -> mlua::Result<DVec3> {
                    let v: Value = p.get(k)?;
                    if v.is_nil() {
                        Ok(DVec3::ZERO)
                    } else {
                        vec3(&v, &format!("simulate: push.{k}"))
                    }
                };
                options.push = Some(Push {
                    force: read("force")?,
                    torque: read("torque")?,
                    duration: opt_number(&p, m, "duration")?.unwrap_or(0.1),
                });
            }
            other => {
                return Err(err(
                    m,
                    format!(
                        "option `push` must be a table {{force, torque, duration}}, got {}",
                        other.type_name()
                    ),
                ))
            }
        }
    }
    build(ctx, m, &common, &options)
}

/// `actor:servo{ target = {dof = value, …} or actor, kp, kd, gravity_compensation, … }`.
pub fn build_servo(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "servo";
    let opts = opt_table_arg(m, args)?;
    let common = CommonOptions::parse(
        ctx,
        m,
        opts.as_ref(),
        &extras(&["target", "kp", "kd", "gravity_compensation"]),
    )?;
    let t = opts
        .as_ref()
        .ok_or_else(|| err(m, "`target` is required"))?;
    let skel = &ctx.skeleton;
    let target = match t.get::<Value>("target")? {
        Value::Table(values) => {
            let mut list = Vec::new();
            for pair in values.pairs::<String, f64>() {
                let (name, v) = pair
                    .map_err(|e| err(m, format!("target must be {{dof_name = number, …}}: {e}")))?;
                if !v.is_finite() {
                    return Err(err(m, format!("target `{name}` is not finite")));
                }
                let k = skel
                    .dof(&name)
                    .map_err(|e| err(m, format!("target: {e}")))?;
                list.push((k, skel.dofs()[k].clamp(v)));
            }
            list.sort_by_key(|(k, _)| *k);
            ServoTarget::Posture(list)
        }
        // An actor, by handle or by name (as `walk`, `give` and `grasp` take them).
        target @ (Value::UserData(_) | Value::String(_)) => {
            if let Value::UserData(u) = &target {
                if !u.is::<ActorRef>() {
                    return Err(err(m, "target must be a posture table or an actor"));
                }
            }
            let other = actor_arg(ctx.lua, m, "target", target)?;
            let same = ctx.with_scene(|s| {
                let o = &s.actors()[other].skeleton;
                o.dof_count() == skel.dof_count()
                    && o.dofs()
                        .iter()
                        .zip(skel.dofs())
                        .all(|(a, b)| a.name == b.name)
            })?;
            if !same {
                return Err(err(
                    m,
                    "the target actor must have the same DOFs (same template topology)",
                ));
            }
            ServoTarget::Actor(other)
        }
        Value::Nil => return Err(err(m, "`target` is required")),
        other => {
            return Err(err(
                m,
                format!(
                    "target must be a posture table, an actor or an actor's name, got {}",
                    other.type_name()
                ),
            ))
        }
    };
    let mut options = DynamicsOptions::new(Drive::Servo {
        target,
        gains: gains(opt_number(t, m, "kp")?, opt_number(t, m, "kd")?),
        gravity_compensation: opt_bool(t, m, "gravity_compensation")?.unwrap_or(true),
    });
    options.params = sim_params(Some(t), m, options.params)?;
    build(ctx, m, &common, &options)
}

/// `actor:track{ sequence = seq_or_path, kp, kd, … }`.
pub fn build_track(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "track";
    let opts = opt_table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, opts.as_ref(), &extras(&["sequence", "kp", "kd"]))?;
    let t = opts
        .as_ref()
        .ok_or_else(|| err(m, "`sequence` is required"))?;
    let sequence = match t.get::<Value>("sequence")? {
        Value::String(path) => load_sequence(ctx.lua, &path.to_str()?, Some(&ctx.skeleton))?,
        Value::UserData(u) => u
            .borrow::<SequenceRef>()
            .map_err(|_| err(m, "`sequence` must be a sequence or a file path"))?
            .0
            .clone(),
        other => {
            return Err(err(
                m,
                format!(
                    "`sequence` must be a sequence or a file path, got {}",
                    other.type_name()
                ),
            ))
        }
    };
    let mut options = DynamicsOptions::new(Drive::Track {
        sequence,
        gains: gains(opt_number(t, m, "kp")?, opt_number(t, m, "kd")?),
    });
    options.params = sim_params(Some(t), m, options.params)?;
    build(ctx, m, &common, &options)
}
