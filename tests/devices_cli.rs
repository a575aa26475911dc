//! End to end through the command line: `troupe emulate` on a pty, `troupe devices probe`,
//! `troupe run --record-devices` with a performer, and replay giving identical postures.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-devcli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// An emulator child process and the pty path it printed; killed on drop.
struct Emu(Child, String);

impl Drop for Emu {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn emulate(args: &[&str]) -> Emu {
    let mut child = troupe()
        .arg("emulate")
        .args(args)
        .args(["--seconds", "60"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    Emu(child, line.trim().to_string())
}

fn ok(c: &mut Command) -> String {
    let out = c.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn probe_an_emulated_flock_and_glove() {
    let link = temp("fob-link");
    let fob = emulate(&["fob", "--birds", "3", "--link", link.to_str().unwrap()]);
    assert!(
        fob.1 == link.display().to_string(),
        "prints the link: {}",
        fob.1
    );
    let out = ok(troupe()
        .args(["devices", "probe", "fob", "--port", &fob.1, "--birds", "3"])
        .args(["--format", "position-matrix", "--samples", "6", "--json"]));
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 6);
    let addrs: Vec<u64> = lines
        .iter()
        .map(|v| v["reading"]["address"].as_u64().unwrap())
        .collect();
    assert_eq!(&addrs[..3], &[1, 2, 3]);
    assert_eq!(lines[0]["reading"]["matrix"].as_array().unwrap().len(), 9);

    let glove = emulate(&["cyberglove", "--sensors", "22"]);
    let out = ok(troupe().args([
        "devices",
        "probe",
        "cyberglove",
        "--port",
        &glove.1,
        "--sensors",
        "22",
        "--samples",
        "3",
    ]));
    assert_eq!(out.lines().count(), 3);
    assert_eq!(
        out.lines().next().unwrap().split_whitespace().count(),
        2 + 22
    );

    // Wrong sensor count and a missing port: clear errors, no panic.
    let out = troupe()
        .args([
            "devices",
            "probe",
            "cyberglove",
            "--port",
            &glove.1,
            "--samples",
            "1",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("samples 22 sensors, configured for 18"));
    let out = troupe()
        .args([
            "devices",
            "probe",
            "fob",
            "--port",
            "/dev/no-such-port",
            "--timeout",
            "1",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/dev/no-such-port"));
}

#[test]
fn run_records_device_streams_and_replay_is_deterministic() {
    let fob = emulate(&["fob", "--birds", "2"]);
    let glove = emulate(&["cyberglove"]);
    let scene = temp("live.lua");
    std::fs::write(
        &scene,
        format!(
            r#"local p = troupe.performer{{ name = "pat",
                 devices = {{ fob = {{ port = "{}", birds = 2, map = {{ pelvis = 1, skullbase = 2 }} }},
                              glove = {{ port = "{}", hand = "left" }} }} }}
               p:capture{{}}"#,
            fob.1, glove.1
        ),
    )
    .unwrap();
    let rec = temp("pat.rec");
    let out = ok(troupe()
        .arg("run")
        .arg(&scene)
        .args(["--ticks", "100", "--realtime", "--record-devices"])
        .arg(&rec));
    assert!(out.contains("recorded the device streams"), "{out}");
    assert!(out.contains("sample-to-posture latency"), "{out}");
    assert!(out.contains("device pat.fob: streaming"), "{out}");

    let replay = temp("replay.lua");
    std::fs::write(
        &replay,
        format!(
            r#"local p = troupe.performer{{ name = "pat",
                 devices = {{ fob = {{ replay = "{0}", birds = 2, map = {{ pelvis = 1, skullbase = 2 }} }},
                              glove = {{ replay = "{0}", hand = "left" }} }} }}
               p:capture{{}}"#,
            rec.display()
        ),
    )
    .unwrap();
    let (a, b) = (temp("a.trk"), temp("b.trk"));
    for (file, threads) in [(&a, "1"), (&b, "2")] {
        ok(troupe()
            .arg("run")
            .arg(&replay)
            .args([
                "--ticks",
                "100",
                "--threads",
                threads,
                "--chunk",
                "1",
                "--record",
            ])
            .arg(file));
    }
    assert_eq!(
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        "replays are identical"
    );
    // And the replayed performer moves: its root has a key on (nearly) every tick.
    let info = ok(troupe().args(["seq", "info"]).arg(&a));
    let keys: usize = info
        .lines()
        .find(|l| l.trim_start().starts_with("root_x"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|k| k.parse().ok())
        .unwrap();
    assert!(keys > 50, "root_x has {keys} keys:\n{info}");
}

#[test]
fn run_sends_poses_and_events_over_osc() {
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    sock.set_read_timeout(Some(std::time::Duration::from_secs(10)))
        .unwrap();
    let port = sock.local_addr().unwrap().port();
    let scene = temp("osc.lua");
    std::fs::write(
        &scene,
        r#"local a = troupe.actor{ name = "ann" } a:look_at{ target = {1, 1.6, 1} }"#,
    )
    .unwrap();
    ok(troupe().arg("run").arg(&scene).args([
        "--ticks",
        "3",
        "--osc-out",
        &format!("127.0.0.1:{port}"),
    ]));
    let mut buf = vec![0u8; 65536];
    let mut addrs = Vec::new();
    while let Ok(n) = sock.recv(&mut buf) {
        // A datagram is a bundle of one actor's joints, or an event message.
        let (_, p) = rosc::decoder::decode_udp(&buf[..n]).unwrap();
        match p {
            rosc::OscPacket::Bundle(b) => {
                for c in b.content {
                    if let rosc::OscPacket::Message(m) = c {
                        assert_eq!(m.args.len(), 7);
                        addrs.push(m.addr);
                    }
                }
            }
            rosc::OscPacket::Message(m) => addrs.push(m.addr),
        }
        // Everything was sent before `run` returned: once data flows, a short wait is enough.
        sock.set_read_timeout(Some(std::time::Duration::from_millis(500)))
            .unwrap();
    }
    assert!(
        addrs.iter().any(|a| a == "/troupe/ann/r_elbow"),
        "{addrs:?}"
    );
    assert!(
        addrs.iter().any(|a| a == "/troupe/event"),
        "the look_at action's events are sent"
    );
}
