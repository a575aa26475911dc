//! The skin: one closed, smooth triangle surface around the body, weighted to the
//! joints so that it deforms with the skeleton (thesis 6.5.2, Skinlib's layered model).
//!
//! [`Skin::build`] makes it from a template skeleton in three steps:
//! 1. **volumes** ([`volumes`]): rounded cones and ellipsoids over the solids, laid out
//!    in the rest pose: torso, limbs, a palm and five fingers per hand, a head with jaw,
//!    nose, ears, eye sockets and eyeballs; then each carried with its joint to the
//!    **bind pose**, the arms raised 45° sideways and the fingers spread
//!    ([`bind_posture`]), where the surface and its weights are made (and from where
//!    their own weights carry them to the posture they are bound in, the hips and the
//!    clavicles a little bent: [`binding`]);
//! 2. **surface** (`surface`): the volumes blended into one signed distance field (smooth
//!    unions where neighbouring joints meet, carving for the eye sockets), its zero level
//!    set extracted by marching tetrahedra on the left of the sagittal plane and
//!    mirrored into a closed mesh (`mirror`: the right side is the left's mirror image,
//!    through every step below), which is then simplified (meshoptimizer's quadric edge
//!    collapse) to at most [`MAX_TRIANGLES`] triangles; its tiny edges are collapsed
//!    (`collapse`) and its thin triangles evened out by edge flips (`flips`) and
//!    tangential relaxation (`relax`), since thin triangles turn over at the slightest
//!    bend, and its few pleats (triangles facing into the body) unfolded (`pleats`);
//!    the finished surface is simplified again into the coarse levels of detail for
//!    actors far from the camera;
//! 3. **weights** (`weights`): at most four joints per vertex, blended across each joint
//!    and smoothed over the surface so that they change continuously from vertex to vertex;
//!    across the big joints the blend runs through [`helpers`], in-between joints turned
//!    by a fraction of the joint's swing (across it) or twist (down the limb), or, next
//!    to the hips, knees, elbows, vc4 and the skullbase, turned with the joint (the hips'
//!    by 0.4 of its twist, vc4's by a quarter) about a point moved into the bend, so that a
//!    bend folds less skin over.
//!
//! The skin deforms by linear blend skinning, the same on the GPU (the viewer), in glTF
//! files and here on the CPU ([`Skin::deform`], used by the tests and exporters).
//!
//! The folds counted in these modules' comments ("the skin test's 50 full-range
//! postures") are over the test's former single draw of 50 postures, which the knobs
//! were set by, and on the surface before its two sides were mirrored; other draws fold
//! about 80 times as many per posture, and other grids as many again. A change is now
//! judged by `examples/skin_folds.rs`, over draws chosen by and draws held out
//! (docs/skin-notes.md, "More draws" and "The two sides mirrored").

pub mod binding;
mod collapse;
mod flips;
pub mod helpers;
mod library;
mod mirror;
mod pleats;
mod regions;
mod relax;
mod surface;
pub mod volumes;
mod weights;

pub use binding::bound_posture;
pub use helpers::Helper;
pub use library::{template_scale, SharedSkin, SkinLibrary};
pub use regions::{CutSkin, RegionDistances, PUPIL_EDGE};
pub use volumes::{bind_globals, bind_posture, rest_globals, Region, BIND_ABDUCTION};
pub use weights::Influences;

use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use crate::transform::Transform;
use glam::DVec3;
use mirror::Mirror;
use volumes::Volume;

