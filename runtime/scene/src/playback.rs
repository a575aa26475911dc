//! Playing recorded objects back: a session input that puts every object where a
//! recording says it was, tick by tick (what `troupe view` of a recording uses, beside a
//! keyframe action per actor).

use crate::error::Result;
use crate::scene::Scene;
use crate::session::Input;
use troupe_body::Object;
use troupe_motion::object_motion::ObjectMotion;

/// Moves recorded objects along their recorded poses.
pub struct ObjectPlayback {
    /// Each object's scene index and motion.
    objects: Vec<(usize, ObjectMotion)>,
}

impl ObjectPlayback {
    /// Adds every object of `motions` to `scene` at its first recorded pose and returns
    /// the input that moves them; a name the scene already has, or a bad shape or mass,
    /// is an error naming it.
    pub fn install(scene: &mut Scene, motions: Vec<ObjectMotion>) -> Result<ObjectPlayback> {
        let mut objects = Vec::new();
        for motion in motions {
            let (position, rotation) = motion.pose_at(scene.time());
            let index = scene.add_object(Object {
                name: motion.name.clone(),
                shape: motion.shape,
                position,
                rotation,
                mass: motion.mass,
            })?;
            objects.push((index, motion));
        }
        Ok(ObjectPlayback { objects })
    }

    /// How many objects it moves.
    pub fn len(&self) -> usize {
        self.objects.len()
    }

    /// Whether it moves none.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }
}

impl Input for ObjectPlayback {
    fn name(&self) -> String {
        "recorded objects".into()
    }

    /// Poses every object as recorded at the scene's time after the coming step: the time
    /// whose posture the actors' replays show after that step (see
    /// `troupe_actions::keyframe::replay`), so that a held object stays in the hand and
    /// the replay is in step with the recorded run (tested in `tests/recorded_objects.rs`).
    fn poll(&mut self, scene: &mut Scene) -> Result<()> {
        let t = scene.time() + scene.dt();
        for (index, motion) in &self.objects {
            let (position, rotation) = motion.pose_at(t);
            if let Some(object) = scene.objects_mut().get_mut(*index) {
                object.position = position;
                object.rotation = rotation;
            }
        }
        Ok(())
    }
}
