//! End to end: a hand-built `.rec` of SpaceMouse HID reports (wired 7-byte and Pro Wireless
//! 13-byte layouts of shared/reference/devices.md) replayed through
//! `troupe.devices.spacemouse{…}` moves and turns objects by exactly speed × time and
//! turn × time, identically with 1 and 2 scheduler threads; a missing device leaves the
//! scene ticking with its health saying why; live reports are recorded one per chunk and
//! replay to the same states.

use glam::{DQuat, DVec3};
use std::path::Path;
use std::time::{Duration, Instant};
use troupe_drivers::record::Recorder;
use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

fn director(threads: usize) -> LuaSession {
    let kinds = troupe_actions::action_kinds();
    let config = SceneConfig {
        rate: 100.0,
        threads,
        seed: 0,
    };
    let mut d = Director::session(config, kinds, ScriptLimits::default()).unwrap();
    troupe_drivers::lua::install(&mut d, None).unwrap();
    d
}

/// A report: ID then three int16 little-endian values (wired ID 1 translation, ID 2
/// rotation).
fn wired(id: u8, v: [i16; 3]) -> Vec<u8> {
    let mut r = vec![id];
    for x in v {
        r.extend_from_slice(&x.to_le_bytes());
    }
    r
}

/// A Pro Wireless report ID 1: translation then rotation, six int16 little-endian.
fn combined(t: [i16; 3], rot: [i16; 3]) -> Vec<u8> {
    let mut r = vec![1];
    for x in t.into_iter().chain(rot) {
        r.extend_from_slice(&x.to_le_bytes());
    }
    r
}

/// Two SpaceMice: `nav` (wired) pushes right at full scale and twists counter-clockwise
/// (seen from above) for 1 s, then rests, then sends a deflection inside the deadzone;
/// `pro` (13-byte reports) pulls towards the user for 0.5 s.
fn write_recording(path: &Path) {
    let r = Recorder::create(path).unwrap();
    let nav = r.add_stream("nav", "spacemouse", serde_json::json!({}));
    let pro = r.add_stream("pro", "spacemouse", serde_json::json!({}));
    r.data_at(nav, 0, &wired(1, [350, 0, 0]));
    r.data_at(nav, 0, &wired(2, [0, 0, -350]));
    r.data_at(pro, 0, &combined([0, 350, 0], [0, 0, 0]));
    // A button report changes no axis.
    r.data_at(nav, 200_000, &[3, 0x01, 0, 0, 0, 0, 0]);
    r.data_at(pro, 500_000, &combined([0, 0, 0], [0, 0, 0]));
    r.data_at(nav, 1_000_000, &wired(1, [0, 0, 0]));
    r.data_at(nav, 1_000_000, &wired(2, [0, 0, 0]));
    // 10/350 is inside a 5 % deadzone: no creeping.
    r.data_at(nav, 1_200_000, &wired(1, [10, -10, 10]));
    r.finish().unwrap();
}

