//! The options of `play`: which sequence, whether it loops, on which DOFs.

use super::Keyframe;
use crate::error::{OptionError, Result};
use std::sync::Arc;
use troupe_body::{Scope, Skeleton};
use troupe_motion::Sequence;

/// The options of a keyframe action.
#[derive(Clone, Debug)]
pub struct KeyframeOptions {
    /// The sequence to play (shared between the actors that play it).
    pub sequence: Arc<Sequence>,
    /// Whether it loops; `None` keeps the sequence's own setting.
    pub looping: Option<bool>,
    /// The DOFs to play (tracks of others are left out); `None`: every track.
    pub scope: Option<Scope>,
}

impl KeyframeOptions {
    /// Plays `sequence` once through (or looping, as it says), on every DOF it names.
    pub fn new(sequence: Arc<Sequence>) -> KeyframeOptions {
        KeyframeOptions {
            sequence,
            looping: None,
            scope: None,
        }
    }

    /// Checks the options that do not depend on a body: the sequence has a track.
    pub fn validate(&self) -> Result<(), OptionError> {
        if self.sequence.tracks().is_empty() {
            return Err(no_track(&self.sequence));
        }
        Ok(())
    }

    /// The keyframe generator for `skeleton`, once the options are valid.
    pub fn keyframe(&self, skeleton: &Skeleton) -> Result<Keyframe> {
        self.validate()?;
        Keyframe::shared(skeleton, self.sequence.clone(), self.scope, self.looping)
    }
}

/// The refusal of a sequence with no track on the DOFs asked for.
pub(super) fn no_track(sequence: &Sequence) -> OptionError {
    OptionError::refused(
        "sequence",
        format!(
            "sequence `{}` has no track on the requested scope",
            sequence.name
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::default_skeleton;
    use troupe_motion::{Key, Track};

    fn wave() -> Arc<Sequence> {
        let mut seq = Sequence::new("wave");
        let keys = vec![Key::new(0.0, 0.0), Key::new(1.0, 0.5)];
        seq.add_track(Track::new("r_elbow_flexion", keys).unwrap())
            .unwrap();
        Arc::new(seq)
    }

    #[test]
    fn a_sequence_with_tracks_passes() {
        let options = KeyframeOptions::new(wave());
        options.validate().unwrap();
        let skeleton = default_skeleton("adult").unwrap();
        let keyframe = options.keyframe(&skeleton).unwrap();
        assert_eq!(keyframe.scope().len(), 1);
    }

    #[test]
    fn an_empty_sequence_is_refused_naming_it() {
        let e = KeyframeOptions::new(Arc::new(Sequence::new("empty")))
            .validate()
            .expect_err("refused");
        assert_eq!(e.option(), "sequence");
        assert!(e.to_string().contains("`empty`"), "{e}");
    }

    #[test]
    fn a_scope_without_the_tracks_is_refused() {
        let skeleton = default_skeleton("adult").unwrap();
        let options = KeyframeOptions {
            scope: Some(skeleton.scope("left_arm").unwrap()),
            ..KeyframeOptions::new(wave())
        };
        let e = options.keyframe(&skeleton).err().expect("refused");
        assert!(e.to_string().contains("no track"), "{e}");
    }
}
