//! The dynamics "Model" (per-DOF links built once from a [`Skeleton`]) and "Data"
//! (preallocated per-call workspace), plus the passes every algorithm shares:
//! kinematics, velocities, composite inertias, energy and momentum.

use super::spatial::{Force, Inertia, Motion};
use crate::error::{Error, Result};
use crate::math;
use crate::skeleton::{DofKind, Skeleton};
use crate::transform::Transform;
use glam::{DMat3, DQuat, DVec3};
use std::ops::Range;

/// Least armature (rotor inertia) of a non-root DOF, kg·m² (or kg for a translation); see
/// `docs/dynamics.md`. It keeps the DOFs of massless chains (fingers, toes, eyes)
/// well-posed.
pub const DEFAULT_ARMATURE: f64 = 1e-4;
/// Armature of a non-root DOF as a fraction of the inertia it moves at the rest posture
/// (the mass matrix's diagonal). It gives the massless links between two joints (vt12,
/// vt1, sacroiliac, …) enough inertia that their internal motions stay slow.
pub const DEFAULT_ARMATURE_FRACTION: f64 = 0.01;

/// Mass (kg) of the nominal body on a moving link that carries no solid (a finger, toe or
/// eye link, an intermediate link of a multi-DOF joint): a bead small enough not to
/// matter to the body's motion, and enough that a tool without armature (Pinocchio's
/// ABA on the exported URDF) has an inertia to divide by.
pub const NOMINAL_LINK_MASS: f64 = 1e-3;
/// Radius (m) of the nominal body: a solid sphere at the link's origin, so its inertia
/// is `2/5 · NOMINAL_LINK_MASS · NOMINAL_LINK_RADIUS²` about every axis.
pub const NOMINAL_LINK_RADIUS: f64 = 0.01;

/// The inertia (kg·m², about every axis through its centre) of the nominal body.
pub fn nominal_link_inertia() -> f64 {
    0.4 * NOMINAL_LINK_MASS * NOMINAL_LINK_RADIUS * NOMINAL_LINK_RADIUS
}

/// Per DOF, whether its link carries the nominal body: a non-root link that no solid
/// rides on (the solids of a joint ride on the link of its last DOF; those of a joint
/// without DOFs on its parent's). The exporter writes the same bodies into URDF.
pub fn nominal_links(skeleton: &Skeleton) -> Vec<bool> {
    let joints = skeleton.joints();
    let mut carrier: Vec<Option<usize>> = Vec::with_capacity(joints.len());
    for joint in joints {
        carrier.push(if joint.dofs.is_empty() {
            joint.parent.and_then(|p| carrier[p])
        } else {
            Some(joint.dofs.end - 1)
        });
    }
    let mut carries = vec![false; skeleton.dof_count()];
    for (j, _) in skeleton.solids() {
        if let Some(k) = carrier[*j] {
            carries[k] = true;
        }
    }
    let root = joints.first().map_or(0..0, |j| j.dofs.clone());
    (0..carries.len())
        .map(|k| !carries[k] && !root.contains(&k))
        .collect()
}

/// A rigid body carried by a link: the sum of the solids attached to it (or the nominal
/// body, see [`NOMINAL_LINK_MASS`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Body {
    pub link: usize,
    pub mass: f64,
    /// Centre of mass in the link's frame.
    pub com: DVec3,
    /// Inertia about the COM, link axes.
    pub inertia: DMat3,
}

/// The articulated body seen by the dynamics: one link per DOF (a joint with three DOFs is
/// a chain of three links, the last carrying the joint's solids). Immutable; build once
/// per skeleton and share.
#[derive(Clone, Debug)]
pub struct Model {
    pub(crate) n: usize,
    pub(crate) parent: Vec<Option<usize>>,
    pub(crate) kind: Vec<DofKind>,
    pub(crate) axis: Vec<DVec3>,
    /// For the first DOF of a joint: the joint's frame (before its DOFs) relative to the
    /// parent link's frame (or the world). `None` for the following DOFs of a joint.
    pub(crate) pre: Vec<Option<Transform>>,
    pub(crate) armature: Vec<f64>,
    pub(crate) bodies: Vec<Body>,
    /// Per link: whether a body rides on it (most links are massless: the first DOFs of
    /// multi-DOF joints, fingers, toes), so that the passes can skip their inertia.
    pub(crate) massive: Vec<bool>,
    /// Per joint: the link whose frame carries it, and the joint frame in that link frame.
    pub(crate) joint_link: Vec<Option<(usize, Transform)>>,
    pub(crate) root: Range<usize>,
    /// `true` for the root's DOFs.
    pub(crate) root_mask: Vec<bool>,
    pub(crate) floating: bool,
    pub(crate) total_mass: f64,
}

