//! The glTF files troupe writes pass the Khronos glTF validator with no error and no
//! warning: a troupe body's motion with its skin (adult and child), with and without a
//! recorded object, the skinned characters `troupe export gltf` writes (a one-frame rest
//! pose), users' characters (CesiumMan, CesiumMan as a VRM 1.0 file, and the VRM 1.0
//! sample of the test assets given a box per bone as its skin) moving with an
//! object, in troupe's rest posture and in their bind pose, and a BVH on its own
//! hierarchy (a Z-up one turned to glTF's axes, and a BVH of two hierarchies), as `.gltf` + `.bin` and as `.glb`; `.gltf` files whose `.bin` name holds
//! characters a URI encodes (`%`, `#`, a space, non-ASCII).
//!
//! The validator is the npm package `gltf-validator`, which `scripts/setup.sh` installs
//! into `.tools/node`; without node or without that package the test prints why and
//! checks nothing.

use std::path::{Path, PathBuf};
use std::process::Command;
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::skin::SkinLibrary;
use troupe_body::solid::Shape;
use troupe_body::template::{template, TemplateParams};
use troupe_body::{Skeleton, Skin};
use troupe_formats::bvh::{parse_bvh, read_bvh};
use troupe_formats::character::read_character;
use troupe_formats::gltf::{
    write_character, write_glb, write_glb_with, write_gltf, write_gltf_with,
};
use troupe_formats::retarget::{bvh_axes, RetargetMap};
use troupe_formats::Rig;
use troupe_motion::object_motion::{Hold, ObjectMotion};
use troupe_motion::sequence::{Key, Sequence, Track};

mod characters;
use characters::{as_vrm, asset, cesium_map, vrm_with_boxes};

/// Two hierarchies in one BVH file (`ROOT A` and `ROOT B`).
const TWO_ROOTS: &str = "HIERARCHY
ROOT A
{
OFFSET 0 0 0
CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
End Site
{
OFFSET 0 5 0
}
}
ROOT B
{
OFFSET 10 0 0
CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
JOINT C
{
OFFSET 0 5 0
CHANNELS 3 Zrotation Xrotation Yrotation
End Site
{
OFFSET 0 5 0
}
}
}
MOTION
Frames: 2
Frame Time: 0.1
0 0 0 0 0 0 10 0 0 0 0 0 0 0 0
1 0 0 0 0 90 10 0 0 90 0 0 45 0 0
";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn body(name: &str) -> Skeleton {
    let t = template(name).unwrap();
    t.instantiate(t.default_params()).unwrap()
}

/// A troupe body waving and walking forward, a knee raised, the head nodding (the
/// skin's sliding helpers at the hip, knee, elbow and skullbase move as well as turn).
fn troupe_rig(skeleton: &Skeleton) -> Rig {
    let mut seq = Sequence::new("wave");
    seq.meta.insert("rate".into(), "30".into());
    for (dof, v) in [
        ("r_shoulder_abduction", 1.4),
        ("r_elbow_flexion", 0.9),
        ("l_hip_flexion", 1.6),
        ("l_knee_flexion", 1.4),
        ("skullbase_flexion", 0.6),
        ("root_z", 0.5),
    ] {
        let keys = vec![Key::new(0.0, 0.0), Key::new(0.5, v), Key::new(1.0, 0.0)];
        seq.add_track(Track::new(dof, keys).unwrap()).unwrap();
    }
    Rig::from_sequence(skeleton, &seq).unwrap()
}

