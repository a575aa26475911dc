//! Between a template's postures and VRM bone poses: what a VMC stream carries.
//!
//! **Frames.** troupe is right-handed with Y up, and an actor facing 0° looks along +Z with
//! its left hand at +X. Unity (so VMC) is left-handed with Y up, and an avatar looks along
//! +Z with its left hand at −X. One mirror of X takes one to the other: a point
//! `(x, y, z)` becomes `(−x, y, z)` and a quaternion `(x, y, z, w)` becomes
//! `(x, −y, −z, w)`, both ways.
//!
//! **Rest pose.** A normalized VRM avatar's bones have no rotation in its T-pose: every
//! bone's frame is the world's. troupe's T-pose is the template's zero posture with the
//! shoulders abducted 90°. So the rotation a VRM bone has in the world is its template
//! joint's global rotation "since the T-pose", `G · G_T⁻¹`, and the rotation VMC sends is
//! that relative to the parent bone's: `L = D_parent⁻¹ · D`.
//!
//! **Root.** `/VMC/Ext/Root/Pos` carries the actor's place on the floor (below the hips)
//! and its heading (the hips' turn about the vertical); `Hips` is relative to it. Each
//! other bone's position is its offset from its parent bone, in the parent's frame.

use crate::vmc::bones::{VrmBone, VRM_BONES};
use glam::{DMat3, DQuat, DVec3};
use std::f64::consts::{PI, TAU};
use std::sync::Arc;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::skeleton::{Dof, DofKind, Skeleton};
use troupe_body::transform::Transform;

/// A point from troupe's frame to Unity's, or back (the mirror is its own inverse).
pub fn mirror_point(p: DVec3) -> DVec3 {
    DVec3::new(-p.x, p.y, p.z)
}

/// A rotation from troupe's frame to Unity's, or back.
pub fn mirror_rotation(q: DQuat) -> DQuat {
    DQuat::from_xyzw(q.x, -q.y, -q.z, q.w)
}

/// A pose from troupe's frame to Unity's, or back.
pub fn mirror(t: Transform) -> Transform {
    Transform::new(mirror_rotation(t.rotation), mirror_point(t.translation))
}

/// What one VMC frame says of an avatar, in Unity's frame: the root's pose, and each VRM
/// bone's pose relative to its parent bone (index of [`VRM_BONES`]; `None`: not sent).
#[derive(Clone, Debug, PartialEq)]
pub struct VmcPose {
    /// `/VMC/Ext/Root/Pos`.
    pub root: Option<Transform>,
    /// `/VMC/Ext/Bone/Pos`, by bone index.
    pub bones: Vec<Option<Transform>>,
}

impl Default for VmcPose {
    fn default() -> Self {
        VmcPose {
            root: None,
            bones: vec![None; VRM_BONES.len()],
        }
    }
}

impl VmcPose {
    /// Whether the frame carries no root and no bone.
    pub fn is_empty(&self) -> bool {
        self.root.is_none() && self.bones.iter().all(Option::is_none)
    }

    /// Writes what `newer` carries over this pose (a receiver keeps each bone's latest).
    pub fn update(&mut self, newer: &VmcPose) {
        if newer.root.is_some() {
            self.root = newer.root;
        }
        for (b, n) in self.bones.iter_mut().zip(&newer.bones) {
            if n.is_some() {
                *b = *n;
            }
        }
    }

    /// The pose between `self` (at 0) and `other` (at 1): positions interpolated linearly
    /// and rotations spherically; a bone only one of them has keeps that value.
    pub fn lerp(&self, other: &VmcPose, u: f64) -> VmcPose {
        let mix = |a: Option<Transform>, b: Option<Transform>| match (a, b) {
            (Some(a), Some(b)) => Some(Transform::new(
                a.rotation.slerp(b.rotation, u).normalize(),
                a.translation.lerp(b.translation, u),
            )),
            (a, b) => a.or(b),
        };
        VmcPose {
            root: mix(self.root, other.root),
            bones: self
                .bones
                .iter()
                .zip(&other.bones)
                .map(|(a, b)| mix(*a, *b))
                .collect(),
        }
    }
}

/// One template prepared for VMC: each VRM bone's joint, the rotation DOFs of the joints
/// it spans, and the T-pose.
pub struct VmcRig {
    skeleton: Arc<Skeleton>,
    /// Per bone: its joint.
    joints: Vec<usize>,
    /// Per bone: its VRM parent's index.
    parents: Vec<Option<usize>>,
    /// Per bone: the rotation DOFs of the joints it spans, parent side first.
    chains: Vec<Vec<usize>>,
    /// Per bone: its joint's global rotation in the T-pose.
    rest: Vec<DQuat>,
    /// Per bone spanning two joints right under its parent bone's: (upper, lower) joint.
    split: Vec<Option<(usize, usize)>>,
    /// The index of `Spine`, whose offset shows the pelvis's own turn.
    spine: usize,
    /// The root joint's rotation DOFs (a received `Hips` turns the whole body).
    root_rotations: Vec<usize>,
    /// The pelvis joint's DOFs, held straight when `Hips` is received.
    pelvis: Vec<usize>,
    /// Thigh plus shank length: how a received stream's hips height is scaled.
    leg_length: f64,
}

/// The template's T-pose: every DOF zero but the shoulders, abducted 90° (arms level).
pub fn t_pose(skeleton: &Skeleton) -> Vec<f64> {
    let mut q = vec![0.0; skeleton.dof_count()];
    for name in ["l_shoulder_abduction", "r_shoulder_abduction"] {
        if let Ok(d) = skeleton.dof(name) {
            q[d] = std::f64::consts::FRAC_PI_2;
        }
    }
    q
}

