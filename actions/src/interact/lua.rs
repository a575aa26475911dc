//! `actor:give{…}`, `actor:receive{…}`, `actor:hold_hand{…}` and `actor:shake_hands{…}`
//! in Lua: reads [`GiveOptions`], [`ReceiveOptions`] and [`HoldHandOptions`].

use super::options::{GiveOptions, HoldHandOptions, ReceiveOptions};
use crate::grasp::lua::{detour, hand_choice};
use mlua::{MultiValue, Table};
use troupe_body::sensors::Side;
use troupe_lua::args::{actor_arg, err, object_arg, opt_number, opt_string, table_arg};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// What a builder returns: the generator and its spec.
type Built = mlua::Result<(Box<dyn Generator>, ActionSpec)>;

/// `actor:give{object = OBJ, to = ACTOR, hand = …, timeout = s, detour = bool}`: starts
/// the receiver's `receive` action too.
pub fn build_give(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "give";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(
        ctx,
        m,
        Some(&t),
        &["object", "to", "hand", "timeout", "detour"],
    )?;
    let options = GiveOptions {
        object: object_arg(ctx.lua, m, "object", t.get("object")?)?,
        to: actor_arg(ctx.lua, m, "to", t.get("to")?)?,
        timeout: opt_number(&t, m, "timeout")?,
        hand: hand_choice(m, &t)?,
        detour: detour(m, &t)?,
    };
    let (generator, scope, body) = ctx
        .with_scene_mut(|s| options.start(s, ctx.actor, common.delay))?
        .map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    spec.duration = None;
    // The lean or crouch it may take to reach the meeting point gives way to a walk, and
    // comes back once the walk has ended: a give started on the way plans when they
    // stand (it planned with the arm alone, the body's part lost for good).
    spec.takes_back = true;
    Ok((generator, crate::grasp::lua::yielding(spec, body)))
}

/// `actor:receive{object = OBJ, from = ACTOR, hand = …, duration = reach seconds,
/// detour = bool}`: take
/// `object` out of `from`'s hand (e.g. from a performer holding it out).
pub fn build_receive(ctx: &BuildContext, args: MultiValue) -> Built {
    let m = "receive";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "from", "hand", "detour"])?;
    let options = ReceiveOptions {
        object: object_arg(ctx.lua, m, "object", t.get("object")?)?,
        from: actor_arg(ctx.lua, m, "from", t.get("from")?)?,
        hand: hand_choice(m, &t)?,
        duration: common.duration.unwrap_or(1.0),
        detour: detour(m, &t)?,
    };
    let (generator, scope) = options
        .receive(&ctx.skeleton, ctx.actor)
        .map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    spec.duration = None;
    let body = crate::grasp::body::BodyReach::body_scope(&ctx.skeleton).map_err(|e| err(m, e))?;
    Ok((Box::new(generator), crate::grasp::lua::yielding(spec, body)))
}

/// Reads `key = "right"|"left"`, `default` when absent.
fn side_arg(method: &str, t: &Table, key: &str, default: Side) -> mlua::Result<Side> {
    match opt_string(t, method, key)? {
        None => Ok(default),
        Some(s) => Side::parse(&s).map_err(|e| err(method, format!("`{key}`: {e}"))),
    }
}

/// Makes a hold (or, with `shake`, a handshake) and starts the other's `follow_hand`.
fn hold_like(ctx: &BuildContext, m: &str, args: MultiValue, shake: bool) -> Built {
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["other", "hand", "other_hand"])?;
    let other = actor_arg(ctx.lua, m, "other", t.get("other")?)?;
    let hand = side_arg(m, &t, "hand", Side::Right)?;
    let mut options = HoldHandOptions::new(other, hand, shake);
    options.other_hand = side_arg(m, &t, "other_hand", options.other_hand)?;
    let (generator, scope) = ctx
        .with_scene_mut(|s| options.start(s, ctx.actor, common.delay, common.duration))?
        .map_err(|e| err(m, e))?;
    Ok((Box::new(generator), common.spec(options.kind(), scope)))
}

/// `actor:hold_hand{other = ACTOR, hand = "right", other_hand = "left", duration = s}`.
pub fn build_hold_hand(ctx: &BuildContext, args: MultiValue) -> Built {
    hold_like(ctx, "hold_hand", args, false)
}

/// `actor:shake_hands{other = ACTOR, hand = "right", other_hand = "right"}`.
pub fn build_shake_hands(ctx: &BuildContext, args: MultiValue) -> Built {
    hold_like(ctx, "shake_hands", args, true)
}
