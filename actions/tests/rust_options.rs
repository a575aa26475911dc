//! Actions made from their Rust options and started on a scene, with no Lua: the path a
//! Rust program takes to embed troupe.

use std::sync::Arc;
use troupe_actions::reach::POSITION_TOLERANCE;
use troupe_actions::{KeyframeOptions, ReachOptions, Reacher, Target};
use troupe_body::glam::DVec3;
use troupe_body::sensors::Side;
use troupe_motion::{Key, Sequence, Track};
use troupe_scene::{ActionId, ActionSpec, ActorDesc, Scene, SceneConfig, Status};

fn scene() -> Scene {
    let mut s = Scene::new(SceneConfig::default()).unwrap();
    s.add_actor(&ActorDesc::new("ann")).unwrap();
    s
}

/// Steps `scene` until action `id` ends; its final status.
fn run(scene: &mut Scene, id: ActionId) -> Status {
    for _ in 0..1000 {
        scene.step();
        let status = scene.action(id).unwrap().status;
        if status.is_final() {
            return status;
        }
    }
    panic!("the action did not end");
}

#[test]
fn a_reach_from_rust_options_brings_the_hand_to_the_point() {
    let mut s = scene();
    let goal = DVec3::new(-0.25, 1.25, 0.4);
    let options = ReachOptions {
        duration: 0.8,
        ..ReachOptions::new(Reacher::Hand(Side::Right), Target::Point(goal))
    };
    options.validate().unwrap();
    let skeleton = s.actors()[0].skeleton.clone();
    let spec = options.spec(&skeleton).unwrap();
    let reach = options.reach(&skeleton).unwrap();
    let scope = reach.dofs().iter().copied().collect();
    let id = s
        .start_action(0, ActionSpec::new(options.kind(), scope), Box::new(reach))
        .unwrap();
    assert_eq!(run(&mut s, id), Status::Completed, "{:?}", s.action(id));
    let hand = spec.effector.position(&s.states()[0].globals);
    assert!((hand - goal).length() <= POSITION_TOLERANCE, "{hand}");
}

#[test]
fn refused_options_never_reach_the_scene() {
    let options = ReachOptions {
        duration: -1.0,
        ..ReachOptions::new(Reacher::Hand(Side::Left), Target::Point(DVec3::Y))
    };
    let e = options.validate().unwrap_err();
    assert_eq!(e.option(), "duration");
    let skeleton = scene().actors()[0].skeleton.clone();
    assert!(options.reach(&skeleton).is_err());
}

#[test]
fn a_keyframe_from_rust_options_plays_its_track() {
    let mut s = scene();
    let mut seq = Sequence::new("nod");
    let keys = vec![Key::new(0.0, 0.0), Key::new(0.5, 0.3)];
    seq.add_track(Track::new("skullbase_flexion", keys).unwrap())
        .unwrap();
    let options = KeyframeOptions::new(Arc::new(seq));
    let skeleton = s.actors()[0].skeleton.clone();
    let keyframe = options.keyframe(&skeleton).unwrap();
    let spec = ActionSpec::new("keyframe", keyframe.scope());
    let id = s.start_action(0, spec, Box::new(keyframe)).unwrap();
    assert_eq!(run(&mut s, id), Status::Completed);
    let dof = skeleton.dof("skullbase_flexion").unwrap();
    assert!((s.states()[0].q[dof] - 0.3).abs() < 1e-9);
}
