//! Writing a rig as glTF 2.0 with `gltf-json`'s typed structures: a `.gltf` (JSON) with a
//! `.bin` buffer beside it, or one binary `.glb`.

use super::character::{add_character, character_rig};
use super::objects::object_node;
use super::skin::{add_skin, with_helper_joints};
use super::uri;
use crate::error::{Error, Result};
use crate::rig::Rig;
use ::gltf::binary::{Glb, Header};
use glam::{DMat4, DQuat};
use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::animation::{Interpolation, Property};
use json::validation::{Checked::Valid, USize64};
use json::{Index, Root};
use std::borrow::Cow;
use std::path::Path;
use troupe_body::{Dressing, Skin, Transform};
use troupe_motion::object_motion::ObjectMotion;

/// A growing binary buffer and the document whose buffer views and accessors point into
/// it.
struct Builder {
    root: Root,
    bytes: Vec<u8>,
}

impl Builder {
    /// Adds `count` elements of `type_` from f32 `data` as one view and one accessor; with
    /// `bounds`, the accessor carries its min and max (glTF requires them on animation
    /// inputs).
    fn floats(
        &mut self,
        data: &[f32],
        type_: Type,
        count: usize,
        bounds: bool,
    ) -> Index<json::Accessor> {
        pad_to_four(&mut self.bytes);
        let offset = self.bytes.len();
        for x in data {
            self.bytes.extend_from_slice(&x.to_le_bytes());
        }
        let view = self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(data.len() * 4),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: None,
            extensions: None,
            extras: Default::default(),
        });
        let (min, max) = if bounds {
            let min = data.iter().copied().fold(f32::INFINITY, f32::min);
            let max = data.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            (
                Some(json::Value::from(vec![min])),
                Some(json::Value::from(vec![max])),
            )
        } else {
            (None, None)
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(GenericComponentType(ComponentType::F32)),
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

    /// Adds one `LINEAR` sampler from `input` to `output` and a channel driving `path` of
    /// `node`.
    fn channel(
        &mut self,
        animation: &mut json::Animation,
        input: Index<json::Accessor>,
        output: Index<json::Accessor>,
        node: usize,
        path: Property,
    ) {
        let sampler = Index::push(
            &mut animation.samplers,
            json::animation::Sampler {
                input,
                output,
                interpolation: Valid(Interpolation::Linear),
                extensions: None,
                extras: Default::default(),
            },
        );
        animation.channels.push(json::animation::Channel {
            sampler,
            target: json::animation::Target {
                node: Index::new(node as u32),
                path: Valid(path),
                extensions: None,
                extras: Default::default(),
            },
            extensions: None,
            extras: Default::default(),
        });
    }
}

/// Zero bytes up to the next multiple of four (glTF aligns views and chunks so).
fn pad_to_four(bytes: &mut Vec<u8>) {
    bytes.resize(bytes.len().next_multiple_of(4), 0);
}

/// The glTF document and binary buffer of `rig`: one node per joint, one skin, one
/// animation named `name`. `bin_uri` is how the document names the buffer (`None`: the
/// binary chunk of a `.glb`).
pub fn to_gltf(rig: &Rig, name: &str, bin_uri: Option<&str>) -> (Root, Vec<u8>) {
    to_gltf_with_objects(rig, &[], name, bin_uri)
}

/// [`to_gltf`] with recorded objects: each a node of the scene animated on the rig's
/// frames (see `objects`); `objects` pairs each object with its one-joint rig
/// ([`Rig::from_object`] on the body rig's times).
pub fn to_gltf_with_objects(
    rig: &Rig,
    objects: &[(&ObjectMotion, Rig)],
    name: &str,
    bin_uri: Option<&str>,
) -> (Root, Vec<u8>) {
    to_gltf_bound(rig, None, objects, name, bin_uri)
}

