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

use super::write::Builder;
use crate::rig::Rig;
use crate::trk::format_shape;
use gltf_json as json;
use json::accessor::Type;
use json::animation::Property;
use json::Index;
use troupe_motion::object_motion::ObjectMotion;

/// Adds a node per object (each paired with its one-joint rig sampled on the body's
/// frames, whose times accessor is `input`) and its channels to `animation`; returns the
/// new nodes, to list among the scene's roots.
pub(crate) fn add_object_nodes(
    b: &mut Builder,
    animation: &mut json::Animation,
    input: Index<json::Accessor>,
    objects: &[(&ObjectMotion, Rig)],
) -> Vec<Index<json::Node>> {
    let mut nodes = Vec::new();
    for (object, rig) in objects {
        let frames = rig.times.len();
        let extras = serde_json::json!({ "troupe_object": {
            "shape": format_shape(&object.shape),
            "mass": object.mass,
            "held": object.holds.iter().map(|h| serde_json::json!({
                "from": h.from, "to": h.to, "actor": h.actor, "joint": h.joint,
            })).collect::<Vec<_>>(),
        }});
        let node = b.root.push(json::Node {
            name: Some(object.name.clone()),
            translation: rig.translations.first().map(|t| t[0].as_vec3().to_array()),
            rotation: rig
                .rotations
                .first()
                .map(|r| json::scene::UnitQuaternion(r[0].normalize().as_quat().to_array())),
            // A JSON value always serializes.
            extras: serde_json::value::to_raw_value(&extras).ok(),
            ..Default::default()
        });
        let translations: Vec<f32> = rig
            .translations
            .iter()
            .flat_map(|f| f[0].as_vec3().to_array())
            .collect();
        let output = b.floats(&translations, Type::Vec3, frames, false);
        b.channel(
            animation,
            input,
            output,
            node.value(),
            Property::Translation,
        );
        let mut prev = troupe_body::glam::DQuat::IDENTITY;
        let rotations: Vec<f32> = rig
            .rotations
            .iter()
            .flat_map(|f| {
                // Neighbouring quaternions in one hemisphere, as for the joints.
                let mut q = f[0].normalize();
                if q.dot(prev) < 0.0 {
                    q = -q;
                }
                prev = q;
                q.as_quat().to_array()
            })
            .collect();
        let output = b.floats(&rotations, Type::Vec4, frames, false);
        b.channel(animation, input, output, node.value(), Property::Rotation);
        nodes.push(node);
    }
    nodes
}