/// The most triangles a skin has at full detail.
pub const MAX_TRIANGLES: usize = 24_000;
/// Triangles of the coarse level of detail.
pub const FAR_TRIANGLES: usize = 6_000;
/// Triangles of the coarsest level of detail, for actors a couple of hundred pixels tall
/// or less.
pub const FARTHEST_TRIANGLES: usize = 1_500;
/// Edges shorter than this many grid cells are collapsed after the simplification
/// (see `collapse`).
const TINY_EDGE: f64 = 0.5;
/// Triangles of lower quality than this (twice the area over the longest edge squared,
/// `flips::quality`) have their longest edge flipped after the relaxation, when that
/// makes both triangles of the pair better.
const THIN: f64 = 0.3;
/// Joints at the parent's end of a helper chain (`weights::Chains::new`): the clavicle
/// and vt1, so that the armpit (shared by the arm and the chest) blends through the
/// shoulder's helpers. With the trunk's human ranges this took the worst posture at half
/// ranges from 10-26 inverted triangles to 1-8; a third joint (vt6) pulled the child's
/// chest too far from its bones.
const CHAIN_ENDS: usize = 2;
/// Joints whose volumes get wider bands of weights (`weights::WIDER`): the pelvis, the
/// hips and the lower belly, where a flexed hip folds the groin; and the upper arms
/// (the shoulders' volumes), where an arm raised 180° folds the armpit. The upper arms'
/// took the adults' worst full-range posture from 62-85 inverted triangles to 48-75
/// (1.25 × and 1.75 × instead of 1.5 did worse: 87 for the 1.40 m adult, 107 for the
/// 0.96 m child). Since the skin is made in the A-pose they matter less, but without
/// them the 1.20 m child turns a triangle over at a quarter of the ranges. The upper
/// arms' are now a little narrower than the groin's (`weights::UPPER_ARM`, 1.35 ×).
const WIDER_BANDS: [&str; 4] = ["sacroiliac", "l_hip", "r_hip", "vl5"];
/// The lower belly leaning on the pelvis beside a flexed hip (`weights::Lean`): the
/// lower spine's weight, the pelvis taking it, and the hips whose sliding helpers'
/// weight says how much of it goes.
const LEAN: [&str; 4] = ["vl5", "sacroiliac", "l_hip", "r_hip"];
/// The upper arms (the shoulders' volumes), whose bands are `weights::UPPER_ARM` wide.
const UPPER_ARM_BANDS: [&str; 2] = ["l_shoulder", "r_shoulder"];
/// Joints whose volumes get narrower bands of weights (`weights::NARROWER`): the root
/// of the neck (vc4, vt1) and the head's skullbase, whose weight otherwise reaches the top
/// of a child's shoulders; and the clavicles (sternoclavicular), whose raising folded
/// the crease between the neck and the trapezius: with them the triangles vt1 turns over
/// in the skin test's 50 full-range postures, summed over its six sizes, went from 307 to
/// 115 (all of them from 1,098 to 922, the worst posture of each size unchanged); wider
/// bands there instead failed the test. vt1's own band is now a little wider than these
/// (`weights::NECK_ROOT`, 0.7 ×), and vc4's narrower (`weights::NECK`, 0.45 ×).
const NARROWER_BANDS: [&str; 3] = ["skullbase", "l_sternoclavicular", "r_sternoclavicular"];
/// The palms (the wrists' volumes), whose bands are `weights::PALM` wide.
const PALM_BANDS: [&str; 2] = ["l_wrist", "r_wrist"];
/// The middle phalanges of the index, middle and ring fingers, whose bands are
/// `weights::FINGER_MIDDLE` wide.
const FINGER_MIDDLE_BANDS: [&str; 6] = [
    "l_index2",
    "r_index2",
    "l_middle2",
    "r_middle2",
    "l_ring2",
    "r_ring2",
];
/// The little fingers' first phalanges, whose bands are `weights::LITTLE_KNUCKLE` wide.
const LITTLE_KNUCKLE_BANDS: [&str; 2] = ["l_pinky1", "r_pinky1"];
/// How wide the band of weights of the vertices nearest to joint `name`'s volumes is, as
/// a multiple of the usual (the lists above and vt1's and vc4's own; 1 for the rest).
fn band_of(name: &str) -> f64 {
    let bands: [(&[&str], f64); 8] = [
        (&WIDER_BANDS, weights::WIDER),
        (&UPPER_ARM_BANDS, weights::UPPER_ARM),
        (&PALM_BANDS, weights::PALM),
        (&FINGER_MIDDLE_BANDS, weights::FINGER_MIDDLE),
        (&LITTLE_KNUCKLE_BANDS, weights::LITTLE_KNUCKLE),
        (&NARROWER_BANDS, weights::NARROWER),
        (&["vt1"], weights::NECK_ROOT),
        (&["vc4"], weights::NECK),
    ];
    bands
        .iter()
        .find(|(names, _)| names.contains(&name))
        .map_or(1.0, |&(_, width)| width)
}

