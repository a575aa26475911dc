//! Reading the arguments of a Lua call: the options table, typed optional options, points,
//! rotations and handles given as values or names. Every error names the method (and the
//! option), so that a script author sees which call and which key to fix.
//!
//! The action kinds of `troupe-actions` and the device functions of `troupe-drivers` read
//! their arguments with these; a `lua.rs` of an action kind should need nothing else.

use crate::handles::{ActorRef, ObjectRef};
use crate::stage::with_scene;
use glam::{DQuat, DVec2, DVec3, EulerRot};
use mlua::{Lua, MultiValue, Table, UserData, Value};
use troupe_scene::scene::Scene;

/// A Lua runtime error with this message.
pub fn lua_err_message(e: impl std::fmt::Display) -> mlua::Error {
    lua_err(e)
}

/// A Lua runtime error with this message (for the crate's own callbacks).
pub(crate) fn lua_err(e: impl std::fmt::Display) -> mlua::Error {
    mlua::Error::runtime(e.to_string())
}

/// A Lua runtime error `"{method}: {message}"`.
pub fn err(method: &str, message: impl std::fmt::Display) -> mlua::Error {
    let message = message.to_string();
    // An error of the scene's may name the method already ("floor: …").
    if message.starts_with(&format!("{method}: ")) {
        lua_err_message(message)
    } else {
        lua_err_message(format!("{method}: {message}"))
    }
}

/// What a value is, for "got …" in messages: its type, or `nan`, `inf`, `-inf` for a
/// number that is not finite.
pub fn value_name(v: &Value) -> String {
    use crate::handles::{ActionRef, ActorRef, BehaviorRef, HandlerRef, ObjectRef, SequenceRef};
    match v {
        Value::Number(n) if n.is_nan() => "nan".into(),
        Value::Number(n) if n.is_infinite() => if *n > 0.0 { "inf" } else { "-inf" }.into(),
        // troupe's handles by what they are, not as "userdata".
        Value::UserData(u) if u.is::<ActorRef>() => "an actor".into(),
        Value::UserData(u) if u.is::<ObjectRef>() => "an object".into(),
        Value::UserData(u) if u.is::<ActionRef>() => "an action".into(),
        Value::UserData(u) if u.is::<BehaviorRef>() => "a behavior".into(),
        Value::UserData(u) if u.is::<HandlerRef>() => "a handler".into(),
        Value::UserData(u) if u.is::<SequenceRef>() => "a sequence".into(),
        other => other.type_name().into(),
    }
}

/// The one wording of a bad argument: `"{method}: {what} must be {expected}, got {…}"`.
pub fn bad_arg(method: &str, what: &str, expected: &str, got: &Value) -> mlua::Error {
    err(
        method,
        format!("{what} must be {expected}, got {}", value_name(got)),
    )
}

/// The message of a method called with `.` instead of `:` (its `self` is missing).
pub fn dot_call_hint(receiver: &str, method: &str) -> String {
    format!("{method}: call it as a method, with `:` (`{receiver}:{method}(…)`), not with `.`")
}

/// The text of an mlua error in troupe's wording: a bad argument that mlua converted
/// (`self` of a method called with `.`, a value of the wrong type) says so as the
/// hand-written checks do; other errors keep their message.
pub fn error_text(e: &mlua::Error) -> String {
    match e {
        mlua::Error::BadArgument {
            to,
            pos,
            name,
            cause,
        } => {
            // mlua names a method `Type.method` (`SequenceRef.dofs`).
            let (receiver, method) = match to.as_deref() {
                Some(t) => t.rsplit_once('.').unwrap_or(("", t)),
                None => ("", "call"),
            };
            if name.as_deref() == Some("self") {
                // The handle as scripts know it: `ActorRef` is an actor.
                let receiver = receiver.strip_suffix("Ref").unwrap_or(receiver);
                return dot_call_hint(&receiver.to_lowercase(), method);
            }
            // A method's arguments are counted after `self`, as the script writes them.
            let is_method = to.as_deref().is_some_and(|t| t.contains('.'));
            let pos = if is_method {
                pos.saturating_sub(1)
            } else {
                *pos
            };
            let what = match name {
                Some(n) => format!("argument {pos} (`{n}`)"),
                None => format!("argument {pos}"),
            };
            match &**cause {
                mlua::Error::FromLuaConversionError { from, to, .. } => {
                    format!("{method}: {what} must be {}, got {from}", lua_type_of(to))
                }
                other => format!("{method}: {what}: {}", error_text(other)),
            }
        }
        mlua::Error::FromLuaConversionError { from, to, .. } => {
            format!("expected {}, got {from}", lua_type_of(to))
        }
        mlua::Error::CallbackError { cause, .. } => error_text(cause),
        mlua::Error::RuntimeError(m) => m.clone(),
        other => other.to_string(),
    }
}

