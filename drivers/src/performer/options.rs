//! The options of `troupe.performer{…}`: the actor, and its devices — a Flock of Birds or
//! OSC poses for the body, a glove for the hand — each live on a port or replayed from a
//! `.rec` file. Errors name the option table (`performer.devices.fob`, …) and the option.

use crate::cyberglove::calibration::GloveCalibration;
use crate::cyberglove::decoder::GloveLayout;
use crate::cyberglove::protocol::{GloveConfig, GloveProtocol};
use crate::device::protocol::{Mode, Protocol};
use crate::device::remote::RemotePorts;
use crate::device::thread::{spawn, spawn_with, DriverOptions, Opener};
use crate::fob::commands::{Hemisphere, OutputFormat, PositionRange};
use crate::fob::protocol::{FobConfig, FobProtocol};
use crate::gesture::{GestureSet, GestureTracker};
use crate::lua::args::{check_keys, resolve};
use crate::osc::listener::OscListener;
use crate::performer::converter::{transmitter_to_world, AnatomicalConverter};
use crate::performer::glove_map::{nominal_glove_calibration, GloveMap};
use crate::performer::registry::Performer;
use crate::performer::source::{scene_clock, FobInput, GloveInput, OscPoses, Source};
use crate::performer::vrpn::vrpn_input;
use crate::record::feed::DeviceReplay;
use crate::record::writer::Recorder;
use glam::DQuat;
use mlua::{Function, Lua, Table, Value};
use std::collections::BTreeMap;
use std::sync::Arc;
use troupe_body::sensors::Side;
use troupe_body::skeleton::Skeleton;
use troupe_body::Scope;
use troupe_lua::api::{lua_err_message, ActorRef};
use troupe_lua::args;
use troupe_scene::InputPose;

/// An optional option of `troupe.performer`, in troupe's wording when it has the wrong
/// type (a boolean must be a boolean: `osc = "no"` is refused, not taken as true).
fn opt<T: mlua::FromLua>(t: &Table, key: &str) -> mlua::Result<Option<T>> {
    let v: Value = t.get(key)?;
    if v.is_nil() {
        return Ok(None);
    }
    let rust = std::any::type_name::<T>();
    let expected = match rust {
        "bool" => "a boolean",
        "alloc::string::String" => "a string",
        "mlua::table::Table" => "a table",
        r if r.starts_with("alloc::vec::Vec") => "a list",
        _ => "a number",
    };
    let refused = || {
        args::err(
            "performer",
            format!(
                "option `{key}` must be {expected}, got {}",
                args::value_name(&v)
            ),
        )
    };
    if rust == "bool" && !matches!(v, Value::Boolean(_)) {
        return Err(refused());
    }
    t.get::<T>(key).map(Some).map_err(|_| refused())
}

