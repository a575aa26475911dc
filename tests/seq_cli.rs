//! End-to-end: the `troupe seq` commands on the shared BVH files.

use std::path::PathBuf;
use std::process::Command;
use troupe_body::glam::{DQuat, DVec3};
use troupe_formats::bvh::read_bvh;

fn shared(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/bvh")).join(name)
}

fn troupe(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_troupe"))
        .args(args)
        .output()
        .expect("run troupe");
    assert!(
        out.status.success(),
        "troupe {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-seq-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn convert_to_another_order_and_back_keeps_every_position() {
    for (file, there, back) in [
        ("pybvhrepo_cmu_12_01_walk.bvh", "XYZ", "ZYX"),
        ("pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh", "ZXY", "XYZ"),
        ("pybvhrepo_rotation_first_root.bvh", "YZX", "ZXY"),
    ] {
        let input = shared(file);
        let a = temp(&format!("{there}-{file}"));
        let b = temp(&format!("{back}-{file}"));
        let s = |p: &PathBuf| p.display().to_string();
        troupe(&[
            "seq",
            "convert",
            &s(&input),
            &s(&a),
            "--rotation-order",
            there,
        ]);
        troupe(&["seq", "convert", &s(&a), &s(&b), "--rotation-order", back]);
        let (orig, round) = (read_bvh(&input).unwrap(), read_bvh(&b).unwrap());
        assert_eq!(orig.frame_count(), round.frame_count());
        let mut worst: f64 = 0.0;
        for k in 0..orig.frame_count() {
            for (p, q) in orig.joint_positions(k).iter().zip(round.joint_positions(k)) {
                worst = worst.max((*p - q).length());
            }
        }
        assert!(worst < 1e-6, "{file}: {worst}");
    }
}

#[test]
fn compress_reports_and_respects_the_tolerance() {
    let out = temp("walk_c.trk");
    let text = troupe(&[
        "seq",
        "compress",
        &shared("pybvhrepo_cmu_12_01_walk.bvh").display().to_string(),
        &out.display().to_string(),
        "--tolerance",
        "0.01",
    ]);
    assert!(text.contains("keys before: 50304"), "{text}");
    let err: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("max error:"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|x| x.parse().ok())
        .unwrap();
    assert!(err <= 0.01, "{text}");
    let info = troupe(&["seq", "info", &out.display().to_string(), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(v["sequences"][0]["tracks"].as_array().unwrap().len(), 96);
}

#[test]
fn info_prints_positions_as_json() {
    let text = troupe(&[
        "seq",
        "info",
        &shared("pybvhrepo_rotation_first_root.bvh")
            .display()
            .to_string(),
        "--frame",
        "2",
        "--positions",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["frames"], 4);
    assert_eq!(v["positions"].as_array().unwrap().len(), 4);
    assert_eq!(v["positions"][0]["position"][0], 12.0);
}

#[test]
fn a_trk_converts_to_bvh_and_gltf_on_a_template_and_back() {
    let wave = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scripts/examples/wave.trk"
    ));
    let bvh = temp("wave-adult.bvh");
    let gltf = temp("wave-adult.gltf");
    let back = temp("wave-back.trk");
    let s = |p: &PathBuf| p.display().to_string();
    troupe(&["seq", "convert", &s(&wave), &s(&bvh), "--template", "adult"]);
    troupe(&[
        "seq",
        "convert",
        &s(&wave),
        &s(&gltf),
        "--template",
        "adult",
    ]);
    assert!(
        gltf.with_extension("bin").is_file()
            || std::fs::read_to_string(&gltf).unwrap().contains("base64")
    );
    troupe(&["seq", "convert", &s(&bvh), &s(&back), "--template", "adult"]);
    let original = &troupe_formats::load_sequences(&wave, None).unwrap()[0];
    let again = &troupe_formats::load_sequences(&back, None).unwrap()[0];
    // At the BVH's frames (the .trk's key times) every driven DOF comes back.
    for track in original.tracks() {
        let other = again
            .track(track.dof())
            .unwrap_or_else(|| panic!("{} came back", track.dof()));
        for key in track.keys() {
            let (a, b) = (track.value(key.time), other.value(key.time));
            assert!(
                (a - b).abs() < 1e-4,
                "{} at {}: {a} → {b}",
                track.dof(),
                key.time
            );
        }
    }
}

#[test]
fn a_tall_actors_bvh_converts_onto_a_default_adult_with_its_feet_on_the_floor() {
    let wave = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scripts/examples/wave.trk"
    ));
    let tall = temp("wave-tall.bvh");
    let back = temp("wave-tall-back.trk");
    let s = |p: &PathBuf| p.display().to_string();
    let (from, to) = (s(&wave), s(&tall));
    troupe(&[
        "seq",
        "convert",
        &from,
        &to,
        "--template",
        "adult",
        "--height",
        "1.95",
    ]);
    let (template, height) =
        troupe_formats::retarget::recorded_body(&read_bvh(&tall).unwrap()).unwrap();
    assert_eq!(template, "adult");
    assert!((height - 1.95).abs() < 1e-9, "{height}");
    troupe(&[
        "seq",
        "convert",
        &s(&tall),
        &s(&back),
        "--template",
        "adult",
    ]);
    let again = &troupe_formats::load_sequences(&back, None).unwrap()[0];
    assert_eq!(again.meta["template"], "adult");
    assert_eq!(again.meta["height"], "1.75");
    // A .trk converted again keeps the body it was made for (it took the default).
    let tall_trk = temp("wave-tall.trk");
    let bvh_again = temp("wave-tall-again.bvh");
    troupe(&[
        "seq",
        "convert",
        &from,
        &s(&tall_trk),
        "--template",
        "adult",
        "--height",
        "1.95",
    ]);
    troupe(&[
        "seq",
        "convert",
        &s(&tall_trk),
        &s(&bvh_again),
        "--template",
        "adult",
    ]);
    let (_, kept) =
        troupe_formats::retarget::recorded_body(&read_bvh(&bvh_again).unwrap()).unwrap();
    assert!(
        (kept - 1.95).abs() < 1e-9,
        "the .trk's 1.95 m body, got {kept}"
    );
    // The wave leaves the root where it stands: on the default adult too, root_y = 0,
    // not the 0.11 m the tall body's root stands higher.
    for key in again.track("root_y").unwrap().keys() {
        assert!(
            key.value.abs() < 1e-9,
            "root_y {} at {}",
            key.value,
            key.time
        );
    }
}

