//! Analytic Jacobians (thesis 2.3): how an end effector's position and orientation move
//! with each DOF of a set (a scope, or the chain from a root joint to the effector).
//!
//! A rotation DOF `d` with world axis `w` through the point `o` moves a point `p` of a
//! descendant segment at `w × (p − o)` and turns it at `w`; a translation DOF moves it at
//! `w` and does not turn it. DOFs that are not ancestors of the effector give zero
//! columns.

use crate::error::{Error, Result};
use crate::kinematics::{dof_transform, forward_kinematics};
use crate::linalg::Mat;
use crate::scope::Scope;
use crate::skeleton::{DofKind, Skeleton};
use crate::transform::Transform;
use glam::{DQuat, DVec3};

/// A point rigidly attached to a joint's frame: what IK moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effector {
    /// The joint that carries the point.
    pub joint: usize,
    /// The point in that joint's frame.
    pub point: DVec3,
}

impl Effector {
    /// The joint's origin as effector.
    pub fn at_joint(joint: usize) -> Effector {
        Effector {
            joint,
            point: DVec3::ZERO,
        }
    }

    /// The effector's world position for the joint globals `globals`.
    #[inline]
    pub fn position(&self, globals: &[Transform]) -> DVec3 {
        globals[self.joint].transform_point(self.point)
    }

    /// The effector's world orientation (its joint's frame).
    #[inline]
    pub fn rotation(&self, globals: &[Transform]) -> DQuat {
        globals[self.joint].rotation
    }
}

/// One DOF's motion axis in world coordinates for the current posture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DofAxis {
    /// A point on the axis (the joint's origin).
    pub origin: DVec3,
    /// The unit axis.
    pub axis: DVec3,
    /// Rotation or translation.
    pub kind: DofKind,
}

/// Computes the world axis of every DOF in `dofs` into `out` (cleared first), for posture
/// `q` whose joint globals are `globals`.
pub fn dof_axes(
    skeleton: &Skeleton,
    q: &[f64],
    globals: &[Transform],
    dofs: &[usize],
    out: &mut Vec<DofAxis>,
) {
    out.clear();
    let all = skeleton.dofs();
    let joints = skeleton.joints();
    for &d in dofs {
        let dof = &all[d];
        let joint = &joints[dof.joint];
        let mut frame = match joint.parent {
            Some(p) => {
                let g = globals[p];
                Transform::new(g.rotation, g.translation + g.rotation * joint.offset)
            }
            None => Transform::from_translation(joint.offset),
        };
        for e in joint.dofs.start..d {
            if q[e] != 0.0 {
                let de = &all[e];
                frame = frame.mul(&dof_transform(de.kind, de.axis, q[e]));
            }
        }
        out.push(DofAxis {
            origin: frame.translation,
            axis: frame.rotation * dof.axis,
            kind: dof.kind,
        });
    }
}

/// The DOFs of the joints that move `joint` (its ancestors and itself), as a scope.
pub fn ancestor_dofs(skeleton: &Skeleton, joint: usize) -> Scope {
    let joints = skeleton.joints();
    let mut scope = Scope::EMPTY;
    let mut j = Some(joint);
    while let Some(i) = j {
        for d in joints[i].dofs.clone() {
            scope.insert(d);
        }
        j = joints[i].parent;
    }
    scope
}

/// The DOFs of the chain from joint `root` down to joint `tip` (both included), in index
/// order. An error if `root` is not an ancestor of (or equal to) `tip`.
pub fn chain_dofs(skeleton: &Skeleton, root: usize, tip: usize) -> Result<Vec<usize>> {
    let joints = skeleton.joints();
    if root >= joints.len() || tip >= joints.len() {
        return Err(Error::Invalid(format!(
            "chain {root}→{tip}: no such joint in `{}`",
            skeleton.name()
        )));
    }
    let mut path = Vec::new();
    let mut j = Some(tip);
    while let Some(i) = j {
        path.push(i);
        if i == root {
            let mut dofs: Vec<usize> = path.iter().flat_map(|&k| joints[k].dofs.clone()).collect();
            dofs.sort_unstable();
            return Ok(dofs);
        }
        j = joints[i].parent;
    }
    Err(Error::Invalid(format!(
        "joint `{}` is not an ancestor of `{}`",
        joints[root].name, joints[tip].name
    )))
}

