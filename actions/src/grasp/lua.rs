//! The Lua face of grasping, manipulation and interaction: the actor methods `grasp`,
//! `release`, `place`, `manipulate`, `give`, `hold_hand`, `shake_hands` and the query
//! `troupe.plan_grasp`.

use super::action::{grasp_scope, Grasp, Release, Signal};
use super::decision::GraspType;
use super::handover::{offer_to_hand, receive, SharedHandBoard};
use super::plan::{plan_grasp, HandChoice, PlanOptions};
use crate::interact::{FollowHand, Give, HoldHand};
use crate::manipulate::{Manipulate, ObjectKey};
use mlua::{Lua, MultiValue, Table, Value};
use std::sync::Arc;
use troupe_body::glam::{DVec3, EulerRot};
use troupe_body::sensors::Side;
use troupe_body::Transform;
use troupe_lua::kinds::args::{
    actor_arg, err, euler_degrees, object_arg, opt_number, opt_string, table_arg, vec3,
};
use troupe_lua::kinds::{with_scene, BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator, Scene};

type Built = mlua::Result<(Box<dyn Generator>, ActionSpec)>;

/// An action that fails at its start with a reason (e.g. an unknown object's name).
struct Refuse(String);

impl Generator for Refuse {
    fn start(&mut self, _: &troupe_scene::GeneratorContext) -> Result<(), String> {
        Err(self.0.clone())
    }
    fn step(
        &mut self,
        _: &troupe_scene::GeneratorContext,
        _: &mut troupe_scene::DofWriter,
    ) -> troupe_scene::Step {
        troupe_scene::Step::Failed(self.0.clone())
    }
}

fn side_arg(method: &str, t: &Table, key: &str, default: Side) -> mlua::Result<Side> {
    match opt_string(t, method, key)? {
        None => Ok(default),
        Some(s) => Side::parse(&s).map_err(|e| err(method, format!("`{key}`: {e}"))),
    }
}

/// The hand holding `object` for `actor`, if it does.
fn holding_side(scene: &Scene, actor: usize, object: usize) -> Option<Side> {
    let h = scene.holder(object).filter(|h| h.actor == actor)?;
    let name = &scene.actors()[actor].skeleton.joints()[h.joint].name;
    Some(if name.starts_with("l_") {
        Side::Left
    } else {
        Side::Right
    })
}

/// The hands a choice may use (`auto`: both, the plan picks).
fn resolve_hands(choice: HandChoice) -> Vec<Side> {
    match choice {
        HandChoice::Right => vec![Side::Right],
        HandChoice::Left => vec![Side::Left],
        HandChoice::Both | HandChoice::Auto => vec![Side::Right, Side::Left],
    }
}

fn hand_choice(method: &str, t: &Table) -> mlua::Result<HandChoice> {
    match opt_string(t, method, "hand")? {
        None => Ok(HandChoice::Auto),
        Some(h) => HandChoice::parse(&h).map_err(|e| err(method, e)),
    }
}

fn pattern(method: &str, t: &Table) -> mlua::Result<Option<GraspType>> {
    opt_string(t, method, "pattern")?
        .map(|p| GraspType::parse(&p).map_err(|e| err(method, e)))
        .transpose()
}

/// `actor:grasp{object = OBJ, hand = "right"|"left"|"both"|"auto", pattern = TYPE,
/// duration = reach seconds, <common options>}`.
pub fn build_grasp(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "grasp";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "hand", "pattern"])?;
    let choice = hand_choice(m, &t)?;
    let sides = resolve_hands(choice);
    let object = match t.get::<Value>("object")? {
        // An unknown name is bad scene data, not a script error: the action fails with
        // the reason, like an unreachable or held object.
        Value::String(name) => {
            let name = name.to_str()?.to_string();
            match with_scene(ctx.lua, |s| s.object_index(&name))? {
                Ok(i) => i,
                Err(e) => {
                    let scope = grasp_scope(&ctx.skeleton, &sides).map_err(|e| err(m, e))?;
                    let mut spec = common.spec("grasp", scope);
                    spec.duration = None;
                    return Ok((Box::new(Refuse(e.to_string())), spec));
                }
            }
        }
        other => object_arg(ctx.lua, m, "object", other)?,
    };
    let options = PlanOptions {
        hand: choice,
        grasp: pattern(m, &t)?,
        ..PlanOptions::default()
    };
    let scope = grasp_scope(&ctx.skeleton, &sides).map_err(|e| err(m, e))?;
    let g = Grasp::new(object, options, sides, common.duration.unwrap_or(1.0))
        .map_err(|e| err(m, e))?;
    let mut spec = common.spec("grasp", scope);
    // The generator decides when it is done; `duration` is the reach time.
    spec.duration = None;
    Ok((Box::new(g), spec))
}

