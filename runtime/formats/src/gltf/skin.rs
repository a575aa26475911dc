//! The skin in glTF: a troupe [`Skin`] as one skinned mesh (positions, normals, vertex
//! colours by region, `JOINTS_0`/`WEIGHTS_0` with at most four joints per vertex) bound
//! to the joint nodes and the skin that [`super::to_gltf`] writes, so that Blender, a web
//! viewer or any glTF tool shows the body moving, not only its bones.
//!
//! The skin's helper joints ([`troupe_body::skin::helpers`]) become joints of the rig
//! ([`with_helper_joints`]): nodes under their joint's parent whose rotation is animated
//! as the fraction of the joint's that the helper takes (and, for the sliding helpers at
//! the hips, knees and elbows, whose translation is animated too; for the helpers
//! between two fingers, both from the two knuckles' frames), so a glTF viewer's linear
//! blend skinning deforms the skin as troupe's viewer does.

use crate::rig::Rig;
use glam::Vec3;
use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::validation::{Checked::Valid, USize64};
use json::{Index, Root};
use std::collections::BTreeMap;
use troupe_body::skin::{CutSkin, Region};
use troupe_body::{Skin, Transform};

/// `rig` (a troupe skeleton's, joints in the skeleton's order) with `skin`'s helper
/// joints appended after its joints, in the skin's slot order, so that the skin's
/// `JOINTS_0` slots are the rig's joints: each helper a child of its joint's parent, at
/// the joint's rest offset, turned on every frame by [`troupe_body::skin::Helper::local_rotation`]
/// of the joint's local rotation and, if it slides, moved from that offset by
/// [`troupe_body::skin::Helper::local_translation`] (an animated translation); a helper
/// between two joints ([`troupe_body::skin::Helper::pair`]) hangs under its parent (the
/// wrist) with its rotation and translation animated by
/// [`troupe_body::skin::Helper::pair_local`] of the two joints' frames there. The rig's
/// rest becomes the posture the skin is made in (the arms raised sideways and the fingers
/// spread, [`troupe_body::skin::bind_posture`]), which a modeller shows unposed; the
/// writer takes the inverse bind matrices from the posture it is bound in
/// ([`troupe_body::skin::bound_posture`], [`Skin::rest`]), not from this rest.
pub fn with_helper_joints(rig: &Rig, skin: &Skin) -> Rig {
    let mut out = rig.clone();
    for j in 0..rig.rest.len() {
        let made = match rig.parents[j] {
            Some(p) => skin.made[p].rotation.inverse() * skin.made[j].rotation,
            None => skin.made[j].rotation,
        };
        // Only the joints the posture the skin is made in turns: the others keep their
        // exact rest rotation (recomputed from the globals it would differ in the last
        // bits).
        if rig.rest[j].rotation.angle_between(made) > 1e-9 {
            out.rest[j].rotation = made.normalize();
        }
    }
    for h in &skin.helpers {
        let slot = out.names.len();
        if let Some(pair) = &h.pair {
            // Between two joints (a web between two fingers): from the two joints' frames
            // in the helper's parent's, composed down the rig from it; rotation and
            // translation both animated.
            let rests = out.rest.clone();
            let local = |frame: Option<usize>| {
                let place = |j: usize| match frame {
                    None => rests[j],
                    Some(f) => {
                        let translation = match rig.moving.iter().position(|&m| m == j) {
                            Some(i) => rig.translations[f][i],
                            None => rests[j].translation,
                        };
                        Transform::new(rig.rotations[f][j], translation)
                    }
                };
                let below = |j: usize| {
                    let mut chain = vec![j];
                    while let Some(p) = rig.parents[*chain.last().expect("not empty")] {
                        if p == h.parent {
                            break;
                        }
                        chain.push(p);
                    }
                    chain
                        .iter()
                        .rev()
                        .fold(Transform::IDENTITY, |t, &k| t.mul(&place(k)))
                };
                h.pair_local(pair, below(h.joint), below(pair.joint))
            };
            out.names.push(h.name.clone());
            out.parents.push(Some(h.parent));
            out.rest.push(local(None));
            out.moving.push(slot);
            for frame in 0..out.rotations.len() {
                let t = local(Some(frame));
                out.rotations[frame].push(t.rotation);
                out.translations[frame].push(t.translation);
            }
            continue;
        }
        let rest = out.rest[h.joint];
        out.names.push(h.name.clone());
        out.parents.push(Some(h.parent));
        out.rest.push(Transform::new(
            h.local_rotation(rest.rotation),
            rest.translation + h.local_translation(rest.rotation),
        ));
        for (frame, rotations) in out.rotations.iter_mut().enumerate() {
            rotations.push(h.local_rotation(rig.rotations[frame][h.joint]));
        }
        if h.pivot != 0.0 {
            // Appended last, so `moving` stays increasing.
            out.moving.push(slot);
            for (frame, translations) in out.translations.iter_mut().enumerate() {
                let local = rig.rotations[frame][h.joint];
                translations.push(rest.translation + h.local_translation(local));
            }
        }
    }
    out
}