impl Model {
    /// Builds the model of `skeleton` with the default armature. Fails on a solid whose
    /// mass is not finite and positive or whose inertia is not finite and positive
    /// semi-definite, and on a skeleton with no mass.
    pub fn new(skeleton: &Skeleton) -> Result<Model> {
        Model::with_armature(skeleton, DEFAULT_ARMATURE, DEFAULT_ARMATURE_FRACTION)
    }

    /// Like [`Model::new`]: each non-root DOF's armature is `fraction` of the inertia it
    /// moves at the rest posture, and at least `least` (kg·m², or kg for a translation).
    /// `least` must be finite and > 0, `fraction` finite and ≥ 0.
    pub fn with_armature(skeleton: &Skeleton, least: f64, fraction: f64) -> Result<Model> {
        if !(least.is_finite() && least > 0.0) {
            return Err(Error::invalid_value(
                "armature",
                least,
                "a finite number > 0",
            ));
        }
        if !(fraction.is_finite() && fraction >= 0.0) {
            return Err(Error::invalid_value(
                "armature fraction",
                fraction,
                "a finite number ≥ 0",
            ));
        }
        let joints = skeleton.joints();
        let dofs = skeleton.dofs();
        let n = dofs.len();
        let mut parent = vec![None; n];
        let mut pre = vec![None; n];
        let mut joint_link: Vec<Option<(usize, Transform)>> = Vec::with_capacity(joints.len());
        for joint in joints {
            // The joint frame relative to the link carrying its parent joint.
            let (plink, offset_frame) = match joint.parent.and_then(|p| joint_link[p]) {
                Some((l, fixed)) => (
                    Some(l),
                    fixed.mul(&Transform::from_translation(joint.offset)),
                ),
                None => {
                    // Under the world (root, or below a DOF-less root): the parent
                    // joint's frame is fixed in the world.
                    let mut frame = Transform::from_translation(joint.offset);
                    let mut p = joint.parent;
                    while let Some(pj) = p {
                        frame = Transform::from_translation(joints[pj].offset).mul(&frame);
                        p = joints[pj].parent;
                    }
                    (None, frame)
                }
            };
            if joint.dofs.is_empty() {
                joint_link.push(plink.map(|l| (l, offset_frame)));
                continue;
            }
            for d in joint.dofs.clone() {
                if d == joint.dofs.start {
                    parent[d] = plink;
                    pre[d] = Some(offset_frame);
                } else {
                    parent[d] = Some(d - 1);
                }
            }
            joint_link.push(Some((joint.dofs.end - 1, Transform::IDENTITY)));
        }
        let root = joints[0].dofs.clone();
        let armature = vec![0.0; n];
        // Sum the solids of each link into one body.
        let mut bodies: Vec<Body> = Vec::new();
        for (j, solid) in skeleton.solids() {
            let bad_mass = !(solid.mass.is_finite() && solid.mass > 0.0);
            let i = solid.inertia;
            let bad_inertia =
                !i.is_finite() || i.x_axis.x < -1e-12 || i.y_axis.y < -1e-12 || i.z_axis.z < -1e-12;
            if bad_mass || bad_inertia {
                return Err(Error::Invalid(format!(
                    "dynamics: solid `{}` of skeleton `{}` has mass {} and inertia diagonal ({}, {}, {}): masses must be finite and > 0, inertias finite and ≥ 0",
                    solid.name, skeleton.name(), solid.mass, i.x_axis.x, i.y_axis.y, i.z_axis.z
                )));
            }
            let Some((link, fixed)) = joint_link[*j] else {
                continue; // fixed to the world: it never moves
            };
            let rot = DMat3::from_quat(fixed.rotation);
            let com = fixed.transform_point(solid.center_of_mass);
            let inertia = rot * solid.inertia * rot.transpose();
            match bodies.iter_mut().find(|b| b.link == link) {
                Some(b) => {
                    let m = b.mass + solid.mass;
                    let c = (b.com * b.mass + com * solid.mass) / m;
                    let shift = |m: f64, d: DVec3| {
                        DMat3::from_diagonal(DVec3::splat(d.length_squared())) * m
                            - DMat3::from_cols(d * d.x, d * d.y, d * d.z) * m
                    };
                    b.inertia =
                        b.inertia + shift(b.mass, b.com - c) + inertia + shift(solid.mass, com - c);
                    b.mass = m;
                    b.com = c;
                }
                None => bodies.push(Body {
                    link,
                    mass: solid.mass,
                    com,
                    inertia,
                }),
            }
        }
        if bodies.iter().map(|b| b.mass).sum::<f64>() <= 0.0 {
            return Err(Error::Invalid(format!(
                "dynamics: skeleton `{}` has no mass",
                skeleton.name()
            )));
        }
        for (link, nominal) in nominal_links(skeleton).into_iter().enumerate() {
            if nominal {
                bodies.push(Body {
                    link,
                    mass: NOMINAL_LINK_MASS,
                    com: DVec3::ZERO,
                    inertia: DMat3::from_diagonal(DVec3::splat(nominal_link_inertia())),
                });
            }
        }
        bodies.sort_by_key(|b| b.link);
        let total_mass: f64 = bodies.iter().map(|b| b.mass).sum();
        let axes = [DVec3::X, DVec3::Y, DVec3::Z];
        let floating = root.len() == 6
            && dofs[root.clone()].iter().enumerate().all(|(i, d)| {
                let (kind, axis) = match i {
                    0..=2 => (DofKind::Translation, axes[i]),
                    3 => (DofKind::Rotation, DVec3::Y),
                    4 => (DofKind::Rotation, DVec3::X),
                    _ => (DofKind::Rotation, DVec3::Z),
                };
                d.kind == kind && (d.axis - axis).length() < 1e-12
            });
        let mut model = Model {
            n,
            parent,
            kind: dofs.iter().map(|d| d.kind).collect(),
            axis: dofs.iter().map(|d| d.axis).collect(),
            pre,
            armature,
            massive: (0..n).map(|k| bodies.iter().any(|b| b.link == k)).collect(),
            bodies,
            joint_link,
            root_mask: (0..n).map(|k| root.contains(&k)).collect(),
            root,
            floating,
            total_mass,
        };
        // Armature from the inertia each DOF moves at rest.
        let mut data = Data::new(&model);
        kinematics(&model, &mut data, &vec![0.0; n], None);
        mass_diagonal(&model, &mut data, None);
        for k in 0..n {
            model.armature[k] = if model.root.contains(&k) {
                0.0
            } else {
                (fraction * data.diag[k]).max(least)
            };
        }
        Ok(model)
    }

