//! `actor:manipulate{…}` in Lua: reads [`ManipulateOptions`], keys given as a list or as
//! a function of time.

use super::{ManipulateOptions, ObjectKey};
use mlua::{MultiValue, Value};
use troupe_lua::args::{
    caught_text, check_keys, err, euler_degrees, object_arg, opt_number, table_arg, vec3,
};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// `actor:manipulate{object = OBJ, keys = {…} | function(t) … end, duration = s}`.
pub fn build_manipulate(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let m = "manipulate";
    let t = table_arg(m, args)?;
    let common = CommonOptions::parse(ctx, m, Some(&t), &["object", "keys"])?;
    let options = ManipulateOptions {
        object: object_arg(ctx.lua, m, "object", t.get("object")?)?,
        keys: parse_keys(ctx.lua, t.get("keys")?, common.duration)?,
    };
    let (generator, scope) = ctx
        .with_scene(|s| options.manipulate(s, ctx.actor))?
        .map_err(|e| err(m, e))?;
    let mut spec = common.spec_moving(ctx, m, scope, scope, "the arm that holds the object")?;
    spec.duration = None;
    Ok((Box::new(generator), spec))
}

/// Object keys from `{ {t = s, at = {x, y, z}, rotation = {x, y, z}}, … }` or a Lua
/// function `f(t) -> at[, rotation]` sampled every 0.04 s (4.4) over `duration`.
fn parse_keys(lua: &mlua::Lua, v: Value, duration: Option<f64>) -> mlua::Result<Vec<ObjectKey>> {
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
                check_keys(
                    &k,
                    &format!("{m}: keys[{}]", i + 1),
                    &["t", "at", "rotation"],
                )?;
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
                let (at, r): (Value, Value) = f.call(time).map_err(|e| {
                    let e = caught_text(lua, &e);
                    err(m, format!("`keys` failed at t = {time:.2} s: {e}"))
                })?;
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
