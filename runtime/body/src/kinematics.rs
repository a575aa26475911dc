//! Forward kinematics: from DOF values to every joint's global (REF) transform.

use crate::math;
use crate::skeleton::{Dof, DofKind, Joint, Skeleton};
use crate::transform::Transform;
use glam::{DQuat, DVec3};

/// The local transform contributed by one DOF at `value`.
#[inline]
pub fn dof_transform(kind: DofKind, axis: DVec3, value: f64) -> Transform {
    match kind {
        DofKind::Rotation => Transform::new(DQuat::from_axis_angle(axis, value), DVec3::ZERO),
        DofKind::Translation => Transform::from_translation(axis * value),
    }
}

/// Computes the global transform of every joint for posture `q` into `globals`
/// (`globals.len()` must equal the joint count, `q.len()` the DOF count).
///
/// A joint's frame is its parent's frame, translated by the joint's offset, then moved by
/// its DOFs in order: `G_j = G_parent · T(offset) · D_1(q_1) · D_2(q_2) · …`.
pub fn forward_kinematics(skeleton: &Skeleton, q: &[f64], globals: &mut [Transform]) {
    debug_assert_eq!(globals.len(), skeleton.joints().len());
    debug_assert_eq!(q.len(), skeleton.dof_count());
    let dofs = skeleton.dofs();
    for (j, joint) in skeleton.joints().iter().enumerate() {
        globals[j] = frame_of(joint, dofs, joint.parent.map(|p| &globals[p]), q);
    }
}

/// The global transform of joint `j` for posture `q`, given its parent's (`None` for a
/// root): what [`forward_kinematics`] computes for it, to the bit, for a chain of joints
/// placed alone.
pub fn joint_frame(
    skeleton: &Skeleton,
    j: usize,
    parent: Option<&Transform>,
    q: &[f64],
) -> Transform {
    frame_of(&skeleton.joints()[j], skeleton.dofs(), parent, q)
}

/// `joint`'s global transform for posture `q` (its skeleton's DOFs `dofs`), given its
/// parent's.
#[inline(always)]
fn frame_of(joint: &Joint, dofs: &[Dof], parent: Option<&Transform>, q: &[f64]) -> Transform {
    let mut frame = match parent {
        Some(parent) => Transform::new(
            parent.rotation,
            parent.translation + parent.rotation * joint.offset,
        ),
        None => Transform::from_translation(joint.offset),
    };
    for d in joint.dofs.clone() {
        // Many DOFs (fingers, eyes) sit at zero: their transform is the identity.
        if q[d] != 0.0 {
            // Compose in place: a rotation DOF only turns the frame, a translation only
            // moves it (cheaper than a full transform product).
            let dof = &dofs[d];
            match dof.kind {
                DofKind::Rotation => frame.rotation *= DQuat::from_axis_angle(dof.axis, q[d]),
                DofKind::Translation => {
                    frame.translation += frame.rotation * (dof.axis * q[d]);
                }
            }
        }
    }
    frame
}

/// The local transform of joint `j` relative to its parent for posture `q`.
pub fn local_transform(skeleton: &Skeleton, j: usize, q: &[f64]) -> Transform {
    let joint = &skeleton.joints()[j];
    let mut frame = Transform::from_translation(joint.offset);
    for d in joint.dofs.clone() {
        let dof = &skeleton.dofs()[d];
        frame = frame.mul(&dof_transform(dof.kind, dof.axis, q[d]));
    }
    frame
}

/// The world position of the whole body's centre of mass for the given joint globals.
pub fn center_of_mass(skeleton: &Skeleton, globals: &[Transform]) -> DVec3 {
    math::center_of_mass(skeleton.solids().iter().map(|(j, solid)| {
        (
            globals[*j].transform_point(solid.center_of_mass),
            solid.mass,
        )
    }))
}

