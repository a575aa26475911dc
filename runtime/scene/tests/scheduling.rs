//! Every priority mode and transition of the scheduler, checked tick by tick.

use troupe_body::Scope;
use troupe_scene::blend::ease;
use troupe_scene::{
    ActionId, ActionSpec, ActorDesc, DofWriter, Ending, Generator, GeneratorContext, Mode, Notes,
    Scene, SceneConfig, SignalId, Status, Step,
};

/// Writes one constant value on every DOF of its scope, forever (or fails, or finishes).
struct Constant {
    value: f64,
    finish_after: Option<f64>,
    fail_after: Option<f64>,
}

impl Generator for Constant {
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        if self.fail_after.is_some_and(|t| ctx.local_time >= t) {
            return Step::Failed("the generator gave up".into());
        }
        for d in ctx.scope.iter() {
            out.set(d, self.value);
        }
        if self.finish_after.is_some_and(|t| ctx.local_time >= t) {
            Step::Finished
        } else {
            Step::Running
        }
    }
}

fn constant(value: f64) -> Box<Constant> {
    Box::new(Constant {
        value,
        finish_after: None,
        fail_after: None,
    })
}

/// Writes every DOF of the skeleton, ignoring its scope.
struct Rogue;

impl Generator for Rogue {
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        for d in 0..ctx.skeleton.dof_count() {
            out.set(d, 0.5);
        }
        Step::Running
    }
}

fn scene() -> (Scene, usize) {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    let actor = scene.add_actor(&ActorDesc::new("ann")).unwrap();
    (scene, actor)
}

fn scope(scene: &Scene, expr: &str) -> Scope {
    scene.actors()[0].skeleton.scope(expr).unwrap()
}

fn dof(scene: &Scene, name: &str) -> usize {
    scene.actors()[0].skeleton.dof(name).unwrap()
}

fn spec(scene: &Scene, expr: &str, mode: Mode) -> ActionSpec {
    ActionSpec {
        mode,
        ..ActionSpec::new("test", scope(scene, expr))
    }
}

fn status(scene: &Scene, id: ActionId) -> Status {
    scene.action(id).unwrap().status
}

fn q(scene: &Scene, name: &str) -> f64 {
    scene.states()[0].q[dof(scene, name)]
}

/// Steps until `id` reaches `status`; returns the tick at which it did.
fn run_until(scene: &mut Scene, id: ActionId, status: Status, max: u64) -> u64 {
    for _ in 0..max {
        let events = scene.step().to_vec();
        if events.iter().any(|e| e.action == id && e.status == status) {
            return scene.tick();
        }
    }
    panic!("action {id} never reached {status:?}");
}

#[test]
fn default_waits_for_an_overlapping_action_and_starts_the_tick_after() {
    let (mut s, a) = scene();
    let first = s
        .start_action(
            a,
            ActionSpec {
                duration: Some(0.1),
                ..spec(&s, "right_arm", Mode::Default)
            },
            constant(0.3),
        )
        .unwrap();
    let second = s
        .start_action(a, spec(&s, "r_elbow", Mode::Default), constant(0.6))
        .unwrap();
    s.step();
    assert_eq!(status(&s, first), Status::Active);
    assert_eq!(status(&s, second), Status::Pending);
    let done = run_until(&mut s, first, Status::Completed, 100);
    assert_eq!(status(&s, second), Status::Pending);
    let started = run_until(&mut s, second, Status::Active, 2);
    assert_eq!(started, done + 1);
    assert_eq!(q(&s, "r_elbow_flexion"), 0.6);
    // The first action's DOFs outside the second's scope hold their last value.
    assert_eq!(q(&s, "r_shoulder_flexion"), 0.3);
}

#[test]
fn default_waits_for_earlier_pending_actions_in_order() {
    let (mut s, a) = scene();
    let long = s
        .start_action(
            a,
            ActionSpec {
                duration: Some(0.05),
                ..spec(&s, "right_arm", Mode::Default)
            },
            constant(0.1),
        )
        .unwrap();
    let mid = s
        .start_action(
            a,
            ActionSpec {
                duration: Some(0.05),
                ..spec(&s, "r_wrist", Mode::Default)
            },
            constant(0.2),
        )
        .unwrap();
    let last = s
        .start_action(a, spec(&s, "r_wrist+r_elbow", Mode::Default), constant(0.3))
        .unwrap();
    let t_long = run_until(&mut s, long, Status::Completed, 50);
    let t_mid = run_until(&mut s, mid, Status::Completed, 50);
    assert!(t_mid > t_long);
    assert_eq!(status(&s, last), Status::Pending);
    s.step();
    assert_eq!(status(&s, last), Status::Active);
}

