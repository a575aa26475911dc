//! The Lua API of SpaceMouse movers: `troupe.devices.spacemouse{…}` makes one, and
//! `troupe.devices.health` answers for it by name.

use crate::device::remote::RemotePorts;
use crate::device::thread::{spawn_with, DriverOptions, Opener};
use crate::lua::args::{check_keys, resolve};
use crate::lua::health::health_table;
use crate::record::feed::DeviceReplay;
use crate::record::file::Recording;
use crate::record::writer::Recorder;
use crate::space_move::mover::{
    MoveOptions, Mover, SharedSpaceMice, Source, SpaceMice, SpaceMouseInput,
};
use crate::spacemouse::decoder::SpaceMouseState;
use crate::spacemouse::hid::open_spacemouse;
use crate::spacemouse::protocol::SpaceMouseProtocol;
use mlua::{Lua, Table, Value};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use troupe_lua::api::{lua_err_message, ObjectRef};
use troupe_lua::args;
use troupe_lua::LuaSession;

/// Installs `troupe.devices.spacemouse` (and SpaceMouse names in `troupe.devices.health`)
/// on the session's director and the input that moves the objects. Called after the
/// performers' install, which makes `troupe.devices`. `recorder` records live SpaceMouse
/// reports.
pub(crate) fn install(
    session: &mut LuaSession,
    recorder: Option<Arc<Recorder>>,
) -> mlua::Result<SharedSpaceMice> {
    let shared = SharedSpaceMice(Arc::new(Mutex::new(SpaceMice {
        movers: Vec::new(),
        recorder,
    })));
    let lua = session.script().lua();
    lua.set_app_data(shared.clone());
    install_lua(lua)?;
    session.add_input(Box::new(SpaceMouseInput(shared.clone())));
    Ok(shared)
}

fn shared(lua: &Lua) -> mlua::Result<SharedSpaceMice> {
    lua.app_data_ref::<SharedSpaceMice>()
        .map(|s| s.clone())
        .ok_or_else(|| lua_err_message("devices are not enabled"))
}

const KEYS: [&str; 9] = [
    "object", "name", "path", "zenoh", "replay", "stream", "speed", "turn", "deadzone",
];

fn install_lua(lua: &Lua) -> mlua::Result<()> {
    let troupe: Table = lua.globals().get("troupe")?;
    let devices: Table = match troupe.get::<Option<Table>>("devices")? {
        Some(t) => t,
        None => {
            let t = lua.create_table()?;
            troupe.set("devices", t.clone())?;
            t
        }
    };
    devices.set("spacemouse", lua.create_function(lua_spacemouse)?)?;
    // `troupe.devices.health(name)` answers for a SpaceMouse name as it does for a
    // performer, and passes anything else on to the performers' function.
    let previous: Option<mlua::Function> = devices.get("health")?;
    devices.set(
        "health",
        lua.create_function(move |lua, who: Value| {
            if let Value::String(n) = &who {
                let n = n.to_str()?.to_string();
                let s = shared(lua)?;
                let report =
                    s.0.lock()
                        .map_err(|_| lua_err_message("spacemouse lock poisoned"))?
                        .health(&n);
                if let Some(report) = report {
                    let t = health_table(lua, report)?;
                    let out = lua.create_table()?;
                    out.set("spacemouse", t)?;
                    return Ok(Value::Table(out));
                }
            }
            match &previous {
                Some(f) => f.call::<Value>(who),
                None => Err(args::err("health", "no device of that name")),
            }
        })?,
    )?;
    Ok(())
}

fn number(t: &Table, key: &str, default: f64) -> mlua::Result<f64> {
    Ok(args::opt_number(t, "spacemouse", key)?.unwrap_or(default))
}

