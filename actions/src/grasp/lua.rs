//! `actor:grasp{…}`, `actor:release{…}`, `actor:place{…}` and `troupe.plan_grasp(…)` in
//! Lua: reads [`GraspOptions`] and [`ReleaseOptions`], and the hand and pattern names
//! that `give` and `receive` share.

use super::decision::GraspType;
use super::options::{GraspOptions, Place, ReleaseOptions};
use super::plan::{plan_grasp, HandChoice, PlanOptions};
use mlua::{Lua, MultiValue, Table, Value};
use troupe_body::glam::{DVec3, EulerRot};
use troupe_lua::args::{
    actor_arg, err, euler_degrees, object_arg, opt_bool, opt_string, table_arg, vec3, vec3_table,
};
use troupe_lua::kinds::{with_scene, BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// What a builder returns: the generator and its spec.
type Built = mlua::Result<(Box<dyn Generator>, ActionSpec)>;

/// Reads `hand = "right"|"left"|"both"|"auto"` (default `auto`).
pub(crate) fn hand_choice(method: &str, t: &Table) -> mlua::Result<HandChoice> {
    match opt_string(t, method, "hand")? {
        None => Ok(HandChoice::Auto),
        Some(h) => HandChoice::parse(&h).map_err(|e| err(method, e)),
    }
}

/// Reads `pattern = TYPE` (default: the decision table's).
fn pattern(method: &str, t: &Table) -> mlua::Result<Option<GraspType>> {
    opt_string(t, method, "pattern")?
        .map(|p| GraspType::parse(&p).map_err(|e| err(method, e)))
        .transpose()
}

/// `spec`, yielding the part of `body` (the whole-body part of a reach) in its scope.
pub(crate) fn yielding(mut spec: ActionSpec, body: troupe_body::Scope) -> ActionSpec {
    spec.yields = body.intersection(&spec.scope);
    spec
}

/// Makes a spec for a hand action on `scope` that decides itself when it is done,
/// yielding the part of `body` (the whole-body part of a reach) in its scope; a `scope`
/// option with nothing of the arm and hand is refused.
fn open_ended(
    ctx: &BuildContext,
    common: &CommonOptions,
    kind: &str,
    scope: troupe_body::Scope,
    body: troupe_body::Scope,
) -> mlua::Result<ActionSpec> {
    let arm = scope.difference(&body);
    let mut spec = common.spec_moving(ctx, kind, scope, arm, "the hand")?;
    spec.duration = None;
    Ok(yielding(spec, body))
}

/// Reads `detour = false` (default `true`: the arm bends round other bodies).
pub(crate) fn detour(method: &str, t: &Table) -> mlua::Result<bool> {
    Ok(opt_bool(t, method, "detour")?.unwrap_or(true))
}

/// `actor:grasp{object = OBJ, hand = "right"|"left"|"both"|"auto", pattern = TYPE,
/// duration = reach seconds, detour = bool, <common options>}`.
pub fn build_grasp(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "grasp";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "hand", "pattern", "detour"])?;
    let hand = hand_choice(m, &t)?;
    // An unknown name is a Lua error, as everywhere (docs/lua-api.md, "Unknown names").
    let object = object_arg(ctx.lua, m, "object", t.get("object")?)?;
    let options = GraspOptions {
        object,
        hand,
        pattern: pattern(m, &t)?,
        duration: common.duration.unwrap_or(1.0),
        detour: detour(m, &t)?,
    };
    let (scope, body) = options.scope(&ctx.skeleton).map_err(|e| err(m, e))?;
    let grasp = options.grasp().map_err(|e| err(m, e))?;
    // The generator decides when it is done; `duration` is the reach time.
    Ok((Box::new(grasp), open_ended(ctx, &common, m, scope, body)?))
}

