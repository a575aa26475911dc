//! A user's character in glTF (`troupe export gltf --look`, `troupe run --record` of an
//! actor dressed with `look = FILE`): the character as troupe fitted it
//! ([`troupe_body::Dressing`]), not troupe's generated skin.
//!
//! - **Nodes and skin**: one node per bone of the character, named as in its file, with
//!   its placed bind pose (turned to face +Z, scaled to the actor's height, standing on
//!   the floor) as the node's rest transform; one skin over them whose inverse bind
//!   matrices are the inverses of those bind frames.
//! - **Mesh**: the character's placed vertices, normals and vertex colours (its material
//!   and texture as the viewer draws them, converted to linear RGB; double-sided if any
//!   of its materials was), each vertex weighted
//!   to the bones that move it (a bone that has no troupe joint moves with its nearest
//!   moving ancestor, so its weights are that bone's).
//! - **Animation**: each bone's local rotation (and translation, for bones that troupe's
//!   joints carry) on every frame, as [`Dressing::bone_frames`] poses them from troupe's
//!   joint frames: what the viewer draws.
//!
//! The mesh node's `extras` say whose character it is (`{"troupe_character": {"source":
//! FILE}}`), so that reading such a file back as a troupe motion is refused: its bones are
//! the character's, not troupe's joints.

use super::skin::{add_skinned_mesh, SkinnedMesh};
use crate::rig::Rig;
use gltf_json::Root;
use troupe_body::{Dressing, Transform};

/// The key in a character mesh node's `extras` that marks a user's character.
pub const CHARACTER_EXTRAS: &str = "troupe_character";

/// Bones whose local translation stays within this of their rest translation (metres) over
/// every frame are not animated in translation: their node's rest translation holds.
const STILL: f64 = 1e-6;

/// The character's bones as a rig following `troupe`, the rig of the skeleton `dressing`
/// was fitted to ([`Rig::from_sequence`]): rest transforms are the placed bind pose, and
/// each frame holds the bones' local transforms for troupe's joint frames at that frame.
pub fn character_rig(dressing: &Dressing, troupe: &Rig) -> Rig {
    let parents = dressing.bone_parents.clone();
    let locals = |frames: &[Transform]| -> Vec<Transform> {
        (0..frames.len())
            .map(|b| match parents[b] {
                Some(p) => frames[p].inverse().mul(&frames[b]),
                None => frames[b],
            })
            .collect()
    };
    let rest = locals(&dressing.bind_frames());
    let posed: Vec<Vec<Transform>> = (0..troupe.times.len())
        .map(|k| locals(&dressing.bone_frames(&troupe.globals(k))))
        .collect();
    let moving: Vec<usize> = (0..rest.len())
        .filter(|&b| {
            posed
                .iter()
                .any(|f| (f[b].translation - rest[b].translation).length() > STILL)
        })
        .collect();
    Rig {
        names: dressing.bone_names.clone(),
        parents,
        rest,
        times: troupe.times.clone(),
        rotations: posed
            .iter()
            .map(|f| f.iter().map(|l| l.rotation).collect())
            .collect(),
        translations: posed
            .iter()
            .map(|f| moving.iter().map(|&b| f[b].translation).collect())
            .collect(),
        moving,
    }
}

/// Adds the character's mesh to a document written by [`super::to_gltf`] for
/// [`character_rig`]: a root node named `{name} {source file name}` with the mesh and the
/// document's first skin (whose joints are the character's bones in order).
pub fn add_character(root: &mut Root, bytes: &mut Vec<u8>, dressing: &Dressing, name: &str) {
    let slot_bones = dressing.slot_bones();
    let mesh = SkinnedMesh {
        positions: &dressing.positions,
        normals: &dressing.normals,
        colors: dressing.colors.iter().map(|c| c.map(linear)).collect(),
        // An unused slot (weight 0) names joint 0, as glTF asks.
        joints: dressing
            .slots
            .iter()
            .zip(&dressing.weights)
            .map(|(s, w)| {
                std::array::from_fn(|k| match w[k] > 0.0 {
                    true => slot_bones[s[k] as usize] as u16,
                    false => 0,
                })
            })
            .collect(),
        weights: &dressing.weights,
        indices: &dressing.indices,
        double_sided: dressing.double_sided,
    };
    let file = std::path::Path::new(&dressing.source)
        .file_name()
        .map_or_else(|| dressing.source.clone(), |f| f.to_string_lossy().into());
    let node = add_skinned_mesh(root, bytes, &mesh, &format!("{name} {file}"));
    let extras = serde_json::json!({ CHARACTER_EXTRAS: { "source": dressing.source } });
    // A JSON value always serializes.
    root.nodes[node.value()].extras = serde_json::value::to_raw_value(&extras).ok();
}

/// The linear value of an sRGB colour component (the character reader's inverse).
fn linear(c: f32) -> f32 {
    c.clamp(0.0, 1.0).powf(2.2)
}
