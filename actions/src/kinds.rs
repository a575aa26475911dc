//! The action kinds this crate adds to Lua: one registration per kind.

use crate::keyframe::Keyframe;
use mlua::{MultiValue, Value};
use troupe_runtime::lua::api::{load_sequence, lua_err_message, SequenceRef};
use troupe_runtime::lua::kinds::{opt_bool, ActionKind, ActionKinds, BuildContext, CommonOptions};
use troupe_runtime::{ActionSpec, Generator};

/// Every action kind implemented here, ready for a [`troupe_runtime::lua::Director`].
pub fn action_kinds() -> ActionKinds {
    let mut kinds = ActionKinds::default();
    kinds.register(ActionKind {
        method: "play",
        build: build_play,
    });
    // Dynamics: simulate, servo, track.
    crate::dynamics::register(&mut kinds);
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
