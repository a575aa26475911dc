//! Per-actor settings that scripts change with `actor:set{…}` and action builders read as
//! defaults. Kept as Lua app data, so each scene (and each scenario test) starts afresh.

use crate::args::lua_err_message;
use mlua::{Lua, Table, Value};
use std::collections::HashMap;

/// The settings `actor:set{}` accepts.
pub const SETTINGS: [&str; 1] = ["self_collision"];

/// The per-actor settings of one scene.
#[derive(Clone, Debug, Default)]
pub struct ActorSettings {
    self_collision: HashMap<usize, bool>,
}

/// `actor:set{ self_collision = bool }`: stores the given settings for `actor`. Unknown
/// names and wrong types are errors naming them.
pub fn set(lua: &Lua, actor: usize, values: &Table) -> mlua::Result<()> {
    let mut collision = None;
    for pair in values.pairs::<Value, Value>() {
        let (key, value) = pair?;
        let name = match &key {
            Value::String(s) => s.to_str()?.to_string(),
            other => {
                return Err(lua_err_message(format!(
                    "set: setting names must be strings, got {}",
                    other.type_name()
                )))
            }
        };
        match (name.as_str(), value) {
            ("self_collision", Value::Boolean(b)) => collision = Some(b),
            ("self_collision", other) => {
                return Err(lua_err_message(format!(
                    "set: `self_collision` must be a boolean, got {}",
                    other.type_name()
                )))
            }
            _ => {
                return Err(lua_err_message(format!(
                    "set: unknown setting `{name}` (known: {})",
                    SETTINGS.join(", ")
                )))
            }
        }
    }
    if lua.app_data_ref::<ActorSettings>().is_none() {
        lua.set_app_data(ActorSettings::default());
    }
    let mut settings = lua
        .app_data_mut::<ActorSettings>()
        .ok_or_else(|| lua_err_message("set: settings are unavailable"))?;
    if let Some(b) = collision {
        settings.self_collision.insert(actor, b);
    }
    Ok(())
}

/// The actor's `self_collision` setting, if a script set one.
pub fn self_collision(lua: &Lua, actor: usize) -> Option<bool> {
    lua.app_data_ref::<ActorSettings>()
        .and_then(|s| s.self_collision.get(&actor).copied())
}
