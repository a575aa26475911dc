//! Interaction end to end: a give between two actors, holding hands while the active
//! actor moves, shaking hands, and manipulation of a held object.

use troupe_actions::grasp::action::{grasp_scope, Grasp};
use troupe_actions::grasp::{HandChoice, HandModel, PlanOptions};
use troupe_actions::interact::{FollowHand, Give, HoldHand};
use troupe_actions::manipulate::{Manipulate, ObjectKey};
use troupe_body::glam::DVec3;
use troupe_body::sensors::Side;
use troupe_body::Shape;
use troupe_scene::{
    ActionId, ActionSpec, ActorDesc, DofWriter, Generator, GeneratorContext, Scene, SceneConfig,
    SignalId, Status, Step,
};

fn run_all(s: &mut Scene, ids: &[ActionId], max_ticks: usize) {
    for _ in 0..max_ticks {
        s.step();
        if ids
            .iter()
            .all(|id| s.action(*id).unwrap().status.is_final())
        {
            return;
        }
    }
}

fn cup(s: &mut Scene, at: DVec3) -> usize {
    s.add_object(Scene::object(
        "cup",
        Shape::Cylinder {
            radius: 0.035,
            height: 0.1,
        },
        at,
        0.3,
    ))
    .unwrap()
}

fn grasp(s: &mut Scene, actor: usize, object: usize) -> ActionId {
    let skel = s.actors()[actor].skeleton.clone();
    let g = Grasp::new(
        object,
        PlanOptions {
            hand: HandChoice::Right,
            ..PlanOptions::default()
        },
        vec![Side::Right],
        0.8,
    )
    .unwrap();
    s.start_action(
        actor,
        ActionSpec::new("grasp", grasp_scope(&skel, &[Side::Right]).unwrap()),
        Box::new(g),
    )
    .unwrap()
}

fn give_scene(threads: usize) -> (Scene, usize, ActionId, ActionId) {
    let mut s = Scene::new(SceneConfig {
        threads,
        ..SceneConfig::default()
    })
    .unwrap();
    s.add_actor(&ActorDesc::new("alice")).unwrap();
    s.add_actor(&ActorDesc {
        at: DVec3::new(0.0, 0.0, 0.9),
        facing_degrees: 180.0,
        ..ActorDesc::new("bob")
    })
    .unwrap();
    let c = cup(&mut s, DVec3::new(-0.2, 1.05, 0.38));
    let id = grasp(&mut s, 0, c);
    run_all(&mut s, &[id], 400);
    assert_eq!(s.action(id).unwrap().status, Status::Completed);
    let (arrived, ended) = (s.new_signal(), s.new_signal());
    let skel = s.actors()[0].skeleton.clone();
    let give = Give::new(c, 1, Side::Right, arrived, ended);
    let gid = s
        .start_action(
            0,
            ActionSpec::new("give", grasp_scope(&skel, &[Side::Right]).unwrap()),
            Box::new(give),
        )
        .unwrap();
    let take = Grasp::new(
        c,
        PlanOptions {
            hand: HandChoice::Auto,
            from: Some(0),
            ..PlanOptions::default()
        },
        vec![Side::Right, Side::Left],
        0.8,
    )
    .unwrap()
    .gated(arrived);
    let rid = s
        .start_action(
            1,
            ActionSpec::new(
                "receive",
                grasp_scope(&skel, &[Side::Right, Side::Left]).unwrap(),
            ),
            Box::new(take),
        )
        .unwrap();
    (s, c, gid, rid)
}

#[test]
fn give_ends_with_the_receiver_holding_and_both_completed() {
    let (mut s, c, gid, rid) = give_scene(1);
    run_all(&mut s, &[gid, rid], 1500);
    let (g, r) = (s.action(gid).unwrap(), s.action(rid).unwrap());
    assert_eq!(g.status, Status::Completed, "giver: {:?}", g.reason);
    assert_eq!(r.status, Status::Completed, "receiver: {:?}", r.reason);
    assert_eq!(s.holder(c).map(|h| h.actor), Some(1));
    assert!(s.held_by(0).is_empty());
    assert_eq!(s.held_by(1), vec![c]);
}