/// Grid cells per metre of standing height when sampling the body's field.
const CELLS_PER_HEIGHT: f64 = 400.0;

/// A skinned surface made in the skeleton's bind pose ([`bind_posture`]: the rest pose
/// with the arms raised 45° sideways and the fingers spread) and bound a little bent
/// ([`bound_posture`]).
#[derive(Clone, Debug)]
pub struct Skin {
    /// Vertex positions (m) in the posture the skin is bound in ([`bound_posture`]).
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals there.
    pub normals: Vec<[f32; 3]>,
    /// Up to four skinning slots per vertex: the skeleton's joints, then the
    /// [`helpers`](Skin::helpers) (slot `joints + i` is helper `i`).
    pub joints: Vec<[u16; 4]>,
    /// The matching weights: each in [0, 1], summing to one.
    pub weights: Vec<[f32; 4]>,
    /// What covers each vertex (skin, shirt, …), for colouring.
    pub regions: Vec<Region>,
    /// How far each vertex lies from each region's volumes, for drawing the edges
    /// between regions between the vertices (see [`RegionDistances`]).
    pub region_distances: Vec<RegionDistances>,
    /// Full-detail triangles, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// Coarse triangles over the same vertices, for actors far away.
    pub far_indices: Vec<u32>,
    /// Coarser still, over the same vertices, for actors further away.
    pub farthest_indices: Vec<u32>,
    /// The frame of every slot, the skeleton's joints then the helpers, in the posture the
    /// skin is bound in ([`bound_posture`]): what skinning turns it from.
    pub rest: Vec<Transform>,
    /// The frame of every slot in the posture the skin is made in ([`bind_posture`]): a
    /// file's rest pose, as a modeller shows the character unposed.
    pub made: Vec<Transform>,
    /// Helper joints at the big joints, after the skeleton's joints among the slots.
    pub helpers: Vec<Helper>,
}

impl Skin {
    /// Builds the skin of a skeleton made from a troupe template (any template, height
    /// and mass); a skeleton lacking the template's joints or solids is an error naming
    /// the first one missing.
    pub fn build(skeleton: &Skeleton) -> Result<Skin> {
        let (made, mirror) = Skin::made(skeleton)?;
        Ok(made.bound_at(&binding::bound_globals(skeleton), &mirror))
    }

