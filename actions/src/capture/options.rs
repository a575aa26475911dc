//! The options of `capture`, without Lua.

use super::{Capture, GloveHand};
use crate::error::{ActionError, Result};
use troupe_body::sensors::HandSensors;
use troupe_body::Scope;
use troupe_scene::Scene;

/// The options of a capture: which of the device-driven DOFs to follow.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CaptureOptions {
    /// The DOFs to follow; every DOF the devices drive when `None`.
    pub scope: Option<Scope>,
}

impl CaptureOptions {
    /// Makes `actor`'s capture and the DOFs it drives. The actor must be driven by a device
    /// (a performer: the scene has an input pose for it); when the scope covers the
    /// fingers of its device-driven hand, the grasping automaton runs on them.
    pub fn capture(&self, scene: &Scene, actor: usize) -> Result<(Capture, Scope)> {
        let pose = scene.input_pose(actor).ok_or_else(|| {
            ActionError::Unfit(
                "this actor is not a performer (create it with troupe.performer)".into(),
            )
        })?;
        let scope = self.scope.unwrap_or(pose.driven);
        let skeleton = &scene.actors()[actor].skeleton;
        let hand = match scene.blackboard().device_hand(actor) {
            Some(side) => {
                let fingers = HandSensors::new(skeleton, side)?.scope;
                (!scope.intersection(&fingers).is_empty()).then(|| GloveHand::new(side))
            }
            None => None,
        };
        Ok((Capture::new(hand), scope))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::sensors::Side;
    use troupe_scene::{ActionSpec, ActorDesc, InputPose, SceneConfig};

    #[test]
    fn a_capture_follows_the_input_pose_of_the_scene() {
        let mut scene = Scene::new(SceneConfig::default()).unwrap();
        let pat = scene.add_actor(&ActorDesc::new("pat")).unwrap();
        let refused = CaptureOptions::default()
            .capture(&scene, pat)
            .err()
            .unwrap();
        assert!(refused.to_string().contains("not a performer"), "{refused}");

        let skeleton = scene.actors()[pat].skeleton.clone();
        let elbow = skeleton.dof("r_elbow_flexion").unwrap();
        let arm = skeleton.scope("right_arm").unwrap();
        let mut pose = InputPose::new(skeleton.dof_count(), arm);
        scene.set_input_pose(pat, pose.clone()).unwrap();
        scene.declare_device_hand(pat, Side::Left).unwrap();
        let (capture, scope) = CaptureOptions::default().capture(&scene, pat).unwrap();
        assert_eq!(scope, arm);
        assert!(
            capture.hand.is_none(),
            "the left hand is not in the right arm"
        );
        scene
            .start_action(pat, ActionSpec::new("capture", scope), Box::new(capture))
            .unwrap();
        scene.step();
        assert_eq!(scene.states()[pat].q[elbow], 0.0, "nothing set yet");
        pose.q[elbow] = 0.8;
        pose.mask[elbow] = true;
        scene.set_input_pose(pat, pose).unwrap();
        scene.step();
        assert!((scene.states()[pat].q[elbow] - 0.8).abs() < 1e-12);
    }
}
