//! A VRPN tracker on a performer: `devices = { vrpn = { device = "Tracker0@host", map =
//! { pelvis = 0, r_wrist = 1 } } }` (or `replay = "file.rec"`). Sensor poses go through the
//! anatomical converter like the Flock's birds, after the server's units and axes are
//! brought to the scene's (metres, Y up); buttons and analog channels served on the same
//! connection become the performer's controls.

use crate::device::reading::Reading;
use crate::device::remote::RemotePorts;
use crate::device::thread::Opener;
use crate::lua::args::{check_keys, resolve};
use crate::performer::controls::Controls;
use crate::performer::converter::AnatomicalConverter;
use crate::performer::source::Source;
use crate::record::feed::DeviceReplay;
use crate::record::writer::Recorder;
use crate::vrpn::{self, DeviceName, VrpnConfig, VrpnReading};
use glam::{DQuat, DVec3};
use mlua::{Lua, Table};
use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;
use std::time::{Duration, Instant};
use troupe_body::skeleton::Skeleton;
use troupe_lua::args;

const WHAT: &str = "performer.devices.vrpn";

/// The server frame's up axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Axes {
    /// X right, Y up, Z towards the viewer: VRPN's usual frame, and the scene's.
    YUp,
    /// X right, Y forward, Z up (Vicon, ART and other lab systems' room frame).
    ZUp,
}

impl Axes {
    /// The rotation from the server's frame to the scene's.
    pub(crate) fn to_scene(self) -> DQuat {
        match self {
            Axes::YUp => DQuat::IDENTITY,
            // Z up becomes Y up and Y forward becomes −Z: a quarter turn about X.
            Axes::ZUp => DQuat::from_rotation_x(-FRAC_PI_2),
        }
    }
}

/// A VRPN tracker (and its controls) on a performer.
pub(crate) struct VrpnInput {
    /// Where the reports come from.
    pub(crate) source: Source,
    /// Sensor poses to joint rotations; a sensor `s` is the converter's address `s + 1`.
    pub(crate) converter: AnatomicalConverter,
    /// The latest pose of each mapped sensor, by converter address, in metres.
    pub(crate) latest: BTreeMap<u8, (DVec3, DQuat)>,
    /// Server units to metres.
    pub(crate) scale: f64,
    /// Buttons and analog channels.
    pub(crate) controls: Controls,
}

impl VrpnInput {
    /// Takes the reports due before the tick after `tick`, at `time`: sensor poses into `latest`, buttons and analogs into
    /// the controls. Returns whether a mapped pose changed and the newest arrival instant.
    pub(crate) fn take(&mut self, tick: u64, time: f64) -> (bool, Option<Instant>) {
        let mut changed = false;
        let mut newest = None;
        let mapped = self.converter.birds();
        for (r, at) in self.source.take(tick, time) {
            let Reading::Vrpn(r) = r else { continue };
            match r {
                VrpnReading::Tracker {
                    sensor,
                    position,
                    quaternion: [x, y, z, w],
                    ..
                } => {
                    let Some(addr) = u8::try_from(sensor + 1).ok().filter(|a| mapped.contains(a))
                    else {
                        continue;
                    };
                    let p = DVec3::from_array(position) * self.scale;
                    let q = DQuat::from_xyzw(x, y, z, w);
                    // A zero or non-finite quaternion is no rotation: skip rather than
                    // turn it into NaN joints.
                    if !(p.is_finite() && q.is_finite() && q.length() > 1e-6) {
                        continue;
                    }
                    self.latest.insert(addr, (p, q.normalize()));
                    changed = true;
                    newest = newest.max(at);
                }
                other => self.controls.apply(&other),
            }
        }
        (changed, newest)
    }
}