    /// The skin made and bound in the bind posture (see [`Skin::build`]), and which
    /// vertex is whose mirror image.
    fn made(skeleton: &Skeleton) -> Result<(Skin, Mirror)> {
        let helpers = helpers::helpers(skeleton)?;
        let joint_bind = volumes::bind_globals(skeleton);
        let rest = with_helpers(&joint_bind, &helpers);
        let mut volumes = volumes::body_volumes(skeleton)?;
        volumes::to_bind(skeleton, &mut volumes);
        let neighbours = neighbour_test(skeleton, &volumes, 1);
        // Surfaces blend a generation further along the trunk, so that its stacked
        // volumes (on a chain of joints) round into one another; elsewhere a wider blend
        // would close loops (a thumb onto the palm, an arm onto the chest).
        let trunk: Vec<bool> = skeleton
            .joints()
            .iter()
            .map(|j| ["sacroiliac", "vl5", "vt12", "vt6", "vt1"].contains(&j.name.as_str()))
            .collect();
        let further = neighbour_test(skeleton, &volumes, 2);
        let blends =
            |a: usize, b: usize| neighbours(a, b) || (trunk[a] && trunk[b] && further(a, b));
        let height = volumes
            .iter()
            .map(|v| v.form.bounds().1.y)
            .fold(0.0f64, f64::max);
        let field = surface::Field::sample(&volumes, height / CELLS_PER_HEIGHT, blends);
        // The left side only, mirrored: see `mirror` for why.
        let (left_positions, dense_left) = field.triangulate_left();
        if dense_left.is_empty() {
            return Err(Error::Invalid(
                "skin: the body's volumes enclose nothing".into(),
            ));
        }
        let (dense_mirror, dense_positions, _) = Mirror::whole(&left_positions, &dense_left);
        // Regions are decided on the dense surface (on its left, the right's vertices
        // taking their images', which come after them) and carried through
        // simplification as attributes, so that collapses keep the edges between them
        // (sleeves, collar, waistband) along rows of vertices.
        let mut dense_regions: Vec<Region> = left_positions
            .iter()
            .map(|&p| regions::distances_at(p, &volumes).region())
            .collect();
        dense_regions.resize(dense_positions.len(), Region::Skin);
        dense_mirror.symmetric_values(&mut dense_regions, |&r| r);
        let full = Simplifier {
            positions: &dense_positions,
            mirror: &dense_mirror,
            regions: &dense_regions,
            height,
            lock_rings: 3,
        }
        .simplify(&dense_left, MAX_TRIANGLES, 0.004 * height)?;
        // Keep only the vertices the full mesh uses, in first-use order.
        let mut remap = vec![u32::MAX; dense_positions.len()];
        let mut positions = Vec::new();
        let mut regions = Vec::new();
        for &i in &full {
            if remap[i as usize] == u32::MAX {
                remap[i as usize] = positions.len() as u32;
                positions.push(dense_positions[i as usize]);
                regions.push(dense_regions[i as usize]);
            }
        }
        let mirror = dense_mirror.renumbered(&remap, positions.len());
        let mut indices: Vec<u32> = full.iter().map(|&i| remap[i as usize]).collect();
        // The steps below run over the whole surface, each made symmetric again from its
        // left side after it (`Mirror::symmetric`).
        collapse::collapse_short_edges(
            &mut positions,
            &mut indices,
            TINY_EDGE * height / CELLS_PER_HEIGHT,
            |a, b| mirror.same_side(a, b),
        );
        mirror.symmetric(&mut positions, &mut indices);
        // Renumber the vertices left, in first-use order.
        let mut renumber = vec![u32::MAX; positions.len()];
        let mut kept = 0u32;
        for &i in &indices {
            if renumber[i as usize] == u32::MAX {
                renumber[i as usize] = kept;
                kept += 1;
            }
        }
        let mut positions = gather(&positions, &renumber, kept as usize);
        let mut regions = gather(&regions, &renumber, kept as usize);
        let mirror = mirror.renumbered(&renumber, kept as usize);
        for i in &mut indices {
            *i = renumber[*i as usize];
        }
        let may_join = |a, b| mirror.may_join(a, b);
        // Thin triangles turn over at the slightest bend: flip the worst away, relax the
        // vertices along the surface, unfold the pleats (`pleats`), flip again what is
        // still thin and relax once more (more rounds changed nothing measurable).
        flips::flip_slivers(&positions, &mut indices, 0.05, may_join);
        mirror.symmetric(&mut positions, &mut indices);
        relax::relax(&mut positions, &indices, &field, 10);
        mirror.symmetric_positions(&mut positions);
        // Unfold the pleats before the last flips and relaxation, which even out the
        // triangles the unfolding leaves thin (unfolded after them, a sliver was left
        // on the 0.96 m child's neck that turned over at a quarter of the ranges).
        pleats::unfold(&mut positions, &indices, &field);
        mirror.symmetric_positions(&mut positions);
        flips::flip_slivers(&positions, &mut indices, THIN, may_join);
        mirror.symmetric(&mut positions, &mut indices);
        relax::relax(&mut positions, &indices, &field, 5);
        mirror.symmetric_positions(&mut positions);
        smooth_regions(&mut regions, &indices);
        // The coarse levels of detail: the full level simplified further, over its
        // vertices.
        let coarse = Simplifier {
            positions: &positions,
            mirror: &mirror,
            regions: &regions,
            height,
            lock_rings: 1,
        };
        let left = mirror.left_of(&indices);
        let (far_indices, farthest_indices) = (
            coarse.simplify(&left, FAR_TRIANGLES, 0.02 * height)?,
            coarse.simplify(&left, FARTHEST_TRIANGLES, 0.04 * height)?,
        );
        let mut region_distances: Vec<RegionDistances> = positions
            .iter()
            .map(|&p| regions::distances_at(p, &volumes))
            .collect();
        // The right's the left's images to the last bit, so that the edges between
        // regions are drawn and cut the same way on both sides.
        mirror.symmetric_values(&mut region_distances, RegionDistances::mirrored);
        let normals = vertex_normals(&positions, &indices);
        let joints = skeleton.joints();
        let band: Vec<f64> = joints.iter().map(|j| band_of(&j.name)).collect();
        let chains = weights::Chains::new(
            &helpers,
            joint_bind.len(),
            CHAIN_ENDS,
            |j| joints[j].parent,
            |j| {
                let end = helpers::bone_end(skeleton, &joint_bind, j);
                (
                    joint_bind[j].translation,
                    end.unwrap_or(joint_bind[j].translation),
                )
            },
            // The head is rigid: its skin goes back from the skullbase's helper to the
            // skullbase itself under the jaw, not across the face.
            |j| {
                if joints[j].name == "skullbase" {
                    weights::HEAD_SPAN
                } else {
                    weights::TWIST_SPAN
                }
            },
            // Nor does the head's weight reach the root of the neck.
            |j| (joints[j].name == "skullbase").then_some(weights::HEAD_FLOOR),
        );
        let named = |name: &str| joints.iter().position(|j| j.name == name);
        let chains = match (named(LEAN[0]), named(LEAN[1])) {
            (Some(from), Some(to)) => chains.leaning(weights::Lean {
                from: from as u16,
                to: to as u16,
                by: helpers
                    .iter()
                    .enumerate()
                    .filter(|(_, h)| {
                        h.swing >= 1.0
                            && h.pair.is_none()
                            && LEAN[2..].contains(&joints[h.joint].name.as_str())
                    })
                    .map(|(i, _)| (joint_bind.len() + i) as u16)
                    .collect(),
            }),
            _ => chains,
        };
        let (joints, weights) =
            weights::skin_weights(&positions, &indices, &volumes, &neighbours, &chains, &band)
                .into_iter()
                .unzip();
        let made = Skin {
            positions: positions.iter().map(|p| p.as_vec3().to_array()).collect(),
            normals,
            joints,
            weights,
            regions,
            region_distances,
            indices,
            far_indices,
            farthest_indices,
            made: rest.clone(),
            rest,
            helpers,
        };
        Ok((made, mirror))
    }

