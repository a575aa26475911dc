//! Embedding troupe in a Rust program, with no Lua at all: build a scene, add actors and
//! actions from typed options, run it in a session with observers, read postures.
//!
//! Ann walks two metres and then reaches for a point in front of her (the reach shares
//! the arm with the walk's arm swing, so the scheduler starts it when the walk ends);
//! Bob nods. The session records every posture, and the program prints where Ann is and
//! where her hand is each second.
//!
//! Run: `cargo run -p troupe-actions --example embed --no-default-features`
//! (`--no-default-features` leaves out the Lua side: nothing of Lua is even compiled).

use std::sync::Arc;
use troupe_actions::{KeyframeOptions, ReachOptions, Reacher, Target, Walk, WalkOptions};
use troupe_body::glam::DVec3;
use troupe_body::sensors::Side;
use troupe_motion::{Key, Sequence, Track};
use troupe_scene::record::PostureRecorder;
use troupe_scene::tally::ActionTally;
use troupe_scene::{ActionSpec, ActorDesc, RunLimit, Scene, SceneConfig, Session};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The scene: two actors facing each other across the origin.
    let mut scene = Scene::new(SceneConfig::default())?;
    let ann = scene.add_actor(&ActorDesc {
        at: DVec3::new(0.0, 0.0, -1.5),
        ..ActorDesc::new("ann")
    })?;
    let bob = scene.add_actor(&ActorDesc {
        at: DVec3::new(0.0, 0.0, 1.5),
        facing_degrees: 180.0,
        ..ActorDesc::new("bob")
    })?;
    let ann_body = scene.actors()[ann].skeleton.clone();
    let bob_body = scene.actors()[bob].skeleton.clone();

    // Ann walks to just short of Bob.
    let walk = Walk::to(&ann_body, DVec3::new(0.0, 0.0, 0.5), WalkOptions::default())?;
    scene.start_action(ann, ActionSpec::new("walk", walk.scope()), Box::new(walk))?;

    // Then she reaches for a point at chest height in front of her.
    let point = DVec3::new(-0.2, 1.25, 0.95);
    let reach = ReachOptions {
        duration: 0.8,
        ..ReachOptions::new(Reacher::Hand(Side::Right), Target::Point(point))
    };
    let hand = reach.spec(&ann_body)?.effector;
    let generator = reach.reach(&ann_body)?;
    let scope = generator.dofs().iter().copied().collect();
    scene.start_action(
        ann,
        ActionSpec::new(reach.kind(), scope),
        Box::new(generator),
    )?;

    // Bob nods: a sequence made in code, played by the keyframe action.
    let mut nod = Sequence::new("nod");
    let keys =
        [(0.0, 0.0), (0.4, 0.35), (0.8, 0.0), (1.2, 0.35), (1.6, 0.0)].map(|(t, v)| Key::new(t, v));
    nod.add_track(Track::new("skullbase_flexion", keys.to_vec())?)?;
    let keyframe = KeyframeOptions::new(Arc::new(nod)).keyframe(&bob_body)?;
    let mut spec = ActionSpec::new("keyframe", keyframe.scope());
    spec.delay = 1.0;
    scene.start_action(bob, spec, Box::new(keyframe))?;

    // The session runs the tick; observers record postures and count how actions ended.
    let mut session = Session::new(scene);
    let postures = session.observe(PostureRecorder::new());
    let tally = session.observe(ActionTally::new());
    let rate = session.scene().config().rate as u64;
    let mut second = 0;
    loop {
        let ran = session.run(RunLimit {
            ticks: rate,
            until_idle: true,
        })?;
        second += 1;
        let scene = session.scene();
        let globals = &scene.states()[ann].globals;
        let pelvis = globals[0].translation;
        let palm = hand.position(globals);
        println!(
            "t = {:4.1} s  ann at ({:5.2}, {:5.2})  right hand {:.3} m from the point",
            scene.time(),
            pelvis.x,
            pelvis.z,
            (palm - point).length()
        );
        if ran < rate || second >= 10 {
            break;
        }
    }
    let scene = session.scene();
    println!("{}", session.observer(tally).summary(scene));
    let recorded = session.observer(postures).sequences(scene);
    println!(
        "recorded {} ticks: {} sequences of {} tracks",
        session.observer(postures).len(),
        recorded.len(),
        recorded[0].tracks().len()
    );
    Ok(())
}