fn run(threads: usize, rec: &Path) -> Vec<(DVec3, DQuat)> {
    let mut d = director(threads);
    d.load_str(
        &format!(
            r#"
            local crate = troupe.object{{ name = "crate", shape = "box", size = {{0.2, 0.2, 0.2}}, at = {{0, 1, 0}} }}
            troupe.object{{ name = "ball", shape = "sphere", radius = 0.1, at = {{1, 1, 0}} }}
            assert(troupe.devices.spacemouse{{ object = crate, name = "nav", replay = {rec:?},
              stream = "nav", speed = 0.5, turn = 90 }} == "nav")
            troupe.devices.spacemouse{{ object = "ball", name = "pro", replay = {rec:?},
              stream = "pro", speed = 2.0 }}
            troupe.actor{{ name = "ann", at = {{3, 0, 3}} }}
            "#,
            rec = rec.display().to_string()
        ),
        "spacemouse",
    )
    .unwrap();
    for _ in 0..200 {
        d.tick().unwrap();
    }
    let health: String = d
        .eval(r#"return troupe.devices.health("nav").spacemouse.state"#)
        .unwrap();
    assert_eq!(health, "replay");
    let poses = d
        .scene()
        .objects()
        .iter()
        .map(|o| (o.position, o.rotation))
        .collect();
    poses
}

#[test]
fn replayed_reports_move_and_turn_objects_identically_with_one_and_two_threads() {
    let dir = std::env::temp_dir().join(format!("troupe-spacemouse-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rec = dir.join("sm.rec");
    write_recording(&rec);
    let one = run(1, &rec);
    let two = run(2, &rec);
    assert_eq!(one, two, "bit-identical with 1 and 2 threads");
    let (crate_p, crate_q) = one[0];
    // 1 s at full right deflection, 0.5 m/s: 0.5 m along +X; the deadzone report moved
    // nothing afterwards.
    assert!(
        (crate_p - DVec3::new(0.5, 1.0, 0.0)).length() < 1e-9,
        "crate at {crate_p}"
    );
    // 1 s of full twist at 90°/s: a quarter turn about +Y.
    let want = DQuat::from_rotation_y(90f64.to_radians());
    assert!(
        crate_q.angle_between(want) < 1e-9,
        "crate turned {crate_q:?}"
    );
    // 0.5 s towards the user at 2 m/s: 1 m along +Z, no turn.
    let (ball_p, ball_q) = one[1];
    assert!(
        (ball_p - DVec3::new(1.0, 1.0, 1.0)).length() < 1e-9,
        "ball at {ball_p}"
    );
    assert!(ball_q.angle_between(DQuat::IDENTITY) < 1e-12);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_missing_device_keeps_the_scene_ticking_and_health_says_why() {
    let mut d = director(1);
    d.load_str(
        r#"
        troupe.object{ name = "crate", shape = "box", size = {0.2, 0.2, 0.2}, at = {0, 1, 0} }
        troupe.devices.spacemouse{ object = "crate", path = "/dev/hidraw-troupe-absent" }
        "#,
        "missing",
    )
    .unwrap();
    let start = Instant::now();
    let error = loop {
        d.tick().unwrap();
        let (state, error): (String, Option<String>) = d
            .eval(
                r#"local h = troupe.devices.health("spacemouse").spacemouse
                   return h.state, h.error"#,
            )
            .unwrap();
        assert!(
            state == "reconnecting" || state == "failed",
            "state {state}"
        );
        if let Some(e) = error {
            break e;
        }
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no error reported for the missing device"
        );
        std::thread::sleep(Duration::from_millis(5));
    };
    assert!(
        error.contains("/dev/hidraw-troupe-absent") || error.starts_with("HID:"),
        "error: {error}"
    );
    let ticks = d.scene().tick();
    assert!(ticks > 0);
    assert_eq!(d.scene().objects()[0].position, DVec3::new(0.0, 1.0, 0.0));
}

#[test]
fn bad_options_are_clear_errors() {
    let mut d = director(1);
    d.load_str(
        r#"troupe.object{ name = "crate", shape = "box", size = {0.2, 0.2, 0.2}, at = {0, 1, 0} }"#,
        "setup",
    )
    .unwrap();
    for (code, want) in [
        (
            r#"troupe.devices.spacemouse{ object = "nope", replay = "x.rec" }"#,
            "nope",
        ),
        (
            r#"troupe.devices.spacemouse{ object = "crate", sped = 1 }"#,
            "unknown option `sped`",
        ),
        (
            r#"troupe.devices.spacemouse{ object = "crate", deadzone = 1.5, replay = "x.rec" }"#,
            "deadzone",
        ),
        (
            r#"troupe.devices.spacemouse{ object = "crate", replay = "/nonexistent/x.rec" }"#,
            "/nonexistent/x.rec",
        ),
        (
            r#"troupe.devices.spacemouse{ replay = "x.rec" }"#,
            "`object` is required",
        ),
    ] {
        let e = d.load_str(code, "bad").unwrap_err().to_string();
        assert!(e.contains(want), "{code}: {e}");
    }
}

/// A stand-in for a hidraw device: each read returns one queued report, then reads time
/// out like a SpaceMouse at rest.
struct FakeHid(std::collections::VecDeque<Vec<u8>>);

impl std::io::Read for FakeHid {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self.0.pop_front() {
            Some(r) => {
                buf[..r.len()].copy_from_slice(&r);
                Ok(r.len())
            }
            None => {
                std::thread::sleep(Duration::from_millis(2));
                Err(std::io::ErrorKind::TimedOut.into())
            }
        }
    }
}

impl std::io::Write for FakeHid {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn live_reports_are_recorded_one_per_chunk_and_replay_to_the_same_states() {
    use troupe_drivers::device::{self, DeviceError, DriverOptions, Opener, Reading};
    use troupe_drivers::record::Recording;
    use troupe_drivers::spacemouse::SpaceMouseProtocol;
    let dir = std::env::temp_dir().join(format!("troupe-smrec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("live.rec");
    let recorder = std::sync::Arc::new(Recorder::create(&path).unwrap());
    let reports = [
        wired(1, [100, -200, 300]),
        vec![9, 9], // unknown report ID: counted, not fatal
        wired(2, [-1, 2, -3]),
        vec![3, 0x05, 0, 0, 0, 0, 0],
        wired(1, [0, 0, 0]),
    ];
    let mut queue = Some(reports.iter().cloned().collect());
    let opener: Opener = Box::new(move |_o: &DriverOptions| match queue.take() {
        Some(q) => Ok(Box::new(FakeHid(q)) as Box<dyn device::Port>),
        None => Err(DeviceError::Closed),
    });
    let mut o = DriverOptions::new("nav", "");
    o.stale_after = Duration::MAX;
    let dev = device::spawn_with(
        o,
        Box::new(SpaceMouseProtocol::default()),
        Some(recorder.clone()),
        opener,
    );
    let mut live = Vec::new();
    let start = Instant::now();
    while live.len() < 4 {
        live.extend(dev.drain().into_iter().map(|s| s.reading));
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "only {} samples",
            live.len()
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    let health = dev.health.report();
    assert_eq!(health.resyncs, 1, "the unknown report is counted");
    assert_eq!(health.state.name(), "streaming");
    dev.stop();
    recorder.finish().unwrap();
    let rec = Recording::read(&path).unwrap();
    let s = rec.find("spacemouse").unwrap();
    assert_eq!(rec.streams[s].name, "nav");
    assert_eq!(rec.chunks.len(), reports.len(), "one chunk per HID report");
    let replayed: Vec<Reading> = rec.readings(s).unwrap().into_iter().map(|r| r.1).collect();
    assert_eq!(replayed, live);
    let Reading::SpaceMouse(last_moving) = &live[2] else {
        panic!("not a SpaceMouse reading: {:?}", live[2]);
    };
    assert_eq!(last_moving.translation, [100, -200, 300]);
    assert_eq!(last_moving.rotation, [-1, 2, -3]);
    assert_eq!(last_moving.buttons, 0b101);
    std::fs::remove_dir_all(&dir).ok();
}

/// The example's SpaceMouse session (`scripts/examples/spacemouse.rec`), a wired device:
/// push right 0–2 s, twist counter-clockwise 2–3 s, lift 3–4 s, press and release
/// button 1 at 4.5 s and 4.6 s, rest.
fn write_example(path: &Path) {
    let r = Recorder::create(path).unwrap();
    let s = r.add_stream("spacemouse", "spacemouse", serde_json::json!({}));
    let at = |t: f64| (t * 1e6).round() as u64;
    r.data_at(s, at(0.0), &wired(1, [350, 0, 0]));
    r.data_at(s, at(2.0), &wired(1, [0, 0, 0]));
    r.data_at(s, at(2.0), &wired(2, [0, 0, -350]));
    r.data_at(s, at(3.0), &wired(2, [0, 0, 0]));
    r.data_at(s, at(3.0), &wired(1, [0, 0, -350]));
    r.data_at(s, at(4.0), &wired(1, [0, 0, 0]));
    r.data_at(s, at(4.5), &[3, 0x01, 0, 0, 0, 0, 0]);
    r.data_at(s, at(4.6), &[3, 0x00, 0, 0, 0, 0, 0]);
    r.finish().unwrap();
}

#[test]
fn example_spacemouse_recording_is_the_script() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/examples/spacemouse.rec");
    let dir = std::env::temp_dir().join(format!("troupe-smex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fresh = dir.join("spacemouse.rec");
    write_example(&fresh);
    if std::env::var_os("TROUPE_WRITE_EXAMPLES").is_some() {
        std::fs::copy(&fresh, &example).unwrap();
    }
    assert_eq!(
        std::fs::read(&fresh).unwrap(),
        std::fs::read(&example).unwrap(),
        "{} differs from its script (TROUPE_WRITE_EXAMPLES=1 rewrites it)",
        example.display()
    );
    std::fs::remove_dir_all(&dir).ok();
}