#[test]
fn disjoint_scopes_run_together() {
    let (mut s, a) = scene();
    let left = s
        .start_action(a, spec(&s, "left_arm", Mode::Default), constant(0.2))
        .unwrap();
    let right = s
        .start_action(a, spec(&s, "right_arm", Mode::Default), constant(0.4))
        .unwrap();
    let legs = s
        .start_action(a, spec(&s, "legs", Mode::Exclusive), constant(0.1))
        .unwrap();
    s.step();
    for id in [left, right, legs] {
        assert_eq!(status(&s, id), Status::Active);
    }
    assert_eq!(q(&s, "l_elbow_flexion"), 0.2);
    assert_eq!(q(&s, "r_elbow_flexion"), 0.4);
    assert_eq!(q(&s, "l_knee_flexion"), 0.1);
}

#[test]
fn weighted_actions_blend_by_weight() {
    let (mut s, a) = scene();
    let w = |s: &Scene, weight| ActionSpec {
        weight,
        ..spec(s, "r_elbow_flexion", Mode::Weighted)
    };
    // Alone at weight 0.7: 70 % of the way from the held value (0).
    let one = s.start_action(a, w(&s, 0.7), constant(1.0)).unwrap();
    s.step();
    assert!((q(&s, "r_elbow_flexion") - 0.7).abs() < 1e-12);
    // Two at 0.7 and 0.6 (total ≥ 1): normalised, (0.7·1 + 0.6·2) / 1.3.
    s.start_action(a, w(&s, 0.6), constant(2.0)).unwrap();
    s.step();
    assert!((q(&s, "r_elbow_flexion") - (0.7 + 1.2) / 1.3).abs() < 1e-12);
    assert_eq!(status(&s, one), Status::Active);
}

#[test]
fn ease_in_and_out_follow_the_documented_curve() {
    let (mut s, a) = scene();
    // A weighted action below full weight leaves the held value (0) in place, so the
    // DOF shows weight × ease factor directly.
    let spec = ActionSpec {
        weight: 0.5,
        ease_in: 0.2,
        ease_out: 0.1,
        duration: Some(0.5),
        ..spec(&s, "r_elbow_flexion", Mode::Weighted)
    };
    let id = s.start_action(a, spec, constant(1.0)).unwrap();
    let mut seen = Vec::new();
    for _ in 0..60 {
        s.step();
        seen.push((s.time(), q(&s, "r_elbow_flexion"), status(&s, id)));
    }
    let start = seen[0].0;
    for (t, value, st) in &seen {
        let local = t - start;
        let factor = if local < 0.4 - 1e-9 {
            ease(local / 0.2)
        } else if local < 0.5 - 1e-9 {
            1.0 - ease((local - 0.4) / 0.1)
        } else {
            0.0
        };
        assert!(
            (value - 0.5 * factor).abs() < 1e-9,
            "t={local:.2}: {value} vs {} ({st:?})",
            0.5 * factor
        );
    }
    assert_eq!(seen[0].2, Status::Initiating);
    assert_eq!(seen[25].2, Status::Active);
    assert_eq!(seen[45].2, Status::Terminating);
    assert_eq!(seen[55].2, Status::Completed);
}

#[test]
fn a_full_weight_action_easing_out_comes_to_rest_where_it_was() {
    // The held value follows a fully driven DOF, so a lone action's ease-out fades its
    // still-moving output into the pose it had when the ease-out began.
    struct Ramp;
    impl Generator for Ramp {
        fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
            for d in ctx.scope.iter() {
                out.set(d, ctx.local_time);
            }
            Step::Running
        }
    }
    let (mut s, a) = scene();
    let spec = ActionSpec {
        ease_out: 0.2,
        duration: Some(1.0),
        ..spec(&s, "r_elbow_flexion", Mode::Default)
    };
    let id = s.start_action(a, spec, Box::new(Ramp)).unwrap();
    run_until(&mut s, id, Status::Terminating, 200);
    let at_ease_out = q(&s, "r_elbow_flexion");
    run_until(&mut s, id, Status::Completed, 200);
    let end = q(&s, "r_elbow_flexion");
    assert!((end - at_ease_out).abs() < 1e-12, "{end} vs {at_ease_out}");
    for _ in 0..3 {
        s.step();
        assert_eq!(q(&s, "r_elbow_flexion"), end);
    }
}

#[test]
fn exclusive_preempts_and_the_preempted_action_eases_out_cancelled() {
    let (mut s, a) = scene();
    let base = ActionSpec {
        ease_out: 0.1,
        ..spec(&s, "right_arm", Mode::Default)
    };
    let old = s.start_action(a, base, constant(1.0)).unwrap();
    let other = s
        .start_action(a, spec(&s, "left_arm", Mode::Default), constant(0.5))
        .unwrap();
    for _ in 0..10 {
        s.step();
    }
    let excl = ActionSpec {
        ease_in: 0.1,
        ..spec(&s, "r_elbow", Mode::Exclusive)
    };
    let new = s.start_action(a, excl, constant(2.0)).unwrap();
    s.step();
    assert_eq!(status(&s, new), Status::Initiating);
    assert_eq!(status(&s, old), Status::Terminating);
    assert_eq!(
        status(&s, other),
        Status::Active,
        "disjoint scopes are not pre-empted"
    );
    // Cross-fade: the two weights sum to one, the value moves monotonically from 1 to 2.
    let mut last = q(&s, "r_elbow_flexion");
    for _ in 0..12 {
        s.step();
        let v = q(&s, "r_elbow_flexion");
        assert!(v >= last - 1e-12 && v <= 2.0 + 1e-12);
        last = v;
    }
    assert_eq!(q(&s, "r_elbow_flexion"), 2.0);
    let info = s.action(old).unwrap();
    assert_eq!(info.status, Status::Cancelled);
    assert!(info.reason.unwrap().contains("pre-empted"));
}

