//! The walking motor's measurable claims, run through a real scene (scheduler, blending,
//! forward kinematics) and measured on the resulting joint positions.

use super::feet::Landing;
use super::*;
use crate::error::ActionError;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::Transform;
use troupe_motion::{Key, Track};
use troupe_scene::action::Status;
use troupe_scene::space::{Capsule, FootSpan, Footprint};
use troupe_scene::{ActionSpec, ActorDesc, Scene, SceneConfig};

/// Points of one foot's sole: (joint, position in that joint's frame).
struct Sole {
    points: Vec<(usize, DVec3)>,
}

/// The heel, the sole under the ball joint and the toe tip of each foot, fixed to their
/// segments (found from the rest pose, where every joint frame is unrotated).
fn soles(skeleton: &Skeleton, rig: &Rig) -> [Sole; 2] {
    let mut rest = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &vec![0.0; skeleton.dof_count()], &mut rest);
    let make = |leg: usize| {
        let l = &rig.legs[leg];
        let (ankle, mt) = (l.joints[0], l.joints[1]);
        let a = rest[ankle].translation;
        let m = rest[mt].translation;
        let under = DVec3::new(a.x, 0.0, a.z);
        // The heel and the ball's sole belong to the foot (the subtalar joint's segment).
        let subtalar = skeleton.joints()[mt]
            .parent
            .expect("metatarsal has a parent");
        let s = rest[subtalar].translation;
        Sole {
            points: vec![
                (subtalar, under + l.heel - s),
                (subtalar, DVec3::new(m.x, 0.0, m.z) - s),
                (mt, l.toe_sole),
            ],
        }
    };
    [make(0), make(1)]
}

/// One tick of a walking actor, as measured.
struct Frame {
    t: f64,
    q: Vec<f64>,
    /// Sole points per foot, world.
    soles: [Vec<DVec3>; 2],
}

struct Run {
    frames: Vec<Frame>,
    status: Status,
    ht: f64,
    rig: Rig,
}

fn adult_scene(rate: f64, threads: usize) -> Scene {
    Scene::new(SceneConfig {
        rate,
        threads,
        ..SceneConfig::default()
    })
    .unwrap()
}

/// Runs one actor's walk made by `make` until it ends or `max_t` seconds pass.
fn run(rate: f64, desc: ActorDesc, max_t: f64, make: impl FnOnce(&Skeleton) -> Walk) -> Run {
    let mut scene = adult_scene(rate, 1);
    let a = scene.add_actor(&desc).unwrap();
    let skeleton = scene.actors()[a].skeleton.clone();
    let walk = make(&skeleton);
    let rig = walk.rig().clone();
    let feet = soles(&skeleton, &rig);
    let id = scene
        .start_action(a, ActionSpec::new("walk", walk.scope()), Box::new(walk))
        .unwrap();
    let mut frames = Vec::new();
    let mut status = Status::Pending;
    while scene.time() < max_t {
        scene.step();
        let st = &scene.states()[a];
        let world = |s: &Sole| {
            s.points
                .iter()
                .map(|(j, p)| st.globals[*j].transform_point(*p))
                .collect::<Vec<_>>()
        };
        frames.push(Frame {
            t: scene.time(),
            q: st.q.clone(),
            soles: [world(&feet[0]), world(&feet[1])],
        });
        status = scene.action(id).unwrap().status;
        if status.is_final() {
            break;
        }
    }
    Run {
        frames,
        status,
        ht: rig.thigh_height,
        rig,
    }
}

fn root_floor(run: &Run, f: &Frame) -> DVec2 {
    DVec2::new(
        run.rig.root_rest.x + f.q[run.rig.root[0]],
        run.rig.root_rest.z + f.q[run.rig.root[2]],
    )
}

#[test]
fn arrives_within_5_cm_facing_the_travel_direction() {
    let goal = DVec3::new(3.0, 0.0, 4.0);
    let r = run(100.0, ActorDesc::new("a"), 20.0, |s| {
        Walk::to(s, goal, WalkOptions::default()).unwrap()
    });
    assert_eq!(r.status, Status::Completed);
    let last = r.frames.last().unwrap();
    let at = root_floor(&r, last);
    let miss = (at - DVec2::new(goal.x, goal.z)).length();
    println!("arrival: {miss:.2e} m from the goal at t = {:.2} s", last.t);
    assert!(miss < 0.05, "stopped {miss} m from the goal");
    let yaw = last.q[r.rig.root[3]];
    let travel = 3.0f64.atan2(4.0);
    assert!(wrap(yaw - travel).abs() < 0.05, "heading {yaw} vs {travel}");
    // It stands: legs straight, feet side by side under the hips.
    for leg in &r.rig.legs {
        assert!(
            last.q[leg.dofs[3]].abs() < 0.02,
            "knee {}",
            last.q[leg.dofs[3]]
        );
    }
}

#[test]
fn arrives_facing_a_requested_heading() {
    let heading = 100f64.to_radians();
    let r = run(100.0, ActorDesc::new("a"), 20.0, |s| {
        Walk::to(
            s,
            DVec3::new(-1.5, 0.0, 2.5),
            WalkOptions {
                heading: Some(heading),
                ..WalkOptions::default()
            },
        )
        .unwrap()
    });
    assert_eq!(r.status, Status::Completed);
    let last = r.frames.last().unwrap();
    assert!((root_floor(&r, last) - DVec2::new(-1.5, 2.5)).length() < 0.05);
    assert!(wrap(last.q[r.rig.root[3]] - heading).abs() < 0.05);
}