    /// Number of DOFs.
    pub fn dof_count(&self) -> usize {
        self.n
    }

    /// The root joint's DOFs.
    pub fn root_dofs(&self) -> Range<usize> {
        self.root.clone()
    }

    /// The armature of every DOF (0 for the root's).
    pub fn armature(&self) -> &[f64] {
        &self.armature
    }

    /// Total mass in kilograms.
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// Whether the root is the humanoid free root (`root_x/y/z`, then yaw about Y, pitch
    /// about X, roll about Z), which the simulator can integrate as a floating base.
    pub fn has_free_root(&self) -> bool {
        self.floating
    }
}

/// The root of a floating base: pose and spatial velocity of the root joint's frame (the
/// frame after its six DOFs), integrated without Euler angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloatingBase {
    /// World position of the root frame.
    pub position: DVec3,
    /// World orientation of the root frame.
    pub rotation: DQuat,
    /// Spatial velocity (world coordinates, at the world origin).
    pub velocity: Motion,
}

/// Preallocated workspace for the dynamics algorithms (the "Data" of the Model/Data
/// split): no call allocates.
#[derive(Clone, Debug)]
pub struct Data {
    pub(crate) rot: Vec<DQuat>,
    pub(crate) pos: Vec<DVec3>,
    pub(crate) s: Vec<Motion>,
    pub(crate) inertia: Vec<Inertia>,
    pub(crate) v: Vec<Motion>,
    pub(crate) c: Vec<Motion>,
    pub(crate) a: Vec<Motion>,
    pub(crate) f: Vec<Force>,
    pub(crate) ia: Vec<Inertia>,
    pub(crate) pa: Vec<Force>,
    pub(crate) uu: Vec<Force>,
    pub(crate) d: Vec<f64>,
    pub(crate) u: Vec<f64>,
    pub(crate) ext: Vec<Force>,
    pub(crate) qd: Vec<f64>,
    pub(crate) qdd: Vec<f64>,
    pub(crate) diag: Vec<f64>,
    /// Per link: the external and gravity wrench on its whole subtree.
    pub(crate) w: Vec<Force>,
}

