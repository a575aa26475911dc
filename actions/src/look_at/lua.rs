//! `actor:look_at{…}` in Lua: reads [`LookAtOptions`].

use super::LookAtOptions;
use mlua::MultiValue;
use troupe_body::Scope;
use troupe_lua::args::{err, table_arg};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// `actor:look_at{ target = …, <common options> }`.
pub fn build_look_at(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "look_at";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["target"])?;
    let options = LookAtOptions {
        target: crate::reach::lua::target(ctx, m, t.get("target")?)?,
    };
    let generator = options.look_at(&ctx.skeleton).map_err(|e| err(m, e))?;
    let natural: Scope = generator.scope_dofs().into_iter().collect();
    let spec = common.spec_moving(ctx, m, natural, natural, "the head or the eyes")?;
    Ok((Box::new(generator), spec))
}