#[test]
fn turns_on_the_spot_step_round_with_the_feet_planted() {
    // Goals behind, beside and ahead of an actor facing +Z, and requested headings at the
    // end from 45° to a half turn. Before the body was held by its planted feet, a walk
    // to a point behind slid a sole 1.02 m and put it 16 cm into the floor; a half turn
    // at the end, 0.90 m and 17 cm.
    for (name, to, heading) in [
        ("behind", DVec3::new(0.3, 0.0, -2.5), None),
        ("beside", DVec3::new(2.5, 0.0, 0.0), None),
        ("ahead, then 45°", DVec3::new(0.0, 0.0, 3.0), Some(45f64)),
        ("ahead, then 90°", DVec3::new(0.0, 0.0, 3.0), Some(90.0)),
        ("ahead, then 180°", DVec3::new(0.0, 0.0, 3.0), Some(180.0)),
        (
            "behind, then 100°",
            DVec3::new(-1.5, 0.0, -2.5),
            Some(100.0),
        ),
        ("where it stands, then 120°", DVec3::ZERO, Some(120.0)),
    ] {
        let heading = heading.map(f64::to_radians);
        let r = run(100.0, ActorDesc::new("a"), 20.0, |s| {
            let options = WalkOptions {
                heading,
                ..WalkOptions::default()
            };
            Walk::to(s, to, options).unwrap()
        });
        assert_eq!(r.status, Status::Completed, "{name}");
        let last = r.frames.last().unwrap();
        let goal = DVec2::new(to.x, to.z);
        assert!((root_floor(&r, last) - goal).length() < 0.05, "{name}");
        if let Some(h) = heading {
            let facing = last.q[r.rig.root[3]];
            assert!(wrap(facing - h).abs() < 0.05, "{name}: faces {facing}");
        }
        assert_feet_planted(&r, name, 0.0067);
    }
}

#[test]
fn sharp_corners_slow_the_walk_so_that_the_feet_stay_planted() {
    // A hairpin, a 135° corner, a zigzag and a square of 1 m sides, asked at a slow, a
    // normal and a fast pace. Before the corners slowed the plan, the body turned at the
    // corner as fast as the route did and the planted feet could not follow: the hairpin
    // slid a sole 0.93 m at 0.6 m/s, the 135° corner 0.19 m at 1.2 m/s, the square
    // 0.40 m at 1.8 m/s, soles down to 23 cm below the floor.
    let p = DVec2::new;
    for (name, points) in [
        ("hairpin", vec![p(0.0, 2.0), p(0.0, 0.0)]),
        (
            "hairpin 0.5 m wide",
            vec![p(0.0, 2.0), p(0.5, 2.0), p(0.5, 0.0)],
        ),
        ("135° corner", vec![p(0.0, 2.0), p(1.5, 0.5)]),
        (
            "zigzag",
            vec![p(0.5, 1.0), p(-0.5, 2.0), p(0.5, 3.0), p(-0.5, 4.0)],
        ),
        (
            "square",
            vec![p(0.0, 1.0), p(1.0, 1.0), p(1.0, 0.0), p(0.0, 0.0)],
        ),
    ] {
        for speed in [0.6, 1.2, 1.8] {
            let r = run(100.0, ActorDesc::new("a"), 30.0, |s| {
                let options = WalkOptions {
                    speed,
                    ..WalkOptions::default()
                };
                Walk::path(s, points.clone(), options).unwrap()
            });
            assert_eq!(r.status, Status::Completed, "{name} at {speed} m/s");
            assert_feet_planted(&r, &format!("{name} at {speed} m/s"), 0.0067);
        }
    }
}

/// Contact of a foot: a sole point within `eps` of the floor.
fn contact(f: &Frame, leg: usize, eps: f64) -> bool {
    f.soles[leg].iter().any(|p| p.y < eps)
}

/// Rising and falling edges of a foot's contact: (strikes, toe-offs) times.
fn contact_edges(r: &Run, leg: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut strikes, mut offs) = (Vec::new(), Vec::new());
    for w in r.frames.windows(2) {
        let (a, b) = (contact(&w[0], leg, 2e-4), contact(&w[1], leg, 2e-4));
        if !a && b {
            strikes.push(w[1].t);
        }
        if a && !b {
            offs.push(w[1].t);
        }
    }
    (strikes, offs)
}