/// The text of the error of a Lua function that Rust called (a walk's `velocity`), as a
/// script sees an error it caught: [`error_text`] without the traceback mlua appends to
/// the message (a failed behavior's report keeps it), a table raised with `error` told
/// by its place and fields rather than `table: 0x…`.
pub fn caught_text(lua: &mlua::Lua, e: &mlua::Error) -> String {
    let text = crate::error_value::explain(lua, error_text(e));
    match text.split_once("\nstack traceback:") {
        Some((message, _)) => message.to_string(),
        None => text,
    }
}

/// The Lua type a Rust type converts from, for messages.
fn lua_type_of(rust: &str) -> String {
    match rust {
        "String" | "string" | "BorrowedStr" => "a string".into(),
        "Function" | "function" => "a function".into(),
        "Table" | "table" => "a table".into(),
        "f64" | "f32" | "number" => "a number".into(),
        "i64" | "i32" | "u64" | "u32" | "usize" | "isize" | "integer" => "an integer".into(),
        "bool" | "boolean" => "a boolean".into(),
        other => format!("a {}", other.to_lowercase()),
    }
}

/// The one table of options a method takes (`actor:reach{…}`); anything else is an error.
pub fn table_arg(method: &str, args: MultiValue) -> mlua::Result<Table> {
    let mut args = args.into_iter();
    match (args.next(), args.next()) {
        (Some(Value::Table(t)), None) => Ok(t),
        (first, _) => Err(err(
            method,
            format!(
                "expects one table of options, got {}",
                first.as_ref().map(value_name).unwrap_or("nothing".into())
            ),
        )),
    }
}

/// The table of options a method may take or leave out (`actor:simulate()`).
pub fn opt_table_arg(method: &str, args: MultiValue) -> mlua::Result<Option<Table>> {
    match args.into_iter().next() {
        None | Some(Value::Nil) => Ok(None),
        Some(Value::Table(t)) => Ok(Some(t)),
        Some(other) => Err(err(
            method,
            format!("expects a table of options, got {}", value_name(&other)),
        )),
    }
}

/// Refuses any key of `t` that is not in `known`, naming it and listing the known ones.
pub fn check_keys(t: &Table, what: &str, known: &[&str]) -> mlua::Result<()> {
    for pair in t.pairs::<Value, Value>() {
        let (k, _) = pair?;
        let ok = matches!(&k, Value::String(s) if known.contains(&s.to_str()?.as_ref()));
        if !ok {
            let name = match &k {
                Value::String(s) => s.to_str()?.to_string(),
                other => format!("<{}>", other.type_name()),
            };
            return Err(err(
                what,
                format!("unknown field `{name}` (known: {})", known.join(", ")),
            ));
        }
    }
    Ok(())
}

/// A Lua number (integer or float) as `f64`; `None` for any other value.
pub fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Integer(i) => Some(*i as f64),
        Value::Number(n) => Some(*n),
        _ => None,
    }
}

/// Reads an optional string option, with an error naming it when it has another type.
pub fn opt_string(opts: &Table, method: &str, key: &str) -> mlua::Result<Option<String>> {
    match opts.get::<Value>(key)? {
        Value::Nil => Ok(None),
        Value::String(s) => Ok(Some(s.to_str()?.to_string())),
        other => Err(err(
            method,
            format!(
                "option `{key}` must be a string, got {}",
                value_name(&other)
            ),
        )),
    }
}

/// Reads an optional number option, with an error naming it when it has another type.
pub fn opt_number(opts: &Table, method: &str, key: &str) -> mlua::Result<Option<f64>> {
    let v = opts.get::<Value>(key)?;
    match (number(&v), v) {
        (_, Value::Nil) => Ok(None),
        (Some(n), _) if n.is_finite() => Ok(Some(n)),
        (Some(_), other) => Err(err(
            method,
            format!(
                "option `{key}` must be a finite number, got {}",
                value_name(&other)
            ),
        )),
        (None, other) => Err(err(
            method,
            format!(
                "option `{key}` must be a number, got {}",
                value_name(&other)
            ),
        )),
    }
}

