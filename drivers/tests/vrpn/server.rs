//! The real VRPN server for tests: built once from the vendored source by
//! `scripts/vrpn-server.sh` (cached under the target folder), started on a free loopback
//! port with a config the test writes, killed when dropped.

use std::net::{TcpListener, UdpSocket};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The built `vrpn_server`, built on first use.
pub fn server_binary() -> PathBuf {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        // The workspace root holds scripts/: the manifest's folder or one above it.
        let script = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .ancestors()
            .map(|d| d.join("scripts/vrpn-server.sh"))
            .find(|p| p.exists())
            .expect("scripts/vrpn-server.sh");
        let out = Command::new("bash")
            .arg(&script)
            .stderr(Stdio::inherit())
            .output()
            .expect("running scripts/vrpn-server.sh");
        assert!(
            out.status.success(),
            "scripts/vrpn-server.sh failed (run scripts/setup.sh for cmake and g++)"
        );
        PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
    })
    .clone()
}

/// A port free for both TCP and UDP on the loopback (the server listens on both).
pub fn free_port() -> u16 {
    loop {
        let t = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = t.local_addr().unwrap().port();
        if UdpSocket::bind(("127.0.0.1", port)).is_ok() {
            return port;
        }
    }
}

/// A running `vrpn_server`.
pub struct Server {
    child: Child,
    config: PathBuf,
}

impl Server {
    /// Starts the server on `port` with the config lines given; returns once it accepts
    /// TCP connections.
    pub fn start(port: u16, config: &str) -> Server {
        let bin = server_binary();
        let dir = std::env::temp_dir().join(format!("troupe-vrpn-{}-{port}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cfg = dir.join("vrpn.cfg");
        std::fs::write(&cfg, config).unwrap();
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
        let s = Server { child, config: dir };
        let start = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "vrpn_server did not start"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        s
    }

    /// Kills the server at once (SIGKILL: no goodbye to its clients).
    #[allow(dead_code)] // this module is shared by test crates that do not all kill it
    pub fn kill(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.stop();
        let _ = std::fs::remove_dir_all(&self.config);
    }
}
