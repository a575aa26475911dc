//! glTF 2.0 export (`.gltf` JSON + `.bin` buffer): a skeleton as a node hierarchy with a
//! skin, and a motion as one animation whose channels are per-joint rotation quaternions
//! (and translations for joints that move, like the root). Metres, Y up, facing +Z —
//! glTF's own conventions, so no axis change is needed.

use crate::error::{Error, Result};
use glam::{DMat4, DQuat};
use serde_json::{json, Value};
use std::path::Path;

/// The rig glTF files are written from.
pub use crate::rig::Rig;

/// A growing binary buffer with its buffer views and accessors.
struct Buffer {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffer {
    /// Adds f32 data as one view + accessor; returns the accessor index.
    fn add(&mut self, data: &[f32], kind: &str, count: usize, minmax: bool) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let offset = self.bytes.len();
        for x in data {
            self.bytes.extend_from_slice(&x.to_le_bytes());
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": offset,
            "byteLength": data.len() * 4,
        }));
        let mut acc = json!({
            "bufferView": self.views.len() - 1,
            "componentType": 5126,
            "count": count,
            "type": kind,
        });
        if minmax {
            let min = data.iter().copied().fold(f32::INFINITY, f32::min);
            let max = data.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            acc["min"] = json!([min]);
            acc["max"] = json!([max]);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }
}

/// The glTF JSON and binary buffer of `rig`; `bin_uri` is how the JSON names the buffer.
pub fn to_gltf(rig: &Rig, name: &str, bin_uri: &str) -> (Value, Vec<u8>) {
    let n = rig.names.len();
    let mut buf = Buffer {
        bytes: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    let nodes: Vec<Value> = (0..n)
        .map(|j| {
            let t = rig.rest[j].translation;
            let r = rig.rest[j].rotation;
            let children: Vec<usize> = (0..n).filter(|&c| rig.parents[c] == Some(j)).collect();
            let mut node = json!({
                "name": rig.names[j],
                "translation": [t.x, t.y, t.z],
            });
            if r != DQuat::IDENTITY {
                node["rotation"] = json!([r.x, r.y, r.z, r.w]);
            }
            if !children.is_empty() {
                node["children"] = json!(children);
            }
            node
        })
        .collect();
    let roots: Vec<usize> = (0..n).filter(|&j| rig.parents[j].is_none()).collect();

    // Inverse bind matrices: inverse of each joint's global rest transform (column major).
    let ibm: Vec<f32> = rig
        .rest_globals()
        .iter()
        .flat_map(|g| {
            DMat4::from_rotation_translation(g.rotation, g.translation)
                .inverse()
                .to_cols_array()
                .map(|x| x as f32)
        })
        .collect();
    let ibm_acc = buf.add(&ibm, "MAT4", n, false);

    let frames = rig.times.len();
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    if frames > 0 {
        let times: Vec<f32> = rig.times.iter().map(|&t| t as f32).collect();
        let input = buf.add(&times, "SCALAR", frames, true);
        for j in 0..n {
            let moves = rig.rotations.iter().any(|f| f[j] != DQuat::IDENTITY);
            if !moves {
                continue;
            }
            let mut prev = DQuat::IDENTITY;
            let data: Vec<f32> = rig
                .rotations
                .iter()
                .flat_map(|f| {
                    // Keep neighbouring quaternions in one hemisphere for interpolation.
                    let mut q = f[j].normalize();
                    if q.dot(prev) < 0.0 {
                        q = -q;
                    }
                    prev = q;
                    [q.x as f32, q.y as f32, q.z as f32, q.w as f32]
                })
                .collect();
            let output = buf.add(&data, "VEC4", frames, false);
            samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
            channels.push(
                json!({"sampler": samplers.len() - 1, "target": {"node": j, "path": "rotation"}}),
            );
        }
        for (i, &j) in rig.moving.iter().enumerate() {
            let data: Vec<f32> = rig
                .translations
                .iter()
                .flat_map(|f| [f[i].x as f32, f[i].y as f32, f[i].z as f32])
                .collect();
            let output = buf.add(&data, "VEC3", frames, false);
            samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": j, "path": "translation"}}));
        }
    }
    while !buf.bytes.len().is_multiple_of(4) {
        buf.bytes.push(0);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("troupe ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": name, "nodes": roots}],
        "nodes": nodes,
        "skins": [{"name": name, "joints": (0..n).collect::<Vec<_>>(), "inverseBindMatrices": ibm_acc, "skeleton": roots.first().copied().unwrap_or(0)}],
        "buffers": [{"uri": bin_uri, "byteLength": buf.bytes.len()}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    });
    if !channels.is_empty() {
        doc["animations"] = json!([{"name": name, "samplers": samplers, "channels": channels}]);
    }
    (doc, buf.bytes)
}

