//! The walking motor's cost: one generator step per actor-tick (the motor alone, from a
//! fixed context), and whole ticks of 1,000 actors walking (scheduler, blending and
//! forward kinematics included) with 1 and 2 worker threads.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::sync::Arc;
use troupe_actions::walk::Speed;
use troupe_actions::{Walk, WalkOptions};
use troupe_body::glam::DVec3;
use troupe_body::template::{template, TemplateParams};
use troupe_body::ActorState;
use troupe_scene::Blackboard;
use troupe_scene::{
    ActionSpec, ActorDesc, ActorInfo, DofWriter, Generator, GeneratorContext, Scene, SceneConfig,
    World,
};

const ACTORS: usize = 1000;

fn generator_step(c: &mut Criterion) {
    let t = template("adult").unwrap();
    let params = TemplateParams {
        height: 1.75,
        mass: 70.0,
    };
    let skeleton = Arc::new(t.instantiate(params).unwrap());
    let state = ActorState::new(&skeleton, vec![0.0; skeleton.dof_count()]);
    let actors = vec![ActorInfo {
        name: "a".into(),
        template: "adult".into(),
        params,
        skeleton: skeleton.clone(),
    }];
    let states = vec![state.clone()];
    let world = World {
        time: 0.0,
        actors: &actors,
        states: &states,
        objects: &[],
        holders: &[],
        held: &[],
        board: &Blackboard::default(),
        input_poses: &[],
        space: &Default::default(),
        obstacle_flags: &[],
        crowd: &Default::default(),
        walking: &[],
    };
    let mut walk = Walk::velocity(
        &skeleton,
        Speed::Constant(1.3),
        None,
        WalkOptions::default(),
    )
    .unwrap();
    let scope = walk.scope();
    let mut values = vec![0.0; skeleton.dof_count()];
    let mut tick = 0u64;
    let ctx = |tick: u64| GeneratorContext {
        time: tick as f64 * 0.01,
        dt: 0.01,
        tick,
        local_time: tick as f64 * 0.01,
        actor: 0,
        skeleton: &skeleton,
        posture: &state,
        world: &world,
        scope,
    };
    walk.start(&ctx(0)).unwrap();
    // Into steady walking first (past the start ramp).
    for _ in 0..300 {
        tick += 1;
        let mut out = DofWriter::new(scope, &mut values);
        walk.step(&ctx(tick), &mut out);
    }
    let mut group = c.benchmark_group("walk generator");
    group.throughput(Throughput::Elements(1));
    group.bench_function("step (one actor-tick)", |b| {
        b.iter(|| {
            tick += 1;
            let mut out = DofWriter::new(scope, &mut values);
            walk.step(&ctx(tick), &mut out)
        })
    });
    group.finish();
}

fn walking_crowd(threads: usize) -> Scene {
    let mut scene = Scene::new(SceneConfig {
        threads,
        ..SceneConfig::default()
    })
    .unwrap();
    for i in 0..ACTORS {
        let (x, z) = ((i % 40) as f64 * 2.0, (i / 40) as f64 * 2.0);
        let a = scene
            .add_actor(&ActorDesc {
                at: DVec3::new(x, 0.0, z),
                ..ActorDesc::new(format!("a{i}"))
            })
            .unwrap();
        let skel = scene.actors()[a].skeleton.clone();
        let speed = 1.0 + 0.5 * ((i * 7919) % 100) as f64 / 100.0;
        let w =
            Walk::velocity(&skel, Speed::Constant(speed), None, WalkOptions::default()).unwrap();
        scene
            .start_action(a, ActionSpec::new("walk", w.scope()), Box::new(w))
            .unwrap();
    }
    for _ in 0..150 {
        scene.step();
    }
    scene
}

fn crowd_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("tick/1000 actors walking");
    group.throughput(Throughput::Elements(ACTORS as u64));
    group.sample_size(20);
    for threads in [1, 2] {
        let mut scene = walking_crowd(threads);
        group.bench_function(format!("{threads} thread(s)"), |b| {
            b.iter(|| scene.step().len())
        });
    }
    group.finish();
}

criterion_group!(benches, generator_step, crowd_tick);
criterion_main!(benches);
