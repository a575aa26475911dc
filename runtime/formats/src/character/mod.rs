//! Reading a user's rigged humanoid from a glTF (`.gltf`, `.glb`) or VRM (`.vrm`, 0.x
//! and 1.0) file into a [`Character`] that `Character::dress` fits to a troupe body.
//!
//! What is read, and the choices made for files that are not as expected:
//! - **The skin**: a file with no skin is an error; with several, the one with the most
//!   joints is taken (ties: the first), and every mesh node it skins is drawn; meshes
//!   of other skins are left out (a warning names them). Only triangle primitives are
//!   read. Inverse bind matrices are required (the bind pose comes from them); the rest
//!   pose the character is fitted by is the nodes' own transforms.
//! - **Weights**: `JOINTS_0`/`WEIGHTS_0`, and `JOINTS_1`/`WEIGHTS_1` when present; of a
//!   vertex's influences the four largest are kept and renormalised to sum to one
//!   (weights that do not sum to one are renormalised too); a vertex whose weights are
//!   all zero, negative or not numbers is an error naming it.
//! - **Bone names** ([`names`]): a VRM file's humanoid bones (`VRMC_vrm.humanoid` in
//!   1.0, `VRM.humanoid` in 0.x), Mixamo names (`mixamorig:LeftForeArm`) and H-Anim names
//!   (`l_elbow`) are recognised; the user's map (`hips = "Skeleton_torso_joint_1"`, keys
//!   being VRM humanoid bone names or troupe joint names) is applied on top. The VRM
//!   humanoid's required bones (hips, spine, head, upper and lower arms, hands, upper and
//!   lower legs, feet) must all be found: otherwise an error names the missing ones.
//! - **Colours**: each vertex takes its material's base colour, times its base-colour
//!   texture at the vertex's UV when that texture is a PNG; other textures are left out.
//!
//! A malformed or truncated file is an error naming the file and what is wrong.

pub mod names;

use crate::error::{Error, Result};
use crate::gltf::read::{check_glb_header, load_buffers};
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::{Accessor, Gltf};
use glam::{DMat4, DQuat, DVec3};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;
use troupe_body::character::{Bone, Character};
use troupe_body::transform::Transform;

