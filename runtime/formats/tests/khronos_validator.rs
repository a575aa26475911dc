//! The glTF files troupe writes pass the Khronos glTF validator with no error and no
//! warning: a troupe body's motion with its skin (adult and child), with and without a
//! recorded object, the skinned characters `troupe export gltf` writes (a one-frame rest
//! pose), users' characters (CesiumMan, CesiumMan as a VRM 1.0 file, and the VRM 1.0
//! sample of the test assets given a box per bone as its skin) moving with an
//! object, in troupe's rest posture and in their bind pose, and a BVH on its own
//! hierarchy, as `.gltf` + `.bin` and as `.glb`.
//!
//! The validator is the npm package `gltf-validator`, which `scripts/setup.sh` installs
//! into `.tools/node`; without node or without that package the test prints why and
//! checks nothing.

use std::path::{Path, PathBuf};
use std::process::Command;
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::solid::Shape;
use troupe_body::template::template;
use troupe_body::{Skeleton, Skin};
use troupe_formats::bvh::read_bvh;
use troupe_formats::character::read_character;
use troupe_formats::gltf::{
    write_character, write_glb, write_glb_with, write_gltf, write_gltf_with,
};
use troupe_formats::Rig;
use troupe_motion::object_motion::{Hold, ObjectMotion};
use troupe_motion::sequence::{Key, Sequence, Track};

mod cesium;
use cesium::{asset, cesium_map, CESIUM_BONES};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn body(name: &str) -> Skeleton {
    let t = template(name).unwrap();
    t.instantiate(t.default_params()).unwrap()
}

/// A troupe body waving and walking forward.
fn troupe_rig(skeleton: &Skeleton) -> Rig {
    let mut seq = Sequence::new("wave");
    seq.meta.insert("rate".into(), "30".into());
    for (dof, v) in [
        ("r_shoulder_abduction", 1.4),
        ("r_elbow_flexion", 0.9),
        ("root_z", 0.5),
    ] {
        let keys = vec![Key::new(0.0, 0.0), Key::new(0.5, v), Key::new(1.0, 0.0)];
        seq.add_track(Track::new(dof, keys).unwrap()).unwrap();
    }
    Rig::from_sequence(skeleton, &seq).unwrap()
}

