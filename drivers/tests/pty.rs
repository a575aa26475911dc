//! Drivers against the emulators over real pseudo-terminals: streaming, polling, a silent
//! device, a port that vanishes and comes back, a full channel, record and replay.

use std::time::{Duration, Instant};
use troupe_drivers::cyberglove::{GloveConfig, GloveLayout, GloveProtocol};
use troupe_drivers::device::{self, DeviceHandle, DriverOptions, HealthState, Mode, Reading};
use troupe_drivers::emulator::{self, DeviceKind, EmulatorOptions};
use troupe_drivers::fob::{FobConfig, FobProtocol, OutputFormat};
use troupe_drivers::record::{Recorder, Recording};

/// Waits (up to 10 s, generous for a loaded machine) until `f` holds.
fn wait_for(what: &str, mut f: impl FnMut() -> bool) {
    let start = Instant::now();
    while !f() {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn fob_driver(path: &str, birds: u8, format: OutputFormat) -> DeviceHandle {
    let mut o = DriverOptions::new("fob", path);
    o.backoff_max = Duration::from_millis(100);
    device::spawn(
        o,
        Box::new(FobProtocol::new(FobConfig::new(birds, format))),
        None,
    )
}

#[test]
fn flock_streams_in_group_mode_through_a_pty() {
    let emu = emulator::start(
        DeviceKind::Fob,
        EmulatorOptions {
            birds: 3,
            ..EmulatorOptions::new()
        },
        None,
    )
    .unwrap();
    let dev = fob_driver(&emu.path(), 3, OutputFormat::PositionQuaternion);
    let mut got = Vec::new();
    wait_for("30 bird records", || {
        got.extend(dev.drain());
        got.len() >= 30
    });
    assert_eq!(dev.health.state(), HealthState::Streaming);
    let addrs: std::collections::BTreeSet<u8> = got
        .iter()
        .map(|s| match &s.reading {
            Reading::Bird(b) => {
                let q = b.quaternion.expect("quaternion format");
                let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!((norm - 1.0).abs() < 1e-3, "unit quaternion, got {q:?}");
                assert!(b.position.is_some() && b.angles.is_none());
                b.address
            }
            other => panic!("unexpected {other:?}"),
        })
        .collect();
    assert_eq!(addrs.into_iter().collect::<Vec<_>>(), vec![1, 2, 3]);
    // Sequence numbers are consecutive: nothing was lost on the way.
    assert!(got.windows(2).all(|w| w[1].seq == w[0].seq + 1));
}

#[test]
fn glove_polls_and_streams_through_a_pty() {
    for (mode, status_byte) in [(Mode::Point, false), (Mode::Stream, true)] {
        let emu = emulator::start(
            DeviceKind::CyberGlove,
            EmulatorOptions {
                sensors: 22,
                ..EmulatorOptions::new()
            },
            None,
        )
        .unwrap();
        let config = GloveConfig {
            layout: GloveLayout {
                sensors: 22,
                status_byte,
            },
            mode,
        };
        let dev = device::spawn(
            DriverOptions::new("glove", &emu.path()),
            Box::new(GloveProtocol::new(config)),
            None,
        );
        let mut got = Vec::new();
        wait_for("10 glove records", || {
            got.extend(dev.drain());
            got.len() >= 10
        });
        for s in &got {
            let Reading::Glove(g) = &s.reading else {
                panic!("not a glove record")
            };
            assert_eq!(g.raw.len(), 22);
            assert_eq!(g.command, if mode == Mode::Point { b'G' } else { b'S' });
            assert_eq!(g.status, status_byte.then_some(0x03));
        }
        assert_eq!(dev.health.report().resyncs, 0);
    }
}

#[test]
fn a_glove_with_the_wrong_sensor_count_fails_with_a_clear_error() {
    let emu = emulator::start(DeviceKind::CyberGlove, EmulatorOptions::new(), None).unwrap();
    let config = GloveConfig {
        layout: GloveLayout {
            sensors: 22,
            status_byte: false,
        },
        mode: Mode::Stream,
    };
    let mut o = DriverOptions::new("glove", &emu.path());
    o.max_attempts = Some(2);
    o.backoff_initial = Duration::from_millis(5);
    let dev = device::spawn(o, Box::new(GloveProtocol::new(config)), None);
    wait_for("failed state", || dev.health.state() == HealthState::Failed);
    let err = dev.health.report().last_error.unwrap();
    assert!(
        err.contains("samples 18 sensors, configured for 22"),
        "{err}"
    );
}

#[test]
fn a_silent_device_goes_stale_and_a_missing_port_reconnects() {
    // A pty nobody answers on: the single-bird configuration needs no reply, so the driver
    // connects and then hears nothing.
    let silent = emulator::Pty::open().unwrap();
    let dev = fob_driver(silent.path(), 1, OutputFormat::PositionAngles);
    wait_for("stale", || dev.health.state() == HealthState::Stale);
    drop(dev);

    // A port that does not exist yet: reconnecting, then streaming once it appears.
    let link = std::env::temp_dir().join(format!("troupe-fob-link-{}", std::process::id()));
    let _ = std::fs::remove_file(&link);
    let dev = fob_driver(link.to_str().unwrap(), 1, OutputFormat::PositionAngles);
    wait_for("reconnecting", || {
        dev.health.state() == HealthState::Reconnecting
    });
    let emu = emulator::start(DeviceKind::Fob, EmulatorOptions::new(), Some(&link)).unwrap();
    wait_for("streaming", || {
        dev.drain();
        dev.health.state() == HealthState::Streaming
    });
    // Unplug: the pty closes; the driver notices and retries.
    emu.stop();
    wait_for("reconnecting after unplug", || {
        dev.health.state() == HealthState::Reconnecting
    });
    let before = dev.health.report().samples;
    // Plug back in (a new pty behind the same link).
    let _emu = emulator::start(DeviceKind::Fob, EmulatorOptions::new(), Some(&link)).unwrap();
    wait_for("streaming again", || {
        dev.drain();
        dev.health.state() == HealthState::Streaming && dev.health.report().samples > before
    });
    assert_eq!(dev.health.report().connections, 2);
}

#[test]
fn a_full_channel_drops_and_counts_instead_of_blocking() {
    let emu = emulator::start(DeviceKind::Fob, EmulatorOptions::new(), None).unwrap();
    let mut o = DriverOptions::new("fob", &emu.path());
    o.capacity = 4;
    let dev = device::spawn(
        o,
        Box::new(FobProtocol::new(FobConfig::new(1, OutputFormat::Position))),
        None,
    );
    wait_for("dropped samples", || {
        dev.health.report().dropped_samples > 0
    });
    assert_eq!(dev.drain().len(), 4);
}

#[test]
fn recorded_streams_replay_identically() {
    let dir = std::env::temp_dir().join(format!("troupe-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("session.rec");
    let rec = std::sync::Arc::new(Recorder::create(&file).unwrap());
    let emu = emulator::start(
        DeviceKind::Fob,
        EmulatorOptions {
            birds: 2,
            ..EmulatorOptions::new()
        },
        None,
    )
    .unwrap();
    let dev = device::spawn(
        DriverOptions::new("flock", &emu.path()),
        Box::new(FobProtocol::new(FobConfig::new(
            2,
            OutputFormat::PositionMatrix,
        ))),
        Some(rec.clone()),
    );
    let mut live = Vec::new();
    wait_for("20 samples", || {
        live.extend(dev.drain());
        live.len() >= 20
    });
    dev.stop();
    rec.finish().unwrap();
    let r = Recording::read(&file).unwrap();
    assert_eq!(r.streams.len(), 1);
    assert_eq!(r.streams[0].kind, "fob");
    let a = r.readings(0).unwrap();
    let b = Recording::read(&file).unwrap().readings(0).unwrap();
    assert_eq!(a, b);
    // The replay decodes what the live driver decoded, in the same order.
    let live: Vec<Reading> = live.into_iter().map(|s| s.reading).collect();
    assert!(a.len() >= live.len());
    assert_eq!(
        a.iter()
            .take(live.len())
            .map(|x| x.1.clone())
            .collect::<Vec<_>>(),
        live
    );
    // The recording can itself drive an emulator.
    let motion = emulator::Motion::from_file(&file, "fob", &[], 2, 1.0).unwrap();
    assert!(matches!(motion, emulator::Motion::Recorded { .. }));
    // At the recording's start it serves the first recorded pose of each bird.
    for bird in 1..=2u8 {
        // The latest record of that bird among those that arrived in the first chunk.
        let of_bird: Vec<(f64, &troupe_drivers::fob::BirdRecord)> = a
            .iter()
            .filter_map(|(t, r)| match r {
                Reading::Bird(b) if b.address == bird => Some((*t, b)),
                _ => None,
            })
            .collect();
        let t0 = of_bird[0].0;
        let first =
            troupe_drivers::fob::bird_pose(of_bird.iter().rev().find(|(t, _)| *t == t0).unwrap().1);
        let (p, q) = motion.bird(0.0, usize::from(bird - 1));
        assert!(
            (p - first.0).length() < 1e-12 && (q - first.1).length() < 1e-12,
            "bird {bird}: {p} {q} vs {first:?} ({} records at t0)",
            of_bird.iter().filter(|(t, _)| *t == t0).count()
        );
    }
    // A damaged file is an error naming the file.
    let bad = dir.join("bad.rec");
    std::fs::write(&bad, b"TROUPEREC1\nZ").unwrap();
    let err = Recording::read(&bad).unwrap_err().to_string();
    assert!(
        err.contains("bad.rec") && err.contains("unknown chunk tag"),
        "{err}"
    );
}

#[test]
fn emulator_answers_point_requests_with_the_motion_encoded_exactly() {
    let mut e = troupe_drivers::fob::FobEmulator::new(EmulatorOptions {
        birds: 2,
        ..EmulatorOptions::new()
    });
    // Group mode, quaternion format, then a POINT request.
    let mut cmds = vec![b'P', 0x32, 2, b'O', 0x24];
    let status = e.handle(&cmds, 0.0);
    assert_eq!(status, vec![0xE0, 0xE0]);
    cmds = vec![0xF1, b']', 0xF2, b']', b'P', 0x23, 1, b'B'];
    let reply = e.handle(&cmds, 1.25);
    assert_eq!(reply.len(), 2 * 15);
    let mut layout = troupe_drivers::fob::RecordLayout::single(OutputFormat::PositionQuaternion);
    layout.group = true;
    let recs = troupe_drivers::fob::RecordDecoder::new(layout, 1).feed_collect(&reply);
    for (i, r) in recs.iter().enumerate() {
        let (p, q) = emulator::Motion::Synthetic.bird(1.25, i);
        let (dp, dq) = troupe_drivers::fob::bird_pose(r);
        assert!((dp - p).length() < 2e-4, "bird {i}: {dp} vs {p}");
        assert!(dq.angle_between(q) < 1e-3, "bird {i}");
        assert_eq!(usize::from(r.address), i + 1);
    }
}

#[test]
fn flock_point_mode_answers_each_request() {
    let emu = emulator::start(DeviceKind::Fob, EmulatorOptions::new(), None).unwrap();
    let mut c = FobConfig::new(1, OutputFormat::Angles);
    c.mode = Mode::Point;
    let dev = device::spawn(
        DriverOptions::new("fob", &emu.path()),
        Box::new(FobProtocol::new(c)),
        None,
    );
    let mut got = Vec::new();
    wait_for("5 polled records", || {
        got.extend(dev.drain());
        got.len() >= 5
    });
    for s in &got {
        let Reading::Bird(b) = &s.reading else {
            panic!("not a bird")
        };
        assert!(b.angles.is_some() && b.position.is_none());
    }
    assert_eq!(dev.health.report().resyncs, 0);
}

#[test]
fn a_bvh_drives_the_flock_emulator() {
    let bvh = "HIERARCHY
ROOT hips
{
  OFFSET 0 100 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT head
  {
    OFFSET 0 50 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
0 100 0 0 0 0 0 0 0
10 100 0 0 0 90 0 0 0
";
    let dir = std::env::temp_dir().join(format!("troupe-bvh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("walk.bvh");
    std::fs::write(&path, bvh).unwrap();
    let m = emulator::Motion::from_file(
        &path,
        "fob",
        &["head".to_string(), "hips".to_string()],
        2,
        0.01,
    )
    .unwrap();
    // Frame 0 (t = 0.2 s): head at (0, 150, 0) cm; frame 1 (t = 0.7 s): hips moved 10 cm, turned 90° about Y.
    let (p, q) = m.bird(0.2, 0);
    assert!(
        (p - troupe_body::glam::DVec3::new(0.0, 1.5, 0.0)).length() < 1e-9,
        "{p}"
    );
    assert!(q.angle_between(troupe_body::glam::DQuat::IDENTITY) < 1e-9);
    let (p, q) = m.bird(0.7, 1);
    assert!(
        (p - troupe_body::glam::DVec3::new(0.1, 1.0, 0.0)).length() < 1e-9,
        "{p}"
    );
    assert!(
        (q.angle_between(troupe_body::glam::DQuat::IDENTITY) - std::f64::consts::FRAC_PI_2).abs()
            < 1e-9
    );
    // Errors name the joint and the file.
    let e = emulator::Motion::from_file(&path, "fob", &["tail".to_string()], 1, 0.01)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("no joint 'tail'") && e.contains("walk.bvh"),
        "{e}"
    );
    let e = emulator::Motion::from_file(&path, "fob", &[], 3, 0.01)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("2 joints for 3 birds"), "{e}");
}