/// Reads the rigged character in `path` (`.gltf`, `.glb` or `.vrm`), mapping its bones
/// to troupe joints by the built-in names and `bones` (pairs of a VRM humanoid bone or
/// troupe joint name and the file's node name).
pub fn read_character(path: impl AsRef<Path>, bones: &[(String, String)]) -> Result<Character> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let bad = |message: String| Error::Parse {
        file: file.clone(),
        line: 0,
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    check_glb_header(&bytes).map_err(bad)?;
    let gltf =
        Gltf::from_slice(&bytes).map_err(|e| bad(format!("not a valid glTF or VRM file: {e}")))?;
    let buffers = load_buffers(&gltf, path, &bad)?;
    let json = document_json(&bytes).map_err(bad)?;

    let skin = gltf
        .skins()
        .max_by_key(|s| (s.joints().count(), std::cmp::Reverse(s.index())))
        .ok_or_else(|| {
            bad(
                "the file has no skin: a character needs a skinned mesh (a rig with weights)"
                    .into(),
            )
        })?;
    let others: Vec<String> = gltf
        .nodes()
        .filter(|n| n.mesh().is_some() && n.skin().is_some_and(|s| s.index() != skin.index()))
        .map(|n| n.name().unwrap_or("(unnamed)").to_string())
        .collect();
    if !others.is_empty() {
        tracing::warn!(
            "{file}: {} skins; drawing the meshes of skin {} ({} joints), not {}",
            gltf.skins().count(),
            skin.index(),
            skin.joints().count(),
            others.join(", ")
        );
    }

    // Bones: the skin's joints, each parented to its nearest ancestor among them.
    let mut node_parent = vec![None; gltf.nodes().count()];
    for node in gltf.nodes() {
        for child in node.children() {
            node_parent[child.index()] = Some(node.index());
        }
    }
    let joint_nodes: Vec<usize> = skin.joints().map(|n| n.index()).collect();
    let depth = |mut n: usize| {
        let mut d = 0usize;
        while let Some(p) = node_parent[n] {
            d += 1;
            n = p;
            if d > node_parent.len() {
                break; // a cycle; gltf's validation refuses those, this is a guard
            }
        }
        d
    };
    let mut order: Vec<usize> = (0..joint_nodes.len()).collect();
    order.sort_by_key(|&k| depth(joint_nodes[k]));
    let bone_of_node: HashMap<usize, usize> = order
        .iter()
        .enumerate()
        .map(|(b, &k)| (joint_nodes[k], b))
        .collect();
    let ibm = match skin.inverse_bind_matrices() {
        Some(a) => read_values(a, &[Dimensions::Mat4], &buffers, &bad)?,
        None => {
            return Err(bad(format!(
                "skin {} has no inverse bind matrices",
                skin.index()
            )))
        }
    };
    if ibm.len() < 16 * joint_nodes.len() {
        return Err(bad(format!(
            "skin {}: {} inverse bind matrices for {} joints",
            skin.index(),
            ibm.len() / 16,
            joint_nodes.len()
        )));
    }
    let node_name = |n: usize| {
        gltf.nodes()
            .nth(n)
            .and_then(|n| n.name().map(str::to_string))
            .unwrap_or_else(|| format!("node {n}"))
    };
    // Each node's frame at rest: its transform composed down from the scene's root.
    let local: Vec<DMat4> = gltf
        .nodes()
        .map(|n| DMat4::from_cols_array_2d(&n.transform().matrix().map(|c| c.map(f64::from))))
        .collect();
    let at_rest = |node: usize| {
        let (mut m, mut n, mut steps) = (local[node], node, 0);
        while let Some(p) = node_parent[n].filter(|_| steps <= node_parent.len()) {
            m = local[p] * m;
            n = p;
            steps += 1;
        }
        m
    };
    let mut character_bones = Vec::with_capacity(order.len());
    for &k in &order {
        let node = joint_nodes[k];
        let m = DMat4::from_cols_slice(&ibm[16 * k..16 * k + 16]);
        let bind = rigid(m.inverse()).ok_or_else(|| {
            bad(format!(
                "joint `{}`: its inverse bind matrix is not invertible",
                node_name(node)
            ))
        })?;
        let node_at_rest = |node: usize| {
            rigid(at_rest(node)).ok_or_else(|| {
                bad(format!(
                    "joint `{}`: its node's transform is not invertible",
                    node_name(node)
                ))
            })
        };
        let mut p = node_parent[node];
        while let Some(q) = p.filter(|q| !bone_of_node.contains_key(q)) {
            p = node_parent[q];
        }
        let parent = p.and_then(|q| bone_of_node.get(&q).map(|&b| (q, b)));
        // The rest pose as the nodes turn each bone from its parent, from the topmost
        // bone's bind frame: whatever the nodes above the skeleton do (turn Z up into Y
        // up, scale centimetres) is already in the inverse bind matrices.
        let rest = match parent {
            Some((q, b)) => {
                let from_parent = node_at_rest(q)?.inverse().mul(&node_at_rest(node)?);
                let parent_rest: &Bone = &character_bones[b];
                parent_rest.rest.mul(&from_parent)
            }
            None => bind,
        };
        character_bones.push(Bone {
            name: node_name(node),
            parent: parent.map(|(_, b)| b),
            bind,
            rest,
            joint: None,
        });
    }
    map_bones(
        &mut character_bones,
        &joint_nodes,
        &bone_of_node,
        &json,
        bones,
    )
    .map_err(bad)?;

    let mut character = Character {
        source: file.clone(),
        bones: character_bones,
        positions: Vec::new(),
        normals: Vec::new(),
        colors: Vec::new(),
        joints: Vec::new(),
        weights: Vec::new(),
        indices: Vec::new(),
        double_sided: false,
    };
    // The skin's joint order → bone order.
    let mut bone_of_joint = vec![0u16; joint_nodes.len()];
    for (k, &node) in joint_nodes.iter().enumerate() {
        bone_of_joint[k] = bone_of_node[&node] as u16;
    }
    let textures = Textures::new(&gltf, &buffers);
    for node in gltf
        .nodes()
        .filter(|n| n.skin().is_some_and(|s| s.index() == skin.index()))
    {
        let Some(mesh) = node.mesh() else { continue };
        for primitive in mesh.primitives() {
            let what = format!(
                "mesh `{}` primitive {}",
                mesh.name().unwrap_or("(unnamed)"),
                primitive.index()
            );
            if primitive.mode() != ::gltf::mesh::Mode::Triangles {
                tracing::warn!("{file}: {what} is not made of triangles: left out");
                continue;
            }
            character.double_sided |= primitive.material().double_sided();
            read_primitive(
                &primitive,
                &buffers,
                &bone_of_joint,
                &textures,
                &mut character,
            )
            .map_err(|m| bad(format!("{what}: {m}")))?;
        }
    }
    if character.indices.is_empty() {
        return Err(bad(format!("skin {} skins no triangles", skin.index())));
    }
    Ok(character)
}

