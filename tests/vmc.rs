//! VMC end to end: troupe sends an actor to a second troupe over UDP and the performer
//! there stands where the actor stood; bad input and bursts are counted, never fatal; the
//! health goes stale and comes back; a live stream recorded with `--record-devices`
//! replays identically on 1 and 2 threads, and `--replay-devices` gives the live run's
//! postures byte for byte; and python-osc, an OSC implementation troupe
//! does not use, reads troupe's stream and drives a troupe performer
//! (`scripts/vmc/compat.py`).

use rosc::{OscBundle, OscMessage, OscPacket, OscType};
use std::ffi::OsStr;
use std::net::UdpSocket;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use troupe_drivers::vmc::VRM_BONES;
use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-vmc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn session(code: &str) -> (LuaSession, troupe_drivers::lua::Devices) {
    let mut s = Director::session(
        SceneConfig::default(),
        troupe_actions::action_kinds(),
        ScriptLimits::default(),
    )
    .unwrap();
    let devices = troupe_drivers::lua::install(&mut s, None).unwrap();
    s.load_str(code, "test").unwrap();
    s.start().unwrap();
    (s, devices)
}

fn receiver(port: u16, latency: f64) -> (LuaSession, troupe_drivers::lua::Devices) {
    session(&format!(
        r#"local pat = troupe.performer{{ name = "pat",
             devices = {{ vmc = {{ listen = "127.0.0.1:{port}", latency = {latency} }} }} }}
           pat:capture{{}}"#
    ))
}

/// Datagrams the performer's listener has received.
fn received(d: &troupe_drivers::lua::Devices) -> u64 {
    let p = d.performers.0.lock().unwrap();
    p.health()
        .iter()
        .find(|(_, dev, _)| *dev == "vmc")
        .map(|(_, _, h)| h.samples)
        .unwrap_or(0)
}

fn wait_for(d: &troupe_drivers::lua::Devices, count: u64) {
    let start = Instant::now();
    while received(d) < count && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(
        received(d) >= count,
        "the listener got {} of {count} datagrams",
        received(d)
    );
}

fn health(s: &mut LuaSession, field: &str) -> String {
    s.eval::<String>(&format!(
        "return tostring(troupe.devices.health('pat').vmc.{field})"
    ))
    .unwrap()
}

#[test]
fn a_round_trip_puts_every_mapped_joint_within_a_centimetre() {
    let port = free_port();
    let (mut rx, devices) = receiver(port, 0.0);
    // Ann walks off at an angle, swinging her arms, and reaches up on the way.
    let (mut tx, _) = session(&format!(
        r#"local ann = troupe.actor{{ name = "ann", at = {{0.3, 0, -0.2}}, facing = 40 }}
           troupe.vmc_out{{ actor = ann, to = "127.0.0.1:{port}", rate = 100 }}
           ann:walk{{ to = {{1.5, 0, 1.5}} }}
           ann:behave(function(self)
             wait(0.6)
             self:reach{{ hand = "left", target = {{0.9, 1.5, 0.9}}, duration = 0.8, mode = "weighted", weight = 1 }}
           end)"#
    ));
    let sk = tx.scene().actors()[0].skeleton.clone();
    let joints: Vec<usize> = VRM_BONES
        .iter()
        .map(|b| sk.joint(b.joint).unwrap())
        .collect();
    let mut worst = (0.0f64, 0, "");
    for tick in 1..=200 {
        tx.tick().unwrap();
        wait_for(&devices, tick);
        rx.tick().unwrap();
        if tick < 3 {
            continue; // the capture starts on the first tick with a pose
        }
        let (a, b) = (
            &tx.scene().states()[0].globals,
            &rx.scene().states()[0].globals,
        );
        for (bone, &j) in VRM_BONES.iter().zip(&joints) {
            let e = (a[j].translation - b[j].translation).length();
            if e > worst.0 {
                worst = (e, tick, bone.name);
            }
        }
    }
    let moved = tx.scene().states()[0].globals[0].translation;
    assert!(moved.z > 0.8, "ann walked ({moved})");
    assert!(
        worst.0 < 0.01,
        "{} off by {:.4} m at tick {}",
        worst.2,
        worst.0,
        worst.1
    );
    println!(
        "round trip: worst joint {:.3} mm ({} at tick {})",
        worst.0 * 1e3,
        worst.2,
        worst.1
    );
}

