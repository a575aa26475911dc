//! A user's own rigged character (a glTF or VRM humanoid) dressed on a troupe skeleton,
//! so that troupe's postures move the character's skin (thesis 6.5.2: the animator sees
//! the motion on the body it is meant for).
//!
//! A [`Character`] is what a file gave, in the file's own space: a skinned mesh in its
//! bind pose, its bones (bind frames from the inverse bind matrices, rest frames from the
//! file's nodes) and, for each bone, the troupe joint it follows (from a name map;
//! `formats::character` reads files). Most files stand in their bind pose at rest; one
//! bound in another posture (troupe's own skin is bound with the hips a little flexed,
//! `skin::binding`) is fitted by the pose it stands in at rest, and skinned from the one
//! it is bound in. [`Character::dress`] fits it to one skeleton and height, giving a [`Dressing`]:
//!
//! 1. **Placement**: the character is turned so that its hips-to-head line and its
//!    left-right axis lie along those of troupe's rest posture (so it faces +Z, troupe's
//!    front, whatever axes the file used), scaled to the actor's height (its mesh's
//!    extent along up, at rest) and its hips put over troupe's.
//! 2. **Rest poses reconciled**: each mapped bone gets a constant rotation `A`, the
//!    shortest arc from its direction in the file's rest pose (towards the centroid of the
//!    nearest mapped bones below it) to the direction from where it stands in troupe's
//!    rest posture to troupe's rest joints of those bones; an upper arm or a thigh aims
//!    at the end of its limb (the wrist, the foot), so the limb hangs straight. So a
//!    character bound in T-pose hangs its arms as troupe's rest posture does, and a
//!    narrow-shouldered one still puts its hands by troupe's hands. The topmost mapped
//!    bone (the hips) keeps its orientation; a mapped bone with no mapped bone below it
//!    keeps its parent's `A`; the bones of a foot keep their rest orientation (`A` = 1):
//!    a file's rest pose and troupe's both stand flat-footed. Last, the character
//!    is lifted so that its lowest vertex in troupe's rest posture is on the floor.
//! 3. **Posing**: a mapped bone takes the world rotation its troupe joint has made since
//!    rest, `R(q) = Rⱼ(q)·Rⱼ(0)⁻¹·A·R_rest`; its position follows the character's own
//!    bone chain (the character keeps its proportions), and the topmost mapped bone is
//!    carried by its troupe joint; its skinning matrix takes the mesh from the bone's
//!    bind frame there. A bone with no troupe joint keeps its rest pose
//!    relative to its parent, so its skinning matrix is its nearest mapped ancestor's:
//!    troupe joints with no bone (extra vertebrae, fingers of a character without finger
//!    bones) are thereby folded into the nearest mapped bone, whose world rotation
//!    includes theirs. A bone named as one of the helper joints of troupe's own skin (a
//!    character troupe exported) turns as that helper does.
//! 4. **Feet on troupe's feet**: then each leg's knee and hip are bent by two-bone
//!    inverse kinematics so that its ankle rides with troupe's foot where the leg can
//!    reach (`feet`): a character of other proportions does not slide its planted
//!    feet.
//!
//! The skin deforms by linear blend skinning with the file's weights (at most four per
//! vertex, normalised by the reader), as glTF viewers do.

mod feet;

use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use crate::skin::{linear_blend, rest_globals, Helper};
use crate::transform::Transform;
use feet::Leg;
use glam::{DQuat, DVec3};

/// Troupe joints a character must have bones for, to be placed and turned upright.
pub const REQUIRED_JOINTS: [&str; 6] = [
    "sacroiliac",
    "skullbase",
    "l_hip",
    "r_hip",
    "l_shoulder",
    "r_shoulder",
];

/// Troupe joints (without their `l_`/`r_`) at the root of a limb: their bones aim at the
/// limb's end when rest poses are reconciled.
const LIMB_ROOTS: [&str; 2] = ["shoulder", "hip"];

