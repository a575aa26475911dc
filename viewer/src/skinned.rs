//! The skin look: each actor's generated [`Skin`] deformed on the GPU by linear blend
//! skinning. Skins are built once per template (`troupe_body::skin::SkinLibrary`: every
//! height of a template shares its skin, scaled by its skinning matrices) and kept on
//! the GPU; each frame uploads only every actor's joint matrices and colours, one
//! uniform block per actor, and draws its skin with that block.
//!
//! An actor dressed in a user's character (`troupe_body::Dressing`) is drawn the same
//! way from the character's own mesh, weights and vertex colours, its skinning matrices
//! found from troupe's joint frames each frame.
//!
//! Linear blend skinning rather than dual quaternions: it is what glTF files and every
//! glTF viewer use, so the window, the PNG frames and an exported `.glb` show the same
//! deformation; with the skin's weights (smoothed over the surface across each joint)
//! dual quaternions turned more triangles over, not fewer (measured in docs/viewer.md).

use crate::frame::ActorFrame;
use bytemuck::{Pod, Zeroable};
use std::collections::HashMap;
use std::sync::Arc;
use troupe_body::skin::{CutSkin, Region, SharedSkin, SkinLibrary};
use troupe_body::{Dressing, Skeleton, Skin};
use wgpu::util::DeviceExt;

/// The most skinning slots a skin may have (troupe's templates have 66 joints and the
/// generated skin adds its helper joints); an actor with more is drawn as solids.
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
    /// Linear colour multiplying the slot's: white for the generated skin, the
    /// character's own colour for a user's character.
    tint: [f32; 4],
    /// Distances from the regions' volumes (bare skin, shirt, trousers, shoes), so that
    /// the fragment shader draws the edges between regions where the volumes put them,
    /// between vertices (see `troupe_body::skin::RegionDistances`).
    cloth: [f32; 4],
    /// Distance from the nearest eyeball, and where on it the vertex lies (see
    /// `RegionDistances::on_eye`).
    eye: [f32; 4],
}

/// Region distances of vertices coloured by vertex (a user's character, its own colours
/// as tints; the generated skin's coarse level, cut along its regions). They are not
/// drawn per pixel; were they, these would make them bare skin, tinted by their own.
const BARE: ([f32; 4], [f32; 4]) = ([0.0, 1.0, 1.0, 1.0], [1.0, 0.0, 0.0, -1.0]);

/// An actor's uniform block: colours and skinning matrices.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct SkinBlock {
    pub colors: [[f32; 4]; COLORS],
    pub joints: [[[f32; 4]; 4]; MAX_JOINTS],
}

/// A skin on the GPU.
pub(crate) struct GpuSkin {
    /// Full detail, for actors near the camera.
    pub near: Level,
    /// The coarse level, for actors far away (a character's is its full mesh again).
    pub far: Level,
    /// The coarsest level, for actors further still (a character's full mesh again).
    pub farthest: Level,
    pub source: SkinSource,
}

/// How much of a skin's detail an actor needs, by its height on screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Detail {
    /// Full detail, colours per pixel.
    Near,
    /// The coarse level.
    Far,
    /// The coarsest level.
    Farthest,
}

impl Detail {
    /// The detail an actor about `pixels` tall on screen needs: full detail from 360
    /// pixels, where the coarse level's facets and its edges between regions begin to
    /// show; the coarsest under 150.
    pub fn for_height(pixels: f32) -> Detail {
        if pixels >= 360.0 {
            Detail::Near
        } else if pixels >= 150.0 {
            Detail::Far
        } else {
            Detail::Farthest
        }
    }
}

impl GpuSkin {
    /// The level of detail to draw for `detail`.
    pub fn level(&self, detail: Detail) -> &Level {
        match detail {
            Detail::Near => &self.near,
            Detail::Far => &self.far,
            Detail::Farthest => &self.farthest,
        }
    }
}