/// Reads an optional boolean option, with an error naming it when it has another type.
pub fn opt_bool(opts: &Table, method: &str, key: &str) -> mlua::Result<Option<bool>> {
    match opts.get::<Value>(key)? {
        Value::Nil => Ok(None),
        Value::Boolean(b) => Ok(Some(b)),
        other => Err(err(
            method,
            format!(
                "option `{key}` must be a boolean, got {}",
                other.type_name()
            ),
        )),
    }
}

/// Reads a point `{x, y, z}` or `{x=…, y=…, z=…}` of finite numbers; `what` names it in
/// errors.
pub fn vec3(value: &Value, what: &str) -> mlua::Result<DVec3> {
    let Value::Table(t) = value else {
        return Err(lua_err_message(format!(
            "{what} must be a table {{x, y, z}}, got {}",
            value.type_name()
        )));
    };
    let get = |i: i64, k: &str| -> mlua::Result<f64> {
        let v: Value = t.get(i)?;
        let v = if v.is_nil() { t.get(k)? } else { v };
        match v {
            Value::Integer(i) => Ok(i as f64),
            Value::Number(n) if n.is_finite() => Ok(n),
            other => Err(lua_err_message(format!(
                "{what}.{k} must be a finite number, got {}",
                value_name(&other)
            ))),
        }
    };
    Ok(DVec3::new(get(1, "x")?, get(2, "y")?, get(3, "z")?))
}

/// Reads a floor point for `method`: `{x, z}`, `{x, y, z}` (y must be the floor) or `{x=…, z=…}`.
pub fn floor_point(v: &Value, method: &str, what: &str) -> mlua::Result<DVec2> {
    let Value::Table(t) = v else {
        return Err(err(
            method,
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
                        method,
                        format!("{what} must be a point {{x, z}} or {{x, 0, z}} of numbers"),
                    ))
                }
            }
        }
        _ => {
            return Err(err(
                method,
                format!("{what} must be a point {{x, z}} or {{x, 0, z}} of numbers"),
            ))
        }
    };
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return Err(err(method, format!("{what} ({x}, {y}, {z}) is not finite")));
    }
    if y.abs() > 0.05 {
        return Err(err(method, format!("{what} ({x}, {y}, {z}) is unreachable by walking: it is {y:.2} m off the floor (y must be 0)"
        )));
    }
    Ok(DVec2::new(x, z))
}

/// A new Lua table `{x, y, z}`.
pub fn vec3_table(lua: &Lua, v: DVec3) -> mlua::Result<Table> {
    let t = lua.create_table()?;
    t.raw_set(1, v.x)?;
    t.raw_set(2, v.y)?;
    t.raw_set(3, v.z)?;
    Ok(t)
}

/// Reads a rotation given as Euler degrees `{x, y, z}`, applied in the order Y, X, Z (as
/// every rotation in the API: objects, reach orientations, manipulation keys).
pub fn euler_degrees(value: &Value, what: &str) -> mlua::Result<DQuat> {
    let r = vec3(value, what)?;
    Ok(DQuat::from_euler(
        EulerRot::YXZ,
        r.y.to_radians(),
        r.x.to_radians(),
        r.z.to_radians(),
    ))
}

/// An object given as a handle or by name: its index in the scene.
pub fn object_arg(lua: &Lua, method: &str, key: &str, v: Value) -> mlua::Result<usize> {
    handle_or_name(
        lua,
        method,
        key,
        "object",
        v,
        |o: &ObjectRef| o.0,
        |s| s.objects().iter().map(|o| o.name.clone()).collect(),
    )
}

/// An actor given as a handle or by name: its index in the scene.
pub fn actor_arg(lua: &Lua, method: &str, key: &str, v: Value) -> mlua::Result<usize> {
    handle_or_name(
        lua,
        method,
        key,
        "actor",
        v,
        |a: &ActorRef| a.0,
        |s| s.actors().iter().map(|a| a.name.clone()).collect(),
    )
}

/// What follows an unknown `name` in a message: the nearest of `known` when `name` looks
/// like a slip of it, else every known one when there are at most `short`.
pub(crate) fn name_hint(name: &str, known: &[&str], short: usize) -> String {
    let hint = troupe_body::error::did_you_mean(name, known.iter().copied());
    if !hint.is_empty() || known.len() > short {
        hint
    } else if known.is_empty() {
        " (there are none)".into()
    } else {
        format!(" (known: {})", known.join(", "))
    }
}

