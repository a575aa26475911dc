//! Helper joints: extra skinning joints at the shoulders, each turned by a fraction of
//! the shoulder's rotation, so that the skin across the shoulder follows a rotation about
//! the joint's centre instead of a straight blend of the chest's and the arm's matrices.
//!
//! Linear blend skinning averages the matrices of the joints that share a vertex; across
//! a joint bent by θ the average of "not turned" and "turned by θ" shrinks the skin
//! towards the joint and turns the inner side over well before θ reaches the joint's
//! limit. The common rigging fix is a chain of in-between joints: the band of vertices
//! shared by a parent and a child is shared instead between neighbours of the chain
//! parent → helpers → child, whose rotations differ by a fraction of θ, and blending
//! rotations that close is nearly a rotation (the shrinking goes as the cosine of half
//! their difference).
//!
//! Only the shoulders get them. A rotation about the joint's centre folds the inner side
//! of a bend of θ unless the band of weights is longer than θ times the skin's distance
//! from the centre; a straight blend, which pulls the inner side in towards the centre,
//! folds a smaller part of a band that is too short. At the shoulder (a range of 180° in
//! every direction, a band that the surface smoothing makes long) helpers turned about
//! 40 % fewer triangles over at full joint ranges; at the elbows, knees and wrists they
//! changed nothing measurable, and at the hips (flexed to 120°, the band across the groin
//! far shorter than θ times its distance from the hip) they turned more over, not fewer.
//!
//! A helper is not a joint of the skeleton: its frame is computed from the posture each
//! time the skin is deformed ([`Helper::frame`]) and written to glTF files as a node under
//! the joint's parent whose rotation is animated ([`Helper::local_rotation`]), so the CPU,
//! the viewer's GPU skinning and any glTF viewer deform the skin the same.

use crate::error::Result;
use crate::skeleton::Skeleton;
use crate::transform::Transform;
use glam::DQuat;

/// The joints given helpers, without their side prefix (see the module's note on why
/// only these).
const HELPED: [&str; 1] = ["shoulder"];

/// Fractions of its joint's rotation the helpers of one joint turn by: three evenly
/// spaced, so neighbours on the chain differ by a quarter of the bend (an arm raised by
/// 180° blends rotations 45° apart, which shrinks the skin by under 8 %; one helper at
/// half measured no better than none, seven no better than three).
pub const FRACTIONS: [f64; 3] = [0.25, 0.5, 0.75];

/// A helper joint: at `joint`'s centre, turned from `parent`'s frame by `fraction` of
/// `joint`'s rotation in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Helper {
    /// Its name in files: the joint's name and the fraction in per cent (`l_shoulder_50`).
    pub name: String,
    /// The joint it helps (index into the skeleton's joints).
    pub joint: usize,
    /// That joint's parent, whose frame the helper hangs in.
    pub parent: usize,
    /// How much of the joint's rotation it takes, in (0, 1).
    pub fraction: f64,
}

impl Helper {
    /// The helper's rotation in its parent's frame when the joint's rotation there is
    /// `joint_local`: that rotation scaled by the fraction (slerp from identity, the
    /// shorter way).
    pub fn local_rotation(&self, joint_local: DQuat) -> DQuat {
        DQuat::IDENTITY.slerp(joint_local, self.fraction)
    }

    /// The helper's frame among joint frames `globals`: at the joint's centre, turned
    /// from the parent's frame by [`Helper::local_rotation`].
    pub fn frame(&self, globals: &[Transform]) -> Transform {
        let (parent, joint) = (globals[self.parent], globals[self.joint]);
        let local = parent.rotation.inverse() * joint.rotation;
        Transform::new(
            (parent.rotation * self.local_rotation(local)).normalize(),
            joint.translation,
        )
    }
}

/// The helpers of a troupe template's skeleton: [`FRACTIONS`] at each side's shoulder,
/// ordered by joint then fraction.
pub(crate) fn helpers(skeleton: &Skeleton) -> Result<Vec<Helper>> {
    let mut out = Vec::new();
    for side in ["l_", "r_"] {
        for name in HELPED {
            let name = format!("{side}{name}");
            let joint = skeleton.joint(&name)?;
            let Some(parent) = skeleton.joints()[joint].parent else {
                continue;
            };
            for fraction in FRACTIONS {
                out.push(Helper {
                    name: format!("{name}_{:.0}", fraction * 100.0),
                    joint,
                    parent,
                    fraction,
                });
            }
        }
    }
    out.sort_by_key(|h| h.joint);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_helper_sits_at_its_joint_turned_by_its_fraction() {
        let bend = DQuat::from_rotation_x(1.2);
        let parent = Transform::new(DQuat::from_rotation_y(0.3), DVec3::new(1.0, 2.0, 3.0));
        let joint = Transform::new(parent.rotation * bend, DVec3::new(1.0, 1.5, 3.0));
        let helper = Helper {
            name: "knee_25".into(),
            joint: 1,
            parent: 0,
            fraction: 0.25,
        };
        let frame = helper.frame(&[parent, joint]);
        assert_eq!(frame.translation, joint.translation);
        let turned = parent.rotation.inverse() * frame.rotation;
        assert!(
            turned.abs_diff_eq(DQuat::from_rotation_x(0.3), 1e-12),
            "{turned:?}"
        );
    }
}
