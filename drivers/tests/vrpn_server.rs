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
