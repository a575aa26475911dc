//! troupe's VRPN client against the real VRPN server (07.38, built from the vendored
//! source): a spinning tracker turns at its configured rate, a NULL tracker holds the
//! identity, buttons toggle, and a killed and restarted server is reconnected to.

#[path = "vrpn/server.rs"]
mod server;

use server::{free_port, Server};
use std::f64::consts::TAU;
use std::time::{Duration, Instant};
use troupe_drivers::device::{DeviceHandle, DriverOptions, HealthState, Reading};
use troupe_drivers::vrpn::{self, DeviceName, VrpnConfig, VrpnReading};

fn client(name: &str, extra: &[&str]) -> DeviceHandle {
    let n = DeviceName::parse(name).unwrap();
    let extra: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    let mut o = DriverOptions::new(name, "");
    o.backoff_max = Duration::from_millis(200);
    vrpn::spawn(
        VrpnConfig::new(&n, &extra),
        o,
        vrpn::HANDSHAKE_TIMEOUT,
        None,
    )
    .unwrap()
}

/// Every VRPN reading the client gets within `d`.
fn collect(h: &DeviceHandle, d: Duration) -> Vec<VrpnReading> {
    let end = Instant::now() + d;
    let mut out = Vec::new();
    while Instant::now() < end {
        if let Ok(s) = h.samples.recv_timeout(Duration::from_millis(20)) {
            if let Reading::Vrpn(r) = s.reading {
                out.push(r);
            }
        }
    }
    out
}

/// (source time, half the rotation angle about +Y) of sensor 0's poses: the quaternion's
/// own angle, continuous modulo a turn as the pose turns.
fn spin_angles(readings: &[VrpnReading]) -> Vec<(f64, f64)> {
    readings
        .iter()
        .filter_map(|r| match r {
            VrpnReading::Tracker {
                sensor: 0,
                quaternion: [x, y, z, w],
                time,
                ..
            } => {
                assert!(x.abs() < 1e-9 && z.abs() < 1e-9, "spin about +Y only");
                Some((*time, y.atan2(*w)))
            }
            _ => None,
        })
        .collect()
}

/// Turns per second: the least-squares slope of the unwrapped half-angle over source time,
/// doubled.
fn turn_rate(samples: &[(f64, f64)]) -> f64 {
    let mut unwrapped = Vec::with_capacity(samples.len());
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    for &(t, a) in samples {
        if let Some(p) = prev {
            let d = a - p;
            if d > TAU / 2.0 {
                offset -= TAU;
            } else if d < -TAU / 2.0 {
                offset += TAU;
            }
        }
        prev = Some(a);
        unwrapped.push((t, a + offset));
    }
    let n = unwrapped.len() as f64;
    let (mt, ma) = unwrapped
        .iter()
        .fold((0.0, 0.0), |(st, sa), (t, a)| (st + t / n, sa + a / n));
    let (num, den) = unwrapped.iter().fold((0.0, 0.0), |(num, den), (t, a)| {
        (num + (t - mt) * (a - ma), den + (t - mt) * (t - mt))
    });
    2.0 * num / den / TAU
}

#[test]
fn a_spinning_tracker_turns_at_its_configured_rate_over_udp_and_over_tcp() {
    let port = free_port();
    let _server = Server::start(
        port,
        "vrpn_Tracker_Spin Spin0 2 100.0 0.0 1.0 0.0 0.25\nvrpn_Button_Example Button0 2 10.0\n",
    );
    for name in [
        format!("Spin0@127.0.0.1:{port}"),
        format!("Spin0@tcp://127.0.0.1:{port}"),
    ] {
        let h = client(&name, &["Button0"]);
        let readings = collect(&h, Duration::from_millis(2500));
        let angles = spin_angles(&readings);
        assert!(
            angles.len() > 150,
            "{name}: {} poses of sensor 0",
            angles.len()
        );
        let rate = turn_rate(&angles);
        assert!(
            (rate - 0.25).abs() / 0.25 < 0.01,
            "{name}: turns at {rate} Hz, configured 0.25 Hz"
        );
        // Both sensors, velocities and accelerations arrive, and the buttons toggle.
        let has = |f: &dyn Fn(&VrpnReading) -> bool| readings.iter().any(f);
        assert!(has(&|r| matches!(
            r,
            VrpnReading::Tracker { sensor: 1, .. }
        )));
        assert!(has(&|r| matches!(r, VrpnReading::Velocity { .. })));
        assert!(has(&|r| matches!(r, VrpnReading::Acceleration { .. })));
        assert!(has(
            &|r| matches!(r, VrpnReading::Button { device, pressed: true, .. } if device == "Button0")
        ));
        assert!(has(&|r| matches!(
            r,
            VrpnReading::Button { pressed: false, .. }
        )));
        let health = h.health.report();
        assert_eq!(health.state, HealthState::Streaming, "{name}: {health:?}");
        assert_eq!((health.resyncs, health.dropped_bytes), (0, 0), "{name}");
    }
}

