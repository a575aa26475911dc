//! `actor:walk{…}` in Lua: one of `to`, `path`, `velocity` or `follow`, the
//! personification options and the common action options.

use super::goal::{Goal, CONVERSATION_DISTANCE, GRASP_DISTANCE};
use super::route::{Route, Speed, PROFILE_DT};
use super::{Walk, WalkOptions};
use mlua::{MultiValue, Value};
use troupe_body::glam::DVec2;
use troupe_lua::api::{load_sequence, ActorRef, ObjectRef, SequenceRef};
use troupe_lua::args::{caught_text, err, floor_point, number, opt_bool, opt_number, table_arg};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// The walk's own option names (besides the common ones).
const WALK_OPTIONS: [&str; 15] = [
    "to",
    "distance",
    "path",
    "velocity",
    "follow",
    "speed",
    "heading",
    "step_length",
    "step_width",
    "pelvis",
    "arm_swing",
    "bounce",
    "run",
    "arms",
    "patience",
];

/// `actor:walk{ to = {x, 0, z} | path = {{x, z}, …} | velocity = number_or_function |
/// follow = SEQUENCE_or_path, speed = m/s, heading = degrees, step_length, step_width,
/// pelvis, arm_swing, bounce, run, arms = bool, patience = seconds, <common options> }`.
pub fn build_walk(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let t = table_arg("walk", args)?;
    let common = CommonOptions::parse(ctx, "walk", Some(&t), &WALK_OPTIONS)?;
    let mut options = WalkOptions::default();
    let num = |k: &str| opt_number(&t, "walk", k);
    if let Some(v) = num("speed")? {
        options.speed = v;
    }
    if let Some(h) = num("heading")? {
        if !h.is_finite() {
            return Err(err(
                "walk",
                format!("`heading` must be finite degrees, got {h}"),
            ));
        }
        options.heading = Some(h.to_radians());
    }
    for (key, slot) in [
        ("step_length", &mut options.step_length),
        ("step_width", &mut options.step_width),
        ("pelvis", &mut options.pelvis),
        ("arm_swing", &mut options.arm_swing),
        ("bounce", &mut options.bounce),
        ("run", &mut options.run),
    ] {
        if let Some(v) = num(key)? {
            *slot = v;
        }
    }
    if let Some(b) = opt_bool(&t, "walk", "arms")? {
        options.arms = b;
    }
    options.patience = num("patience")?;
    let given: Vec<&str> = ["to", "path", "velocity", "follow"]
        .into_iter()
        .filter(|k| !matches!(t.get::<Value>(*k), Ok(Value::Nil)))
        .collect();
    if given.len() != 1 {
        return Err(err(
            "walk",
            format!(
                "give exactly one of `to`, `path`, `velocity` or `follow` (got {})",
                if given.is_empty() {
                    "none".to_string()
                } else {
                    given.join(", ")
                }
            ),
        ));
    }
    let kind = given[0];
    if options.heading.is_some() && !matches!(kind, "to" | "path") {
        return Err(err(
            "walk",
            format!("`heading` (the way to face on arrival) applies to `to` and `path` walks, not to a `{kind}` walk"),
        ));
    }
    if options.patience.is_some() && !matches!(kind, "to" | "path") {
        return Err(err(
            "walk",
            format!("`patience` (how long to wait for those in the way) applies to `to` and `path` walks, not to a `{kind}` walk"),
        ));
    }
    if kind != "velocity" && common.duration.is_some() {
        return Err(err(
            "walk",
            format!("`duration` applies to velocity walks; a `{kind}` walk ends when it arrives"),
        ));
    }
    if kind == "velocity" && num("speed")?.is_some() {
        return Err(err(
            "walk",
            "a velocity walk takes its speed from `velocity`, not `speed`",
        ));
    }
    let distance = num("distance")?;
    if let Some(d) = distance {
        if !(d.is_finite() && (0.0..=10.0).contains(&d)) {
            return Err(err(
                "walk",
                format!("`distance` must be in [0, 10] m, got {d}"),
            ));
        }
        if kind != "to" {
            return Err(err(
                "walk",
                "`distance` applies to `to = OBJECT` or `to = ACTOR`",
            ));
        }
    }
    let goal = match kind {
        "to" => Some(goal_to(ctx, t.get::<Value>("to")?, distance)?),
        "path" => {
            let Value::Table(list) = t.get::<Value>("path")? else {
                return Err(err("walk", "`path` must be a list of points {{x, z}, …}"));
            };
            let mut points = Vec::new();
            for (i, v) in list.sequence_values::<Value>().enumerate() {
                points.push(floor_point(&v?, "walk", &format!("path[{}]", i + 1))?);
            }
            Some(Goal::Through(points))
        }
        _ => None,
    };
    let route = match kind {
        "to" | "path" => Route::Path {
            points: vec![DVec2::ZERO],
            heading: options.heading,
            speed: options.speed,
        },
        "velocity" => {
            let duration = common.duration;
            let speed = match t.get::<Value>("velocity")? {
                Value::Function(f) => {
                    let Some(d) = duration else {
                        return Err(err(
                            "walk",
                            "`velocity = function(t)` needs a `duration` (seconds)",
                        ));
                    };
                    if !(d.is_finite() && d > 0.0 && d <= 3600.0) {
                        return Err(err(
                            "walk",
                            format!("`duration` must be in (0, 3600] s, got {d}"),
                        ));
                    }
                    let n = (d / PROFILE_DT).round() as usize + 1;
                    let mut samples = Vec::with_capacity(n);
                    for i in 0..n {
                        let time = i as f64 * PROFILE_DT;
                        let v: Value = f.call(time).map_err(|e| {
                            let e = caught_text(ctx.lua, &e);
                            err("walk", format!("`velocity` failed at t = {time:.2} s: {e}"))
                        })?;
                        let v = number(&v).ok_or_else(|| {
                            err("walk", format!("`velocity` returned {} at t = {time:.2} s: expected a speed in m/s",
                                v.type_name()
                            ))
                        })?;
                        samples.push(v);
                    }
                    Speed::Samples(samples)
                }
                v => match number(&v) {
                    Some(x) => Speed::Constant(x),
                    None => {
                        return Err(err(
                            "walk",
                            format!(
                                "`velocity` must be a speed (m/s) or a function of time, got {}",
                                v.type_name()
                            ),
                        ))
                    }
                },
            };
            Route::Velocity { speed, duration }
        }
        _ => {
            let seq = match t.get::<Value>("follow")? {
                Value::UserData(u) => match u.borrow::<SequenceRef>() {
                    Ok(s) => s.0.clone(),
                    Err(_) => {
                        return Err(err("walk", "`follow` must be a sequence or a file path"))
                    }
                },
                Value::String(p) => load_sequence(ctx.lua, &p.to_str()?, Some(&ctx.skeleton))?,
                other => {
                    return Err(err(
                        "walk",
                        format!(
                            "`follow` must be a sequence or a file path, got {}",
                            other.type_name()
                        ),
                    ))
                }
            };
            Route::Follow(seq)
        }
    };
    let walk = match goal {
        Some(goal) => Walk::navigate(&ctx.skeleton, goal, options),
        None => Walk::new(&ctx.skeleton, route, options),
    }
    .map_err(|e| err("walk", e))?;
    let mut spec = common.spec("walk", walk.scope());
    // Without the root, the pelvis and the legs a walk would "complete" having gone
    // nowhere.
    let essential: Vec<&str> = walk
        .scope()
        .iter()
        .filter(|&d| !walk.yields().contains(d) && !spec.scope.contains(d))
        .map(|d| ctx.skeleton.dofs()[d].name.as_str())
        .collect();
    if !essential.is_empty() {
        return Err(err(
            "walk",
            format!(
                "the scope leaves out {} DOF(s) a walk cannot do without (`{}`{}): the root, \
                 the pelvis and the legs; give a scope that holds them (\"all\", the default, or \
                 \"global+lower_body\"), and `arms = false` to leave the arms to others",
                essential.len(),
                essential[..essential.len().min(4)].join("`, `"),
                if essential.len() > 4 { ", …" } else { "" }
            ),
        ));
    }
    spec.yields = walk.yields().intersection(&spec.scope);
    // An arm lent to a wave or a grasp swings again, or carries what it took, afterwards.
    spec.takes_back = true;
    // The walk decides when it has arrived (and a velocity walk's duration is its route's).
    spec.duration = None;
    Ok((Box::new(walk), spec))
}

