//! Arms kept where they are on the body while an action moves the body under them.
//!
//! A place that leans or crouches moves the shoulders. An arm it does not place with
//! keeps its joint values unless someone solves it again, so it swings with the trunk: a
//! cup held in the other hand tipped 45° and went down to the thigh, and a free hand
//! hanging by the body went into the table the trunk leaned over. The second hand of a
//! two-handed hold, interpolated in joint space like the first, drifted off the box on
//! the way. Each tick, [`KeepArms`] solves each such arm for its wrist's pose relative to
//! an anchor joint, as it was when the action started: the root for an arm of its own
//! (so the hand stays beside the body, upright, and goes down with a crouch), the first
//! hand's wrist for the second hand of a hold (so both hands carry the object together).

use super::plan::ArmIk;
use crate::error::Result;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::sensors::Side;
use troupe_body::{Scope, Skeleton, Transform};

/// One kept arm: its IK, the joint it keeps to and its wrist's pose in that joint's frame.
struct Kept {
    ik: ArmIk,
    anchor: usize,
    relative: Transform,
}

/// Arms whose wrists keep their poses relative to another joint while the body moves.
#[derive(Default)]
pub struct KeepArms {
    arms: Vec<Kept>,
    globals: Vec<Transform>,
}

impl KeepArms {
    /// Keeps the wrist of the `side` arm at its pose relative to joint `anchor`, both as
    /// in `globals` (the posture the action starts from).
    pub fn keep(
        &mut self,
        skeleton: &Skeleton,
        side: Side,
        anchor: usize,
        globals: &[Transform],
    ) -> Result<()> {
        let ik = ArmIk::new(skeleton, side, 20)?.tracking()?;
        let relative = globals[anchor].inverse().mul(&globals[ik.wrist]);
        self.arms.push(Kept {
            ik,
            anchor,
            relative,
        });
        Ok(())
    }

    /// Keeps each arm on the body (its wrist relative to the root, as in `globals`),
    /// right then left, but the arms of `busy` and those not wholly in `scope` (another
    /// action drives them); returns the sides it kept.
    pub fn keep_free_arms(
        &mut self,
        skeleton: &Skeleton,
        scope: &Scope,
        busy: &[Side],
        globals: &[Transform],
    ) -> Result<Vec<Side>> {
        let mut kept = Vec::new();
        for side in [Side::Right, Side::Left] {
            if busy.contains(&side) {
                continue;
            }
            let arm = skeleton.scope(&format!("{}_arm", side.name()))?;
            if scope.contains_all(&arm) {
                self.keep(skeleton, side, 0, globals)?;
                kept.push(side);
            }
        }
        Ok(kept)
    }

    /// Whether it keeps no arm.
    pub fn is_empty(&self) -> bool {
        self.arms.is_empty()
    }

    /// The DOFs of the arms it keeps.
    pub fn dofs(&self) -> Scope {
        (self.arms.iter())
            .flat_map(|k| k.ik.dofs().iter().copied())
            .collect()
    }

    /// Solves each kept arm of posture `q` (the rest of it as the action wants it this
    /// tick) for its wrist's pose relative to its anchor in `q`; returns the worst
    /// distance (m) and angle (rad) left.
    pub fn apply(&mut self, skeleton: &Skeleton, q: &mut [f64]) -> Result<(f64, f64)> {
        if self.arms.is_empty() {
            return Ok((0.0, 0.0));
        }
        self.globals
            .resize(skeleton.joints().len(), Transform::IDENTITY);
        forward_kinematics(skeleton, q, &mut self.globals);
        let mut worst = (0.0f64, 0.0f64);
        for k in &mut self.arms {
            // No kept arm moves another's anchor: each arm's DOFs end at its own wrist.
            let goal = self.globals[k.anchor].mul(&k.relative);
            let (miss, angle) = k.ik.solve(skeleton, q, &goal)?;
            worst = (worst.0.max(miss), worst.1.max(angle));
        }
        Ok(worst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keep_free_arms_keeps_the_arms_in_scope_but_the_busy_ones() {
        let sk = troupe_body::template::default_skeleton("adult").unwrap();
        let q = vec![0.0; sk.dof_count()];
        let mut g = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &q, &mut g);
        let left = sk.scope("left_arm").unwrap();
        let right = sk.scope("right_arm").unwrap();
        let (all, no_left) = (sk.all(), sk.all().difference(&left));
        let (r, l) = (Side::Right, Side::Left);
        // Right then left; a busy arm and one another action drives (not in the scope)
        // are not kept.
        for (scope, busy, want) in [
            (all, vec![], vec![r, l]),
            (all, vec![r], vec![l]),
            (all, vec![r, l], vec![]),
            (no_left, vec![], vec![r]),
            (no_left, vec![r], vec![]),
        ] {
            let mut keep = KeepArms::default();
            let kept = keep.keep_free_arms(&sk, &scope, &busy, &g).unwrap();
            assert_eq!(kept, want, "busy {busy:?}");
            let dofs = keep.dofs();
            assert_eq!(dofs.overlaps(&right), want.contains(&r), "busy {busy:?}");
            assert_eq!(dofs.overlaps(&left), want.contains(&l), "busy {busy:?}");
            assert_eq!(keep.is_empty(), want.is_empty());
        }
    }
}