/// The humanoid bones a VRM file declares (VRM 1.0 `VRMC_vrm.humanoid` or 0.x
/// `VRM.humanoid`), as pairs of a VRM bone name (1.0's names) and the node's name; empty
/// for a file that is not VRM.
pub fn vrm_humanoid_bones(path: impl AsRef<Path>) -> Result<Vec<(String, String)>> {
    let path = path.as_ref();
    let bad = |message: String| Error::Parse {
        file: path.display().to_string(),
        line: 0,
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    check_glb_header(&bytes).map_err(bad)?;
    let json = document_json(&bytes).map_err(bad)?;
    let nodes = json["nodes"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or_default();
    vrm_humanoid(&json)
        .into_iter()
        .map(|(bone, node)| {
            let name = nodes.get(node).ok_or_else(|| {
                bad(format!(
                    "humanoid bone `{bone}` names node {node}, which does not exist"
                ))
            })?["name"]
                .as_str()
                .map_or_else(|| format!("node {node}"), str::to_string);
            Ok((bone, name))
        })
        .collect()
}

/// The JSON document of a `.gltf` or of a `.glb`'s first chunk (for the VRM extensions,
/// which the `gltf` crate does not read).
fn document_json(bytes: &[u8]) -> std::result::Result<Value, String> {
    let text = if bytes.starts_with(b"glTF") {
        let len = bytes
            .get(12..16)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
            .ok_or("truncated binary glTF: no JSON chunk")?;
        bytes
            .get(20..20 + len)
            .ok_or("truncated binary glTF: JSON chunk cut short")?
    } else {
        bytes
    };
    serde_json::from_slice(text).map_err(|e| format!("not glTF JSON: {e}"))
}

/// Names each bone's troupe joint: the best-matching built-in names, then the user's map;
/// an error names the required humanoid bones that are still missing.
fn map_bones(
    bones: &mut [Bone],
    joint_nodes: &[usize],
    bone_of_node: &HashMap<usize, usize>,
    json: &Value,
    user: &[(String, String)],
) -> std::result::Result<(), String> {
    // Candidate maps: VRM bone name → bone index.
    let by_vrm = vrm_humanoid(json);
    let mut candidates: Vec<(&str, HashMap<String, usize>)> = Vec::new();
    if !by_vrm.is_empty() {
        let found = by_vrm
            .iter()
            .filter_map(|(b, node)| Some((b.clone(), *bone_of_node.get(node)?)))
            .collect();
        candidates.push(("VRM humanoid", found));
    }
    let mixamo = bones
        .iter()
        .enumerate()
        .filter_map(|(b, bone)| Some((names::mixamo_bone(&bone.name)?, b)))
        .collect();
    candidates.push(("Mixamo", mixamo));
    let troupe_joints: Vec<&str> = names::VRM_BONES
        .iter()
        .map(|(_, j)| *j)
        .chain(["l_ankle", "r_ankle", "vt6", "HumanoidRoot"])
        .collect();
    let mut hanim: HashMap<String, usize> = HashMap::new();
    for (b, bone) in bones.iter().enumerate() {
        if let Some(j) = names::hanim_joint(&bone.name, &troupe_joints) {
            hanim.insert(j.to_string(), b);
        }
    }
    let (_, best) = candidates
        .into_iter()
        .max_by_key(|(_, m)| m.len())
        .unwrap_or(("", HashMap::new()));
    // Troupe joint name → bone, from the best VRM-named map or H-Anim, whichever has more.
    let mut chosen: HashMap<String, usize> = if hanim.len() > best.len() {
        hanim
    } else {
        best.into_iter()
            .filter_map(|(b, k)| Some((names::vrm_joint(&b)?.to_string(), k)))
            .collect()
    };
    let by_name: HashMap<&str, usize> = bones
        .iter()
        .enumerate()
        .map(|(b, bone)| (bone.name.as_str(), b))
        .collect();
    for (key, node) in user {
        // A VRM humanoid bone name (any case), else a troupe joint name, which dressing
        // checks against the skeleton.
        let joint = names::VRM_BONES
            .iter()
            .find(|(b, _)| b.eq_ignore_ascii_case(key))
            .map_or_else(|| key.clone(), |(_, j)| j.to_string());
        let &b = by_name.get(node.as_str()).ok_or_else(|| {
            let known: Vec<&str> = bones.iter().map(|b| b.name.as_str()).collect();
            format!("bones map: `{key}` names `{node}`, which is not a joint of the skin (its joints: {})", known.join(", "))
        })?;
        chosen.retain(|_, v| *v != b);
        chosen.insert(joint, b);
    }
    let missing: Vec<&str> = names::REQUIRED
        .iter()
        .copied()
        .filter(|b| {
            // A foot may follow the ankle (H-Anim) as well as the subtalar joint.
            names::vrm_joint(b).is_some_and(|j| {
                !chosen.contains_key(j) && !chosen.contains_key(&j.replace("subtalar", "ankle"))
            })
        })
        .collect();
    if !missing.is_empty() {
        let known: Vec<&str> = bones.iter().map(|b| b.name.as_str()).take(40).collect();
        return Err(format!(
            "not a humanoid troupe can dress: no bone found for {} (its {} joints: {}{}); name them with a `bones` map",
            missing.join(", "),
            joint_nodes.len(),
            known.join(", "),
            if joint_nodes.len() > 40 { ", …" } else { "" }
        ));
    }
    for (joint, b) in chosen {
        bones[b].joint = Some(joint);
    }
    Ok(())
}

/// A VRM file's humanoid bones (VRM bone name → node), VRM 1.0 or 0.x.
fn vrm_humanoid(json: &Value) -> Vec<(String, usize)> {
    let ext = &json["extensions"];
    if let Some(bones) = ext["VRMC_vrm"]["humanoid"]["humanBones"].as_object() {
        return bones
            .iter()
            .filter_map(|(name, b)| Some((name.clone(), b["node"].as_u64()? as usize)))
            .collect();
    }
    let Some(bones) = ext["VRM"]["humanoid"]["humanBones"].as_array() else {
        return Vec::new();
    };
    bones
        .iter()
        .filter_map(|b| {
            let name = b["bone"].as_str()?;
            let name = names::VRM0_THUMBS
                .iter()
                .find(|(old, _)| *old == name)
                .map_or(name, |(_, new)| *new);
            Some((name.to_string(), b["node"].as_u64()? as usize))
        })
        .collect()
}

/// The rotation and translation of an affine matrix (its scale dropped), or `None` when
/// it is singular or not finite.
fn rigid(m: DMat4) -> Option<Transform> {
    if !m.is_finite() || m.determinant().abs() < 1e-12 {
        return None;
    }
    let (_, rotation, translation) = m.to_scale_rotation_translation();
    let rotation = if rotation.is_finite() {
        rotation.normalize()
    } else {
        DQuat::IDENTITY
    };
    Some(Transform::new(rotation, translation))
}

/// Reads one triangle primitive's vertices, weights, colours and triangles into
/// `character`.
fn read_primitive(
    primitive: &::gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    bone_of_joint: &[u16],
    textures: &Textures,
    character: &mut Character,
) -> std::result::Result<(), String> {
    let get = |semantic: ::gltf::Semantic,
               dims: &[Dimensions]|
     -> std::result::Result<Option<Vec<f64>>, String> {
        primitive
            .get(&semantic)
            .map(|a| {
                read_values(a, dims, buffers, &|m| Error::Invalid(m)).map_err(|e| e.to_string())
            })
            .transpose()
    };
    let positions = get(::gltf::Semantic::Positions, &[Dimensions::Vec3])?.ok_or("no POSITION")?;
    let n = positions.len() / 3;
    let counted = |v: Option<Vec<f64>>,
                   per: usize,
                   name: &str|
     -> std::result::Result<Option<Vec<f64>>, String> {
        match v {
            Some(v) if v.len() != n * per => Err(format!(
                "{name} has {} values for {n} vertices",
                v.len() / per
            )),
            other => Ok(other),
        }
    };
    let normals = counted(
        get(::gltf::Semantic::Normals, &[Dimensions::Vec3])?,
        3,
        "NORMAL",
    )?;
    let uvs = counted(
        get(::gltf::Semantic::TexCoords(0), &[Dimensions::Vec2])?,
        2,
        "TEXCOORD_0",
    )?;
    // Vertex colours (linear RGB or RGBA) multiply the material's, as glTF says.
    let vertex_colors = match get(
        ::gltf::Semantic::Colors(0),
        &[Dimensions::Vec3, Dimensions::Vec4],
    )? {
        Some(c) if c.len() == n * 3 => Some((c, 3)),
        Some(c) if c.len() == n * 4 => Some((c, 4)),
        Some(c) => return Err(format!("COLOR_0 has {} values for {n} vertices", c.len())),
        None => None,
    };
    let mut sets = Vec::new();
    for set in 0..2 {
        let j = counted(
            get(::gltf::Semantic::Joints(set), &[Dimensions::Vec4])?,
            4,
            "JOINTS",
        )?;
        let w = counted(
            get(::gltf::Semantic::Weights(set), &[Dimensions::Vec4])?,
            4,
            "WEIGHTS",
        )?;
        match (j, w) {
            (Some(j), Some(w)) => sets.push((j, w)),
            (None, None) => {}
            _ => return Err(format!("JOINTS_{set} and WEIGHTS_{set} must come together")),
        }
    }
    if sets.is_empty() {
        return Err("no JOINTS_0/WEIGHTS_0: the mesh is not weighted to the skeleton".into());
    }
    let indices: Vec<u32> = match primitive.indices() {
        Some(a) => read_values(a, &[Dimensions::Scalar], buffers, &|m| Error::Invalid(m))
            .map_err(|e| e.to_string())?
            .into_iter()
            .map(|i| i as u32)
            .collect(),
        None => (0..n as u32).collect(),
    };
    if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("a triangle names vertex {i} of {n}"));
    }
    let color = textures.material_color(primitive.material());
    let base = character.positions.len() as u32;
    for v in 0..n {
        let mut influences: Vec<(u16, f64)> = Vec::with_capacity(8);
        for (j, w) in &sets {
            for k in 0..4 {
                let (joint, weight) = (j[4 * v + k], w[4 * v + k]);
                if !weight.is_finite() || weight < 0.0 {
                    return Err(format!("vertex {v} has weight {weight} (weights are ≥ 0)"));
                }
                if weight > 0.0 {
                    let bone = *bone_of_joint.get(joint as usize).ok_or_else(|| {
                        format!(
                            "vertex {v} names joint {joint}, but the skin has {}",
                            bone_of_joint.len()
                        )
                    })?;
                    influences.push((bone, weight));
                }
            }
        }
        let (joints, weights) = strongest_four(influences)
            .ok_or_else(|| format!("vertex {v}: its weights are all zero"))?;
        character.joints.push(joints);
        character.weights.push(weights);
        let p = [positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]];
        if p.iter().any(|x| !x.is_finite()) {
            return Err(format!("vertex {v} has a position that is not a number"));
        }
        character.positions.push(p.map(|x| x as f32));
        character.normals.push(match &normals {
            Some(nv) => DVec3::new(nv[3 * v], nv[3 * v + 1], nv[3 * v + 2])
                .try_normalize()
                .unwrap_or(DVec3::Y)
                .as_vec3()
                .to_array(),
            None => [0.0; 3],
        });
        let uv = uvs.as_ref().map(|t| [t[2 * v], t[2 * v + 1]]);
        let mut c = color.at(uv);
        if let Some((colors, per)) = &vertex_colors {
            for (k, c) in c.iter_mut().enumerate() {
                *c *= srgb(colors[per * v + k] as f32);
            }
        }
        character.colors.push(c);
    }
    character.indices.extend(indices.iter().map(|i| i + base));
    if normals.is_none() {
        face_normals(character, base as usize, &indices);
    }
    Ok(())
}