#[test]
fn info_names_each_tracks_interpolation() {
    let file = temp("interpolations.trk");
    std::fs::write(
        &file,
        "troupe-trk 2\ntrack a\n0 0\n1 1\nend\ntrack b step\n0 0\n1 1\nend\n",
    )
    .unwrap();
    let path = file.display().to_string();
    let v: serde_json::Value =
        serde_json::from_str(&troupe(&["seq", "info", &path, "--json"])).unwrap();
    let tracks = &v["sequences"][0]["tracks"];
    assert_eq!(tracks[0]["interpolation"], "cubic");
    assert_eq!(tracks[1]["interpolation"], "step");
    let text = troupe(&["seq", "info", &path]);
    assert!(text.contains("2 keys, step"), "{text}");
}

/// The JSON chunk of a binary glTF file.
fn glb_json(path: &PathBuf) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

#[test]
fn a_z_up_bvh_converts_to_an_upright_gltf() {
    // pybvh's example is Z up and faces +Y: its root node is turned so that the file's
    // +Z is glTF's +Y and its +Y glTF's +Z (the body faces +Z, as glTF asks).
    let s = |p: &PathBuf| p.display().to_string();
    let glb = temp("zup.glb");
    let out = troupe(&[
        "seq",
        "convert",
        &s(&shared("pybvhrepo_bvh_example.bvh")),
        &s(&glb),
    ]);
    assert!(
        out.contains("the file's up +Z and forward +Y became +Y and +Z"),
        "{out}"
    );
    let doc = glb_json(&glb);
    let root = doc["scenes"][0]["nodes"][0].as_u64().unwrap() as usize;
    let q: Vec<f64> = doc["nodes"][root]["rotation"]
        .as_array()
        .expect("a turned root")
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let turn = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
    for (file_axis, gltf_axis) in [(DVec3::Z, DVec3::Y), (DVec3::Y, DVec3::Z)] {
        let got = turn * file_axis;
        assert!((got - gltf_axis).length() < 1e-6, "{file_axis} → {got}");
    }
    // A Y-up file facing +Z (CMU) is written as it is.
    let glb = temp("walk.glb");
    let out = troupe(&[
        "seq",
        "convert",
        &s(&shared("pybvhrepo_cmu_12_01_walk.bvh")),
        &s(&glb),
        "--scale",
        "0.056444",
    ]);
    assert!(!out.contains("turned"), "{out}");
    let doc = glb_json(&glb);
    assert!(
        doc["nodes"][0].get("rotation").is_none(),
        "{}",
        doc["nodes"][0]
    );
}