    /// This skin, made and bound in the same posture, bound instead where the skeleton's
    /// joints are at `globals` (see [`binding`]): its own weights carry it there, and its
    /// two sides stay each other's mirror images to the bit (a vertex blending a left and a
    /// right joint sums their parts in the order of its slots, which differs between a
    /// vertex and its image).
    fn bound_at(mut self, globals: &[Transform], mirror: &Mirror) -> Skin {
        let mut positions = self.deform(globals);
        mirror.symmetric_positions(&mut positions);
        self.normals = vertex_normals(&positions, &self.indices);
        self.positions = positions.iter().map(|p| p.as_vec3().to_array()).collect();
        self.rest = self.frames(globals);
        self
    }

    /// The frame of every skinning slot for joint frames `globals`: the joints' own, then
    /// each helper's.
    pub fn frames(&self, globals: &[Transform]) -> Vec<Transform> {
        self.scaled_frames(globals, 1.0)
    }

    /// [`Skin::frames`] for the joint frames `globals` of this skin's body scaled by
    /// `scale` (a [`SharedSkin`]'s): the sliding helpers' moves scale with the body.
    pub fn scaled_frames(&self, globals: &[Transform], scale: f64) -> Vec<Transform> {
        let mut frames = globals.to_vec();
        frames.extend(self.helpers.iter().map(|h| h.scaled_frame(globals, scale)));
        frames
    }