#[test]
fn give_is_identical_with_one_and_two_threads() {
    let mut out = Vec::new();
    for threads in [1, 2] {
        let (mut s, c, gid, rid) = give_scene(threads);
        // One actor per chunk: giver and receiver are stepped on both threads.
        s.set_chunk_size(Some(1));
        run_all(&mut s, &[gid, rid], 1500);
        out.push((
            s.states()[0].q.clone(),
            s.states()[1].q.clone(),
            s.objects()[c].position,
        ));
    }
    assert_eq!(out[0], out[1]);
}

#[test]
fn give_without_holding_fails() {
    let mut s = Scene::new(SceneConfig::default()).unwrap();
    s.add_actor(&ActorDesc::new("alice")).unwrap();
    s.add_actor(&ActorDesc {
        at: DVec3::new(0.0, 0.0, 0.9),
        facing_degrees: 180.0,
        ..ActorDesc::new("bob")
    })
    .unwrap();
    let c = cup(&mut s, DVec3::new(-0.2, 1.05, 0.38));
    let skel = s.actors()[0].skeleton.clone();
    let (arrived, ended) = (s.new_signal(), s.new_signal());
    let give = Give::new(c, 1, Side::Right, arrived, ended);
    let id = s
        .start_action(
            0,
            ActionSpec::new("give", grasp_scope(&skel, &[Side::Right]).unwrap()),
            Box::new(give),
        )
        .unwrap();
    run_all(&mut s, &[id], 5);
    let a = s.action(id).unwrap();
    assert_eq!(a.status, Status::Failed);
    assert!(a.reason.unwrap().contains("`alice` does not hold `cup`"));
}

/// Moves the root sideways and forward by a smooth key-framed trajectory.
struct RootPath {
    x: usize,
    z: usize,
    x0: f64,
    z0: f64,
}

impl Generator for RootPath {
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        // Keys at 0, 1, 2, 3 s: (0, 0) → (0.06, 0.08) → (-0.04, 0.12) → (0, 0), eased.
        let keys = [
            (0.0, 0.0, 0.0),
            (1.0, 0.06, 0.08),
            (2.0, -0.04, 0.12),
            (3.0, 0.0, 0.0),
        ];
        let t = ctx.local_time.min(3.0);
        let i = (t.floor() as usize).min(2);
        let u = t - i as f64;
        let e = u * u * (3.0 - 2.0 * u);
        let (a, b) = (keys[i], keys[i + 1]);
        out.set(self.x, self.x0 + a.1 + (b.1 - a.1) * e);
        out.set(self.z, self.z0 + a.2 + (b.2 - a.2) * e);
        if ctx.local_time >= 3.0 {
            Step::Finished
        } else {
            Step::Running
        }
    }
}

fn palm(s: &Scene, actor: usize, side: Side) -> DVec3 {
    let m = HandModel::new(&s.actors()[actor].skeleton, side).unwrap();
    s.states()[actor].globals[m.sensors.wrist].transform_point(m.sensors.palm)
}

fn hold_scene(shake: bool) -> (Scene, ActionId, ActionId, SignalId) {
    let mut s = Scene::new(SceneConfig::default()).unwrap();
    s.add_actor(&ActorDesc::new("alice")).unwrap();
    s.add_actor(&ActorDesc {
        at: DVec3::new(-0.45, 0.0, 0.0),
        ..ActorDesc::new("bob")
    })
    .unwrap();
    let (held, finished, gave_up) = (s.new_signal(), s.new_signal(), s.new_signal());
    let skel = s.actors()[0].skeleton.clone();
    let active = HoldHand::new(
        1,
        (Side::Right, Side::Left),
        shake,
        (held, finished, gave_up),
    );
    let aid = s
        .start_action(
            0,
            ActionSpec::new("hold_hand", grasp_scope(&skel, &[Side::Right]).unwrap()),
            Box::new(active),
        )
        .unwrap();
    let wrist = skel.joint("r_wrist").unwrap();
    let follow = FollowHand::new((0, wrist), Side::Left, (held, finished, gave_up));
    let fid = s
        .start_action(
            1,
            ActionSpec::new("follow_hand", skel.scope("left_arm").unwrap()),
            Box::new(follow),
        )
        .unwrap();
    (s, aid, fid, held)
}