/// One level of detail on the GPU: its vertices and the triangles over them.
#[derive(Clone)]
pub(crate) struct Level {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    /// Indices to draw.
    pub count: u32,
}

/// What a GPU skin was made from.
pub(crate) enum SkinSource {
    /// A skeleton's generated skin.
    Generated(Arc<Skin>),
    /// A user's character fitted to an actor.
    Character(Arc<Dressing>),
}

/// Which skin an actor is drawn with: its character's, else its skeleton's.
#[derive(Clone)]
pub(crate) enum SkinKey {
    /// The generated skin of a skeleton.
    Generated(Arc<Skeleton>),
    /// A user's character.
    Character(Arc<Dressing>),
}

impl SkinKey {
    /// The key of how `actor` is drawn.
    pub fn of(actor: &ActorFrame) -> SkinKey {
        match &actor.look {
            Some(d) => SkinKey::Character(d.clone()),
            None => SkinKey::Generated(actor.skeleton.clone()),
        }
    }
}

/// Skins built so far. Skeletons are kept alive while cached, so their addresses are
/// never reused for others.
#[derive(Default)]
pub(crate) struct SkinCache {
    library: SkinLibrary,
    /// By skeleton: how its generated skin is drawn; `None` when it is drawn as solids.
    skeletons: HashMap<usize, (Arc<Skeleton>, Option<Drawn>)>,
    /// Generated skins on the GPU, by the address of their shared skin (kept alive in
    /// their [`SkinSource`]).
    generated: HashMap<usize, GpuSkin>,
    /// Characters' skins, by dressing (kept alive with it, as skeletons are).
    characters: HashMap<usize, (Arc<Dressing>, Option<GpuSkin>)>,
}

/// How a skeleton's generated skin is drawn.
#[derive(Clone, Copy)]
struct Drawn {
    /// The address of its shared [`Skin`], a key of `SkinCache::generated`.
    skin: usize,
    /// The skeleton's lengths divided by those of the body the skin was made for.
    scale: f64,
}

impl SkinCache {
    /// The GPU skin of `key`, made on first use, and the scale its vertices are drawn
    /// at; `None` when it cannot be drawn so (a skeleton lacking a joint or solid the
    /// skin needs, too many joints or slots): drawn as solids.
    pub fn get_key(
        &mut self,
        device: &wgpu::Device,
        key: &SkinKey,
        skeleton: &Skeleton,
    ) -> Option<(&GpuSkin, f64)> {
        match key {
            SkinKey::Generated(skeleton) => self.get(device, skeleton),
            SkinKey::Character(dressing) => self
                .character(device, dressing, skeleton)
                .map(|skin| (skin, 1.0)),
        }
    }

    /// The GPU skin of a character fitted to an actor.
    fn character(
        &mut self,
        device: &wgpu::Device,
        dressing: &Arc<Dressing>,
        skeleton: &Skeleton,
    ) -> Option<&GpuSkin> {
        let key = Arc::as_ptr(dressing) as usize;
        let entry = self.characters.entry(key).or_insert_with(|| {
            let skin = if dressing.slot_count() > MAX_JOINTS {
                tracing::warn!(
                    "{}: {} moving bones, more than the {MAX_JOINTS} the skin look draws: drawing solids",
                    dressing.source,
                    dressing.slot_count()
                );
                None
            } else {
                Some(upload_character(device, dressing.clone(), skeleton))
            };
            (dressing.clone(), skin)
        });
        entry.1.as_ref()
    }

