//! The Lua side of VMC: `troupe.vmc_out{ actor, to, rate }` and a performer's
//! `devices = { vmc = { listen = "0.0.0.0:39540" | zenoh = KEY | replay = "file.rec",
//! latency, … } }`.

use crate::device::remote::RemotePorts;
use crate::lua::args::{check_keys, resolve};
use crate::record::feed::DeviceReplay;
use crate::record::writer::Recorder;
use crate::vmc::input::{VmcInput, VmcSource};
use crate::vmc::listener::VmcListener;
use crate::vmc::output::{SharedVmcOut, VmcStream, DEFAULT_RATE};
use crate::vmc::rig::VmcRig;
use glam::{DQuat, DVec3};
use mlua::{Lua, Table, Value};
use std::sync::Arc;
use troupe_body::sensors::Side;
use troupe_body::skeleton::Skeleton;
use troupe_body::transform::Transform;
use troupe_lua::api::{lua_err_message, ActorRef};
use troupe_lua::args;
use troupe_lua::LuaSession;

/// The port a Performer listens on for Assistants, which troupe uses by default.
pub const PERFORMER_PORT: u16 = 39540;

/// Installs `troupe.vmc_out` and the observer that sends its streams after every tick.
pub(crate) fn install(session: &mut LuaSession) -> mlua::Result<()> {
    let shared = SharedVmcOut::default();
    let (director, _) = session.script_and_scene();
    let lua = director.lua();
    let troupe: Table = lua.globals().get("troupe")?;
    let s = shared.clone();
    troupe.set(
        "vmc_out",
        lua.create_function(move |lua, t: Table| {
            check_keys(&t, "vmc_out", &["actor", "to", "rate"])?;
            let to: String = t
                .get::<Option<String>>("to")?
                .ok_or_else(|| args::err("vmc_out", "`to` (host:port) is required"))?;
            let actor = match t.get::<Value>("actor")? {
                Value::Nil => None,
                Value::String(n) => {
                    let n = n.to_str()?.to_string();
                    let known = troupe_lua::kinds::with_scene(lua, |sc| {
                        sc.actors().iter().any(|a| a.name == n)
                    })?;
                    if !known {
                        return Err(args::err("vmc_out", format!("no actor named '{n}'")));
                    }
                    Some(n)
                }
                Value::UserData(u) => {
                    let i = u.borrow::<ActorRef>()?.0;
                    Some(
                        troupe_lua::kinds::with_scene(lua, |sc| {
                            sc.actors().get(i).map(|a| a.name.clone())
                        })?
                        .ok_or_else(|| args::err("vmc_out", "the actor vanished"))?,
                    )
                }
                _ => return Err(args::err("vmc_out", "`actor` must be an actor or its name")),
            };
            let rate: f64 = t.get::<Option<f64>>("rate")?.unwrap_or(DEFAULT_RATE);
            let stream = VmcStream::new(&to, actor, rate).map_err(|e| args::err("vmc_out", e))?;
            s.0.lock()
                .map_err(|_| lua_err_message("VMC out lock poisoned"))?
                .streams
                .push(stream);
            Ok(())
        })?,
    )?;
    session.observe(shared);
    Ok(())
}

/// Reads `performer.devices.vmc` into the performer's VMC input for `skeleton`, whose
/// actor stands at `at` facing `yaw` (the sender's origin is put there), made at `clock`
/// (scene time and tick), and the hand whose fingers grasp (`hand = "right"|"left"`: the
/// grasping automaton runs on the sender's finger bones, as on a glove's).
pub(crate) fn vmc_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    (scene_time, tick): (f64, u64),
    place: (DVec3, f64),
) -> mlua::Result<(VmcInput, Option<Side>)> {
    const WHAT: &str = "performer.devices.vmc";
    check_keys(
        t,
        WHAT,
        &["listen", "zenoh", "replay", "stream", "latency", "hand"],
    )?;
    let hand = match t.get::<Option<String>>("hand")? {
        Some(h) => Some(Side::parse(&h).map_err(|e| args::err(WHAT, e))?),
        None => None,
    };
    let listen: Option<String> = t.get("listen")?;
    let remote: Option<String> = t.get("zenoh")?;
    let replay: Option<String> = t.get("replay")?;
    let stream_name = format!("{name}.vmc");
    // A replay of the whole run's inputs stands in for the port and the relay.
    let replayed = lua.app_data_ref::<DeviceReplay>().map(|r| r.clone());
    let live = |listener| VmcSource::Live {
        listener,
        opened: tick,
    };
    let source = match (listen, remote, replay) {
        (Some(_), None, None) | (None, Some(_), None) if replayed.is_some() => {
            let replay = replayed.as_ref().expect("a replay");
            VmcSource::Replayed {
                feed: replay
                    .stream(&stream_name)
                    .map_err(|e| args::err(WHAT, e))?,
                opened: tick,
                start: scene_time,
            }
        }
        (Some(l), None, None) => {
            let l = if l.contains(':') {
                l
            } else {
                format!("{l}:{PERFORMER_PORT}")
            };
            live(VmcListener::bind(&l, &stream_name, recorder).map_err(|e| args::err(WHAT, e))?)
        }
        (None, Some(key), None) => {
            // Datagrams served by `troupe relay vmc` on the sender's machine.
            let ports = RemotePorts::from_lua(lua, WHAT, &key)?;
            let port = (ports.0)(&key).map_err(|e| args::err(WHAT, e))?;
            live(
                VmcListener::relayed(port, &key, &stream_name, recorder)
                    .map_err(|e| args::err(WHAT, e))?,
            )
        }
        (None, None, Some(r)) => {
            let stream: Option<String> = t.get("stream")?;
            VmcSource::replay(&resolve(lua, &r), stream.as_deref(), scene_time)
                .map_err(|e| args::err(WHAT, e))?
        }
        (None, None, None) => return Err(args::err(
            WHAT,
            "`listen` (host:port), `zenoh` (a relay's key) or `replay` (a .rec file) is required",
        )),
        _ => {
            return Err(args::err(
                WHAT,
                "give one of `listen`, `zenoh` and `replay`",
            ))
        }
    };
    // Two ticks by default: a 30 Hz sender is then always between two frames.
    let tick = troupe_lua::kinds::with_scene(lua, |s| s.dt())?;
    let latency: f64 = t.get::<Option<f64>>("latency")?.unwrap_or(2.0 * tick);
    if !(latency.is_finite() && (0.0..=2.0).contains(&latency)) {
        return Err(args::err(
            WHAT,
            format!("`latency` must be 0…2 seconds, got {latency}"),
        ));
    }
    let rig = VmcRig::new(skeleton.clone()).map_err(|e| args::err(WHAT, e))?;
    let (at, yaw) = place;
    let place = Transform::new(DQuat::from_rotation_y(yaw), DVec3::new(at.x, 0.0, at.z));
    Ok((VmcInput::new(source, rig, place, latency), hand))
}

/// A VMC input's health for `troupe.devices.health`: the listener's state and counters
/// (`state = "replay"` for a replay), what could not be used, and the sender's time.
pub(crate) fn health(lua: &Lua, v: &VmcInput) -> mlua::Result<Table> {
    let t = crate::lua::health::health_table(lua, v.health())?;
    let c = &v.counters;
    t.set("packets", c.packets)?;
    t.set("malformed", c.malformed)?;
    t.set("unknown", c.unknown)?;
    t.set("ignored", c.ignored)?;
    t.set("invalid", c.invalid)?;
    t.set("unknown_bones", c.unknown_bones)?;
    t.set("source_time", v.source_time)?;
    Ok(t)
}
