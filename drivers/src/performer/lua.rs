//! The Lua API of performers: `troupe.performer{…}` makes an actor driven by its devices
//! (its options are read in `options`), and `troupe.devices.*` calibrates them, reports
//! their health, reads the glove and its hand, and trains and handles gestures.

use crate::device::reading::Reading;
use crate::gesture::{GestureSet, GestureTracker};
use crate::lua::args::resolve;
use crate::lua::health::health_table;
use crate::performer::options::new_performer;
use crate::performer::registry::{Performer, PerformerInput, Performers, SharedPerformers};
use crate::record::file::Recording;
use crate::record::writer::Recorder;
use mlua::{Function, Lua, Table, Value};
use std::sync::{Arc, Mutex};
use troupe_body::sensors::Side;
use troupe_lua::api::{lua_err_message, ActorRef};
use troupe_lua::args;
use troupe_lua::LuaSession;

/// Installs `troupe.performer` and `troupe.devices.*` on the session's director, the
/// performers' input on the session, and the script hook that calls gesture handlers.
/// `recorder` records every live device stream (`--record-devices`).
pub(crate) fn install(
    session: &mut LuaSession,
    recorder: Option<Arc<Recorder>>,
) -> mlua::Result<SharedPerformers> {
    let shared = SharedPerformers(Arc::new(Mutex::new(Performers::new(recorder))));
    let (director, _) = session.script_and_scene();
    let lua = director.lua();
    lua.set_app_data(shared.clone());
    install_lua(lua)?;
    let s = shared.clone();
    director.add_script_hook(Box::new(move |_lua: &Lua| {
        // Take the events and release the lock before calling Lua: a handler may query
        // the performers.
        let events = std::mem::take(
            &mut s
                .0
                .lock()
                .map_err(|_| lua_err_message("performer lock poisoned"))?
                .gesture_events,
        );
        // A failing handler is reported and the others still run.
        for (f, name, new, old) in events {
            if let Err(e) = f.call::<()>((name.clone(), new, old)) {
                tracing::error!(performer = %name, "gesture handler failed: {e}");
            }
        }
        Ok(())
    }));
    // The VRPN controls' events, after the gestures'.
    director.add_script_hook(Box::new(crate::performer::controls_api::call_handlers));
    session.add_input(Box::new(PerformerInput(shared.clone())));
    Ok(shared)
}

fn shared(lua: &Lua) -> mlua::Result<SharedPerformers> {
    lua.app_data_ref::<SharedPerformers>()
        .map(|s| s.clone())
        .ok_or_else(|| lua_err_message("devices are not enabled"))
}

/// Runs `f` on the performer `who` (a name or an actor) names, under the performers'
/// lock; `f` must not call Lua functions that reach the performers.
/// Runs `f` on the performer `who` names (its actor or its name); `function` is the
/// `troupe.devices` function asking, named in the error when `who` is not a performer.
fn with_performer<R>(
    lua: &Lua,
    function: &str,
    who: &Value,
    f: impl FnOnce(&mut Performer) -> mlua::Result<R>,
) -> mlua::Result<R> {
    let i = performer_index(lua, function, who)?;
    let s = shared(lua)?;
    let mut perf =
        s.0.lock()
            .map_err(|_| lua_err_message("performer lock poisoned"))?;
    f(&mut perf.list[i])
}

/// The index of the performer `who` names; the error names `function` and the value.
fn performer_index(lua: &Lua, function: &str, who: &Value) -> mlua::Result<usize> {
    let s = shared(lua)?;
    let found = {
        let perf =
            s.0.lock()
                .map_err(|_| lua_err_message("performer lock poisoned"))?;
        match who {
            Value::String(n) => {
                let n = n.to_str()?.to_string();
                perf.list.iter().position(|p| p.name == n)
            }
            Value::UserData(u) => {
                let a = u.borrow::<ActorRef>()?.0;
                perf.list.iter().position(|p| p.actor == a)
            }
            _ => None,
        }
    };
    found.ok_or_else(|| {
        let what = match who {
            Value::String(n) => format!("no performer named '{}'", n.to_string_lossy()),
            Value::UserData(u) => {
                let name = u.borrow::<ActorRef>().ok().and_then(|a| {
                    troupe_lua::kinds::with_scene(lua, |sc| {
                        sc.actors().get(a.0).map(|x| x.name.clone())
                    })
                    .ok()
                    .flatten()
                });
                match name {
                    Some(n) => format!("actor '{n}' is not a performer"),
                    None => "the actor is not a performer".to_string(),
                }
            }
            other => format!(
                "expected a performer (its actor or its name), got {}",
                other.type_name()
            ),
        };
        args::err(&format!("troupe.devices.{function}"), what)
    })
}

