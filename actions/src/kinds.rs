//! The action kinds this crate adds to Lua: one registration per kind.

use crate::keyframe::Keyframe;
use crate::look_at::LookAt;
use crate::reach::{Reach, ReachSpec, Target};
use mlua::{MultiValue, Table, Value};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::jacobian::{ancestor_dofs, scope_dofs_moving, Effector};
use troupe_body::Scope;
use troupe_lua::api::{load_sequence, lua_err_message, ActorRef, ObjectRef, SequenceRef};
use troupe_lua::kinds::args::{euler_degrees, opt_bool, opt_string, table_arg, vec3};
use troupe_lua::kinds::{ActionKind, ActionKinds, BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// Every action kind implemented here, ready for a [`troupe_lua::Director`].
pub fn action_kinds() -> ActionKinds {
    let mut kinds = ActionKinds::default();
    kinds.register(ActionKind {
        method: "play",
        build: build_play,
    });
    // Dynamics: simulate, servo, track.
    crate::dynamics::register(&mut kinds);
    kinds.register(ActionKind {
        method: "reach",
        build: build_reach,
    });
    kinds.register(ActionKind {
        method: "ik",
        build: build_ik,
    });
    kinds.register(ActionKind {
        method: "look_at",
        build: build_look_at,
    });
    // Walking: the procedural walking motor (thesis 2.6, 6.4.2).
    crate::walk::register(&mut kinds);
    // Grasping, manipulation, interaction: grasp, release, place, manipulate, give,
    // hold_hand, shake_hands and troupe.plan_grasp.
    crate::grasp::register(&mut kinds);
    kinds
}

/// `actor:play(sequence_or_path, { loop = bool, <common options> })`.
fn build_play(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let mut args = args.into_iter();
    let sequence = match args.next() {
        Some(Value::String(path)) => load_sequence(ctx.lua, &path.to_str()?, Some(&ctx.skeleton))?,
        Some(Value::UserData(u)) => match u.borrow::<SequenceRef>() {
            Ok(s) => s.0.clone(),
            Err(_) => {
                return Err(lua_err_message(
                    "play: the first argument must be a sequence or a file path",
                ))
            }
        },
        other => {
            return Err(lua_err_message(format!(
                "play: the first argument must be a sequence or a file path, got {}",
                other.map(|v| v.type_name()).unwrap_or("nothing")
            )))
        }
    };
    let opts = match args.next() {
        None | Some(Value::Nil) => None,
        Some(Value::Table(t)) => Some(t),
        Some(other) => {
            return Err(lua_err_message(format!(
                "play: the second argument must be a table of options, got {}",
                other.type_name()
            )))
        }
    };
    let common = CommonOptions::parse(ctx, "play", opts.as_ref(), &["loop"])?;
    let looping = match &opts {
        Some(t) => opt_bool(t, "play", "loop")?,
        None => None,
    };
    let generator = Keyframe::shared(&ctx.skeleton, sequence, common.scope, looping)
        .map_err(|e| lua_err_message(format!("play: {e}")))?;
    let spec = common.spec("keyframe", generator.scope());
    Ok((Box::new(generator), spec))
}

/// Reads a target: an object, an actor (its root), `{actor = A, joint = NAME[, offset =
/// {x, y, z}]}` or a point `{x, y, z}`.
fn parse_target(ctx: &BuildContext, method: &str, value: Value) -> mlua::Result<Target> {
    match value {
        Value::Nil => Err(lua_err_message(format!("{method}: `target` is required"))),
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
            Err(lua_err_message(format!(
                "{method}: `target` must be an object, an actor, {{actor=…, joint=…}} or {{x, y, z}}"
            )))
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
                    .map_err(|_| lua_err_message(format!("{method}: target.actor must be an actor")))?,
                Value::String(name) => {
                    let name = name.to_str()?.to_string();
                    ctx.with_scene(|s| s.actor_index(&name))?
                        .map_err(|e| lua_err_message(format!("{method}: target: {e}")))?
                }
                other => {
                    return Err(lua_err_message(format!(
                        "{method}: target.actor must be an actor or a name, got {}",
                        other.type_name()
                    )))
                }
            };
            let joint = opt_string(&t, method, "joint")?
                .ok_or_else(|| lua_err_message(format!("{method}: target.joint is required")))?;
            let (actor, known) = ctx.with_scene(|s| {
                let a = &s.actors()[index];
                (a.name.clone(), a.skeleton.joint(&joint).map(|_| ()))
            })?;
            known.map_err(|e| lua_err_message(format!("{method}: target: {e}")))?;
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
        other => Err(lua_err_message(format!(
            "{method}: `target` must be an object, an actor, {{actor=…, joint=…}} or {{x, y, z}}, got {}",
            other.type_name()
        ))),
    }
}