impl Data {
    /// A workspace sized for `model`.
    pub fn new(model: &Model) -> Data {
        let n = model.n;
        Data {
            rot: vec![DQuat::IDENTITY; n],
            pos: vec![DVec3::ZERO; n],
            s: vec![Motion::ZERO; n],
            inertia: vec![Inertia::ZERO; n],
            v: vec![Motion::ZERO; n],
            c: vec![Motion::ZERO; n],
            a: vec![Motion::ZERO; n],
            f: vec![Force::ZERO; n],
            ia: vec![Inertia::ZERO; n],
            pa: vec![Force::ZERO; n],
            uu: vec![Force::ZERO; n],
            d: vec![0.0; n],
            u: vec![0.0; n],
            ext: vec![Force::ZERO; n],
            qd: vec![0.0; n],
            qdd: vec![0.0; n],
            diag: vec![0.0; n],
            w: vec![Force::ZERO; n],
        }
    }
}

/// The first link the passes visit: past the root DOFs when a floating base replaces them.
#[inline]
pub(crate) fn first_link(model: &Model, base: Option<&FloatingBase>) -> usize {
    if base.is_some() {
        model.root.end
    } else {
        0
    }
}

/// Link frames, joint axes (`S`) and world inertias for posture `q`. With a floating base,
/// the root DOFs are ignored and every root link takes the base's pose.
///
/// The frames are those of [`crate::kinematics::forward_kinematics`], walked per link
/// instead of per joint, with each link's rotation renormalized (the simulator integrates
/// over thousands of steps) and the motion axes computed on the way: sharing that
/// function would change the rounding of one of the two, and both feed recordings.
pub(crate) fn kinematics(model: &Model, data: &mut Data, q: &[f64], base: Option<&FloatingBase>) {
    let start = first_link(model, base);
    if let Some(b) = base {
        for k in model.root.clone() {
            data.rot[k] = b.rotation;
            data.pos[k] = b.position;
            data.s[k] = Motion::ZERO;
        }
    }
    for k in start..model.n {
        let (mut r, mut p) = match model.parent[k] {
            Some(pk) => (data.rot[pk], data.pos[pk]),
            None => (DQuat::IDENTITY, DVec3::ZERO),
        };
        if let Some(pre) = &model.pre[k] {
            p += r * pre.translation;
            r *= pre.rotation;
        }
        let axis = r * model.axis[k];
        match model.kind[k] {
            DofKind::Rotation => {
                data.s[k] = Motion::new(axis, p.cross(axis));
                if q[k] != 0.0 {
                    r *= DQuat::from_axis_angle(model.axis[k], q[k]);
                }
            }
            DofKind::Translation => {
                data.s[k] = Motion::new(DVec3::ZERO, axis);
                p += axis * q[k];
            }
        }
        data.rot[k] = r.normalize();
        data.pos[k] = p;
    }
    for k in 0..model.n {
        data.inertia[k] = Inertia::ZERO;
    }
    for b in &model.bodies {
        let (r, p) = (data.rot[b.link], data.pos[b.link]);
        let m = DMat3::from_quat(r);
        data.inertia[b.link] = Inertia::rigid(b.mass, p + r * b.com, m * b.inertia * m.transpose());
    }
}

/// Link velocities `v` and velocity-product accelerations `c = v ×ₘ S q̇` for `qd`
/// (after [`kinematics`]).
pub(crate) fn velocities(model: &Model, data: &mut Data, qd: &[f64], base: Option<&FloatingBase>) {
    let start = first_link(model, base);
    if let Some(b) = base {
        for k in model.root.clone() {
            data.v[k] = b.velocity;
            data.c[k] = Motion::ZERO;
        }
    }
    for k in start..model.n {
        let vp = model.parent[k].map_or(Motion::ZERO, |p| data.v[p]);
        let vj = data.s[k] * qd[k];
        let v = vp + vj;
        data.c[k] = v.cross_motion(&vj);
        data.v[k] = v;
    }
}