/// Keeps the four largest influences and renormalises them to sum to one; `None` when
/// there are none.
fn strongest_four(mut influences: Vec<(u16, f64)>) -> Option<([u16; 4], [f32; 4])> {
    // Merge repeats of one bone first (a file may name a joint twice).
    influences.sort_by_key(|&(b, _)| b);
    influences.dedup_by(|a, b| {
        if a.0 == b.0 {
            b.1 += a.1;
            true
        } else {
            false
        }
    });
    influences.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    influences.truncate(4);
    let sum: f64 = influences.iter().map(|(_, w)| w).sum();
    if sum <= 0.0 {
        return None;
    }
    let mut joints = [0u16; 4];
    let mut weights = [0f32; 4];
    for (k, (b, w)) in influences.into_iter().enumerate() {
        joints[k] = b;
        weights[k] = (w / sum) as f32;
    }
    Some((joints, weights))
}

/// Area-weighted normals for a primitive that has none.
fn face_normals(character: &mut Character, base: usize, indices: &[u32]) {
    let p = |i: u32| DVec3::from(character.positions[base + i as usize].map(f64::from));
    let mut sums = vec![DVec3::ZERO; character.positions.len() - base];
    for t in indices.chunks_exact(3) {
        let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
        for &i in t {
            sums[i as usize] += n;
        }
    }
    for (k, s) in sums.iter().enumerate() {
        character.normals[base + k] = s.try_normalize().unwrap_or(DVec3::Y).as_vec3().to_array();
    }
}