/// Reads the `vrpn` table of a performer's devices.
pub(crate) fn vrpn_input(
    lua: &Lua,
    t: &Table,
    skeleton: &Arc<Skeleton>,
    name: &str,
    recorder: Option<Arc<Recorder>>,
    clock: (f64, u64),
) -> mlua::Result<VrpnInput> {
    check_keys(
        t,
        WHAT,
        &[
            "device", "zenoh", "replay", "stream", "map", "units", "axes", "buttons", "analogs",
            "timeout",
        ],
    )?;
    let map_t: Table = t
        .get::<Option<Table>>("map")?
        .ok_or_else(|| args::err(WHAT, "`map` (joint = sensor, from 0) is required"))?;
    let mut map = Vec::new();
    for pair in map_t.pairs::<String, i64>() {
        let (j, s) = pair?;
        if !(0..=254).contains(&s) {
            return Err(args::err(
                WHAT,
                format!("map.{j} = {s} is not a sensor 0…254"),
            ));
        }
        map.push((j, s as u8 + 1));
    }
    map.sort();
    let scale = match t.get::<Option<String>>("units")?.as_deref() {
        None | Some("m") => 1.0,
        Some("cm") => 0.01,
        Some("mm") => 0.001,
        Some(o) => {
            return Err(args::err(
                WHAT,
                format!("units must be \"m\", \"cm\" or \"mm\", got \"{o}\""),
            ))
        }
    };
    let axes = match t.get::<Option<String>>("axes")?.as_deref() {
        None | Some("y-up") => Axes::YUp,
        Some("z-up") => Axes::ZUp,
        Some(o) => {
            return Err(args::err(
                WHAT,
                format!("axes must be \"y-up\" or \"z-up\", got \"{o}\""),
            ))
        }
    };
    let converter = AnatomicalConverter::new(skeleton.clone(), &map, axes.to_scene())
        .map_err(|e| args::err(WHAT, e))?;
    let device: Option<String> = t.get("device")?;
    let replay: Option<String> = t.get("replay")?;
    let replayed = lua.app_data_ref::<DeviceReplay>().map(|r| r.clone());
    let source = match (device, replay) {
        // A replay of the whole run's inputs stands in for the server.
        (Some(_), None) if replayed.is_some() => {
            let replay = replayed.as_ref().expect("a replay");
            Source::replayed(replay, &format!("{name}.vrpn"), clock)
                .map_err(|e| args::err(WHAT, e))?
        }
        (Some(d), None) => {
            let n = DeviceName::parse(&d).map_err(|e| args::err(WHAT, e))?;
            let extra: Vec<String> = ["buttons", "analogs"]
                .into_iter()
                .map(|k| t.get::<Option<String>>(k))
                .collect::<mlua::Result<Vec<_>>>()?
                .into_iter()
                .flatten()
                .collect();
            let timeout = t
                .get::<Option<f64>>("timeout")?
                .unwrap_or(vrpn::HANDSHAKE_TIMEOUT.as_secs_f64());
            if !(timeout > 0.0 && timeout <= 60.0) {
                return Err(args::err(
                    WHAT,
                    format!("timeout must be 0…60 s, got {timeout}"),
                ));
            }
            let options = vrpn::driver_options(&format!("{name}.vrpn"), &d);
            let h = match t.get::<Option<String>>("zenoh")? {
                // The server is reached through `troupe relay vrpn` on another machine.
                Some(key) => {
                    let ports = RemotePorts::from_lua(lua, WHAT, &key)?;
                    let opener: Opener = Box::new(move |_| (ports.0)(&key));
                    vrpn::spawn_through(VrpnConfig::new(&n, &extra), options, recorder, opener)
                }
                None => vrpn::spawn(
                    VrpnConfig::new(&n, &extra),
                    options,
                    Duration::from_secs_f64(timeout),
                    recorder,
                )
                .map_err(|e| args::err(WHAT, e))?,
            };
            Source::Live {
                handle: h,
                opened: clock.1,
            }
        }
        (None, Some(r)) => {
            let stream: Option<String> = t.get("stream")?;
            Source::replay(&resolve(lua, &r), stream.as_deref(), "vrpn", clock)
                .map_err(|e| args::err(WHAT, e))?
        }
        (Some(_), Some(_)) => return Err(args::err(WHAT, "give `device` or `replay`, not both")),
        (None, None) => {
            return Err(args::err(
                WHAT,
                "`device` (Tracker0@host) or `replay` (a .rec file) is required",
            ))
        }
    };
    Ok(VrpnInput {
        source,
        converter,
        latest: BTreeMap::new(),
        scale,
        controls: Controls::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_up_axes_turn_into_the_scenes_y_up() {
        let r = Axes::ZUp.to_scene();
        assert!((r * DVec3::Z - DVec3::Y).length() < 1e-12);
        assert!((r * DVec3::Y + DVec3::Z).length() < 1e-12);
        assert!((r * DVec3::X - DVec3::X).length() < 1e-12);
        assert_eq!(Axes::YUp.to_scene(), DQuat::IDENTITY);
    }
}