/// Makes a release (or, with `place`, a place) of `t`'s `object`.
fn release_like(
    ctx: &BuildContext,
    m: &str,
    t: &Table,
    common: &CommonOptions,
    place: Option<Place>,
) -> Built {
    let options = ReleaseOptions {
        object: object_arg(ctx.lua, m, "object", t.get("object")?)?,
        place,
    };
    // Not holding it: the action fails at its start with the reason.
    let (release, scope, body) = ctx
        .with_scene(|s| options.release(s, ctx.actor))?
        .map_err(|e| err(m, e))?;
    Ok((Box::new(release), open_ended(ctx, common, m, scope, body)?))
}

/// `actor:release{object = OBJ, <common options>}`.
pub fn build_release(ctx: &BuildContext, args: MultiValue) -> Built {
    let t = table_arg("release", args)?;
    let common = CommonOptions::parse(ctx, "release", Some(&t), &["object"])?;
    release_like(ctx, "release", &t, &common, None)
}

/// `actor:place{object = OBJ, at = {x, y, z}, rotation = {x, y, z}, duration = s}`.
pub fn build_place(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "place";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "at", "rotation"])?;
    let at: Value = t.get("at")?;
    if at.is_nil() {
        return Err(err(m, "`at` is required"));
    }
    let rotation: Value = t.get("rotation")?;
    let place = Place {
        at: vec3(&at, "place: at")?,
        rotation: if rotation.is_nil() {
            None
        } else {
            Some(euler_degrees(&rotation, "place: rotation")?)
        },
        duration: common.duration.unwrap_or(1.0),
    };
    release_like(ctx, m, &t, &common, Some(place))
}

/// `troupe.plan_grasp(actor, object[, {hand = …, pattern = …}])` → a plan table, or nil
/// and the reason.
pub fn make_plan_grasp(lua: &Lua) -> mlua::Result<mlua::Function> {
    lua.create_function(
        |lua, (actor, object, opts): (Value, Value, Option<Table>)| {
            let m = "plan_grasp";
            let actor = actor_arg(lua, m, "actor", actor)?;
            let object = object_arg(lua, m, "object", object)?;
            let mut options = PlanOptions::default();
            let mut scope = None;
            if let Some(t) = &opts {
                options.hand = hand_choice(m, t)?;
                options.grasp = pattern(m, t)?;
                scope = opt_string(t, m, "scope")?;
            }
            let result = with_scene(lua, |s| {
                let skel = s.actors()[actor].skeleton.clone();
                if let Some(expr) = &scope {
                    let body = super::body::BodyReach::body_scope(&skel)?;
                    options.body = Some(skel.scope(expr)?.intersection(&body));
                }
                plan_grasp(
                    &skel,
                    &s.states()[actor],
                    actor,
                    &s.world(),
                    object,
                    &options,
                )
            })?;
            let mut out = MultiValue::new();
            match result {
                Ok(plan) => {
                    let t = lua.create_table()?;
                    t.set("type", plan.grasp.name())?;
                    t.set("decided", plan.decision.grasp.name())?;
                    t.set("hand_count", plan.hands.len())?;
                    t.set("lean", plan.lean)?;
                    t.set("crouch", plan.crouch)?;
                    let hands = lua.create_table()?;
                    for (i, h) in plan.hands.iter().enumerate() {
                        let ht = lua.create_table()?;
                        ht.set("hand", h.side.name())?;
                        ht.set("palm", vec3_table(lua, h.palm)?)?;
                        ht.set("wrist", vec3_table(lua, h.wrist.translation)?)?;
                        let (y, x, z) = h.wrist.rotation.to_euler(EulerRot::YXZ);
                        ht.set(
                            "rotation",
                            vec3_table(
                                lua,
                                DVec3::new(x.to_degrees(), y.to_degrees(), z.to_degrees()),
                            )?,
                        )?;
                        ht.set("cost", h.cost)?;
                        hands.set(i + 1, ht)?;
                    }
                    t.set("hands", hands)?;
                    out.push_back(Value::Table(t));
                }
                Err(reason) => {
                    out.push_back(Value::Nil);
                    out.push_back(Value::String(lua.create_string(reason.to_string())?));
                }
            }
            Ok(out)
        },
    )
}