/// The values of an accessor as numbers (normalised integers scaled to [0, 1]), row
/// after row, checking every size against its buffer.
fn read_values(
    accessor: Accessor<'_>,
    dims: &[Dimensions],
    buffers: &[Vec<u8>],
    bad: &dyn Fn(String) -> Error,
) -> Result<Vec<f64>> {
    let i = accessor.index();
    if !dims.contains(&accessor.dimensions()) {
        return Err(bad(format!(
            "accessor {i}: expected {:?}, found {:?}",
            dims,
            accessor.dimensions()
        )));
    }
    if accessor.sparse().is_some() {
        return Err(bad(format!(
            "accessor {i}: sparse accessors are not supported"
        )));
    }
    let view = accessor
        .view()
        .ok_or_else(|| bad(format!("accessor {i}: no buffer view")))?;
    let width = accessor.data_type().size();
    let count = accessor.dimensions().multiplicity();
    let element = width * count;
    let stride = view.stride().unwrap_or(element);
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| bad(format!("accessor {i}: no buffer {}", view.buffer().index())))?;
    let n = accessor.count();
    let start = view.offset().checked_add(accessor.offset());
    let end = start
        .zip(n.checked_sub(1).map_or(Some(0), |m| m.checked_mul(stride)))
        .and_then(|(s, span)| {
            s.checked_add(span)?
                .checked_add(if n > 0 { element } else { 0 })
        });
    let fits = end.is_some_and(|e| e <= data.len() && e <= view.offset() + view.length());
    let (Some(start), true) = (start, fits) else {
        return Err(bad(format!(
            "accessor {i}: {n} elements do not fit in their buffer (cut short?)"
        )));
    };
    let normalized = accessor.normalized();
    let mut out = Vec::with_capacity(n * count);
    for e in 0..n {
        for c in 0..count {
            let at = start + e * stride + c * width;
            let b = &data[at..at + width];
            out.push(match accessor.data_type() {
                DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                DataType::U16 => {
                    let v = u16::from_le_bytes([b[0], b[1]]) as f64;
                    if normalized {
                        v / 65535.0
                    } else {
                        v
                    }
                }
                DataType::U8 => {
                    let v = b[0] as f64;
                    if normalized {
                        v / 255.0
                    } else {
                        v
                    }
                }
                DataType::I16 => {
                    let v = i16::from_le_bytes([b[0], b[1]]) as f64;
                    if normalized {
                        (v / 32767.0).max(-1.0)
                    } else {
                        v
                    }
                }
                DataType::I8 => {
                    let v = b[0] as i8 as f64;
                    if normalized {
                        (v / 127.0).max(-1.0)
                    } else {
                        v
                    }
                }
            });
        }
    }
    Ok(out)
}

