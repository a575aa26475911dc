//! The skin look: each actor's generated [`Skin`] deformed on the GPU by linear blend
//! skinning. Skins are built once per skeleton (actors of one template instance share
//! it) and kept on the GPU; each frame uploads only every actor's joint matrices and
//! colours, one uniform block per actor, and draws its skin with that block.
//!
//! Linear blend skinning rather than dual quaternions: it is what glTF files and every
//! glTF viewer use, so the window, the PNG frames and an exported `.glb` show the same
//! deformation; the skin's weights are blended over a few centimetres on each side of a
//! joint, which keeps LBS's volume loss small at elbows and knees.

use crate::frame::ActorFrame;
use bytemuck::{Pod, Zeroable};
use std::collections::HashMap;
use std::sync::Arc;
use troupe_body::skin::Region;
use troupe_body::{Skeleton, Skin};
use wgpu::util::DeviceExt;

/// The most joints a skinned skeleton may have (troupe's templates have 66); an actor
/// with more is drawn as solids.
pub(crate) const MAX_JOINTS: usize = 96;
/// Colour slots of an actor's block: the skin regions, then the two hands.
const COLORS: usize = 8;
/// Colour slot of the left hand's skin; the right hand's is the next.
const LEFT_HAND: u32 = 6;

/// One skin vertex as the GPU reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct SkinVertex {
    pos: [f32; 3],
    normal: [f32; 3],
    joints: [u16; 4],
    weights: [f32; 4],
    /// Colour slot: a [`Region`], or a hand.
    part: u32,
}

/// An actor's uniform block: colours and skinning matrices.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct SkinBlock {
    pub colors: [[f32; 4]; COLORS],
    pub joints: [[[f32; 4]; 4]; MAX_JOINTS],
}

/// A skin on the GPU.
pub(crate) struct GpuSkin {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub count: u32,
    pub far_indices: wgpu::Buffer,
    pub far_count: u32,
    pub skin: Arc<Skin>,
}

/// Skins built so far, by skeleton. The skeleton is kept alive with its skin, so its
/// address is never reused for another while cached.
#[derive(Default)]
pub(crate) struct SkinCache {
    skins: HashMap<usize, (Arc<Skeleton>, Option<GpuSkin>)>,
}

impl SkinCache {
    /// The GPU skin of `skeleton`, built on first use; `None` when the skeleton cannot
    /// be skinned (not a troupe template, or too many joints): it is drawn as solids.
    pub fn get(&mut self, device: &wgpu::Device, skeleton: &Arc<Skeleton>) -> Option<&GpuSkin> {
        let key = Arc::as_ptr(skeleton) as usize;
        let entry = self.skins.entry(key).or_insert_with(|| {
            let skin = if skeleton.joints().len() > MAX_JOINTS {
                tracing::warn!(
                    "skeleton `{}` has {} joints, more than the {MAX_JOINTS} the skin look draws: drawing solids",
                    skeleton.name(),
                    skeleton.joints().len()
                );
                None
            } else {
                match Skin::build(skeleton) {
                    Ok(skin) => Some(upload(device, Arc::new(skin), skeleton)),
                    Err(e) => {
                        tracing::warn!("no skin for skeleton `{}` ({e}): drawing solids", skeleton.name());
                        None
                    }
                }
            };
            (skeleton.clone(), skin)
        });
        entry.1.as_ref()
    }
}

/// The colour slot of each vertex: its region, or a hand for bare skin moved mostly by a
/// joint at or below a wrist (so grasp states can tint the hands).
fn parts(skin: &Skin, skeleton: &Skeleton) -> Vec<u32> {
    let wrists = [
        skeleton.joint("l_wrist").ok(),
        skeleton.joint("r_wrist").ok(),
    ];
    let mut hand_of: Vec<Option<u32>> = vec![None; skeleton.joints().len()];
    for (j, joint) in skeleton.joints().iter().enumerate() {
        hand_of[j] = match wrists.iter().position(|w| *w == Some(j)) {
            Some(side) => Some(LEFT_HAND + side as u32),
            None => joint.parent.and_then(|p| hand_of[p]),
        };
    }
    skin.regions
        .iter()
        .zip(&skin.joints)
        .map(
            |(&region, joints)| match (region, hand_of[joints[0] as usize]) {
                (Region::Skin, Some(hand)) => hand,
                _ => region as u32,
            },
        )
        .collect()
}

fn upload(device: &wgpu::Device, skin: Arc<Skin>, skeleton: &Skeleton) -> GpuSkin {
    let parts = parts(&skin, skeleton);
    let vertices: Vec<SkinVertex> = (0..skin.positions.len())
        .map(|i| SkinVertex {
            pos: skin.positions[i],
            normal: skin.normals[i],
            joints: skin.joints[i],
            weights: skin.weights[i],
            part: parts[i],
        })
        .collect();
    let buffer = |label, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    GpuSkin {
        vertices: buffer(
            "skin vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        ),
        indices: buffer(
            "skin triangles",
            bytemuck::cast_slice(&skin.indices),
            wgpu::BufferUsages::INDEX,
        ),
        count: skin.indices.len() as u32,
        far_indices: buffer(
            "skin far triangles",
            bytemuck::cast_slice(&skin.far_indices),
            wgpu::BufferUsages::INDEX,
        ),
        far_count: skin.far_indices.len() as u32,
        skin,
    }
}

/// Vertex attributes of [`SkinVertex`].
pub(crate) const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Uint16x4, 3 => Float32x4, 4 => Uint32
];

/// The uniform block of one actor: `colors` by slot and the skinning matrices for its
/// current joint frames.
pub(crate) fn block(skin: &Skin, actor: &ActorFrame, colors: [[f32; 4]; COLORS]) -> SkinBlock {
    let mut block = SkinBlock {
        colors,
        joints: [[[0.0; 4]; 4]; MAX_JOINTS],
    };
    for (slot, t) in block
        .joints
        .iter_mut()
        .zip(skin.skinning_transforms(&actor.globals))
    {
        let m =
            glam::Mat4::from_rotation_translation(t.rotation.as_quat(), t.translation.as_vec3());
        *slot = m.to_cols_array_2d();
    }
    block
}

/// Bytes between two actors' blocks in the uniform buffer (a multiple of the 256-byte
/// offset alignment).
pub(crate) const BLOCK_STRIDE: u64 = (std::mem::size_of::<SkinBlock>() as u64).div_ceil(256) * 256;
