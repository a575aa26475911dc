//! The glove hand through the grasping automaton (thesis 4.7) in a scene: a scripted glove
//! recording closes a performer's hand on a ball (fingers stop at it, the automaton goes
//! FREE → GRASPING → SECURE and attaches it, the ball follows the hand, opening releases
//! it), and a synthetic actor gives a ball to the performer; both bit-identical with 1 and
//! 2 scheduler threads.

use std::path::{Path, PathBuf};
use troupe_actions::grasp::handover::offer_point;
use troupe_actions::grasp::HandState;
use troupe_body::sensors::{HandSensors, Side};
use troupe_drivers::cyberglove::write_glove_script;
use troupe_drivers::performer::SharedPerformers;
use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

fn director(threads: usize) -> (LuaSession, SharedPerformers) {
    let kinds = troupe_actions::action_kinds();
    let config = SceneConfig {
        rate: 100.0,
        threads,
        seed: 0,
    };
    let mut d = Director::session(config, kinds, ScriptLimits::default()).unwrap();
    // One actor per chunk: with two threads, even two actors are stepped on both.
    d.scene_mut().set_chunk_size(Some(1));
    let shared = troupe_drivers::lua::install(&mut d, None)
        .unwrap()
        .performers;
    (d, shared)
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-glove-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn lua_path(p: &Path) -> String {
    format!("{:?}", p.display().to_string())
}

/// Deepest penetration (metres, ≥ 0) of `side`'s hand sensors into `object`.
fn penetration_of(d: &LuaSession, actor: usize, object: usize, side: Side) -> f64 {
    let scene = d.scene();
    let sk = &scene.actors()[actor].skeleton;
    let hs = HandSensors::new(sk, side).unwrap();
    let g = &scene.states()[actor].globals;
    let o = &scene.objects()[object];
    (0..hs.sensors.len())
        .map(|i| -hs.distance_to_object(i, g, o))
        .fold(0.0, f64::max)
}

/// Every posture and object pose of a run, for the thread comparison.
type Trace = Vec<Vec<f64>>;

/// Deepest penetration of the right hand's sensors into `object`.
fn penetration(d: &LuaSession, actor: usize, object: usize) -> f64 {
    penetration_of(d, actor, object, Side::Right)
}

fn snapshot(d: &LuaSession) -> Vec<f64> {
    let mut v: Vec<f64> = d
        .scene()
        .states()
        .iter()
        .flat_map(|s| s.q.clone())
        .collect();
    for o in d.scene().objects() {
        v.extend(o.position.to_array());
        v.extend(o.rotation.to_array());
    }
    v
}

/// Pat's glove hand state, as the capture posted it on the scene's blackboard.
fn state(d: &LuaSession) -> HandState {
    let pat = d.scene().actor_index("pat").unwrap();
    d.scene().blackboard().hand_state(pat).unwrap().1
}

/// A ball put where the performer's open right hand can close on it; the glove closes,
/// the arm lifts, the glove opens.
fn grasp_run(threads: usize, rec: &Path, side: Side) -> Trace {
    let (mut d, _shared) = director(threads);
    let (s, other) = (side.prefix(), side.other().name());
    d.load_str(
        &format!(
            r#"pat = troupe.performer{{ name = "pat", devices = {{ glove = {{ replay = {}, hand = "{}" }} }} }}
               cap = pat:capture{{}}"#,
            lua_path(rec),
            side.name()
        ),
        "performer",
    )
    .unwrap();
    let pat = d.scene().actor_index("pat").unwrap();
    let e = offer_point(&d.scene().world(), pat, Side::Right, 0).unwrap_err();
    assert!(e.to_string().contains("no object"), "{e}");
    // A probe of the ball's shape, far away, gives the point in the open hand.
    d.load_str(
        r#"troupe.object{ name = "probe", shape = "sphere", radius = 0.03, at = {0, 3, 5} }"#,
        "probe",
    )
    .unwrap();
    let probe = d.scene().object_index("probe").unwrap();
    let at = offer_point(&d.scene().world(), pat, side, probe).unwrap();
    d.load_str(
        &format!(
            r#"ball = troupe.object{{ name = "ball", shape = "sphere", radius = 0.03, at = {{{}, {}, {}}} }}"#,
            at.x, at.y, at.z
        ),
        "ball",
    )
    .unwrap();
    let ball = d.scene().object_index("ball").unwrap();
    let sk = d.scene().actors()[pat].skeleton.clone();
    let wrist = sk.joint(&format!("{s}wrist")).unwrap();
    let left: Vec<usize> = sk.scope(&format!("{other}_hand")).unwrap().iter().collect();
    let left0: Vec<f64> = left.iter().map(|&i| d.scene().states()[pat].q[i]).collect();

    let mut trace = Vec::new();
    let mut states = vec![HandState::FreeHand];
    let mut grip: Option<troupe_body::glam::DVec3> = None;
    let mut wrist_travel: f64 = 0.0;
    let mut worst_follow: f64 = 0.0;
    let mut lifted = false;
    let mut released_at = None;
    for tick in 0..700 {
        if tick == 300 {
            // The performer's arm lifts while the hand holds the ball.
            d.load_str(
                &format!(
                    r#"lift = pat:play(troupe.sequence{{ {s}shoulder_flexion = {{ {{0, 0}}, {{1, 0.6}} }},
                                                         {s}elbow_flexion = {{ {{0, 0}}, {{1, 0.5}} }} }})"#
                ),
                "lift",
            )
            .unwrap();
            lifted = true;
        }
        d.tick().unwrap();
        trace.push(snapshot(&d));
        let s = state(&d);
        if *states.last().unwrap() != s {
            states.push(s);
        }
        let pen = penetration_of(&d, pat, ball, side);
        assert!(
            pen <= 0.002,
            "tick {tick}: a sensor is {pen} m inside the ball"
        );
        let w = d.scene().states()[pat].globals[wrist];
        let b = d.scene().objects()[ball].position;
        match d.scene().holder(ball) {
            Some(h) => {
                assert_eq!(h.actor, pat);
                assert!(released_at.is_none(), "grasped again after the release");
                let local = w.inverse().transform_point(b);
                let g0 = *grip.get_or_insert(local);
                worst_follow = worst_follow.max((local - g0).length());
                if lifted {
                    wrist_travel = wrist_travel.max((w.translation - at).length());
                }
            }
            None if grip.is_some() && released_at.is_none() => released_at = Some(tick),
            None => {}
        }
    }
    assert_eq!(
        states,
        vec![
            HandState::FreeHand,
            HandState::GraspingInProgress(ball),
            HandState::SecureGrasp(ball),
            HandState::GraspingInProgress(ball),
            HandState::FreeHand,
        ],
        "the automaton's states over the run"
    );
    assert!(grip.is_some(), "the ball was attached");
    assert!(
        wrist_travel > 0.1,
        "the hand moved while holding: {wrist_travel}"
    );
    assert!(
        worst_follow < 1e-3,
        "the ball followed the hand within 1 mm: {worst_follow}"
    );
    assert!(released_at.is_some(), "opening the glove released the ball");
    let left1: Vec<f64> = left.iter().map(|&i| d.scene().states()[pat].q[i]).collect();
    assert_eq!(left0, left1, "the hand without a glove is untouched");
    trace
}