#[test]
fn clearing_stops_every_action_of_the_actor() {
    let (mut s, a) = scene();
    let arm = s
        .start_action(a, spec(&s, "right_arm", Mode::Default), constant(1.0))
        .unwrap();
    let leg = s
        .start_action(a, spec(&s, "left_leg", Mode::Weighted), constant(0.3))
        .unwrap();
    s.step();
    let queued = s
        .start_action(a, spec(&s, "right_arm", Mode::Default), constant(0.1))
        .unwrap();
    let clear = s
        .start_action(a, spec(&s, "head", Mode::Clearing), constant(0.2))
        .unwrap();
    s.step();
    for id in [arm, leg, queued] {
        assert_eq!(status(&s, id), Status::Cancelled, "{id}");
    }
    assert_eq!(status(&s, clear), Status::Active);
}

#[test]
fn cancel_pending_and_running() {
    let (mut s, a) = scene();
    let later = s
        .start_action(
            a,
            ActionSpec {
                delay: 1.0,
                ..spec(&s, "left_arm", Mode::Default)
            },
            constant(1.0),
        )
        .unwrap();
    let running = s
        .start_action(
            a,
            ActionSpec {
                ease_out: 0.05,
                ..spec(&s, "right_arm", Mode::Default)
            },
            constant(1.0),
        )
        .unwrap();
    s.step();
    s.cancel(later).unwrap();
    s.cancel(running).unwrap();
    s.step();
    assert_eq!(status(&s, later), Status::Cancelled);
    assert_eq!(status(&s, running), Status::Terminating);
    run_until(&mut s, running, Status::Cancelled, 10);
    assert!(!s.has_unfinished_actions());
}

#[test]
fn delay_postpones_the_start() {
    let (mut s, a) = scene();
    let id = s
        .start_action(
            a,
            ActionSpec {
                delay: 0.25,
                ..spec(&s, "left_arm", Mode::Weighted)
            },
            constant(1.0),
        )
        .unwrap();
    let tick = run_until(&mut s, id, Status::Active, 100);
    assert_eq!(tick, 25);
}

#[test]
fn finished_generator_completes_and_the_dof_holds_its_last_value() {
    let (mut s, a) = scene();
    let gen = Box::new(Constant {
        value: 0.8,
        finish_after: Some(0.1),
        fail_after: None,
    });
    let id = s
        .start_action(a, spec(&s, "r_knee", Mode::Default), gen)
        .unwrap();
    run_until(&mut s, id, Status::Completed, 50);
    for _ in 0..5 {
        s.step();
        assert_eq!(q(&s, "r_knee_flexion"), 0.8);
    }
}

#[test]
fn failing_generator_fails_with_its_reason() {
    let (mut s, a) = scene();
    let gen = Box::new(Constant {
        value: 0.8,
        finish_after: None,
        fail_after: Some(0.05),
    });
    let id = s
        .start_action(a, spec(&s, "r_knee", Mode::Default), gen)
        .unwrap();
    run_until(&mut s, id, Status::Failed, 50);
    assert_eq!(
        s.action(id).unwrap().reason.as_deref(),
        Some("the generator gave up")
    );
}

#[test]
fn an_action_never_changes_a_dof_outside_its_scope() {
    let (mut s, a) = scene();
    let before = s.states()[0].q.clone();
    let arm = scope(&s, "right_arm");
    s.start_action(a, spec(&s, "right_arm", Mode::Exclusive), Box::new(Rogue))
        .unwrap();
    for _ in 0..5 {
        s.step();
    }
    for (d, (b, after)) in before.iter().zip(&s.states()[0].q).enumerate() {
        if arm.contains(d) {
            assert_eq!(
                *after,
                0.5_f64.clamp(
                    s.actors()[0].skeleton.dofs()[d].min,
                    s.actors()[0].skeleton.dofs()[d].max
                )
            );
        } else {
            assert_eq!(b, after, "DOF {d} outside the scope changed");
        }
    }
    assert!(s.refused_writes() > 0);
}