    /// The skeleton joint a skinning slot follows: the slot's own joint, or the joint a
    /// helper helps.
    pub fn slot_joint(&self, slot: usize) -> usize {
        let joints = self.rest.len() - self.helpers.len();
        match slot.checked_sub(joints) {
            Some(h) => self.helpers[h].joint,
            None => slot,
        }
    }

    /// Number of full-detail triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Bytes held by the skin's arrays (what an actor's skin costs in memory).
    pub fn memory_bytes(&self) -> usize {
        let n = self.positions.len();
        n * (12 + 12 + 8 + 16 + 1 + std::mem::size_of::<RegionDistances>())
            + (self.indices.len() + self.far_indices.len() + self.farthest_indices.len()) * 4
            + (self.rest.len() + self.made.len()) * std::mem::size_of::<Transform>()
    }

    /// Skinning transforms for joint frames `globals`, one per slot (joints, then
    /// helpers): `frame[s] · rest[s]⁻¹`, which carries a bind-pose point attached to slot
    /// `s` to where the slot has moved it.
    pub fn skinning_transforms(&self, globals: &[Transform]) -> Vec<Transform> {
        self.frames(globals)
            .iter()
            .zip(&self.rest)
            .map(|(g, r)| g.mul(&r.inverse()))
            .collect()
    }

    /// The same skin with every length times `scale`: the skin of its skeleton scaled so
    /// (see [`SkinLibrary`]).
    pub fn scaled(&self, scale: f64) -> Skin {
        let k = scale as f32;
        let mut skin = self.clone();
        for p in &mut skin.positions {
            *p = p.map(|x| x * k);
        }
        for d in &mut skin.region_distances {
            d.cloth = d.cloth.map(|x| x * k);
            d.eye *= k;
        }
        for r in skin.rest.iter_mut().chain(&mut skin.made) {
            r.translation *= scale;
        }
        for h in &mut skin.helpers {
            h.pivot *= scale;
        }
        skin
    }

    /// The skin's vertex positions for joint frames `globals`, by linear blend skinning.
    pub fn deform(&self, globals: &[Transform]) -> Vec<DVec3> {
        let m = self.skinning_transforms(globals);
        linear_blend(&self.positions, &self.joints, &self.weights, &m)
    }
}

/// `positions` moved by linear blend skinning: each point the sum of its slots'
/// `transforms` applied to it, by its weights (a weight of zero left out; a slot with no
/// transform keeps the point where it is for its weight, which only a file's bad bone
/// index gives, named as an error by `Character::dress`).
pub(crate) fn linear_blend(
    positions: &[[f32; 3]],
    slots: &[[u16; 4]],
    weights: &[[f32; 4]],
    transforms: &[Transform],
) -> Vec<DVec3> {
    positions
        .iter()
        .zip(slots.iter().zip(weights))
        .map(|(p, (ss, ws))| {
            let p = DVec3::from(p.map(f64::from));
            ss.iter()
                .zip(ws)
                .filter(|(_, &w)| w > 0.0)
                .map(|(&s, &w)| {
                    transforms
                        .get(s as usize)
                        .map_or(p, |m| m.transform_point(p))
                        * w as f64
                })
                .sum()
        })
        .collect()
}

/// The items of `list` whose `renumber` is not `u32::MAX`, each at that index.
fn gather<T: Copy>(list: &[T], renumber: &[u32], count: usize) -> Vec<T> {
    let mut out: Vec<Option<T>> = vec![None; count];
    for (item, &to) in list.iter().zip(renumber) {
        if to != u32::MAX {
            out[to as usize] = Some(*item);
        }
    }
    out.into_iter()
        .map(|item| item.expect("every kept vertex is numbered"))
        .collect()
}

/// Joint frames `globals` followed by the frames of `helpers` among them.
fn with_helpers(globals: &[Transform], helpers: &[Helper]) -> Vec<Transform> {
    let mut frames = globals.to_vec();
    frames.extend(helpers.iter().map(|h| h.frame(globals)));
    frames
}

