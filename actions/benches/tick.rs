//! Whole-tick benchmarks: 1,000 actors each playing a full-body keyframe action, and
//! 1,000 actors each running a Lua behavior, with 1 and 2 worker threads.
//! Throughput is reported in actor-ticks per second ("elements").

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use troupe_actions::{action_kinds, Keyframe};
use troupe_body::glam::DVec3;
use troupe_lua::{Director, LuaSessionExt, ScriptLimits};
use troupe_motion::{Key, Sequence, Track};
use troupe_scene::{ActionSpec, ActorDesc, Scene, SceneConfig};

const ACTORS: usize = 1000;

fn full_body_sequence(skeleton: &troupe_body::Skeleton) -> Sequence {
    let mut seq = Sequence::new("full body");
    seq.looping = true;
    for (d, dof) in skeleton.dofs().iter().enumerate().skip(6) {
        let keys = (0..5)
            .map(|k| Key::new(k as f64 * 0.5, ((d + k) as f64 * 0.7).sin() * 0.2))
            .collect();
        seq.add_track(Track::new(dof.name.clone(), keys).unwrap())
            .unwrap();
    }
    seq
}

fn keyframe_scene(threads: usize) -> Scene {
    let mut scene = Scene::new(SceneConfig {
        threads,
        ..SceneConfig::default()
    })
    .unwrap();
    let mut clip = None;
    for i in 0..ACTORS {
        let desc = ActorDesc {
            at: DVec3::new(i as f64, 0.0, 0.0),
            ..ActorDesc::new(format!("a{i}"))
        };
        let a = scene.add_actor(&desc).unwrap();
        let skel = scene.actors()[a].skeleton.clone();
        // The crowd plays one shared clip, as scripts do with troupe.sequence().
        let clip = clip.get_or_insert_with(|| std::sync::Arc::new(full_body_sequence(&skel)));
        let gen = Keyframe::shared(&skel, clip.clone(), None, Some(true)).unwrap();
        let spec = ActionSpec::new("keyframe", gen.scope());
        scene.start_action(a, spec, Box::new(gen)).unwrap();
    }
    scene
}

fn keyframe_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("tick/1000 actors, full-body keyframe + FK");
    group.throughput(Throughput::Elements(ACTORS as u64));
    group.sample_size(20);
    for threads in [1, 2] {
        let mut scene = keyframe_scene(threads);
        group.bench_function(format!("{threads} thread(s)"), |b| {
            b.iter(|| scene.step().len())
        });
    }
    group.finish();
}

const BEHAVIOR: &str = r#"
local seq = troupe.sequence{ r_elbow_flexion = { {0, 0}, {0.3, 1.0}, {0.6, 0} } }
for i = 1, 1000 do
  local a = troupe.actor{ name = "a" .. i, at = { i, 0, 0 } }
  a:behave(function(self)
    wait(math.random() * 0.5)
    while true do
      local act = self:play(seq, { mode = "weighted", weight = 0.5, ease_in = 0.1, ease_out = 0.1 })
      wait(0.2)
      if math.random() < 0.5 then act:cancel() end
      act:wait()
    end
  end)
end
"#;

fn lua_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("tick/1000 actors, Lua behaviors (play, wait, cancel)");
    group.throughput(Throughput::Elements(ACTORS as u64));
    group.sample_size(20);
    for threads in [1, 2] {
        let config = SceneConfig {
            threads,
            ..SceneConfig::default()
        };
        let mut d = Director::session(config, action_kinds(), ScriptLimits::default()).unwrap();
        d.load_str(BEHAVIOR, "bench.lua").unwrap();
        for _ in 0..100 {
            d.tick().unwrap();
        }
        group.bench_function(format!("{threads} thread(s)"), |b| {
            b.iter(|| d.tick().unwrap().len())
        });
    }
    group.finish();

    // The script phase alone (handlers and behavior resumes), per actor-tick.
    let mut group = c.benchmark_group("scripts phase/1000 Lua behaviors");
    group.throughput(Throughput::Elements(ACTORS as u64));
    group.sample_size(20);
    let mut d = Director::session(
        SceneConfig::default(),
        action_kinds(),
        ScriptLimits::default(),
    )
    .unwrap();
    d.load_str(BEHAVIOR, "bench.lua").unwrap();
    for _ in 0..100 {
        d.tick().unwrap();
    }
    group.bench_function("1 thread", |b| {
        b.iter_custom(|iters| {
            d.set_phase_timing(true);
            d.take_phase_times();
            for _ in 0..iters {
                d.tick().unwrap();
            }
            d.take_phase_times().script
        })
    });
    group.finish();
}

criterion_group!(benches, keyframe_tick, lua_tick);
criterion_main!(benches);