#[test]
fn pose_sets_dofs_and_an_action_takes_over() {
    let (mut s, a) = scene();
    let d = dof(&s, "r_elbow_flexion");
    s.set_dofs(a, &[(d, 1.0)]).unwrap();
    s.step();
    assert_eq!(q(&s, "r_elbow_flexion"), 1.0, "undriven DOFs hold");
    s.start_action(a, spec(&s, "r_elbow_flexion", Mode::Default), constant(0.2))
        .unwrap();
    s.step();
    assert_eq!(q(&s, "r_elbow_flexion"), 0.2);
    // Values are clamped to the limits.
    s.set_dofs(a, &[(d, 99.0)]).unwrap();
    assert_eq!(
        q(&s, "r_elbow_flexion"),
        s.actors()[0].skeleton.dofs()[d].max
    );
}

#[test]
fn bad_input_gives_clear_errors() {
    let (mut s, a) = scene();
    let skel = s.actors()[0].skeleton.clone();
    assert!(matches!(
        skel.scope("right_wing"),
        Err(troupe_body::Error::UnknownScope { .. })
    ));
    assert!(matches!(
        skel.dof("r_elbow_twist"),
        Err(troupe_body::Error::UnknownDof { .. })
    ));
    assert!(matches!(
        skel.joint("r_antenna"),
        Err(troupe_body::Error::UnknownJoint { .. })
    ));
    let base = spec(&s, "right_arm", Mode::Weighted);
    let cases = [
        (
            ActionSpec {
                weight: 1.5,
                ..base.clone()
            },
            "weight",
        ),
        (
            ActionSpec {
                weight: -0.1,
                ..base.clone()
            },
            "weight",
        ),
        (
            ActionSpec {
                weight: f64::NAN,
                ..base.clone()
            },
            "weight",
        ),
        (
            ActionSpec {
                duration: Some(-1.0),
                ..base.clone()
            },
            "duration",
        ),
        (
            ActionSpec {
                delay: -1.0,
                ..base.clone()
            },
            "delay",
        ),
        (
            ActionSpec {
                ease_in: -0.5,
                ..base.clone()
            },
            "ease_in",
        ),
        (
            ActionSpec {
                duration: Some(1.0),
                ease_in: 0.8,
                ease_out: 0.8,
                ..base.clone()
            },
            "ease_in + ease_out",
        ),
        (
            ActionSpec {
                scope: Scope::EMPTY,
                ..base.clone()
            },
            "scope",
        ),
    ];
    for (bad, needle) in cases {
        let err = s
            .start_action(a, bad, constant(0.0))
            .unwrap_err()
            .to_string();
        assert!(err.contains(needle), "{err}");
    }
    assert!(s.start_action(7, base, constant(0.0)).is_err());
    assert!(Mode::parse("polite").is_err());
    assert!(s
        .add_actor(&ActorDesc {
            template: "robot".into(),
            ..ActorDesc::new("bob")
        })
        .is_err());
    assert!(
        s.add_actor(&ActorDesc::new("ann")).is_err(),
        "duplicate name"
    );
    assert!(s
        .add_actor(&ActorDesc {
            height: Some(-2.0),
            ..ActorDesc::new("tiny")
        })
        .is_err());
}

#[test]
fn ended_actions_are_forgotten_unless_kept() {
    let (mut s, a) = scene();
    let spec = ActionSpec {
        duration: Some(0.05),
        ..spec(&s, "r_knee", Mode::Weighted)
    };
    let kept = s.start_action(a, spec.clone(), constant(0.1)).unwrap();
    let dropped = s.start_action(a, spec, constant(0.2)).unwrap();
    for _ in 0..20 {
        s.step();
    }
    assert_eq!(status(&s, kept), Status::Completed);
    assert_eq!(
        s.forget_ended_actions(0.0, |_| false),
        0,
        "nothing ended before t = 0"
    );
    assert_eq!(s.forget_ended_actions(s.time(), |id| id == kept), 1);
    assert!(s.action(dropped).is_none());
    assert_eq!(status(&s, kept), Status::Completed);
}

#[test]
fn the_worked_example_of_docs_scheduling_md() {
    let (mut s, a) = scene();
    let at = |s: &mut Scene, tick: u64| {
        while s.tick() < tick {
            s.step();
        }
        q(s, "r_elbow_flexion")
    };
    at(&mut s, 99); // created at t = 0.99 s, admitted on the tick at t = 1 s
    let wave = ActionSpec {
        weight: 0.6,
        ease_in: 0.5,
        ease_out: 0.5,
        ..spec(&s, "right_arm", Mode::Weighted)
    };
    let wave = s.start_action(a, wave, constant(1.2)).unwrap();
    assert!((at(&mut s, 125) - 0.36).abs() < 1e-9);
    assert!((at(&mut s, 150) - 0.72).abs() < 1e-9);
    at(&mut s, 199);
    let excl = ActionSpec {
        ease_in: 0.5,
        ..spec(&s, "right_arm", Mode::Exclusive)
    };
    s.start_action(a, excl, constant(0.4)).unwrap();
    assert!((at(&mut s, 225) - 0.56).abs() < 1e-9);
    assert!((at(&mut s, 250) - 0.4).abs() < 1e-9);
    let info = s.action(wave).unwrap();
    assert_eq!(info.status, Status::Cancelled);
    assert_eq!(info.reason.as_deref(), Some("pre-empted by action #2"));
}