/// Runs troupe expecting it to fail; returns its stderr.
fn fails(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_troupe"))
        .args(args)
        .output()
        .expect("run troupe");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "troupe {args:?} succeeded: {err}");
    err
}

#[test]
fn plot_refuses_a_width_out_of_range_naming_the_range() {
    let wave = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/examples/wave.trk");
    let png = temp("narrow.png");
    for width in ["100", "9000"] {
        let err = fails(&[
            "seq",
            "plot",
            wave,
            &png.display().to_string(),
            "--width",
            width,
        ]);
        assert!(err.contains("200..=8000"), "{width}: {err}");
    }
    troupe(&[
        "seq",
        "plot",
        wave,
        &png.display().to_string(),
        "--width",
        "200",
    ]);
}

#[test]
fn warp_keeps_the_rate_true() {
    let rated = temp("rated.trk");
    std::fs::write(
        &rated,
        "troupe-trk 1\nsequence s\nmeta rate 100\ntrack r_elbow_flexion\n0 0\n0.01 0.1\n0.02 0.3\n0.03 0.2\nend\n",
    )
    .unwrap();
    let s = |p: &PathBuf| p.display().to_string();
    let rate = |p: &PathBuf| {
        let v: serde_json::Value =
            serde_json::from_str(&troupe(&["seq", "info", &s(p), "--json"])).unwrap();
        v["sequences"][0]["meta"]["rate"]
            .as_str()
            .map(str::to_string)
    };
    // Twice as slow: the keys are 0.02 s apart, 50 Hz.
    let slow = temp("slow.trk");
    let text = troupe(&["seq", "warp", &s(&rated), &s(&slow), "--map", "0:0,1:2"]);
    assert!(text.contains("rate 100 Hz -> 50 Hz"), "{text}");
    assert_eq!(rate(&slow).as_deref(), Some("50"));
    // Unevenly warped keys have no rate.
    let uneven = temp("uneven.trk");
    let text = troupe(&[
        "seq",
        "warp",
        &s(&rated),
        &s(&uneven),
        "--squeeze",
        "0:0.01:0.03:0.02",
    ]);
    assert!(text.contains("rate 100 Hz dropped"), "{text}");
    assert_eq!(rate(&uneven), None);
}

/// A recording of two actors (ann, bob) and the table of the greeting scene.
fn greeting_recording(name: &str) -> PathBuf {
    let trk = temp(name);
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/examples/greeting.lua");
    let s = trk.display().to_string();
    troupe(&["run", scene, "--seconds", "0.2", "--record", &s]);
    trk
}