#[test]
fn glove_closes_on_a_ball_without_penetration_holds_it_and_releases_it() {
    let rec = temp("grasp.rec");
    // Open 1 s, close over 1.5 s, hold 3.5 s (the arm lifts at 3 s), open over 1 s.
    write_glove_script(
        &rec,
        18,
        100.0,
        &[
            (0.0, 0.0),
            (1.0, 0.0),
            (2.5, 1.0),
            (5.0, 1.0),
            (6.0, 0.0),
            (7.0, 0.0),
        ],
    )
    .unwrap();
    let one = grasp_run(1, &rec, Side::Right);
    let two = grasp_run(2, &rec, Side::Right);
    assert!(one == two, "identical with 1 and 2 threads");
}

#[test]
fn a_left_glove_grasps_the_same_way() {
    let rec = temp("grasp-left.rec");
    write_glove_script(
        &rec,
        18,
        100.0,
        &[
            (0.0, 0.0),
            (1.0, 0.0),
            (2.5, 1.0),
            (5.0, 1.0),
            (6.0, 0.0),
            (7.0, 0.0),
        ],
    )
    .unwrap();
    grasp_run(1, &rec, Side::Left);
}

/// Ann grasps a ball and gives it to pat, who holds out a hand and closes the glove.
fn give_run(threads: usize, rec: &Path, close: bool) -> (Trace, String, Option<String>) {
    let (mut d, _shared) = director(threads);
    d.load_str(
        r#"ann = troupe.actor{ name = "ann" }
           ball = troupe.object{ name = "ball", shape = "sphere", radius = 0.03, at = {-0.2, 1.05, 0.38} }
           g = ann:grasp{ object = ball, hand = "right" }"#,
        "ann",
    )
    .unwrap();
    let mut trace = Vec::new();
    for _ in 0..400 {
        d.tick().unwrap();
        let st: String = d.eval("return g.status").unwrap();
        if st == "completed" {
            break;
        }
    }
    let ball = d.scene().object_index("ball").unwrap();
    let ann = d.scene().actor_index("ann").unwrap();
    assert_eq!(
        d.scene().holder(ball).map(|h| h.actor),
        Some(ann),
        "ann holds the ball"
    );
    d.load_str(
        &format!(
            r#"pat = troupe.performer{{ name = "pat", at = {{-0.45, 0, 0.8}}, facing = 180,
                 devices = {{ glove = {{ replay = {}, hand = "right" }} }} }}
               cap = pat:capture{{}}
               arm = pat:play(troupe.sequence{{ r_shoulder_flexion = {{ {{0, 0.7}}, {{12, 0.7}} }},
                                                r_elbow_flexion = {{ {{0, 0.6}}, {{12, 0.6}} }} }})"#,
            lua_path(rec)
        ),
        "pat",
    )
    .unwrap();
    let pat = d.scene().actor_index("pat").unwrap();
    for _ in 0..30 {
        d.tick().unwrap();
    }
    d.load_str(
        r#"give = ann:give{ object = ball, to = pat, timeout = 4 }"#,
        "give",
    )
    .unwrap();
    let mut status = String::new();
    for _ in 0..900 {
        d.tick().unwrap();
        trace.push(snapshot(&d));
        assert!(
            penetration(&d, pat, ball) <= 0.002,
            "no sensor of pat inside the ball"
        );
        status = d.eval("return give.status").unwrap();
        if status == "completed" || status == "failed" {
            break;
        }
    }
    let error: Option<String> = d.eval("return give.error").unwrap();
    if close {
        assert_eq!(status, "completed", "the give completed: {error:?}");
        assert_eq!(
            d.scene().holder(ball).map(|h| h.actor),
            Some(pat),
            "pat holds the ball"
        );
        assert_eq!(state(&d), HandState::SecureGrasp(ball));
        let (name, object): (String, Option<String>) = d
            .eval(r#"return troupe.devices.hand_state(pat, "right")"#)
            .unwrap();
        assert_eq!(
            (name.as_str(), object.as_deref()),
            ("SECURE_GRASP", Some("ball"))
        );
    }
    (trace, status, error)
}