#[test]
fn a_null_tracker_holds_the_identity() {
    let port = free_port();
    let _server = Server::start(port, "vrpn_Tracker_NULL Null0 2 50.0\n");
    let h = client(&format!("Null0@127.0.0.1:{port}"), &[]);
    let readings = collect(&h, Duration::from_millis(1500));
    let poses: Vec<_> = readings
        .iter()
        .filter_map(|r| match r {
            VrpnReading::Tracker {
                sensor,
                position,
                quaternion,
                ..
            } => Some((*sensor, *position, *quaternion)),
            _ => None,
        })
        .collect();
    assert!(poses.len() > 40, "{} poses", poses.len());
    assert!(poses.iter().any(|p| p.0 == 0) && poses.iter().any(|p| p.0 == 1));
    for (_, position, quaternion) in poses {
        assert_eq!(position, [0.0; 3]);
        assert_eq!(quaternion, [0.0, 0.0, 0.0, 1.0]);
    }
}

#[test]
fn a_quiet_device_stays_connected_through_pings_and_pongs() {
    // Buttons toggling every 10 s: after the states sent on connection, only the pongs
    // to troupe's pings (one a second) keep the connection from looking dead (3 s).
    let port = free_port();
    let _server = Server::start(port, "vrpn_Button_Example Button0 2 0.1\n");
    let h = client(&format!("Button0@127.0.0.1:{port}"), &[]);
    let readings = collect(&h, Duration::from_millis(5000));
    assert!(
        matches!(readings.first(), Some(VrpnReading::Buttons { pressed, .. }) if pressed.len() == 2),
        "{readings:?}"
    );
    let r = h.health.report();
    assert_eq!(r.connections, 1, "{r:?}");
    assert_eq!(r.last_error, None);
}

#[test]
fn a_killed_and_restarted_server_is_reconnected_to() {
    let port = free_port();
    let config = "vrpn_Tracker_NULL Null0 1 100.0\n";
    let server = Server::start(port, config);
    let h = client(&format!("Null0@127.0.0.1:{port}"), &[]);
    let wait_for = |what: &str, f: &dyn Fn() -> bool| {
        let start = Instant::now();
        while !f() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "waiting for {what}: {:?}",
                h.health.report()
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        start.elapsed()
    };
    wait_for("streaming", &|| h.health.state() == HealthState::Streaming);
    server.kill();
    wait_for("the loss noticed", &|| {
        h.health.state() != HealthState::Streaming
    });
    let before = h.health.report().samples;
    let _server = Server::start(port, config);
    let back = wait_for("streaming again", &|| {
        h.health.state() == HealthState::Streaming && h.health.report().samples > before
    });
    let r = h.health.report();
    assert!(r.connections >= 2, "{r:?}");
    eprintln!(
        "streaming again {:.0} ms after the server accepted",
        back.as_secs_f64() * 1e3
    );
}

mod performer {
    use super::server::{free_port, Server};
    use std::sync::Arc;
    use std::time::{Duration, Instant};
    use troupe_drivers::record::Recorder;
    use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
    use troupe_scene::SceneConfig;

    fn director(threads: usize, recorder: Option<Arc<Recorder>>) -> LuaSession {
        let config = SceneConfig {
            rate: 100.0,
            threads,
            seed: 0,
        };
        let mut d = Director::session(
            config,
            troupe_actions::action_kinds(),
            ScriptLimits::default(),
        )
        .unwrap();
        d.scene_mut().set_chunk_size(Some(1));
        troupe_drivers::lua::install(&mut d, recorder).unwrap();
        d
    }

