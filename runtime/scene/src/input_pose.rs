//! What a device asks of an actor: the posture a performer's trackers and glove give, set
//! by the session's input phase and read by the actor's `capture` action through the
//! world, like everything else a generator reads.

use troupe_body::Scope;

/// The posture a device input asks of an actor, and which DOFs it sets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InputPose {
    /// Target DOF values (the whole actor; only those in `mask` mean anything).
    pub q: Vec<f64>,
    /// Which DOFs the latest samples set.
    pub mask: Vec<bool>,
    /// Every DOF the devices can drive: the natural scope of a `capture`.
    pub driven: Scope,
}

impl InputPose {
    /// A pose that sets nothing yet, for an actor of `dofs` DOFs whose devices can drive
    /// `driven`.
    pub fn new(dofs: usize, driven: Scope) -> Self {
        InputPose {
            q: vec![0.0; dofs],
            mask: vec![false; dofs],
            driven,
        }
    }

    /// The target of DOF `d`, when the devices set it.
    #[inline]
    pub fn target(&self, d: usize) -> Option<f64> {
        self.mask
            .get(d)
            .copied()
            .unwrap_or(false)
            .then(|| self.q.get(d).copied())
            .flatten()
    }
}
