//! `troupe.publish(key, value)` and `troupe.subscribe(expr, function(value, key) … end)`:
//! messages between scenes and tools, Lua values ↔ JSON. The scene's [`Mailbox`] holds
//! them; the director calls the subscribers at the start of the next tick's script
//! phase, in the mailbox's order, each subscriber in the order it subscribed.
//!
//! [`Mailbox`]: troupe_scene::Mailbox

use crate::args::{bad_arg, lua_err};
use crate::stage::stage;
use mlua::{Lua, LuaSerdeExt, Table, Value};

/// Adds `publish` and `subscribe` to the `troupe` table.
pub(crate) fn install(lua: &Lua, troupe: &Table) -> mlua::Result<()> {
    troupe.set(
        "publish",
        lua.create_function(|lua, (key, value): (Value, Value)| {
            let key = string_arg("publish", "argument 1 (the key)", key)?;
            if let Some(path) = non_finite(&value, String::new(), &mut Default::default()) {
                return Err(lua_err(format!(
                    "publish {key}: value{path} is not a finite number (JSON has none)"
                )));
            }
            let json = to_json(lua, value).map_err(|e| lua_err(format!("publish {key}: {e}")))?;
            stage(lua)?
                .scene
                .mailbox_mut()
                .publish(&key, json)
                .map_err(|e| lua_err(format!("publish: {e}")))
        })?,
    )?;
    troupe.set(
        "subscribe",
        lua.create_function(|lua, (expr, f): (Value, Value)| {
            let expr = string_arg("subscribe", "argument 1 (the key expression)", expr)?;
            let Value::Function(f) = f else {
                return Err(bad_arg(
                    "subscribe",
                    "argument 2",
                    "a function(value, key)",
                    &f,
                ));
            };
            let mut st = stage(lua)?;
            st.scene
                .mailbox_mut()
                .subscribe(&expr)
                .map_err(|e| lua_err(format!("subscribe: {e}")))?;
            st.subscriptions.push((expr, f));
            Ok(())
        })?,
    )?;
    Ok(())
}

/// Argument `what` of `method`, which must be a string.
fn string_arg(method: &str, what: &str, v: Value) -> mlua::Result<String> {
    match v {
        Value::String(s) => Ok(s.to_str()?.to_string()),
        other => Err(bad_arg(method, what, "a string", &other)),
    }
}

/// Where in `value` (`path` so far: `[2].x`) a number is not finite (NaN or infinite),
/// which JSON cannot carry, if one is. Each table is looked into once (`seen`), so a
/// table that holds itself, or one table held many times, costs one visit; the conversion
/// to JSON then refuses a cycle.
fn non_finite(
    value: &Value,
    path: String,
    seen: &mut std::collections::HashSet<usize>,
) -> Option<String> {
    match value {
        Value::Number(n) if !n.is_finite() => Some(path),
        Value::Table(t) if !seen.insert(t.to_pointer() as usize) => None,
        Value::Table(t) => t.pairs::<Value, Value>().flatten().find_map(|(k, v)| {
            let key = match &k {
                Value::Integer(i) => format!("[{i}]"),
                Value::String(s) => format!(".{}", s.to_string_lossy()),
                other => format!("[{}]", other.type_name()),
            };
            non_finite(&v, format!("{path}{key}"), seen)
        }),
        _ => None,
    }
}

/// A Lua value as JSON: tables with keys 1..n are arrays, other tables objects (string
/// keys only); functions, threads and userdata are refused.
fn to_json(lua: &Lua, value: Value) -> mlua::Result<serde_json::Value> {
    let json: serde_json::Value = lua.from_value(value)?;
    Ok(json)
}

/// A JSON value as a Lua value (objects and arrays as tables, null as nil).
pub(crate) fn to_lua(lua: &Lua, value: &serde_json::Value) -> mlua::Result<Value> {
    lua.to_value_with(
        value,
        mlua::serde::SerializeOptions::new()
            .serialize_none_to_null(false)
            .serialize_unit_to_null(false),
    )
}
