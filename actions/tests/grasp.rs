//! Grasping end to end on a scene: every shape grasped, fingers in contact or at their
//! limits, no penetration, the held object following the hand; bad input failing.

use troupe_actions::grasp::action::{grasp_scope, Grasp, Release};
use troupe_actions::grasp::{HandModel, PlanOptions};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::sensors::{object_distance, Side};
use troupe_body::Shape;
use troupe_scene::{ActionId, ActionSpec, ActorDesc, Scene, SceneConfig, Status};

fn scene(threads: usize) -> Scene {
    let mut s = Scene::new(SceneConfig {
        threads,
        ..SceneConfig::default()
    })
    .unwrap();
    s.add_actor(&ActorDesc::new("alice")).unwrap();
    s
}

fn run(s: &mut Scene, id: ActionId, max_ticks: usize) -> Status {
    for _ in 0..max_ticks {
        s.step();
        let st = s.action(id).unwrap().status;
        if st.is_final() {
            return st;
        }
    }
    s.action(id).unwrap().status
}

fn start_grasp(s: &mut Scene, actor: usize, object: usize, sides: Vec<Side>) -> ActionId {
    let skel = s.actors()[actor].skeleton.clone();
    let scope = grasp_scope(&skel, &sides).unwrap();
    let hand = match sides.as_slice() {
        [Side::Left] => troupe_actions::grasp::HandChoice::Left,
        [Side::Right] => troupe_actions::grasp::HandChoice::Right,
        _ => troupe_actions::grasp::HandChoice::Both,
    };
    let g = Grasp::new(
        object,
        PlanOptions {
            hand,
            ..PlanOptions::default()
        },
        sides,
        0.8,
    )
    .unwrap();
    s.start_action(actor, ActionSpec::new("grasp", scope), Box::new(g))
        .unwrap()
}

/// Max penetration of any sensor of `side`'s hand into `object`, and the fingers' states.
fn hand_report(s: &Scene, actor: usize, object: usize, side: Side) -> (f64, [bool; 5], [bool; 5]) {
    let skel = s.actors()[actor].skeleton.clone();
    let m = HandModel::new(&skel, side).unwrap();
    let g = &s.states()[actor].globals;
    let o = &s.objects()[object];
    let mut deepest: f64 = 0.0;
    for i in 0..m.sensors.sensors.len() {
        let d = m.sensors.distance_to_object(i, g, o);
        deepest = deepest.max(-d);
    }
    let field = |p| object_distance(o, p);
    (
        deepest,
        m.fingers_touching(g, &field),
        m.fingers_at_limit(&skel, &s.states()[actor].q),
    )
}

fn shapes() -> Vec<(&'static str, Shape)> {
    vec![
        (
            "box",
            Shape::Box {
                half_extents: DVec3::new(0.03, 0.05, 0.03),
            },
        ),
        ("sphere", Shape::Sphere { radius: 0.04 }),
        (
            "cylinder",
            Shape::Cylinder {
                radius: 0.035,
                height: 0.12,
            },
        ),
        (
            "frustum",
            Shape::Frustum {
                bottom_radius: 0.03,
                top_radius: 0.042,
                height: 0.11,
            },
        ),
        (
            "ellipsoid",
            Shape::Ellipsoid {
                radii: DVec3::new(0.035, 0.05, 0.03),
            },
        ),
    ]
}