/// Vertex colours (linear RGB) of the skin's regions in a file.
fn region_color(region: Region) -> [f32; 3] {
    match region {
        Region::Skin => [0.84, 0.50, 0.32],
        Region::Shirt => [0.03, 0.23, 0.30],
        Region::Trousers => [0.04, 0.05, 0.09],
        Region::Shoes => [0.02, 0.015, 0.012],
        Region::Eye => [0.88, 0.86, 0.80],
        Region::Pupil => [0.01, 0.006, 0.004],
    }
}

/// Appends `data` to the buffer as one view for `target` and returns an accessor of
/// `count` elements.
#[allow(clippy::too_many_arguments)]
fn accessor(
    root: &mut Root,
    bytes: &mut Vec<u8>,
    data: &[u8],
    component: ComponentType,
    type_: Type,
    count: usize,
    target: json::buffer::Target,
    bounds: Option<(Vec<f32>, Vec<f32>)>,
) -> Index<json::Accessor> {
    bytes.resize(bytes.len().next_multiple_of(4), 0);
    let offset = bytes.len();
    bytes.extend_from_slice(data);
    let view = root.push(json::buffer::View {
        buffer: Index::new(0),
        byte_length: USize64::from(data.len()),
        byte_offset: Some(USize64::from(offset)),
        byte_stride: None,
        name: None,
        target: Some(Valid(target)),
        extensions: None,
        extras: Default::default(),
    });
    let (min, max) = match bounds {
        Some((lo, hi)) => (Some(json::Value::from(lo)), Some(json::Value::from(hi))),
        None => (None, None),
    };
    root.push(json::Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(GenericComponentType(component)),
        type_: Valid(type_),
        min,
        max,
        name: None,
        normalized: false,
        sparse: None,
        extensions: None,
        extras: Default::default(),
    })
}

fn le_f32(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// The vertex arrays of a skinned triangle mesh, as one glTF primitive holds them.
pub struct SkinnedMesh<'a> {
    /// Bind-pose positions.
    pub positions: &'a [[f32; 3]],
    /// Unit normals.
    pub normals: &'a [[f32; 3]],
    /// Linear RGB colour of each vertex (`COLOR_0`).
    pub colors: Vec<[f32; 3]>,
    /// Up to four joints per vertex, indices into the document's skin's joints; unused
    /// slots have weight 0.
    pub joints: Vec<[u16; 4]>,
    /// Their weights, summing to one.
    pub weights: &'a [[f32; 4]],
    /// Triangles.
    pub indices: &'a [u32],
    /// Whether both faces are to be drawn (the material's `doubleSided`).
    pub double_sided: bool,
}

/// Adds `skin` to a document written by [`super::to_gltf`] for the same skeleton: a mesh
/// on a root node named `{name} skin` that uses the document's first skin, whose joints
/// are the skin's slots in order (the skeleton's joints, then the helpers: a document of
/// the rig [`with_helper_joints`] makes). `bytes` is the document's one buffer; its length
/// is updated.
pub fn add_skin(root: &mut Root, bytes: &mut Vec<u8>, skin: &Skin, name: &str) {
    // Coloured by vertex, the surface is cut along the edges between regions first, so
    // that sleeves, waistband and collar run where troupe's viewer draws them.
    let cut = CutSkin::new(skin);
    let mesh = SkinnedMesh {
        positions: &cut.positions,
        normals: &cut.normals,
        colors: cut.regions.iter().map(|&r| region_color(r)).collect(),
        joints: cut.joints.clone(),
        weights: &cut.weights,
        indices: &cut.indices,
        // Closed and wound outwards: only its outside is ever seen.
        double_sided: false,
    };
    add_skinned_mesh(root, bytes, &mesh, &format!("{name} skin"));
}