/// Troupe joints (without their `l_`/`r_`) of the foot: their bones keep their
/// orientation at rest, since a character's rest pose and troupe's rest posture both
/// stand flat-footed. Aiming them at troupe's foot joints instead would tilt a foot
/// whose bones are placed otherwise (CesiumMan's toe bone sits at the ball, 4 cm ahead
/// of the ankle, troupe's 18 cm): toes up, heel 3 cm into the floor.
const FOOT: [&str; 4] = ["ankle", "subtalar", "midtarsal", "metatarsal"];

/// A troupe joint's name without its side (`l_hip` → `hip`).
fn sideless(name: &str) -> &str {
    name.strip_prefix("l_")
        .or_else(|| name.strip_prefix("r_"))
        .unwrap_or(name)
}

/// One bone of a character, in the file's space.
#[derive(Clone, Debug, PartialEq)]
pub struct Bone {
    /// The bone's node name in the file.
    pub name: String,
    /// The parent bone (an index into the character's bones, always smaller).
    pub parent: Option<usize>,
    /// The bone's frame in the bind pose (the inverse of its inverse bind matrix): where
    /// the mesh is bound to it.
    pub bind: Transform,
    /// The bone's frame in the file's rest pose (its node's transform, composed from the
    /// scene's root): the pose a modeller shows the character in, which is fitted to
    /// troupe's rest posture. Most files' is their bind pose.
    pub rest: Transform,
    /// The troupe joint whose motion it follows, if mapped.
    pub joint: Option<String>,
}

/// A rigged character as a file describes it: a skinned mesh in its bind pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Character {
    /// Where it came from (the file), for messages.
    pub source: String,
    /// Bones, parents before children.
    pub bones: Vec<Bone>,
    /// Bind-pose vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Bind-pose unit normals.
    pub normals: Vec<[f32; 3]>,
    /// sRGB colour of each vertex (its material's, sampled from its texture where the
    /// reader could, times its vertex colour where the file has one).
    pub colors: Vec<[f32; 3]>,
    /// Up to four bones per vertex (indices into `bones`).
    pub joints: Vec<[u16; 4]>,
    /// Their weights, summing to one.
    pub weights: Vec<[f32; 4]>,
    /// Triangles, counter-clockwise from outside.
    pub indices: Vec<u32>,
    /// Whether both faces of its triangles are to be drawn (a glTF material's
    /// `doubleSided`, on any of its surfaces): an open mesh, a cloak's hem. Otherwise only
    /// the faces seen from outside are, as glTF asks of single-sided materials.
    pub double_sided: bool,
}

/// A character fitted to one skeleton and height, ready to follow its postures.
#[derive(Clone, Debug)]
pub struct Dressing {
    /// Where the character came from.
    pub source: String,
    /// Placed bind-pose vertex positions (troupe's frame, metres).
    pub positions: Vec<[f32; 3]>,
    /// Placed unit normals.
    pub normals: Vec<[f32; 3]>,
    /// sRGB colour of each vertex.
    pub colors: Vec<[f32; 3]>,
    /// Up to four skinning slots per vertex (indices into [`Dressing::skinning_transforms`]).
    pub slots: Vec<[u16; 4]>,
    /// Their weights, summing to one.
    pub weights: Vec<[f32; 4]>,
    /// Triangles.
    pub indices: Vec<u32>,
    /// Whether both faces of its triangles are to be drawn ([`Character::double_sided`]).
    pub double_sided: bool,
    /// Each bone's node name in the file.
    pub bone_names: Vec<String>,
    /// Each bone's parent bone (always a smaller index).
    pub bone_parents: Vec<Option<usize>>,
    bones: Vec<Posed>,
    /// For each slot, the bone whose skinning matrix it is.
    slot_bones: Vec<usize>,
    /// The troupe skeleton's rest frames.
    rest: Vec<Transform>,
    /// The legs whose ankles are kept on troupe's feet.
    legs: Vec<Leg>,
    /// The skin's helper joints that bones of the character are (see [`Rule::Helper`]),
    /// each with its frame's rotation in the pose troupe's skin is made in, inverted, and
    /// its place then in its parent's frame.
    helpers: Vec<(Helper, DQuat, DVec3)>,
}