/// The DOFs of `scope` that move `joint` (in index order): the useful columns of its
/// Jacobian.
pub fn scope_dofs_moving(skeleton: &Skeleton, scope: &Scope, joint: usize) -> Vec<usize> {
    ancestor_dofs(skeleton, joint)
        .intersection(scope)
        .iter()
        .collect()
}

/// Writes the Jacobian rows of `effector` into `out` starting at row `first_row`: three
/// position rows, then (when `orientation`) three angular-velocity rows. Column `c` is
/// DOF `dofs[c]`, whose world axis is `axes[c]` (from [`dof_axes`]). `out` must be large
/// enough.
#[allow(clippy::too_many_arguments)]
pub fn fill_jacobian(
    skeleton: &Skeleton,
    globals: &[Transform],
    dofs: &[usize],
    axes: &[DofAxis],
    effector: &Effector,
    orientation: bool,
    out: &mut Mat,
    first_row: usize,
) {
    let moving = ancestor_dofs(skeleton, effector.joint);
    let p = effector.position(globals);
    for (c, (&d, a)) in dofs.iter().zip(axes).enumerate() {
        let (lin, ang) = if !moving.contains(d) {
            (DVec3::ZERO, DVec3::ZERO)
        } else {
            match a.kind {
                DofKind::Rotation => (a.axis.cross(p - a.origin), a.axis),
                DofKind::Translation => (a.axis, DVec3::ZERO),
            }
        };
        out.set(first_row, c, lin.x);
        out.set(first_row + 1, c, lin.y);
        out.set(first_row + 2, c, lin.z);
        if orientation {
            out.set(first_row + 3, c, ang.x);
            out.set(first_row + 4, c, ang.y);
            out.set(first_row + 5, c, ang.z);
        }
    }
}

/// The Jacobian (3 × n, or 6 × n with `orientation`) of `effector` with respect to
/// `dofs` at posture `q` — a convenience that allocates; solvers use [`fill_jacobian`].
pub fn jacobian(
    skeleton: &Skeleton,
    q: &[f64],
    dofs: &[usize],
    effector: &Effector,
    orientation: bool,
) -> Result<Mat> {
    if q.len() != skeleton.dof_count() {
        return Err(Error::Invalid(format!(
            "jacobian: posture has {} values, the skeleton {} DOFs",
            q.len(),
            skeleton.dof_count()
        )));
    }
    if effector.joint >= skeleton.joints().len() {
        return Err(Error::Invalid(format!(
            "jacobian: no joint {} in `{}`",
            effector.joint,
            skeleton.name()
        )));
    }
    if let Some(&d) = dofs.iter().find(|&&d| d >= skeleton.dof_count()) {
        return Err(Error::Invalid(format!(
            "jacobian: no DOF {d} in `{}`",
            skeleton.name()
        )));
    }
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, q, &mut globals);
    let mut axes = Vec::with_capacity(dofs.len());
    dof_axes(skeleton, q, &globals, dofs, &mut axes);
    let mut j = Mat::zeros(if orientation { 6 } else { 3 }, dofs.len());
    fill_jacobian(
        skeleton,
        &globals,
        dofs,
        &axes,
        effector,
        orientation,
        &mut j,
        0,
    );
    Ok(j)
}

