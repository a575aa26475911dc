//! troupe across processes over Zenoh, on the loopback interface with explicit endpoints:
//! a follower matching its leader bit for bit, relayed devices (a glove, a SpaceMouse, a
//! VRPN server, a VMC sender) feeding the simulation host, recorded and replayed bit for
//! bit, a relay killed and restarted, a render node writing frames, and the independent
//! Python client (`eclipse-zenoh` from PyPI) checking postures against the `.trk`.
#![cfg(feature = "zenoh")]

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::net::{TcpListener, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;
use troupe_net::zenoh::{Session, Wait};

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

fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// The loopback endpoint on `port`: every process here names its endpoints.
fn on(port: u16) -> String {
    format!("tcp/127.0.0.1:{port}")
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
struct Running(Option<Child>);

impl Running {
    /// Starts `command` with its output kept for [`Running::output`].
    fn piped(command: &mut Command) -> Running {
        let child = command.stdout(Stdio::piped()).stderr(Stdio::piped());
        Running(Some(child.spawn().unwrap()))
    }

    /// Starts `command` with its output thrown away.
    fn quiet(command: &mut Command) -> Running {
        let child = command.stdout(Stdio::null()).stderr(Stdio::null());
        Running(Some(child.spawn().unwrap()))
    }

    /// Waits for the process to end on its own; its output.
    fn output(mut self) -> Output {
        self.0.take().unwrap().wait_with_output().unwrap()
    }

    /// Kills the process now.
    fn kill(mut self) {
        if let Some(mut c) = self.0.take() {
            c.kill().unwrap();
            c.wait().unwrap();
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// `troupe run SCENE --realtime` publishing under `prefix` on `port`.
fn publisher(scene: impl AsRef<OsStr>, prefix: &str, port: u16) -> Command {
    let mut c = troupe();
    c.arg("run").arg(scene).arg("--realtime");
    c.args([
        "--zenoh",
        "--zenoh-prefix",
        prefix,
        "--zenoh-listen",
        &on(port),
    ]);
    c
}

/// A [`publisher`] waiting for a follower before its first tick.
fn leader(scene: impl AsRef<OsStr>, prefix: &str, port: u16) -> Command {
    let mut c = publisher(scene, prefix, port);
    c.arg("--zenoh-await-followers");
    c
}

/// `troupe run SCENE` following the leader on `port` under `prefix`, on two threads with
/// one actor a chunk (replication holds whatever the thread count).
fn follower(scene: impl AsRef<OsStr>, prefix: &str, port: u16) -> Command {
    let mut c = troupe();
    c.arg("run").arg(scene);
    c.args(["--threads", "2", "--chunk", "1"]);
    c.args(["--zenoh-follow", prefix, "--zenoh-connect", &on(port)]);
    c
}

/// `troupe relay KIND DEVICE-OPTIONS --key KEY` listening on `port`.
fn relay(kind: &str, device: &[&str], key: &str, port: u16) -> Running {
    Running::quiet(troupe().args(["relay", kind]).args(device).args([
        "--key",
        key,
        "--zenoh-listen",
        &on(port),
    ]))
}

/// A tool's session (sending cues, listening, playing a relay's part), connected to the
/// troupe listening on `port`.
fn tool(port: u16) -> Session {
    troupe_net::Endpoints::loopback_peer(port).open().unwrap()
}

/// Checks that a follower compared `postures` postures, all equal to its leader's.
fn assert_followed(out: &Output, postures: usize) {
    let t = text(out);
    assert!(out.status.success(), "follower:\n{t}");
    let said = format!("{postures} postures compared, all equal to the leader's bit for bit");
    assert!(t.contains(&said), "{t}");
    assert!(!t.contains("not compared"), "{t}");
}

/// Adds `--record-devices REC --record TRK` to a run: its inputs and its postures.
fn recording<'a>(run: &'a mut Command, rec: &Path, trk: &Path) -> &'a mut Command {
    run.arg("--record-devices")
        .arg(rec)
        .arg("--record")
        .arg(trk)
}

/// `troupe run SCENE LENGTH --replay-devices REC --record TRK`, which must succeed: the
/// scene run from a recording of its inputs, without devices or a network.
fn replay_devices(scene: impl AsRef<OsStr>, length: &[&str], rec: &Path, trk: &Path) -> Output {
    let out = troupe()
        .arg("run")
        .arg(scene)
        .args(length)
        .arg("--replay-devices")
        .arg(rec)
        .arg("--record")
        .arg(trk)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    out
}

/// Checks that two `.trk` files are byte for byte the same.
fn assert_same_trk(live: &Path, replayed: &Path) {
    let (a, b) = (
        std::fs::read(live).unwrap(),
        std::fs::read(replayed).unwrap(),
    );
    assert!(
        a == b,
        "the replay's {} differs from the recorded run's {}",
        replayed.display(),
        live.display()
    );
}

/// The health states a scene's [`watcher`] printed for `device` (a log line ending `lua:
/// vmc stale at 212 actor=watcher`), in order.
fn states<'a>(t: &'a str, device: &str) -> Vec<&'a str> {
    let said = format!("lua: {device} ");
    t.lines()
        .filter_map(|l| l.split(&said).nth(1))
        .filter_map(|l| l.split_whitespace().next())
        .collect()
}

/// Checks that a device streamed, went stale (its relay gone) and streamed again.
fn assert_stale_then_back(t: &str, device: &str) {
    let states = states(t, device);
    let streaming = states.iter().position(|s| *s == "streaming");
    let stale = states.iter().position(|s| *s == "stale");
    let again = states.iter().rposition(|s| *s == "streaming");
    assert!(
        streaming.is_some() && streaming < stale && stale < again,
        "{device} states {states:?}:\n{t}"
    );
}

/// A watcher printing `DEVICE STATE at TICK` whenever the health of `pat`'s `device`
/// changes (Lua, for a scene).
fn watcher(device: &str) -> String {
    format!(
        r#"local seen = {{}}
           troupe.actor{{ name = "watcher" }}:behave(function()
             while true do
               local s = troupe.devices.health(pat).{device}
               if s and s.state ~= seen[#seen] then
                 seen[#seen + 1] = s.state
                 print("{device} " .. s.state .. " at " .. troupe.tick())
               end
               wait(0.05)
             end
           end)"#
    )
}

#[test]
fn a_follower_matches_its_leader_bit_for_bit_over_1000_ticks() {
    let port = free_port();
    let prefix = "troupe/follow-test";
    let scene = "tests/scenes/zenoh_follow.lua";
    let leader =
        Running::piped(leader(scene, prefix, port).args(["--ticks", "1000", "--seed", "7"]));
    wait_listening(port);
    let follower = Running::piped(follower(scene, prefix, port).args(["--ticks", "1000"]));
    // A tool sends the cue bob waits for, mid-run: the leader receives it from the
    // network, the follower from the leader's replicated inputs.
    let tool = tool(port);
    std::thread::sleep(Duration::from_secs(3));
    tool.put("cue/bob", r#"{"side":"left","angle":1.2}"#)
        .wait()
        .unwrap();
    assert_followed(&follower.output(), 3000);
    assert!(leader.output().status.success(), "leader failed");
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
    let _leader = Running::quiet(leader(&leader_scene, prefix, port).args(["--ticks", "150"]));
    wait_listening(port);
    let out = troupe()
        .arg("run")
        .arg(&follower_scene)
        .args(["--ticks", "150", "--zenoh-follow", prefix])
        .args(["--zenoh-connect", &on(port)])
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
    (Running(Some(child)), line.trim().to_string())
}

#[test]
fn a_relayed_glove_feeds_a_performer_and_survives_its_relay_restarting() {
    let (_emulator, pty) = emulated_glove();
    let port = free_port();
    let key = "troupe/devices/glove";
    let scene = temp("relayed.lua");
    std::fs::write(
        &scene,
        format!(
            r#"local pat = troupe.performer{{ name = "pat",
                 devices = {{ glove = {{ zenoh = "{key}", hand = "right" }} }} }}
               pat:capture{{}}
               {}"#,
            watcher("glove")
        ),
    )
    .unwrap();
    let rec = temp("relayed.rec");
    let first = relay("cyberglove", &["--port", &pty], key, port);
    wait_listening(port);
    let run = Running::piped(
        troupe()
            .arg("run")
            .arg(&scene)
            .args(["--seconds", "6", "--realtime", "--record-devices"])
            .arg(&rec)
            .args(["--zenoh-connect", &on(port)]),
    );
    // Kill the relay 2 s in; start another on the same port 1 s later.
    std::thread::sleep(Duration::from_secs(2));
    first.kill();
    std::thread::sleep(Duration::from_secs(1));
    let _second = relay("cyberglove", &["--port", &pty], key, port);
    let out = run.output();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    // Streaming, stale while the relay was gone, streaming again; the scene kept ticking.
    assert_stale_then_back(&t, "glove");
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

/// The inputs of a live run travel to a follower (a relayed glove's samples and a tool's
/// message, with their ticks) and into the `.rec` file; the follower and a replay of the
/// file compute the leader's postures bit for bit; the behaviors' messages are published
/// on `<prefix>/messages` with their ticks.
#[test]
fn live_inputs_are_replicated_to_a_follower_and_replayed_from_the_rec_bit_for_bit() {
    let (_emulator, pty) = emulated_glove();
    let (relay_port, leader_port) = (free_port(), free_port());
    let key = "troupe/devices/glove-replicated";
    let _relay = relay("cyberglove", &["--port", &pty], key, relay_port);
    wait_listening(relay_port);
    let prefix = "troupe/replicated-test";
    let scene = "tests/scenes/zenoh_relayed.lua";
    let (rec, leader_trk, replay_trk) = (temp("lead.rec"), temp("lead.trk"), temp("replay.trk"));
    let leader = Running::piped(recording(
        leader(scene, prefix, leader_port)
            .args(["--ticks", "400", "--seed", "3"])
            .args(["--zenoh-connect", &on(relay_port)]),
        &rec,
        &leader_trk,
    ));
    wait_listening(leader_port);
    let follower = Running::piped(follower(scene, prefix, leader_port).args(["--ticks", "400"]));
    // A tool listens to the behavior messages and, mid-run, sends bob his cue.
    let tool = tool(leader_port);
    let messages = tool
        .declare_subscriber(format!("{prefix}/messages"))
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    tool.put("cue/bob", r#"{"side":"left","angle":1.1}"#)
        .wait()
        .unwrap();
    assert_followed(&follower.output(), 1200);
    assert!(leader.output().status.success(), "leader failed");
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
    replay_devices(scene, &["--ticks", "400", "--seed", "3"], &rec, &replay_trk);
    assert_same_trk(&leader_trk, &replay_trk);
    // The glove moved the hand: the replay is not equal merely for want of input.
    let recording = troupe_drivers::record::Recording::read(&rec).unwrap();
    assert!(
        recording.marks.len() > 100,
        "{} tick marks",
        recording.marks.len()
    );
    assert_eq!(recording.messages.len(), 1, "{:?}", recording.messages);
}

/// What cannot work is refused at once, naming it: a relay of a kind troupe does not
/// relay, a VMC relay on an address it cannot bind, a VMC performer naming a relay's key
/// without a network session, or naming both a UDP port and a key.
#[test]
fn bad_relay_and_vmc_options_are_refused_naming_them() {
    let refused = |c: &mut Command| {
        let out = c.output().unwrap();
        assert!(!out.status.success(), "{}", text(&out));
        text(&out)
    };
    let t = refused(troupe().args(["relay", "osc", "--key", "stage/osc"]));
    assert!(
        t.contains("troupe relay osc: relays serve") && t.contains("vmc"),
        "{t}"
    );
    let t = refused(troupe().args(["relay", "vmc", "--listen", "256.1.1.1:9", "--key", "k"]));
    assert!(t.contains("troupe relay vmc --listen 256.1.1.1:9"), "{t}");
    for (devices, says) in [
        (
            r#"{ zenoh = "stage/vmc" }"#,
            r#"zenoh = "stage/vmc" needs a network session"#,
        ),
        (
            r#"{ listen = "127.0.0.1:0", zenoh = "stage/vmc" }"#,
            "give one of `listen`, `zenoh` and `replay`",
        ),
    ] {
        let scene = temp("bad-vmc.lua");
        let lua = format!(r#"troupe.performer{{ name = "pat", devices = {{ vmc = {devices} }} }}"#);
        std::fs::write(&scene, lua).unwrap();
        let t = refused(troupe().arg("run").arg(&scene).args(["--ticks", "1"]));
        assert!(t.contains(&format!("performer.devices.vmc: {says}")), "{t}");
    }
}

/// `troupe relay vmc` on the sender's machine: a VMC sender (`troupe emulate vmc`, playing
/// a recorded wave over UDP) feeds the relay, a performer on the simulation host names its
/// key; a follower matches the leader bit for bit from the replicated datagrams, tick
/// marks and clock marks; `--replay-devices` of the leader's `.rec` gives its `.trk` byte
/// for byte; the relay killed mid-run makes the performer stale, the scene ticks on, and
/// the stream resumes when a relay starts again.
#[test]
fn a_relayed_vmc_sender_drives_a_performer_followed_and_replayed_bit_for_bit() {
    let (udp, relay_port, leader_port) = (free_udp_port(), free_port(), free_port());
    let key = "troupe/devices/vmc";
    let listen = format!("127.0.0.1:{udp}");
    let _sender = Running::quiet(
        troupe()
            .args(["emulate", "vmc", "--from", "scripts/examples/wave.trk"])
            .args(["--seconds", "60", "--to", &listen]),
    );
    let first = relay("vmc", &["--listen", &listen], key, relay_port);
    wait_listening(relay_port);
    let scene = temp("vmc.lua");
    std::fs::write(
        &scene,
        format!(
            r#"local pat = troupe.performer{{ name = "pat", devices = {{ vmc = {{ zenoh = "{key}" }} }} }}
               pat:capture{{}}
               {}"#,
            watcher("vmc")
        ),
    )
    .unwrap();
    let prefix = "troupe/vmc-test";
    let (rec, leader_trk, replay_trk) = (temp("vmc.rec"), temp("vmc.trk"), temp("vmc-replay.trk"));
    let leader = Running::piped(recording(
        leader(&scene, prefix, leader_port)
            .args(["--ticks", "600"])
            .args(["--zenoh-connect", &on(relay_port)]),
        &rec,
        &leader_trk,
    ));
    wait_listening(leader_port);
    let follower = Running::piped(follower(&scene, prefix, leader_port).args(["--ticks", "600"]));
    // Kill the relay 2 s in; start another on the same ports 1 s later.
    std::thread::sleep(Duration::from_secs(2));
    first.kill();
    std::thread::sleep(Duration::from_secs(1));
    let _second = relay("vmc", &["--listen", &listen], key, relay_port);
    assert_followed(&follower.output(), 1200);
    let out = leader.output();
    let t = text(&out);
    assert!(out.status.success(), "leader:\n{t}");
    assert_stale_then_back(&t, "vmc");

    replay_devices(&scene, &["--ticks", "600"], &rec, &replay_trk);
    assert_same_trk(&leader_trk, &replay_trk);
    // The datagrams moved the performer: every tick read the clock, and over a hundred
    // took datagrams (60 a second while a relay ran).
    let recording = troupe_drivers::record::Recording::read(&rec).unwrap();
    assert_eq!(recording.streams[0].name, "pat.vmc");
    assert_eq!(recording.clocks.len(), 600, "one clock mark a tick");
    assert!(
        recording.marks.len() > 100,
        "{} tick marks",
        recording.marks.len()
    );
}

#[test]
fn a_render_node_writes_frames_of_a_remote_scene() {
    let port = free_port();
    let frames = temp("frames");
    let scene = "scripts/examples/greeting.lua";
    let _leader =
        Running::quiet(publisher(scene, "troupe/render-test", port).args(["--seconds", "8"]));
    wait_listening(port);
    let out = troupe()
        .args(["view", "--zenoh", "troupe/render-test"])
        .args(["--zenoh-connect", &on(port)])
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

/// A SpaceMouse served under a key moves its object on the simulation host; the run's
/// `.rec` (the relayed reports and the ticks that took them) replays the object's path
/// byte for byte. No SpaceMouse is plugged in here, so the test plays `troupe relay
/// spacemouse`'s part: one HID report per chunk on `<key>/rx` (combined report 1:
/// translation x at 350 of 350, full right).
#[test]
fn a_relayed_spacemouse_moves_its_object_and_replays_bit_for_bit() {
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
    let (rec, live_trk, replay_trk) = (
        temp("mouse.rec"),
        temp("mouse.trk"),
        temp("mouse-replay.trk"),
    );
    let run = Running::piped(recording(
        troupe()
            .arg("run")
            .arg(&scene)
            .args(["--seconds", "3", "--realtime"])
            .args(["--zenoh-listen", &on(port)]),
        &rec,
        &live_trk,
    ));
    wait_listening(port);
    let relay = tool(port);
    let report = |x: i16| {
        let mut r = vec![1u8];
        for axis in [x, 0, 0, 0, 0, 0] {
            r.extend_from_slice(&axis.to_le_bytes());
        }
        r
    };
    // Pushed for one second, a little less hard for the next, then let go.
    for i in 0..160 {
        let r = report(match i {
            0..100 => 350,
            100..150 => 175,
            _ => 0,
        });
        let chunk = troupe_net::relay::encode_chunk(troupe_net::relay::now_micros(), &r);
        relay.put("troupe/devices/mouse/rx", chunk).wait().unwrap();
        std::thread::sleep(Duration::from_millis(10));
    }
    let out = run.output();
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    let x: f64 = t
        .split("crate x ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no position printed:\n{t}"));
    // About a second at 0.25 m/s and half a second at about half of it (the first
    // reports may arrive before the device opens).
    assert!(x > 0.15 && x < 0.4, "crate moved {x} m:\n{t}");

    // The replay takes each report at the tick the live run took it, without a network.
    let out = replay_devices(&scene, &["--seconds", "3"], &rec, &replay_trk);
    assert!(
        text(&out).contains(&format!("crate x {x:.3}")),
        "{}",
        text(&out)
    );
    assert_same_trk(&live_trk, &replay_trk);
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
    let device = format!("Spin0@tcp://127.0.0.1:{vrpn_port}");
    let _relay = relay(
        "vrpn",
        &["--device", &device],
        "troupe/devices/vrpn",
        relay_port,
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
        .args(["--zenoh-connect", &on(relay_port)])
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
        listen: vec![on(port)],
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
    let node = Running::quiet(
        troupe()
            .args(["view", "--zenoh", "troupe/kill-test"])
            .args(["--zenoh-connect", &on(port)])
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
            .arg(&frames),
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
    node.kill();
    let killed = median((0..200).map(|_| tick(&mut session)).collect());
    assert!(
        killed <= alive * 2.0 + 0.002,
        "median tick {:.3} ms with the subscriber, {:.3} ms after it was killed",
        alive * 1e3,
        killed * 1e3
    );
    session.finish().unwrap();
}