/// How one bone is posed from troupe's joint frames.
#[derive(Clone, Debug)]
struct Posed {
    /// Placed bind frame: where the mesh is bound to the bone.
    bind: Transform,
    /// Placed rest frame: what the bone's rule turns and carries.
    rest: Transform,
    /// How its position and rotation are found.
    rule: Rule,
}

#[derive(Clone, Debug)]
enum Rule {
    /// Carried rigidly by a troupe joint (the topmost mapped bone, and bones above it).
    Carried { joint: usize, align: DQuat },
    /// Rotates with a troupe joint; placed along its parent at its bind offset.
    Mapped {
        joint: usize,
        align: DQuat,
        parent: usize,
        offset: DVec3,
    },
    /// Keeps its rest pose relative to its parent.
    Follows { parent: usize },
    /// One of the helper joints of troupe's own skin (a character troupe exported: its
    /// shoulders' `l_shoulder_50`, `l_shoulder_twist_25`, its hips' `l_hip_slide`, …):
    /// turned from the pose troupe's skin is made in (its file's rest pose) as the helper
    /// turns (`Helper::frame`), placed along its parent at its rest offset and moved as
    /// the helper moves from its joint's centre, so the skin it carries moves as troupe's
    /// does.
    Helper {
        helper: usize,
        parent: usize,
        offset: DVec3,
    },
}

impl Character {
    /// The mesh standing in the file's rest pose (in the file's space): each vertex
    /// carried by its weights from its bones' bind frames to their rest frames; the
    /// bind-pose positions themselves where the two poses are one (most files).
    fn at_rest(&self) -> Vec<DVec3> {
        if self.bones.iter().all(|b| b.rest == b.bind) {
            return self
                .positions
                .iter()
                .map(|p| DVec3::from(p.map(f64::from)))
                .collect();
        }
        let moved: Vec<Transform> = self
            .bones
            .iter()
            .map(|b| b.rest.mul(&b.bind.inverse()))
            .collect();
        linear_blend(&self.positions, &self.joints, &self.weights, &moved)
    }

