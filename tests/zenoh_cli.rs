//! troupe across processes over Zenoh, on the loopback interface with explicit endpoints:
//! a follower matching its leader bit for bit, a relayed glove feeding a performer (its
//! relay killed and restarted), a render node writing frames, and the independent
//! Python client (`eclipse-zenoh` from PyPI) checking postures against the `.trk`.
#![cfg(feature = "zenoh")]

use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;
use troupe_net::zenoh::Wait;

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-zenoh-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Waits until something listens on `port` (a troupe that has opened its session).
fn wait_listening(port: u16) {
    for _ in 0..300 {
        if std::net::TcpStream::connect(("127.0.0.1", port)).is_ok() {
            return;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!("nothing listens on {port}");
}

/// A child process killed when dropped (a failing test leaves nothing running).
struct Running(Child);
impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn a_follower_matches_its_leader_bit_for_bit_over_1000_ticks() {
    let port = free_port();
    let prefix = "troupe/follow-test";
    let scene = "tests/scenes/zenoh_follow.lua";
    let leader = Running(
        troupe()
            .args(["run", scene, "--ticks", "1000", "--seed", "7", "--realtime"])
            .args([
                "--zenoh",
                "--zenoh-prefix",
                prefix,
                "--zenoh-await-followers",
            ])
            .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{port}")])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    wait_listening(port);
    // Two threads, one actor per chunk: replication holds whatever the thread count.
    let follower = troupe()
        .args([
            "run",
            scene,
            "--ticks",
            "1000",
            "--threads",
            "2",
            "--chunk",
            "1",
        ])
        .args(["--zenoh-follow", prefix])
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A tool sends the cue bob waits for, mid-run: the leader receives it from the
    // network, the follower from the leader's replicated inputs.
    let tool = troupe_net::Endpoints {
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        listen: vec!["tcp/127.0.0.1:0".into()],
    }
    .open()
    .unwrap();
    std::thread::sleep(Duration::from_secs(3));
    tool.put("cue/bob", r#"{"side":"left","angle":1.2}"#)
        .wait()
        .unwrap();
    let follower = follower.wait_with_output().unwrap();
    let mut leader = leader;
    let leader_out = leader.0.wait().unwrap();
    let follower_text = text(&follower);
    assert!(follower.status.success(), "follower:\n{follower_text}");
    assert!(leader_out.success(), "leader failed");
    assert!(
        follower_text.contains("3000 postures compared, all equal to the leader's bit for bit"),
        "{follower_text}"
    );
    assert!(!follower_text.contains("not compared"), "{follower_text}");
}

#[test]
fn a_follower_running_another_scene_names_the_first_tick_that_differs() {
    let port = free_port();
    let prefix = "troupe/diverge-test";
    let leader_scene = temp("leader.lua");
    let follower_scene = temp("follower.lua");
    let scene = |delay: f64| {
        format!(
            r#"local ann = troupe.actor{{ name = "ann" }}
               ann:behave(function(self)
                 wait({delay})
                 self:play(troupe.sequence{{ r_elbow_flexion = {{ {{0, 0}}, {{1, 1}} }} }}):wait()
               end)"#
        )
    };
    std::fs::write(&leader_scene, scene(0.5)).unwrap();
    std::fs::write(&follower_scene, scene(0.6)).unwrap();
    let _leader = Running(
        troupe()
            .arg("run")
            .arg(&leader_scene)
            .args([
                "--ticks",
                "150",
                "--realtime",
                "--zenoh",
                "--zenoh-prefix",
                prefix,
            ])
            .args(["--zenoh-await-followers"])
            .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{port}")])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    wait_listening(port);
    let out = troupe()
        .arg("run")
        .arg(&follower_scene)
        .args(["--ticks", "150", "--zenoh-follow", prefix])
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{port}")])
        .output()
        .unwrap();
    let t = text(&out);
    assert!(!out.status.success(), "{t}");
    // The leader's behavior starts the bend in the script phase of tick 51 (after 0.5 s);
    // the elbow first moves in tick 52, which is the first to differ.
    assert!(
        t.contains("postures differ from the leader first at tick 52: ann r_elbow_flexion"),
        "{t}"
    );
}

/// `troupe emulate cyberglove`: the pty path it prints.
fn emulated_glove() -> (Running, String) {
    let mut child = troupe()
        .args(["emulate", "cyberglove", "--seconds", "60"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    (Running(child), line.trim().to_string())
}

fn relay(pty: &str, port: u16) -> Running {
    Running(
        troupe()
            .args([
                "relay",
                "cyberglove",
                "--port",
                pty,
                "--key",
                "troupe/devices/glove",
            ])
            .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{port}")])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    )
}

#[test]
fn a_relayed_glove_feeds_a_performer_and_survives_its_relay_restarting() {
    let (_emulator, pty) = emulated_glove();
    let port = free_port();
    let scene = temp("relayed.lua");
    std::fs::write(
        &scene,
        r#"local pat = troupe.performer{ name = "pat",
             devices = { glove = { zenoh = "troupe/devices/glove", hand = "right" } } }
           pat:capture{}
           local seen = {}
           troupe.actor{ name = "watcher" }:behave(function()
             while true do
               local s = troupe.devices.health(pat).glove
               if s and s.state ~= seen[#seen] then
                 seen[#seen + 1] = s.state
                 print("glove " .. s.state .. " at " .. troupe.tick())
               end
               wait(0.05)
             end
           end)"#,
    )
    .unwrap();
    let rec = temp("relayed.rec");
    let mut first = Some(relay(&pty, port));
    wait_listening(port);
    let run = troupe()
        .arg("run")
        .arg(&scene)
        .args(["--seconds", "6", "--realtime", "--record-devices"])
        .arg(&rec)
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Kill the relay 2 s in; start another on the same port 1 s later.
    std::thread::sleep(Duration::from_secs(2));
    drop(first.take());
    std::thread::sleep(Duration::from_secs(1));
    let _second = relay(&pty, port);
    let out = run.wait_with_output().unwrap();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    // Streaming, stale while the relay was gone, streaming again; the scene kept ticking.
    let states: Vec<&str> = t
        .lines()
        .filter_map(|l| l.split("glove ").nth(1))
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    let streaming = states.iter().position(|s| *s == "streaming");
    let stale = states.iter().position(|s| *s == "stale");
    let again = states.iter().rposition(|s| *s == "streaming");
    assert!(
        streaming < stale && stale < again && streaming.is_some(),
        "glove states {states:?}:\n{t}"
    );
    assert!(t.contains("for 600 ticks"), "{t}");
    // The relayed bytes were recorded like a local device's: a replay reads them.
    let replay = temp("replay.lua");
    std::fs::write(
        &replay,
        format!(
            r#"local pat = troupe.performer{{ name = "pat",
                 devices = {{ glove = {{ replay = "{}", hand = "right" }} }} }}
               pat:capture{{}}"#,
            rec.display()
        ),
    )
    .unwrap();
    let out = troupe()
        .arg("run")
        .arg(&replay)
        .args(["--ticks", "100"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
}

fn relay_on(pty: &str, port: u16, key: &str) -> Running {
    Running(
        troupe()
            .args(["relay", "cyberglove", "--port", pty, "--key", key])
            .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{port}")])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    )
}

/// The inputs of a live run travel to a follower (a relayed glove's samples and a tool's
/// message, with their ticks) and into the `.rec` file; the follower and a replay of the
/// file compute the leader's postures bit for bit; the behaviors' messages are published
/// on `<prefix>/messages` with their ticks.
#[test]
fn live_inputs_are_replicated_to_a_follower_and_replayed_from_the_rec_bit_for_bit() {
    let (_emulator, pty) = emulated_glove();
    let (relay_port, leader_port) = (free_port(), free_port());
    let _relay = relay_on(&pty, relay_port, "troupe/devices/glove-replicated");
    wait_listening(relay_port);
    let prefix = "troupe/replicated-test";
    let scene = "tests/scenes/zenoh_relayed.lua";
    let (rec, leader_trk, replay_trk) = (temp("lead.rec"), temp("lead.trk"), temp("replay.trk"));
    let leader = troupe()
        .args(["run", scene, "--ticks", "400", "--seed", "3", "--realtime"])
        .args([
            "--zenoh",
            "--zenoh-prefix",
            prefix,
            "--zenoh-await-followers",
        ])
        .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{leader_port}")])
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{relay_port}")])
        .arg("--record-devices")
        .arg(&rec)
        .arg("--record")
        .arg(&leader_trk)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let leader = Running(leader);
    wait_listening(leader_port);
    let follower = troupe()
        .args([
            "run",
            scene,
            "--ticks",
            "400",
            "--threads",
            "2",
            "--chunk",
            "1",
        ])
        .args(["--zenoh-follow", prefix])
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{leader_port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A tool listens to the behavior messages and, mid-run, sends bob his cue.
    let tool = troupe_net::Endpoints {
        connect: vec![format!("tcp/127.0.0.1:{leader_port}")],
        listen: vec!["tcp/127.0.0.1:0".into()],
    }
    .open()
    .unwrap();
    let messages = tool
        .declare_subscriber(format!("{prefix}/messages"))
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    tool.put("cue/bob", r#"{"side":"left","angle":1.1}"#)
        .wait()
        .unwrap();
    let follower = follower.wait_with_output().unwrap();
    let mut leader = leader;
    let leader_out = leader.0.wait().unwrap();
    let follower_text = text(&follower);
    assert!(leader_out.success(), "leader failed");
    assert!(follower.status.success(), "follower:\n{follower_text}");
    assert!(
        follower_text.contains("1200 postures compared, all equal to the leader's bit for bit"),
        "{follower_text}"
    );
    // Behavior messages: JSON with the tick that published them, in tick order.
    let mut ticks = Vec::new();
    while let Ok(Some(sample)) = messages.try_recv() {
        let doc: serde_json::Value = serde_json::from_slice(&sample.payload().to_bytes()).unwrap();
        assert_eq!(doc["key"], "ann/reached", "{doc}");
        let (tick, said) = (doc["tick"].as_u64().unwrap(), doc["value"]["tick"].as_u64());
        // The behavior ran in the script phase of the tick that published it.
        assert!(said == Some(tick) || said == Some(tick - 1), "{doc}");
        ticks.push(tick);
    }
    assert!(
        ticks.len() >= 3,
        "behavior messages seen at ticks {ticks:?}"
    );
    assert!(ticks.windows(2).all(|w| w[0] < w[1]), "{ticks:?}");

    // The replay of the leader's recording (glove bytes, tick marks, the cue) makes the
    // leader's postures, byte for byte, without the relay or the network.
    let out = troupe()
        .args(["run", scene, "--ticks", "400", "--seed", "3"])
        .arg("--replay-devices")
        .arg(&rec)
        .arg("--record")
        .arg(&replay_trk)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let (a, b) = (
        std::fs::read(&leader_trk).unwrap(),
        std::fs::read(&replay_trk).unwrap(),
    );
    assert!(
        a == b,
        "the replay's postures differ from the recorded run's"
    );
    // The glove moved the hand: the replay is not equal merely for want of input.
    let recording = troupe_drivers::record::Recording::read(&rec).unwrap();
    assert!(
        recording.marks.len() > 100,
        "{} tick marks",
        recording.marks.len()
    );
    assert_eq!(recording.messages.len(), 1, "{:?}", recording.messages);
}

#[test]
fn a_render_node_writes_frames_of_a_remote_scene() {
    let port = free_port();
    let frames = temp("frames");
    let _leader = Running(
        troupe()
            .args([
                "run",
                "scripts/examples/greeting.lua",
                "--seconds",
                "8",
                "--realtime",
            ])
            .args(["--zenoh", "--zenoh-prefix", "troupe/render-test"])
            .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{port}")])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    wait_listening(port);
    let out = troupe()
        .args(["view", "--zenoh", "troupe/render-test"])
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{port}")])
        .args([
            "--seconds",
            "1",
            "--every",
            "25",
            "--size",
            "160x90",
            "--no-msaa",
        ])
        .arg("--frames")
        .arg(&frames)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let pngs = std::fs::read_dir(&frames).unwrap().count();
    assert!(pngs >= 4, "{pngs} frames written");
}

#[test]
fn an_independent_python_client_checks_the_postures_against_the_trk() {
    // The venv scripts/setup.sh --tests makes in .tools/python, with eclipse-zenoh.
    let python = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(".tools/python/bin/python");
    let has_zenoh = Command::new(&python).args(["-c", "import zenoh"]).output();
    if !has_zenoh.is_ok_and(|o| o.status.success()) {
        eprintln!(
            "skipped: {} with eclipse-zenoh is not installed (scripts/setup.sh --tests installs it)",
            python.display()
        );
        return;
    }
    let out_dir = temp("python");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = Command::new(&python)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .arg("scripts/zenoh_check.py")
        .arg(env!("CARGO_BIN_EXE_troupe"))
        .arg("scripts/examples/greeting.lua")
        .arg(&out_dir)
        .args(["--ticks", "300"])
        .output()
        .unwrap();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    assert!(t.contains("match"), "{t}");
}

/// A SpaceMouse served under a key moves its object on the simulation host. No SpaceMouse
/// is plugged in here, so the test plays `troupe relay spacemouse`'s part: one HID report
/// per chunk on `<key>/rx` (combined report 1: translation x at 350 of 350, full right).
#[test]
fn a_relayed_spacemouse_moves_its_object() {
    let port = free_port();
    let scene = temp("mouse.lua");
    std::fs::write(
        &scene,
        r#"local crate = troupe.object{ name = "crate", shape = "box", size = {0.3, 0.3, 0.3}, at = {0, 1, 0} }
           troupe.devices.spacemouse{ object = crate, zenoh = "troupe/devices/mouse", speed = 0.25 }
           troupe.actor{ name = "watcher" }:behave(function()
             wait(2.5)
             local p = crate:position()
             print(string.format("crate x %.3f", p[1]))
           end)"#,
    )
    .unwrap();
    let run = troupe()
        .arg("run")
        .arg(&scene)
        .args(["--seconds", "3", "--realtime"])
        .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_listening(port);
    let relay = troupe_net::Endpoints {
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        listen: vec!["tcp/127.0.0.1:0".into()],
    }
    .open()
    .unwrap();
    let report = |x: i16| {
        let mut r = vec![1u8];
        for axis in [x, 0, 0, 0, 0, 0] {
            r.extend_from_slice(&axis.to_le_bytes());
        }
        r
    };
    // Pushed for one second, then let go.
    for i in 0..110 {
        let r = report(if i < 100 { 350 } else { 0 });
        let chunk = troupe_net::relay::encode_chunk(troupe_net::relay::now_micros(), &r);
        relay.put("troupe/devices/mouse/rx", chunk).wait().unwrap();
        std::thread::sleep(Duration::from_millis(10));
    }
    let out = run.wait_with_output().unwrap();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    let x: f64 = t
        .split("crate x ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no position printed:\n{t}"));
    // About a second at 0.25 m/s (the first reports may arrive before the device opens).
    assert!(x > 0.1 && x < 0.3, "crate moved {x} m:\n{t}");
}

#[path = "../drivers/tests/vrpn/server.rs"]
mod vrpn_server;

/// `troupe relay vrpn` reaches a VRPN server (the real one) on its machine; a performer on
/// the simulation host names the relay's key and streams.
#[test]
fn a_vrpn_server_reached_through_a_relay_streams_to_a_performer() {
    let vrpn_port = vrpn_server::free_port();
    let _server = vrpn_server::Server::start(
        vrpn_port,
        "vrpn_Tracker_Spin Spin0 2 100.0 0.0 1.0 0.0 0.25\n",
    );
    let relay_port = free_port();
    let _relay = Running(
        troupe()
            .args([
                "relay",
                "vrpn",
                "--device",
                &format!("Spin0@tcp://127.0.0.1:{vrpn_port}"),
            ])
            .args(["--key", "troupe/devices/vrpn"])
            .args(["--zenoh-listen", &format!("tcp/127.0.0.1:{relay_port}")])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    wait_listening(relay_port);
    let scene = temp("vrpn.lua");
    std::fs::write(
        &scene,
        r#"local p = troupe.performer{ name = "pat",
             devices = { vrpn = { device = "Spin0@relay", zenoh = "troupe/devices/vrpn",
                                  map = { pelvis = 0, skullbase = 1 } } } }
           p:capture{}"#,
    )
    .unwrap();
    let out = troupe()
        .arg("run")
        .arg(&scene)
        .args(["--ticks", "150", "--realtime"])
        .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{relay_port}")])
        .output()
        .unwrap();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    assert!(t.contains("device pat.vrpn: streaming"), "{t}");
}

/// A leader's tick times, a subscriber alive and after it is killed: a subscriber that
/// vanishes must not slow the leader. Ticks are paced at 100 Hz; the subscriber is a
/// render node in its own process (headless frames), killed with SIGKILL mid-run. The
/// bound is loose (shared machines are noisy): a leader that waited for the vanished
/// subscriber would take tens of milliseconds a tick, not a fraction of one.
#[test]
fn a_subscriber_killed_mid_run_leaves_the_leaders_tick_times_alone() {
    use troupe_scene::{ActorDesc, Scene, SceneConfig, Session};
    let port = free_port();
    let keys = troupe_net::SceneKeys::new("troupe/kill-test").unwrap();
    let leader = troupe_net::Endpoints {
        connect: vec![],
        listen: vec![format!("tcp/127.0.0.1:{port}")],
    }
    .open()
    .unwrap();
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    for i in 0..50 {
        scene.add_actor(&ActorDesc::new(format!("a{i}"))).unwrap();
    }
    let mut session = Session::new(scene);
    session.observe(troupe_net::ScenePublisher::new(leader, keys).unwrap());
    session.start().unwrap();
    let frames = temp("kill-frames");
    let mut node = Running(
        troupe()
            .args(["view", "--zenoh", "troupe/kill-test"])
            .args(["--zenoh-connect", &format!("tcp/127.0.0.1:{port}")])
            .args([
                "--seconds",
                "60",
                "--every",
                "20",
                "--size",
                "64x36",
                "--no-msaa",
            ])
            .arg("--frames")
            .arg(&frames)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let tick = |session: &mut Session| {
        let t0 = std::time::Instant::now();
        session.tick().unwrap();
        let spent = t0.elapsed();
        std::thread::sleep(Duration::from_millis(10).saturating_sub(spent));
        spent.as_secs_f64()
    };
    // Tick until the render node has drawn a frame: it is subscribed.
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    while std::fs::read_dir(&frames).map_or(0, |d| d.count()) == 0 {
        assert!(
            std::time::Instant::now() < deadline,
            "the render node drew nothing"
        );
        tick(&mut session);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let alive = median((0..200).map(|_| tick(&mut session)).collect());
    node.0.kill().unwrap();
    node.0.wait().unwrap();
    let killed = median((0..200).map(|_| tick(&mut session)).collect());
    assert!(
        killed <= alive * 2.0 + 0.002,
        "median tick {:.3} ms with the subscriber, {:.3} ms after it was killed",
        alive * 1e3,
        killed * 1e3
    );
    session.finish().unwrap();
}
