//! End-to-end tests of `troupe snapshot` and `troupe view` (headless, on this machine's
//! adapter).

mod common;

use common::{finishes, succeeds};
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
    succeeds(
        troupe()
            .args([
                "view",
                trk.to_str().unwrap(),
                "--frames",
                frames.to_str().unwrap(),
            ])
            .args(["--every", "25", "--size", "96x64"]),
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

/// Records 0.2 s of the greeting scene (ann and bob) to `out`.
fn record_greeting(out: &Path) {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/examples/greeting.lua");
    let status = troupe()
        .args(["run", scene, "--seconds", "0.2", "--record"])
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success());
}

#[test]
fn view_of_a_gltf_names_the_actor_recorded_whatever_the_file_is_called() {
    let dir = temp_dir("gltf-name");
    record_greeting(&dir.join("rec.glb"));
    let renamed = dir.join("renamed.glb");
    std::fs::copy(dir.join("rec.bob.glb"), &renamed).unwrap();
    succeeds(
        troupe()
            .arg("view")
            .arg(&renamed)
            .args([
                "--camera",
                "follow:bob",
                "--size",
                "64x48",
                "--every",
                "100",
            ])
            .args(["--look", "bones", "--no-msaa", "--frames"])
            .arg(dir.join("frames")),
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Each recording is read through a named pipe that gives its bytes once: a second read
/// of the file would wait for ever.
#[cfg(unix)]
#[test]
fn view_reads_a_recording_once() {
    let dir = temp_dir("read-once");
    record_greeting(&dir.join("rec.trk"));
    record_greeting(&dir.join("rec.bvh"));
    record_greeting(&dir.join("rec.glb"));
    for (file, ext) in [
        ("rec.trk", "trk"),
        ("rec.ann.bvh", "bvh"),
        ("rec.ann.glb", "glb"),
    ] {
        let bytes = std::fs::read(dir.join(file)).unwrap();
        let pipe = dir.join(format!("pipe.{ext}"));
        let made = Command::new("mkfifo").arg(&pipe).status().unwrap();
        assert!(made.success());
        let writer = {
            let pipe = pipe.clone();
            std::thread::spawn(move || std::fs::write(pipe, bytes))
        };
        let child = troupe()
            .arg("view")
            .arg(&pipe)
            .args(["--size", "48x32", "--every", "100", "--look", "bones"])
            .args(["--no-msaa", "--no-labels", "--frames"])
            .arg(dir.join(format!("frames-{ext}")))
            .stderr(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let out = finishes(child, 120, &format!("view of a .{ext} through a pipe"));
        assert!(
            out.status.success(),
            "{ext}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        writer.join().unwrap().unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Renders a scene of one actor named `name` with its label; the picture's bytes.
fn label_picture(dir: &Path, name: &str) -> Vec<u8> {
    let scene = dir.join("named.lua");
    std::fs::write(&scene, format!("troupe.actor{{ name = \"{name}\" }}\n")).unwrap();
    let png = dir.join("named.png");
    succeeds(
        troupe()
            .arg("render")
            .arg(&scene)
            .arg(&png)
            // Far enough for the label and the marks above it to stand inside the picture.
            .args([
                "--size",
                "400x300",
                "--look",
                "bones",
                "--camera",
                "fit@0,10,8",
            ]),
    );
    std::fs::read(&png).unwrap()
}

#[test]
fn labels_draw_accented_letters() {
    let dir = temp_dir("accents");
    for (accented, plain) in [("Zoë", "Zoe"), ("José", "Jose"), ("Čapek", "Capek")] {
        let picture = label_picture(&dir, accented);
        // Not the `?` a letter the font lacks draws, and not the letter without its mark.
        let question = accented.replace(|c: char| !c.is_ascii(), "?");
        assert_ne!(picture, label_picture(&dir, &question), "{accented}");
        assert_ne!(picture, label_picture(&dir, plain), "{accented}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