    /// Fits the character to `skeleton` at standing height `height` (metres); an error
    /// names the troupe joints it lacks bones for, or a mapped joint the skeleton does
    /// not have.
    pub fn dress(&self, skeleton: &Skeleton, height: f64) -> Result<Dressing> {
        let invalid = |m: String| Error::Invalid(format!("{}: {m}", self.source));
        if !(height.is_finite() && height > 0.0) {
            return Err(invalid(format!("height {height} is not a positive length")));
        }
        let mut joint_of = Vec::with_capacity(self.bones.len());
        for bone in &self.bones {
            joint_of.push(match &bone.joint {
                Some(name) => Some(skeleton.joint(name).map_err(|_| {
                    invalid(format!(
                        "bone `{}` is mapped to `{name}`, which is not a joint of skeleton `{}`",
                        bone.name,
                        skeleton.name()
                    ))
                })?),
                None => None,
            });
        }
        let bone_of = |name: &str| -> Option<usize> {
            let j = skeleton.joint(name).ok()?;
            joint_of.iter().position(|&b| b == Some(j))
        };
        let missing: Vec<&str> = REQUIRED_JOINTS
            .iter()
            .copied()
            .filter(|n| bone_of(n).is_none())
            .collect();
        if !missing.is_empty() {
            return Err(invalid(format!(
                "no bone is mapped to troupe's {} (a humanoid needs them to stand up)",
                missing.join(", ")
            )));
        }
        let at = |name: &str| bone_of(name).map(|b| self.bones[b].rest.translation);
        let rest = rest_globals(skeleton);
        let troupe_at = |name: &str| skeleton.joint(name).ok().map(|j| rest[j].translation);
        // The character's frame (up from hips to head, left from its right side) is
        // turned onto the same frame of troupe's rest posture: a head carried a little
        // forward of the hips stays so.
        let character_frame = frame(&at).ok_or_else(|| {
            invalid("its hips, head and left and right bones do not span a body".into())
        })?;
        let troupe_frame = frame(&troupe_at).ok_or_else(|| {
            invalid(format!(
                "skeleton `{}` has no hips, head or sides",
                skeleton.name()
            ))
        })?;
        let turn = DQuat::from_mat3(&(troupe_frame * character_frame.transpose())).normalize();
        let turned: Vec<DVec3> = self
            .positions
            .iter()
            .map(|p| turn * DVec3::from(p.map(f64::from)))
            .collect();
        // Its height is its mesh's extent standing at rest.
        let (low, high) = self
            .at_rest()
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                let p = turn * *p;
                (lo.min(p.y), hi.max(p.y))
            });
        if turned.is_empty() || !(high - low).is_finite() || high - low <= 0.0 {
            return Err(invalid("its mesh has no height".into()));
        }
        let scale = height / (high - low);
        let hips_bone = bone_of("sacroiliac").unwrap_or(0);
        let hips = rest[joint_of[hips_bone].unwrap_or(0)].translation;
        let hips_char = turn * self.bones[hips_bone].rest.translation * scale;
        let shift = DVec3::new(hips.x - hips_char.x, -low * scale, hips.z - hips_char.z);
        let place = |p: DVec3| turn * p * scale + shift;
        let placed = |t: &Transform| Transform::new(turn * t.rotation, place(t.translation));
        let binds: Vec<Transform> = self.bones.iter().map(|b| placed(&b.bind)).collect();
        let rests: Vec<Transform> = self.bones.iter().map(|b| placed(&b.rest)).collect();

        // The nearest mapped ancestor of each bone, and which bones are mapped.
        let mapped_above: Vec<Option<usize>> = (0..self.bones.len())
            .map(|b| {
                let mut p = self.bones[b].parent;
                while let Some(q) = p {
                    if joint_of[q].is_some() {
                        return Some(q);
                    }
                    p = self.bones[q].parent;
                }
                None
            })
            .collect();
        // Each bone's alignment and where it stands in troupe's rest posture, parents
        // first: a mapped bone aims from where it now stands at troupe's rest joints of
        // the nearest mapped bones below it (so a narrow-shouldered character's hands
        // still hang by troupe's hands); other bones keep their parent's alignment.
        let mut align = vec![DQuat::IDENTITY; self.bones.len()];
        let mut standing = vec![DVec3::ZERO; self.bones.len()];
        for b in 0..self.bones.len() {
            let parent = self.bones[b].parent;
            standing[b] = match parent {
                Some(p) => standing[p] + align[p] * (rests[b].translation - rests[p].translation),
                None => rests[b].translation,
            };
            align[b] = parent.map_or(DQuat::IDENTITY, |p| align[p]);
            let (Some(j), Some(_)) = (joint_of[b], mapped_above[b]) else {
                continue; // the topmost mapped bone keeps its orientation
            };
            let name = sideless(&skeleton.joints()[j].name);
            if FOOT.contains(&name) {
                align[b] = DQuat::IDENTITY;
                continue;
            }
            let mapped_below = |b: usize| -> Vec<usize> {
                (0..self.bones.len())
                    .filter(|&c| mapped_above[c] == Some(b) && joint_of[c].is_some())
                    .collect()
            };
            let mut below = mapped_below(b);
            // An upper arm or thigh aims at the end of its limb (the wrist, the foot),
            // so the limb hangs straight as troupe's does at rest.
            if LIMB_ROOTS.contains(&name) && below.len() == 1 {
                let further = mapped_below(below[0]);
                if further.len() == 1 {
                    below = further;
                }
            }
            if below.is_empty() {
                continue;
            }
            let centroid = |f: &dyn Fn(usize) -> DVec3| {
                below.iter().map(|&c| f(c)).sum::<DVec3>() / below.len() as f64
            };
            let from = centroid(&|c| rests[c].translation) - rests[b].translation;
            let to = centroid(&|c| rest[joint_of[c].unwrap_or(j)].translation) - standing[b];
            align[b] = arc(from, to);
        }

        // Bones named as the helper joints of troupe's skin for this skeleton.
        let skin_helpers = crate::skin::helpers::helpers(skeleton).unwrap_or_default();
        let bind_pose = crate::skin::bind_globals(skeleton);
        let mut helpers: Vec<(Helper, DQuat, DVec3)> = Vec::new();
        let bones: Vec<Posed> = (0..self.bones.len())
            .map(|b| {
                let (bind, rest) = (binds[b], rests[b]);
                let offset_from = |parent: usize| {
                    rests[parent]
                        .inverse()
                        .transform_vector(rest.translation - rests[parent].translation)
                };
                let helper = skin_helpers.iter().find(|h| h.name == self.bones[b].name);
                if let (None, Some(parent), Some(h)) = (joint_of[b], self.bones[b].parent, helper) {
                    let frame = h.frame(&bind_pose);
                    helpers.push((
                        h.clone(),
                        frame.rotation.inverse(),
                        bind_pose[h.parent]
                            .inverse()
                            .transform_point(frame.translation),
                    ));
                    return Posed {
                        bind,
                        rest,
                        rule: Rule::Helper {
                            helper: helpers.len() - 1,
                            parent,
                            offset: offset_from(parent),
                        },
                    };
                }
                let rule = match (joint_of[b], self.bones[b].parent) {
                    (Some(joint), Some(parent)) if mapped_above[b].is_some() => Rule::Mapped {
                        joint,
                        align: align[b],
                        parent,
                        offset: offset_from(parent),
                    },
                    (Some(joint), _) => Rule::Carried {
                        joint,
                        align: align[b],
                    },
                    (None, Some(parent)) => Rule::Follows { parent },
                    // A bone above every mapped one (an armature root) moves with the body.
                    (None, None) => Rule::Carried {
                        joint: joint_of[hips_bone].unwrap_or(0),
                        align: DQuat::IDENTITY,
                    },
                };
                Posed { bind, rest, rule }
            })
            .collect();

        // A bone that follows its parent has its parent's skinning matrix, so vertices
        // are skinned by the bones that move on their own: at most one per troupe joint.
        let driver: Vec<usize> = {
            let mut d: Vec<usize> = (0..bones.len()).collect();
            for b in 0..bones.len() {
                if let Rule::Follows { parent } = bones[b].rule {
                    d[b] = d[parent];
                }
            }
            d
        };
        let mut slot_bones: Vec<usize> = Vec::new();
        let mut slot_of = vec![u16::MAX; bones.len()];
        let mut slots = Vec::with_capacity(self.joints.len());
        let mut weights = Vec::with_capacity(self.joints.len());
        for (js, ws) in self.joints.iter().zip(&self.weights) {
            let mut merged: Vec<(u16, f32)> = Vec::with_capacity(4);
            for (&j, &w) in js.iter().zip(ws) {
                if w <= 0.0 {
                    continue;
                }
                let bone = *driver.get(j as usize).ok_or_else(|| {
                    invalid(format!("a vertex names bone {j}, which does not exist"))
                })?;
                if slot_of[bone] == u16::MAX {
                    slot_of[bone] = slot_bones.len() as u16;
                    slot_bones.push(bone);
                }
                match merged.iter_mut().find(|(s, _)| *s == slot_of[bone]) {
                    Some((_, sum)) => *sum += w,
                    None => merged.push((slot_of[bone], w)),
                }
            }
            let mut s = [0u16; 4];
            let mut w = [0f32; 4];
            for (k, (slot, weight)) in merged.into_iter().enumerate() {
                s[k] = slot;
                w[k] = weight;
            }
            slots.push(s);
            weights.push(w);
        }
        let mut dressing = Dressing {
            source: self.source.clone(),
            positions: turned
                .iter()
                .map(|p| (p * scale + shift).as_vec3().to_array())
                .collect(),
            normals: self
                .normals
                .iter()
                .map(|n| (turn * DVec3::from(n.map(f64::from))).as_vec3().to_array())
                .collect(),
            colors: self.colors.clone(),
            slots,
            weights,
            indices: self.indices.clone(),
            double_sided: self.double_sided,
            bone_names: self.bones.iter().map(|b| b.name.clone()).collect(),
            bone_parents: self.bones.iter().map(|b| b.parent).collect(),
            bones,
            slot_bones,
            rest,
            legs: Vec::new(),
            helpers,
        };
        // Reconciling rest poses moves the mesh (legs bound apart hang straight, and
        // so reach lower): it stands on the floor in troupe's rest posture.
        let lowest = dressing
            .deform(&dressing.rest)
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        dressing.lift(-lowest);
        dressing.legs = dressing.legs(skeleton, &joint_of);
        Ok(dressing)
    }
}