/// The rotation vector (axis × angle, world frame, angle in [0, π]) that turns `from`
/// into `to`: the orientation error of a goal.
pub fn rotation_error(from: DQuat, to: DQuat) -> DVec3 {
    let mut d = to * from.inverse();
    if d.w < 0.0 {
        d = -d;
    }
    let v = DVec3::new(d.x, d.y, d.z);
    let s = v.length();
    if s < 1e-300 {
        return DVec3::ZERO;
    }
    let angle = 2.0 * s.atan2(d.w);
    v * (angle / s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adult() -> Skeleton {
        crate::template::default_skeleton("adult").unwrap()
    }

    fn random_posture(s: &Skeleton, draw: &mut impl FnMut() -> f64) -> Vec<f64> {
        s.dofs()
            .iter()
            .map(|d| {
                let u = draw();
                let (lo, hi) = if d.min.is_finite() {
                    (d.min, d.max)
                } else {
                    (-1.0, 1.0)
                };
                lo + (hi - lo) * u
            })
            .collect()
    }

    fn pose(s: &Skeleton, q: &[f64], e: &Effector) -> (DVec3, DQuat) {
        let mut g = vec![Transform::IDENTITY; s.joints().len()];
        forward_kinematics(s, q, &mut g);
        (e.position(&g), e.rotation(&g))
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let s = adult();
        let mut draw = crate::math::draws(11);
        let cases = [
            (
                "r_wrist",
                DVec3::new(0.0, -0.07, 0.005),
                "right_arm+spine+global",
            ),
            ("l_wrist", DVec3::ZERO, "left_arm"),
            ("skullbase", DVec3::new(0.0, 0.1, 0.05), "spine+neck+head"),
            (
                "l_metatarsal",
                DVec3::new(0.01, 0.0, 0.03),
                "left_leg+pelvis+global",
            ),
            ("r_index3", DVec3::ZERO, "right_arm+right_hand"),
        ];
        for _ in 0..20 {
            let q = random_posture(&s, &mut draw);
            for (joint, point, scope) in cases {
                let e = Effector {
                    joint: s.joint(joint).unwrap(),
                    point,
                };
                let dofs: Vec<usize> = s.scope(scope).unwrap().iter().collect();
                let j = jacobian(&s, &q, &dofs, &e, true).unwrap();
                let h = 1e-6;
                for (c, &d) in dofs.iter().enumerate() {
                    let mut qp = q.clone();
                    let mut qm = q.clone();
                    qp[d] += h;
                    qm[d] -= h;
                    let (pp, rp) = pose(&s, &qp, &e);
                    let (pm, rm) = pose(&s, &qm, &e);
                    let lin = (pp - pm) / (2.0 * h);
                    let ang = rotation_error(rm, rp) / (2.0 * h);
                    let analytic_lin = DVec3::new(j.get(0, c), j.get(1, c), j.get(2, c));
                    let analytic_ang = DVec3::new(j.get(3, c), j.get(4, c), j.get(5, c));
                    assert!(
                        (lin - analytic_lin).length() < 1e-7,
                        "{joint} / {}: {lin} vs {analytic_lin}",
                        s.dofs()[d].name
                    );
                    assert!(
                        (ang - analytic_ang).length() < 1e-7,
                        "{joint} / {}: {ang} vs {analytic_ang}",
                        s.dofs()[d].name
                    );
                }
            }
        }
    }

    #[test]
    fn chains_and_scopes_pick_the_moving_dofs() {
        let s = adult();
        let shoulder = s.joint("r_shoulder").unwrap();
        let wrist = s.joint("r_wrist").unwrap();
        let chain = chain_dofs(&s, shoulder, wrist).unwrap();
        let names: Vec<&str> = chain.iter().map(|&d| s.dofs()[d].name.as_str()).collect();
        assert_eq!(
            names,
            [
                "r_shoulder_flexion",
                "r_shoulder_abduction",
                "r_shoulder_twist",
                "r_elbow_flexion",
                "r_elbow_pronation",
                "r_wrist_flexion",
                "r_wrist_deviation"
            ]
        );
        assert!(chain_dofs(&s, wrist, shoulder).is_err());
        let moving = scope_dofs_moving(&s, &s.scope("arms+spine").unwrap(), wrist);
        assert_eq!(moving.len(), 9 + 12);
        // Columns of DOFs that do not move the effector are zero.
        let dofs: Vec<usize> = s.scope("left_arm").unwrap().iter().collect();
        let q = vec![0.0; s.dof_count()];
        let j = jacobian(&s, &q, &dofs, &Effector::at_joint(wrist), false).unwrap();
        assert!((0..3).all(|r| (0..dofs.len()).all(|c| j.get(r, c) == 0.0)));
    }

    #[test]
    fn bad_inputs_are_errors() {
        let s = adult();
        let q = vec![0.0; s.dof_count()];
        assert!(jacobian(&s, &q[..3], &[0], &Effector::at_joint(1), false).is_err());
        assert!(jacobian(&s, &q, &[0], &Effector::at_joint(10_000), false).is_err());
        assert!(jacobian(&s, &q, &[10_000], &Effector::at_joint(1), false).is_err());
    }

    #[test]
    fn rotation_error_is_the_rotation_vector() {
        let a = DQuat::from_rotation_y(0.3);
        let b = DQuat::from_rotation_y(0.3) * DQuat::from_rotation_x(0.2);
        let e = rotation_error(a, b);
        assert!((e.length() - 0.2).abs() < 1e-12);
        assert!(rotation_error(a, -a).length() < 1e-12);
    }
}
