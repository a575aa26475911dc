//! `actor:walk{…}` in Lua: one of `to`, `path`, `velocity` or `follow`, the
//! personification options and the common action options.

use super::route::{Route, Speed, PROFILE_DT};
use super::{Walk, WalkOptions};
use mlua::{MultiValue, Value};
use troupe_body::glam::DVec2;
use troupe_lua::api::{load_sequence, SequenceRef};
use troupe_lua::args::{err, number, opt_bool, opt_number, table_arg};
use troupe_lua::kinds::{BuildContext, CommonOptions};
use troupe_scene::{ActionSpec, Generator};

/// The walk's own option names (besides the common ones).
const WALK_OPTIONS: [&str; 13] = [
    "to",
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
];

/// Reads a floor point: `{x, z}`, `{x, y, z}` (y must be the floor) or `{x=…, z=…}`.
fn floor_point(v: &Value, what: &str) -> mlua::Result<DVec2> {
    let Value::Table(t) = v else {
        return Err(err(
            "walk",
            format!(
                "{what} must be a point {{x, z}} or {{x, 0, z}}, got {}",
                v.type_name()
            ),
        ));
    };
    let items: Vec<Value> = t
        .clone()
        .sequence_values::<Value>()
        .collect::<mlua::Result<_>>()?;
    let nums: Vec<Option<f64>> = items.iter().map(number).collect();
    let (x, y, z) = match nums.as_slice() {
        [Some(x), Some(z)] => (*x, 0.0, *z),
        [Some(x), Some(y), Some(z)] => (*x, *y, *z),
        [] => {
            let x = number(&t.get::<Value>("x")?);
            let z = number(&t.get::<Value>("z")?);
            let y = number(&t.get::<Value>("y")?).unwrap_or(0.0);
            match (x, z) {
                (Some(x), Some(z)) => (x, y, z),
                _ => {
                    return Err(err(
                        "walk",
                        format!("{what} must be a point {{x, z}} or {{x, 0, z}} of numbers"),
                    ))
                }
            }
        }
        _ => {
            return Err(err(
                "walk",
                format!("{what} must be a point {{x, z}} or {{x, 0, z}} of numbers"),
            ))
        }
    };
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return Err(err("walk", format!("{what} ({x}, {y}, {z}) is not finite")));
    }
    if y.abs() > 0.05 {
        return Err(err("walk", format!("{what} ({x}, {y}, {z}) is unreachable by walking: it is {y:.2} m off the floor (y must be 0)"
        )));
    }
    Ok(DVec2::new(x, z))
}

/// `actor:walk{ to = {x, 0, z} | path = {{x, z}, …} | velocity = number_or_function |
/// follow = SEQUENCE_or_path, speed = m/s, heading = degrees, step_length, step_width,
/// pelvis, arm_swing, bounce, run, arms = bool, <common options> }`.
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
    let route = match kind {
        "to" => Route::Path {
            points: vec![floor_point(&t.get("to")?, "`to`")?],
            heading: options.heading,
            speed: options.speed,
        },
        "path" => {
            let Value::Table(list) = t.get::<Value>("path")? else {
                return Err(err("walk", "`path` must be a list of points {{x, z}, …}"));
            };
            let mut points = Vec::new();
            for (i, v) in list.sequence_values::<Value>().enumerate() {
                points.push(floor_point(&v?, &format!("path[{}]", i + 1))?);
            }
            Route::Path {
                points,
                heading: options.heading,
                speed: options.speed,
            }
        }
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
    let walk = Walk::new(&ctx.skeleton, route, options).map_err(|e| err("walk", e))?;
    let mut spec = common.spec("walk", walk.scope());
    spec.yields = walk.yields().intersection(&spec.scope);
    // The walk decides when it has arrived (and a velocity walk's duration is its route's).
    spec.duration = None;
    Ok((Box::new(walk), spec))
}