impl Dressing {
    /// Moves the whole character up by `height` (metres): its bind pose, so its every
    /// posture.
    fn lift(&mut self, height: f64) {
        for p in &mut self.positions {
            p[1] += height as f32;
        }
        for bone in &mut self.bones {
            bone.bind.translation.y += height;
            bone.rest.translation.y += height;
        }
    }

    /// Number of skinning slots (distinct matrices the vertices use).
    pub fn slot_count(&self) -> usize {
        self.slot_bones.len()
    }

    /// The bone whose skinning matrix each slot is (an index into the bones).
    pub fn slot_bones(&self) -> &[usize] {
        &self.slot_bones
    }

    /// Every bone's placed bind frame (troupe's frame, metres): where
    /// [`Dressing::positions`] are bound.
    pub fn bind_frames(&self) -> Vec<Transform> {
        self.bones.iter().map(|b| b.bind).collect()
    }

    /// The troupe joint whose motion moves each skinning slot.
    pub fn slot_joints(&self) -> Vec<usize> {
        self.slot_bones
            .iter()
            .map(|&b| self.slot_joint_of(b))
            .collect()
    }

    /// The troupe joint that moves bone `b`: its own, or its nearest moving ancestor's.
    fn slot_joint_of(&self, mut b: usize) -> usize {
        loop {
            match self.bones[b].rule {
                Rule::Carried { joint, .. } | Rule::Mapped { joint, .. } => return joint,
                Rule::Helper { helper, .. } => return self.helpers[helper].0.joint,
                Rule::Follows { parent } => b = parent,
            }
        }
    }