/// Sets the rotation DOFs of `joint` in `q` so that their product comes closest to
/// `target` (Gauss–Newton on the rotation error, from the current values).
pub fn solve_joint_angles(skeleton: &Skeleton, joint: usize, target: DQuat, q: &mut [f64]) {
    let dofs: Vec<usize> = skeleton.joints()[joint]
        .dofs
        .clone()
        .filter(|&d| skeleton.dofs()[d].kind == DofKind::Rotation)
        .collect();
    if dofs.is_empty() {
        return;
    }
    for _ in 0..30 {
        // Rotation so far and the axis of each DOF in the joint's parent-side frame.
        let mut r = DQuat::IDENTITY;
        let mut axes = Vec::with_capacity(dofs.len());
        for &d in &dofs {
            let dof = &skeleton.dofs()[d];
            axes.push(r * dof.axis);
            r *= DQuat::from_axis_angle(dof.axis, q[d]);
        }
        let mut err_q = target * r.inverse();
        if err_q.w < 0.0 {
            err_q = -err_q;
        }
        // 2·atan2(|v|, w) keeps full precision for small angles (acos(w) does not).
        let v = DVec3::new(err_q.x, err_q.y, err_q.z);
        let sin_half = v.length();
        let e = if sin_half > 0.0 {
            v * (2.0 * sin_half.atan2(err_q.w) / sin_half)
        } else {
            DVec3::ZERO
        };
        if e.length() < 1e-12 {
            break;
        }
        // Normal equations (JᵀJ + λI) δ = Jᵀe; at most 3 unknowns.
        let k = axes.len();
        let mut m = [[0.0f64; 4]; 3];
        for i in 0..k {
            for j in 0..k {
                m[i][j] = axes[i].dot(axes[j]) + if i == j { 1e-9 } else { 0.0 };
            }
            m[i][3] = axes[i].dot(e);
        }
        let delta = gauss_jordan(&mut m, k);
        for (i, &d) in dofs.iter().enumerate() {
            q[d] += delta[i];
        }
    }
}

