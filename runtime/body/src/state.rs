//! Per-actor mutable state in flat arrays indexed by DOF or joint (the "Data" of the
//! Model/Data split).

use crate::kinematics::forward_kinematics;
use crate::skeleton::Skeleton;
use crate::transform::Transform;

/// One actor's posture at the end of a tick.
#[derive(Clone, Debug, PartialEq)]
pub struct ActorState {
    /// DOF values (radians or metres).
    pub q: Vec<f64>,
    /// DOF velocities over the last tick.
    pub qd: Vec<f64>,
    /// The value each DOF falls back to when no action fully drives it (see
    /// the scene's blend rule).
    pub held: Vec<f64>,
    /// Global transform of every joint (the REF frames), from forward kinematics.
    pub globals: Vec<Transform>,
}

impl ActorState {
    /// The state of `skeleton` at posture `q`, at rest, with its kinematics computed.
    pub fn new(skeleton: &Skeleton, q: Vec<f64>) -> Self {
        let n = skeleton.dof_count();
        debug_assert_eq!(q.len(), n);
        let mut state = ActorState {
            held: q.clone(),
            q,
            qd: vec![0.0; n],
            globals: vec![Transform::IDENTITY; skeleton.joints().len()],
        };
        state.update_kinematics(skeleton);
        state
    }

    /// Recomputes the joint globals from `q`.
    pub fn update_kinematics(&mut self, skeleton: &Skeleton) {
        forward_kinematics(skeleton, &self.q, &mut self.globals);
    }
}