/// The vertices of a symmetric closed mesh, and what its simplification keeps to.
struct Simplifier<'a> {
    /// Every vertex, the right's the mirror images of the left's.
    positions: &'a [DVec3],
    /// Which vertex is whose mirror image.
    mirror: &'a Mirror,
    /// Each vertex's region: collapses keep the edges between regions.
    regions: &'a [Region],
    /// The body's height, which the cost of changing region is a part of.
    height: f64,
    /// How many rings of vertices round a pinch are locked before simplifying again:
    /// about a centimetre either way, three rings of the dense surface (cells of 4.4 mm
    /// on a 1.75 m adult) or one of the finished one (edges of about 1.3 cm). Three of
    /// the finished surface's, as the coarsest level had when it was simplified from the
    /// full level's triangles, locked so much of the 1.20 m child's mirrored skin that it
    /// kept 4,032 triangles for its 1,500.
    lock_rings: usize,
}

impl Simplifier<'_> {
    /// Simplifies the left side `left` of the mesh (triangles with no vertex on the
    /// right) to at most `triangles` triangles in all (moving the surface by at most
    /// `error` m where it can), and returns the whole mesh, the left and its mirror
    /// image, closed. The seam stays on the plane: meshoptimizer collapses a vertex on
    /// the open rim only along the rim. Edge collapse can pinch a thin part (a
    /// fingertip, an ear's rim) into an edge shared by four triangles; where that
    /// happens the vertices around it are locked and the simplification runs again, so
    /// those few spots keep their fine triangles.
    fn simplify(&self, left: &[u32], triangles: usize, error: f64) -> Result<Vec<u32>> {
        let Simplifier {
            positions,
            mirror,
            regions,
            height,
            ..
        } = *self;
        let points: Vec<[f32; 3]> = positions.iter().map(|p| p.as_vec3().to_array()).collect();
        let adapter = meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&points), 12, 0)
            .map_err(|e| Error::Invalid(format!("skin: {e}")))?;
        // One attribute per region, 1 where the vertex has it: changing region along a
        // collapse costs as much as moving the surface by REGION_WEIGHT × height.
        const REGIONS: usize = 6;
        const REGION_WEIGHT: f64 = 0.01;
        let mut attributes = vec![0.0f32; regions.len() * REGIONS];
        for (v, &r) in regions.iter().enumerate() {
            attributes[v * REGIONS + r as usize] = 1.0;
        }
        let weights = [(REGION_WEIGHT * height) as f32; REGIONS];
        let mut lock = vec![false; adapter.vertex_count];
        // The seam's vertices kept about an edge's length apart: that of an equilateral
        // triangle of the surface's mean area at the level's count.
        let area: f64 = left
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|v| positions[v as usize]);
                (b - a).cross(c - a).length() / 2.0
            })
            .sum();
        let spacing = (4.0 * area / (3f64.sqrt() * (triangles / 2) as f64)).sqrt();
        for v in Mirror::along_seam(left, positions, spacing) {
            lock[v as usize] = true;
        }
        let mut rings: Option<Vec<Vec<u32>>> = None;
        for _ in 0..12 {
            let simplified = meshopt::simplify_with_attributes_and_locks(
                left,
                &adapter,
                &attributes,
                &weights,
                REGIONS * std::mem::size_of::<f32>(),
                &lock,
                triangles / 2 * 3,
                error as f32,
                meshopt::SimplifyOptions::ErrorAbsolute | meshopt::SimplifyOptions::Regularize,
                None,
            );
            let whole = mirror.with_mirror_image(&simplified);
            // A pinch on the right is its mirror image's on the left.
            let pinched: Vec<u32> = pinched_vertices(&whole)
                .into_iter()
                .map(|v| mirror.on_left(v))
                .collect();
            if pinched.is_empty() {
                return Ok(whole);
            }
            let rings = rings.get_or_insert_with(|| neighbours_of(left, adapter.vertex_count));
            // Lock each pinched vertex and its neighbourhood, `lock_rings` rings deep.
            let mut frontier = pinched;
            for _ in 0..self.lock_rings {
                let mut next = Vec::new();
                for v in frontier {
                    if !lock[v as usize] {
                        lock[v as usize] = true;
                    }
                    next.extend(
                        rings[v as usize]
                            .iter()
                            .copied()
                            .filter(|&n| !lock[n as usize]),
                    );
                }
                frontier = next;
            }
            for v in frontier {
                lock[v as usize] = true;
            }
        }
        Err(Error::Invalid(
        "skin: the simplified surface stayed pinched (an edge shared by more than two triangles)"
            .into(),
    ))
    }
}

