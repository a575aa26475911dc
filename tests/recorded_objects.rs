//! Objects in recordings, end to end: `troupe run --record` keeps every object's pose and
//! holders (`.trk`, glTF, BVH), and a recording played back (as `troupe view` does) moves
//! the objects with the actors' hands.

use std::path::{Path, PathBuf};
use std::process::Command;
use troupe_actions::keyframe::replay;
use troupe_formats::trk::{read_trk_file, TrkFile};
use troupe_scene::playback::ObjectPlayback;
use troupe_scene::{ActorDesc, RunLimit, Scene, SceneConfig, Session};

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY");
    c
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("troupe-objects-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Records the bundled hand-over (ann gives bob the cup) for 6 s to `out`.
fn record_handover(out: &Path) -> String {
    let o = troupe()
        .args([
            "run",
            "scripts/examples/handover.lua",
            "--seconds",
            "6",
            "--seed",
            "7",
        ])
        .arg("--record")
        .arg(out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    text
}

/// The recording played as `troupe view` plays it: a keyframe per actor and the objects
/// on their recorded poses. Returns, per tick, the distance from the cup to bob's right
/// wrist and whether it is bob's hand that holds the cup by the recording.
fn play(file: &TrkFile, until: f64) -> Vec<(f64, f64, bool)> {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    for seq in &file.sequences {
        let actor = scene.add_actor(&ActorDesc::new(seq.name.clone())).unwrap();
        replay(&mut scene, actor, seq, Some(false)).unwrap();
    }
    let playback = ObjectPlayback::install(&mut scene, file.objects.clone()).unwrap();
    assert_eq!(playback.len(), 2);
    let mut session = Session::new(scene);
    session.add_input(Box::new(playback));
    let cup = file.objects.iter().find(|o| o.name == "cup").unwrap();
    let mut out = Vec::new();
    in_step(&session, file);
    while session.scene().time() < until {
        session
            .run(RunLimit {
                ticks: 1,
                until_idle: false,
            })
            .unwrap();
        let scene = session.scene();
        let bob = scene.actors().iter().position(|a| a.name == "bob").unwrap();
        let wrist = scene.actors()[bob].skeleton.joint("r_wrist").unwrap();
        let hand = scene.states()[bob].globals[wrist].translation;
        let object = scene.objects().iter().find(|o| o.name == "cup").unwrap();
        let t = scene.time();
        let held = cup.holder_at(t).is_some_and(|h| h.actor == "bob");
        out.push((t, (object.position - hand).length(), held));
        in_step(&session, file);
    }
    out
}

/// Checks that every actor of the session shows the posture its recording has at the
/// scene's time, and every object its recorded pose: the replay is in step with the run
/// (it was one tick behind, and showed everyone at rest before the first tick).
fn in_step(session: &Session, file: &TrkFile) {
    let scene = session.scene();
    let t = scene.time();
    for (a, seq) in file.sequences.iter().enumerate() {
        let skeleton = &scene.actors()[a].skeleton;
        for track in seq.tracks() {
            let d = skeleton.dof(track.dof()).unwrap();
            let (got, want) = (scene.states()[a].q[d], track.value(t.min(seq.end())));
            assert!(
                (got - want).abs() < 1e-9,
                "{} at {t}: {got} against {want}",
                track.dof()
            );
        }
    }
    for motion in &file.objects {
        let object = scene
            .objects()
            .iter()
            .find(|o| o.name == motion.name)
            .unwrap();
        let (want, _) = motion.pose_at(t);
        assert!(
            (object.position - want).length() < 1e-9,
            "{} at {t}",
            motion.name
        );
    }
}

#[test]
fn a_recorded_hand_over_keeps_the_cup_and_who_held_it() {
    let dir = temp_dir("trk");
    let trk = dir.join("handover.trk");
    let text = record_handover(&trk);
    assert!(text.contains("and 2 object(s)"), "{text}");
    let file = read_trk_file(&trk).unwrap();
    let names: Vec<&str> = file.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["table", "cup"]);
    let cup = &file.objects[1];
    let holders: Vec<&str> = cup.holds.iter().map(|h| h.actor.as_str()).collect();
    assert_eq!(holders, ["ann", "bob"], "{:?}", cup.holds);
    assert!(cup.holds.iter().all(|h| h.joint == "r_wrist"));
    assert_eq!(
        cup.holds[0].to, cup.holds[1].from,
        "handed over in one tick"
    );

    // Played back, the cup stays in bob's hand: its distance to the wrist is the grip's,
    // constant while he holds it (a tick's lag between objects and actors would show).
    let ticks = play(&file, 6.0);
    let held: Vec<f64> = ticks.iter().filter(|t| t.2).map(|t| t.1).collect();
    assert!(held.len() > 100, "bob holds it for over a second");
    let (lo, hi) = held
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &d| (a.min(d), b.max(d)));
    assert!(
        hi - lo < 1e-6,
        "cup-to-wrist distance varies by {} m while held",
        hi - lo
    );
    assert!(hi < 0.15, "the cup is in the hand: {hi} m from the wrist");
    // Before the hand-over the cup is elsewhere (on the table, then in ann's hand).
    assert!(ticks[0].1 > 0.3, "{}", ticks[0].1);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn view_draws_a_recordings_objects_and_gltf_and_bvh_keep_them() {
    let dir = temp_dir("view");
    let trk = dir.join("handover.trk");
    record_handover(&trk);
    // The view of the recording differs from the view of its actors alone: the table
    // and the cup are drawn.
    let mut actors_only = read_trk_file(&trk).unwrap();
    actors_only.objects.clear();
    let bare = dir.join("bare.trk");
    troupe_formats::trk::write_trk_file(&bare, &actors_only).unwrap();
    let mut pictures = Vec::new();
    for (file, frames) in [(&trk, dir.join("with")), (&bare, dir.join("without"))] {
        let o = troupe()
            .arg("view")
            .arg(file)
            .args([
                "--seconds",
                "0.5",
                "--every",
                "50",
                "--size",
                "160x90",
                "--no-msaa",
            ])
            .args(["--camera", "fit"])
            .arg("--frames")
            .arg(&frames)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        pictures.push(std::fs::read(frames.join("frame_000000.png")).unwrap());
    }
    assert_ne!(pictures[0], pictures[1], "the objects are drawn");
    // glTF: a node per object; BVH: a file per object.
    let gltf = dir.join("handover.gltf");
    record_handover(&gltf);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("handover.ann.gltf")).unwrap())
            .unwrap();
    let cup = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == "cup")
        .expect("a cup node");
    assert_eq!(cup["extras"]["troupe_object"]["held"][1]["actor"], "bob");
    record_handover(&dir.join("handover.bvh"));
    for name in ["ann", "bob", "table", "cup"] {
        assert!(dir.join(format!("handover.{name}.bvh")).is_file(), "{name}");
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn names_that_are_not_plain_words_are_recorded_and_read_back() {
    // Lua refuses only `/`, `\` and control characters in a name: spaces, `#`, accents
    // and a name with spaces around it beside the same name without are all recorded.
    let dir = temp_dir("names");
    let scene = dir.join("names.lua");
    std::fs::write(
        &scene,
        r#"local ann = troupe.actor{ name = "Ann Lee" }
troupe.actor{ name = "take#2", at = {1, 0, 0} }
troupe.actor{ name = " lead ", at = {2, 0, 0} }
troupe.actor{ name = "lead", at = {3, 0, 0} }
troupe.object{ name = "table", shape = "box", size = {0.6, 0.95, 0.3}, at = {-0.45, 0.475, 0.45}, mass = 20 }
local cup = troupe.object{ name = "cup é", shape = "cylinder", radius = 0.035, height = 0.1, at = {-0.2, 1.0, 0.38} }
ann:behave(function(self) self:grasp{ object = cup, hand = "right" }:wait(); wait(0.2) end)
"#,
    )
    .unwrap();
    let trk = dir.join("names.trk");
    let o = troupe()
        .arg("run")
        .arg(&scene)
        .arg("--record")
        .arg(&trk)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = read_trk_file(&trk).unwrap();
    let actors: Vec<&str> = file.sequences.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(actors, ["Ann Lee", "take#2", " lead ", "lead"]);
    let objects: Vec<&str> = file.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(objects, ["table", "cup é"]);
    let holders: Vec<&str> = file.objects[1]
        .holds
        .iter()
        .map(|h| h.actor.as_str())
        .collect();
    assert_eq!(holders, ["Ann Lee"]);
    // `troupe view` plays it: every actor by its name, the cup in Ann Lee's hand.
    let o = troupe()
        .arg("view")
        .arg(&trk)
        .args(["--seconds", "0.1", "--size", "160x90", "--no-msaa"])
        .arg("--frames")
        .arg(dir.join("frames"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(dir).ok();
}