    /// The GPU skin of `skeleton` and its scale, built on first use (shared by every
    /// height of a template; any other skeleton gets its own); `None` when the skeleton
    /// cannot be skinned (lacking a joint or solid the skin needs, or too many joints):
    /// it is drawn as solids.
    pub fn get(
        &mut self,
        device: &wgpu::Device,
        skeleton: &Arc<Skeleton>,
    ) -> Option<(&GpuSkin, f64)> {
        let key = Arc::as_ptr(skeleton) as usize;
        if !self.skeletons.contains_key(&key) {
            let drawn = match self.library.get(skeleton) {
                // Slots: the skeleton's joints and the skin's helper joints.
                Ok(shared) if shared.skin.rest.len() > MAX_JOINTS => {
                    tracing::warn!(
                        "skeleton `{}` has {} joints and helpers, more than the {MAX_JOINTS} the skin look draws: drawing solids",
                        skeleton.name(),
                        shared.skin.rest.len()
                    );
                    None
                }
                Ok(SharedSkin { skin, scale }) => {
                    let at = Arc::as_ptr(&skin) as usize;
                    self.generated
                        .entry(at)
                        .or_insert_with(|| upload(device, skin, skeleton));
                    Some(Drawn { skin: at, scale })
                }
                Err(e) => {
                    tracing::warn!(
                        "no skin for skeleton `{}` ({e}): drawing solids",
                        skeleton.name()
                    );
                    None
                }
            };
            self.skeletons.insert(key, (skeleton.clone(), drawn));
        }
        let drawn = self.skeletons[&key].1?;
        Some((&self.generated[&drawn.skin], drawn.scale))
    }
}

/// The colour slot of each vertex of `regions` moved by `joints` (slots of `skin`): its
/// region, or a hand for bare skin moved mostly by a joint at or below a wrist (so grasp
/// states can tint the hands).
fn parts(skin: &Skin, skeleton: &Skeleton, regions: &[Region], joints: &[[u16; 4]]) -> Vec<u32> {
    let hand_of = hand_slots(skeleton);
    regions
        .iter()
        .zip(joints)
        .map(
            |(&region, joints)| match (region, hand_of[skin.slot_joint(joints[0] as usize)]) {
                (Region::Skin, Some(hand)) => hand,
                _ => region as u32,
            },
        )
        .collect()
}

/// The hand colour slot of each joint at or below a wrist.
fn hand_slots(skeleton: &Skeleton) -> Vec<Option<u32>> {
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
    hand_of
}

fn upload(device: &wgpu::Device, skin: Arc<Skin>, skeleton: &Skeleton) -> GpuSkin {
    let near_parts = parts(&skin, skeleton, &skin.regions, &skin.joints);
    let vertices: Vec<SkinVertex> = (0..skin.positions.len())
        .map(|i| SkinVertex {
            pos: skin.positions[i],
            normal: skin.normals[i],
            joints: skin.joints[i],
            weights: skin.weights[i],
            part: near_parts[i],
            tint: [1.0; 4],
            cloth: skin.region_distances[i].cloth,
            eye: {
                let d = &skin.region_distances[i];
                [d.eye, d.on_eye[0], d.on_eye[1], d.on_eye[2]]
            },
        })
        .collect();
    // The coarse levels are coloured by vertex (cheaper than per pixel, and their edges
    // are a pixel or two wide), so they are cut along the edges between regions first,
    // as a glTF export is: each triangle then has one colour, and an edge runs straight
    // through the triangles it crosses instead of blurring across them.
    let coarse = |cut: CutSkin| {
        let parts = parts(&skin, skeleton, &cut.regions, &cut.joints);
        let vertices: Vec<SkinVertex> = (0..cut.positions.len())
            .map(|i| SkinVertex {
                pos: cut.positions[i],
                normal: cut.normals[i],
                joints: cut.joints[i],
                weights: cut.weights[i],
                part: parts[i],
                tint: [1.0; 4],
                cloth: BARE.0,
                eye: BARE.1,
            })
            .collect();
        upload_level(device, &vertices, &cut.indices)
    };
    let (far, farthest) = (
        coarse(CutSkin::far(&skin)),
        coarse(CutSkin::farthest(&skin)),
    );
    GpuSkin {
        near: upload_level(device, &vertices, &skin.indices),
        far,
        farthest,
        source: SkinSource::Generated(skin),
    }
}