/// Writes `rig` as `path` (`.gltf`) and a `.bin` of the same stem beside it.
pub fn write_gltf(path: impl AsRef<Path>, rig: &Rig, name: &str) -> Result<()> {
    let path = path.as_ref();
    let bin = path.with_extension("bin");
    let uri = bin
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "motion.bin".into());
    let (doc, bytes) = to_gltf(rig, name, &uri);
    let text = serde_json::to_string_pretty(&doc)
        .map_err(|e| Error::Invalid(format!("glTF JSON: {e}")))?;
    std::fs::write(path, text).map_err(|e| Error::io(path, e))?;
    std::fs::write(&bin, bytes).map_err(|e| Error::io(&bin, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{fixtures, read_bvh};

    fn check_consistent(doc: &Value, bin: &[u8]) {
        assert_eq!(doc["asset"]["version"], "2.0");
        assert_eq!(
            doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize,
            bin.len()
        );
        let views = doc["bufferViews"].as_array().unwrap();
        for v in views {
            let end = v["byteOffset"].as_u64().unwrap() + v["byteLength"].as_u64().unwrap();
            assert!(end as usize <= bin.len());
            assert_eq!(v["byteOffset"].as_u64().unwrap() % 4, 0);
        }
        let accessors = doc["accessors"].as_array().unwrap();
        for a in accessors {
            let comps = match a["type"].as_str().unwrap() {
                "SCALAR" => 1,
                "VEC3" => 3,
                "VEC4" => 4,
                "MAT4" => 16,
                t => panic!("{t}"),
            };
            let view = &views[a["bufferView"].as_u64().unwrap() as usize];
            assert_eq!(
                a["count"].as_u64().unwrap() * comps * 4,
                view["byteLength"].as_u64().unwrap()
            );
        }
        let nodes = doc["nodes"].as_array().unwrap().len() as u64;
        let skin = &doc["skins"][0];
        assert_eq!(skin["joints"].as_array().unwrap().len() as u64, nodes);
        assert_eq!(
            accessors[skin["inverseBindMatrices"].as_u64().unwrap() as usize]["count"]
                .as_u64()
                .unwrap(),
            nodes
        );
        let anim = &doc["animations"][0];
        for s in anim["samplers"].as_array().unwrap() {
            let i = &accessors[s["input"].as_u64().unwrap() as usize];
            let o = &accessors[s["output"].as_u64().unwrap() as usize];
            assert_eq!(i["count"], o["count"]);
            assert!(i["min"].is_array() && i["max"].is_array());
        }
        for c in anim["channels"].as_array().unwrap() {
            assert!(c["target"]["node"].as_u64().unwrap() < nodes);
        }
    }

    #[test]
    fn bvh_export_is_consistent() {
        let bvh = read_bvh(fixtures::data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let rig = Rig::from_bvh(&bvh, 0.056444);
        let dir = std::env::temp_dir().join(format!("troupe-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("walk.gltf");
        write_gltf(&file, &rig, "walk").unwrap();
        let doc: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        let bin = std::fs::read(dir.join("walk.bin")).unwrap();
        assert_eq!(doc["buffers"][0]["uri"], "walk.bin");
        check_consistent(&doc, &bin);
        assert_eq!(doc["nodes"].as_array().unwrap().len(), 31 + 7);
        std::fs::remove_dir_all(dir).ok();
    }
}
