//! Feet that stay on troupe's feet: a character's legs are bent by two-bone inverse
//! kinematics so that its ankle rides with troupe's foot joint.
//!
//! A character keeps its own proportions (CesiumMan at 1.75 m has 62 cm from hip to
//! ankle against troupe's 87 cm, and its hips stand 21 cm lower), so the same joint
//! rotations put its foot elsewhere: turned about other hips, a shorter leg sweeps a
//! shorter arc, and the foot that troupe plants for a step slides under the character.
//! Over the leg postures of a stride (hip −20° to 40°, knee 0° to 60°) CesiumMan's ankle
//! strayed up to 19 cm from the point of troupe's foot it stands on at rest, and 33 cm
//! between two postures. Retargeting systems correct this the same way, with an analytic
//! two-bone solve per leg after the rotations are copied (ozz-animation's
//! `IKTwoBoneJob`, Unity's humanoid foot IK): the knee bends until hip-to-ankle is as far
//! as the goal, then the thigh swings the ankle onto it. Where the goal is beyond the
//! leg's length the leg points at it, straight (CesiumMan: at most 3 cm short in a
//! stride). The foot keeps troupe's rotation, so a planted foot stays flat.

use crate::transform::Transform;
use glam::{DQuat, DVec3};

/// One leg of a character: its bones, troupe's joints, and where its ankle sits on
/// troupe's foot.
#[derive(Clone, Debug)]
pub(super) struct Leg {
    /// The thigh bone (mapped to troupe's hip).
    pub thigh: usize,
    /// The shank bone (mapped to troupe's knee).
    pub shin: usize,
    /// The foot bone (mapped to troupe's ankle or subtalar joint).
    pub foot: usize,
    /// Troupe's knee joint (its flexion axis is the bend's).
    pub knee_joint: usize,
    /// Troupe's foot joint that the ankle rides with.
    pub foot_joint: usize,
    /// The foot bone's origin in troupe's foot joint frame, in troupe's rest posture.
    pub in_foot: DVec3,
}

impl Leg {
    /// The world rotations to add to the thigh and the shank, posed as `frames` (bones)
    /// for troupe's joint frames `globals` (whose rest frames are `rest`), so that the
    /// ankle reaches its goal on troupe's foot, or comes as near as the leg's length
    /// allows (straight, pointing at it).
    pub fn reach(
        &self,
        frames: &[Transform],
        globals: &[Transform],
        rest: &[Transform],
    ) -> [(usize, DQuat); 2] {
        let (knee, foot) = (self.knee_joint, self.foot_joint);
        let goal = globals[foot].transform_point(self.in_foot);
        let (h, k, a) = (
            frames[self.thigh].translation,
            frames[self.shin].translation,
            frames[self.foot].translation,
        );
        let (thigh, shank) = ((k - h).length(), (a - k).length());
        if thigh * shank < 1e-12 {
            return [(self.thigh, DQuat::IDENTITY), (self.shin, DQuat::IDENTITY)];
        }
        // The knee's inner angle for a hip-to-ankle distance (law of cosines); the goal's
        // distance is kept within what the two bones can span.
        let inner = |span: f64| {
            ((thigh * thigh + shank * shank - span * span) / (2.0 * thigh * shank))
                .clamp(-1.0, 1.0)
                .acos()
        };
        let span = (goal - h)
            .length()
            .clamp((thigh - shank).abs(), thigh + shank);
        // The knee bends about troupe's knee axis (its flexion axis, left-right at rest,
        // turned with the thigh), which bends it forwards whatever the character's bind
        // pose; or, once it is clearly bent the same way, in the leg's own plane, where
        // the law of cosines is exact.
        let hinge = globals[knee].rotation * rest[knee].rotation.inverse() * DVec3::X;
        let own = (k - h).cross(a - k);
        let clearly_bent = own.length() > thigh * shank * 10f64.to_radians().sin();
        let axis = match own.try_normalize() {
            Some(n) if clearly_bent && n.dot(hinge) > 0.0 => n,
            _ => hinge,
        };
        let bend = DQuat::from_axis_angle(axis, inner((a - h).length()) - inner(span));
        let bent_ankle = k + bend * (a - k);
        let swing = match ((bent_ankle - h).try_normalize(), (goal - h).try_normalize()) {
            (Some(from), Some(to)) => DQuat::from_rotation_arc(from, to),
            _ => DQuat::IDENTITY,
        };
        [(self.thigh, swing), (self.shin, swing * bend)]
    }
}
