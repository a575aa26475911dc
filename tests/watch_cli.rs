//! `troupe run --watch`: only with `--view`, and without the outputs a reload would split.
//! (The reload itself is tested headless in src/watch.rs.)

use std::process::Command;

fn run(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_troupe"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn watch_needs_view_and_refuses_recordings() {
    let scene = "scripts/examples/greeting.lua";
    let (ok, err) = run(&["run", scene, "--watch"]);
    assert!(!ok && err.contains("--view"), "{err}");
    let (ok, err) = run(&["run", scene, "--view", "--watch", "--record", "x.trk"]);
    assert!(!ok && err.contains("--record"), "{err}");
    let (ok, err) = run(&["run", scene, "--view", "--watch"]);
    assert!(!ok && err.contains("needs a display"), "{err}");
}
