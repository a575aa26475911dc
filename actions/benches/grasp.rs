//! Grasp planning time per shape, and the per-tick cost of closing the fingers with the
//! 20 finger sensors (thesis 4.7 reports ~10 interactive frames per second for this).

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use troupe_actions::grasp::automaton::GraspAutomaton;
use troupe_actions::grasp::pattern::HandPattern;
use troupe_actions::grasp::{plan_grasp, GraspType, HandModel, PlanOptions};
use troupe_body::glam::DVec3;
use troupe_body::sensors::{object_distance, Side};
use troupe_body::{Scope, Shape};
use troupe_scene::{ActorDesc, Scene, SceneConfig};

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

fn planning(c: &mut Criterion) {
    let mut group = c.benchmark_group("grasp_plan");
    for (name, shape) in shapes() {
        let mut s = Scene::new(SceneConfig::default()).unwrap();
        s.add_actor(&ActorDesc::new("a")).unwrap();
        let o = s
            .add_object(Scene::object(
                name,
                shape,
                DVec3::new(-0.2, 1.05, 0.38),
                0.3,
            ))
            .unwrap();
        let skel = s.actors()[0].skeleton.clone();
        let opts = PlanOptions::default();
        group.bench_function(name, |b| {
            b.iter(|| {
                let w = s.world();
                black_box(plan_grasp(&skel, &s.states()[0], 0, &w, o, &opts).unwrap())
            })
        });
    }
    group.finish();
}

fn closing(c: &mut Criterion) {
    // The hand at rest with a ball in front of the palm: one tick of closing moves every
    // finger DOF by one pattern step and tests the 20 finger sensors each sub-step.
    let mut s = Scene::new(SceneConfig::default()).unwrap();
    s.add_actor(&ActorDesc::new("a")).unwrap();
    let skel = s.actors()[0].skeleton.clone();
    let model = HandModel::new(&skel, Side::Right).unwrap();
    let st = s.states()[0].clone();
    let w = st.globals[model.sensors.wrist];
    let centre =
        w.transform_point(model.sensors.palm) + w.rotation * model.sensors.palm_normal * 0.07;
    let ball = Scene::object("ball", Shape::Sphere { radius: 0.04 }, centre, 0.2);
    let field = |p| object_distance(&ball, p);
    let pattern = HandPattern::builtin(GraspType::Wrap)
        .bind(&skel, Side::Right, &st.q)
        .unwrap();
    // The steepest tick of the pattern (0.6 s at 100 Hz: s moves by 1/60), where the
    // fingers move most and need the most sub-steps.
    let mut samples = Vec::new();
    let mut start = st.q.clone();
    pattern.sample(0.5 - 1.0 / 60.0, &mut samples);
    for &(d, v) in &samples {
        start[d] = v;
    }
    pattern.sample(0.5, &mut samples);
    c.bench_function("finger_closing_tick_20_sensors", |b| {
        let mut q = st.q.clone();
        let mut g = st.globals.clone();
        b.iter(|| {
            q.copy_from_slice(&start);
            let mut blocked = Scope::EMPTY;
            model.advance(&skel, &mut q, &mut g, &samples, &mut blocked, &field);
            black_box(&q);
        })
    });
    // The automaton with a glove asking for a fist while the ball stops the fingers.
    let want: Vec<(usize, f64)> = model
        .sensors
        .scope
        .iter()
        .map(|d| (d, skel.dofs()[d].max))
        .collect();
    let objects = [ball.clone()];
    c.bench_function("automaton_update_20_sensors", |b| {
        let mut a = GraspAutomaton::new(&skel, Side::Right, &st.q).unwrap();
        b.iter(|| {
            black_box(
                a.update(&skel, &st.q, &st.globals, &want, &objects)
                    .unwrap(),
            )
        })
    });
}

criterion_group!(benches, planning, closing);
criterion_main!(benches);