/// `troupe.performer{ name=…, template=…, at=…, facing=…, calibrate="auto"|"manual",
/// devices = { fob = {…} | osc = {…} | vrpn = {…}, glove = {…} } }`: makes the actor (with
/// `troupe.actor`) and its devices; returns the performer and the actor's handle.
/// `recorder` records its live device streams.
pub(crate) fn new_performer(
    lua: &Lua,
    t: Table,
    recorder: Option<Arc<Recorder>>,
) -> mlua::Result<(Performer, Value)> {
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
    // The actor itself is made by troupe.actor, with the actor options, once its devices
    // are open: a device that fails to open then leaves no actor behind. They open with
    // the skeleton the actor will have and the place it will stand on.
    let actor_opts = lua.create_table()?;
    for k in ["name", "template", "height", "mass", "at", "facing"] {
        actor_opts.set(k, t.get::<Value>(k)?)?;
    }
    let desc = troupe_lua::api::actor_desc(&actor_opts)?;
    let skeleton = troupe_lua::kinds::with_scene_mut(lua, |scene| scene.skeleton_for(&desc))?
        .map_err(|e| lua_err_message(format!("actor: {e}")))?
        .0;
    let name = desc.name.clone();
    let clock = scene_clock(lua)?;
    let mut fob = None;
    let mut osc = None;
    let mut glove = None;
    let mut vrpn = None;
    let mut vmc = None;
    let mut vmc_hand = None;
    if let Some(d) = &devices {
        check_keys(
            d,
            "performer.devices",
            &["fob", "glove", "osc", "vmc", "vrpn"],
        )?;
        if let Some(f) = opt::<Table>(d, "fob")? {
            fob = Some(fob_input(
                lua,
                &f,
                &skeleton,
                &name,
                recorder.clone(),
                clock,
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
        // One source of body poses: they would fight over the same DOFs.
        let one_body_source = || {
            args::err(
                "performer.devices",
                "give one source of body poses: `fob`, `osc`, `vmc` or `vrpn`",
            )
        };
        if let Some(v) = opt::<Table>(d, "vrpn")? {
            if fob.is_some() || osc.is_some() {
                return Err(one_body_source());
            }
            vrpn = Some(vrpn_input(
                lua,
                &v,
                &skeleton,
                &name,
                recorder.clone(),
                clock,
            )?);
        }
        if let Some(v) = opt::<Table>(d, "vmc")? {
            if fob.is_some() || osc.is_some() || vrpn.is_some() {
                return Err(one_body_source());
            }
            let place = (
                glam::DVec3::new(desc.at.x, 0.0, desc.at.z),
                desc.facing_degrees.to_radians(),
            );
            let (input, hand) = crate::vmc::lua::vmc_input(
                lua,
                &v,
                &skeleton,
                &name,
                recorder.clone(),
                clock,
                place,
            )?;
            vmc = Some(input);
            vmc_hand = hand;
        }
        if let Some(g) = opt::<Table>(d, "glove")? {
            glove = Some(glove_input(
                lua,
                &g,
                &skeleton,
                &name,
                recorder.clone(),
                clock,
            )?);
        }
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
    let n = skeleton.dof_count();
    // Every DOF the devices can drive: the natural scope of the performer's `capture`.
    let mut driven = Scope::EMPTY;
    let converters = fob
        .iter()
        .map(|f| &f.converter)
        .chain(osc.iter().map(|o| &o.converter))
        .chain(vrpn.iter().map(|v| &v.converter));
    for c in converters {
        for d in c.driven_dofs() {
            driven.insert(d);
        }
    }
    if let Some(g) = &glove {
        for d in g.map.all_dofs() {
            driven.insert(d);
        }
    }
    if let Some(v) = &vmc {
        for d in v.rig.dofs() {
            driven.insert(d);
        }
    }
    let glove_side = glove.as_ref().map(|g| g.side).or(vmc_hand);
    troupe_lua::kinds::with_scene_mut(lua, |scene| {
        // Nothing asked until the first samples arrive.
        scene.set_input_pose(actor, InputPose::new(n, driven))?;
        if let Some(side) = glove_side {
            // A giver brings objects into this hand rather than handing them over.
            scene.declare_device_hand(actor, side)?;
        }
        Ok::<_, troupe_scene::Error>(())
    })?
    .map_err(|e| args::err("performer", e))?;
    let performer = Performer {
        name,
        actor,
        skeleton,
        fob,
        osc,
        vrpn,
        glove,
        vmc,
        auto_calibrate: calibrate == "auto",
        calibrate_requested: false,
        made: 0,
        driven,
        gesture_handlers: Vec::new(),
    };
    Ok((performer, actor_value))
}

fn source(
    lua: &Lua,
    t: &Table,
    what: &str,
    kind: &str,
    clock: (f64, u64),
    recorder: Option<Arc<Recorder>>,
    live: impl FnOnce(String) -> (DriverOptions, Box<dyn Protocol>),
) -> mlua::Result<Source> {
    let port: Option<String> = opt(t, "port")?;
    let replay: Option<String> = opt(t, "replay")?;
    let remote: Option<String> = opt(t, "zenoh")?;
    // A replay of the whole run's inputs stands in for every port and relay.
    let replayed = lua.app_data_ref::<DeviceReplay>().map(|r| r.clone());
    if let (Some(replay), None, true) = (&replayed, &replay, port.is_some() || remote.is_some()) {
        let (options, _) = live(port.clone().or(remote.clone()).unwrap_or_default());
        return Source::replayed(replay, &options.name, clock).map_err(|e| args::err(what, e));
    }
    match (port, replay, remote) {
        (Some(p), None, None) => {
            let (options, protocol) = live(p);
            Ok(Source::Live {
                handle: spawn(options, protocol, recorder),
                opened: clock.1,
            })
        }
        (None, Some(r), None) => {
            let stream: Option<String> = opt(t, "stream")?;
            Source::replay(&resolve(lua, &r), stream.as_deref(), kind, clock)
                .map_err(|e| args::err(what, e))
        }
        (None, None, Some(key)) => {
            let ports = RemotePorts::from_lua(lua, what, &key)?;
            let (options, protocol) = live(format!("zenoh:{key}"));
            let opener: Opener = Box::new(move |_| (ports.0)(&key));
            Ok(Source::Live {
                handle: spawn_with(options, protocol, recorder, opener),
                opened: clock.1,
            })
        }
        (None, None, None) => Err(args::err(
            what,
            "`port` (a serial port), `replay` (a .rec file) or `zenoh` (a relay's key) is required",
        )),
        _ => Err(args::err(what, "give one of `port`, `replay` and `zenoh`")),
    }
}

fn fob_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    clock: (f64, u64),
) -> mlua::Result<FobInput> {
    check_keys(
        t,
        "performer.devices.fob",
        &[
            "port",
            "replay",
            "zenoh",
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
    let src = source(
        lua,
        t,
        "performer.devices.fob",
        "fob",
        clock,
        recorder,
        |port| {
            let mut o = DriverOptions::new(&format!("{name}.fob"), &port);
            o.baud = baud;
            (o, Box::new(FobProtocol::new(config)))
        },
    )?;
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
    clock: (f64, u64),
) -> mlua::Result<GloveInput> {
    check_keys(
        t,
        "performer.devices.glove",
        &[
            "port",
            "replay",
            "zenoh",
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
            clock,
            recorder,
            |port| {
                let mut o = DriverOptions::new(&format!("{name}.glove"), &port);
                o.baud = baud;
                (o, Box::new(GloveProtocol::new(config)))
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