#[test]
fn convert_of_a_recording_writes_every_actor_or_the_one_asked() {
    let trk = greeting_recording("two.trk");
    let s = |p: &PathBuf| p.display().to_string();
    let file = |p: &PathBuf| troupe_formats::trk::read_trk_file(p).unwrap();
    // To .trk: every actor and object (only the first actor was kept).
    let copy = temp("two-copy.trk");
    troupe(&["seq", "convert", &s(&trk), &s(&copy)]);
    let (before, after) = (file(&trk), file(&copy));
    let names = |f: &troupe_formats::trk::TrkFile| -> Vec<String> {
        f.sequences.iter().map(|q| q.name.clone()).collect()
    };
    assert_eq!(names(&after), ["ann", "bob"]);
    assert_eq!(after.objects.len(), before.objects.len());
    // To glTF on a template: one file per actor, as `run --record` writes them.
    let glb = temp("two.glb");
    let text = troupe(&["seq", "convert", &s(&trk), &s(&glb), "--template", "adult"]);
    for actor in ["ann", "bob"] {
        let one = glb.with_file_name(format!("two.{actor}.glb"));
        assert!(one.is_file() && text.contains(&s(&one)), "{text}");
    }
    // --actor chooses one; an actor the file lacks is refused, naming those there are.
    let bob = temp("bob.trk");
    troupe(&["seq", "convert", &s(&trk), &s(&bob), "--actor", "bob"]);
    assert_eq!(names(&file(&bob)), ["bob"]);
    let err = fails(&["seq", "convert", &s(&trk), &s(&bob), "--actor", "cleo"]);
    assert!(err.contains("no actor `cleo` (actors: ann, bob)"), "{err}");
    // Any seq command, on a recording of one actor too: the one named or an error (it
    // went on with the only actor there, saying nothing); a BVH holds one motion.
    let plot = temp("bob.png");
    let err = fails(&["seq", "--actor", "ann", "plot", &s(&bob), &s(&plot)]);
    assert!(err.contains("no actor `ann` (actors: bob)"), "{err}");
    let bvh = temp("bob.bvh");
    troupe(&["seq", "convert", &s(&bob), &s(&bvh), "--template", "adult"]);
    let err = fails(&["seq", "--actor", "bob", "plot", &s(&bvh), &s(&plot)]);
    assert!(
        err.contains("is a BVH file, which holds one motion"),
        "{err}"
    );
}

#[test]
fn convert_refuses_a_map_on_an_input_other_than_bvh() {
    let trk = greeting_recording("mapped.trk");
    let s = |p: &PathBuf| p.display().to_string();
    let map = temp("mine.map");
    std::fs::write(&map, "Hips HumanoidRoot\n").unwrap();
    let glb = temp("mapped.glb");
    troupe(&[
        "seq",
        "convert",
        &s(&trk),
        &s(&glb),
        "--template",
        "adult",
        "--actor",
        "ann",
    ]);
    // A retargeting map names BVH joints: on a recording or a glTF it was ignored.
    for (input, kind) in [(&trk, ".trk"), (&glb, "glTF")] {
        let out = temp("mapped-out.trk");
        let err = fails(&[
            "seq",
            "convert",
            &s(input),
            &s(&out),
            "--template",
            "adult",
            "--map",
            &s(&map),
        ]);
        assert!(
            err.contains(&format!(
                "--map {}: a retargeting map applies to a BVH input, and {} is a {kind} file",
                s(&map),
                s(input)
            )),
            "{err}"
        );
    }
    // A BVH converted without a template to BVH or a recording does not read it either.
    let bvh = shared("pybvhrepo_cmu_12_01_walk.bvh");
    for out in [temp("mapped-out.bvh"), temp("mapped-out2.trk")] {
        let err = fails(&["seq", "convert", &s(&bvh), &s(&out), "--map", &s(&map)]);
        assert!(
            err.contains("a retargeting map is read with --template, or for a BVH written to glTF"),
            "{err}"
        );
    }
}

#[test]
fn blend_of_different_skeletons_says_what_it_cannot_blend() {
    let (a, b) = (
        shared("pybvhrepo_cmu_12_01_walk.bvh"),
        shared("pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh"),
    );
    let s = |p: &PathBuf| p.display().to_string();
    let blend = |out: &PathBuf| {
        Command::new(env!("CARGO_BIN_EXE_troupe"))
            .args([
                "seq",
                "blend",
                &s(&a),
                &s(&b),
                &s(out),
                "--at",
                "0.5",
                "--over",
                "0.3",
            ])
            .output()
            .unwrap()
    };
    // A BVH written on the first file's hierarchy cannot hold the second's thumbs.
    let out = blend(&temp("mixed.bvh"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("has no channel for 12 track(s): LeftHandThumb1.Xrotation"),
        "{err}"
    );
    // A .trk holds every track; those only one file has are named, unblended.
    let out = blend(&temp("mixed.trk"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("36 track(s) the other sequence lacks, kept unblended: LHipJoint"),
        "{err}"
    );
    // Sequences sharing no track have nothing to blend.
    let wave = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scripts/examples/wave.trk"
    ));
    let err = fails(&[
        "seq",
        "blend",
        &s(&a),
        &s(&wave),
        &s(&temp("none.trk")),
        "--at",
        "0",
        "--over",
        "1",
    ]);
    assert!(err.contains("share no track: nothing to blend"), "{err}");
}
