//! `actor:reach{…}` and `actor:ik{…}` in Lua: reads [`ReachOptions`] (and the target
//! reader `look_at` shares).

use super::{ReachOptions, Reacher, Target};
use mlua::{MultiValue, Table, Value};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::sensors::Side;
use troupe_body::Scope;
use troupe_lua::api::{ActorRef, ObjectRef};
use troupe_lua::args::{err, euler_degrees, opt_bool, opt_string, table_arg, vec3};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// The options of `reach` and `ik` besides the common ones and the effector's.
const REACH_OPTIONS: [&str; 5] = ["target", "orientation", "via", "self_collision", "detour"];

/// `actor:reach{ hand = "right"|"left", target = …, orientation = {x, y, z}, via = {…},
/// self_collision = bool, detour = bool, <common options> }`.
pub fn build_reach(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "reach";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &[&["hand"], &REACH_OPTIONS[..]].concat())?;
    let side = match opt_string(&t, m, "hand")?.as_deref() {
        None | Some("right") => Side::Right,
        Some("left") => Side::Left,
        Some(other) => {
            return Err(err(
                m,
                format!("`hand` must be \"right\" or \"left\", got \"{other}\""),
            ))
        }
    };
    build(ctx, m, &t, common, Reacher::Hand(side))
}

/// `actor:ik{ effector = JOINT, point = {x, y, z}, target = …, orientation = …, via = …,
/// self_collision = bool, detour = bool, <common options> }`.
pub fn build_ik(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "ik";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(
        ctx,
        m,
        Some(&t),
        &[&["effector", "point"], &REACH_OPTIONS[..]].concat(),
    )?;
    let name = opt_string(&t, m, "effector")?
        .ok_or_else(|| err(m, "`effector` (a joint name) is required"))?;
    let point: Value = t.get("point")?;
    let point = if point.is_nil() {
        DVec3::ZERO
    } else {
        vec3(&point, "ik: point")?
    };
    build(ctx, m, &t, common, Reacher::Joint { name, point })
}

/// Reads the options `reach` and `ik` share and makes the action.
fn build(
    ctx: &BuildContext,
    m: &str,
    t: &Table,
    common: CommonOptions,
    effector: Reacher,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let mut options = ReachOptions::new(effector, target(ctx, m, t.get("target")?)?);
    // The default comes from the actor's settings (`actor:set{self_collision = …}`).
    if let Some(on) = opt_bool(t, m, "self_collision")?
        .or_else(|| troupe_lua::settings::self_collision(ctx.lua, ctx.actor))
    {
        options.self_collision = on;
    }
    if let Some(on) = opt_bool(t, m, "detour")? {
        options.detour = on;
    }
    options.orientation = orientation(m, t)?;
    options.via = via(m, t)?;
    options.duration = common.duration.unwrap_or(options.duration);
    options.scope = common.scope;
    let hand = matches!(options.effector, Reacher::Hand(_));
    let generator = options.reach(&ctx.skeleton).map_err(|e| err(m, e))?;
    let mut natural: Scope = generator.dofs().iter().copied().collect();
    // A hand reach may lean and crouch when the arm alone does not reach: its default
    // scope adds that part, yieldable (it starts at once during a walk, without the legs).
    let body = crate::grasp::body::BodyReach::body_scope(&ctx.skeleton).map_err(|e| err(m, e))?;
    if hand && common.scope.is_none() {
        natural = natural.union(&body);
    }
    let mut spec = common.spec(options.kind(), natural);
    spec.yields = body.intersection(&spec.scope);
    // The generator decides when it is done (and whether it failed).
    spec.duration = None;
    Ok((Box::new(generator), spec))
}

/// Reads a target: an object, an actor (its root), `{actor = A, joint = NAME[, offset =
/// {x, y, z}]}` or a point `{x, y, z}`.
pub(crate) fn target(ctx: &BuildContext, method: &str, value: Value) -> mlua::Result<Target> {
    let expected = "`target` must be an object, an actor, {actor=…, joint=…} or {x, y, z}";
    match value {
        Value::Nil => Err(err(method, "`target` is required")),
        Value::UserData(u) => {
            if let Ok(o) = u.borrow::<ObjectRef>() {
                let i = o.0;
                return Ok(Target::Object(
                    ctx.with_scene(|s| s.objects()[i].name.clone())?,
                ));
            }
            if let Ok(a) = u.borrow::<ActorRef>() {
                let i = a.0;
                return Ok(Target::Joint {
                    actor: ctx.with_scene(|s| s.actors()[i].name.clone())?,
                    joint: "HumanoidRoot".into(),
                    offset: DVec3::ZERO,
                });
            }
            Err(err(method, expected))
        }
        Value::Table(t) => {
            let actor: Value = t.get("actor")?;
            if actor.is_nil() {
                return Ok(Target::Point(vec3(
                    &Value::Table(t),
                    &format!("{method}: target"),
                )?));
            }
            let index = match actor {
                Value::UserData(u) => u
                    .borrow::<ActorRef>()
                    .map(|a| a.0)
                    .map_err(|_| err(method, "target.actor must be an actor"))?,
                Value::String(name) => {
                    let name = name.to_str()?.to_string();
                    ctx.with_scene(|s| s.actor_index(&name))?
                        .map_err(|e| err(method, format!("target: {e}")))?
                }
                other => {
                    return Err(err(
                        method,
                        format!(
                            "target.actor must be an actor or a name, got {}",
                            other.type_name()
                        ),
                    ))
                }
            };
            let joint = opt_string(&t, method, "joint")?
                .ok_or_else(|| err(method, "target.joint is required"))?;
            let (actor, known) = ctx.with_scene(|s| {
                let a = &s.actors()[index];
                (a.name.clone(), a.skeleton.joint(&joint).map(|_| ()))
            })?;
            known.map_err(|e| err(method, format!("target: {e}")))?;
            let offset: Value = t.get("offset")?;
            let offset = if offset.is_nil() {
                DVec3::ZERO
            } else {
                vec3(&offset, &format!("{method}: target.offset"))?
            };
            Ok(Target::Joint {
                actor,
                joint,
                offset,
            })
        }
        other => Err(err(
            method,
            format!("{expected}, got {}", other.type_name()),
        )),
    }
}

/// Reads `orientation = {x, y, z}` (Euler degrees, applied Y, X, Z, as object rotations).
fn orientation(method: &str, t: &Table) -> mlua::Result<Option<DQuat>> {
    let v: Value = t.get("orientation")?;
    if v.is_nil() {
        return Ok(None);
    }
    euler_degrees(
        &v,
        &format!("{method}: orientation (degrees about x, y, z)"),
    )
    .map(Some)
}

/// Reads `via = {{x, y, z}, …}`.
fn via(method: &str, t: &Table) -> mlua::Result<Vec<DVec3>> {
    match t.get::<Value>("via")? {
        Value::Nil => Ok(Vec::new()),
        Value::Table(list) => list
            .sequence_values::<Value>()
            .enumerate()
            .map(|(i, v)| vec3(&v?, &format!("{method}: via[{}]", i + 1)))
            .collect(),
        other => Err(err(
            method,
            format!("`via` must be a list of points, got {}", other.type_name()),
        )),
    }
}