/// A template joint that a VRM bone needs is missing.
#[derive(Debug, thiserror::Error)]
#[error("VMC: the template has no joint '{joint}' for VRM bone {bone}")]
pub struct RigError {
    /// The VRM bone.
    pub bone: &'static str,
    /// The joint it needs.
    pub joint: &'static str,
}

impl VmcRig {
    /// Prepares `skeleton` (a troupe template: its joints carry the VRM bones).
    pub fn new(skeleton: Arc<Skeleton>) -> Result<VmcRig, RigError> {
        let joint_of = |b: &VrmBone| {
            skeleton.joint(b.joint).map_err(|_| RigError {
                bone: b.name,
                joint: b.joint,
            })
        };
        let joints = VRM_BONES
            .iter()
            .map(joint_of)
            .collect::<Result<Vec<_>, _>>()?;
        let parents: Vec<Option<usize>> = VRM_BONES
            .iter()
            .map(|b| b.parent.and_then(crate::vmc::bones::bone_index))
            .collect();
        let rotations = |j: usize| {
            skeleton.joints()[j]
                .dofs
                .clone()
                .filter(|&d| skeleton.dofs()[d].kind == DofKind::Rotation)
                .collect::<Vec<_>>()
        };
        let mut chains = Vec::with_capacity(joints.len());
        let mut split = Vec::with_capacity(joints.len());
        for (i, &j) in joints.iter().enumerate() {
            // The chain stops at the parent bone's joint or any joint above it (the
            // spine hangs from the root, not from the pelvis that carries `Hips`).
            let mut stops = Vec::new();
            let mut a = parents[i].map(|p| joints[p]);
            while let Some(p) = a {
                stops.push(p);
                a = skeleton.joints()[p].parent;
            }
            let mut path = vec![j];
            let mut a = skeleton.joints()[j].parent;
            while let Some(p) = a.filter(|p| !stops.contains(p)) {
                path.push(p);
                a = skeleton.joints()[p].parent;
            }
            let under_parent = |a: usize| skeleton.joints()[a].parent == stops.first().copied();
            split.push(match path.as_slice() {
                [lower, upper] if under_parent(*upper) => Some((*upper, *lower)),
                _ => None,
            });
            chains.push(path.iter().rev().flat_map(|&j| rotations(j)).collect());
        }
        let root = 0;
        let pelvis = joints[0];
        let mut g = vec![Transform::IDENTITY; skeleton.joints().len()];
        forward_kinematics(&skeleton, &t_pose(&skeleton), &mut g);
        let rest = joints.iter().map(|&j| g[j].rotation).collect();
        let at = |name: &str| skeleton.joint(name).map(|j| g[j].translation).ok();
        let leg_length = match (at("l_hip"), at("l_knee"), at("l_subtalar")) {
            (Some(h), Some(k), Some(a)) => (k - h).length() + (a - k).length(),
            _ => 1.0,
        };
        Ok(VmcRig {
            split,
            spine: crate::vmc::bones::bone_index("Spine").unwrap_or(0),
            root_rotations: rotations(root),
            pelvis: rotations(pelvis),
            skeleton,
            joints,
            parents,
            chains,
            rest,
            leg_length,
        })
    }

    /// The skeleton.
    pub fn skeleton(&self) -> &Arc<Skeleton> {
        &self.skeleton
    }