/// A linear colour component as sRGB, the colours here being sRGB as the viewer's
/// palette (a product of linear components is the product of their sRGB ones).
fn srgb(c: f32) -> f32 {
    c.clamp(0.0, 1.0).powf(1.0 / 2.2)
}

/// Decoded base-colour textures, by image index (only PNG images decode).
struct Textures {
    images: HashMap<usize, image::RgbaImage>,
}

/// A material's colour: a factor, and a texture to sample at the vertex's UV.
struct MaterialColor<'a> {
    factor: [f32; 3],
    texture: Option<&'a image::RgbaImage>,
}

impl Textures {
    fn new(gltf: &Gltf, buffers: &[Vec<u8>]) -> Textures {
        let mut images = HashMap::new();
        for image in gltf.images() {
            let bytes = match image.source() {
                ::gltf::image::Source::View { view, .. } => buffers
                    .get(view.buffer().index())
                    .and_then(|b| b.get(view.offset()..view.offset() + view.length())),
                ::gltf::image::Source::Uri { .. } => None,
            };
            let decoded = bytes
                .and_then(|b| image::load_from_memory_with_format(b, image::ImageFormat::Png).ok());
            if let Some(d) = decoded {
                images.insert(image.index(), d.to_rgba8());
            }
        }
        Textures { images }
    }

    fn material_color(&self, material: ::gltf::Material<'_>) -> MaterialColor<'_> {
        let pbr = material.pbr_metallic_roughness();
        let f = pbr.base_color_factor();
        MaterialColor {
            factor: [srgb(f[0]), srgb(f[1]), srgb(f[2])],
            texture: pbr
                .base_color_texture()
                .and_then(|t| self.images.get(&t.texture().source().index())),
        }
    }
}

impl MaterialColor<'_> {
    /// The sRGB colour at texture coordinate `uv` (wrapping, nearest texel).
    fn at(&self, uv: Option<[f64; 2]>) -> [f32; 3] {
        let (Some(t), Some([u, v])) = (self.texture, uv) else {
            return self.factor;
        };
        let (w, h) = t.dimensions();
        let wrap = |x: f64, n: u32| ((x.rem_euclid(1.0) * n as f64) as u32).min(n - 1);
        let p = t.get_pixel(wrap(u, w), wrap(v, h));
        [0, 1, 2].map(|c| p[c] as f32 / 255.0 * self.factor[c])
    }
}