#[test]
fn written_gltf_files_pass_the_khronos_validator() {
    let modules = repo().join(".tools/node/node_modules");
    if Command::new("node").arg("--version").output().is_err() {
        println!("skipped: node is not installed, so the Khronos glTF validator cannot run");
        return;
    }
    if !modules.join("gltf-validator").is_dir() {
        println!(
            "skipped: the Khronos glTF validator is not installed (scripts/setup.sh installs it into {})",
            modules.display()
        );
        return;
    }
    let dir = std::env::temp_dir().join(format!("troupe-khronos-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bvh = read_bvh(repo().join("../shared/data/bvh/pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
    let mut files = Vec::new();
    let walk = Rig::from_bvh(&bvh, 0.056444);
    write_gltf(dir.join("walk.gltf"), &walk, "walk").unwrap();
    write_glb(dir.join("walk.glb"), &walk, "walk").unwrap();
    files.extend([dir.join("walk.gltf"), dir.join("walk.glb")]);
    // A Z-up BVH turned to glTF's axes, as `troupe seq convert` writes it.
    let zup = read_bvh(repo().join("../shared/data/bvh/pybvhrepo_bvh_example.bvh")).unwrap();
    let mut upright = Rig::from_bvh(&zup, 0.01);
    upright.turn(bvh_axes(&zup, &RetargetMap::detect(&zup)).unwrap().turn);
    write_gltf(dir.join("upright.gltf"), &upright, "upright").unwrap();
    write_glb(dir.join("upright.glb"), &upright, "upright").unwrap();
    files.extend([dir.join("upright.gltf"), dir.join("upright.glb")]);
    // A BVH of two hierarchies: its skin has no common root.
    let two = Rig::from_bvh(&parse_bvh(TWO_ROOTS, "two.bvh").unwrap(), 0.01);
    write_gltf(dir.join("two_roots.gltf"), &two, "two_roots").unwrap();
    write_glb(dir.join("two_roots.glb"), &two, "two_roots").unwrap();
    files.extend([dir.join("two_roots.gltf"), dir.join("two_roots.glb")]);
    for template in ["adult", "child"] {
        let skeleton = body(template);
        let skin = Skin::build(&skeleton).unwrap();
        let rest = Rig::from_sequence(&skeleton, &Sequence::new("rest")).unwrap();
        for (name, rig) in [("wave", troupe_rig(&skeleton)), ("rest", rest)] {
            let stem = format!("{template}_{name}");
            let gltf = dir.join(format!("{stem}.gltf"));
            let glb = dir.join(format!("{stem}.glb"));
            write_gltf_with(&gltf, &rig, Some(&skin), &[], &stem).unwrap();
            write_glb_with(&glb, &rig, Some(&skin), &[], &stem).unwrap();
            files.extend([gltf, glb]);
        }
    }
    // Other heights: the template's skin made once and scaled to each (`SkinLibrary`),
    // as the viewer and `run --record` use it.
    let mut library = SkinLibrary::default();
    for (template_name, height, mass) in [("adult", 1.6, 60.0), ("child", 1.05, 18.0)] {
        let skeleton = template(template_name)
            .unwrap()
            .instantiate(TemplateParams { height, mass })
            .unwrap();
        let skin = library.get(&skeleton).unwrap().to_skin();
        let stem = format!("{template_name}_{height}_wave");
        let glb = dir.join(format!("{stem}.glb"));
        write_glb_with(&glb, &troupe_rig(&skeleton), Some(&skin), &[], &stem).unwrap();
        files.push(glb);
    }
    // A recording with an object, as `run --record` writes it: the skinned body and one
    // more animated node, with extras.
    let skeleton = body("adult");
    let skin = Skin::build(&skeleton).unwrap();
    let rig = troupe_rig(&skeleton);
    let times = [0.0, 0.5, 1.0];
    let poses = times.map(|t| (DVec3::new(0.3, 1.0 + t, 0.2), DQuat::from_rotation_x(t)));
    let mut ball =
        ObjectMotion::from_samples("ball", Shape::Sphere { radius: 0.1 }, 0.4, &times, &poses)
            .unwrap();
    ball.holds.push(Hold {
        from: 0.2,
        to: 0.8,
        actor: "wave".into(),
        joint: "r_wrist".into(),
    });
    let objects = [(&ball, Rig::from_object(&ball, 0.0, &rig.times))];
    let gltf = dir.join("carry.gltf");
    let glb = dir.join("carry.glb");
    write_gltf_with(&gltf, &rig, Some(&skin), &objects, "carry").unwrap();
    write_glb_with(&glb, &rig, Some(&skin), &objects, "carry").unwrap();
    files.extend([gltf, glb]);
    // File names a URI must percent-encode: `%`, `#` (a fragment), a space, non-ASCII.
    for stem in ["G%20v1", "G.take#2", "cup é"] {
        let gltf = dir.join(format!("{stem}.gltf"));
        write_gltf_with(&gltf, &rig, Some(&skin), &objects, stem).unwrap();
        files.push(gltf);
    }
    // Users' characters, as `troupe export gltf --look` and `run --record` write them:
    // CesiumMan (mapped by a `bones` map) waving with an object, and in troupe's rest
    // posture; a VRM 1.0 file (CesiumMan with a `VRMC_vrm` humanoid, mapped by it) at
    // rest and in its bind pose (no animation); the VRM 1.0 sample of the test assets
    // (its own skeleton and humanoid bones) skinned with a box per bone.
    let cesium = read_character(asset("CesiumMan.glb"), &cesium_map()).unwrap();
    let vrm = dir.join("cesium.vrm");
    std::fs::write(&vrm, as_vrm(&asset("CesiumMan.glb"))).unwrap();
    let vrm = read_character(&vrm, &[]).unwrap();
    let boxes = dir.join("boxes.vrm");
    std::fs::write(&boxes, vrm_with_boxes(&asset("VRM1_humanoid_no_skin.vrm"))).unwrap();
    let boxes = read_character(&boxes, &[]).unwrap();
    let rest = Rig::from_sequence(&skeleton, &Sequence::new("rest")).unwrap();
    let mut bind = rest.clone();
    (bind.times, bind.rotations, bind.translations) = (vec![], vec![], vec![]);
    for (stem, character, rig, with) in [
        ("cesium_carry", &cesium, &rig, &objects[..]),
        ("cesium_rest", &cesium, &rest, &[][..]),
        ("vrm_rest", &vrm, &rest, &[][..]),
        ("vrm_bind", &vrm, &bind, &[][..]),
        ("boxes_carry", &boxes, &rig, &objects[..]),
        ("boxes_bind", &boxes, &bind, &[][..]),
    ] {
        let dressing = character.dress(&skeleton, 1.75).unwrap();
        for ext in ["gltf", "glb"] {
            let file = dir.join(format!("{stem}.{ext}"));
            write_character(&file, &dressing, rig, with, stem).unwrap();
            files.push(file);
        }
    }
    let out = Command::new("node")
        .arg(repo().join("scripts/validate-gltf.js"))
        .args(&files)
        .env("NODE_PATH", &modules)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    println!("{report}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "the validator reports problems:\n{report}"
    );
    std::fs::remove_dir_all(dir).ok();
}