/// Uploads a character's mesh: its colours as tints of a white slot, the vertices moved
/// mostly by a wrist or a finger in the hand slots (so grasp states can tint them).
fn upload_character(
    device: &wgpu::Device,
    dressing: Arc<Dressing>,
    skeleton: &Skeleton,
) -> GpuSkin {
    let hands = hand_slots(skeleton);
    let slot_hands: Vec<Option<u32>> = dressing
        .slot_joints()
        .iter()
        .map(|&j| hands.get(j).copied().flatten())
        .collect();
    let vertices: Vec<SkinVertex> = (0..dressing.positions.len())
        .map(|i| SkinVertex {
            pos: dressing.positions[i],
            normal: dressing.normals[i],
            joints: dressing.slots[i],
            weights: dressing.weights[i],
            part: slot_hands[dressing.slots[i][0] as usize].unwrap_or(Region::Skin as u32),
            tint: {
                let c = dressing.colors[i].map(srgb_to_linear);
                [c[0], c[1], c[2], 1.0]
            },
            cloth: BARE.0,
            eye: BARE.1,
        })
        .collect();
    let near = upload_level(device, &vertices, &dressing.indices);
    GpuSkin {
        far: near.clone(),
        farthest: near.clone(),
        near,
        source: SkinSource::Character(dressing.clone()),
    }
}

/// An sRGB component as linear light.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Uploads one level of detail: `vertices` and the triangles `indices` over them.
fn upload_level(device: &wgpu::Device, vertices: &[SkinVertex], indices: &[u32]) -> Level {
    let buffer = |label, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    Level {
        vertices: buffer(
            "skin vertices",
            bytemuck::cast_slice(vertices),
            wgpu::BufferUsages::VERTEX,
        ),
        indices: buffer(
            "skin triangles",
            bytemuck::cast_slice(indices),
            wgpu::BufferUsages::INDEX,
        ),
        count: indices.len() as u32,
    }
}

/// Vertex attributes of [`SkinVertex`].
pub(crate) const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 8] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Uint16x4, 3 => Float32x4, 4 => Uint32, 5 => Float32x4,
    6 => Float32x4, 7 => Float32x4
];

/// The uniform block of one actor: `colors` by slot and the skinning matrices for its
/// current joint frames, drawing the skin at `scale` (a shared skin at the actor's size).
pub(crate) fn block(
    source: &SkinSource,
    actor: &ActorFrame,
    colors: [[f32; 4]; COLORS],
    scale: f64,
) -> SkinBlock {
    let mut block = SkinBlock {
        colors,
        joints: [[[0.0; 4]; 4]; MAX_JOINTS],
    };
    let matrices = match source {
        SkinSource::Generated(skin) => SharedSkin {
            skin: skin.clone(),
            scale,
        }
        .skinning_matrices(&actor.globals),
        SkinSource::Character(dressing) => {
            // The character's own colours show through white slots; a hand keeps the
            // tint of its grasp state when it is not the plain skin colour.
            let skin = block.colors[Region::Skin as usize];
            for (slot, color) in block.colors.iter_mut().enumerate() {
                if slot < LEFT_HAND as usize || *color == skin {
                    *color = [1.0; 4];
                }
            }
            dressing
                .skinning_transforms(&actor.globals)
                .iter()
                .map(|t| glam::DMat4::from_rotation_translation(t.rotation, t.translation))
                .collect()
        }
    };
    for (slot, m) in block.joints.iter_mut().zip(matrices) {
        *slot = m.as_mat4().to_cols_array_2d();
    }
    block
}

/// Bytes between two actors' blocks in the uniform buffer (a multiple of the 256-byte
/// offset alignment).
pub(crate) const BLOCK_STRIDE: u64 = (std::mem::size_of::<SkinBlock>() as u64).div_ceil(256) * 256;
