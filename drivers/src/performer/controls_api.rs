//! The Lua side of a performer's controls: values (`troupe.devices.buttons(pattern)`,
//! `troupe.devices.analogs(pattern)`) and events (`troupe.devices.on_button(pattern, fn)`,
//! `troupe.devices.on_analog(pattern, fn)`), called at the start of the script phase of the
//! tick whose input brought the change, in the order the reports came.

use crate::performer::controls::{glob, Change};
use crate::performer::registry::SharedPerformers;
use mlua::{Function, Lua, Table, Value};
use std::sync::{Arc, Mutex};
use troupe_lua::api::lua_err_message;

/// Handlers of control events: (is a button handler, pattern, function).
#[derive(Clone, Default)]
struct Handlers(Arc<Mutex<Vec<(bool, String, Function)>>>);

fn performers(lua: &Lua) -> mlua::Result<SharedPerformers> {
    lua.app_data_ref::<SharedPerformers>()
        .map(|s| s.clone())
        .ok_or_else(|| lua_err_message("devices are not enabled"))
}

/// Every control of every performer whose name matches `pattern`, as a Lua table.
fn values(lua: &Lua, pattern: Option<String>, buttons: bool) -> mlua::Result<Table> {
    let pattern = pattern.unwrap_or_else(|| "*".into());
    let s = performers(lua)?;
    let perf =
        s.0.lock()
            .map_err(|_| lua_err_message("performer lock poisoned"))?;
    let out = lua.create_table()?;
    for c in perf
        .list
        .iter()
        .filter_map(|p| p.vrpn.as_ref().map(|v| &v.controls))
    {
        if buttons {
            for (n, v) in c.buttons.iter().filter(|(n, _)| glob(&pattern, n)) {
                out.set(n.as_str(), *v)?;
            }
        } else {
            for (n, v) in c.analogs.iter().filter(|(n, _)| glob(&pattern, n)) {
                out.set(n.as_str(), *v)?;
            }
        }
    }
    Ok(out)
}

/// Installs `buttons`, `analogs`, `on_button` and `on_analog` in `troupe.devices`.
pub(crate) fn install_lua(lua: &Lua, devices: &Table) -> mlua::Result<()> {
    let handlers = Handlers::default();
    lua.set_app_data(handlers);
    devices.set(
        "buttons",
        lua.create_function(|lua, pat: Option<String>| values(lua, pat, true))?,
    )?;
    devices.set(
        "analogs",
        lua.create_function(|lua, pat: Option<String>| values(lua, pat, false))?,
    )?;
    for (key, is_button) in [("on_button", true), ("on_analog", false)] {
        devices.set(
            key,
            // A nil pattern matches every control, as for `buttons` and `analogs`.
            lua.create_function(move |lua, (pat, f): (Option<String>, Function)| {
                let pat = pat.unwrap_or_else(|| "*".into());
                let h = lua
                    .app_data_ref::<Handlers>()
                    .map(|h| h.clone())
                    .ok_or_else(|| lua_err_message("devices are not enabled"))?;
                h.0.lock()
                    .map_err(|_| lua_err_message("handler lock poisoned"))?
                    .push((is_button, pat, f));
                Ok(())
            })?,
        )?;
    }
    Ok(())
}

/// The script hook: hands every performer's control changes of this tick to the matching
/// handlers, as `fn(name, value, performer)`. A failing handler is reported and the
/// others still run.
pub(crate) fn call_handlers(lua: &Lua) -> mlua::Result<()> {
    let Some(handlers) = lua.app_data_ref::<Handlers>().map(|h| h.clone()) else {
        return Ok(());
    };
    // Take the changes and release the lock before calling Lua: a handler may query.
    let changes: Vec<(String, Change)> = {
        let s = performers(lua)?;
        let mut perf =
            s.0.lock()
                .map_err(|_| lua_err_message("performer lock poisoned"))?;
        perf.list
            .iter_mut()
            .filter_map(|p| {
                let name = p.name.clone();
                p.vrpn
                    .as_mut()
                    .map(|v| (name, std::mem::take(&mut v.controls.changes)))
            })
            .flat_map(|(name, cs)| cs.into_iter().map(move |c| (name.clone(), c)))
            .collect()
    };
    if changes.is_empty() {
        return Ok(());
    }
    let list = handlers
        .0
        .lock()
        .map_err(|_| lua_err_message("handler lock poisoned"))?
        .clone();
    for (performer, change) in changes {
        let (is_button, name, value) = match &change {
            Change::Button(n, p) => (true, n, Value::Boolean(*p)),
            Change::Analog(n, v) => (false, n, Value::Number(*v)),
        };
        for (_, _, f) in list
            .iter()
            .filter(|(b, pat, _)| *b == is_button && glob(pat, name))
        {
            if let Err(e) = f.call::<()>((name.as_str(), value.clone(), performer.as_str())) {
                tracing::error!(performer = %performer, control = %name, "handler failed: {e}");
            }
        }
    }
    Ok(())
}