    /// The legs whose thigh, shank and foot bones are mapped to troupe's hip, knee and
    /// ankle (or subtalar) joints, each bone below the one before, given the troupe
    /// joint of each bone (`joint_of`); with where each ankle stands on troupe's foot.
    fn legs(&self, skeleton: &Skeleton, joint_of: &[Option<usize>]) -> Vec<Leg> {
        let bone = |name: &str| -> Option<(usize, usize)> {
            let j = skeleton.joint(name).ok()?;
            let b = joint_of.iter().position(|&x| x == Some(j))?;
            matches!(self.bones[b].rule, Rule::Mapped { .. }).then_some((b, j))
        };
        let below = |lower: usize, upper: usize| {
            let mut b = Some(lower);
            while let Some(x) = b {
                if x == upper {
                    return true;
                }
                b = self.bone_parents[x];
            }
            false
        };
        let rest_frames = self.bone_frames(&self.rest);
        ["l_", "r_"]
            .iter()
            .filter_map(|side| {
                let (thigh, _) = bone(&format!("{side}hip"))?;
                let (shin, knee) = bone(&format!("{side}knee"))?;
                let (foot, ankle) =
                    bone(&format!("{side}ankle")).or_else(|| bone(&format!("{side}subtalar")))?;
                (shin != thigh && foot != shin && below(shin, thigh) && below(foot, shin)).then(
                    || Leg {
                        thigh,
                        shin,
                        foot,
                        knee_joint: knee,
                        foot_joint: ankle,
                        in_foot: self.rest[ankle]
                            .inverse()
                            .transform_point(rest_frames[foot].translation),
                    },
                )
            })
            .collect()
    }

