//! `actor:play(sequence_or_path, {…})` in Lua: reads [`KeyframeOptions`].

use super::KeyframeOptions;
use mlua::{MultiValue, Value};
use troupe_lua::api::{load_part, SequenceRef};
use troupe_lua::args::{err, opt_bool, opt_string};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// `actor:play(sequence_or_path, { loop = bool, <common options> })`.
pub fn build_play(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "play";
    let mut args = args.into_iter();
    let expected = "the first argument must be a sequence or a file path";
    let first = args.next();
    let opts = match args.next() {
        None | Some(Value::Nil) => None,
        Some(Value::Table(t)) => Some(t),
        Some(other) => {
            return Err(err(
                m,
                format!(
                    "the second argument must be a table of options, got {}",
                    other.type_name()
                ),
            ))
        }
    };
    // A recording of several actors plays this actor's part, or the one `part` names.
    let part = match &opts {
        Some(t) => opt_string(t, m, "part")?,
        None => None,
    };
    let sequence = match first {
        Some(Value::String(path)) => {
            let chosen = part.is_some();
            let mine = ctx.with_scene(|s| s.actors()[ctx.actor].name.clone())?;
            let part = part.unwrap_or(mine);
            let skeleton = Some(&ctx.skeleton);
            load_part(ctx.lua, &path.to_str()?, skeleton, (&part, chosen))?
        }
        Some(Value::UserData(_)) if part.is_some() => {
            return Err(err(
                m,
                "`part` chooses an actor's part of a recording file, not of a sequence",
            ))
        }
        Some(Value::UserData(u)) => match u.borrow::<SequenceRef>() {
            Ok(s) => s.0.clone(),
            Err(_) => return Err(err(m, expected)),
        },
        other => {
            return Err(err(
                m,
                format!(
                    "{expected}, got {}",
                    other.map(|v| v.type_name()).unwrap_or("nothing")
                ),
            ))
        }
    };
    let common = CommonOptions::parse(ctx, m, opts.as_ref(), &["loop", "part"])?;
    let options = KeyframeOptions {
        looping: match &opts {
            Some(t) => opt_bool(t, m, "loop")?,
            None => None,
        },
        scope: common.scope,
        ..KeyframeOptions::new(sequence)
    };
    let generator = options.keyframe(&ctx.skeleton).map_err(|e| err(m, e))?;
    let spec = common.spec("keyframe", generator.scope());
    Ok((Box::new(generator), spec))
}
