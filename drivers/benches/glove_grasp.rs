//! Cost of a whole scene tick with a performer whose glove hand runs the grasping
//! automaton (4.7): the glove closed into a fist around a held ball (the fingers pinned on
//! it: the automaton's worst case), against the same performer with nothing near its hand.

use criterion::{criterion_group, criterion_main, Criterion};
use troupe_actions::grasp::handover::offer_point;
use troupe_body::sensors::Side;
use troupe_drivers::cyberglove::write_glove_script;
use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

fn scene(ball: bool) -> LuaSession {
    let dir = std::env::temp_dir().join(format!("troupe-glove-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rec = dir.join("fist.rec");
    // Closes over 1 s, then stays closed for 10 minutes of scene time.
    write_glove_script(
        &rec,
        18,
        100.0,
        &[(0.0, 0.0), (0.5, 0.0), (1.5, 1.0), (600.0, 1.0)],
    )
    .unwrap();
    let kinds = troupe_actions::action_kinds();
    let mut d = Director::session(SceneConfig::default(), kinds, ScriptLimits::default()).unwrap();
    troupe_drivers::lua::install(&mut d, None).unwrap();
    d.load_str(
        &format!(
            r#"pat = troupe.performer{{ name = "pat", devices = {{ glove = {{ replay = {:?} }} }} }}
               troupe.object{{ name = "probe", shape = "sphere", radius = 0.03, at = {{0, 3, 5}} }}"#,
            rec.display().to_string()
        ),
        "bench",
    )
    .unwrap();
    if ball {
        let pat = d.scene().actor_index("pat").unwrap();
        let probe = d.scene().object_index("probe").unwrap();
        let at = offer_point(&d.scene().world(), pat, Side::Right, probe).unwrap();
        d.load_str(
            &format!(
                r#"troupe.object{{ name = "ball", shape = "sphere", radius = 0.03, at = {{{}, {}, {}}} }}"#,
                at.x, at.y, at.z
            ),
            "ball",
        )
        .unwrap();
    }
    d.load_str("pat:capture{}", "capture").unwrap();
    while d.scene().time() < 2.0 {
        d.tick().unwrap();
    }
    if ball {
        let b = d.scene().object_index("ball").unwrap();
        assert!(d.scene().holder(b).is_some(), "the fist holds the ball");
    }
    d
}

fn bench(c: &mut Criterion) {
    let mut held = scene(true);
    c.bench_function("performer_tick_glove_fist_holding_a_ball", |b| {
        b.iter(|| held.tick().unwrap())
    });
    let mut free = scene(false);
    c.bench_function("performer_tick_glove_fist_nothing_near", |b| {
        b.iter(|| free.tick().unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
