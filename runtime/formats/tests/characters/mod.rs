//! The third-party characters of `tests/assets/characters/` and the variants tests make
//! of them, shared by the tests that dress them (each test uses a part).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A file of the third-party characters in `tests/assets/characters/`.
pub fn asset(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/assets/characters")
        .join(name)
}

/// The VRM humanoid bones of CesiumMan, whose joints have names of their own.
pub const CESIUM_BONES: [(&str, &str); 19] = [
    ("hips", "Skeleton_torso_joint_1"),
    ("spine", "Skeleton_torso_joint_2"),
    ("upperChest", "torso_joint_3"),
    ("neck", "Skeleton_neck_joint_1"),
    ("head", "Skeleton_neck_joint_2"),
    ("rightUpperArm", "Skeleton_arm_joint_R"),
    ("rightLowerArm", "Skeleton_arm_joint_R__2_"),
    ("rightHand", "Skeleton_arm_joint_R__3_"),
    ("leftUpperArm", "Skeleton_arm_joint_L__4_"),
    ("leftLowerArm", "Skeleton_arm_joint_L__3_"),
    ("leftHand", "Skeleton_arm_joint_L__2_"),
    ("rightUpperLeg", "leg_joint_R_1"),
    ("rightLowerLeg", "leg_joint_R_2"),
    ("rightFoot", "leg_joint_R_3"),
    ("rightToes", "leg_joint_R_5"),
    ("leftUpperLeg", "leg_joint_L_1"),
    ("leftLowerLeg", "leg_joint_L_2"),
    ("leftFoot", "leg_joint_L_3"),
    ("leftToes", "leg_joint_L_5"),
];

/// The `bones` map a user gives for CesiumMan.
pub fn cesium_map() -> Vec<(String, String)> {
    CESIUM_BONES
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect()
}

/// The index of the node named `name` in a glTF document's JSON.
pub fn node_index(json: &serde_json::Value, name: &str) -> usize {
    json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .position(|n| n["name"] == name)
        .unwrap()
}

/// The binary glTF `path` as a VRM 1.0 file: its JSON given a `VRMC_vrm` humanoid that
/// names CesiumMan's joints.
pub fn as_vrm(path: &Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    let glb = gltf::binary::Glb::from_slice(&bytes).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    let bones: serde_json::Map<String, serde_json::Value> = CESIUM_BONES
        .iter()
        .map(|(bone, name)| {
            (
                bone.to_string(),
                serde_json::json!({ "node": node_index(&json, name) }),
            )
        })
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
pub fn vrm_with_boxes(path: &Path) -> Vec<u8> {
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