#[test]
fn every_shape_is_grasped_with_contact_and_follows_the_hand() {
    for (name, shape) in shapes() {
        let mut s = scene(1);
        let o = s
            .add_object(Scene::object(
                name,
                shape,
                DVec3::new(-0.2, 1.05, 0.38),
                0.3,
            ))
            .unwrap();
        let id = start_grasp(&mut s, 0, o, vec![Side::Right]);
        let status = run(&mut s, id, 400);
        let info = s.action(id).unwrap();
        assert_eq!(status, Status::Completed, "{name}: {:?}", info.reason);
        assert_eq!(s.holder(o).map(|h| h.actor), Some(0), "{name}");
        let (deepest, touching, at_limit) = hand_report(&s, 0, o, Side::Right);
        assert!(deepest <= 0.002, "{name}: a sensor penetrates {deepest} m");
        for f in 0..5 {
            assert!(
                touching[f] || at_limit[f],
                "{name}: finger {f} neither touches nor is at its limit"
            );
        }
        assert!(
            touching.iter().filter(|t| **t).count() >= 2,
            "{name}: {touching:?}"
        );
        // While held, the object follows the hand: move the arm and compare.
        let skel = s.actors()[0].skeleton.clone();
        let wrist = skel.joint("r_wrist").unwrap();
        let before = s.states()[0].globals[wrist]
            .inverse()
            .transform_point(s.objects()[o].position);
        let elbow = skel.dof("r_elbow_flexion").unwrap();
        let q = s.states()[0].q[elbow];
        s.set_dofs(0, &[(elbow, q + 0.3)]).unwrap();
        s.step();
        let after = s.states()[0].globals[wrist]
            .inverse()
            .transform_point(s.objects()[o].position);
        assert!(
            (after - before).length() <= 0.001,
            "{name}: object drifted {}",
            (after - before).length()
        );
    }
}

#[test]
fn release_lets_go_and_place_puts_the_object_down() {
    let mut s = scene(1);
    let o = s
        .add_object(Scene::object(
            "cup",
            Shape::Cylinder {
                radius: 0.035,
                height: 0.1,
            },
            DVec3::new(-0.2, 1.05, 0.38),
            0.3,
        ))
        .unwrap();
    let id = start_grasp(&mut s, 0, o, vec![Side::Right]);
    assert_eq!(run(&mut s, id, 400), Status::Completed);
    let skel = s.actors()[0].skeleton.clone();
    let scope = grasp_scope(&skel, &[Side::Right]).unwrap();
    let at = DVec3::new(-0.15, 1.1, 0.35);
    let place = Release::new(
        o,
        vec![Side::Right],
        Some((
            troupe_body::Transform::new(s.objects()[o].rotation, at),
            0.8,
        )),
    )
    .unwrap();
    let id = s
        .start_action(0, ActionSpec::new("place", scope), Box::new(place))
        .unwrap();
    let st = run(&mut s, id, 400);
    assert_eq!(st, Status::Completed, "{:?}", s.action(id).unwrap().reason);
    assert_eq!(s.holder(o), None);
    assert!((s.objects()[o].position - at).length() <= 0.01);
    // Releasing again fails: nobody holds it.
    let r = Release::new(o, vec![Side::Right], None).unwrap();
    let id = s
        .start_action(0, ActionSpec::new("release", scope), Box::new(r))
        .unwrap();
    assert_eq!(run(&mut s, id, 10), Status::Failed);
    assert!(s
        .action(id)
        .unwrap()
        .reason
        .unwrap()
        .contains("does not hold `cup`"));
}

#[test]
fn out_of_reach_and_held_by_another_fail_with_reasons() {
    let mut s = scene(1);
    s.add_actor(&ActorDesc {
        at: DVec3::new(0.0, 0.0, 1.2),
        facing_degrees: 180.0,
        ..ActorDesc::new("bob")
    })
    .unwrap();
    let far = s
        .add_object(Scene::object(
            "far",
            Shape::Sphere { radius: 0.04 },
            DVec3::new(0.0, 1.0, 3.0),
            0.3,
        ))
        .unwrap();
    let id = start_grasp(&mut s, 0, far, vec![Side::Right]);
    assert_eq!(run(&mut s, id, 10), Status::Failed);
    let reason = s.action(id).unwrap().reason.unwrap();
    assert!(
        reason.contains("out of reach") && reason.contains("far"),
        "{reason}"
    );

    let cup = s
        .add_object(Scene::object(
            "cup",
            Shape::Cylinder {
                radius: 0.035,
                height: 0.1,
            },
            DVec3::new(-0.2, 1.05, 0.38),
            0.3,
        ))
        .unwrap();
    let wrist = s.actors()[1].skeleton.joint("r_wrist").unwrap();
    assert!(s.request_hold(
        1,
        troupe_scene::holding::HoldRequest::Attach {
            object: cup,
            joint: wrist,
            also: None,
            from: None
        }
    ));
    let id = start_grasp(&mut s, 0, cup, vec![Side::Right]);
    assert_eq!(run(&mut s, id, 10), Status::Failed);
    let reason = s.action(id).unwrap().reason.unwrap();
    assert!(
        reason.contains("held by `bob`") && reason.contains("give"),
        "{reason}"
    );
}

