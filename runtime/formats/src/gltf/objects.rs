//! Recorded objects in a glTF file: one node per object at the scene's top level, its
//! translation and rotation animated on the body's frames (`LINEAR`), and in the node's
//! `extras` what glTF has no field for — the object's shape, mass and who held it when:
//!
//! ```json
//! { "troupe_object": { "shape": "cylinder 0.04 0.1", "mass": 0.3,
//!                      "held": [ { "from": 2.5, "to": 6.1, "actor": "ann", "joint": "r_wrist" } ] } }
//! ```
//!
//! The shape is the `.trk` `shape` line's text (docs/formats.md). The nodes carry no mesh.

use crate::rig::Rig;
use crate::trk::format_shape;
use gltf_json as json;
use troupe_body::glam::DQuat;
use troupe_motion::object_motion::ObjectMotion;

/// What an object adds to a glTF document: its node (named after it, at its first pose,
/// its shape, mass and holders in `extras`) and its animation's outputs on the rig's
/// frames: translations (3 floats a frame) and rotations (4 floats, neighbouring
/// quaternions in one hemisphere).
pub(crate) struct ObjectNode {
    pub(crate) node: json::Node,
    pub(crate) translations: Vec<f32>,
    pub(crate) rotations: Vec<f32>,
}

/// The node and animation outputs of `object`, whose one-joint rig `rig` is sampled on
/// the body's frames.
pub(crate) fn object_node(object: &ObjectMotion, rig: &Rig) -> ObjectNode {
    let extras = serde_json::json!({ "troupe_object": {
        "shape": format_shape(&object.shape),
        "mass": object.mass,
        "held": object.holds.iter().map(|h| serde_json::json!({
            "from": h.from, "to": h.to, "actor": h.actor, "joint": h.joint,
        })).collect::<Vec<_>>(),
    }});
    let node = json::Node {
        name: Some(object.name.clone()),
        translation: rig.translations.first().map(|t| t[0].as_vec3().to_array()),
        rotation: rig
            .rotations
            .first()
            .map(|r| json::scene::UnitQuaternion(r[0].normalize().as_quat().to_array())),
        // A JSON value always serializes.
        extras: serde_json::value::to_raw_value(&extras).ok(),
        ..Default::default()
    };
    let translations = rig
        .translations
        .iter()
        .flat_map(|f| f[0].as_vec3().to_array())
        .collect();
    let mut prev = DQuat::IDENTITY;
    let rotations = rig
        .rotations
        .iter()
        .flat_map(|f| {
            let mut q = f[0].normalize();
            if q.dot(prev) < 0.0 {
                q = -q;
            }
            prev = q;
            q.as_quat().to_array()
        })
        .collect();
    ObjectNode {
        node,
        translations,
        rotations,
    }
}