#[test]
fn cycle_and_phase_durations_match_eq_2_5_and_2_6() {
    for rv in [0.5, 1.0, 1.5, 2.0] {
        let mut ht = 0.0;
        let r = run(1000.0, ActorDesc::new("a"), 14.0, |s| {
            let w =
                Walk::velocity(s, Speed::Constant(1.0), Some(1.0), WalkOptions::default()).unwrap();
            ht = w.rig().thigh_height;
            Walk::velocity(s, Speed::Constant(rv * ht), None, WalkOptions::default()).unwrap()
        });
        let v = rv * r.ht;
        let steady = |t: f64| t > 5.0 && t < 13.5;
        let (ls, lo) = contact_edges(&r, 0);
        let (rs, _) = contact_edges(&r, 1);
        let ls: Vec<f64> = ls.into_iter().filter(|t| steady(*t)).collect();
        assert!(ls.len() >= 3, "rv {rv}: too few strikes {ls:?}");
        let dc = (ls[ls.len() - 1] - ls[0]) / (ls.len() - 1) as f64;
        // Cycle length: distance the body travels in one cycle, normalized by Ht.
        let rlc = v * dc / r.ht;
        let want = 1.346 * rv.sqrt();
        assert!(
            (rlc / want - 1.0).abs() < 0.05,
            "rv {rv}: RLc {rlc} vs {want}"
        );
        let model = CycleTimes::from_cycle(dc);
        // Support: from a left strike to the next left toe-off.
        let mut ds = Vec::new();
        let mut dds = Vec::new();
        for &s in &ls {
            if let Some(&off) = lo.iter().find(|&&o| o > s) {
                ds.push(off - s);
                // Double support after the right strike: until the left toe-off.
                if let Some(&rstrike) = rs.iter().find(|&&x| x > s && x < off) {
                    dds.push(off - rstrike);
                }
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        assert!(!ds.is_empty() && !dds.is_empty(), "rv {rv}");
        let (ds, dds) = (mean(&ds), mean(&dds));
        println!("rv {rv}: Dc {dc:.4} RLc {rlc:.4} (eq. 2-5 {want:.4}) Ds {ds:.4} (eq. 2-6 {:.4}) Dds {dds:.4} (eq. 2-6 {:.4})", model.support, model.double_support);
        assert!(
            (ds / model.support - 1.0).abs() < 0.05,
            "rv {rv}: support {ds} vs eq. 2-6 {}",
            model.support
        );
        assert!(
            (dds / model.double_support - 1.0).abs() < 0.05,
            "rv {rv}: double support {dds} vs eq. 2-6 {}",
            model.double_support
        );
    }
}

/// Per step (contact period) and foot, the longest horizontal path a sole point travels
/// while touching the floor (within 1 mm); and the lowest any sole point goes.
fn skating(r: &Run) -> (f64, f64) {
    let mut worst: f64 = 0.0;
    let mut lowest = f64::INFINITY;
    for leg in 0..2 {
        let mut slide = vec![0.0; r.frames[0].soles[leg].len()];
        for w in r.frames.windows(2) {
            for (s, (a, b)) in slide
                .iter_mut()
                .zip(w[0].soles[leg].iter().zip(&w[1].soles[leg]))
            {
                lowest = lowest.min(b.y);
                if a.y < 1e-3 && b.y < 1e-3 {
                    *s += DVec2::new(b.x - a.x, b.z - a.z).length();
                }
            }
            if !contact(&w[1], leg, 1e-3) {
                for s in slide.iter_mut() {
                    worst = worst.max(*s);
                    *s = 0.0;
                }
            }
        }
        worst = worst.max(slide.iter().cloned().fold(0.0, f64::max));
    }
    (worst, lowest)
}

/// Prints `what`'s largest slide and lowest sole point (see [`skating`]) and holds the
/// slide to `bound` (m) and every sole point to at most 1 mm below the floor.
fn assert_feet_planted(r: &Run, what: &str, bound: f64) {
    let (slide, lowest) = skating(r);
    println!(
        "{what}: largest slide {:.2} mm, lowest sole point {:.2} mm, {:.2} s",
        slide * 1e3,
        lowest * 1e3,
        r.frames.last().map_or(0.0, |f| f.t)
    );
    assert!(slide <= bound, "{what}: a planted foot slid {slide} m");
    assert!(
        lowest >= -1e-3,
        "{what}: a foot went {lowest} m below the floor"
    );
}

#[test]
fn planted_feet_do_not_skate_nor_go_below_the_floor() {
    // Straight walks over the speed range, and a path with turns.
    for rv in [0.5, 1.0, 1.5, 2.0] {
        let r = run(200.0, ActorDesc::new("a"), 8.0, |s| {
            let ht = Rig::new(s).unwrap().thigh_height;
            Walk::velocity(
                s,
                Speed::Constant(rv * ht),
                Some(7.0),
                WalkOptions::default(),
            )
            .unwrap()
        });
        assert_feet_planted(&r, &format!("rv {rv}"), 0.01);
    }
    let r = run(200.0, ActorDesc::new("a"), 30.0, |s| {
        let pts = vec![
            DVec2::new(0.0, 2.0),
            DVec2::new(2.0, 3.0),
            DVec2::new(2.5, 0.5),
            DVec2::new(0.0, 0.0),
        ];
        Walk::path(s, pts, WalkOptions::default()).unwrap()
    });
    assert_eq!(r.status, Status::Completed);
    assert_feet_planted(&r, "path", 0.01);
}

#[test]
fn a_speed_change_keeps_joint_values_and_velocities_continuous() {
    let change = 4.0;
    let r = run(100.0, ActorDesc::new("a"), 10.0, |s| {
        let samples: Vec<f64> = (0..900)
            .map(|i| if (i as f64) * 0.01 < change { 1.0 } else { 1.7 })
            .collect();
        Walk::velocity(
            s,
            Speed::Samples(samples),
            Some(9.0),
            WalkOptions::default(),
        )
        .unwrap()
    });
    let dofs = {
        let skel = troupe_body::template::default_skeleton("adult").unwrap();
        Walk::to(&skel, DVec3::new(1.0, 0.0, 0.0), WalkOptions::default())
            .unwrap()
            .dofs()
            .to_vec()
    };
    // Per DOF: largest change of value (≈ velocity) and of velocity (≈ acceleration) per
    // tick inside a window.
    let measure = |from: f64, to: f64| {
        let mut dq: f64 = 0.0;
        let mut ddq: f64 = 0.0;
        for w in r.frames.windows(3) {
            if w[1].t < from || w[1].t > to {
                continue;
            }
            for &d in &dofs {
                let v1 = w[1].q[d] - w[0].q[d];
                let v2 = w[2].q[d] - w[1].q[d];
                dq = dq.max(v2.abs());
                ddq = ddq.max((v2 - v1).abs());
            }
        }
        (dq, ddq)
    };
    let (dq_change, ddq_change) = measure(change - 0.3, change + 1.0);
    let (dq_steady, ddq_steady) = measure(change + 1.5, 8.0);
    println!("speed change: max |Δq| {dq_change:.4} vs steady {dq_steady:.4}; max |Δ²q| {ddq_change:.4} vs steady {ddq_steady:.4}");
    assert!(
        dq_change <= 1.2 * dq_steady,
        "values jump at the change: {dq_change} vs {dq_steady}"
    );
    assert!(
        ddq_change <= 1.2 * ddq_steady,
        "velocities jump at the change: {ddq_change} vs {ddq_steady}"
    );
    // The body's speed follows without a jump.
    let speed: Vec<f64> = r
        .frames
        .windows(2)
        .map(|w| (root_floor(&r, &w[1]) - root_floor(&r, &w[0])).length() / 0.01)
        .collect();
    for w in speed.windows(2) {
        assert!(
            (w[1] - w[0]).abs() < 0.05,
            "speed jumps {} → {}",
            w[0],
            w[1]
        );
    }
}

#[test]
fn bad_input_is_a_clear_error() {
    let s = troupe_body::template::default_skeleton("adult").unwrap();
    let o = WalkOptions::default();
    let err = |r: Result<Walk, ActionError>| r.err().expect("an error").to_string();
    assert!(err(Walk::to(&s, DVec3::new(f64::NAN, 0.0, 1.0), o)).contains("not finite"));
    assert!(err(Walk::to(&s, DVec3::new(1.0, 1.5, 1.0), o)).contains("unreachable"));
    assert!(err(Walk::to(&s, DVec3::new(1e6, 0.0, 1.0), o)).contains("unreachable"));
    for speed in [0.0, -1.0, f64::NAN] {
        let e = err(Walk::to(
            &s,
            DVec3::new(1.0, 0.0, 1.0),
            WalkOptions { speed, ..o },
        ));
        assert!(e.contains("`speed`") && e.contains("> 0"), "{e}");
    }
    assert!(err(Walk::to(
        &s,
        DVec3::new(1.0, 0.0, 1.0),
        WalkOptions { speed: 9.0, ..o }
    ))
    .contains("beyond"));
    assert!(err(Walk::path(&s, vec![], o)).contains("empty"));
    assert!(err(Walk::path(
        &s,
        vec![DVec2::ONE, DVec2::new(0.0, f64::INFINITY)],
        o
    ))
    .contains("path point 2"));
    assert!(err(Walk::to(
        &s,
        DVec3::ONE.with_y(0.0),
        WalkOptions { run: 2.0, ..o }
    ))
    .contains("`run`"));
    let seq = Arc::new(Sequence::new("nothing"));
    assert!(err(Walk::follow(&s, seq, o)).contains("root_x"));
    let samples = vec![1.0, 1.0, f64::NAN];
    assert!(err(Walk::velocity(&s, Speed::Samples(samples), Some(1.0), o)).contains("t = 0.02"));
}

#[test]
fn follows_a_keyframed_global_motion() {
    let mut seq = Sequence::new("global_motion");
    seq.add_track(
        Track::new(
            "root_x",
            vec![Key::new(0.0, 0.0), Key::new(3.0, 1.0), Key::new(6.0, 3.0)],
        )
        .unwrap(),
    )
    .unwrap();
    seq.add_track(
        Track::new(
            "root_z",
            vec![Key::new(0.0, 0.0), Key::new(3.0, 3.0), Key::new(6.0, 4.0)],
        )
        .unwrap(),
    )
    .unwrap();
    let seq = Arc::new(seq);
    let desc = ActorDesc {
        at: DVec3::new(1.0, 0.0, -1.0),
        ..ActorDesc::new("a")
    };
    let r = run(100.0, desc, 12.0, |s| {
        Walk::follow(s, seq.clone(), WalkOptions::default()).unwrap()
    });
    assert_eq!(r.status, Status::Completed);
    // The keyframed path, translated to start where the actor stood.
    let at = root_floor(&r, r.frames.last().unwrap());
    assert!((at - DVec2::new(4.0, 3.0)).length() < 0.05, "{at}");
    // Mid-way it is on the keyframed curve.
    let mid = r.frames.iter().find(|f| (f.t - 3.0).abs() < 1e-6).unwrap();
    assert!((root_floor(&r, mid) - DVec2::new(2.0, 2.0)).length() < 0.08);
    let (slide, _) = skating(&r);
    assert!(slide <= 0.01, "{slide}");
}

#[test]
fn same_result_with_one_and_two_threads() {
    let finals: Vec<Vec<Vec<f64>>> = [1usize, 2]
        .iter()
        .map(|&threads| {
            let mut scene = adult_scene(100.0, threads);
            // One actor per chunk: the three walkers are stepped on both threads.
            scene.set_chunk_size(Some(1));
            for (i, (from, to)) in [
                ((0.0, 0.0), (3.0, 3.0)),
                ((3.0, 0.0), (0.0, 3.0)),
                ((1.5, -1.0), (1.5, 4.0)),
            ]
            .iter()
            .enumerate()
            {
                let a = scene
                    .add_actor(&ActorDesc {
                        at: DVec3::new(from.0, 0.0, from.1),
                        ..ActorDesc::new(format!("a{i}"))
                    })
                    .unwrap();
                let s = scene.actors()[a].skeleton.clone();
                let w = Walk::to(&s, DVec3::new(to.0, 0.0, to.1), WalkOptions::default()).unwrap();
                scene
                    .start_action(a, ActionSpec::new("walk", w.scope()), Box::new(w))
                    .unwrap();
            }
            for _ in 0..500 {
                scene.step();
            }
            scene.states().iter().map(|s| s.q.clone()).collect()
        })
        .collect();
    assert_eq!(finals[0], finals[1]);
}

#[test]
fn the_walk_leaves_head_and_hands_free() {
    let s = troupe_body::template::default_skeleton("adult").unwrap();
    let w = Walk::to(&s, DVec3::new(1.0, 0.0, 1.0), WalkOptions::default()).unwrap();
    let scope = w.scope();
    for free in ["head", "right_hand", "left_hand"] {
        assert!(!scope.overlaps(&s.scope(free).unwrap()), "{free}");
    }
    assert!(scope.contains_all(
        &s.scope("legs-l_ankle-r_ankle")
            .unwrap()
            .intersection(&scope)
    ));
    let no_arms = Walk::to(
        &s,
        DVec3::new(1.0, 0.0, 1.0),
        WalkOptions {
            arms: false,
            ..WalkOptions::default()
        },
    )
    .unwrap();
    assert!(!no_arms.scope().overlaps(&s.scope("arms").unwrap()));
}

#[test]
fn a_walk_to_where_the_actor_stands_finishes_without_stepping() {
    let r = run(100.0, ActorDesc::new("a"), 5.0, |s| {
        Walk::to(s, DVec3::ZERO, WalkOptions::default()).unwrap()
    });
    assert_eq!(r.status, Status::Completed);
    // No foot ever left the floor.
    assert!(r
        .frames
        .iter()
        .all(|f| contact(f, 0, 1e-4) && contact(f, 1, 1e-4)));
    assert!(r.frames.last().unwrap().t < 1.0);
}

/// Adds actor `a` at the origin and `b` 8 m ahead facing it, and starts each walking to
/// where the other stands: the walks' ids.
fn two_walkers_head_on(scene: &mut Scene) -> Vec<troupe_scene::ActionId> {
    let a = scene.add_actor(&ActorDesc::new("a")).unwrap();
    let b = scene
        .add_actor(&ActorDesc {
            at: DVec3::new(0.0, 0.0, 8.0),
            facing_degrees: 180.0,
            ..ActorDesc::new("b")
        })
        .unwrap();
    let skeleton = scene.actors()[a].skeleton.clone();
    let mut ids = Vec::new();
    for (actor, goal) in [(a, DVec2::new(0.0, 8.0)), (b, DVec2::ZERO)] {
        let walk =
            Walk::navigate(&skeleton, Goal::Through(vec![goal]), WalkOptions::default()).unwrap();
        let spec = ActionSpec::new("walk", walk.scope());
        ids.push(scene.start_action(actor, spec, Box::new(walk)).unwrap());
    }
    ids
}

#[test]
fn steered_feet_stay_planted_when_two_walkers_pass_head_on() {
    let mut scene = adult_scene(200.0, 1);
    let ids = two_walkers_head_on(&mut scene);
    let a = 0;
    let skeleton = scene.actors()[a].skeleton.clone();
    let rig = Rig::new(&skeleton).unwrap();
    let feet = soles(&skeleton, &rig);
    let mut frames = Vec::new();
    let mut sideways: f64 = 0.0;
    while scene.time() < 20.0
        && !ids
            .iter()
            .all(|id| scene.action(*id).unwrap().status.is_final())
    {
        scene.step();
        let st = &scene.states()[a];
        sideways = sideways.max(st.globals[0].translation.x.abs());
        frames.push(Frame {
            t: scene.time(),
            q: st.q.clone(),
            soles: [0, 1].map(|leg| {
                feet[leg]
                    .points
                    .iter()
                    .map(|(j, p)| st.globals[*j].transform_point(*p))
                    .collect()
            }),
        });
    }
    for id in &ids {
        assert_eq!(scene.action(*id).unwrap().status, Status::Completed);
    }
    let r = Run {
        frames,
        status: Status::Completed,
        ht: rig.thigh_height,
        rig,
    };
    let (slide, lowest) = skating(&r);
    println!(
        "head-on: sidestep {sideways:.3} m, largest slide {:.2} mm, lowest sole point {:.2} mm",
        slide * 1e3,
        lowest * 1e3
    );
    assert!(sideways > 0.2, "the walkers did not sidestep: {sideways}");
    assert!(slide <= 0.0067, "a planted foot slid {slide} m");
    assert!(lowest >= -1e-3, "a foot went {lowest} m below the floor");
}

/// Two pairs walking abreast meet head-on in a corridor too narrow for four abreast
/// (1.6 m between the walls): neither can step aside, and avoidance alone had them all
/// stand for good. One pair steps back (see [`super::standoff`]) and all four pass,
/// their discs apart. (Their feet are not held to the head-on bound here: squeezed past
/// one another, a foot held in the air jumps to its landing; docs/navigation.md,
/// "Stand-offs".)
#[test]
fn two_pairs_face_to_face_in_a_corridor_step_back_and_pass() {
    use troupe_scene::space::{body_radius, Wall};
    let mut scene = adult_scene(200.0, 1);
    for x in [-0.9, 0.9] {
        scene
            .add_wall(Wall {
                from: DVec2::new(x, -6.0),
                to: DVec2::new(x, 6.0),
                thickness: 0.2,
                height: 2.0,
            })
            .unwrap();
    }
    // (start x, start z, facing, goal x, goal z): the pairs 0.65 m apart, 7 m apart.
    let walkers = [
        (-0.325, -3.5, 0.0, -0.4, 8.0),
        (0.325, -3.5, 0.0, 0.4, 8.0),
        (-0.325, 3.5, 180.0, -0.4, -8.0),
        (0.325, 3.5, 180.0, 0.4, -8.0),
    ];
    let mut ids = Vec::new();
    for (k, &(x, z, facing, gx, gz)) in walkers.iter().enumerate() {
        let a = scene
            .add_actor(&ActorDesc {
                at: DVec3::new(x, 0.0, z),
                facing_degrees: facing,
                ..ActorDesc::new(format!("w{k}"))
            })
            .unwrap();
        let skeleton = scene.actors()[a].skeleton.clone();
        let goal = Goal::Through(vec![DVec2::new(gx, gz)]);
        let walk = Walk::navigate(&skeleton, goal, WalkOptions::default()).unwrap();
        let spec = ActionSpec::new("walk", walk.scope());
        ids.push(scene.start_action(a, spec, Box::new(walk)).unwrap());
    }
    let radius = body_radius(&scene.actors()[0].skeleton);
    // Per walker, the furthest it has come along its way (+z for the first pair, −z for
    // the second), and the most any walker stepped back from there; the least distance
    // between two bodies' centres.
    let mut furthest = [f64::NEG_INFINITY; 4];
    let mut stepped_back: f64 = 0.0;
    let mut closest = f64::INFINITY;
    while scene.time() < 60.0
        && !ids
            .iter()
            .all(|id| scene.action(*id).unwrap().status.is_final())
    {
        scene.step();
        let roots: Vec<DVec2> = (0..4)
            .map(|a| {
                let p = scene.states()[a].globals[0].translation;
                DVec2::new(p.x, p.z)
            })
            .collect();
        for a in 0..4 {
            let along = if a < 2 { roots[a].y } else { -roots[a].y };
            furthest[a] = furthest[a].max(along);
            stepped_back = stepped_back.max(furthest[a] - along);
            for b in a + 1..4 {
                closest = closest.min((roots[a] - roots[b]).length());
            }
        }
    }
    for id in &ids {
        assert_eq!(scene.action(*id).unwrap().status, Status::Completed);
    }
    println!(
        "two pairs in a corridor: all passed by {:.1} s, the most a walker stepped back {stepped_back:.2} m, closest centres {closest:.3} m",
        scene.time()
    );
    assert!(stepped_back > 0.1, "nobody stepped back: {stepped_back}");
    assert!(
        closest >= 2.0 * radius - 0.01,
        "discs overlapped: {closest}"
    );
}

#[test]
fn a_walk_reports_its_plan_ahead_and_its_avoidance_for_drawing() {
    let mut scene = adult_scene(100.0, 1);
    two_walkers_head_on(&mut scene);
    // Nothing is reported before the walks start (on the first step).
    assert!(scene.navigation().is_empty());
    let (a, b) = (0, 1);
    let mut swerved = false;
    let mut first_length = None;
    for _ in 0..400 {
        scene.step();
        let nav = scene.navigation();
        assert_eq!(nav.iter().map(|(i, _)| *i).collect::<Vec<_>>(), vec![a, b]);
        let (_, mine) = &nav[0];
        assert_eq!(mine.goal, DVec2::new(0.0, 8.0));
        assert_eq!(*mine.path.last().unwrap(), mine.goal);
        // The path ahead shrinks as the plan is walked.
        let length: f64 = mine.path.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        assert!(length <= *first_length.get_or_insert(length) + 1e-9);
        let (preferred, chosen) = mine.velocities.expect("a decision every tick");
        swerved |= (preferred - chosen).length() > 0.05;
    }
    assert!(first_length.unwrap() > 7.5, "{first_length:?}");
    assert!(swerved, "avoidance chose another velocity than the plan's");
}

#[test]
fn walks_that_do_not_navigate_go_straight_through_a_table() {
    // A 2 m × 1 m table across the way: a navigated walk goes round its end; one that
    // goes straight (`Walking::Straight`, `troupe bench --navigation off`) through it.
    let widest = |walking: Walking| {
        let mut scene = adult_scene(100.0, 1);
        scene.set_walking(walking);
        let a = scene.add_actor(&ActorDesc::new("a")).unwrap();
        scene
            .add_object(troupe_body::object::Object {
                name: "table".into(),
                shape: troupe_body::Shape::Box {
                    half_extents: DVec3::new(1.0, 0.4, 0.5),
                },
                position: DVec3::new(0.0, 0.4, 3.0),
                rotation: troupe_body::glam::DQuat::IDENTITY,
                mass: 30.0,
            })
            .unwrap();
        let skeleton = scene.actors()[a].skeleton.clone();
        let goal = Goal::Through(vec![DVec2::new(0.0, 6.0)]);
        let walk = Walk::navigate(&skeleton, goal, WalkOptions::default()).unwrap();
        let spec = ActionSpec::new("walk", walk.scope());
        let id = scene.start_action(a, spec, Box::new(walk)).unwrap();
        let mut widest: f64 = 0.0;
        while scene.time() < 20.0 && !scene.action(id).unwrap().status.is_final() {
            scene.step();
            widest = widest.max(scene.states()[a].globals[0].translation.x.abs());
        }
        assert_eq!(scene.action(id).unwrap().status, Status::Completed);
        widest
    };
    let round = widest(Walking::Navigated);
    assert!(round > 1.0 + 0.28, "navigated: {round}");
    let straight = widest(Walking::Straight);
    assert!(straight < 0.1, "straight: {straight}");
}

/// An adult's walk 3 m straight ahead, not started, and its plan: for a foot's steps
/// driven one at a time.
fn adult_walk_ahead() -> (Walk, Plan) {
    let skeleton = troupe_body::template::default_skeleton("adult").unwrap();
    let walk = Walk::to(&skeleton, DVec3::new(0.0, 0.0, 3.0), WalkOptions::default()).unwrap();
    let plan = Plan::new(&walk.route, DVec2::ZERO, 0.0);
    (walk, plan)
}

/// A foot swinging from `from` (rolled onto its toes, 0.05 m lift) to landing `to`.
fn swing(from: DVec3, to: Landing) -> Foot {
    Foot::Swing {
        from,
        from_pitch: -0.5,
        from_yaw: 0.0,
        from_toes: -0.3,
        to,
        lift: 0.05,
        start_rate: 0.5,
        begin: 0.0,
    }
}

#[test]
fn a_swinging_foot_held_for_its_knee_swings_on_from_where_it_was_held() {
    let (mut walk, plan) = adult_walk_ahead();
    let around = Surroundings::default();
    let sigma = 0.6;
    walk.feet[0] = swing(
        DVec3::new(0.1, 0.12, -0.1),
        Landing {
            plant: DVec2::new(0.15, 0.45),
            yaw: 0.2,
            strike: 0.2,
            roll: 0.3,
            pinched: false,
        },
    );
    walk.lambda[0] = 0.66;
    let held = walk.step_foot(&around, &plan, 0, 0.68, sigma);
    walk.poses[0] = held;
    let unheld = walk.step_foot(&around, &plan, 0, 0.70, sigma);
    assert!(walk.hold_foot(0, held, sigma));
    assert_eq!(walk.poses[0].ankle, held.ankle);
    // The swing, rebased, gives the held pose at the phase it was held at ...
    let again = walk.step_foot(&around, &plan, 0, 0.70, sigma);
    assert!(
        (again.ankle - held.ankle).length() < 1e-9,
        "{again:?} {held:?}"
    );
    for (a, b) in [
        (again.yaw, held.yaw),
        (again.pitch, held.pitch),
        (again.toes, held.toes),
    ] {
        assert!((a - b).abs() < 1e-9, "{again:?} {held:?}");
    }
    // ... and moves on from there as a swing does, towards its landing: a tick's move
    // about as long as the unheld swing's (at most half as long again), and the landing
    // reached at the swing's end.
    let next = walk.step_foot(&around, &plan, 0, 0.72, sigma);
    let step = |a: &FootPose, b: &FootPose| (a.ankle - b.ankle).length();
    assert!(step(&next, &held) > 0.0);
    assert!(
        step(&next, &held) <= 1.5 * step(&unheld, &held),
        "{next:?} {unheld:?}"
    );
    let landed = walk.step_foot(&around, &plan, 0, 0.999_999, sigma);
    let target = walk
        .rig
        .ankle_from_plant(0, DVec2::new(0.15, 0.45), 0.2, 0.2);
    assert!((landed.ankle - target).length() < 1e-3, "{landed:?}");
    // A foot flat in its support is not held: it bends no knee forwards.
    walk.feet[1] = Foot::Stance {
        plant: DVec2::ZERO,
        yaw: 0.0,
        rocker: 0.0,
        roll: None,
        next: None,
        stays: false,
    };
    assert!(!walk.hold_foot(1, held, sigma));
}

#[test]
fn a_swinging_foot_held_by_the_clearance_keeps_its_whole_pose() {
    let (mut walk, plan) = adult_walk_ahead();
    let sigma = 0.6;
    let landing = Landing {
        plant: DVec2::new(0.15, 0.45),
        yaw: 0.2,
        strike: 0.2,
        roll: 0.3,
        pinched: false,
    };
    walk.feet[0] = swing(DVec3::new(0.1, 0.12, -0.1), landing);
    walk.lambda[0] = 0.66;
    let open = Surroundings::default();
    let before = walk.step_foot(&open, &plan, 0, 0.68, sigma);
    walk.poses[0] = before;
    // Unheld, the next tick moves the foot on and flattens it from its toes.
    let swinging = walk.feet[0];
    let free = walk.step_foot(&open, &plan, 0, 0.70, sigma);
    (walk.feet[0], walk.lambda[0]) = (swinging, 0.68);
    assert!(
        free.pitch > before.pitch + 1e-3 && free.toes > before.toes,
        "{free:?}"
    );
    // Another's foot lies across the way, 2 cm beyond the toes: the next tick's move
    // would close more than half of that.
    let span = surroundings::foot_span(
        &walk.rig.legs[0],
        DVec2::new(before.ankle.x, before.ankle.z),
        before.yaw,
    );
    let way = (DVec2::new(free.ankle.x, free.ankle.z) - DVec2::new(before.ankle.x, before.ankle.z))
        .normalize();
    let middle = span.toe + way * (2.0 * span.radius + 0.02);
    let across = FootSpan {
        heel: middle - way.perp() * 0.12,
        toe: middle + way.perp() * 0.12,
        radius: span.radius,
    };
    let around = Surroundings {
        feet: vec![across],
        ..Surroundings::default()
    };
    let held = walk.step_foot(&around, &plan, 0, 0.70, sigma);
    // Held whole: where it was, and no flatter (the clearance sees a foot as if flat, so
    // toes flattening where the ankle was held went into what held it).
    assert_eq!(held.ankle, before.ankle);
    assert_eq!(
        (held.yaw, held.pitch, held.toes),
        (before.yaw, before.pitch, before.toes)
    );
    // Once the way is clear it swings on to its landing from there.
    walk.poses[0] = held;
    let on = walk.step_foot(&open, &plan, 0, 0.72, sigma);
    assert!((on.ankle - held.ankle).length() > 1e-3, "{on:?}");
    let landed = walk.step_foot(&open, &plan, 0, 0.999_999, sigma);
    let target = walk
        .rig
        .ankle_from_plant(0, landing.plant, landing.yaw, landing.strike);
    assert!((landed.ankle - target).length() < 1e-3, "{landed:?}");
}

#[test]
fn a_landing_across_a_corner_from_the_body_jumps_round_it_rather_than_staying() {
    let (mut walk, plan) = adult_walk_ahead();
    let lambda = 0.7;
    // Where the body wants the left foot, in the open.
    let fresh = {
        let cycle = walk.cycle(walk.cadence);
        let ahead = 1.0 - lambda + PLACEMENT * cycle.support_fraction();
        let t_mid = walk.t + ahead * cycle.cycle;
        let open = Surroundings::default();
        walk.landing_at(&open, &plan, 0, (t_mid, 0.0), DVec2::new(0.1, -0.3))
    };
    // The plaza, layout 11.1/1.42, at 83.2 s: s2_43's left foot was to land by planter 1's
    // side, across its corner from where the body now wanted it, beside another walker;
    // the landing stayed there while the body went round the corner, and the foot came
    // down 0.22 m into the planter. That scene, turned and moved so that the body's spot
    // is this walk's.
    let (there, there_yaw) = (
        DVec2::new(-3.8947816751207305, -2.6655615501522987),
        -3.0667476739409665,
    );
    let turn = fresh.yaw - there_yaw;
    let (sin, cos) = turn.sin_cos();
    let rotate = |v: DVec2| DVec2::new(v.x * cos + v.y * sin, -v.x * sin + v.y * cos);
    let here = |p: DVec2| fresh.plant + rotate(p - there);
    let planter = Footprint::hull(
        "planter1",
        &[
            here(DVec2::new(-4.75, -4.75)),
            here(DVec2::new(-3.25, -4.75)),
            here(DVec2::new(-3.25, -3.25)),
            here(DVec2::new(-4.75, -3.25)),
        ],
    );
    let walker = Capsule::new(
        here(DVec2::new(-3.2491204366805815, -2.917149769020532)),
        rotate(DVec2::new(-0.9876925467549307, 0.15640790608137242)),
        0.03811298390304806,
        0.28811361059089663,
    );
    let around = Surroundings {
        bodies: vec![walker],
        obstacles: vec![&planter].into(),
        ..Surroundings::default()
    };
    let by_face = here(DVec2::new(-3.103093344958247, -3.3009414295741357));
    walk.feet[0] = swing(
        DVec3::new(0.1, 0.12, -0.3),
        Landing {
            plant: by_face,
            yaw: fresh.yaw,
            strike: 0.26,
            roll: 1.0,
            pinched: false,
        },
    );
    walk.lambda[0] = lambda;
    // A step towards the body's spot goes into the corner, and clearing puts it back.
    let f = fresh.plant;
    let step = RETARGET_SPEED * walk.dt;
    let towards = by_face + (f - by_face).clamp_length_max(step);
    let back_out = walk.cleared(&around, 0, towards, fresh.yaw, 0.0).unwrap();
    assert!(
        (back_out - f).length() > (by_face - f).length() - 0.25 * step,
        "{by_face} {back_out}"
    );
    // So the landing jumps to the body's spot, clear of both.
    walk.follow_steering(&around, &plan, 0, lambda);
    let Foot::Swing { to, .. } = walk.feet[0] else {
        panic!()
    };
    assert!(
        (to.plant - f).length() < 1e-9,
        "{} stayed, not {f}",
        to.plant
    );
    assert_eq!(to.yaw, fresh.yaw);
}