/// Raises `raise` at its local time `at`, then finishes `steps_after` ticks later; raises
/// `ended` when its action ends (however it ends).
struct Signaller {
    raise: SignalId,
    at: f64,
    ended: SignalId,
    finish_after: Option<f64>,
}

impl Generator for Signaller {
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        if ctx.local_time >= self.at - 1e-9 {
            out.raise(self.raise);
        }
        match self.finish_after {
            Some(t) if ctx.local_time >= t - 1e-9 => Step::Finished,
            _ => Step::Running,
        }
    }

    fn end(&mut self, _ending: &Ending, notes: &mut Notes) {
        notes.raise(self.ended);
    }
}

/// The first tick at which the world shows each signal, read as a generator would.
fn first_seen(scene: &mut Scene, signals: &[SignalId], ticks: u64) -> Vec<Option<u64>> {
    let mut seen = vec![None; signals.len()];
    for _ in 0..ticks {
        scene.step();
        // What a generator of the next tick reads.
        let next = scene.tick() + 1;
        for (s, slot) in signals.iter().zip(seen.iter_mut()) {
            if slot.is_none() && scene.blackboard().before(*s, next) {
                *slot = Some(next);
            }
        }
    }
    seen
}

#[test]
fn a_signal_is_seen_the_tick_after_it_is_raised_and_an_end_the_tick_after_the_last_run() {
    let (mut s, a) = scene();
    let (raised, ended) = (s.new_signal(), s.new_signal());
    let gen = Signaller {
        raise: raised,
        at: 0.05,
        ended,
        finish_after: Some(0.1),
    };
    // Admitted and first stepped at tick 1 (local time 0): raises at tick 6, finishes
    // (last step) at tick 11 and, without ease-out, ends in that tick.
    let id = s
        .start_action(a, spec(&s, "right_arm", Mode::Weighted), Box::new(gen))
        .unwrap();
    let seen = first_seen(&mut s, &[raised, ended], 20);
    assert_eq!(status(&s, id), Status::Completed);
    assert_eq!(seen[0], Some(7), "raised at tick 6, seen from tick 7");
    assert_eq!(
        seen[1],
        Some(13),
        "last ran at tick 11: stamped 12, seen from 13 (as the Drop stamps were)"
    );
}

#[test]
fn an_action_that_never_ran_ends_at_once_for_its_partners() {
    let (mut s, a) = scene();
    let ended = s.new_signal();
    let gen = Signaller {
        raise: s.new_signal(),
        at: 1.0,
        ended,
        finish_after: None,
    };
    let mut pending = spec(&s, "right_arm", Mode::Weighted);
    pending.delay = 1.0;
    let id = s.start_action(a, pending, Box::new(gen)).unwrap();
    s.step();
    s.cancel(id).unwrap();
    let seen = first_seen(&mut s, &[ended], 5);
    assert_eq!(status(&s, id), Status::Cancelled);
    assert_eq!(
        seen[0],
        Some(3),
        "cancelled while pending at tick 2, seen from 3"
    );
    // An action refused outright ends before it began: its partners learn it next tick.
    let refused = s.new_signal();
    let bad = Signaller {
        raise: s.new_signal(),
        at: 0.0,
        ended: refused,
        finish_after: None,
    };
    assert!(s
        .start_action(7, spec(&s, "right_arm", Mode::Weighted), Box::new(bad))
        .is_err());
    assert!(s.blackboard().before(refused, s.tick() + 1));
}

/// Writes a constant on its scope; once asked to stop, keeps going for `wind` seconds at
/// full weight, then finishes (a walk slowing down).
struct WindsDown {
    value: f64,
    wind: f64,
    stopping_since: Option<f64>,
    asked: bool,
}

impl Generator for WindsDown {
    fn stop(&mut self) -> bool {
        self.asked = true;
        true
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        // Writes its whole original scope: the scheduler drops what it gave up.
        for d in ctx.skeleton.scope("right_arm+left_arm").unwrap().iter() {
            out.set(d, self.value);
        }
        if self.asked {
            let since = *self.stopping_since.get_or_insert(ctx.local_time);
            if ctx.local_time - since >= self.wind - 1e-9 {
                return Step::Finished;
            }
        }
        Step::Running
    }
}

fn winds_down(value: f64, wind: f64) -> Box<WindsDown> {
    Box::new(WindsDown {
        value,
        wind,
        stopping_since: None,
        asked: false,
    })
}

/// Both arms, the left one yieldable.
fn yielding_spec(s: &Scene) -> ActionSpec {
    ActionSpec {
        yields: scope(s, "left_arm"),
        ..spec(s, "right_arm+left_arm", Mode::Default)
    }
}