/// A handle `H` (a `noun` such as "actor") or one of the scene's `names` (in index
/// order); an unknown name's error gives the nearest of them, or lists them when few.
fn handle_or_name<H: UserData + 'static>(
    lua: &Lua,
    method: &str,
    key: &str,
    noun: &str,
    v: Value,
    index: fn(&H) -> usize,
    names: fn(&Scene) -> Vec<String>,
) -> mlua::Result<usize> {
    let expected = format!("`{key}` must be an {noun} or an {noun}'s name");
    match v {
        Value::UserData(u) => u
            .borrow::<H>()
            .map(|h| index(&h))
            .map_err(|_| err(method, &expected)),
        Value::String(name) => {
            let name = name.to_str()?.to_string();
            let known = with_scene(lua, names)?;
            known.iter().position(|n| *n == name).ok_or_else(|| {
                let known: Vec<&str> = known.iter().map(String::as_str).collect();
                let hint = name_hint(&name, &known, 8);
                err(method, format!("unknown {noun} `{name}`{hint}"))
            })
        }
        Value::Nil => Err(err(method, format!("`{key}` is required"))),
        other => Err(err(
            method,
            format!("{expected}, got {}", value_name(&other)),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Asserts that `r` is an error whose message contains `needle`.
    fn refused<T: std::fmt::Debug>(r: mlua::Result<T>, needle: &str) {
        let e = r.unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    }

    fn table(lua: &Lua, src: &str) -> Table {
        lua.load(src).eval().expect("a table")
    }

    #[test]
    fn typed_options_name_the_key_and_the_type() {
        let lua = Lua::new();
        let t = table(&lua, "{ n = 2, x = 1.5, s = 'a', b = true }");
        assert_eq!(opt_number(&t, "m", "n").unwrap(), Some(2.0));
        assert_eq!(opt_number(&t, "m", "x").unwrap(), Some(1.5));
        assert_eq!(opt_number(&t, "m", "none").unwrap(), None);
        assert_eq!(opt_string(&t, "m", "s").unwrap().as_deref(), Some("a"));
        assert_eq!(opt_bool(&t, "m", "b").unwrap(), Some(true));
        refused(
            opt_number(&t, "m", "s"),
            "m: option `s` must be a number, got string",
        );
        refused(
            opt_bool(&t, "m", "n"),
            "m: option `n` must be a boolean, got integer",
        );
        refused(
            opt_string(&t, "m", "b"),
            "m: option `b` must be a string, got boolean",
        );
    }

    #[test]
    fn unknown_keys_are_named() {
        let lua = Lua::new();
        let t = table(&lua, "{ name = 'a', nmae = 'b' }");
        check_keys(&t, "actor", &["name", "nmae"]).unwrap();
        refused(
            check_keys(&t, "actor", &["name"]),
            "actor: unknown field `nmae` (known: name)",
        );
    }

    #[test]
    fn table_arguments() {
        let lua = Lua::new();
        let t = table(&lua, "{}");
        let one = MultiValue::from_vec(vec![Value::Table(t.clone())]);
        assert!(table_arg("reach", one.clone()).is_ok());
        assert!(opt_table_arg("simulate", one).unwrap().is_some());
        assert!(opt_table_arg("simulate", MultiValue::new())
            .unwrap()
            .is_none());
        refused(
            table_arg("reach", MultiValue::new()),
            "reach: expects one table of options, got nothing",
        );
        let two = MultiValue::from_vec(vec![Value::Table(t.clone()), Value::Table(t)]);
        assert!(table_arg("reach", two).is_err());
        refused(
            opt_table_arg("simulate", MultiValue::from_vec(vec![Value::Integer(1)])),
            "expects a table of options, got integer",
        );
    }

    #[test]
    fn points_and_rotations() {
        let lua = Lua::new();
        let p = Value::Table(table(&lua, "{ 1, 2, 3 }"));
        assert_eq!(vec3(&p, "at").unwrap(), DVec3::new(1.0, 2.0, 3.0));
        let named = Value::Table(table(&lua, "{ x = 1, y = 2, z = 3 }"));
        assert_eq!(vec3(&named, "at").unwrap(), DVec3::new(1.0, 2.0, 3.0));
        refused(
            vec3(&Value::Table(table(&lua, "{ 1, 2 }")), "at"),
            "at.z must be a finite number, got nil",
        );
        let quarter = Value::Table(table(&lua, "{ 0, 90, 0 }"));
        let q = euler_degrees(&quarter, "rotation").unwrap();
        let turned = q * DVec3::Z;
        assert!((turned - DVec3::X).length() < 1e-12, "{turned}");
    }
}
