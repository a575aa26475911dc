//! The Lua API of performers: `troupe.performer{…}` makes an actor driven by its devices,
//! and `troupe.devices.*` calibrates them, reports their health, reads the glove and its
//! hand, and trains and handles gestures. Option errors name the function and the option.

use crate::cyberglove::calibration::GloveCalibration;
use crate::cyberglove::decoder::GloveLayout;
use crate::cyberglove::protocol::{GloveConfig, GloveProtocol};
use crate::device::protocol::Mode;
use crate::device::reading::Reading;
use crate::device::thread::{self as driver, DeviceHandle, DriverOptions};
use crate::fob::commands::{Hemisphere, OutputFormat, PositionRange};
use crate::fob::protocol::{FobConfig, FobProtocol};
use crate::gesture::{GestureSet, GestureTracker};
use crate::glove_grasp::HandStatus;
use crate::lua::args::{check_keys, resolve};
use crate::lua::health::health_table;
use crate::osc::listener::OscListener;
use crate::performer::converter::{transmitter_to_world, AnatomicalConverter};
use crate::performer::glove_map::{nominal_glove_calibration, GloveMap};
use crate::performer::registry::{
    CaptureTarget, Performer, PerformerInput, Performers, SharedPerformers,
};
use crate::performer::source::{FobInput, GloveInput, OscPoses, Source};
use crate::record::file::Recording;
use crate::record::writer::Recorder;
use glam::DQuat;
use mlua::{Function, Lua, Table, Value};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use troupe_actions::grasp::handover::SharedHandBoard;
use troupe_actions::grasp::HandState;
use troupe_body::sensors::Side;
use troupe_body::skeleton::Skeleton;
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
    // Glove hands and offers to them, shared with `give` (troupe-actions).
    if lua.app_data_ref::<SharedHandBoard>().is_none() {
        lua.set_app_data(SharedHandBoard::default());
    }
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
        for (f, name, new, old) in events {
            f.call::<()>((name.clone(), new, old))
                .map_err(|e| lua_err_message(format!("gesture handler of '{name}': {e}")))?;
        }
        Ok(())
    }));
    session.add_input(Box::new(PerformerInput(shared.clone())));
    Ok(shared)
}

fn shared(lua: &Lua) -> mlua::Result<SharedPerformers> {
    lua.app_data_ref::<SharedPerformers>()
        .map(|s| s.clone())
        .ok_or_else(|| lua_err_message("devices are not enabled"))
}

fn performer_index(lua: &Lua, who: &Value) -> mlua::Result<usize> {
    let s = shared(lua)?;
    let perf =
        s.0.lock()
            .map_err(|_| lua_err_message("performer lock poisoned"))?;
    let found = match who {
        Value::String(n) => {
            let n = n.to_str()?.to_string();
            perf.list.iter().position(|p| p.name == n)
        }
        Value::UserData(u) => {
            let a = u.borrow::<ActorRef>()?.0;
            perf.list.iter().position(|p| p.actor == a)
        }
        _ => None,
    };
    found.ok_or_else(|| lua_err_message("not a performer (give the actor or its name)"))
}