/// The goal of `walk{ to = … }`: a floor point, or an object or actor given by handle or
/// by name, `distance` from it (its default when `None`).
fn goal_to(ctx: &BuildContext, to: Value, distance: Option<f64>) -> mlua::Result<Goal> {
    enum Named {
        Object(usize),
        Actor(usize),
    }
    let named = match &to {
        Value::UserData(u) if u.is::<ObjectRef>() => Named::Object(u.borrow::<ObjectRef>()?.0),
        Value::UserData(u) if u.is::<ActorRef>() => Named::Actor(u.borrow::<ActorRef>()?.0),
        Value::String(name) => {
            let name = name.to_str()?.to_string();
            let found =
                ctx.with_scene(|s| (s.object_index(&name).ok(), s.actor_index(&name).ok()))?;
            match found {
                (Some(o), None) => Named::Object(o),
                (None, Some(a)) => Named::Actor(a),
                (Some(_), Some(_)) => {
                    return Err(err(
                        "walk",
                        format!("`to = \"{name}\"` names both an object and an actor: pass the one you mean"),
                    ))
                }
                (None, None) => {
                    let known = ctx.with_scene(|s| {
                        let objects = s.objects().iter().map(|o| o.name.clone());
                        objects.chain(s.actors().iter().map(|a| a.name.clone())).collect::<Vec<_>>()
                    })?;
                    let hint = troupe_body::error::did_you_mean(&name, known.iter().map(String::as_str));
                    return Err(err(
                        "walk",
                        format!("`to = \"{name}\"`: no object or actor has that name{hint}"),
                    ));
                }
            }
        }
        v => {
            if distance.is_some() {
                return Err(err(
                    "walk",
                    "`distance` applies to `to = OBJECT` or `to = ACTOR`, not to a point",
                ));
            }
            let point = floor_point(v, "walk", "`to` (a point, an object or an actor)")?;
            return Ok(Goal::Through(vec![point]));
        }
    };
    match named {
        Named::Object(object) => {
            let holder = ctx.with_scene(|s| s.holder(object).map(|h| h.actor))?;
            if holder == Some(ctx.actor) {
                return Err(err(
                    "walk",
                    "an actor cannot walk `to` an object in its own hands",
                ));
            }
            Ok(Goal::Object {
                object,
                distance: distance.unwrap_or(GRASP_DISTANCE),
            })
        }
        Named::Actor(actor) => {
            if actor == ctx.actor {
                return Err(err("walk", "an actor cannot walk `to` itself"));
            }
            Ok(Goal::Actor {
                actor,
                distance: distance.unwrap_or(CONVERSATION_DISTANCE),
            })
        }
    }
}