#[test]
fn grasp_is_identical_with_one_and_two_threads() {
    let mut postures = Vec::new();
    for threads in [1, 2] {
        let mut s = scene(threads);
        // One actor per chunk: the two actors are stepped on both threads.
        s.set_chunk_size(Some(1));
        s.add_actor(&ActorDesc {
            at: DVec3::new(1.0, 0.0, 0.0),
            ..ActorDesc::new("bob")
        })
        .unwrap();
        let a = s
            .add_object(Scene::object(
                "a",
                Shape::Sphere { radius: 0.04 },
                DVec3::new(-0.2, 1.05, 0.38),
                0.3,
            ))
            .unwrap();
        let b = s
            .add_object(Scene::object(
                "b",
                Shape::Sphere { radius: 0.04 },
                DVec3::new(0.8, 1.05, 0.38),
                0.3,
            ))
            .unwrap();
        let x = start_grasp(&mut s, 0, a, vec![Side::Right]);
        let y = start_grasp(&mut s, 1, b, vec![Side::Right]);
        run(&mut s, x, 400);
        run(&mut s, y, 50);
        postures.push((
            s.states()[0].q.clone(),
            s.states()[1].q.clone(),
            s.objects()[a].position,
            s.objects()[b].rotation,
        ));
    }
    assert_eq!(postures[0], postures[1]);
    let _ = DQuat::IDENTITY;
}

#[test]
fn the_world_lists_the_objects_held_in_object_order_as_holders_change() {
    use troupe_scene::holding::HoldRequest;
    let mut s = scene(1);
    s.add_actor(&ActorDesc {
        at: DVec3::new(1.0, 0.0, 0.0),
        ..ActorDesc::new("bob")
    })
    .unwrap();
    let ball = |s: &mut Scene, name: &str, x: f64| {
        let shape = Shape::Sphere { radius: 0.04 };
        s.add_object(Scene::object(name, shape, DVec3::new(x, 1.05, 0.38), 0.3))
            .unwrap()
    };
    // `c` within reach of alice's right hand, for a grasp at the end.
    let (a, b, c) = (
        ball(&mut s, "a", 0.8),
        ball(&mut s, "b", 0.4),
        ball(&mut s, "c", -0.2),
    );
    let wrist = s.actors()[0].skeleton.joint("r_wrist").unwrap();
    let attach = |object| HoldRequest::Attach {
        object,
        joint: wrist,
        also: None,
        from: None,
    };
    let held = |s: &Scene| -> Vec<(usize, usize)> {
        s.world().held.iter().map(|(o, h)| (*o, h.actor)).collect()
    };
    assert!(held(&s).is_empty());
    // Taken in the order c, a (bob), then b: listed by object.
    assert!(s.request_hold(0, attach(c)));
    assert!(s.request_hold(1, attach(a)));
    assert!(s.request_hold(0, attach(b)));
    assert_eq!(held(&s), vec![(a, 1), (b, 0), (c, 0)]);
    // What the holders say, object by object.
    for (object, holder) in s.world().held {
        assert_eq!(s.holder(*object), Some(*holder));
    }
    // Let go: gone from the list, the rest kept; a tick keeps it as it is.
    assert!(s.request_hold(0, HoldRequest::Release { object: b }));
    s.step();
    assert_eq!(held(&s), vec![(a, 1), (c, 0)]);
    // A grasp's own attachment, made in a tick, is listed too.
    assert!(s.request_hold(0, HoldRequest::Release { object: c }));
    let id = start_grasp(&mut s, 0, c, vec![Side::Right]);
    assert_eq!(run(&mut s, id, 400), Status::Completed);
    assert_eq!(held(&s), vec![(a, 1), (c, 0)]);
}