fn release_like(
    ctx: &BuildContext,
    m: &str,
    t: &Table,
    common: &CommonOptions,
    place: Option<DVec3>,
) -> Built {
    let object = object_arg(ctx.lua, m, "object", t.get("object")?)?;
    let (side, rot) = ctx.with_scene(|s| {
        (
            holding_side(s, ctx.actor, object),
            s.objects()[object].rotation,
        )
    })?;
    // Not holding it: the action fails at its start with the reason.
    let sides = vec![side.unwrap_or(Side::Right)];
    let place = match place {
        Some(at) => {
            let r: Value = t.get("rotation")?;
            let r = if r.is_nil() {
                rot
            } else {
                euler_degrees(&r, &format!("{m}: rotation"))?
            };
            Some((Transform::new(r, at), common.duration.unwrap_or(1.0)))
        }
        None => None,
    };
    let scope = grasp_scope(&ctx.skeleton, &sides).map_err(|e| err(m, e))?;
    let g = Release::new(object, sides, place).map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    spec.duration = None;
    Ok((Box::new(g), spec))
}

/// `actor:release{object = OBJ, <common options>}`.
pub fn build_release(ctx: &BuildContext, args: MultiValue) -> Built {
    let t = table_arg("release", args)?;
    let common = CommonOptions::parse(ctx, "release", Some(&t), &["object"])?;
    release_like(ctx, "release", &t, &common, None)
}

/// `actor:place{object = OBJ, at = {x, y, z}, rotation = {x, y, z}, duration = s}`.
pub fn build_place(ctx: &BuildContext, args: MultiValue) -> Built {
    let t = table_arg("place", args)?;
    let common = CommonOptions::parse(ctx, "place", Some(&t), &["object", "at", "rotation"])?;
    let at: Value = t.get("at")?;
    if at.is_nil() {
        return Err(err("place", "`at` is required"));
    }
    let at = vec3(&at, "place: at")?;
    release_like(ctx, "place", &t, &common, Some(at))
}

/// Object keys from `{ {t = s, at = {x, y, z}, rotation = {x, y, z}}, … }` or a Lua
/// function `f(t) -> at[, rotation]` sampled every 0.04 s (4.4) over `duration`.
fn parse_keys(v: Value, duration: Option<f64>) -> mlua::Result<Vec<ObjectKey>> {
    let m = "manipulate";
    match v {
        Value::Table(list) => {
            let mut keys = Vec::new();
            for (i, k) in list.sequence_values::<Value>().enumerate() {
                let Value::Table(k) = k? else {
                    return Err(err(
                        m,
                        format!(
                            "keys[{}] must be a table {{t = …, at = {{x, y, z}}}}",
                            i + 1
                        ),
                    ));
                };
                let time = opt_number(&k, m, "t")?
                    .ok_or_else(|| err(m, format!("keys[{}].t is required", i + 1)))?;
                let at: Value = k.get("at")?;
                let position = vec3(&at, &format!("{m}: keys[{}].at", i + 1))?;
                let r: Value = k.get("rotation")?;
                let rotation = if r.is_nil() {
                    None
                } else {
                    Some(euler_degrees(
                        &r,
                        &format!("{m}: keys[{}].rotation", i + 1),
                    )?)
                };
                keys.push(ObjectKey {
                    time,
                    position,
                    rotation,
                });
            }
            Ok(keys)
        }
        Value::Function(f) => {
            let duration = duration
                .filter(|d| d.is_finite() && *d > 0.0)
                .ok_or_else(|| err(m, "a function of time needs `duration` (seconds > 0)"))?;
            const STEP: f64 = 0.04;
            // The tolerance keeps `0.28 / 0.04 = 7.000…01` from adding a key at the end
            // time twice.
            let n = (duration / STEP - 1e-9).ceil().max(1.0) as usize;
            let mut keys = Vec::with_capacity(n);
            for i in 1..=n {
                let time = if i == n {
                    duration
                } else {
                    (i as f64 * STEP).min(duration)
                };
                let (at, r): (Value, Value) = f.call(time)?;
                let position = vec3(&at, &format!("{m}: keys({time})"))?;
                let rotation = if r.is_nil() {
                    None
                } else {
                    Some(euler_degrees(&r, &format!("{m}: keys({time}) rotation"))?)
                };
                keys.push(ObjectKey {
                    time,
                    position,
                    rotation,
                });
            }
            Ok(keys)
        }
        Value::Nil => Err(err(m, "`keys` is required")),
        other => Err(err(
            m,
            format!(
                "`keys` must be a list of keys or a function of time, got {}",
                other.type_name()
            ),
        )),
    }
}