/// Gauss–Jordan elimination with partial pivoting on a k×k system (k ≤ 3) stored as rows
/// `[a0, a1, a2, b]`; an unknown whose pivot vanishes is left at 0.
///
/// Not [`math::solve_small`]: that one eliminates below the pivot and substitutes back,
/// which rounds differently (about 2 % of solves from random postures end a bit apart),
/// and the angles solved here become postures (performers' trackers, glTF import,
/// retargeting), so switching would change what those record.
fn gauss_jordan(m: &mut [[f64; 4]; 3], k: usize) -> [f64; 3] {
    for col in 0..k {
        let pivot = (col..k)
            .max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))
            .unwrap_or(col);
        m.swap(col, pivot);
        let p = m[col][col];
        if p.abs() < 1e-15 {
            continue;
        }
        let pivot_row = m[col];
        for (row, r) in m.iter_mut().enumerate().take(k) {
            if row != col {
                let f = r[col] / p;
                for (x, y) in r.iter_mut().zip(pivot_row.iter()).skip(col) {
                    *x -= f * y;
                }
            }
        }
    }
    let mut x = [0.0; 3];
    for i in 0..k {
        if m[i][i].abs() >= 1e-15 {
            x[i] = m[i][3] / m[i][i];
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::template::{template, TemplateParams};
    use std::f64::consts::FRAC_PI_2;

    fn adult(height: f64) -> Skeleton {
        template("adult")
            .unwrap()
            .instantiate(TemplateParams { height, mass: 70.0 })
            .unwrap()
    }

    fn fk(s: &Skeleton, q: &[f64]) -> Vec<Transform> {
        let mut g = vec![Transform::IDENTITY; s.joints().len()];
        forward_kinematics(s, q, &mut g);
        g
    }

    fn pos(s: &Skeleton, g: &[Transform], joint: &str) -> DVec3 {
        g[s.joint(joint).unwrap()].translation
    }

    fn assert_close(a: DVec3, b: DVec3) {
        assert!((a - b).length() < 1e-9, "{a} != {b}");
    }

    #[test]
    fn a_chain_placed_alone_has_the_frames_of_the_whole_body_to_the_bit() {
        let s = adult(1.75);
        let q: Vec<f64> = (0..s.dof_count())
            .map(|d| 0.1 * ((d % 7) as f64 - 3.0))
            .collect();
        let g = fk(&s, &q);
        let mut chain = vec![s.joint("l_wrist").unwrap()];
        while let Some(p) = s.joints()[*chain.last().unwrap()].parent {
            chain.push(p);
        }
        let mut parent: Option<Transform> = None;
        for &j in chain.iter().rev() {
            let frame = joint_frame(&s, j, parent.as_ref(), &q);
            assert_eq!(frame, g[j], "{}", s.joints()[j].name);
            parent = Some(frame);
        }
    }

    #[test]
    fn rest_pose_matches_the_proportions() {
        let s = adult(1.75);
        let g = fk(&s, &vec![0.0; s.dof_count()]);
        assert!((pos(&s, &g, "l_knee").y - 0.285 * 1.75).abs() < 1e-12);
        assert!(pos(&s, &g, "l_hip").x > 0.0, "left is +X");
        assert_close(
            pos(&s, &g, "r_hip"),
            pos(&s, &g, "l_hip") * DVec3::new(-1.0, 1.0, 1.0),
        );
        let upper_arm = (pos(&s, &g, "l_shoulder") - pos(&s, &g, "l_elbow")).length();
        assert!((upper_arm - 0.186 * 1.75).abs() < 1e-12);
    }

    #[test]
    fn elbow_flexion_by_a_right_angle_points_the_forearm_forward() {
        let s = adult(1.75);
        let mut q = vec![0.0; s.dof_count()];
        for side in ["l", "r"] {
            q[s.dof(&format!("{side}_elbow_flexion")).unwrap()] = FRAC_PI_2;
        }
        let g = fk(&s, &q);
        let forearm = 0.146 * 1.75;
        for side in ["l", "r"] {
            let elbow = pos(&s, &g, &format!("{side}_elbow"));
            let wrist = pos(&s, &g, &format!("{side}_wrist"));
            assert_close(wrist, elbow + DVec3::new(0.0, 0.0, forearm));
        }
    }

    #[test]
    fn root_places_and_turns_the_actor() {
        let s = adult(1.75);
        let mut q = vec![0.0; s.dof_count()];
        q[s.dof("root_x").unwrap()] = 2.0;
        q[s.dof("root_z").unwrap()] = -1.0;
        q[s.dof("root_yaw").unwrap()] = FRAC_PI_2; // face +X
        let rest = fk(&s, &vec![0.0; s.dof_count()]);
        let g = fk(&s, &q);
        // A quarter turn about Y maps the rest-pose left hip (+X) to -Z.
        let l_hip = pos(&s, &rest, "l_hip");
        let expected = DVec3::new(2.0, l_hip.y, -1.0 - l_hip.x);
        assert_close(pos(&s, &g, "l_hip"), expected);
        // Knee flexion with the hip flexed 90°: the shank hangs straight down again.
        q[s.dof("l_hip_flexion").unwrap()] = FRAC_PI_2;
        q[s.dof("l_knee_flexion").unwrap()] = FRAC_PI_2;
        let g = fk(&s, &q);
        let knee = pos(&s, &g, "l_knee");
        let ankle = pos(&s, &g, "l_ankle");
        assert_close(ankle - knee, DVec3::new(0.0, -(0.285 - 0.039) * 1.75, 0.0));
    }

    #[test]
    fn scaling_scales_segment_lengths() {
        let (a, b) = (adult(1.5), adult(1.8));
        let ga = fk(&a, &vec![0.0; a.dof_count()]);
        let gb = fk(&b, &vec![0.0; b.dof_count()]);
        for (from, to) in [
            ("l_hip", "l_knee"),
            ("r_shoulder", "r_wrist"),
            ("vl5", "skullbase"),
            ("r_index1", "r_index3"),
        ] {
            let la = (pos(&a, &ga, from) - pos(&a, &ga, to)).length();
            let lb = (pos(&b, &gb, from) - pos(&b, &gb, to)).length();
            assert!((lb / la - 1.8 / 1.5).abs() < 1e-12, "{from}-{to}");
        }
    }

    #[test]
    fn standing_center_of_mass_is_between_the_feet() {
        let s = adult(1.75);
        let g = fk(&s, &vec![0.0; s.dof_count()]);
        let com = center_of_mass(&s, &g);
        assert!(com.x.abs() < 1e-9);
        // Humans stand with the COM at about 55 % of their height.
        assert!((0.50..0.62).contains(&(com.y / 1.75)), "{}", com.y / 1.75);
    }
    #[test]
    fn joint_angles_are_recovered_from_rotations() {
        let skel = crate::template::default_skeleton("adult").unwrap();
        for joint in ["r_shoulder", "l_hip", "vt12", "r_thumb1", "r_elbow"] {
            let j = skel.joint(joint).unwrap();
            let mut q = vec![0.0; skel.dof_count()];
            for (i, d) in skel.joints()[j].dofs.clone().enumerate() {
                q[d] = 0.3 - 0.25 * i as f64;
            }
            let target = local_transform(&skel, j, &q).rotation;
            let mut solved = vec![0.0; skel.dof_count()];
            solve_joint_angles(&skel, j, target, &mut solved);
            for d in skel.joints()[j].dofs.clone() {
                assert!(
                    (solved[d] - q[d]).abs() < 1e-9,
                    "{joint}: {} vs {}",
                    solved[d],
                    q[d]
                );
            }
        }
    }
}