#[test]
fn a_synthetic_actor_gives_a_ball_to_a_performer_who_closes_the_glove() {
    let rec = temp("take.rec");
    // Open while ann brings the ball (1 s carry), then close over 1.5 s and keep closed.
    write_glove_script(
        &rec,
        18,
        100.0,
        &[(0.0, 0.0), (2.0, 0.0), (3.5, 1.0), (12.0, 1.0)],
    )
    .unwrap();
    let (one, _, _) = give_run(1, &rec, true);
    let (two, _, _) = give_run(2, &rec, true);
    assert!(one == two, "identical with 1 and 2 threads");
}

#[test]
fn a_give_to_a_performer_who_never_closes_fails_after_the_timeout() {
    let rec = temp("open.rec");
    write_glove_script(&rec, 18, 100.0, &[(0.0, 0.0), (12.0, 0.0)]).unwrap();
    let (_, status, error) = give_run(1, &rec, false);
    assert_eq!(status, "failed");
    let e = error.unwrap();
    assert!(
        e.contains("`pat` did not take the object within 4 s"),
        "{e}"
    );
}

#[test]
fn glove_scripts_reject_bad_keys() {
    let p = temp("bad.rec");
    let e = write_glove_script(&p, 18, 100.0, &[(1.0, 0.0), (0.5, 1.0)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("increasing"), "{e}");
    let e = write_glove_script(&p, 18, 100.0, &[(0.0, 1.5)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("closure in 0…1"), "{e}");
    let e = write_glove_script(&p, 20, 100.0, &[(0.0, 0.0)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("18 or 22"), "{e}");
}

#[test]
fn a_performer_hands_a_ball_to_a_synthetic_actor_who_receives_it() {
    let rec = temp("handout.rec");
    // Close on the ball over 1.5 s, hold it out, open from 5 s.
    write_glove_script(
        &rec,
        18,
        100.0,
        &[
            (0.0, 0.0),
            (0.5, 0.0),
            (2.0, 1.0),
            (5.0, 1.0),
            (6.0, 0.0),
            (8.0, 0.0),
        ],
    )
    .unwrap();
    let (mut d, _shared) = director(1);
    d.load_str(
        &format!(
            r#"ann = troupe.actor{{ name = "ann" }}
               pat = troupe.performer{{ name = "pat", at = {{-0.45, 0, 0.8}}, facing = 180,
                 devices = {{ glove = {{ replay = {}, hand = "right" }} }} }}
               arm = pat:play(troupe.sequence{{ r_shoulder_flexion = {{ {{0, 0.7}}, {{12, 0.7}} }},
                                                r_elbow_flexion = {{ {{0, 0.6}}, {{12, 0.6}} }} }})
               troupe.object{{ name = "probe", shape = "sphere", radius = 0.03, at = {{0, 3, 5}} }}"#,
            lua_path(&rec)
        ),
        "scene",
    )
    .unwrap();
    // The arm is held out after a tick; then the ball goes into the open hand.
    d.tick().unwrap();
    let pat = d.scene().actor_index("pat").unwrap();
    let ann = d.scene().actor_index("ann").unwrap();
    let probe = d.scene().object_index("probe").unwrap();
    let at = offer_point(&d.scene().world(), pat, Side::Right, probe).unwrap();
    d.load_str(
        &format!(
            r#"ball = troupe.object{{ name = "ball", shape = "sphere", radius = 0.03, at = {{{}, {}, {}}} }}
               cap = pat:capture{{}}"#,
            at.x, at.y, at.z
        ),
        "ball",
    )
    .unwrap();
    let ball = d.scene().object_index("ball").unwrap();
    // A performer does not `give`: the error says how to hand an object over.
    let e = d
        .load_str(r#"pat:give{ object = ball, to = ann }"#, "give")
        .unwrap_err()
        .to_string();
    assert!(e.contains("receiver:receive"), "{e}");
    for _ in 0..250 {
        d.tick().unwrap();
    }
    assert_eq!(
        d.scene().holder(ball).map(|h| h.actor),
        Some(pat),
        "pat holds the ball"
    );
    assert_eq!(state(&d), HandState::SecureGrasp(ball));
    // Ann cannot just grasp it out of pat's hand…
    d.load_str(r#"steal = ann:grasp{ object = ball }"#, "steal")
        .unwrap();
    for _ in 0..5 {
        d.tick().unwrap();
    }
    let steal: String = d.eval("return steal.status").unwrap();
    assert_eq!(steal, "failed", "a plain grasp does not take a held object");
    // …but receives it from pat.
    d.load_str(
        r#"rx = ann:receive{ object = ball, from = pat }"#,
        "receive",
    )
    .unwrap();
    let mut rx = String::new();
    for _ in 0..500 {
        d.tick().unwrap();
        rx = d.eval("return rx.status").unwrap();
        if rx != "active" && rx != "pending" {
            break;
        }
    }
    let error: Option<String> = d.eval("return rx.error").unwrap();
    assert_eq!(rx, "completed", "receive: {error:?}");
    assert_eq!(
        d.scene().holder(ball).map(|h| h.actor),
        Some(ann),
        "ann holds the ball"
    );
    // Pat opens the glove (from 5 s): the hand frees, ann keeps the ball.
    while d.scene().time() < 7.0 {
        d.tick().unwrap();
    }
    assert_eq!(state(&d), HandState::FreeHand);
    assert_eq!(
        d.scene().holder(ball).map(|h| h.actor),
        Some(ann),
        "ann still holds it"
    );
}

/// The glove recording of `scripts/examples/performer_handover.lua` is this script's
/// output (`TROUPE_WRITE_EXAMPLES=1` rewrites it).
#[test]
fn example_glove_recording_is_the_script() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scripts/examples/performer_handover_glove.rec");
    let fresh = temp("example.rec");
    write_glove_script(
        &fresh,
        18,
        100.0,
        &[
            (0.0, 0.0),
            (4.5, 0.0),
            (6.0, 1.0),
            (9.0, 1.0),
            (10.0, 0.0),
            (12.0, 0.0),
        ],
    )
    .unwrap();
    if std::env::var_os("TROUPE_WRITE_EXAMPLES").is_some() {
        std::fs::copy(&fresh, &example).unwrap();
    }
    assert_eq!(
        std::fs::read(&fresh).unwrap(),
        std::fs::read(&example).unwrap(),
        "{} differs from its script (TROUPE_WRITE_EXAMPLES=1 rewrites it)",
        example.display()
    );
}