/// `actor:manipulate{object = OBJ, keys = {…} | function(t) … end, duration = s}`.
pub fn build_manipulate(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "manipulate";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "keys"])?;
    let object = object_arg(ctx.lua, m, "object", t.get("object")?)?;
    let keys = parse_keys(t.get("keys")?, common.duration)?;
    let side = ctx.with_scene(|s| holding_side(s, ctx.actor, object))?;
    let sides = vec![side.unwrap_or(Side::Right)];
    let scope = ctx
        .skeleton
        .scope(&format!("{}_arm", sides[0].name()))
        .map_err(|e| err(m, e))?;
    let g = Manipulate::new(object, keys, sides).map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    spec.duration = None;
    Ok((Box::new(g), spec))
}

/// `actor:give{object = OBJ, to = ACTOR}`: starts the receiver's `receive` action too.
pub fn build_give(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "give";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "to", "hand", "timeout"])?;
    let object = object_arg(ctx.lua, m, "object", t.get("object")?)?;
    let to = actor_arg(ctx.lua, m, "to", t.get("to")?)?;
    if to == ctx.actor {
        return Err(err(m, "`to` must be another actor"));
    }
    let timeout = opt_number(&t, m, "timeout")?;
    if let Some(s) = timeout {
        if !(s.is_finite() && s > 0.0) {
            return Err(err(m, format!("`timeout` must be seconds > 0, got {s}")));
        }
    }
    let side = ctx.with_scene(|s| holding_side(s, ctx.actor, object))?;
    let side = side.unwrap_or(Side::Right);
    let scope = grasp_scope(&ctx.skeleton, &[side]).map_err(|e| err(m, e))?;
    // Hands driven by a person (a performer's glove, 4.7) neither reach nor carry.
    if let Some(board) = ctx.lua.app_data_ref::<SharedHandBoard>().map(|b| b.clone()) {
        let hands = board
            .0
            .lock()
            .map_err(|_| err(m, "hand board lock poisoned"))?;
        let (mine, theirs) = (hands.hand(ctx.actor), hands.hand(to));
        drop(hands);
        if mine.is_some() {
            return Err(err(
                m,
                "a performer gives by holding the object out: let the receiver take it with \
                 receiver:receive{object = …, from = performer}, then open the glove",
            ));
        }
        if let Some(hand) = theirs {
            let giver = offer_to_hand(&board, object, ctx.actor, side, to, hand, timeout)
                .map_err(|e| err(m, e))?;
            let mut spec = common.spec(m, scope);
            spec.duration = None;
            return Ok((Box::new(giver), spec));
        }
    }
    let arrived = Arc::new(Signal::default());
    let mut giver = Give::new(object, to, side, arrived.clone());
    if let Some(t) = timeout {
        giver = giver.with_timeout(t);
    }
    // The receiver: a grasp that waits for the object to arrive and may take it from us.
    let choice = hand_choice(m, &t)?;
    let rx_sides = resolve_hands(choice);
    let rx_skel = ctx.with_scene(|s| s.actors()[to].skeleton.clone())?;
    let rx_scope = grasp_scope(&rx_skel, &rx_sides).map_err(|e| err(m, e))?;
    let receive = Grasp::new(
        object,
        PlanOptions {
            hand: choice,
            from: Some(ctx.actor),
            ..PlanOptions::default()
        },
        rx_sides,
        1.0,
    )
    .map_err(|e| err(m, e))?
    .gated(arrived)
    .abandoned_by(giver.ended());
    let mut rx_spec = ActionSpec::new("receive", rx_scope);
    rx_spec.delay = common.delay;
    ctx.with_scene_mut(|s| s.start_action(to, rx_spec, Box::new(receive)))?
        .map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    spec.duration = None;
    Ok((Box::new(giver), spec))
}

