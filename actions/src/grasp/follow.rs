//! A grasp's arms kept on their wrist goals while the body under them moves.
//!
//! A grasp plans its arm postures for the body as it stands when it starts, and moves the
//! arms there in joint space. During a walk (the grasp takes the arms at once and the walk
//! goes on, `docs/scheduling.md`), the body walks on: the same joint values then put the
//! hand where the cup was relative to the body, and the hand closed half a metre past the
//! cup. So while the body stands elsewhere on the floor than at the plan (root x, z or
//! yaw), each hand's arm is solved again every tick for its planned wrist pose, from the
//! posture of this tick, and the grasp moves towards that instead.

use super::plan::{ArmIk, HandPlan};
use crate::error::Result;
use troupe_body::Skeleton;

/// How far (m or rad) the body may have moved on the floor since the plan before the arms
/// are solved again: less is the rounding of a body standing still.
const MOVED: f64 = 1e-6;

/// The arms' targets of a grasp, kept on the plan's wrist poses as the body moves.
pub struct FollowBody {
    /// The root's x, z and yaw DOFs, and their values when the grasp planned.
    floor: Option<[(usize, f64); 3]>,
    /// Per planned hand: its arm's IK and the arm values it asks for now.
    arms: Vec<(ArmIk, Vec<(usize, f64)>)>,
    /// The posture the arms are solved from (scratch).
    q: Vec<f64>,
}

impl FollowBody {
    /// For `hands` planned from posture `q` of `skeleton`.
    pub fn new(skeleton: &Skeleton, q: &[f64], hands: &[HandPlan]) -> Result<FollowBody> {
        let dof = |name: &str| skeleton.dof(name).ok().map(|d| (d, q[d]));
        let floor = (|| Some([dof("root_x")?, dof("root_z")?, dof("root_yaw")?]))();
        let arms = hands
            .iter()
            .map(|h| Ok((ArmIk::new(skeleton, h.side, 20)?, h.arm.clone())))
            .collect::<Result<_>>()?;
        Ok(FollowBody {
            floor,
            arms,
            q: Vec::new(),
        })
    }

    /// Whether the body of posture `q` stands elsewhere on the floor than at the plan.
    pub fn moved(&self, q: &[f64]) -> bool {
        self.floor
            .is_some_and(|f| f.iter().any(|&(d, v)| (q[d] - v).abs() > MOVED))
    }

    /// The arm values hand `i` of `hands` asks for from posture `q`: the plan's while the
    /// body stands where it stood; else its arm solved for the planned wrist pose from `q`,
    /// starting from what it asked for on the last tick.
    pub fn arm<'a>(
        &'a mut self,
        skeleton: &Skeleton,
        q: &[f64],
        hands: &'a [HandPlan],
        i: usize,
    ) -> Result<&'a [(usize, f64)]> {
        if !self.moved(q) {
            return Ok(&hands[i].arm);
        }
        let (ik, target) = &mut self.arms[i];
        self.q.clear();
        self.q.extend_from_slice(q);
        for &(d, v) in target.iter() {
            self.q[d] = v;
        }
        ik.solve(skeleton, &mut self.q, &hands[i].wrist)?;
        for (d, v) in target.iter_mut() {
            *v = self.q[*d];
        }
        Ok(target)
    }
}
