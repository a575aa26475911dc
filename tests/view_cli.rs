//! End-to-end tests of `troupe snapshot` and `troupe view` (headless, on this machine's
//! adapter).

use std::path::{Path, PathBuf};
use std::process::Command;

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    // Headless even when the developer has a display.
    c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY");
    c
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("troupe-view-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Width and height from a PNG header.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG", "{} is a PNG", path.display());
    let be = |o: usize| u32::from_be_bytes(bytes[o..o + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn snapshot_writes_a_png_of_posed_actors() {
    let dir = temp_dir("snapshot");
    let out = dir.join("pose.png");
    let status = troupe()
        .args(["snapshot", out.to_str().unwrap(), "--size", "200x120"])
        .args(["--pose", "r_shoulder_abduction=80,r_hand=secure"])
        .args(["--pose", "l_knee_flexion=40,at=1:-1,facing=30", "--bones"])
        .args(["--camera", "fit@-20,15"])
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(png_size(&out), (200, 120));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn snapshot_rejects_bad_poses_and_cameras_with_a_message() {
    for args in [
        vec!["--pose", "no_such_dof=3"],
        vec!["--pose", "r_hand=sticky"],
        vec!["--camera", "orbit"],
        vec!["--size", "12"],
    ] {
        let out = troupe()
            .args(["snapshot", "/nonexistent/never.png"])
            .args(&args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.starts_with("troupe: "), "{args:?}: {err}");
    }
    // Following an actor the scene lacks is refused, as `render` does (it silently used
    // the default camera).
    let out = troupe()
        .args([
            "snapshot",
            "/nonexistent/never.png",
            "--camera",
            "follow:nobody",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("the scene has no actor `nobody` (actors: ann)"),
        "{err}"
    );
}

#[test]
fn view_plays_a_recording_headless_into_frames() {
    let dir = temp_dir("view");
    let trk = dir.join("wave.trk");
    std::fs::write(
        &trk,
        "troupe-trk 1\nsequence wave\ntrack r_shoulder_abduction\n0 0\n0.5 2.4\n1 0\nend\n",
    )
    .unwrap();
    let frames = dir.join("frames");
    let out = troupe()
        .args([
            "view",
            trk.to_str().unwrap(),
            "--frames",
            frames.to_str().unwrap(),
        ])
        .args(["--every", "25", "--size", "96x64"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // 1 s at 100 Hz: ticks 0, 25, 50, 75, 100.
    let mut names: Vec<_> = std::fs::read_dir(&frames)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        (0..5)
            .map(|i| format!("frame_{i:06}.png"))
            .collect::<Vec<_>>()
    );
    assert_eq!(png_size(&frames.join("frame_000004.png")), (96, 64));
    // Different poses give different pictures.
    let a = std::fs::read(frames.join("frame_000000.png")).unwrap();
    let b = std::fs::read(frames.join("frame_000002.png")).unwrap();
    assert_ne!(a, b);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn view_refuses_unknown_formats() {
    let out = troupe().args(["view", "walk.fbx"]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("motion files with `.fbx` (use .trk, .bvh, .gltf or .glb)"),
        "{err}"
    );
    // So is a camera following an actor the recording lacks.
    let dir = temp_dir("view-camera");
    let trk = dir.join("wave.trk");
    std::fs::write(
        &trk,
        "troupe-trk 1\nsequence wave\ntrack r_shoulder_abduction\n0 0\n1 0\nend\n",
    )
    .unwrap();
    let out = troupe()
        .args(["view", trk.to_str().unwrap(), "--frames"])
        .arg(dir.join("frames"))
        .args(["--camera", "follow:nobody"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("the scene has no actor `nobody` (actors: wave)"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    // A known format that is missing names the file.
    let out = troupe().args(["view", "walk.gltf"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("walk.gltf"));
}