/// The diagonal of the joint-space mass matrix (composite inertia about each DOF axis,
/// armature included) into `data.diag` (after [`kinematics`]).
pub(crate) fn mass_diagonal(model: &Model, data: &mut Data, base: Option<&FloatingBase>) {
    let start = first_link(model, base);
    for k in 0..model.n {
        data.ia[k] = data.inertia[k];
    }
    for k in (0..model.n).rev() {
        let ic = data.ia[k];
        data.diag[k] = if k >= start {
            data.s[k].dot(&ic.apply(&data.s[k])) + model.armature[k]
        } else {
            0.0
        };
        if let Some(p) = model.parent[k] {
            data.ia[p] += ic;
        }
    }
}

/// Kinetic energy (bodies and armatures), after [`velocities`].
pub(crate) fn kinetic_energy(model: &Model, data: &Data, qd: &[f64]) -> f64 {
    let mut e = 0.0;
    for b in &model.bodies {
        let v = &data.v[b.link];
        e += 0.5 * v.dot(&data.inertia[b.link].apply(v));
    }
    for k in 0..model.n {
        e += 0.5 * model.armature[k] * qd[k] * qd[k];
    }
    e
}

/// Potential energy in `gravity` (zero at the world origin), after [`kinematics`].
pub(crate) fn potential_energy(model: &Model, data: &Data, gravity: DVec3) -> f64 {
    let mut e = 0.0;
    for b in &model.bodies {
        let com = data.pos[b.link] + data.rot[b.link] * b.com;
        e -= b.mass * gravity.dot(com);
    }
    e
}

/// Total spatial momentum of the bodies about the world origin, after [`velocities`].
pub(crate) fn momentum(model: &Model, data: &Data) -> Force {
    let mut h = Force::ZERO;
    for b in &model.bodies {
        h += data.inertia[b.link].apply(&data.v[b.link]);
    }
    h
}

/// The whole body's centre of mass, after [`kinematics`].
pub(crate) fn center_of_mass(model: &Model, data: &Data) -> DVec3 {
    // The bodies' masses sum to `model.total_mass` in this order, which is positive.
    math::center_of_mass(
        model
            .bodies
            .iter()
            .map(|b| (data.pos[b.link] + data.rot[b.link] * b.com, b.mass)),
    )
}

/// Per link, the total spatial momentum of its subtree into `data.f` (after
/// [`velocities`]).
pub(crate) fn subtree_momenta(model: &Model, data: &mut Data) {
    for k in 0..model.n {
        data.f[k] = if model.massive[k] {
            data.inertia[k].apply(&data.v[k])
        } else {
            Force::ZERO
        };
    }
    for k in (0..model.n).rev() {
        if let Some(p) = model.parent[k] {
            let f = data.f[k];
            data.f[p] += f;
        }
    }
}

/// Per link, the wrench of gravity and of the external forces in `data.ext` on its
/// whole subtree into `data.w` (after [`kinematics`]).
pub(crate) fn subtree_wrenches(model: &Model, data: &mut Data, gravity: DVec3) {
    for k in 0..model.n {
        data.w[k] = data.ext[k];
    }
    for b in &model.bodies {
        let com = data.pos[b.link] + data.rot[b.link] * b.com;
        data.w[b.link] += Force::at_point(com, gravity * b.mass, DVec3::ZERO);
    }
    for k in (0..model.n).rev() {
        if let Some(p) = model.parent[k] {
            let w = data.w[k];
            data.w[p] += w;
        }
    }
}

/// Generalized momentum of DOF `k`, `p_k = ∂T/∂q̇_k = S_k·h_k + J_k q̇_k` (`h_k` the
/// subtree momentum, `J_k` the armature), after [`subtree_momenta`].
#[inline]
pub(crate) fn generalized_momentum(model: &Model, data: &Data, k: usize, qd: f64) -> f64 {
    data.s[k].dot(&data.f[k]) + model.armature[k] * qd
}

/// The rate of DOF `k`'s generalized momentum without its own joint force:
/// `ṗ_k − τ_k = S_k·W_k + Ṡ_k·h_k`, with `Ṡ_k = v_k ×ₘ S_k` (the axis moves with its
/// link), `W_k` the gravity and external wrench on the subtree and `h_k` its momentum;
/// i.e. `∂L/∂q_k` plus the external generalized force (after [`subtree_wrenches`] and
/// [`subtree_momenta`]).
#[inline]
pub(crate) fn momentum_rate(data: &Data, k: usize) -> f64 {
    let s = data.s[k];
    s.dot(&data.w[k]) + data.v[k].cross_motion(&s).dot(&data.f[k])
}
