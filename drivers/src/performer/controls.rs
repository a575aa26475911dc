//! A performer's controls: the buttons and analog channels of its VRPN devices, named
//! `Device.index` (`Wand0.2`), as values (`troupe.devices.buttons(pat)`,
//! `troupe.devices.analogs(pat)`) and as events (`troupe.devices.on_button(pat, fn)`,
//! `troupe.devices.on_analog(pat, fn)`), called at the start of the script phase of the
//! tick whose input brought the change, in the order the reports came.

use crate::performer::registry::SharedPerformers;
use crate::vrpn::VrpnReading;
use mlua::{Function, Lua, Table, Value};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use troupe_lua::api::lua_err_message;

/// One control that changed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Change {
    /// A button went down (`true`) or up.
    Button(String, bool),
    /// An analog channel took a new value.
    Analog(String, f64),
}

/// The latest value of every control, and the changes not yet handed to handlers.
#[derive(Debug, Default)]
pub(crate) struct Controls {
    pub(crate) buttons: BTreeMap<String, bool>,
    pub(crate) analogs: BTreeMap<String, f64>,
    pub(crate) changes: Vec<Change>,
}

impl Controls {
    fn button(&mut self, name: String, pressed: bool) {
        if self.buttons.insert(name.clone(), pressed) != Some(pressed) {
            self.changes.push(Change::Button(name, pressed));
        }
    }

    /// Takes a button or analog report (others are not controls).
    pub(crate) fn apply(&mut self, r: &VrpnReading) {
        match r {
            VrpnReading::Button {
                device,
                button,
                pressed,
                ..
            } => self.button(format!("{device}.{button}"), *pressed),
            VrpnReading::Buttons {
                device, pressed, ..
            } => {
                for (i, p) in pressed.iter().enumerate() {
                    self.button(format!("{device}.{i}"), *p);
                }
            }
            VrpnReading::Analog {
                device, channels, ..
            } => {
                for (i, v) in channels.iter().enumerate() {
                    let name = format!("{device}.{i}");
                    if self.analogs.insert(name.clone(), *v) != Some(*v) {
                        self.changes.push(Change::Analog(name, *v));
                    }
                }
            }
            _ => {}
        }
    }
}

/// Whether `name` matches `pattern`, where `*` stands for any run of characters.
pub(crate) fn glob(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((head, rest)) => {
            let Some(tail) = name.strip_prefix(head) else {
                return false;
            };
            (0..=tail.len())
                .filter(|&i| tail.is_char_boundary(i))
                .any(|i| glob(rest, &tail[i..]))
        }
    }
}

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
            lua.create_function(move |lua, (pat, f): (String, Function)| {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn globs_match_runs_of_any_characters() {
        assert!(glob("Wand0.*", "Wand0.12"));
        assert!(glob("*", ""));
        assert!(glob("*.1", "Button0.1"));
        assert!(!glob("*.1", "Button0.10"));
        assert!(glob("W*0.*2", "Wand0.2"));
        assert!(!glob("Wand0.1", "Wand0.10"));
    }

    #[test]
    fn only_changes_are_events() {
        let mut c = Controls::default();
        let b = |pressed| VrpnReading::Button {
            device: "B".into(),
            button: 1,
            pressed,
            time: 0.0,
        };
        c.apply(&b(true));
        c.apply(&b(true));
        c.apply(&VrpnReading::Buttons {
            device: "B".into(),
            pressed: vec![false, true],
            time: 0.0,
        });
        c.apply(&VrpnReading::Analog {
            device: "A".into(),
            channels: vec![0.5],
            time: 0.0,
        });
        c.apply(&VrpnReading::Analog {
            device: "A".into(),
            channels: vec![0.5],
            time: 0.0,
        });
        assert_eq!(
            c.changes,
            vec![
                Change::Button("B.1".into(), true),
                Change::Button("B.0".into(), false),
                Change::Analog("A.0".into(), 0.5)
            ]
        );
    }
}