/// A walk-like action on both arms, the left one yieldable, that takes back (or not) what
/// it yields.
fn walk_taking_back(s: &mut Scene, a: usize, takes_back: bool) -> ActionId {
    let spec = ActionSpec {
        takes_back,
        ..yielding_spec(s)
    };
    s.start_action(a, spec, constant(0.3)).unwrap()
}

/// A 0.1 s action on the left elbow.
fn short_wave(s: &mut Scene, a: usize) -> ActionId {
    let spec = ActionSpec {
        duration: Some(0.1),
        ..spec(s, "l_elbow", Mode::Default)
    };
    s.start_action(a, spec, constant(1.0)).unwrap()
}

#[test]
fn a_yielded_part_comes_back_eased_in_when_its_taker_ends_if_the_action_takes_back() {
    for takes_back in [true, false] {
        let (mut s, a) = scene();
        let walk = walk_taking_back(&mut s, a, takes_back);
        s.step();
        let wave = short_wave(&mut s, a);
        s.step();
        assert_eq!(s.action(walk).unwrap().yielded, scope(&s, "l_elbow"));
        assert_eq!(q(&s, "l_elbow_flexion"), 1.0);
        run_until(&mut s, wave, Status::Completed, 20);
        s.step();
        let info = s.action(walk).unwrap();
        if !takes_back {
            assert_eq!(info.yielded, scope(&s, "l_elbow"), "lost for good");
            for _ in 0..40 {
                s.step();
                assert_eq!(q(&s, "l_elbow_flexion"), 1.0, "held where the wave left it");
            }
            continue;
        }
        assert!(info.yielded.is_empty(), "back in its scope");
        assert!(info.scope.contains(dof(&s, "l_elbow_flexion")));
        // Eased in over TAKE_BACK_EASE from where the wave left it, never jumping.
        let mut last = q(&s, "l_elbow_flexion");
        assert!(last > 0.99, "starts from the wave's posture: {last}");
        let ticks = (troupe_scene::scheduler::TAKE_BACK_EASE / s.dt()).round() as usize;
        for _ in 0..ticks {
            s.step();
            let now = q(&s, "l_elbow_flexion");
            assert!(now <= last && last - now < 0.1, "{last} → {now}");
            last = now;
        }
        assert!(
            (last - 0.3).abs() < 1e-12,
            "the walk's own value once eased in: {last}"
        );
        assert_eq!(s.refused_writes(), 0);
    }
}

/// Holds still; its purpose is done (see [`Generator::unfinished`]) after `done_after`
/// seconds of running.
struct Purpose {
    done_after: f64,
    done: bool,
}

impl Generator for Purpose {
    fn unfinished(&self) -> Option<String> {
        (!self.done).then(|| "stopped before it was done".to_string())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        self.done |= ctx.local_time >= self.done_after;
        for d in ctx.scope.iter() {
            out.set(d, 0.2);
        }
        Step::Running
    }
}

#[test]
fn a_stop_that_leaves_the_purpose_undone_cancels_unless_it_is_done_by_the_end_of_the_ease_out() {
    // (done after, expected ending, reason)
    for (done_after, ending, reason) in [
        (10.0, Status::Cancelled, Some("stopped before it was done")),
        (0.15, Status::Completed, None),
        (0.0, Status::Completed, None),
    ] {
        let (mut s, a) = scene();
        let id = s
            .start_action(
                a,
                ActionSpec {
                    ease_out: 0.2,
                    ..spec(&s, "r_elbow", Mode::Default)
                },
                Box::new(Purpose {
                    done_after,
                    done: false,
                }),
            )
            .unwrap();
        for _ in 0..5 {
            s.step();
        }
        s.stop(id).unwrap();
        let info = loop {
            s.step();
            let info = s.action(id).unwrap();
            if info.status.is_final() {
                break info;
            }
        };
        assert_eq!(info.status, ending, "done after {done_after}");
        assert_eq!(info.reason.as_deref(), reason, "done after {done_after}");
    }
}

#[test]
fn a_part_given_up_on_admission_comes_back_though_a_later_action_waits_behind() {
    let (mut s, a) = scene();
    // A wave on the elbow runs when the walk is admitted: the walk gives it up at once.
    let wave = short_wave(&mut s, a);
    s.step();
    let walk = walk_taking_back(&mut s, a, true);
    // Queued behind the walk, on its essential part (the right elbow) and on the part it
    // gave up: pending until the walk ends, and no holder of that part meanwhile.
    let next = s
        .start_action(a, spec(&s, "l_elbow+r_elbow", Mode::Default), constant(0.6))
        .unwrap();
    s.step();
    assert_eq!(s.action(walk).unwrap().yielded, scope(&s, "l_elbow"));
    run_until(&mut s, wave, Status::Completed, 20);
    s.step();
    assert_eq!(status(&s, next), Status::Pending);
    assert!(
        s.action(walk).unwrap().yielded.is_empty(),
        "the elbow came back though an action waits behind the walk"
    );
}