    /// Every DOF a received stream can set: the root's, and those of each bone's joints.
    pub fn dofs(&self) -> Vec<usize> {
        let root = &self.skeleton.joints()[0];
        let mut v: Vec<usize> = root.dofs.clone().collect();
        v.extend(self.pelvis.iter().copied());
        v.extend(self.chains.iter().flatten().copied());
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The DOFs bone `i` sets when received (the root's and the pelvis's for `Hips`).
    pub fn bone_dofs(&self, i: usize) -> Vec<usize> {
        if i == 0 {
            let mut v: Vec<usize> = self.skeleton.joints()[0].dofs.clone().collect();
            v.extend(self.pelvis.iter().copied());
            v
        } else {
            self.chains[i].clone()
        }
    }

    /// The VMC pose of an actor whose joints are at `globals` (world frame): the root on
    /// the floor below the hips, turned with them; every bone relative to its parent.
    pub fn pose(&self, globals: &[Transform]) -> VmcPose {
        let since_rest: Vec<DQuat> = self
            .joints
            .iter()
            .zip(&self.rest)
            .map(|(&j, r)| (globals[j].rotation * r.inverse()).normalize())
            .collect();
        let hips = globals[self.joints[0]].translation;
        let d = since_rest[0];
        let heading = DQuat::from_xyzw(0.0, d.y, 0.0, d.w);
        let heading = if heading.length() > 1e-9 {
            heading.normalize()
        } else {
            DQuat::IDENTITY
        };
        let root = Transform::new(heading, DVec3::new(hips.x, 0.0, hips.z));
        let mut bones = Vec::with_capacity(self.joints.len());
        for (i, &j) in self.joints.iter().enumerate() {
            let (parent_rot, parent_at) = match self.parents[i] {
                Some(p) => (since_rest[p], globals[self.joints[p]].translation),
                None => (root.rotation, root.translation),
            };
            let inv = parent_rot.inverse();
            let local = Transform::new(
                (inv * since_rest[i]).normalize(),
                inv * (globals[j].translation - parent_at),
            );
            bones.push(Some(mirror(local)));
        }
        VmcPose {
            root: Some(mirror(root)),
            bones,
        }
    }

    /// Retargets a received pose onto the actor: `q` starts as the actor's posture now and
    /// receives the root's place and every received bone's rotation, through the T-pose;
    /// `mask` marks what was set. `place` puts the sender's world in the scene (the
    /// performer's place and facing). A sender's hips height is scaled by the legs'
    /// length ratio when it sends the shank and foot offsets (its proportions).
    pub fn retarget(&self, pose: &VmcPose, place: &Transform, q: &mut [f64], mask: &mut [bool]) {
        let sk = &self.skeleton;
        let root = place.mul(&mirror(pose.root.unwrap_or(Transform::IDENTITY)));
        let scale = self.proportions(pose);
        // Each bone's rotation since the T-pose, parents first: received, or the actor's
        // own under what was received above it (a bone not sent keeps its local pose).
        let mut since_rest = vec![DQuat::IDENTITY; self.joints.len()];
        for (i, bone) in pose.bones.iter().enumerate() {
            let Some(local) = bone.map(mirror) else {
                since_rest[i] = global_rotation(sk, self.joints[i], q) * self.rest[i].inverse();
                continue;
            };
            let parent = match self.parents[i] {
                Some(p) => since_rest[p],
                None => root.rotation,
            };
            since_rest[i] = (parent * local.rotation).normalize();
            let wanted = since_rest[i] * self.rest[i];
            if i == 0 {
                let hips = root.transform_point(local.translation * scale);
                let spine = pose.bones[self.spine].map(|t| mirror_point(t.translation));
                self.place_root(hips, wanted, spine, q, mask);
            } else {
                let top = self.chains[i].first().map(|&d| sk.dofs()[d].joint);
                let above = top
                    .and_then(|j| sk.joints()[j].parent)
                    .map(|p| global_rotation(sk, p, q))
                    .unwrap_or(DQuat::IDENTITY);
                let offset = self.parents[i].map(|p| self.rest[p].inverse() * local.translation);
                self.solve_bone(i, above.inverse() * wanted, offset, q);
                self.chains[i].iter().for_each(|&d| mask[d] = true);
            }
        }
    }

    /// Sets bone `i`'s chain to the rotation `wanted` relative to the joint above it. A
    /// chain of two joints under the parent bone's joint (vt6 and vt1, ring0 and ring1, the
    /// ankle and the subtalar joint) is split as the sender's `offset` says (the bone's
    /// position in the parent joint's frame) when that offset fits the template: it is
    /// then a troupe sender, and the bend is shared as it was. Otherwise the smallest
    /// change shares it.
    fn solve_bone(&self, i: usize, wanted: DQuat, offset: Option<DVec3>, q: &mut [f64]) {
        let sk = &self.skeleton;
        let split = match (self.split[i], offset) {
            (Some((upper, lower)), Some(s)) => {
                let (a, b) = (sk.joints()[upper].offset, sk.joints()[lower].offset);
                swing(b, s - a).map(|arc| (upper, lower, arc))
            }
            _ => None,
        };
        let Some((upper, lower, arc)) = split else {
            solve_chain(sk, &self.chains[i], wanted, q);
            return;
        };
        let dofs = |j: usize| -> Vec<usize> {
            self.chains[i]
                .iter()
                .copied()
                .filter(|&d| sk.dofs()[d].joint == j)
                .collect()
        };
        let upper_dofs = dofs(upper);
        solve_chain(sk, &upper_dofs, arc, q);
        let got = chain_rotation(sk, &upper_dofs, q);
        solve_chain(sk, &dofs(lower), got.inverse() * wanted, q);
    }

    /// The root joint so that the pelvis is at `hips` with the global rotation `wanted`.
    /// The pelvis joint takes the part of that rotation that the sender's spine offset
    /// `spine` (in the pelvis's frame) shows, when it fits the template; the root the rest.
    fn place_root(
        &self,
        hips: DVec3,
        wanted: DQuat,
        spine: Option<DVec3>,
        q: &mut [f64],
        mask: &mut [bool],
    ) {
        let sk = &self.skeleton;
        let root = &sk.joints()[0];
        let pelvis = &sk.joints()[self.joints[0]];
        let spine_offset = sk.joints()[self.joints[self.spine]].offset - pelvis.offset;
        for &d in &self.pelvis {
            q[d] = 0.0;
        }
        if let Some(arc) = spine.and_then(|s| swing(s, spine_offset)) {
            solve_chain(sk, &self.pelvis, arc, q);
        }
        let turn = chain_rotation(sk, &self.pelvis, q);
        let body = wanted * turn.inverse();
        solve_chain(sk, &self.root_rotations, body, q);
        let at = hips - body * pelvis.offset - root.offset;
        for d in root.dofs.clone() {
            let dof = &sk.dofs()[d];
            if dof.kind == DofKind::Translation {
                q[d] = dof.axis.dot(at);
            }
        }
        root.dofs
            .clone()
            .chain(self.pelvis.iter().copied())
            .for_each(|d| mask[d] = true);
    }

    /// Receiver leg length over the sender's, when the sender's shank and foot offsets
    /// are known; 1 otherwise.
    fn proportions(&self, pose: &VmcPose) -> f64 {
        let len = |name: &str| {
            crate::vmc::bones::bone_index(name)
                .and_then(|i| pose.bones[i])
                .map(|t| t.translation.length())
        };
        match (len("LeftLowerLeg"), len("LeftFoot")) {
            (Some(a), Some(b)) if a + b > 0.2 && (a + b).is_finite() => self.leg_length / (a + b),
            _ => 1.0,
        }
    }
}

/// The rotation taking direction `from` to direction `to` when both have the same length
/// (within a millimetre: the sender's bones are the template's); `None` otherwise.
fn swing(from: DVec3, to: DVec3) -> Option<DQuat> {
    let (a, b) = (from.length(), to.length());
    ((a - b).abs() < 1e-3 && a > 1e-6).then(|| DQuat::from_rotation_arc(from / a, to / b))
}

/// Joint `j`'s global rotation at `q` (joint offsets carry no rotation: the product of
/// the rotation DOFs from the root down).
fn global_rotation(skeleton: &Skeleton, j: usize, q: &[f64]) -> DQuat {
    let mut path = Vec::new();
    let mut a = Some(j);
    while let Some(k) = a {
        path.push(k);
        a = skeleton.joints()[k].parent;
    }
    path.iter().rev().fold(DQuat::IDENTITY, |r, &k| {
        skeleton.joints()[k].dofs.clone().fold(r, |r, d| {
            let dof = &skeleton.dofs()[d];
            match dof.kind {
                DofKind::Rotation => r * DQuat::from_axis_angle(dof.axis, q[d]),
                DofKind::Translation => r,
            }
        })
    })
}

/// The product of the rotations of `dofs` at `q`, in order.
fn chain_rotation(skeleton: &Skeleton, dofs: &[usize], q: &[f64]) -> DQuat {
    dofs.iter().fold(DQuat::IDENTITY, |r, &d| {
        r * DQuat::from_axis_angle(skeleton.dofs()[d].axis, q[d])
    })
}

/// Sets the rotation DOFs `dofs` (of one joint or a chain of joints, parent side first,
/// whose offsets carry no rotation) so that their product is `target`. Three DOFs about
/// the three principal axes (a shoulder, a hip, the root) are Euler angles, solved in
/// closed form (`solve_euler`); any other chain by damped least squares, each step the
/// smallest change, so a chain of similar joints shares a bend.
pub fn solve_chain(skeleton: &Skeleton, dofs: &[usize], target: DQuat, q: &mut [f64]) {
    match euler_axes(skeleton, dofs) {
        Some(axes) => solve_euler(skeleton, dofs, axes, target, q),
        None => solve_least_squares(skeleton, dofs, target, q),
    }
}

/// Below this `cos b` (the middle Euler angle within 1e-9 rad of ±90°) the first and last
/// axes line up (gimbal lock): only their sum or difference is set, and taking the whole
/// target as that case moves the result by at most this angle.
const GIMBAL: f64 = 1e-9;

/// Below this `cos b` (the middle angle within 1.15° of ±90°) the joint is near gimbal
/// lock: the exact first angle is the direction of the target's small departure from the
/// lock, so a sender's noise of a tenth of a degree turns it by up to 90° frame to frame
/// (and the last angle back), the product staying right. Angles near the current ones
/// within [`NEAR_LOCK_TOLERANCE`] of the target are then also offered. Farther out the
/// solve is exact; at this bound, taking the exact angles moves the first one by at most
/// asin(sin 0.1° / sin 1.15°) ≈ 5°, about what the sender's noise moves it there anyway.
const NEAR_LOCK: f64 = 2e-2;

/// How far from the target (0.1°: a sender's noise) a solution near gimbal lock may turn
/// the joint to stay continuous with the current posture. Within 0.1° of the lock every
/// first angle is within it, so the current one is kept; farther, the first angle moves
/// only as far as needed to come within it.
const NEAR_LOCK_TOLERANCE: f64 = 0.1 * PI / 180.0;

/// A DOF axis that is a principal axis of its joint's frame: its index (X 0, Y 1, Z 2)
/// and its sign.
fn principal_axis(axis: DVec3) -> Option<(usize, f64)> {
    let a = axis.to_array();
    let i = (0..3).max_by(|&x, &y| a[x].abs().total_cmp(&a[y].abs()))?;
    let off = (0..3)
        .filter(|&k| k != i)
        .map(|k| a[k].abs())
        .fold(0.0, f64::max);
    ((a[i].abs() - 1.0).abs() < 1e-9 && off < 1e-9).then(|| (i, a[i].signum()))
}

/// The principal axes (index, sign) of `dofs` when they are three rotations about the
/// three different principal axes: then their angles are Euler angles.
fn euler_axes(skeleton: &Skeleton, dofs: &[usize]) -> Option<[(usize, f64); 3]> {
    let axis = |d: usize| {
        let dof = &skeleton.dofs()[d];
        if dof.kind == DofKind::Rotation {
            principal_axis(dof.axis)
        } else {
            None
        }
    };
    let &[d0, d1, d2] = dofs else { return None };
    let axes = [axis(d0)?, axis(d1)?, axis(d2)?];
    let distinct = axes[0].0 != axes[1].0 && axes[1].0 != axes[2].0 && axes[0].0 != axes[2].0;
    distinct.then_some(axes)
}

/// Sets three Euler-angle DOFs (`axes` from [`euler_axes`]) so that their product is
/// exactly `target`. A rotation has two sets of Euler angles (`(a, b, c)` and
/// `(a + π, π − b, c + π)`), each angle up to turns, and in gimbal lock a continuum: the
/// set kept is the one within the DOFs' limits (else the least outside them) nearest the
/// current values. The current values so only choose between equal rotations (near gimbal
/// lock, [`NEAR_LOCK`], between rotations within [`NEAR_LOCK_TOLERANCE`] of the target, so
/// that the angles follow a noisy target continuously): an iterative solve from them can
/// end on the set outside the limits, which clamping then turns into another rotation.
fn solve_euler(
    skeleton: &Skeleton,
    dofs: &[usize],
    axes: [(usize, f64); 3],
    target: DQuat,
    q: &mut [f64],
) {
    let [(i, _), (j, _), (k, _)] = axes;
    let e = DVec3::AXES;
    // Angles about the positive axes e_i, e_j, e_k; ε = e_i · (e_j × e_k).
    let eps = if j == (i + 1) % 3 { 1.0 } else { -1.0 };
    let target = target.normalize();
    // Given the first angle a, the others: P = R_i(a)⁻¹ · target = R_j(b) · R_k(c) takes
    // e_k to cos b · e_k + ε sin b · e_i, which gives b; c is what remains about e_k, so
    // the product is the target whenever a belongs to one of its solutions.
    let rest = |a: f64| -> [f64; 3] {
        let p = DQuat::from_axis_angle(e[i], a).inverse() * target;
        let w = p * e[k];
        let b = (eps * w[i]).atan2(w[k]);
        let n = DQuat::from_axis_angle(e[j], b).inverse() * p;
        let c = 2.0 * n.xyz()[k].atan2(n.w);
        [a, b, c]
    };
    let sign = axes.map(|(_, s)| s);
    let now = [
        q[dofs[0]] * sign[0],
        q[dofs[1]] * sign[1],
        q[dofs[2]] * sign[2],
    ];
    // target · e_k = R_i(a) (cos b · e_k + ε sin b · e_i): its e_j, e_k part is a's.
    let v = target * e[k];
    let cos_b = v[j].hypot(v[k]);
    let exact = cos_b > GIMBAL;
    let a_exact = (-eps * v[j]).atan2(v[k]);
    let mut candidates: Vec<[f64; 3]> = if exact {
        vec![rest(a_exact), rest(a_exact + PI)]
    } else {
        Vec::new()
    };
    if cos_b < NEAR_LOCK {
        // In lock any a works, with c = c(a₀) − σ (a − a₀): the candidates are a₀, the
        // point nearest the current (a₀, c₀), and where a or c meets a limit. Near lock
        // `rest(a)` turns the joint asin(cos b · |sin(a − a*)|) off the target (a* the
        // exact first angle: it misses only p · e_k's e_j part), so these are kept within
        // the tolerance, and the first angles where that error reaches it are added (the
        // ends of the arcs it allows, so a current one outside moves only to the nearest).
        let from_now = rest(now[0]);
        let sigma = eps * from_now[1].signum();
        let offset = |c: f64| wrap_pi(from_now[2] - c);
        let limits = |n: usize| {
            let dof = &skeleton.dofs()[dofs[n]];
            [dof.min * sign[n], dof.max * sign[n]]
                .into_iter()
                .filter(|l| l.is_finite())
        };
        let mut ts = vec![now[0], now[0] + sigma * offset(now[2]) / 2.0];
        ts.extend(limits(0));
        ts.extend(limits(2).map(|c| now[0] + sigma * offset(c)));
        if exact {
            // Just inside the tolerance, so rounding does not filter them out.
            let w = (NEAR_LOCK_TOLERANCE.sin() * (1.0 - 1e-9) / cos_b)
                .min(1.0)
                .asin();
            ts.extend([-w, w, PI - w, PI + w].map(|x| a_exact + x));
        }
        let near = |angles: &[f64; 3]| {
            let [a, b, c] = *angles;
            let got = DQuat::from_axis_angle(e[i], a)
                * DQuat::from_axis_angle(e[j], b)
                * DQuat::from_axis_angle(e[k], c);
            let d = got * target.inverse();
            2.0 * d.xyz().length().atan2(d.w.abs()) <= NEAR_LOCK_TOLERANCE
        };
        candidates.extend(ts.into_iter().map(rest).filter(|c| !exact || near(c)));
    }
    let mut best: Option<(f64, f64, [f64; 3])> = None;
    for angles in candidates {
        let mut set = [0.0; 3];
        let (mut out, mut dist) = (0.0, 0.0);
        for n in 0..3 {
            let dof = &skeleton.dofs()[dofs[n]];
            let (x, o) = nearest_turn(dof, angles[n] * sign[n], q[dofs[n]]);
            set[n] = x;
            out += o;
            dist += (x - q[dofs[n]]).powi(2);
        }
        let better = match best {
            None => true,
            Some((bo, _, _)) if (out - bo).abs() > 1e-12 => out < bo,
            Some((_, bd, _)) => dist < bd,
        };
        if better {
            best = Some((out, dist, set));
        }
    }
    if let Some((_, _, set)) = best {
        for n in 0..3 {
            q[dofs[n]] = set[n];
        }
    }
}

/// `x` turned into (−π, π].
fn wrap_pi(x: f64) -> f64 {
    let y = x.rem_euclid(TAU);
    if y > PI {
        y - TAU
    } else {
        y
    }
}

/// `angle` plus the number of turns that puts it within `dof`'s limits, or least outside
/// them, and nearest `now`; and how far outside the limits that is.
fn nearest_turn(dof: &Dof, angle: f64, now: f64) -> (f64, f64) {
    let near = |to: f64| angle + TAU * ((to - angle) / TAU).round();
    let mid = (dof.min + dof.max) / 2.0;
    let mut bases = vec![near(now)];
    if mid.is_finite() {
        bases.push(near(mid));
    }
    let mut best = (angle, f64::INFINITY, f64::INFINITY);
    for base in bases {
        for x in [base - TAU, base, base + TAU] {
            let out = (dof.min - x).max(0.0) + (x - dof.max).max(0.0);
            let dist = (x - now).abs();
            if out < best.1 - 1e-12 || (out <= best.1 + 1e-12 && dist < best.2) {
                best = (x, out, dist);
            }
        }
    }
    (best.0, best.1)
}

/// Damped least squares from the current values, each step the smallest change (what a
/// chain of similar joints needs to share a bend).
fn solve_least_squares(skeleton: &Skeleton, dofs: &[usize], target: DQuat, q: &mut [f64]) {
    if dofs.is_empty() {
        return;
    }
    let mut axes = Vec::with_capacity(dofs.len());
    for _ in 0..40 {
        axes.clear();
        let mut r = DQuat::IDENTITY;
        for &d in dofs {
            let dof = &skeleton.dofs()[d];
            axes.push(r * dof.axis);
            r *= DQuat::from_axis_angle(dof.axis, q[d]);
        }
        let mut err = target * r.inverse();
        if err.w < 0.0 {
            err = -err;
        }
        let v = DVec3::new(err.x, err.y, err.z);
        let s = v.length();
        let e = if s > 0.0 {
            v * (2.0 * s.atan2(err.w) / s)
        } else {
            DVec3::ZERO
        };
        if e.length() < 1e-12 {
            break;
        }
        // δ = Jᵀ (J Jᵀ + λI)⁻¹ e, with J's columns the DOF axes (3 × n).
        let mut jjt = DMat3::from_diagonal(DVec3::splat(1e-6));
        for a in &axes {
            jjt += DMat3::from_cols(*a * a.x, *a * a.y, *a * a.z);
        }
        let y = jjt.inverse() * e;
        let mut step = 0.0f64;
        for (&d, a) in dofs.iter().zip(&axes) {
            let delta = a.dot(y);
            q[d] += delta;
            step = step.max(delta.abs());
        }
        // A target the axes cannot reach exactly (a float32 rotation for a 1-DOF joint)
        // leaves an error no step reduces: stop when the steps vanish.
        if step < 1e-12 {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vmc::bones::bone_index;
    use crate::vmc::message::{frame_bundle, read_datagram, VmcCounters};

    fn adult() -> Arc<Skeleton> {
        Arc::new(troupe_body::template::default_skeleton("adult").unwrap())
    }

    fn fk(sk: &Skeleton, q: &[f64]) -> Vec<Transform> {
        let mut g = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(sk, q, &mut g);
        g
    }

    /// A posture with every body DOF moved (deterministic), within the limits.
    fn moved(sk: &Skeleton, amplitude: f64, seed: u64) -> Vec<f64> {
        let mut draw = troupe_body::math::draws(seed);
        let mut q = vec![0.0; sk.dof_count()];
        for (d, dof) in sk.dofs().iter().enumerate() {
            let u = draw() * 2.0 - 1.0;
            q[d] = (u * amplitude).clamp(dof.min, dof.max);
        }
        q[sk.dof("root_x").unwrap()] = 0.7;
        q[sk.dof("root_z").unwrap()] = -1.2;
        q[sk.dof("root_y").unwrap()] = -0.05;
        q[sk.dof("root_yaw").unwrap()] = 2.0;
        q
    }

    #[test]
    fn the_t_pose_sends_unit_rotations_in_unitys_frame() {
        let sk = adult();
        let rig = VmcRig::new(sk.clone()).unwrap();
        let pose = rig.pose(&fk(&sk, &t_pose(&sk)));
        for (b, t) in VRM_BONES.iter().zip(&pose.bones) {
            let t = t.unwrap();
            assert!(
                t.rotation.angle_between(DQuat::IDENTITY) < 1e-9,
                "{}",
                b.name
            );
        }
        let at = |n: &str| pose.bones[bone_index(n).unwrap()].unwrap().translation;
        // The avatar's left arm points to Unity's −X, its hips stand about 1 m up, its
        // toes point forward (+Z).
        assert!(at("LeftLowerArm").x < -0.2 && at("RightLowerArm").x > 0.2);
        assert!(at("Hips").y > 0.8 && at("Hips").y < 1.1);
        assert!(at("LeftToes").z > 0.05);
        assert_eq!(pose.root.unwrap().translation.y, 0.0);
    }

    #[test]
    fn a_round_trip_puts_every_mapped_joint_within_a_centimetre() {
        let sk = adult();
        let rig = VmcRig::new(sk.clone()).unwrap();
        for seed in 1..6 {
            let q = moved(&sk, 0.5, seed);
            let g = fk(&sk, &q);
            let bytes = rosc::encoder::encode(&frame_bundle(&rig.pose(&g), 1.0)).unwrap();
            let mut counters = VmcCounters::default();
            let got = read_datagram(&bytes, &mut counters);
            assert_eq!(
                counters,
                VmcCounters {
                    packets: 1,
                    ..Default::default()
                }
            );
            let mut back = vec![0.0; sk.dof_count()];
            let mut mask = vec![false; sk.dof_count()];
            rig.retarget(&got.pose, &Transform::IDENTITY, &mut back, &mut mask);
            let g2 = fk(&sk, &back);
            let worst = VRM_BONES
                .iter()
                .map(|b| {
                    let j = sk.joint(b.joint).unwrap();
                    ((g2[j].translation - g[j].translation).length(), b.name)
                })
                .fold((0.0, ""), |a, b| if b.0 > a.0 { b } else { a });
            assert!(
                worst.0 < 0.01,
                "seed {seed}: {} off by {:.4} m",
                worst.1,
                worst.0
            );
            assert!(mask[sk.dof("r_elbow_flexion").unwrap()] && mask[sk.dof("root_x").unwrap()]);
        }
    }

    #[test]
    fn bones_not_received_keep_the_actors_posture() {
        let sk = adult();
        let rig = VmcRig::new(sk.clone()).unwrap();
        let mut pose = VmcPose::default();
        pose.bones[bone_index("RightLowerArm").unwrap()] = Some(mirror(Transform::new(
            DQuat::from_rotation_y(-0.8),
            DVec3::ZERO,
        )));
        let start = moved(&sk, 0.3, 9);
        let (mut q, mut mask) = (start.clone(), vec![false; sk.dof_count()]);
        rig.retarget(&pose, &Transform::IDENTITY, &mut q, &mut mask);
        let set: Vec<&str> = (0..q.len())
            .filter(|&d| mask[d])
            .map(|d| sk.dofs()[d].name.as_str())
            .collect();
        assert_eq!(set, ["r_elbow_flexion", "r_elbow_pronation"]);
        assert!((0..q.len()).all(|d| mask[d] || q[d] == start[d]));
    }

    /// What the scene does to an input posture: every DOF within its limits.
    fn clamp_to_limits(sk: &Skeleton, q: &mut [f64]) {
        for (v, dof) in q.iter_mut().zip(sk.dofs()) {
            *v = dof.clamp(*v);
        }
    }

    /// The rotation DOFs of `joint`.
    fn rotations(sk: &Skeleton, joint: &str) -> Vec<usize> {
        let j = sk.joint(joint).unwrap();
        sk.joints()[j]
            .dofs
            .clone()
            .filter(|&d| sk.dofs()[d].kind == DofKind::Rotation)
            .collect()
    }

    /// The angle between two rotations, precise near zero (`angle_between` takes an
    /// arccosine, which cannot tell apart rotations closer than about 1e-8 rad).
    fn angle(a: DQuat, b: DQuat) -> f64 {
        let d = a * b.inverse();
        2.0 * d.xyz().length().atan2(d.w.abs())
    }

    /// Whether `dofs` at `q` are within their limits and turn their joint by `target`.
    fn check_solved(sk: &Skeleton, dofs: &[usize], q: &[f64], target: DQuat, case: &str) {
        let deg: Vec<String> = dofs
            .iter()
            .map(|&d| format!("{} {:.2}°", sk.dofs()[d].name, q[d].to_degrees()))
            .collect();
        let off = angle(chain_rotation(sk, dofs, q), target);
        assert!(
            off < 1e-9,
            "{case}: {:.3}° off at {deg:?}",
            off.to_degrees()
        );
        for &d in dofs {
            let dof = &sk.dofs()[d];
            assert!(
                q[d] >= dof.min - 1e-9 && q[d] <= dof.max + 1e-9,
                "{case}: outside the limits at {deg:?}"
            );
        }
    }

    #[test]
    fn an_arm_brought_forward_from_the_t_pose_arrives_whatever_frame_played_between() {
        // The tester's sender: the right arm level to the side (T-pose), then forward palm
        // down (Unity's Y turned −90°). The jitter buffer plays one frame between them,
        // interpolated at some u: from the T-pose's gimbal lock (twist axis on the flexion
        // axis) the old least-squares solve could wind flexion and twist to −630°, which the
        // limits clamp; from there it reached the forward arm's other Euler angle set
        // (flexion −90°, beyond its −60° limit), clamped to a pose 30° off, for good.
        let sk = adult();
        let rig = VmcRig::new(sk.clone()).unwrap();
        let arm = bone_index("RightUpperArm").unwrap();
        let with_arm = |r: DQuat| {
            let mut pose = VmcPose::default();
            pose.bones[arm] = Some(Transform::new(r, DVec3::ZERO));
            pose
        };
        let level = with_arm(DQuat::IDENTITY);
        let forward = with_arm(DQuat::from_rotation_y(-std::f64::consts::FRAC_PI_2));
        let dofs = rotations(&sk, "r_shoulder");
        for step in 1..40 {
            let u = step as f64 / 40.0;
            let mut q = t_pose(&sk);
            let frames = [&level, &level.lerp(&forward, u), &forward, &forward];
            for pose in frames {
                let mut mask = vec![false; q.len()];
                rig.retarget(pose, &Transform::IDENTITY, &mut q, &mut mask);
                clamp_to_limits(&sk, &mut q);
            }
            let sent = rig.pose(&fk(&sk, &q)).bones[arm].unwrap().rotation;
            let deg: Vec<String> = dofs
                .iter()
                .map(|&d| format!("{:.1}°", q[d].to_degrees()))
                .collect();
            assert!(
                angle(sent, forward.bones[arm].unwrap().rotation) < 1e-9,
                "through u = {u}: the arm is off, shoulder at {deg:?}"
            );
        }
    }

    #[test]
    fn three_axis_joints_reach_every_rotation_within_their_limits_from_any_posture() {
        let sk = adult();
        for joint in ["r_shoulder", "l_shoulder", "r_hip", "vt12", "skullbase"] {
            let dofs = rotations(&sk, joint);
            assert_eq!(dofs.len(), 3, "{joint}");
            // Targets and starting postures within the limits, the starts including the
            // T-pose (the shoulders in gimbal lock) and the limits' corners.
            let mut starts = vec![t_pose(&sk)];
            for corner in 0..8 {
                let mut q = vec![0.0; sk.dof_count()];
                for (n, &d) in dofs.iter().enumerate() {
                    let dof = &sk.dofs()[d];
                    q[d] = if corner >> n & 1 == 0 {
                        dof.min
                    } else {
                        dof.max
                    };
                }
                starts.push(q);
            }
            starts.extend((0..20).map(|seed| moved(&sk, 3.2, 100 + seed)));
            for seed in 0..20 {
                let wanted = moved(&sk, 3.2, seed);
                let target = chain_rotation(&sk, &dofs, &wanted);
                for (n, start) in starts.iter().enumerate() {
                    let mut q = start.clone();
                    solve_chain(&sk, &dofs, target, &mut q);
                    check_solved(&sk, &dofs, &q, target, &format!("{joint} {seed} from {n}"));
                }
            }
        }
    }

    #[test]
    fn a_shoulder_in_gimbal_lock_splits_flexion_and_twist_within_the_limits() {
        // Abducted 90°, the shoulder's twist axis is its flexion axis: only their sum (or
        // difference) is set, and an even split from the T-pose can put the twist beyond
        // ±90°, or the flexion beyond its limits; one takes what the other cannot.
        let sk = adult();
        let dofs = rotations(&sk, "r_shoulder");
        let posture = |flexion: f64, twist: f64| {
            let mut q = vec![0.0; sk.dof_count()];
            let angles = [flexion, 90.0, twist].map(|a: f64| a.to_radians());
            for (&d, a) in dofs.iter().zip(angles) {
                q[d] = a;
            }
            q
        };
        let starts = [
            (0.0, 0.0),
            (150.0, 0.0),
            (-50.0, 0.0),
            (0.0, 80.0),
            (0.0, -80.0),
        ];
        for (flexion, twist) in [(170.0, 80.0), (170.0, -80.0), (-50.0, 85.0), (-50.0, -85.0)] {
            let target = chain_rotation(&sk, &dofs, &posture(flexion, twist));
            for (f0, t0) in starts {
                let mut q = posture(f0, t0);
                solve_chain(&sk, &dofs, target, &mut q);
                let case = format!("{flexion}° {twist}° from {f0}° {t0}°");
                check_solved(&sk, &dofs, &q, target, &case);
            }
        }
    }

    /// Near gimbal lock, a rotation changing by less than 0.5° a tick moves no DOF by 3°.
    #[test]
    fn a_noisy_sender_near_gimbal_lock_moves_every_dof_continuously() {
        // A sender in VMC's calibration pose (the T-pose: shoulders abducted 90°, in gimbal
        // lock) or lying (the root pitched 90°): its sensors' noise turns each bone by up to
        // 0.1° about any axis, while the middle angle wanders within 0.15° of 90° and the
        // others drift slowly. Just outside exact lock, the exact Euler angles' first angle
        // is the direction of that noise: flexion and twist jumped by up to 167° a tick
        // with their product right (which blending, easing or interpolating per DOF turns
        // into wrong poses), and by clamping to the limits a shoulder ended 14° off.
        let sk = adult();
        let mut draw = troupe_body::math::draws(7);
        let mut uniform = || draw() * 2.0 - 1.0;
        for joint in ["r_shoulder", "l_shoulder", "HumanoidRoot"] {
            let dofs = rotations(&sk, joint);
            let posture = |first: f64, middle: f64, last: f64| {
                let mut q = vec![0.0; sk.dof_count()];
                let angles = [first, middle, last].map(|a: f64| a.to_radians());
                for (&d, a) in dofs.iter().zip(angles) {
                    q[d] = a;
                }
                q
            };
            let mut q = posture(20.0, 90.0, 10.0);
            let mut before = chain_rotation(&sk, &dofs, &q);
            let (mut worst, mut worst_off) = (0.0f64, 0.0f64);
            for tick in 0..2000 {
                let t = tick as f64 / 100.0;
                let drift = chain_rotation(
                    &sk,
                    &dofs,
                    &posture(
                        20.0 + 5.0 * (t / 3.0).sin(),
                        90.0 + 0.15 * (t / 4.0).sin(),
                        10.0 + 5.0 * (t / 2.0).sin(),
                    ),
                );
                let axis = DVec3::new(uniform(), uniform(), uniform()).normalize_or_zero();
                let noise = DQuat::from_axis_angle(axis, 0.1f64.to_radians() * uniform());
                let target = drift * noise;
                assert!(angle(target, before) < 0.5f64.to_radians());
                before = target;
                let was = q.clone();
                solve_chain(&sk, &dofs, target, &mut q);
                clamp_to_limits(&sk, &mut q);
                worst = dofs
                    .iter()
                    .map(|&d| (q[d] - was[d]).abs())
                    .fold(worst, f64::max);
                worst_off = worst_off.max(angle(chain_rotation(&sk, &dofs, &q), target));
            }
            assert!(
                worst < 3f64.to_radians(),
                "{joint}: a DOF moved {:.1}° in a tick",
                worst.to_degrees()
            );
            assert!(
                worst_off <= NEAR_LOCK_TOLERANCE + 1e-12,
                "{joint}: {:.4}° off the target",
                worst_off.to_degrees()
            );
        }
    }
}