/// Vertices of edges that are not shared by exactly two opposite triangles.
fn pinched_vertices(indices: &[u32]) -> Vec<u32> {
    let mut edges: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for t in indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    let mut bad: Vec<u32> = edges
        .iter()
        .filter(|(&(a, b), &count)| count != 1 || edges.get(&(b, a)) != Some(&1))
        .flat_map(|(&(a, b), _)| [a, b])
        .collect();
    bad.sort_unstable();
    bad.dedup();
    bad
}

/// Each vertex's neighbours along the triangles' edges.
fn neighbours_of(indices: &[u32], count: usize) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); count];
    for t in indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            out[a as usize].push(b);
            out[b as usize].push(a);
        }
    }
    out
}

/// Evens out the edges between clothes and skin: a vertex whose neighbours mostly wear
/// another region (a tooth sticking out of a sleeve or a waistband) takes theirs. Eyes
/// and pupils are left as they are.
fn smooth_regions(regions: &mut [Region], indices: &[u32]) {
    let neighbours = neighbours_of(indices, regions.len());
    for _ in 0..2 {
        let before = regions.to_vec();
        for (v, around) in neighbours.iter().enumerate() {
            if matches!(before[v], Region::Eye | Region::Pupil) {
                continue;
            }
            let mut counts = [0usize; 6];
            for &n in around {
                counts[before[n as usize] as usize] += 1;
            }
            let (best, &count) = counts
                .iter()
                .enumerate()
                .max_by_key(|&(r, &c)| (c, std::cmp::Reverse(r)))
                .expect("six regions");
            let region = [
                Region::Skin,
                Region::Shirt,
                Region::Trousers,
                Region::Shoes,
                Region::Eye,
                Region::Pupil,
            ][best];
            if count * 2 > around.len() && !matches!(region, Region::Eye | Region::Pupil) {
                regions[v] = region;
            }
        }
    }
}

/// Area-weighted vertex normals.
fn vertex_normals(positions: &[DVec3], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
        let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for v in [a, b, c] {
            normals[v] += n;
        }
    }
    normals
        .iter()
        .map(|n| n.try_normalize().unwrap_or(DVec3::Y).as_vec3().to_array())
        .collect()
}

/// Whether the volumes of two joints blend (or share weights): the same joint, or one
/// an ancestor of the other at most `generations` steps up, counting only joints with
/// volumes (the two joints under the root, pelvis and spine, count as neighbours).
fn neighbour_test(
    skeleton: &Skeleton,
    volumes: &[Volume],
    generations: usize,
) -> impl Fn(usize, usize) -> bool {
    let joints = skeleton.joints();
    let mut has = vec![false; joints.len()];
    for v in volumes {
        has[v.joint] = true;
    }
    let fleshy_parent: Vec<Option<usize>> = (0..joints.len())
        .map(|j| {
            let mut p = joints[j].parent;
            while let Some(q) = p {
                if has[q] {
                    return Some(q);
                }
                p = joints[q].parent;
            }
            None
        })
        .collect();
    move |a: usize, b: usize| {
        let within = |a: usize, b: usize| {
            let mut up = Some(a);
            (0..generations).any(|_| {
                up = up.and_then(|j| fleshy_parent[j]);
                up == Some(b)
            })
        };
        a == b
            || within(a, b)
            || within(b, a)
            || (fleshy_parent[a].is_none() && fleshy_parent[b].is_none())
    }
}
