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