/// `troupe.devices.spacemouse{ object=…, name="spacemouse", path=nil, zenoh=nil,
/// replay=nil, stream=nil, speed=1.0, turn=90, deadzone=0.05 }` → the mover's name.
fn lua_spacemouse(lua: &Lua, t: Table) -> mlua::Result<String> {
    check_keys(&t, "spacemouse", &KEYS)?;
    let object = match t.get::<Value>("object")? {
        Value::UserData(u) => {
            u.borrow::<ObjectRef>()
                .map_err(|_| {
                    args::err("spacemouse", "`object` must be an object or an object name")
                })?
                .0
        }
        Value::String(n) => {
            let n = n.to_str()?.to_string();
            troupe_lua::kinds::with_scene(lua, |s| s.object_index(&n))?
                .map_err(|e| args::err("spacemouse", e))?
        }
        Value::Nil => return Err(args::err("spacemouse", "`object` is required")),
        _ => {
            return Err(args::err(
                "spacemouse",
                "`object` must be an object or an object name",
            ))
        }
    };
    let name = args::opt_string(&t, "spacemouse", "name")?.unwrap_or_else(|| "spacemouse".into());
    let speed = number(&t, "speed", 1.0)?;
    let turn = number(&t, "turn", 90.0)?;
    let deadzone = number(&t, "deadzone", 0.05)?;
    if speed < 0.0 || turn < 0.0 {
        return Err(args::err(
            "spacemouse",
            "`speed` and `turn` must not be negative",
        ));
    }
    if !(0.0..1.0).contains(&deadzone) {
        return Err(args::err(
            "spacemouse",
            format!("`deadzone` must be in [0, 1), got {deadzone}"),
        ));
    }
    let path: Option<String> = t.get("path")?;
    let replay: Option<String> = t.get("replay")?;
    let stream: Option<String> = t.get("stream")?;
    let s = shared(lua)?;
    let recorder = {
        let g =
            s.0.lock()
                .map_err(|_| lua_err_message("spacemouse lock poisoned"))?;
        if g.movers.iter().any(|m| m.name == name) {
            return Err(args::err(
                "spacemouse",
                format!("a SpaceMouse named '{name}' exists already (give another `name`)"),
            ));
        }
        g.recorder.clone()
    };
    let remote: Option<String> = t.get("zenoh")?;
    if path.is_some() && remote.is_some() {
        return Err(args::err("spacemouse", "give `path` or `zenoh`, not both"));
    }
    let clock = crate::performer::source::scene_clock(lua)?;
    // A replay of the whole run's inputs stands in for the live or relayed device.
    let replayed = lua.app_data_ref::<DeviceReplay>().map(|r| r.clone());
    let source = match (replay, replayed) {
        (None, Some(whole_run)) => Source::Replayed {
            feed: whole_run
                .stream(&name)
                .map_err(|e| args::err("spacemouse", e))?,
            opened: clock.1,
            start: clock.0,
        },
        (Some(r), _) => {
            if path.is_some() {
                return Err(args::err("spacemouse", "give `path` or `replay`, not both"));
            }
            let file = resolve(lua, &r);
            let rec = Recording::read(&file).map_err(|e| args::err("spacemouse", e))?;
            let i = rec
                .find(stream.as_deref().unwrap_or("spacemouse"))
                .ok_or_else(|| {
                    args::err(
                        "spacemouse",
                        format!(
                            "{} has no single 'spacemouse' stream (name one with stream=…)",
                            file.display()
                        ),
                    )
                })?;
            if rec.streams[i].kind != "spacemouse" {
                return Err(args::err(
                    "spacemouse",
                    format!(
                        "stream '{}' of {} is a {} stream",
                        rec.streams[i].name,
                        file.display(),
                        rec.streams[i].kind
                    ),
                ));
            }
            let readings = rec.readings(i).map_err(|e| args::err("spacemouse", e))?;
            Source::Replay {
                readings,
                next: 0,
                start: None,
            }
        }
        (None, None) => {
            let mut o = DriverOptions::new(&name, path.as_deref().unwrap_or(""));
            // A SpaceMouse at rest sends nothing: silence is not staleness.
            o.stale_after = Duration::MAX;
            let opener: Opener = match remote {
                // Served by `troupe relay spacemouse` on another machine.
                Some(key) => {
                    let ports = RemotePorts::from_lua(lua, "spacemouse", &key)?;
                    Box::new(move |_o: &DriverOptions| (ports.0)(&key))
                }
                None => Box::new(move |_o: &DriverOptions| open_spacemouse(path.as_deref())),
            };
            Source::Live {
                handle: spawn_with(o, Box::new(SpaceMouseProtocol::default()), recorder, opener),
                opened: clock.1,
            }
        }
    };
    s.0.lock()
        .map_err(|_| lua_err_message("spacemouse lock poisoned"))?
        .movers
        .push(Mover {
            name: name.clone(),
            object,
            source,
            state: SpaceMouseState::default(),
            options: MoveOptions {
                speed,
                turn: turn.to_radians(),
                deadzone,
            },
        });
    Ok(name)
}