    /// Every bone's world frame for troupe joint frames `globals`: the rotations troupe's
    /// joints made (steps 3 and 4 of [the module](self)), then the legs bent so that the
    /// feet stay on troupe's.
    pub fn bone_frames(&self, globals: &[Transform]) -> Vec<Transform> {
        // How far each helper has turned from the pose troupe's skin is made in, and how
        // far a sliding helper has moved from its joint's centre (the same for both passes
        // below).
        let helpers_turned: Vec<Transform> = self
            .helpers
            .iter()
            .map(|(h, bind_inv, place)| {
                let frame = h.frame(globals);
                // Moved from where its parent carries it: for a helper at its joint's
                // centre, from the joint's centre; for one between two joints, from its
                // place between them at the bind.
                let from = match h.pair {
                    None => globals[h.joint].translation,
                    Some(_) => globals[h.parent].transform_point(*place),
                };
                Transform::new(frame.rotation * *bind_inv, frame.translation - from)
            })
            .collect();
        let frames = self.rotated_frames(globals, &helpers_turned, &[]);
        if self.legs.is_empty() {
            return frames;
        }
        let turns: Vec<(usize, DQuat)> = self
            .legs
            .iter()
            .flat_map(|leg| leg.reach(&frames, globals, &self.rest))
            .collect();
        self.rotated_frames(globals, &helpers_turned, &turns)
    }

    /// Every bone's world frame with the rotations of troupe's joints and the helpers'
    /// turns and moves `helpers_turned` (the world rotation from the bind, the world
    /// offset from the joint's centre), a mapped bone turned further by its entry of
    /// `turns` (bone, world rotation) if it has one.
    fn rotated_frames(
        &self,
        globals: &[Transform],
        helpers_turned: &[Transform],
        turns: &[(usize, DQuat)],
    ) -> Vec<Transform> {
        let mut frames: Vec<Transform> = Vec::with_capacity(self.bones.len());
        for (b, bone) in self.bones.iter().enumerate() {
            let moved = |joint: usize| globals[joint].mul(&self.rest[joint].inverse());
            let turn = turns
                .iter()
                .find(|(t, _)| *t == b)
                .map_or(DQuat::IDENTITY, |(_, q)| *q);
            let frame = match bone.rule {
                Rule::Carried { joint, align } => {
                    let m = moved(joint);
                    Transform::new(
                        m.rotation * align * bone.rest.rotation,
                        m.transform_point(bone.rest.translation),
                    )
                }
                Rule::Mapped {
                    joint,
                    align,
                    parent,
                    offset,
                } => Transform::new(
                    turn * moved(joint).rotation * align * bone.rest.rotation,
                    frames[parent].transform_point(offset),
                ),
                Rule::Follows { parent } => {
                    frames[parent].mul(&self.bones[parent].rest.inverse().mul(&bone.rest))
                }
                Rule::Helper {
                    helper,
                    parent,
                    offset,
                } => Transform::new(
                    helpers_turned[helper].rotation * bone.rest.rotation,
                    frames[parent].transform_point(offset) + helpers_turned[helper].translation,
                ),
            };
            frames.push(frame);
        }
        frames
    }

    /// Skinning transforms for troupe joint frames `globals`, one per slot: each carries
    /// a placed bind-pose vertex to where its bone has moved it.
    pub fn skinning_transforms(&self, globals: &[Transform]) -> Vec<Transform> {
        let frames = self.bone_frames(globals);
        self.slot_bones
            .iter()
            .map(|&b| frames[b].mul(&self.bones[b].bind.inverse()))
            .collect()
    }

    /// The character's vertex positions for troupe joint frames `globals`, by linear
    /// blend skinning.
    pub fn deform(&self, globals: &[Transform]) -> Vec<DVec3> {
        let m = self.skinning_transforms(globals);
        linear_blend(&self.positions, &self.slots, &self.weights, &m)
    }
}

/// The body frame of joint positions `at` (by troupe joint name): columns left (+X in
/// troupe), up from hips to head, front; `None` when they do not span one.
fn frame(at: &dyn Fn(&str) -> Option<DVec3>) -> Option<glam::DMat3> {
    let pair = |l: &str, r: &str| Some(at(l)? - at(r)?);
    let up = pair("skullbase", "sacroiliac")?.try_normalize()?;
    let lateral = pair("l_hip", "r_hip")? + pair("l_shoulder", "r_shoulder")?;
    let left = (lateral - up * lateral.dot(up)).try_normalize()?;
    Some(glam::DMat3::from_cols(left, up, left.cross(up)))
}