fn install_lua(lua: &Lua) -> mlua::Result<()> {
    let troupe: Table = lua.globals().get("troupe")?;
    troupe.set("performer", lua.create_function(lua_performer)?)?;
    let devices = lua.create_table()?;
    devices.set(
        "calibrate",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let mut perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            perf.list[i].calibrate_requested = true;
            Ok(())
        })?,
    )?;
    devices.set(
        "is_calibrated",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            Ok(perf.list[i]
                .fob
                .as_ref()
                .is_none_or(|f| f.converter.is_calibrated()))
        })?,
    )?;
    devices.set(
        "health",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            let p = &perf.list[i];
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
            Ok(out)
        })?,
    )?;
    devices.set(
        "hand",
        lua.create_function(|lua, who: Value| {
            // The glove's hand DOF targets by name: what a grasp corrector would consume.
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            let p = &perf.list[i];
            let out = lua.create_table()?;
            let Some(g) = &p.glove else { return Ok(out) };
            let t = p
                .target
                .lock()
                .map_err(|_| lua_err_message("target lock poisoned"))?;
            for d in g.map.all_dofs() {
                if t.mask.get(d).copied().unwrap_or(false) {
                    out.set(p.skeleton.dofs()[d].name.as_str(), t.q[d])?;
                }
            }
            Ok(out)
        })?,
    )?;
    devices.set(
        "hand_state",
        lua.create_function(|lua, (who, hand): (Value, Option<String>)| {
            // The glove hand's grasping automaton (4.7): its state, and the object it
            // touches or holds (nil when free).
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            let p = &perf.list[i];
            let status = p
                .hand
                .as_ref()
                .and_then(|h| h.lock().ok().map(|h| *h))
                .ok_or_else(|| args::err("hand_state", format!("`{}` has no glove", p.name)))?;
            if let Some(h) = hand {
                let want = Side::parse(&h).map_err(|e| args::err("hand_state", e))?;
                if want != status.side {
                    return Err(args::err(
                        "hand_state",
                        format!(
                            "`{}` wears the glove on the {} hand, not the {h}",
                            p.name,
                            status.side.name()
                        ),
                    ));
                }
            }
            let object = match status.state {
                HandState::FreeHand => None,
                HandState::GraspingInProgress(o) | HandState::SecureGrasp(o) => Some(o),
            };
            drop(perf);
            let name = match object {
                Some(o) => troupe_lua::kinds::with_scene(lua, |sc| {
                    sc.objects().get(o).map(|x| x.name.clone())
                })?,
                None => None,
            };
            Ok((status.state.name(), name))
        })?,
    )?;
    devices.set(
        "glove",
        lua.create_function(|lua, who: Value| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            match perf.list[i].glove.as_ref().and_then(|g| g.latest.clone()) {
                Some(raw) => Ok(Value::Table(lua.create_sequence_from(raw)?)),
                None => Ok(Value::Nil),
            }
        })?,
    )?;
    devices.set(
        "on_gesture",
        lua.create_function(|lua, (who, f): (Value, Function)| {
            let i = performer_index(lua, &who)?;
            let s = shared(lua)?;
            let mut perf =
                s.0.lock()
                    .map_err(|_| lua_err_message("performer lock poisoned"))?;
            perf.list[i].gesture_handlers.push(f);
            Ok(())
        })?,
    )?;
    devices.set(
        "train_gestures",
        lua.create_function(|lua, (who, examples): (Value, Table)| {
            // { name = "file.rec", … }: every glove record of each recording is an example.
            let i = performer_index(lua, &who)?;
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
    troupe.set("devices", devices)?;
    Ok(())
}

fn opt<T: mlua::FromLua>(t: &Table, key: &str) -> mlua::Result<Option<T>> {
    t.get::<Option<T>>(key)
}

/// `troupe.performer{ name=…, template=…, at=…, facing=…, calibrate="auto"|"manual",
/// devices = { fob = {…}, glove = {…} } }`.
fn lua_performer(lua: &Lua, t: Table) -> mlua::Result<Value> {
    check_keys(
        &t,
        "performer",
        &[
            "name",
            "template",
            "height",
            "mass",
            "at",
            "facing",
            "devices",
            "calibrate",
        ],
    )?;
    let devices: Option<Table> = opt(&t, "devices")?;
    let calibrate: String = opt(&t, "calibrate")?.unwrap_or_else(|| "auto".into());
    if calibrate != "auto" && calibrate != "manual" {
        return Err(args::err(
            "performer",
            format!("`calibrate` must be \"auto\" or \"manual\", got \"{calibrate}\""),
        ));
    }
    // The actor itself is made by troupe.actor, with the actor options.
    let actor_opts = lua.create_table()?;
    for k in ["name", "template", "height", "mass", "at", "facing"] {
        actor_opts.set(k, t.get::<Value>(k)?)?;
    }
    let troupe: Table = lua.globals().get("troupe")?;
    let make: Function = troupe.get("actor")?;
    let actor_value: Value = make.call(actor_opts)?;
    let Value::UserData(ud) = &actor_value else {
        return Err(args::err(
            "performer",
            "troupe.actor did not return an actor",
        ));
    };
    let actor = ud.borrow::<ActorRef>()?.0;
    let name: String = t.get("name")?;
    let skeleton = troupe_lua::actor_skeletons(lua)
        .ok_or_else(|| lua_err_message("no scene"))?
        .get(actor)
        .cloned()
        .ok_or_else(|| args::err("performer", "actor vanished"))?;
    let s = shared(lua)?;
    let recorder =
        s.0.lock()
            .map_err(|_| lua_err_message("performer lock poisoned"))?
            .recorder
            .clone();
    let scene_time = lua
        .globals()
        .get::<Table>("troupe")?
        .get::<Function>("time")
        .ok()
        .map(|f| f.call::<f64>(()))
        .transpose()?
        .unwrap_or(0.0);
    let mut fob = None;
    let mut osc = None;
    let mut glove = None;
    if let Some(d) = &devices {
        check_keys(d, "performer.devices", &["fob", "glove", "osc"])?;
        if let Some(f) = opt::<Table>(d, "fob")? {
            fob = Some(fob_input(
                lua,
                &f,
                &skeleton,
                &name,
                recorder.clone(),
                scene_time,
            )?);
        }
        if let Some(o) = opt::<Table>(d, "osc")? {
            if fob.is_some() {
                return Err(args::err(
                    "performer.devices",
                    "give `fob` or `osc` poses, not both",
                ));
            }
            osc = Some(osc_input(&o, &skeleton)?);
        }
        if let Some(g) = opt::<Table>(d, "glove")? {
            glove = Some(glove_input(
                lua,
                &g,
                &skeleton,
                &name,
                recorder.clone(),
                scene_time,
            )?);
        }
    }
    let n = skeleton.dof_count();
    let hand = match &glove {
        Some(g) => {
            let board = lua
                .app_data_ref::<SharedHandBoard>()
                .map(|b| b.clone())
                .ok_or_else(|| args::err("performer", "no hand board in this run"))?;
            board
                .0
                .lock()
                .map_err(|_| lua_err_message("hand board lock poisoned"))?
                .add_hand(actor, g.side);
            Some(Arc::new(Mutex::new(HandStatus {
                state: HandState::FreeHand,
                side: g.side,
            })))
        }
        None => None,
    };
    let performer = Performer {
        name,
        actor,
        skeleton,
        fob,
        osc,
        glove,
        auto_calibrate: calibrate == "auto",
        calibrate_requested: false,
        target: Arc::new(Mutex::new(CaptureTarget {
            q: vec![0.0; n],
            mask: vec![false; n],
            arrived: None,
            made: 0,
        })),
        gesture_handlers: Vec::new(),
        hand,
    };
    s.0.lock()
        .map_err(|_| lua_err_message("performer lock poisoned"))?
        .list
        .push(performer);
    Ok(actor_value)
}

fn source(
    lua: &Lua,
    t: &Table,
    what: &str,
    kind: &str,
    scene_time: f64,
    live: impl FnOnce(String) -> mlua::Result<DeviceHandle>,
) -> mlua::Result<Source> {
    let port: Option<String> = opt(t, "port")?;
    let replay: Option<String> = opt(t, "replay")?;
    match (port, replay) {
        (Some(p), None) => Ok(Source::Live(live(p)?)),
        (None, Some(r)) => {
            let stream: Option<String> = opt(t, "stream")?;
            Source::replay(&resolve(lua, &r), stream.as_deref(), kind, scene_time)
                .map_err(|e| args::err(what, e))
        }
        (Some(_), Some(_)) => Err(args::err(what, "give `port` or `replay`, not both")),
        (None, None) => Err(args::err(
            what,
            "`port` (a serial port) or `replay` (a .rec file) is required",
        )),
    }
}

fn fob_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    scene_time: f64,
) -> mlua::Result<FobInput> {
    check_keys(
        t,
        "performer.devices.fob",
        &[
            "port",
            "replay",
            "stream",
            "birds",
            "map",
            "format",
            "baud",
            "range",
            "hemisphere",
            "mode",
        ],
    )?;
    let birds: u8 = opt(t, "birds")?.unwrap_or(1);
    if birds == 0 || birds > 14 {
        return Err(args::err(
            "performer.devices.fob",
            format!("birds must be 1…14, got {birds}"),
        ));
    }
    let map_t: Table = opt(t, "map")?.ok_or_else(|| {
        args::err(
            "performer.devices.fob",
            "`map` (joint = bird address) is required",
        )
    })?;
    let mut map = Vec::new();
    for pair in map_t.pairs::<String, u8>() {
        let (j, a) = pair?;
        if a == 0 || a > birds {
            return Err(args::err(
                "performer.devices.fob",
                format!("map.{j} = {a} is not a bird address 1…{birds}"),
            ));
        }
        map.push((j, a));
    }
    let converter = AnatomicalConverter::new(skeleton.clone(), &map, transmitter_to_world())
        .map_err(|e| args::err("performer.devices.fob", e))?;
    let format = OutputFormat::parse(
        &opt::<String>(t, "format")?.unwrap_or_else(|| "position-quaternion".into()),
    )
    .map_err(lua_err_message)?;
    if !matches!(
        format,
        OutputFormat::PositionAngles
            | OutputFormat::PositionQuaternion
            | OutputFormat::PositionMatrix
    ) {
        return Err(args::err(
            "performer.devices.fob",
            "a performer needs a position/orientation format",
        ));
    }
    let mut config = FobConfig::new(birds, format);
    if let Some(r) = opt::<u32>(t, "range")? {
        config.layout.range = PositionRange::parse(&r.to_string()).map_err(lua_err_message)?;
    }
    if let Some(h) = opt::<String>(t, "hemisphere")? {
        config.hemisphere = Hemisphere::parse(&h).map_err(lua_err_message)?;
    }
    if let Some(m) = opt::<String>(t, "mode")? {
        config.mode = parse_mode(&m)?;
    }
    let baud: u32 = opt(t, "baud")?.unwrap_or(115_200);
    let src = source(lua, t, "performer.devices.fob", "fob", scene_time, |port| {
        let mut o = DriverOptions::new(&format!("{name}.fob"), &port);
        o.baud = baud;
        Ok(driver::spawn(
            o,
            Box::new(FobProtocol::new(config)),
            recorder,
        ))
    })?;
    Ok(FobInput {
        source: src,
        converter,
        latest: BTreeMap::new(),
    })
}

fn osc_input(t: &Table, skeleton: &Arc<Skeleton>) -> mlua::Result<OscPoses> {
    check_keys(t, "performer.devices.osc", &["listen", "joints"])?;
    let listen: String = opt(t, "listen")?
        .ok_or_else(|| args::err("performer.devices.osc", "`listen` (host:port) is required"))?;
    let names: Vec<String> = opt::<Vec<String>>(t, "joints")?.ok_or_else(|| {
        args::err(
            "performer.devices.osc",
            "`joints` (the joint names sent) is required",
        )
    })?;
    if names.is_empty() || names.len() > 250 {
        return Err(args::err(
            "performer.devices.osc",
            "`joints` must list 1…250 joints",
        ));
    }
    let joints: Vec<(String, u8)> = names
        .into_iter()
        .enumerate()
        .map(|(i, n)| (n, i as u8 + 1))
        .collect();
    let converter = AnatomicalConverter::new(skeleton.clone(), &joints, DQuat::IDENTITY)
        .map_err(|e| args::err("performer.devices.osc", e))?;
    let listener =
        OscListener::bind(&listen, 4096).map_err(|e| args::err("performer.devices.osc", e))?;
    Ok(OscPoses {
        listener,
        converter,
        joints,
        latest: BTreeMap::new(),
    })
}

fn parse_mode(m: &str) -> mlua::Result<Mode> {
    match m {
        "stream" => Ok(Mode::Stream),
        "point" => Ok(Mode::Point),
        other => Err(lua_err_message(format!(
            "mode must be \"stream\" or \"point\", got \"{other}\""
        ))),
    }
}

fn glove_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    scene_time: f64,
) -> mlua::Result<GloveInput> {
    check_keys(
        t,
        "performer.devices.glove",
        &[
            "port",
            "replay",
            "stream",
            "hand",
            "sensors",
            "calibration",
            "gestures",
            "baud",
            "mode",
            "osc",
        ],
    )?;
    let side = match opt::<String>(t, "hand")?.as_deref() {
        None | Some("right") => "r_",
        Some("left") => "l_",
        Some(o) => {
            return Err(args::err(
                "performer.devices.glove",
                format!("hand must be \"right\" or \"left\", got \"{o}\""),
            ))
        }
    };
    let sensors: usize = opt(t, "sensors")?.unwrap_or(18);
    if sensors != 18 && sensors != 22 {
        return Err(args::err(
            "performer.devices.glove",
            format!("sensors must be 18 or 22, got {sensors}"),
        ));
    }
    let calibration = match opt::<String>(t, "calibration")? {
        Some(f) => {
            let c = GloveCalibration::load(&resolve(lua, &f)).map_err(lua_err_message)?;
            if c.sensors.len() != sensors {
                return Err(lua_err_message(format!(
                    "{f}: calibration for {} sensors, glove has {sensors}",
                    c.sensors.len()
                )));
            }
            c
        }
        None => nominal_glove_calibration(skeleton, sensors, side),
    };
    let map = GloveMap::new(skeleton, sensors, side);
    let gestures = match opt::<String>(t, "gestures")? {
        Some(f) => Some(GestureTracker::new(
            GestureSet::load(&resolve(lua, &f)).map_err(lua_err_message)?,
        )),
        None => None,
    };
    let mode = parse_mode(&opt::<String>(t, "mode")?.unwrap_or_else(|| "stream".into()))?;
    let baud: u32 = opt(t, "baud")?.unwrap_or(115_200);
    let config = GloveConfig {
        layout: GloveLayout {
            sensors,
            status_byte: false,
        },
        mode,
    };
    // `osc = true`: the values arrive as /troupe/<performer>/glove over the performer's
    // OSC listener.
    let src = if opt::<bool>(t, "osc")?.unwrap_or(false) {
        Source::External
    } else {
        source(
            lua,
            t,
            "performer.devices.glove",
            "cyberglove",
            scene_time,
            |port| {
                let mut o = DriverOptions::new(&format!("{name}.glove"), &port);
                o.baud = baud;
                Ok(driver::spawn(
                    o,
                    Box::new(GloveProtocol::new(config)),
                    recorder,
                ))
            },
        )?
    };
    Ok(GloveInput {
        source: src,
        calibration,
        map,
        latest: None,
        gestures,
        side: if side == "l_" {
            Side::Left
        } else {
            Side::Right
        },
    })
}
