//! Measures a VRPN performer against the real VRPN server: sample-to-posture latency (from
//! the arrival of the newest report a tick uses to the end of that tick's step, ticks paced
//! at 100 Hz in real time) and reconnection time (from a restarted server accepting again
//! to the first report after it).
//!
//! Run (release, as recorded in docs/PERFORMANCE.md):
//! `cargo run --release -p troupe-drivers --example vrpn_latency -- "$(scripts/vrpn-server.sh)"`

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use troupe_drivers::performer::median_p99;
use troupe_lua::{Director, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

const CONFIG: &str = "vrpn_Tracker_Spin Spin0 3 100.0 0.0 1.0 0.0 0.25\n";

fn start(bin: &str, cfg: &std::path::Path, port: u16) -> (Child, Instant) {
    let child = Command::new(bin)
        .args([
            "-f",
            cfg.to_str().unwrap(),
            "-millisleep",
            "1",
            &port.to_string(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("starting vrpn_server");
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        std::thread::sleep(Duration::from_millis(1));
    }
    (child, Instant::now())
}

fn main() {
    let bin = std::env::args().nth(1).expect("give the vrpn_server path");
    let port = 39_883;
    let dir = std::env::temp_dir().join(format!("troupe-vrpn-latency-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("vrpn.cfg");
    std::fs::write(&cfg, CONFIG).unwrap();
    let (mut server, _) = start(&bin, &cfg, port);

    let config = SceneConfig {
        rate: 100.0,
        threads: 1,
        seed: 0,
    };
    let mut d = Director::session(
        config,
        troupe_actions::action_kinds(),
        ScriptLimits::default(),
    )
    .unwrap();
    let perf = troupe_drivers::lua::install(&mut d, None)
        .unwrap()
        .performers;
    d.load_str(
        &format!(
            r#"pat = troupe.performer{{ name = "pat", devices = {{ vrpn = {{
                 device = "Spin0@127.0.0.1:{port}", map = {{ pelvis = 0, r_wrist = 1, l_wrist = 2 }} }} }} }}
               pat:capture{{}}"#
        ),
        "latency",
    )
    .unwrap();
    let period = Duration::from_millis(10);
    let mut next = Instant::now();
    let mut tick = |d: &mut troupe_lua::LuaSession| {
        d.tick().unwrap();
        perf.0.lock().unwrap().end_tick();
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        } else {
            next = Instant::now();
        }
    };
    // Warm up (connection, calibration), then measure 20 s.
    for _ in 0..100 {
        tick(&mut d);
    }
    perf.0.lock().unwrap().latencies.clear();
    for _ in 0..2000 {
        tick(&mut d);
    }
    let lat = perf.0.lock().unwrap().latencies.clone();
    let (m, p99) = median_p99(&lat).unwrap();
    println!(
        "sample-to-posture: median {:.2} ms, p99 {:.2} ms over {} ticks that used a report",
        m * 1e3,
        p99 * 1e3,
        lat.len()
    );

    // Reconnection: kill, leave the server down for `down`, restart, time the first report.
    let samples = || perf.0.lock().unwrap().health()[0].2.samples;
    for down in [0.2, 1.0, 3.0] {
        let mut times = Vec::new();
        for _ in 0..5 {
            let _ = server.kill();
            let _ = server.wait();
            let until = Instant::now() + Duration::from_secs_f64(down);
            while Instant::now() < until {
                tick(&mut d);
            }
            let before = samples();
            let (s, accepting) = start(&bin, &cfg, port);
            server = s;
            while samples() == before {
                tick(&mut d);
            }
            times.push(accepting.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        println!(
            "reconnection after {down} s down: median {:.0} ms, max {:.0} ms (5 restarts)",
            times[2] * 1e3,
            times[4] * 1e3
        );
    }
    let _ = server.kill();
    let _ = server.wait();
    let _ = std::fs::remove_dir_all(&dir);
}
