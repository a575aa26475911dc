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
    let python = Command::new("python3")
        .args(["-c", "import zenoh"])
        .output();
    if !python.is_ok_and(|o| o.status.success()) {
        eprintln!(
            "skipped: python3 with eclipse-zenoh is not installed (scripts/setup.sh installs it)"
        );
        return;
    }
    let out_dir = temp("python");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = Command::new("python3")
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
