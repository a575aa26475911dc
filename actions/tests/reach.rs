//! Reach and look-at on a scene: accuracy, moving targets, failures, self-collision.

use troupe_actions::reach::{Reach, ReachSpec, Target, POSITION_TOLERANCE};
use troupe_actions::LookAt;
use troupe_body::glam::DVec3;
use troupe_body::jacobian::{scope_dofs_moving, Effector};
use troupe_body::self_collision::BodySensors;
use troupe_body::Shape;
use troupe_scene::{ActionId, ActionSpec, ActorDesc, Scene, SceneConfig, Status};

fn scene() -> Scene {
    let mut s = Scene::new(SceneConfig::default()).unwrap();
    s.add_actor(&ActorDesc::new("ann")).unwrap();
    s
}

fn hand(scene: &Scene) -> Effector {
    let sk = &scene.actors()[0].skeleton;
    let center = sk
        .solids()
        .iter()
        .find(|(_, s)| s.name == "r_hand")
        .unwrap()
        .1
        .center;
    Effector {
        joint: sk.joint("r_wrist").unwrap(),
        point: center,
    }
}

fn reach(
    scene: &mut Scene,
    target: Target,
    duration: f64,
    collision: bool,
    via: Vec<DVec3>,
) -> ActionId {
    let sk = scene.actors()[0].skeleton.clone();
    let e = hand(scene);
    let scope = sk.scope("right_arm").unwrap();
    let dofs = scope_dofs_moving(&sk, &scope, e.joint);
    let spec = ReachSpec {
        effector: e,
        target,
        orientation: None,
        duration,
        via,
        self_collision: collision,
        detour: collision,
        dofs,
    };
    let g = Reach::new(&sk, spec).unwrap();
    scene
        .start_action(0, ActionSpec::new("reach", scope), Box::new(g))
        .unwrap()
}

fn run_until_done(scene: &mut Scene, id: ActionId, mut each: impl FnMut(&Scene)) -> Status {
    for _ in 0..1000 {
        scene.step();
        each(scene);
        let info = scene.action(id).unwrap();
        if info.status.is_final() {
            return info.status;
        }
    }
    panic!("the action did not end");
}

#[test]
fn reaching_a_point_ends_within_a_millimetre_and_passes_the_via_point() {
    let mut s = scene();
    let goal = DVec3::new(-0.25, 1.25, 0.4);
    let via = DVec3::new(-0.4, 1.0, 0.2);
    let id = reach(&mut s, Target::Point(goal), 1.0, true, vec![via]);
    let e = hand(&s);
    let mut closest_to_via = f64::INFINITY;
    let status = run_until_done(&mut s, id, |s| {
        let p = e.position(&s.states()[0].globals);
        closest_to_via = closest_to_via.min((p - via).length());
    });
    assert_eq!(
        status,
        Status::Completed,
        "{:?}",
        s.action(id).unwrap().reason
    );
    let p = e.position(&s.states()[0].globals);
    assert!((p - goal).length() <= POSITION_TOLERANCE, "{p}");
    assert!(
        closest_to_via < 0.01,
        "passes by the via point: {closest_to_via}"
    );
}

#[test]
fn an_unreachable_point_fails_with_the_residual_distance() {
    let mut s = scene();
    let id = reach(
        &mut s,
        Target::Point(DVec3::new(0.0, 1.3, 2.0)),
        0.5,
        true,
        vec![],
    );
    assert_eq!(run_until_done(&mut s, id, |_| {}), Status::Failed);
    let reason = s.action(id).unwrap().reason.unwrap();
    assert!(reason.contains("m from it"), "{reason}");
}

#[test]
fn a_moving_object_is_followed() {
    let mut s = scene();
    let ball = Scene::object(
        "ball",
        Shape::Sphere { radius: 0.03 },
        DVec3::new(-0.3, 1.0, 0.35),
        0.1,
    );
    s.add_object(ball).unwrap();
    let id = reach(&mut s, Target::Object("ball".into()), 1.0, false, vec![]);
    let status = run_until_done(&mut s, id, |_| {});
    assert_eq!(status, Status::Completed);
    // Again, moving the ball while the hand goes.
    let id = reach(&mut s, Target::Object("ball".into()), 1.0, false, vec![]);
    let mut n = 0;
    loop {
        n += 1;
        if n < 80 {
            s.objects_mut()[0].position += DVec3::new(0.0, 0.002, 0.0);
        }
        s.step();
        if s.action(id).unwrap().status.is_final() {
            break;
        }
    }
    assert_eq!(s.action(id).unwrap().status, Status::Completed);
    let p = hand(&s).position(&s.states()[0].globals);
    assert!((p - s.objects()[0].position).length() <= POSITION_TOLERANCE);
}

