//! `actor:play(sequence_or_path, {…})` in Lua: reads [`KeyframeOptions`].

use super::KeyframeOptions;
use mlua::{MultiValue, Value};
use troupe_lua::api::{load_sequence, SequenceRef};
use troupe_lua::args::{err, opt_bool};
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
    let sequence = match args.next() {
        Some(Value::String(path)) => load_sequence(ctx.lua, &path.to_str()?, Some(&ctx.skeleton))?,
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
    let common = CommonOptions::parse(ctx, m, opts.as_ref(), &["loop"])?;
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
