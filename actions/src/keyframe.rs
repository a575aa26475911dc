//! The keyframe generator: plays a [`Sequence`] of Hermite tracks on a scope.

use std::sync::Arc;
use troupe_runtime::{
    DofWriter, Error, Generator, GeneratorContext, Result, Scope, Sequence, Skeleton, Step,
};

/// Plays a sequence's tracks on the DOFs they name, from the sequence's first key time.
/// Actors playing the same sequence share its keys.
pub struct Keyframe {
    sequence: Arc<Sequence>,
    /// (DOF index, track index in the sequence, evaluation cursor)
    tracks: Vec<(usize, usize, usize)>,
    start: f64,
    length: f64,
    looping: bool,
}

impl Keyframe {
    /// Binds `sequence` to `skeleton`. Tracks of DOFs outside `scope` are left out; every
    /// track must name a DOF of the skeleton. `looping` overrides the sequence's default.
    pub fn new(
        skeleton: &Skeleton,
        sequence: &Sequence,
        scope: Option<Scope>,
        looping: Option<bool>,
    ) -> Result<Keyframe> {
        Keyframe::shared(skeleton, Arc::new(sequence.clone()), scope, looping)
    }

    /// Like [`Keyframe::new`], sharing the sequence instead of copying it.
    pub fn shared(
        skeleton: &Skeleton,
        sequence: Arc<Sequence>,
        scope: Option<Scope>,
        looping: Option<bool>,
    ) -> Result<Keyframe> {
        let mut tracks = Vec::new();
        for (i, track) in sequence.tracks().iter().enumerate() {
            let dof = skeleton.dof(track.dof())?;
            if scope.is_none_or(|s| s.contains(dof)) {
                tracks.push((dof, i, 0));
            }
        }
        if tracks.is_empty() {
            return Err(Error::Invalid(format!(
                "sequence `{}` has no track on the requested scope",
                sequence.name
            )));
        }
        Ok(Keyframe {
            tracks,
            start: sequence.start(),
            length: sequence.duration(),
            looping: looping.unwrap_or(sequence.looping),
            sequence,
        })
    }

    /// The DOFs the sequence drives (the natural scope of the action).
    pub fn scope(&self) -> Scope {
        self.tracks.iter().map(|(d, _, _)| *d).collect()
    }

    /// The sequence's length in seconds.
    pub fn length(&self) -> f64 {
        self.length
    }
}

impl Generator for Keyframe {
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let mut t = ctx.local_time;
        let finished = !self.looping && t >= self.length;
        if self.looping && self.length > 0.0 {
            t = t.rem_euclid(self.length);
        }
        let t = self.start + t.min(self.length);
        let tracks = self.sequence.tracks();
        for (dof, track, cursor) in self.tracks.iter_mut() {
            out.set(*dof, tracks[*track].value_at(t, cursor));
        }
        if finished {
            Step::Finished
        } else {
            Step::Running
        }
    }
}