/// [`to_gltf_with_objects`], the skin's inverse bind matrices written from the joints'
/// global frames `bound` (one per joint of `rig`) instead of from its rest: a troupe
/// skin is bound in a posture of its own ([`Skin::rest`]), not in the rest pose its file
/// shows.
pub(crate) fn to_gltf_bound(
    rig: &Rig,
    bound: Option<&[Transform]>,
    objects: &[(&ObjectMotion, Rig)],
    name: &str,
    bin_uri: Option<&str>,
) -> (Root, Vec<u8>) {
    let n = rig.names.len();
    let mut b = Builder {
        root: Root {
            asset: json::Asset {
                generator: Some(concat!("troupe ", env!("CARGO_PKG_VERSION")).into()),
                ..Default::default()
            },
            ..Default::default()
        },
        bytes: Vec::new(),
    };
    for j in 0..n {
        let t = rig.rest[j].translation.as_vec3();
        let r = rig.rest[j].rotation;
        let children: Vec<Index<json::Node>> = (0..n)
            .filter(|&c| rig.parents[c] == Some(j))
            .map(|c| Index::new(c as u32))
            .collect();
        b.root.push(json::Node {
            name: Some(rig.names[j].clone()),
            translation: Some(t.to_array()),
            rotation: (r != DQuat::IDENTITY)
                .then(|| json::scene::UnitQuaternion(r.as_quat().to_array())),
            children: (!children.is_empty()).then_some(children),
            ..Default::default()
        });
    }
    let mut roots: Vec<Index<json::Node>> = (0..n)
        .filter(|&j| rig.parents[j].is_none())
        .map(|j| Index::new(j as u32))
        .collect();
    // glTF asks a skin's `skeleton` to be a common root of all its joints: a rig of
    // several roots (a BVH with several ROOTs) has none among its nodes, and the skin
    // leaves it out (its joints then resolve from the scene's root).
    let skeleton = match roots[..] {
        [root] => Some(root),
        _ => None,
    };

    // Inverse bind matrices: inverse of each joint's global bind transform (column major),
    // its rest's unless bound elsewhere.
    let rest = rig.rest_globals();
    debug_assert!(
        bound.is_none_or(|b| b.len() == n),
        "a bind frame for each joint"
    );
    let ibm: Vec<f32> = bound
        .unwrap_or(&rest)
        .iter()
        .flat_map(|g| {
            DMat4::from_rotation_translation(g.rotation, g.translation)
                .inverse()
                .to_cols_array()
                .map(|x| x as f32)
        })
        .collect();
    let ibm = b.floats(&ibm, Type::Mat4, n, false);

    let mut animation = json::Animation {
        name: Some(name.into()),
        channels: Vec::new(),
        samplers: Vec::new(),
        extensions: None,
        extras: Default::default(),
    };
    let frames = rig.times.len();
    if frames > 0 {
        let times: Vec<f32> = rig.times.iter().map(|&t| t as f32).collect();
        let input = b.floats(&times, Type::Scalar, frames, true);
        for j in 0..n {
            // A joint that stays at its rest rotation needs no channel: its node has it.
            if rig.rotations.iter().all(|f| f[j] == rig.rest[j].rotation) {
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
                    q.as_quat().to_array()
                })
                .collect();
            let output = b.floats(&data, Type::Vec4, frames, false);
            b.channel(&mut animation, input, output, j, Property::Rotation);
        }
        for (i, &j) in rig.moving.iter().enumerate() {
            let data: Vec<f32> = rig
                .translations
                .iter()
                .flat_map(|f| f[i].as_vec3().to_array())
                .collect();
            let output = b.floats(&data, Type::Vec3, frames, false);
            b.channel(&mut animation, input, output, j, Property::Translation);
        }
        roots.extend(add_object_nodes(&mut b, &mut animation, input, objects));
    }
    pad_to_four(&mut b.bytes);
    let skin = json::Skin {
        name: Some(name.into()),
        joints: (0..n).map(|j| Index::new(j as u32)).collect(),
        inverse_bind_matrices: Some(ibm),
        skeleton,
        extensions: None,
        extras: Default::default(),
    };
    b.root.push(skin);
    let scene = b.root.push(json::Scene {
        name: Some(name.into()),
        nodes: roots,
        extensions: None,
        extras: Default::default(),
    });
    b.root.scene = Some(scene);
    b.root.push(json::Buffer {
        byte_length: USize64::from(b.bytes.len()),
        uri: bin_uri.map(str::to_string),
        name: None,
        extensions: None,
        extras: Default::default(),
    });
    if !animation.channels.is_empty() {
        b.root.push(animation);
    }
    (b.root, b.bytes)
}

/// Adds a node per recorded object (see [`super::objects`]) and its translation and
/// rotation channels on the frames whose times accessor is `input`; returns the nodes,
/// to list among the scene's roots.
fn add_object_nodes(
    b: &mut Builder,
    animation: &mut json::Animation,
    input: Index<json::Accessor>,
    objects: &[(&ObjectMotion, Rig)],
) -> Vec<Index<json::Node>> {
    let mut nodes = Vec::new();
    for (object, rig) in objects {
        let frames = rig.times.len();
        let added = object_node(object, rig);
        let node = b.root.push(added.node);
        let output = b.floats(&added.translations, Type::Vec3, frames, false);
        b.channel(
            animation,
            input,
            output,
            node.value(),
            Property::Translation,
        );
        let output = b.floats(&added.rotations, Type::Vec4, frames, false);
        b.channel(animation, input, output, node.value(), Property::Rotation);
        nodes.push(node);
    }
    nodes
}