/// The rotation taking direction `from` onto `to` by the shortest arc (identity when
/// either has no direction).
fn arc(from: DVec3, to: DVec3) -> DQuat {
    match (from.try_normalize(), to.try_normalize()) {
        (Some(a), Some(b)) => DQuat::from_rotation_arc(a, b),
        _ => DQuat::IDENTITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward_kinematics;
    use crate::template::default_skeleton;

    /// A character made of troupe's own skeleton: one bone per joint at its rest frame,
    /// one vertex on each joint (moved by it alone), and two on the floor and the crown.
    fn troupe_shaped(skeleton: &Skeleton, height: f64) -> Character {
        let rest = rest_globals(skeleton);
        let joints = skeleton.joints();
        let mut positions: Vec<[f32; 3]> = rest
            .iter()
            .map(|t| t.translation.as_vec3().to_array())
            .collect();
        let mut bone_of: Vec<u16> = (0..joints.len() as u16).collect();
        positions.push([0.0, 0.0, 0.0]);
        positions.push([0.0, height as f32, 0.0]);
        bone_of.extend([0, skeleton.joint("skullbase").unwrap() as u16]);
        let n = positions.len();
        Character {
            source: "troupe-shaped".into(),
            bones: joints
                .iter()
                .zip(&rest)
                .map(|(j, t)| Bone {
                    name: j.name.clone(),
                    parent: j.parent,
                    bind: Transform::new(DQuat::IDENTITY, t.translation),
                    rest: Transform::new(DQuat::IDENTITY, t.translation),
                    joint: Some(j.name.clone()),
                })
                .collect(),
            normals: vec![[0.0, 1.0, 0.0]; n],
            colors: vec![[1.0; 3]; n],
            joints: bone_of.iter().map(|&b| [b, 0, 0, 0]).collect(),
            weights: vec![[1.0, 0.0, 0.0, 0.0]; n],
            indices: vec![0, 1, 2],
            double_sided: false,
            positions,
        }
    }

    #[test]
    fn a_character_shaped_like_troupe_follows_its_joints_exactly() {
        let skeleton = default_skeleton("adult").unwrap();
        let character = troupe_shaped(&skeleton, 1.75);
        let dressing = character.dress(&skeleton, 1.75).unwrap();
        let mut q = vec![0.0; skeleton.dof_count()];
        for (d, v) in q.iter_mut().enumerate() {
            // Every DOF moved, each by its own amount.
            *v = 0.3 * ((d * 7919 % 13) as f64 / 13.0 - 0.5);
        }
        let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
        forward_kinematics(&skeleton, &q, &mut globals);
        let posed = dressing.deform(&globals);
        for (j, g) in globals.iter().enumerate() {
            assert!(
                (posed[j] - g.translation).length() < 1e-4,
                "{}: {} vs {}",
                skeleton.joints()[j].name,
                posed[j],
                g.translation
            );
        }
        // Folded joints: with only the required bones mapped, a fingertip follows the
        // wrist's nearest mapped ancestor rigidly, never tearing away from it.
        let mut sparse = character.clone();
        for bone in &mut sparse.bones {
            if !REQUIRED_JOINTS.contains(&bone.joint.as_deref().unwrap()) {
                bone.joint = None;
            }
        }
        let dressing = sparse.dress(&skeleton, 1.75).unwrap();
        assert!(dressing.slot_count() <= REQUIRED_JOINTS.len() + 1);
        let posed = dressing.deform(&globals);
        assert!(posed.iter().all(|p| p.is_finite()));
    }

    #[test]
    fn missing_required_bones_and_unknown_joints_are_named() {
        let skeleton = default_skeleton("adult").unwrap();
        let mut character = troupe_shaped(&skeleton, 1.75);
        for bone in &mut character.bones {
            if bone.name.ends_with("_hip") {
                bone.joint = None;
            }
        }
        let err = character.dress(&skeleton, 1.75).unwrap_err().to_string();
        assert!(err.contains("l_hip, r_hip"), "{err}");
        character.bones[3].joint = Some("tail".into());
        let err = character.dress(&skeleton, 1.75).unwrap_err().to_string();
        assert!(err.contains("mapped to `tail`"), "{err}");
        assert!(troupe_shaped(&skeleton, 1.75)
            .dress(&skeleton, f64::NAN)
            .is_err());
    }
}