fn install_lua(lua: &Lua) -> mlua::Result<()> {
    let troupe: Table = lua.globals().get("troupe")?;
    troupe.set(
        "performer",
        lua.create_function(|lua, t: Table| {
            let s = shared(lua)?;
            let recorder =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?
                    .recorder
                    .clone();
            let (performer, actor) = new_performer(lua, t, recorder)?;
            s.0.lock()
                .map_err(|_| lua_err_message("performer lock poisoned"))?
                .list
                .push(performer);
            Ok(actor)
        })?,
    )?;
    let devices = lua.create_table()?;
    devices.set(
        "calibrate",
        lua.create_function(|lua, who: Value| {
            with_performer(lua, "calibrate", &who, |p| {
                p.calibrate_requested = true;
                Ok(())
            })
        })?,
    )?;
    devices.set(
        "is_calibrated",
        lua.create_function(|lua, who: Value| {
            with_performer(lua, "is_calibrated", &who, |p| {
                Ok(p.fob.as_ref().is_none_or(|f| f.converter.is_calibrated())
                    && p.vrpn.as_ref().is_none_or(|v| v.converter.is_calibrated()))
            })
        })?,
    )?;
    devices.set(
        "health",
        lua.create_function(|lua, who: Value| {
            with_performer(lua, "health", &who, |p| {
                let out = lua.create_table()?;
                let reports = [
                    ("fob", p.fob.as_ref().map(|f| f.source.health())),
                    ("glove", p.glove.as_ref().map(|g| g.source.health())),
                    (
                        "osc",
                        p.osc.as_ref().map(|o| Some(o.listener.health.report())),
                    ),
                ];
                for (dev, report) in reports {
                    let Some(report) = report else { continue };
                    out.set(dev, health_table(lua, report)?)?;
                }
                if let Some(v) = &p.vrpn {
                    out.set("vrpn", v.health_table(lua)?)?;
                }
                if let Some(v) = &p.vmc {
                    out.set("vmc", crate::vmc::lua::health(lua, v)?)?;
                }
                Ok(out)
            })
        })?,
    )?;
    devices.set(
        "hand",
        lua.create_function(|lua, who: Value| {
            // The glove's hand DOF targets by name: what a grasp corrector would consume.
            with_performer(lua, "hand", &who, |p| {
                let hand = troupe_lua::kinds::with_scene(lua, |scene| {
                    scene
                        .input_pose(p.actor)
                        .map(|pose| p.hand_target(pose))
                        .unwrap_or_default()
                })?;
                let out = lua.create_table()?;
                for (d, v) in hand {
                    out.set(p.skeleton.dofs()[d].name.as_str(), v)?;
                }
                Ok(out)
            })
        })?,
    )?;
    devices.set(
        "hand_state",
        lua.create_function(|lua, (who, hand): (Value, Option<String>)| {
            // The glove hand's grasping automaton (4.7): its state, and the object it
            // touches or holds (nil when free).
            // The capture posts it on the scene's blackboard after every tick.
            let (name, actor) =
                with_performer(lua, "hand_state", &who, |p| Ok((p.name.clone(), p.actor)))?;
            let (side, state, object) = troupe_lua::kinds::with_scene(lua, |sc| {
                sc.blackboard().hand_state(actor).map(|(side, state)| {
                    let object = state
                        .object()
                        .and_then(|o| sc.objects().get(o).map(|x| x.name.clone()));
                    (side, state, object)
                })
            })?
            .ok_or_else(|| args::err("hand_state", format!("`{name}` has no glove")))?;
            if let Some(h) = hand {
                let want = Side::parse(&h).map_err(|e| args::err("hand_state", e))?;
                if want != side {
                    return Err(args::err(
                        "hand_state",
                        format!(
                            "`{name}` wears the glove on the {} hand, not the {h}",
                            side.name()
                        ),
                    ));
                }
            }
            Ok((state.name(), object))
        })?,
    )?;
    devices.set(
        "glove",
        lua.create_function(|lua, who: Value| {
            match with_performer(lua, "glove", &who, |p| {
                Ok(p.glove.as_ref().and_then(|g| g.latest.clone()))
            })? {
                Some(raw) => Ok(Value::Table(lua.create_sequence_from(raw)?)),
                None => Ok(Value::Nil),
            }
        })?,
    )?;
    devices.set(
        "on_gesture",
        lua.create_function(|lua, (who, f): (Value, Function)| {
            with_performer(lua, "on_gesture", &who, |p| {
                p.gesture_handlers.push(f);
                Ok(())
            })
        })?,
    )?;
    devices.set(
        "train_gestures",
        lua.create_function(|lua, (who, examples): (Value, Table)| {
            // { name = "file.rec", … }: every glove record of each recording is an example.
            let i = performer_index(lua, "train_gestures", &who)?;
            let mut ex = Vec::new();
            for pair in examples.pairs::<String, String>() {
                let (name, file) = pair?;
                let path = resolve(lua, &file);
                let rec = Recording::read(&path).map_err(lua_err_message)?;
                let s = rec.find("cyberglove").ok_or_else(|| {
                    lua_err_message(format!("{}: no glove stream", path.display()))
                })?;
                let raws: Vec<Vec<u8>> = rec
                    .readings(s)
                    .map_err(lua_err_message)?
                    .into_iter()
                    .filter_map(|(_, r)| match r {
                        Reading::Glove(g) => Some(g.raw),
                        _ => None,
                    })
                    .collect();
                ex.push((name, raws));
            }
            ex.sort_by(|a, b| a.0.cmp(&b.0));
            let set = GestureSet::train(&ex).map_err(|e| args::err("train_gestures", e))?;
            let s = shared(lua)?;
            let mut perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            let g = perf.list[i]
                .glove
                .as_mut()
                .ok_or_else(|| args::err("train_gestures", "this performer has no glove"))?;
            g.gestures = Some(GestureTracker::new(set));
            Ok(())
        })?,
    )?;
    crate::performer::controls_api::install_lua(lua, &devices)?;
    troupe.set("devices", devices)?;
    Ok(())
}