#[test]
fn a_yielded_part_another_action_took_meanwhile_comes_back_when_that_one_ends() {
    let (mut s, a) = scene();
    let walk = walk_taking_back(&mut s, a, true);
    s.step();
    let first = s
        .start_action(a, spec(&s, "l_elbow", Mode::Default), constant(1.0))
        .unwrap();
    s.step();
    // A second, exclusive, pre-empts the first on the elbow the walk lent it.
    let second = s
        .start_action(
            a,
            ActionSpec {
                duration: Some(0.2),
                ..spec(&s, "l_elbow", Mode::Exclusive)
            },
            constant(0.7),
        )
        .unwrap();
    run_until(&mut s, first, Status::Cancelled, 5);
    s.step();
    assert_eq!(
        s.action(walk).unwrap().yielded,
        scope(&s, "l_elbow"),
        "the second holds it"
    );
    assert_eq!(q(&s, "l_elbow_flexion"), 0.7);
    run_until(&mut s, second, Status::Completed, 30);
    s.step();
    assert!(
        s.action(walk).unwrap().yielded.is_empty(),
        "then it comes back"
    );
}

#[test]
fn every_mode_against_a_yieldable_part() {
    // (mode, whether A keeps running, whether A is narrowed)
    for (mode, keeps, narrowed) in [
        (Mode::Default, true, true),
        (Mode::Weighted, true, false),
        (Mode::Exclusive, true, true),
        (Mode::Clearing, false, true),
    ] {
        let (mut s, a) = scene();
        let walk = s
            .start_action(a, yielding_spec(&s), winds_down(0.3, 0.05))
            .unwrap();
        s.step();
        let b = s
            .start_action(a, spec(&s, "l_elbow", mode), constant(1.0))
            .unwrap();
        let events = s.step().to_vec();
        assert!(status(&s, b).is_running(), "{mode:?}: B starts at once");
        let info = s.action(walk).unwrap();
        let expected = if keeps {
            Status::Active
        } else {
            Status::Terminating
        };
        assert_eq!(info.status, expected, "{mode:?}");
        let narrow_events = events.iter().filter(|e| e.narrowed.is_some()).count();
        if narrowed {
            assert_eq!(info.yielded, scope(&s, "l_elbow"), "{mode:?}");
            assert_eq!(q(&s, "l_elbow_flexion"), 1.0, "{mode:?}: B alone drives it");
            assert_eq!(
                narrow_events,
                usize::from(keeps),
                "{mode:?}: reported when it goes on"
            );
        } else {
            assert!(info.yielded.is_empty(), "{mode:?}");
            assert!(
                (q(&s, "l_elbow_flexion") - 0.65).abs() < 1e-12,
                "{mode:?}: blends"
            );
        }
        assert_eq!(
            q(&s, "r_elbow_flexion"),
            0.3,
            "{mode:?}: A still drives the rest"
        );
        // A clearing action takes all of a winding-down A's overlap but lets it finish.
        if !keeps {
            let end = run_until(&mut s, walk, Status::Cancelled, 20);
            assert!(end >= 4, "wound down over 0.05 s at full weight, not cut");
        }
        assert_eq!(
            s.refused_writes(),
            0,
            "{mode:?}: yielded writes are not refused"
        );
    }
}

#[test]
fn an_action_that_needs_an_essential_part_waits_or_stops_it() {
    let (mut s, a) = scene();
    let walk = s
        .start_action(a, yielding_spec(&s), winds_down(0.3, 0.05))
        .unwrap();
    s.step();
    let waits = s
        .start_action(a, spec(&s, "r_elbow", Mode::Default), constant(1.0))
        .unwrap();
    s.step();
    assert_eq!(status(&s, waits), Status::Pending);
    s.cancel(waits).unwrap();
    let takes = s
        .start_action(a, spec(&s, "r_elbow", Mode::Exclusive), constant(1.0))
        .unwrap();
    s.step();
    assert!(status(&s, takes).is_running());
    let info = s.action(walk).unwrap();
    assert_eq!(info.status, Status::Terminating, "winds down");
    assert_eq!(
        info.yielded,
        scope(&s, "r_elbow"),
        "gives the overlap up at once"
    );
    assert_eq!(q(&s, "r_elbow_flexion"), 1.0);
    assert_eq!(
        q(&s, "l_elbow_flexion"),
        0.3,
        "and keeps the rest until it has finished"
    );
    run_until(&mut s, walk, Status::Cancelled, 20);
    assert!(s
        .action(walk)
        .unwrap()
        .reason
        .unwrap()
        .contains("pre-empted"));
}