/// Reads `orientation = {x, y, z}` (Euler degrees, applied Y, X, Z, as object rotations).
fn parse_orientation(method: &str, t: &Table) -> mlua::Result<Option<DQuat>> {
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
fn parse_via(method: &str, t: &Table) -> mlua::Result<Vec<DVec3>> {
    match t.get::<Value>("via")? {
        Value::Nil => Ok(Vec::new()),
        Value::Table(list) => list
            .sequence_values::<Value>()
            .enumerate()
            .map(|(i, v)| vec3(&v?, &format!("{method}: via[{}]", i + 1)))
            .collect(),
        other => Err(lua_err_message(format!(
            "{method}: `via` must be a list of points, got {}",
            other.type_name()
        ))),
    }
}

/// The shared part of `reach` and `ik`.
fn build_reaching(
    ctx: &BuildContext,
    method: &str,
    t: &Table,
    common: CommonOptions,
    effector: Effector,
    natural: Scope,
    collision_default: bool,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let target = parse_target(ctx, method, t.get("target")?)?;
    let self_collision = opt_bool(t, method, "self_collision")?
        .or_else(|| troupe_lua::settings::self_collision(ctx.lua, ctx.actor))
        .unwrap_or(collision_default);
    let scope = common.scope.unwrap_or(natural);
    let dofs = scope_dofs_moving(&ctx.skeleton, &scope, effector.joint);
    if dofs.is_empty() {
        return Err(lua_err_message(format!(
            "{method}: the scope has no DOF that moves the effector"
        )));
    }
    let spec = ReachSpec {
        effector,
        target,
        orientation: parse_orientation(method, t)?,
        duration: common.duration.unwrap_or(1.0),
        via: parse_via(method, t)?,
        self_collision,
        dofs,
    };
    let generator =
        Reach::new(&ctx.skeleton, spec).map_err(|e| lua_err_message(format!("{method}: {e}")))?;
    let natural_scope: Scope = generator.dofs().iter().copied().collect();
    let mut action = common.spec("reach", natural_scope);
    action.kind = method.to_string();
    // The generator decides when it is done (and whether it failed).
    action.duration = None;
    Ok((Box::new(generator), action))
}

/// `actor:reach{ hand = "right"|"left", target = …, orientation = {x, y, z}, via = {…},
/// self_collision = bool, <common options> }`.
fn build_reach(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let t = table_arg("reach", args)?;
    let common = CommonOptions::parse(
        ctx,
        "reach",
        Some(&t),
        &["hand", "target", "orientation", "via", "self_collision"],
    )?;
    let side = match opt_string(&t, "reach", "hand")?.as_deref() {
        None | Some("right") => "r",
        Some("left") => "l",
        Some(other) => {
            return Err(lua_err_message(format!(
                "reach: `hand` must be \"right\" or \"left\", got \"{other}\""
            )))
        }
    };
    let skeleton = &ctx.skeleton;
    let err = |e: troupe_body::Error| lua_err_message(format!("reach: {e}"));
    let wrist = skeleton.joint(&format!("{side}_wrist")).map_err(err)?;
    let hand_name = format!("{side}_hand");
    let point = skeleton
        .solids()
        .iter()
        .find(|(_, s)| s.name == hand_name)
        .map(|(_, s)| s.center)
        .unwrap_or(DVec3::ZERO);
    let natural = skeleton
        .scope(if side == "r" { "right_arm" } else { "left_arm" })
        .map_err(err)?;
    build_reaching(
        ctx,
        "reach",
        &t,
        common,
        Effector {
            joint: wrist,
            point,
        },
        natural,
        true,
    )
}

/// `actor:ik{ effector = JOINT, point = {x, y, z}, target = …, orientation = …, via = …,
/// self_collision = bool, <common options> }`.
fn build_ik(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let t = table_arg("ik", args)?;
    let common = CommonOptions::parse(
        ctx,
        "ik",
        Some(&t),
        &[
            "effector",
            "point",
            "target",
            "orientation",
            "via",
            "self_collision",
        ],
    )?;
    let name = opt_string(&t, "ik", "effector")?
        .ok_or_else(|| lua_err_message("ik: `effector` (a joint name) is required"))?;
    let skeleton = &ctx.skeleton;
    let joint = skeleton
        .joint(&name)
        .map_err(|e| lua_err_message(format!("ik: {e}")))?;
    let point: Value = t.get("point")?;
    let point = if point.is_nil() {
        DVec3::ZERO
    } else {
        vec3(&point, "ik: point")?
    };
    let global = skeleton.scope("global").unwrap_or(Scope::EMPTY);
    let natural = ancestor_dofs(skeleton, joint).difference(&global);
    build_reaching(
        ctx,
        "ik",
        &t,
        common,
        Effector { joint, point },
        natural,
        false,
    )
}

/// `actor:look_at{ target = …, <common options> }`.
fn build_look_at(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let t = table_arg("look_at", args)?;
    let common = CommonOptions::parse(ctx, "look_at", Some(&t), &["target"])?;
    let target = parse_target(ctx, "look_at", t.get("target")?)?;
    let generator =
        LookAt::new(&ctx.skeleton, target).map_err(|e| lua_err_message(format!("look_at: {e}")))?;
    let natural: Scope = generator.scope_dofs().into_iter().collect();
    Ok((Box::new(generator), common.spec("look_at", natural)))
}
