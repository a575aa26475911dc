//! End to end: emulator → pty → driver → performer actor, and replay of the recorded
//! streams giving identical postures on two runs (and with 1 or 2 scheduler threads).

use std::sync::Arc;
use std::time::{Duration, Instant};
use troupe_drivers::emulator::{self, DeviceKind, EmulatorOptions};
use troupe_drivers::performer::{median_p99, SharedPerformers};
use troupe_drivers::record::Recorder;
use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

fn director(threads: usize, recorder: Option<Arc<Recorder>>) -> (LuaSession, SharedPerformers) {
    let kinds = troupe_actions::action_kinds();
    let config = SceneConfig {
        rate: 100.0,
        threads,
        seed: 0,
    };
    let mut d = Director::session(config, kinds, ScriptLimits::default()).unwrap();
    // One actor per chunk: with two threads, even two actors are stepped on both.
    d.scene_mut().set_chunk_size(Some(1));
    let shared = troupe_drivers::lua::install(&mut d, recorder)
        .unwrap()
        .performers;
    (d, shared)
}

fn scene(fob: &str, glove: &str) -> String {
    format!(
        r#"
        pat = troupe.performer{{ name = "pat", at = {{0, 0, 1}},
          devices = {{ fob = {{ {fob}, birds = 3, map = {{ pelvis = 1, skullbase = 2, r_wrist = 3 }} }},
                       glove = {{ {glove}, hand = "right" }} }} }}
        cap = pat:capture{{}}
        "#
    )
}