    fn scene(device: &str) -> String {
        format!(
            r#"
            pat = troupe.performer{{ name = "pat", at = {{0, 0, 1}},
              devices = {{ vrpn = {{ {device}, map = {{ pelvis = 0, skullbase = 1 }} }} }} }}
            other = troupe.actor{{ name = "other", at = {{2, 0, 0}} }}
            pat:capture{{}}
            presses = {{}}
            troupe.devices.on_button("Button0.*", function(name, down, who)
              presses[#presses + 1] = string.format("%.2f %s %s %s", troupe.time(), who, name, tostring(down))
            end)
            function state() return troupe.devices.health(pat).vrpn.state end
            function samples() return troupe.devices.health(pat).vrpn.samples end
            "#
        )
    }

    fn eval<T: mlua::FromLua>(d: &mut LuaSession, code: &str) -> T {
        d.script_and_scene().0.lua().load(code).eval().unwrap()
    }

    #[test]
    fn a_performer_rides_out_a_server_restart_while_the_scene_ticks_and_replays_identically() {
        let port = free_port();
        let config =
            "vrpn_Tracker_Spin Spin0 2 100.0 0.0 1.0 0.0 0.5\nvrpn_Button_Example Button0 2 5.0\n";
        let server = Server::start(port, config);
        let dir = std::env::temp_dir().join(format!("troupe-vrpn-perf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rec_path = dir.join("pat.rec");
        let recorder = Arc::new(Recorder::create(&rec_path).unwrap());
        let mut d = director(1, Some(recorder.clone()));
        d.load_str(
            &scene(&format!(
                r#"device = "Spin0@127.0.0.1:{port}", buttons = "Button0""#
            )),
            "live",
        )
        .unwrap();
        let mut slowest_tick = Duration::ZERO;
        let mut tick = |d: &mut LuaSession, n: usize| {
            for _ in 0..n {
                let t = Instant::now();
                d.tick().unwrap();
                slowest_tick = slowest_tick.max(t.elapsed());
                std::thread::sleep(Duration::from_millis(10));
            }
        };
        let until = |d: &mut LuaSession,
                     tick: &mut dyn FnMut(&mut LuaSession, usize),
                     what: &str,
                     f: &dyn Fn(&mut LuaSession) -> bool| {
            let start = Instant::now();
            while !f(d) {
                assert!(
                    start.elapsed() < Duration::from_secs(10),
                    "waiting for {what}"
                );
                tick(d, 1);
            }
        };
        until(&mut d, &mut tick, "streaming", &|d| {
            eval::<String>(d, "return state()") == "streaming"
        });
        let yaw_of = |d: &LuaSession| {
            let sk = &d.scene().actors()[0].skeleton;
            d.scene().states()[0].q[sk.dof("root_yaw").unwrap()]
        };
        let streaming_from = yaw_of(&d);
        tick(&mut d, 50);
        let before_kill = yaw_of(&d);
        // The spin drives the performer while it streams. (Not: the posture at the kill
        // differs from the one held after it: a loaded machine may deliver no sample
        // between the two, and a full run of scripts/test.sh once did not.)
        assert_ne!(streaming_from, before_kill, "the spin drives the performer");
        server.kill();
        let ticks_at_kill = d.scene().tick();
        until(&mut d, &mut tick, "the loss", &|d| {
            eval::<String>(d, "return state()") != "streaming"
        });
        let lost_state: String = eval(&mut d, "return state()");
        // The scene keeps ticking without the server, the posture held.
        tick(&mut d, 30);
        assert!(d.scene().tick() >= ticks_at_kill + 30);
        let held = yaw_of(&d);
        tick(&mut d, 10);
        assert_eq!(held, yaw_of(&d), "no samples, no motion");
        let samples_before: u64 = eval(&mut d, "return samples()");
        let _server = Server::start(port, config);
        until(&mut d, &mut tick, "streaming again", &|d| {
            eval::<String>(d, "return state()") == "streaming"
                && eval::<u64>(d, "return samples()") > samples_before
        });
        // Wait for the motion, not a fixed number of ticks: in two runs of scripts/test.sh
        // on a loaded machine the performer had not yet moved 20 ticks after the samples
        // resumed (it passed alone every time; why the delay, not traced).
        until(
            &mut d,
            &mut tick,
            "the spin to drive the performer again",
            &|d| yaw_of(d) != held,
        );
        assert!(
            ["stale", "reconnecting"].contains(&lost_state.as_str()),
            "{lost_state}"
        );
        assert!(
            slowest_tick < Duration::from_millis(100),
            "a tick took {slowest_tick:?}"
        );
        let presses: Vec<String> = eval(&mut d, "return presses");
        assert!(presses.len() >= 2, "{presses:?}");
        drop(d);
        recorder.finish().unwrap();

        // The recording replays identically, postures and button events, on 1 and 2 threads.
        let replay = format!(r#"replay = {:?}"#, rec_path.display().to_string());
        let run = |threads: usize| {
            let mut d = director(threads, None);
            d.load_str(&scene(&replay), "replay").unwrap();
            let mut postures = Vec::new();
            for _ in 0..300 {
                d.tick().unwrap();
                postures.push(d.scene().states()[0].q.clone());
            }
            let presses: Vec<String> = eval(&mut d, "return presses");
            (postures, presses)
        };
        let (a, pa) = run(1);
        let (b, pb) = run(2);
        assert!(a == b && pa == pb, "replay differs between 1 and 2 threads");
        assert!(a.first() != a.last(), "the replayed performer moves");
        assert!(!pa.is_empty(), "the replay has button events");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