/// The document and binary buffer of a file: [`to_gltf_with_objects`], plus `skin` as the
/// body's skinned mesh when there is one.
fn document(
    rig: &Rig,
    skin: Option<&Skin>,
    objects: &[(&ObjectMotion, Rig)],
    name: &str,
    uri: Option<&str>,
) -> (Root, Vec<u8>) {
    // The skin's helper joints join the rig, so its slots are the rig's joints.
    let rig = &match skin {
        Some(skin) => with_helper_joints(rig, skin),
        None => rig.clone(),
    };
    let bound = skin.map(|skin| skin.rest.as_slice());
    let (mut root, mut bytes) = to_gltf_bound(rig, bound, objects, name, uri);
    if let Some(skin) = skin {
        add_skin(&mut root, &mut bytes, skin, name);
    }
    (root, bytes)
}

/// Writes `rig` as `path` (`.gltf`) and a `.bin` of the same stem beside it.
pub fn write_gltf(path: impl AsRef<Path>, rig: &Rig, name: &str) -> Result<()> {
    write_gltf_with(path, rig, None, &[], name)
}

/// Writes `rig` as `path` (`.gltf`) and a `.bin` beside it, with `skin` (made for the
/// skeleton the rig comes from) as its skinned mesh and recorded `objects` as animated
/// nodes (see [`to_gltf_with_objects`]).
pub fn write_gltf_with(
    path: impl AsRef<Path>,
    rig: &Rig,
    skin: Option<&Skin>,
    objects: &[(&ObjectMotion, Rig)],
    name: &str,
) -> Result<()> {
    save_document(path.as_ref(), false, |uri| {
        document(rig, skin, objects, name, uri)
    })
}

/// Writes `rig` as one binary glTF file `path` (`.glb`).
pub fn write_glb(path: impl AsRef<Path>, rig: &Rig, name: &str) -> Result<()> {
    write_glb_with(path, rig, None, &[], name)
}

/// Writes `rig` as one binary glTF file `path` (`.glb`) with `skin` (made for the
/// skeleton the rig comes from) as its skinned mesh and recorded `objects` as animated
/// nodes (see [`to_gltf_with_objects`]).
pub fn write_glb_with(
    path: impl AsRef<Path>,
    rig: &Rig,
    skin: Option<&Skin>,
    objects: &[(&ObjectMotion, Rig)],
    name: &str,
) -> Result<()> {
    save_document(path.as_ref(), true, |uri| {
        document(rig, skin, objects, name, uri)
    })
}

/// Writes a user's character (`dressing`) following `troupe`, the rig of the skeleton
/// it was fitted to, with recorded `objects` (on `troupe`'s frames), as `path`: one binary
/// file if its extension is `.glb` (any case), else `.gltf` and a `.bin` beside it (see
/// [`super::character`]).
pub fn write_character(
    path: impl AsRef<Path>,
    dressing: &Dressing,
    troupe: &Rig,
    objects: &[(&ObjectMotion, Rig)],
    name: &str,
) -> Result<()> {
    let path = path.as_ref();
    let binary = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    save_document(path, binary, |uri| {
        let rig = character_rig(dressing, troupe);
        let (mut root, mut bytes) = to_gltf_with_objects(&rig, objects, name, uri);
        add_character(&mut root, &mut bytes, dressing, name);
        (root, bytes)
    })
}

/// Writes the document `build` makes, given how it names its buffer: as one binary
/// `path` (a JSON chunk and a binary chunk, the buffer unnamed) when `binary`, else as
/// JSON `path` with the buffer in a `.bin` of the same stem beside it (named by its
/// percent-encoded file name).
fn save_document(
    path: &Path,
    binary: bool,
    build: impl FnOnce(Option<&str>) -> (Root, Vec<u8>),
) -> Result<()> {
    if !binary {
        let bin = path.with_extension("bin");
        let uri = bin
            .file_name()
            .map(|s| uri::encode(&s.to_string_lossy()))
            .unwrap_or_else(|| "motion.bin".into());
        let (root, bytes) = build(Some(&uri));
        let text = root.to_string_pretty().map_err(|e| json_error(path, e))?;
        std::fs::write(path, text).map_err(|e| Error::io(path, e))?;
        return std::fs::write(&bin, bytes).map_err(|e| Error::io(&bin, e));
    }
    let (root, bytes) = build(None);
    let glb = Glb {
        header: Header {
            magic: *b"glTF",
            version: 2,
            // `Glb::to_vec` computes the total length (and pads both chunks) itself.
            length: 0,
        },
        json: Cow::Owned(root.to_vec().map_err(|e| json_error(path, e))?),
        bin: Some(Cow::Owned(bytes)),
    };
    let bytes = glb.to_vec().map_err(|e| Error::Io {
        path: path.display().to_string(),
        message: format!("binary glTF: {e}"),
    })?;
    std::fs::write(path, bytes).map_err(|e| Error::io(path, e))
}

/// A document that did not serialize (it cannot happen for what [`to_gltf`] builds, and
/// still names the file if it does).
fn json_error(path: &Path, e: serde_json::Error) -> Error {
    Error::Io {
        path: path.display().to_string(),
        message: format!("glTF JSON: {e}"),
    }
}