#[test]
fn performer_follows_the_emulated_motion_within_one_tick_and_replays_identically() {
    let fob = emulator::start(
        DeviceKind::Fob,
        EmulatorOptions {
            birds: 3,
            ..EmulatorOptions::new()
        },
        None,
    )
    .unwrap();
    let glove = emulator::start(DeviceKind::CyberGlove, EmulatorOptions::new(), None).unwrap();
    let dir = std::env::temp_dir().join(format!("troupe-perf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rec_path = dir.join("pat.rec");
    let recorder = Arc::new(Recorder::create(&rec_path).unwrap());
    let (mut d, shared) = director(1, Some(recorder.clone()));
    d.load_str(
        &scene(
            &format!("port = {:?}", fob.path()),
            &format!("port = {:?}", glove.path()),
        ),
        "live",
    )
    .unwrap();
    let actor = d.scene().actor_index("pat").unwrap();
    let sk = d.scene().actors()[actor].skeleton.clone();
    let root_x = sk.dof("root_x").unwrap();
    let index = sk.dof("r_index1_flexion").unwrap();
    let mut checked = 0;
    let mut moved = false;
    let mut first_root: Option<f64> = None;
    let start = Instant::now();
    while checked < 50 {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "performer never followed the devices"
        );
        d.tick().unwrap();
        let mut perf = shared.0.lock().unwrap();
        perf.end_tick();
        let made_now = perf.made(0).unwrap();
        let ticks = d.scene().tick();
        let target = d.scene().input_pose(actor).unwrap().clone();
        drop(perf);
        // A target made at this tick's start is in this tick's posture: ≤ 1 tick latency.
        if made_now == ticks && target.mask[root_x] && target.mask[index] {
            let q = d.scene().states()[actor].q.clone();
            for (dof, (&want, &set)) in target.q.iter().zip(&target.mask).enumerate() {
                if set {
                    let want = sk.dofs()[dof].clamp(want);
                    assert!(
                        (q[dof] - want).abs() < 1e-9,
                        "dof {} = {} but the sample says {}",
                        sk.dofs()[dof].name,
                        q[dof],
                        want
                    );
                }
            }
            let r0 = *first_root.get_or_insert(q[root_x]);
            moved |= (q[root_x] - r0).abs() > 1e-3;
            checked += 1;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(moved, "the root followed the pelvis bird's motion");
    let lat = shared.0.lock().unwrap().latencies.clone();
    assert!(median_p99(&lat).is_some());
    drop(d);
    recorder.finish().unwrap();
    drop(fob);
    drop(glove);

    // Replay twice (and with two threads): bit-identical postures.
    let replay = format!("replay = {:?}", rec_path.display().to_string());
    let run = |threads: usize| {
        let (mut d, _s) = director(threads, None);
        d.load_str(&scene(&replay, &replay), "replay").unwrap();
        let mut postures = Vec::new();
        for _ in 0..150 {
            d.tick().unwrap();
            postures.push(d.scene().states()[0].q.clone());
        }
        postures
    };
    let a = run(1);
    let b = run(1);
    let c = run(2);
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert!(a.first() != a.last(), "the replayed performer moves");
}

#[test]
fn bad_performer_options_are_clear_errors() {
    let (mut d, _) = director(1, None);
    for (code, expect) in [
        (
            r#"troupe.performer{ name = "a", devices = { fob = { port = "/x", birds = 2, map = { nose = 1 } } } }"#,
            "no joint 'nose'",
        ),
        (
            r#"troupe.performer{ name = "b", devices = { fob = { port = "/x", birds = 2, map = { pelvis = 3 } } } }"#,
            "not a bird address",
        ),
        (
            r#"troupe.performer{ name = "c", devices = { glove = { hand = "middle", port = "/x" } } }"#,
            "hand must be",
        ),
        (
            r#"troupe.performer{ name = "d", devices = { glove = { replay = "nope.rec" } } }"#,
            "nope.rec",
        ),
        (
            r#"troupe.performer{ name = "e", devices = { fob = { map = { pelvis = 1 } } } }"#,
            "`port`",
        ),
        (
            r#"troupe.performer{ name = "f", colour = "red" }"#,
            "unknown option `colour`",
        ),
        (
            // Not an address of this machine: the listener cannot bind it.
            r#"troupe.performer{ name = "a", devices = { osc = { listen = "203.0.113.1:9", joints = { "pelvis" } } } }"#,
            "binding 203.0.113.1:9",
        ),
    ] {
        let e = d.load_str(code, "bad").unwrap_err().to_string();
        assert!(e.contains(expect), "{code}: {e}");
    }
    // A refused performer leaves no actor behind: its name is free for the next one.
    assert_eq!(d.scene().actors().len(), 0);
    d.load_str(
        r#"troupe.performer{ name = "a", devices = { osc = { listen = "127.0.0.1:0", joints = { "pelvis" } } } }"#,
        "good",
    )
    .unwrap();
    assert_eq!(d.scene().actors().len(), 1);
    let e = d
        .load_str(r#"troupe.performer{ name = "a" }"#, "again")
        .unwrap_err()
        .to_string();
    assert!(e.contains("actor") && e.contains("`a`"), "{e}");
}

#[test]
fn osc_poses_and_glove_values_drive_a_performer() {
    use rosc::{OscMessage, OscPacket, OscType};
    use troupe_body::glam::{DQuat, DVec3};
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let (mut d, _shared) = director(1, None);
    d.load_str(
        &format!(
            r#"oz = troupe.performer{{ name = "oz", devices = {{
                 osc = {{ listen = "127.0.0.1:{port}", joints = {{ "pelvis", "r_wrist" }} }},
                 glove = {{ osc = true, hand = "right" }} }} }}
               oz:capture{{}}"#
        ),
        "osc",
    )
    .unwrap();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let pose = |joint: &str, p: DVec3, q: DQuat| {
        let args = [p.x, p.y, p.z, q.w, q.x, q.y, q.z]
            .iter()
            .map(|v| OscType::Float(*v as f32))
            .collect();
        rosc::encoder::encode(&OscPacket::Message(OscMessage {
            addr: format!("/troupe/oz/{joint}"),
            args,
        }))
        .unwrap()
    };
    let pelvis = DVec3::new(0.25, 1.0, 0.5);
    let yaw = DQuat::from_rotation_y(0.4);
    let glove: Vec<OscType> = (0..18).map(|_| OscType::Int(255)).collect();
    let glove = rosc::encoder::encode(&OscPacket::Message(OscMessage {
        addr: "/troupe/oz/glove".into(),
        args: glove,
    }))
    .unwrap();
    let sk = d.scene().actors()[0].skeleton.clone();
    let index = sk.dof("r_index1_flexion").unwrap();
    let start = Instant::now();
    loop {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "OSC input never reached the performer"
        );
        sock.send_to(&pose("pelvis", pelvis, yaw), ("127.0.0.1", port))
            .unwrap();
        sock.send_to(&glove, ("127.0.0.1", port)).unwrap();
        std::thread::sleep(Duration::from_millis(5));
        d.tick().unwrap();
        let st = d.scene().states()[0].clone();
        if st.q[index] > 0.0 && (st.globals[0].translation - pelvis).length() < 1e-6 {
            assert!(st.globals[0].rotation.angle_between(yaw) < 1e-6);
            assert_eq!(
                st.q[index],
                sk.dofs()[index].max,
                "raw 255 = the DOF's upper limit"
            );
            let perf = _shared.0.lock().unwrap();
            assert_eq!(perf.glove_raw("oz"), Some(vec![255; 18]));
            let hand = perf.hand_target("oz", d.scene()).unwrap();
            assert!(hand.contains(&(index, sk.dofs()[index].max)));
            assert!(hand
                .iter()
                .all(|&(d, _)| sk.dofs()[d].name.starts_with("r_")));
            break;
        }
    }
    // Inputs the performer cannot use are counted, never applied: glove values of a
    // 22-sensor glove for this 18-sensor one, a joint it does not listen for.
    let health = |d: &mut LuaSession| -> mlua::Table {
        d.eval("return troupe.devices.health('oz').osc").unwrap()
    };
    let before: u64 = health(&mut d).get("resyncs").unwrap();
    let wide = rosc::encoder::encode(&OscPacket::Message(OscMessage {
        addr: "/troupe/oz/glove".into(),
        args: (0..22).map(|_| OscType::Int(1)).collect(),
    }))
    .unwrap();
    sock.send_to(&wide, ("127.0.0.1", port)).unwrap();
    sock.send_to(&pose("l_wrist", pelvis, yaw), ("127.0.0.1", port))
        .unwrap();
    let start = Instant::now();
    while health(&mut d).get::<u64>("resyncs").unwrap() < before + 2 {
        assert!(start.elapsed() < Duration::from_secs(10), "not counted");
        std::thread::sleep(Duration::from_millis(5));
        d.tick().unwrap();
    }
    assert_eq!(health(&mut d).get::<u64>("resyncs").unwrap(), before + 2);
    let error: String = health(&mut d).get("error").unwrap();
    assert!(
        error.contains("'l_wrist' is not one of the performer's OSC joints (pelvis, r_wrist)"),
        "{error}"
    );
    assert_eq!(
        _shared.0.lock().unwrap().glove_raw("oz"),
        Some(vec![255; 18])
    );
}

