//! VRPN through the command line, against the real VRPN server: `troupe devices probe vrpn`
//! (text and JSON, and a server that never answers), `troupe run --record-devices` with a
//! VRPN performer, and its replay giving byte-identical recordings on 1 and 2 threads.

#[path = "../drivers/tests/vrpn/server.rs"]
mod server;

use server::{free_port, Server};
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-vrpncli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
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
fn probe_record_and_replay_a_vrpn_performer() {
    let port = free_port();
    let _server = Server::start(
        port,
        "vrpn_Tracker_Spin Spin0 2 100.0 0.0 1.0 0.0 0.25\nvrpn_Button_Example Button0 2 4.0\n",
    );
    let device = format!("Spin0@127.0.0.1:{port}");
    let text = ok(troupe().args([
        "devices",
        "probe",
        "vrpn",
        "--device",
        &device,
        "--samples",
        "5",
    ]));
    assert!(text.contains("Spin0 sensor 0 pos"), "{text}");
    let json = ok(troupe().args([
        "devices",
        "probe",
        "vrpn",
        "--device",
        &device,
        "--also",
        "Button0",
        "--samples",
        "40",
        "--json",
    ]));
    let lines: Vec<serde_json::Value> = json
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 40);
    assert!(lines.iter().all(|l| l["reading"]["kind"] == "vrpn"));
    assert!(lines.iter().any(|l| l["reading"]["message"] == "tracker"
        && l["reading"]["quaternion"].as_array().unwrap().len() == 4
        && l["reading"]["time"].as_f64().unwrap() > 1e9));

    let scene = temp("live.lua");
    let map = "map = { pelvis = 0, skullbase = 1 }";
    std::fs::write(
        &scene,
        format!(
            r#"local p = troupe.performer{{ name = "pat",
                 devices = {{ vrpn = {{ device = "{device}", buttons = "Button0", {map} }} }} }}
               p:capture{{}}"#
        ),
    )
    .unwrap();
    let rec = temp("pat.rec");
    let out = ok(troupe()
        .arg("run")
        .arg(&scene)
        .args(["--ticks", "150", "--realtime", "--record-devices"])
        .arg(&rec));
    assert!(out.contains("device pat.vrpn: streaming"), "{out}");
    assert!(out.contains("recorded the device streams"), "{out}");

    let replay = temp("replay.lua");
    std::fs::write(
        &replay,
        format!(
            r#"local p = troupe.performer{{ name = "pat",
                 devices = {{ vrpn = {{ replay = "{}", {map} }} }} }}
               p:capture{{}}
               troupe.devices.on_button("*", function(n, d) print(n, d) end)"#,
            rec.display()
        ),
    )
    .unwrap();
    let runs: Vec<(Vec<u8>, String)> = [("1", "0"), ("2", "1"), ("1", "0")]
        .iter()
        .enumerate()
        .map(|(i, (threads, chunk))| {
            let file = temp(&format!("r{i}.trk"));
            let mut c = troupe();
            c.arg("run")
                .arg(&replay)
                .args(["--ticks", "150", "--threads", threads]);
            if *chunk != "0" {
                c.args(["--chunk", chunk]);
            }
            let out = c.arg("--record").arg(&file).output().unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            (
                std::fs::read(&file).unwrap(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            )
        })
        .collect();
    assert!(
        runs[0].0 == runs[1].0 && runs[0].0 == runs[2].0,
        "replays are byte-identical"
    );
    let presses = |log: &str| log.lines().filter(|l| l.contains("Button0.")).count();
    assert!(
        presses(&runs[0].1) > 0,
        "button events replayed:\n{}",
        runs[0].1
    );
    assert_eq!(presses(&runs[0].1), presses(&runs[1].1));
}

#[test]
fn probe_reports_a_server_that_never_answers_within_its_timeout() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let hold = std::thread::spawn(move || {
        let conns: Vec<_> = listener.incoming().take(3).collect();
        std::thread::sleep(Duration::from_secs(4));
        drop(conns);
    });
    let start = Instant::now();
    let out = troupe()
        .args([
            "devices",
            "probe",
            "vrpn",
            "--device",
            &format!("T@127.0.0.1:{port}"),
            "--timeout",
            "1.5",
        ])
        .output()
        .unwrap();
    let took = start.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(took < Duration::from_millis(2500), "{took:?}");
    assert!(err.contains("no VRPN cookie within 0.8 s"), "{err}");
    drop(hold);
}

/// `troupe run scripts/examples/performer_vrpn.lua` with `threads` threads: what the scene
/// printed.
fn run_example(threads: &str) -> Vec<String> {
    let out = troupe()
        .args([
            "run",
            "scripts/examples/performer_vrpn.lua",
            "--seconds",
            "12",
        ])
        .args(["--threads", threads, "--chunk", "1"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "troupe run failed:\n{text}");
    text.lines()
        .filter_map(|l| l.split_once("lua: ").map(|(_, m)| m.to_string()))
        .collect()
}

#[test]
fn the_example_performer_tracked_over_vrpn_takes_the_cup() {
    let lines = run_example("1");
    assert!(lines.len() == 2, "{lines:?}");
    assert!(
        lines[0].starts_with("3.50 s: pat presses Wand0.0"),
        "{lines:?}"
    );
    assert!(
        lines[1].starts_with("give: completed, the cup is held by pat"),
        "{lines:?}"
    );
    assert_eq!(lines, run_example("2"), "the same with 2 threads");
}