/// `actor:receive{object = OBJ, from = ACTOR, hand = …, duration = reach seconds}`: take
/// `object` out of `from`'s hand (e.g. from a performer holding it out).
pub fn build_receive(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "receive";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "from", "hand"])?;
    let object = object_arg(ctx.lua, m, "object", t.get("object")?)?;
    let from = actor_arg(ctx.lua, m, "from", t.get("from")?)?;
    if from == ctx.actor {
        return Err(err(m, "`from` must be another actor"));
    }
    let choice = hand_choice(m, &t)?;
    let (g, scope) = receive(
        &ctx.skeleton,
        object,
        from,
        choice,
        resolve_hands(choice),
        common.duration.unwrap_or(1.0),
    )
    .map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    spec.duration = None;
    Ok((Box::new(g), spec))
}

fn hold_like(ctx: &BuildContext, m: &str, args: MultiValue, shake: bool) -> Built {
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["other", "hand", "other_hand"])?;
    let other = actor_arg(ctx.lua, m, "other", t.get("other")?)?;
    if other == ctx.actor {
        return Err(err(m, "`other` must be another actor"));
    }
    let side = side_arg(m, &t, "hand", Side::Right)?;
    let default_other = if shake { Side::Right } else { side.other() };
    let other_side = side_arg(m, &t, "other_hand", default_other)?;
    let held = Arc::new(Signal::default());
    let finished = Arc::new(Signal::default());
    let active = HoldHand::new(
        other,
        side,
        other_side,
        shake,
        held.clone(),
        finished.clone(),
    );
    let scope = grasp_scope(&ctx.skeleton, &[side]).map_err(|e| err(m, e))?;
    let wrist = ctx
        .skeleton
        .joint(&format!("{}wrist", side.prefix()))
        .map_err(|e| err(m, e))?;
    let other_skel = ctx.with_scene(|s| s.actors()[other].skeleton.clone())?;
    let follow_scope = other_skel
        .scope(&format!("{}_arm", other_side.name()))
        .map_err(|e| err(m, e))?;
    let follow = FollowHand::new(ctx.actor, wrist, other_side, held, finished);
    let mut follow_spec = ActionSpec::new("follow_hand", follow_scope);
    follow_spec.delay = common.delay;
    follow_spec.duration = common.duration;
    ctx.with_scene_mut(|s| s.start_action(other, follow_spec, Box::new(follow)))?
        .map_err(|e| err(m, e))?;
    Ok((Box::new(active), common.spec(m, scope)))
}

/// `actor:hold_hand{other = ACTOR, hand = "right", other_hand = "left", duration = s}`.
pub fn build_hold_hand(ctx: &BuildContext, args: MultiValue) -> Built {
    hold_like(ctx, "hold_hand", args, false)
}

/// `actor:shake_hands{other = ACTOR, hand = "right", other_hand = "right"}`.
pub fn build_shake_hands(ctx: &BuildContext, args: MultiValue) -> Built {
    hold_like(ctx, "shake_hands", args, true)
}

fn vec_table(lua: &Lua, v: DVec3) -> mlua::Result<Table> {
    let t = lua.create_table()?;
    t.set(1, v.x)?;
    t.set(2, v.y)?;
    t.set(3, v.z)?;
    Ok(t)
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
            if let Some(t) = &opts {
                options.hand = hand_choice(m, t)?;
                options.grasp = pattern(m, t)?;
            }
            let result = with_scene(lua, |s| {
                let skel = s.actors()[actor].skeleton.clone();
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
                    let hands = lua.create_table()?;
                    for (i, h) in plan.hands.iter().enumerate() {
                        let ht = lua.create_table()?;
                        ht.set("hand", h.side.name())?;
                        ht.set("palm", vec_table(lua, h.palm)?)?;
                        ht.set("wrist", vec_table(lua, h.wrist.translation)?)?;
                        let (y, x, z) = h.wrist.rotation.to_euler(EulerRot::YXZ);
                        ht.set(
                            "rotation",
                            vec_table(
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
                    out.push_back(Value::String(lua.create_string(&reason)?));
                }
            }
            Ok(out)
        },
    )
}