#[test]
fn health_is_visible_from_lua_and_a_missing_port_keeps_the_scene_ticking() {
    let (mut d, _s) = director(1, None);
    d.load_str(
        r#"ghost = troupe.performer{ name = "ghost",
             devices = { fob = { port = "/dev/troupe-no-such-port", map = { pelvis = 1 } } } }
           ghost:capture{}"#,
        "ghost",
    )
    .unwrap();
    let start = Instant::now();
    loop {
        d.tick().unwrap();
        let h: mlua::Table = d
            .eval(r#"return troupe.devices.health("ghost").fob"#)
            .unwrap();
        let state: String = h.get("state").unwrap();
        // The thread starts out reconnecting; after its first attempt the error says why.
        let error: Option<String> = h.get("error").unwrap();
        if let (true, Some(e)) = (state == "reconnecting", error) {
            assert!(e.contains("/dev/troupe-no-such-port"), "{e}");
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "state stayed {state}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    // The scene kept ticking all along.
    assert!(d.scene().tick() > 0);
}

/// Writes a glove recording: each (value, count) posture held for `count` records at 100 Hz.
fn glove_rec(path: &std::path::Path, postures: &[(u8, usize)]) {
    let r = Recorder::create(path).unwrap();
    let config = troupe_drivers::cyberglove::GloveConfig {
        layout: troupe_drivers::cyberglove::GloveLayout {
            sensors: 18,
            status_byte: false,
        },
        mode: troupe_drivers::device::Mode::Stream,
    };
    let s = r.add_stream("g", "cyberglove", serde_json::to_value(&config).unwrap());
    let mut k = 0u64;
    for &(value, count) in postures {
        for _ in 0..count {
            let mut rec = vec![b'S'];
            // The fingers take the posture's value; the thumb stays.
            rec.extend((0..18).map(|i| if i < 4 { 60 } else { value }));
            rec.push(0);
            r.data_at(s, k * 10_000, &rec);
            k += 1;
        }
    }
    r.finish().unwrap();
}

#[test]
fn gestures_trained_from_recordings_fire_lua_events_on_change() {
    let dir = std::env::temp_dir().join(format!("troupe-gest-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, v) in [
        ("neutral", 60u8),
        ("fist", 230),
        ("half", 150),
        ("flat", 5),
        ("claw", 100),
    ] {
        glove_rec(&dir.join(format!("{name}.rec")), &[(v, 10)]);
    }
    // The session: neutral, fist, neutral again, each held 20 samples.
    glove_rec(&dir.join("session.rec"), &[(60, 20), (230, 20), (60, 20)]);
    let (mut d, _s) = director(1, None);
    let code = format!(
        r#"troupe.fired = {{}}
           g = troupe.performer{{ name = "g", devices = {{ glove = {{ replay = "{0}/session.rec" }} }} }}
           troupe.devices.train_gestures(g, {{ neutral = "{0}/neutral.rec", fist = "{0}/fist.rec",
              half = "{0}/half.rec", flat = "{0}/flat.rec", claw = "{0}/claw.rec" }})
           troupe.devices.on_gesture(g, function(who, gesture, previous)
             troupe.fired[#troupe.fired + 1] = who .. ":" .. gesture .. "<" .. tostring(previous)
           end)"#,
        dir.display()
    );
    d.load_str(&code, "gestures").unwrap();
    for _ in 0..80 {
        d.tick().unwrap();
    }
    let fired: Vec<String> = d.eval("return troupe.fired").unwrap();
    assert_eq!(
        fired,
        vec!["g:neutral<nil", "g:fist<neutral", "g:neutral<fist"]
    );
    let e = d
        .load_str(
            &format!(
                r#"troupe.devices.train_gestures(g, {{ x = "{}/missing.rec" }})"#,
                dir.display()
            ),
            "bad",
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.rec"), "{e}");
}

#[test]
fn device_functions_and_vrpn_options_name_what_is_wrong() {
    let (mut d, _s) = director(1, None);
    d.load_str(r#"ann = troupe.actor{ name = "ann" }"#, "ann")
        .unwrap();
    let error = |d: &mut LuaSession, code: &str| -> String {
        let (ok, e): (bool, String) = d
            .eval(&format!(
                "local ok, e = pcall(function() {code} end) return ok, tostring(e)"
            ))
            .unwrap();
        assert!(!ok, "{code} did not fail");
        e
    };
    let cases = [
        (
            r#"troupe.devices.health("nobody")"#,
            "troupe.devices.health: no performer named 'nobody'",
        ),
        (
            "troupe.devices.calibrate(ann)",
            "troupe.devices.calibrate: actor 'ann' is not a performer",
        ),
        (
            "troupe.devices.glove(3)",
            "troupe.devices.glove: expected a performer (its actor or its name), got integer",
        ),
        (
            r#"troupe.performer{ name = "v1", devices = { vrpn = { replay = "x.rec", map = { pelvis = 1.5 } } } }"#,
            "map.pelvis = 1.5 is not a sensor 0…254 (a whole number)",
        ),
        (
            r#"troupe.performer{ name = "v2", devices = { vrpn = { device = "T@127.0.0.1:1", map = { pelvis = 0 }, timeout = 0 } } }"#,
            "timeout must be more than 0 and at most 60 s, got 0",
        ),
    ];
    for (code, want) in cases {
        let e = error(&mut d, code);
        assert!(e.contains(want), "{code}: {e}");
    }
    // A float with a whole value is still a sensor: the missing file is the error.
    let e = error(
        &mut d,
        r#"troupe.performer{ name = "v3", devices = { vrpn = { replay = "x.rec", map = { pelvis = 1.0 } } } }"#,
    );
    assert!(e.contains("x.rec") && !e.contains("not a sensor"), "{e}");
}