#[test]
fn a_yielded_dof_fades_out_over_the_ease_out_while_the_taker_comes_in() {
    let (mut s, a) = scene();
    let yielding = ActionSpec {
        ease_out: 0.1,
        ..yielding_spec(&s)
    };
    s.start_action(a, yielding, constant(0.4)).unwrap();
    s.step();
    s.start_action(a, spec(&s, "l_elbow", Mode::Default), constant(1.0))
        .unwrap();
    s.step();
    // Admitted at t = 0.02: the yielded DOF's weight is 1 − ease(0) = 1 → the average.
    assert!((q(&s, "l_elbow_flexion") - 0.7).abs() < 1e-12);
    s.step();
    let f = 1.0 - ease(0.1);
    let want = (1.0 + f * 0.4) / (1.0 + f);
    assert!((q(&s, "l_elbow_flexion") - want).abs() < 1e-12);
    for _ in 0..10 {
        s.step();
    }
    assert_eq!(q(&s, "l_elbow_flexion"), 1.0, "faded out");
}

#[test]
fn stop_winds_down_at_full_weight_and_completes_or_eases_out() {
    let (mut s, a) = scene();
    let graceful = s
        .start_action(
            a,
            spec(&s, "right_arm", Mode::Default),
            winds_down(0.3, 0.05),
        )
        .unwrap();
    let plain = s
        .start_action(
            a,
            ActionSpec {
                ease_out: 0.1,
                ..spec(&s, "left_arm", Mode::Default)
            },
            constant(0.6),
        )
        .unwrap();
    s.step();
    s.stop(graceful).unwrap();
    s.stop(plain).unwrap();
    s.step();
    assert_eq!(status(&s, graceful), Status::Terminating);
    assert_eq!(
        q(&s, "r_elbow_flexion"),
        0.3,
        "full weight while winding down"
    );
    assert_eq!(status(&s, plain), Status::Terminating);
    run_until(&mut s, graceful, Status::Completed, 20);
    run_until(&mut s, plain, Status::Completed, 20);
    assert_eq!(s.action(graceful).unwrap().reason, None);
    let pending = s
        .start_action(
            a,
            ActionSpec {
                delay: 1.0,
                ..spec(&s, "right_arm", Mode::Default)
            },
            constant(0.1),
        )
        .unwrap();
    s.stop(pending).unwrap();
    s.step();
    assert_eq!(status(&s, pending), Status::Cancelled);
}

#[test]
fn narrowing_is_the_same_on_one_and_two_threads() {
    let run = |threads: usize| {
        let mut s = Scene::new(SceneConfig {
            threads,
            ..SceneConfig::default()
        })
        .unwrap();
        s.set_chunk_size(Some(1));
        let mut actors = Vec::new();
        for i in 0..4 {
            actors.push(s.add_actor(&ActorDesc::new(format!("a{i}"))).unwrap());
        }
        for (k, &a) in actors.iter().enumerate() {
            let spec = ActionSpec {
                ease_out: 0.05 * k as f64,
                ..yielding_spec(&s)
            };
            s.start_action(a, spec, winds_down(0.1 * k as f64, 0.03))
                .unwrap();
        }
        let mut trace = Vec::new();
        for t in 0..40 {
            if t == 5 {
                for (k, &a) in actors.iter().enumerate() {
                    let mode = [
                        Mode::Default,
                        Mode::Exclusive,
                        Mode::Clearing,
                        Mode::Weighted,
                    ][k];
                    s.start_action(a, spec(&s, "l_elbow", mode), constant(0.9))
                        .unwrap();
                }
            }
            s.step();
            for st in s.states() {
                trace.extend(st.q.iter().map(|v| v.to_bits()));
            }
        }
        trace
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn a_narrowing_is_an_event_and_an_instant_in_the_timeline() {
    let (mut s, a) = scene();
    let mut timeline = troupe_scene::timeline::TimelineRecorder::new();
    let walk = s
        .start_action(a, yielding_spec(&s), winds_down(0.3, 0.05))
        .unwrap();
    let events = s.step().to_vec();
    timeline.record(&s, &events);
    s.start_action(a, spec(&s, "left_arm", Mode::Default), constant(1.0))
        .unwrap();
    let events = s.step().to_vec();
    timeline.record(&s, &events);
    let narrowed: Vec<_> = events.iter().filter(|e| e.narrowed.is_some()).collect();
    assert_eq!(narrowed.len(), 1);
    assert_eq!(narrowed[0].action, walk);
    assert_eq!(
        narrowed[0].status,
        Status::Active,
        "its status is unchanged"
    );
    assert_eq!(narrowed[0].narrowed, Some(scope(&s, "left_arm")));
    let trace = timeline.to_json(&s);
    let instants: Vec<_> = trace["traceEvents"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["ph"] == "i")
        .collect();
    assert_eq!(instants.len(), 1);
    assert_eq!(instants[0]["name"], "test narrowed");
    assert_eq!(instants[0]["args"]["yielded"], "left_arm");
    assert_eq!(instants[0]["args"]["action"], walk.0);
}