#[test]
fn holding_hands_the_hands_stay_within_a_centimetre_while_the_active_actor_moves() {
    let (mut s, aid, fid, held) = hold_scene(false);
    for _ in 0..300 {
        s.step();
        if s.blackboard().before(held, s.tick()) {
            break;
        }
    }
    assert!(
        s.blackboard().before(held, s.tick()),
        "never held: {:?}",
        s.action(aid).unwrap().reason
    );
    s.step();
    let gap0 = palm(&s, 0, Side::Right) - palm(&s, 1, Side::Left);
    let skel = s.actors()[0].skeleton.clone();
    let (x, z) = (skel.dof("root_x").unwrap(), skel.dof("root_z").unwrap());
    let q = &s.states()[0].q;
    let walk = RootPath {
        x,
        z,
        x0: q[x],
        z0: q[z],
    };
    let wid = s
        .start_action(
            0,
            ActionSpec::new("keyframe", skel.scope("global").unwrap()),
            Box::new(walk),
        )
        .unwrap();
    let mut worst: f64 = 0.0;
    let mut moved: f64 = 0.0;
    let start_root = s.states()[0].globals[0].translation;
    for _ in 0..320 {
        s.step();
        let gap = palm(&s, 0, Side::Right) - palm(&s, 1, Side::Left);
        worst = worst.max((gap - gap0).length());
        moved = moved.max((s.states()[0].globals[0].translation - start_root).length());
    }
    assert_eq!(s.action(wid).unwrap().status, Status::Completed);
    assert!(moved > 0.1, "the active actor barely moved ({moved} m)");
    assert!(worst <= 0.01, "hands drifted apart by {worst} m");
    assert!(s.action(aid).unwrap().status.is_running());
    assert!(s.action(fid).unwrap().status.is_running());
}

#[test]
fn shaking_hands_completes_for_both() {
    let (mut s, aid, fid, _) = hold_scene(true);
    run_all(&mut s, &[aid, fid], 800);
    assert_eq!(
        s.action(aid).unwrap().status,
        Status::Completed,
        "{:?}",
        s.action(aid).unwrap().reason
    );
    assert_eq!(
        s.action(fid).unwrap().status,
        Status::Completed,
        "{:?}",
        s.action(fid).unwrap().reason
    );
}

#[test]
fn manipulate_moves_the_held_object_along_keys() {
    let mut s = Scene::new(SceneConfig::default()).unwrap();
    s.add_actor(&ActorDesc::new("alice")).unwrap();
    let c = cup(&mut s, DVec3::new(-0.2, 1.05, 0.38));
    let id = grasp(&mut s, 0, c);
    run_all(&mut s, &[id], 400);
    let p0 = s.objects()[c].position;
    let keys = vec![
        ObjectKey {
            time: 0.5,
            position: p0 + DVec3::new(0.0, 0.1, 0.0),
            rotation: None,
        },
        ObjectKey {
            time: 1.0,
            position: p0 + DVec3::new(0.05, 0.1, -0.05),
            rotation: None,
        },
    ];
    let skel = s.actors()[0].skeleton.clone();
    let m = Manipulate::new(c, keys.clone(), vec![Side::Right]).unwrap();
    let mid = s
        .start_action(
            0,
            ActionSpec::new("manipulate", skel.scope("right_arm").unwrap()),
            Box::new(m),
        )
        .unwrap();
    run_all(&mut s, &[mid], 200);
    assert_eq!(
        s.action(mid).unwrap().status,
        Status::Completed,
        "{:?}",
        s.action(mid).unwrap().reason
    );
    assert!((s.objects()[c].position - keys[1].position).length() < 0.01);
    assert!(Manipulate::new(c, vec![], vec![Side::Right]).is_err());
}
