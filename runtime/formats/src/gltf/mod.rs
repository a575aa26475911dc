//! glTF 2.0, written with `gltf-json`'s typed structures and read with `gltf`.
//!
//! A rig is written as a node hierarchy with a skin, and its motion as one animation whose
//! channels are per-joint rotation quaternions (and translations for joints that move,
//! like the root): a `.gltf` (JSON) with a `.bin` beside it, or one `.glb`. Metres, Y up,
//! facing +Z — glTF's own conventions, so a troupe body needs no axis change (a BVH of
//! other axes is turned to them first: `Rig::turn`, `retarget::bvh_axes`). A troupe body's file
//! also carries its generated skin as a skinned mesh ([`skin`]). Reading takes the
//! first animation back onto a troupe skeleton whose joint names the nodes carry. An
//! actor dressed in a user's character is written as that character ([`character`]).
//! A recording's objects are written as animated nodes beside the skeleton (`objects`).

pub mod character;
mod objects;
pub mod read;
pub mod skin;
mod uri;
pub mod write;

pub use read::{read_gltf_motion, recorded_body, GltfFile};
pub use skin::{add_skin, with_helper_joints};
pub use write::{
    to_gltf, to_gltf_with_objects, write_character, write_glb, write_glb_with, write_gltf,
    write_gltf_with,
};

/// The rig glTF files are written from (the crate's one [`crate::rig::Rig`]).
pub use crate::rig::Rig;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{fixtures, read_bvh};
    use crate::rig::tests::adult;
    use serde_json::Value;
    use troupe_motion::sequence::{Key, Sequence, Track};

    /// The document as JSON, as another tool would see it.
    fn as_json(root: &gltf_json::Root) -> Value {
        serde_json::from_str(&root.to_string().unwrap()).unwrap()
    }

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
    fn a_bvh_rig_is_written_as_a_consistent_gltf() {
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

    #[test]
    fn a_rig_of_several_roots_has_no_skeleton_root() {
        let bvh = crate::bvh::parse_bvh(fixtures::TWO_ROOTS, "two.bvh").unwrap();
        let rig = Rig::from_bvh(&bvh, 0.01);
        let (root, bin) = to_gltf(&rig, "two", Some("two.bin"));
        let doc = as_json(&root);
        check_consistent(&doc, &bin);
        assert_eq!(doc["scenes"][0]["nodes"].as_array().unwrap().len(), 2);
        assert!(
            doc["skins"][0].get("skeleton").is_none(),
            "{}",
            doc["skins"][0]
        );
        // One root is the skin's skeleton root.
        let walk = read_bvh(fixtures::data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let (root, _) = to_gltf(&Rig::from_bvh(&walk, 0.056444), "walk", None);
        assert_eq!(as_json(&root)["skins"][0]["skeleton"], 0);
    }

    #[test]
    fn a_troupe_rig_is_written_as_a_consistent_gltf() {
        let s = adult();
        let mut seq = Sequence::new("wave");
        seq.add_track(
            Track::new(
                "l_elbow_flexion",
                vec![Key::new(0.0, 0.0), Key::new(1.0, 0.8)],
            )
            .unwrap(),
        )
        .unwrap();
        let rig = Rig::from_sequence(&s, &seq).unwrap();
        let (root, bin) = to_gltf(&rig, "wave", Some("wave.bin"));
        check_consistent(&as_json(&root), &bin);
        // A .glb has no buffer URI: its buffer is the binary chunk.
        let (root, _) = to_gltf(&rig, "wave", None);
        assert!(as_json(&root)["buffers"][0].get("uri").is_none());
    }
}