/// The binary glTF `path` as a VRM 1.0 file: its JSON given a `VRMC_vrm` humanoid that
/// names CesiumMan's joints.
fn as_vrm(path: &Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    let node = |name: &str| {
        json["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .position(|n| n["name"] == name)
            .unwrap()
    };
    let bones: serde_json::Map<String, serde_json::Value> = CESIUM_BONES
        .iter()
        .map(|(bone, name)| (bone.to_string(), serde_json::json!({ "node": node(name) })))
        .collect();
    json["extensions"] = serde_json::json!({
        "VRMC_vrm": { "specVersion": "1.0", "humanoid": { "humanBones": bones } }
    });
    let glb = gltf::binary::Glb {
        json: serde_json::to_vec(&json).unwrap().into(),
        ..glb
    };
    glb.to_vec().unwrap()
}

/// The VRM 1.0 sample in the test assets (a real humanoid skeleton, bound with rotated
/// limbs, and no skin) given a skin: a box along each of its humanoid bones, weighted
/// wholly to that bone, bound where the file's nodes stand.
fn vrm_with_boxes(path: &Path) -> Vec<u8> {
    use troupe_body::glam::{DMat4, DQuat, DVec3};
    let bytes = std::fs::read(path).unwrap();
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    let mut bin = glb.bin.as_deref().unwrap_or_default().to_vec();
    let nodes = json["nodes"].as_array().unwrap().clone();
    let vec = |v: &serde_json::Value, n: usize, default: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|k| v.get(k).and_then(|x| x.as_f64()).unwrap_or(default[k]))
            .collect()
    };
    let mut parent = vec![None; nodes.len()];
    for (i, node) in nodes.iter().enumerate() {
        for c in node["children"].as_array().into_iter().flatten() {
            parent[c.as_u64().unwrap() as usize] = Some(i);
        }
    }
    let world = |mut n: usize| {
        let mut m = DMat4::IDENTITY;
        loop {
            let t = vec(&nodes[n]["translation"], 3, &[0.0; 3]);
            let r = vec(&nodes[n]["rotation"], 4, &[0.0, 0.0, 0.0, 1.0]);
            m = DMat4::from_rotation_translation(
                DQuat::from_xyzw(r[0], r[1], r[2], r[3]).normalize(),
                DVec3::new(t[0], t[1], t[2]),
            ) * m;
            match parent[n] {
                Some(p) => n = p,
                None => return m,
            }
        }
    };
    let bones: Vec<usize> = json["extensions"]["VRMC_vrm"]["humanoid"]["humanBones"]
        .as_object()
        .unwrap()
        .values()
        .map(|b| b["node"].as_u64().unwrap() as usize)
        .collect();
    let (mut positions, mut joints, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for (j, &b) in bones.iter().enumerate() {
        let from = world(b).w_axis.truncate();
        let ends: Vec<DVec3> = bones
            .iter()
            .filter(|&&c| parent[c] == Some(b))
            .map(|&c| world(c).w_axis.truncate())
            .collect();
        let to = match ends.len() {
            0 => from + world(b).transform_vector3(DVec3::Y) * 0.08, // a hand, a toe, the head
            n => ends.iter().sum::<DVec3>() / n as f64,
        };
        let along = (to - from).normalize();
        let (u, v) = along.any_orthonormal_pair();
        let base = positions.len() as u32;
        for end in [from, to] {
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(end + (u * a + v * b) * 0.03);
                joints.push(j as u16);
            }
        }
        let centre = (from + to) / 2.0;
        let quads = [
            [0, 1, 2, 3],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ];
        for q in quads {
            for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let p = tri.map(|k| positions[(base + k) as usize]);
                // Counter-clockwise seen from outside.
                let outward = (p[1] - p[0]).cross(p[2] - p[0]).dot(p[0] - centre) > 0.0;
                let tri = if outward {
                    tri
                } else {
                    [tri[0], tri[2], tri[1]]
                };
                indices.extend(tri.map(|k| base + k));
            }
        }
    }
    let mut push = |data: Vec<u8>, count: usize, component: u32, kind: &str| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let views = json["bufferViews"].as_array_mut().unwrap();
        views.push(
            serde_json::json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": data.len() }),
        );
        let view = views.len() - 1;
        bin.extend(data);
        let accessors = json["accessors"].as_array_mut().unwrap();
        accessors.push(serde_json::json!({
            "bufferView": view, "componentType": component, "count": count, "type": kind
        }));
        accessors.len() - 1
    };
    let f32s = |v: &mut dyn Iterator<Item = f64>| -> Vec<u8> {
        v.flat_map(|x| (x as f32).to_le_bytes()).collect()
    };
    let n = positions.len();
    let position = push(
        f32s(&mut positions.iter().flat_map(|p| p.to_array())),
        n,
        5126,
        "VEC3",
    );
    let joint = push(
        joints
            .iter()
            .flat_map(|&j| [j, 0, 0, 0])
            .flat_map(u16::to_le_bytes)
            .collect(),
        n,
        5123,
        "VEC4",
    );
    let weight = push(
        f32s(&mut (0..n).flat_map(|_| [1.0, 0.0, 0.0, 0.0])),
        n,
        5126,
        "VEC4",
    );
    let index = push(
        indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
        indices.len(),
        5125,
        "SCALAR",
    );
    let ibm = push(
        f32s(
            &mut bones
                .iter()
                .flat_map(|&b| world(b).inverse().to_cols_array()),
        ),
        bones.len(),
        5126,
        "MAT4",
    );
    let (lo, hi) = positions.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    json["accessors"][position]["min"] = lo.as_vec3().to_array().to_vec().into();
    json["accessors"][position]["max"] = hi.as_vec3().to_array().to_vec().into();
    json["buffers"][0]["byteLength"] = bin.len().into();
    let meshes = json["meshes"].as_array_mut().unwrap();
    meshes.push(serde_json::json!({ "name": "boxes", "primitives": [{
        "attributes": { "POSITION": position, "JOINTS_0": joint, "WEIGHTS_0": weight },
        "indices": index,
    }]}));
    let mesh = meshes.len() - 1;
    let skins = json
        .as_object_mut()
        .unwrap()
        .entry("skins")
        .or_insert(serde_json::json!([]));
    skins
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({ "joints": bones, "inverseBindMatrices": ibm }));
    let skin = skins.as_array().unwrap().len() - 1;
    let nodes = json["nodes"].as_array_mut().unwrap();
    nodes.push(serde_json::json!({ "name": "boxes", "mesh": mesh, "skin": skin }));
    let node = nodes.len() - 1;
    json["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(node.into());
    let glb = gltf::binary::Glb {
        json: serde_json::to_vec(&json).unwrap().into(),
        bin: Some(bin.into()),
        ..glb
    };
    glb.to_vec().unwrap()
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