/// Adds `skin` as a mesh named `name` (with a white, rough material, so that its vertex
/// colours show) on a root node of that name using the document's first skin; returns
/// the node.
pub fn add_skinned_mesh(
    root: &mut Root,
    bytes: &mut Vec<u8>,
    skin: &SkinnedMesh,
    name: &str,
) -> Index<json::Node> {
    let n = skin.positions.len();
    let (lo, hi) = skin.positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(Vec3::from(*p)), hi.max(Vec3::from(*p))),
    );
    let array = json::buffer::Target::ArrayBuffer;
    let positions = accessor(
        root,
        bytes,
        &le_f32(skin.positions.iter().flatten().copied()),
        ComponentType::F32,
        Type::Vec3,
        n,
        array,
        Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
    );
    let normals = accessor(
        root,
        bytes,
        &le_f32(skin.normals.iter().flatten().copied()),
        ComponentType::F32,
        Type::Vec3,
        n,
        array,
        None,
    );
    let colors = accessor(
        root,
        bytes,
        &le_f32(skin.colors.iter().flatten().copied()),
        ComponentType::F32,
        Type::Vec3,
        n,
        array,
        None,
    );
    let joints: Vec<u8> = skin
        .joints
        .iter()
        .flatten()
        .flat_map(|j| j.to_le_bytes())
        .collect();
    let joints = accessor(
        root,
        bytes,
        &joints,
        ComponentType::U16,
        Type::Vec4,
        n,
        array,
        None,
    );
    let weights = accessor(
        root,
        bytes,
        &le_f32(skin.weights.iter().flatten().copied()),
        ComponentType::F32,
        Type::Vec4,
        n,
        array,
        None,
    );
    let indices: Vec<u8> = skin.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let indices = accessor(
        root,
        bytes,
        &indices,
        ComponentType::U32,
        Type::Scalar,
        skin.indices.len(),
        json::buffer::Target::ElementArrayBuffer,
        None,
    );
    let material = root.push(json::Material {
        name: Some(name.to_string()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(0.8),
            ..Default::default()
        },
        double_sided: skin.double_sided,
        ..Default::default()
    });
    let attributes: BTreeMap<_, _> = [
        (json::mesh::Semantic::Positions, positions),
        (json::mesh::Semantic::Normals, normals),
        (json::mesh::Semantic::Colors(0), colors),
        (json::mesh::Semantic::Joints(0), joints),
        (json::mesh::Semantic::Weights(0), weights),
    ]
    .into_iter()
    .map(|(s, a)| (Valid(s), a))
    .collect();
    let mesh = root.push(json::Mesh {
        name: Some(name.to_string()),
        primitives: vec![json::mesh::Primitive {
            attributes,
            indices: Some(indices),
            material: Some(material),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
            extensions: None,
            extras: Default::default(),
        }],
        weights: None,
        extensions: None,
        extras: Default::default(),
    });
    // A skinned mesh's node sits at the root: glTF ignores its transform, and the
    // validator warns when it has a parent.
    let node = root.push(json::Node {
        name: Some(name.to_string()),
        mesh: Some(mesh),
        skin: Some(Index::new(0)),
        ..Default::default()
    });
    if let Some(scene) = root.scenes.first_mut() {
        scene.nodes.push(node);
    }
    bytes.resize(bytes.len().next_multiple_of(4), 0);
    if let Some(buffer) = root.buffers.first_mut() {
        buffer.byte_length = USize64::from(bytes.len());
    }
    node
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::template;
    use troupe_motion::sequence::{Key, Sequence, Track};

    /// What a glTF viewer computes from the written rig (each node's global transform
    /// times its inverse bind matrix, the inverse of the skin's frame in the posture it
    /// is bound in) is the skin's own skinning transforms, helpers included, on every
    /// frame.
    #[test]
    fn a_viewer_of_the_written_rig_skins_with_the_skins_own_transforms() {
        let t = template("adult").unwrap();
        let skeleton = t.instantiate(t.default_params()).unwrap();
        let skin = Skin::build(&skeleton).unwrap();
        assert!(!skin.helpers.is_empty());
        let mut seq = Sequence::new("raise");
        seq.meta.insert("rate".into(), "10".into());
        for (dof, v) in [
            ("l_hip_flexion", 2.0),
            ("l_hip_abduction", 0.6),
            ("r_knee_flexion", 1.9),
            ("r_elbow_flexion", 2.2),
            ("l_shoulder_abduction", 2.8),
            ("l_shoulder_flexion", 0.9),
            ("r_shoulder_twist", -1.2),
            ("l_sternoclavicular_elevation", 0.5),
            ("root_yaw", 0.7),
            // The webs' helpers: a little finger bent beside a ring finger bent back,
            // its metacarpal flexed, and the index turned towards the thumb.
            ("l_pinky1_flexion", 1.5),
            ("l_ring1_flexion", -0.3),
            ("l_ring1_pivot", -0.3),
            ("l_pinky0_flexion", 0.3),
            ("l_index1_pivot", 0.3),
        ] {
            let keys = vec![Key::new(0.0, 0.0), Key::new(1.0, v)];
            seq.add_track(Track::new(dof, keys).unwrap()).unwrap();
        }
        let rig = Rig::from_sequence(&skeleton, &seq).unwrap();
        let written = with_helper_joints(&rig, &skin);
        assert_eq!(written.names.len(), skin.rest.len());
        // The inverse bind matrices' frames (`to_gltf_bound`).
        let bind = &skin.rest;
        for k in 0..written.times.len() {
            let nodes = written.globals(k);
            let joints = &rig.globals(k)[..];
            let expected = skin.skinning_transforms(joints);
            for (slot, want) in expected.iter().enumerate() {
                let got = nodes[slot].mul(&bind[slot].inverse());
                assert!(
                    got.rotation.abs_diff_eq(want.rotation, 1e-9)
                        && got.translation.abs_diff_eq(want.translation, 1e-9),
                    "frame {k}, slot {} ({}): {got:?} against {want:?}",
                    slot,
                    written.names[slot]
                );
            }
        }
    }
}