fn bone(name: &str, v: [f32; 7]) -> OscPacket {
    let mut args = vec![OscType::String(name.into())];
    args.extend(v.iter().map(|x| OscType::Float(*x)));
    OscPacket::Message(OscMessage {
        addr: "/VMC/Ext/Bone/Pos".into(),
        args,
    })
}

fn bundle(content: Vec<OscPacket>) -> Vec<u8> {
    rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
        timetag: (0, 1).into(),
        content,
    }))
    .unwrap()
}

#[test]
fn bad_input_and_bursts_are_counted_and_skipped() {
    let port = free_port();
    let (mut rx, devices) = receiver(port, 0.0);
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = ("127.0.0.1", port);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    // The forearm turned forward (Unity −Y), as a valid message among bad ones.
    let good = bone("RightLowerArm", [0.0, 0.0, 0.0, 0.0, -h, 0.0, h]);
    let valid = bundle(vec![good.clone()]);
    let bad: Vec<Vec<u8>> = vec![
        b"garbage that is no OSC".to_vec(),
        valid[..valid.len() / 2].to_vec(),
        bundle(vec![bone("Neck", [0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 1.0])]),
        bundle(vec![bone("Neck", [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0])]),
        bundle(vec![bone("Tail", [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])]),
        bundle(vec![OscPacket::Message(OscMessage {
            addr: "/VMC/Ext/Bone/Pos".into(),
            args: vec![OscType::Int(1), OscType::String("x".into())],
        })]),
        bundle(vec![OscPacket::Message(OscMessage {
            addr: "/other/thing".into(),
            args: vec![],
        })]),
    ];
    for b in &bad {
        s.send_to(b, to).unwrap();
    }
    s.send_to(&valid, to).unwrap();
    wait_for(&devices, bad.len() as u64 + 1);
    rx.tick().unwrap();
    rx.tick().unwrap();
    assert!(health(&mut rx, "malformed").parse::<u64>().unwrap() >= 1);
    assert_eq!(health(&mut rx, "invalid"), "3");
    assert_eq!(health(&mut rx, "unknown_bones"), "1");
    assert_eq!(health(&mut rx, "unknown"), "1");
    let elbow: f64 = rx
        .eval("return troupe.get_actor('pat'):dof('r_elbow_flexion')")
        .unwrap();
    assert!(
        (elbow - std::f64::consts::FRAC_PI_2).abs() < 1e-3,
        "elbow {elbow}"
    );
    // A burst of 5000 datagrams: the queue keeps what fits, the rest is counted, and the
    // next tick reads what waits without stalling.
    for _ in 0..5000 {
        let _ = s.send_to(&valid, to);
    }
    std::thread::sleep(Duration::from_millis(300));
    for _ in 0..3 {
        rx.tick().unwrap();
    }
    let packets: u64 = health(&mut rx, "packets").parse().unwrap();
    let dropped: u64 = health(&mut rx, "dropped_samples").parse().unwrap();
    assert!(packets > 100, "{packets} datagrams read");
    assert!(
        packets + dropped <= 5000 + 8 && packets <= 8 + 1024 + 1024,
        "{packets}, {dropped}"
    );
    assert_eq!(rx.scene().tick(), 5);
}

#[test]
fn health_goes_stale_after_half_a_second_and_comes_back() {
    let port = free_port();
    let (mut rx, devices) = receiver(port, 0.0);
    assert_eq!(health(&mut rx, "state"), "connected");
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    let frame = bundle(vec![bone("Head", [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])]);
    s.send_to(&frame, ("127.0.0.1", port)).unwrap();
    wait_for(&devices, 1);
    assert_eq!(health(&mut rx, "state"), "streaming");
    std::thread::sleep(Duration::from_millis(800));
    assert_eq!(health(&mut rx, "state"), "stale");
    s.send_to(&frame, ("127.0.0.1", port)).unwrap();
    wait_for(&devices, 2);
    assert_eq!(health(&mut rx, "state"), "streaming");
}

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    c.current_dir(repo());
    c
}

