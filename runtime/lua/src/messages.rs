//! `troupe.publish(key, value)` and `troupe.subscribe(expr, function(value, key) … end)`:
//! messages between scenes and tools, Lua values ↔ JSON. The scene's [`Mailbox`] holds
//! them; the director calls the subscribers at the start of the next tick's script
//! phase, in the mailbox's order, each subscriber in the order it subscribed.
//!
//! [`Mailbox`]: troupe_scene::Mailbox

use crate::args::lua_err;
use crate::stage::stage;
use mlua::{Function, Lua, LuaSerdeExt, Table, Value};

/// Adds `publish` and `subscribe` to the `troupe` table.
pub(crate) fn install(lua: &Lua, troupe: &Table) -> mlua::Result<()> {
    troupe.set(
        "publish",
        lua.create_function(|lua, (key, value): (String, Value)| {
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
        lua.create_function(|lua, (expr, f): (String, Function)| {
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