#[test]
fn targets_that_cannot_be_found_fail_without_panicking() {
    let mut s = scene();
    let ghost = Target::Joint {
        actor: "ghost".into(),
        joint: "r_wrist".into(),
        offset: DVec3::ZERO,
    };
    let id = reach(&mut s, ghost, 1.0, false, vec![]);
    assert_eq!(run_until_done(&mut s, id, |_| {}), Status::Failed);
    assert!(s.action(id).unwrap().reason.unwrap().contains("ghost"));
    let id = reach(&mut s, Target::Object("nothing".into()), 1.0, false, vec![]);
    assert_eq!(run_until_done(&mut s, id, |_| {}), Status::Failed);

    let sk = s.actors()[0].skeleton.clone();
    let spec = ReachSpec {
        effector: hand(&s),
        target: Target::Point(DVec3::new(f64::NAN, 0.0, 0.0)),
        orientation: None,
        duration: 1.0,
        via: vec![],
        self_collision: false,
        detour: false,
        dofs: vec![50],
    };
    assert!(Reach::new(&sk, spec.clone()).is_err());
    let bad_duration = ReachSpec {
        target: Target::Point(DVec3::ONE),
        duration: 0.0,
        ..spec
    };
    assert!(Reach::new(&sk, bad_duration).is_err());
}

/// The right hand reaches to the left of the chest from the side: the straight path goes
/// through the trunk. Every tick, every sensor is checked against the body.
fn reach_across(collision: bool) -> (f64, Status) {
    let mut s = scene();
    let sensors = BodySensors::new(&s.actors()[0].skeleton).unwrap();
    let goal = DVec3::new(0.12, 1.2, 0.25);
    let id = reach(&mut s, Target::Point(goal), 1.0, collision, vec![]);
    let mut deepest: f64 = 0.0;
    let status = run_until_done(&mut s, id, |s| {
        let sk = &s.actors()[0].skeleton;
        deepest = deepest.max(sensors.deepest(sk, &s.states()[0].globals).0);
    });
    (deepest, status)
}

#[test]
fn self_collision_correction_keeps_the_arm_out_of_the_trunk() {
    let (off, _) = reach_across(false);
    assert!(
        off > 0.01,
        "without correction the forearm goes through: {off}"
    );
    let (on, status) = reach_across(true);
    assert_eq!(on, 0.0, "with correction no sensor penetrates");
    assert_eq!(status, Status::Completed);
}

#[test]
fn look_at_aims_the_eyes_and_follows() {
    let mut s = scene();
    let sk = s.actors()[0].skeleton.clone();
    s.add_object(Scene::object(
        "fly",
        Shape::Sphere { radius: 0.01 },
        DVec3::new(0.5, 1.8, 1.0),
        0.01,
    ))
    .unwrap();
    let look = LookAt::new(&sk, Target::Object("fly".into())).unwrap();
    let scope = look.scope_dofs().into_iter().collect();
    let id = s
        .start_action(0, ActionSpec::new("look_at", scope), Box::new(look))
        .unwrap();
    let gaze_error = |s: &Scene| -> f64 {
        let g = &s.states()[0].globals;
        let target = s.objects()[0].position;
        ["l_eyeball_joint", "r_eyeball_joint"]
            .iter()
            .map(|n| {
                let t = g[sk.joint(n).unwrap()];
                let gaze = t.rotation * DVec3::Z;
                gaze.angle_between(target - t.translation)
            })
            .fold(0.0, f64::max)
    };
    for _ in 0..200 {
        s.step();
    }
    assert!(
        gaze_error(&s) < 1f64.to_radians(),
        "{}",
        gaze_error(&s).to_degrees()
    );
    let yaw = s.states()[0].q[sk.dof("skullbase_torsion").unwrap()];
    assert!(yaw > 0.1, "the head turns left toward +X: {yaw}");
    // The fly moves to the other side: the gaze follows.
    for _ in 0..200 {
        s.objects_mut()[0].position.x -= 0.005;
        s.step();
    }
    for _ in 0..100 {
        s.step();
    }
    assert!(gaze_error(&s) < 1f64.to_radians());
    assert_eq!(s.action(id).unwrap().status, Status::Active);
}
