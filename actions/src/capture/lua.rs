//! `actor:capture{…}` in Lua: reads [`CaptureOptions`].

use super::CaptureOptions;
use mlua::MultiValue;
use troupe_lua::args::{err, opt_table_arg};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// `actor:capture{ <common options> }` on a performer: follow the devices (runs until
/// cancelled). Default scope: every DOF the devices drive.
pub fn build_capture(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "capture";
    let t = opt_table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, t.as_ref(), &[])?;
    let options = CaptureOptions {
        scope: common.scope,
    };
    let (capture, scope) = ctx
        .with_scene(|scene| options.capture(scene, ctx.actor))?
        .map_err(|e| err(m, e))?;
    let mut spec = common.spec(m, scope);
    // A capture follows the devices until it is cancelled.
    spec.duration = None;
    Ok((Box::new(capture), spec))
}
