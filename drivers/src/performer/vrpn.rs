//! A VRPN tracker on a performer: `devices = { vrpn = { device = "Tracker0@host", map =
//! { pelvis = 0, r_wrist = 1 } } }` (or `replay = "file.rec"`). Sensor poses go through the
//! anatomical converter like the Flock's birds, after the server's units and axes are
//! brought to the scene's (metres, Y up); buttons and analog channels served on the same
//! connection become the performer's controls.

use crate::device::health::HealthReport;
use crate::device::reading::Reading;
use crate::device::remote::RemotePorts;
use crate::device::thread::Opener;
use crate::lua::args::{check_keys, resolve};
use crate::lua::health::health_table;
use crate::performer::controls::Controls;
use crate::performer::converter::AnatomicalConverter;
use crate::performer::source::Source;
use crate::record::feed::DeviceReplay;
use crate::record::writer::Recorder;
use crate::vrpn::{self, DeviceName, VrpnConfig, VrpnReading};
use glam::{DQuat, DVec3};
use mlua::{Lua, Table, Value};
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

/// Metres from the server's origin beyond which a tracker position is refused. Tracked
/// rooms are tens of metres; a position a kilometre away is a broken server or a wrong
/// `units`, and taken as is it would throw the actor out of the scene.
pub(crate) const MAX_POSITION: f64 = 1000.0;

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
    /// Reports taken from the source (what a replay reports as its samples).
    pub(crate) samples: u64,
    /// Reports refused: a non-finite number, a zero quaternion, a position beyond
    /// [`MAX_POSITION`].
    pub(crate) invalid: u64,
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
            self.samples += 1;
            match r {
                VrpnReading::Tracker {
                    sensor,
                    position,
                    quaternion: [x, y, z, w],
                    ..
                } => {
                    let p = DVec3::from_array(position) * self.scale;
                    let q = DQuat::from_xyzw(x, y, z, w);
                    // A zero or non-finite quaternion is no rotation, a position beyond
                    // the bound no place in the room: refused rather than turned into
                    // NaN joints or an actor kilometres away.
                    let usable = p.is_finite()
                        && p.length() <= MAX_POSITION
                        && q.is_finite()
                        && q.length() > 1e-6;
                    if !usable {
                        self.invalid += 1;
                        continue;
                    }
                    let Some(addr) = sensor
                        .checked_add(1)
                        .and_then(|s| u8::try_from(s).ok())
                        .filter(|a| mapped.contains(a))
                    else {
                        continue;
                    };
                    self.latest.insert(addr, (p, q.normalize()));
                    changed = true;
                    newest = newest.max(at);
                }
                other => {
                    if !self.controls.apply(&other) {
                        self.invalid += 1;
                    }
                }
            }
        }
        (changed, newest)
    }

    /// The live connection's health with the refused reports counted as resyncs (what
    /// `troupe run` prints); `None` for a replay.
    pub(crate) fn health(&self) -> Option<HealthReport> {
        let mut h = self.source.health()?;
        h.resyncs += self.invalid;
        Some(h)
    }

    /// The health table of `troupe.devices.health(pat).vrpn`: the connection's state and
    /// counters and `invalid`. A replay has the same fields, counted from what it
    /// replays: `samples` the reports taken, `resyncs` and `dropped_bytes` what its
    /// decoder could not use plus the refused reports, `state = "replay"`.
    pub(crate) fn health_table(&self, lua: &Lua) -> mlua::Result<Table> {
        let t = match self.health() {
            Some(h) => health_table(lua, Some(h))?,
            None => {
                let t = health_table(lua, None)?;
                let (resyncs, dropped_bytes) = self.source.decode_counters();
                t.set("samples", self.samples)?;
                t.set("resyncs", resyncs + self.invalid)?;
                t.set("dropped_bytes", dropped_bytes)?;
                t.set("dropped_samples", 0)?;
                t.set("connections", 0)?;
                t
            }
        };
        t.set("invalid", self.invalid)?;
        Ok(t)
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
    for pair in map_t.pairs::<String, Value>() {
        let (j, v) = pair?;
        // A sensor is a whole number: say which entry is not, rather than mlua's bare
        // "expected an integer".
        let s = match v {
            Value::Integer(s) => s,
            Value::Number(n) if n.fract() == 0.0 && n.abs() <= 1e15 => n as i64,
            other => {
                let shown = match &other {
                    Value::Number(n) => n.to_string(),
                    o => o.type_name().to_string(),
                };
                return Err(args::err(
                    WHAT,
                    format!("map.{j} = {shown} is not a sensor 0…254 (a whole number)"),
                ));
            }
        };
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
                    format!("timeout must be more than 0 and at most 60 s, got {timeout}"),
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
        samples: 0,
        invalid: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::performer::controls::Change;
    use crate::performer::converter::tests::adult;
    use crate::record::writer::Recorder;
    use crate::vrpn::decoder::types;
    use crate::vrpn::wire::{encode, name_payload, system};

    fn numbers(words: &[i32], values: &[f64]) -> Vec<u8> {
        let mut p: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
        p.extend(values.iter().flat_map(|v| v.to_be_bytes()));
        p
    }

    /// A recorded VRPN stream (Tracker0 sensor 0 and Wand0's analogs) of `reports`:
    /// `(sender, type, payload)` with senders 0 Tracker0, 1 Wand0 and types 0 Pos_Quat,
    /// 1 Analog Channel.
    fn recording(name: &str, reports: &[(i32, i32, Vec<u8>)]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("troupe-vrpn-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        let rec = Recorder::create(&path).unwrap();
        let config = VrpnConfig {
            device: "Tracker0@localhost".into(),
            senders: vec!["Tracker0".into(), "Wand0".into()],
        };
        let s = rec.add_stream("pat.vrpn", "vrpn", serde_json::to_value(&config).unwrap());
        let described = [
            (0, system::SENDER_DESCRIPTION, "Tracker0"),
            (1, system::SENDER_DESCRIPTION, "Wand0"),
            (0, system::TYPE_DESCRIPTION, types::POS_QUAT),
            (1, system::TYPE_DESCRIPTION, types::ANALOG),
        ];
        for (id, kind, name) in described {
            rec.data_at(s, 0, &encode(0, 0, id, kind, &name_payload(name)));
        }
        for (k, (sender, kind, payload)) in reports.iter().enumerate() {
            rec.data_at(
                s,
                1000 * (k as u64 + 1),
                &encode(0, 0, *sender, *kind, payload),
            );
        }
        rec.finish().unwrap();
        path
    }

    fn input(path: &std::path::Path) -> VrpnInput {
        let map = [("pelvis".to_string(), 1u8)];
        VrpnInput {
            source: Source::replay(path, None, "vrpn", (0.0, 0)).unwrap(),
            converter: AnatomicalConverter::new(adult(), &map, Axes::YUp.to_scene()).unwrap(),
            latest: BTreeMap::new(),
            scale: 1.0,
            controls: Controls::default(),
            samples: 0,
            invalid: 0,
        }
    }

    #[test]
    fn non_finite_and_far_reports_are_refused_and_counted() {
        let (w, id) = ([0, 0], [0.0, 0.0, 0.0, 1.0]);
        let pose = |p: [f64; 3]| (0, 0, numbers(&w, &[p.as_slice(), &id].concat()));
        let analog = |v: f64| (1, 1, numbers(&[], &[1.0, v]));
        let path = recording(
            "refused.rec",
            &[
                pose([0.1, 1.0, 0.2]),
                pose([f64::NAN, 1.0, 0.2]),
                // 1e300 m (the tester's) and just past the bound: refused.
                pose([0.0, 1e300, 0.0]),
                pose([MAX_POSITION + 1.0, 0.0, 0.0]),
                analog(0.5),
                analog(f64::NAN),
                analog(f64::NAN),
                analog(f64::INFINITY),
            ],
        );
        let mut v = input(&path);
        let (changed, _) = v.take(0, 10.0);
        assert!(changed);
        assert_eq!(v.latest[&1].0, DVec3::new(0.1, 1.0, 0.2));
        assert_eq!(v.controls.changes, [Change::Analog("Wand0.0".into(), 0.5)]);
        assert_eq!(v.controls.analogs["Wand0.0"], 0.5);
        assert_eq!((v.samples, v.invalid), (8, 6));
    }

    #[test]
    fn a_replayed_tracker_reports_the_live_health_fields() {
        let report = numbers(&[0, 0], &[0.1, 1.0, 0.2, 0.0, 0.0, 0.0, 1.0]);
        let path = recording(
            "health.rec",
            &[
                (0, 0, report.clone()),
                (0, 0, report[..20].to_vec()), // short: the decoder's resync
                (0, 0, numbers(&[0, 0], &[f64::NAN; 7])),
                (0, 0, report),
            ],
        );
        let mut v = input(&path);
        v.take(0, 10.0);
        let lua = Lua::new();
        let t = v.health_table(&lua).unwrap();
        assert_eq!(t.get::<String>("state").unwrap(), "replay");
        let field = |k: &str| t.get::<u64>(k).unwrap();
        assert_eq!(field("samples"), 3);
        assert_eq!(field("invalid"), 1);
        assert_eq!(field("resyncs"), 2);
        assert_eq!(field("dropped_bytes"), 20);
        assert_eq!((field("dropped_samples"), field("connections")), (0, 0));
    }

    #[test]
    fn z_up_axes_turn_into_the_scenes_y_up() {
        let r = Axes::ZUp.to_scene();
        assert!((r * DVec3::Z - DVec3::Y).length() < 1e-12);
        assert!((r * DVec3::Y + DVec3::Z).length() < 1e-12);
        assert!((r * DVec3::X - DVec3::X).length() < 1e-12);
        assert_eq!(Axes::YUp.to_scene(), DQuat::IDENTITY);
    }
}