#[test]
fn a_recorded_stream_replays_identically_on_one_and_two_threads() {
    let port = free_port();
    let rec = temp("live.rec");
    let live = temp("live.lua");
    std::fs::write(
        &live,
        format!(
            r#"local pat = troupe.performer{{ name = "pat", devices = {{ vmc = {{ listen = "127.0.0.1:{port}" }} }} }}
               pat:capture{{}}"#
        ),
    )
    .unwrap();
    let mut emu = troupe()
        .args([
            "emulate",
            "vmc",
            "--from",
            "scripts/examples/wave.trk",
            "--seconds",
            "4",
        ])
        .arg("--to")
        .arg(format!("127.0.0.1:{port}"))
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let live_trk = temp("live.trk");
    let out = troupe()
        .args(["run", "--realtime", "--seconds", "2", "--record-devices"])
        .arg(&rec)
        .arg("--record")
        .arg(&live_trk)
        .arg(&live)
        .output()
        .unwrap();
    let _ = emu.kill();
    let _ = emu.wait();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let samples: u64 = text
        .split("device pat.vmc: streaming, ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no VMC health line in {text}"));
    assert!(samples >= 60, "{samples} datagrams in 2 s at 60 Hz");
    let replay = temp("replay.lua");
    std::fs::write(
        &replay,
        format!(
            r#"local pat = troupe.performer{{ name = "pat", devices = {{ vmc = {{ replay = "{}" }} }} }}
               pat:capture{{}}"#,
            rec.display()
        ),
    )
    .unwrap();
    // `troupe run SCENE --seconds 2 EXTRA --record TRK` on 1, then 2 threads: the
    // postures of each.
    let postures = |scene: &PathBuf, extra: &[&OsStr]| -> Vec<Vec<u8>> {
        let threads = [&["--threads", "1"][..], &["--threads", "2", "--chunk", "1"]];
        (threads.iter().enumerate())
            .map(|(i, threads)| {
                let trk = temp(&format!("replay{i}.trk"));
                let out = troupe()
                    .args(["run", "--seconds", "2"])
                    .args(extra)
                    .args(*threads)
                    .arg("--record")
                    .arg(&trk)
                    .arg(scene)
                    .output()
                    .unwrap();
                let err = String::from_utf8_lossy(&out.stderr);
                assert!(out.status.success(), "{err}");
                std::fs::read(&trk).unwrap()
            })
            .collect()
    };
    let by_time = postures(&replay, &[]);
    assert!(
        by_time[0] == by_time[1],
        "replays differ between 1 and 2 threads"
    );
    // The whole run's inputs replayed in place of the listener: each datagram at the tick
    // the live run took it, the jitter buffer played at the live run's clock marks, so
    // the postures are the live run's byte for byte (1 and 2 threads).
    let live_postures = std::fs::read(&live_trk).unwrap();
    let whole_run = postures(&live, &["--replay-devices".as_ref(), rec.as_os_str()]);
    for (threads, replayed) in whole_run.iter().enumerate() {
        assert!(
            *replayed == live_postures,
            "--replay-devices on {} thread(s): the postures differ from the live run's",
            threads + 1
        );
    }
}

#[test]
fn python_osc_reads_troupes_stream_and_drives_a_performer() {
    let python = repo().join(".tools/python/bin/python");
    let has_osc = Command::new(&python)
        .args(["-c", "import pythonosc"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_osc {
        println!(
            "skipped: python-osc is not installed (scripts/setup.sh installs it into {})",
            python.display()
        );
        return;
    }
    let out = Command::new(&python)
        .current_dir(repo())
        .arg("scripts/vmc/compat.py")
        .arg(env!("CARGO_BIN_EXE_troupe"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
}
