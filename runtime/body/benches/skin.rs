//! Skin benchmarks: what the viewer and the CPU pay per actor-frame for a skinned adult.
//! Side by side in one run: the forward kinematics that give the joints' frames, the
//! skinning transforms of the joints alone, those of every slot (the joints and the
//! helper joints, whose frames are computed from the posture: a swing-twist split and two
//! slerps each, and for the sliding helpers at the hips, knees and elbows their move from
//! the joint's centre), and the whole skin deformed on the CPU.
//!
//! Run: `cargo bench -p troupe-body --bench skin`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::{template, Skeleton, Skin, Transform};

fn adult() -> Skeleton {
    let t = template("adult").unwrap();
    t.instantiate(t.default_params()).unwrap()
}

/// A posture with every DOF at a third of the way from its lower to its upper limit, so
/// the shoulders swing and twist (the helpers' work depends on neither's size).
fn posture(s: &Skeleton) -> Vec<f64> {
    s.limits()
        .iter()
        .map(|&(lo, hi)| lo + (hi - lo) / 3.0)
        .collect()
}

fn bench_skin(c: &mut Criterion) {
    let skeleton = adult();
    let skin = Skin::build(&skeleton).expect("the adult's skin builds");
    let q = posture(&skeleton);
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(&skeleton, &q, &mut globals);
    let joints = skeleton.joints().len();
    // The joints' rest frames are the skin's first slots; inverted once, as a viewer
    // without helpers would keep them.
    let rest_inverse: Vec<Transform> = skin.rest[..joints].iter().map(|r| r.inverse()).collect();
    println!(
        "adult: {} joints, {} helpers, {} vertices",
        joints,
        skin.helpers.len(),
        skin.positions.len()
    );

    let mut group = c.benchmark_group("skin");
    group.bench_function("forward kinematics", |b| {
        let mut out = globals.clone();
        b.iter(|| forward_kinematics(&skeleton, black_box(&q), &mut out))
    });
    group.bench_function("skinning transforms, joints only", |b| {
        b.iter(|| {
            black_box(&globals)
                .iter()
                .zip(&rest_inverse)
                .map(|(g, r)| g.mul(r))
                .collect::<Vec<_>>()
        })
    });
    group.bench_function("skinning transforms, joints and helpers", |b| {
        b.iter(|| skin.skinning_transforms(black_box(&globals)))
    });
    group.bench_function("deform on the CPU", |b| {
        b.iter(|| skin.deform(black_box(&globals)))
    });
    group.finish();
}

criterion_group!(benches, bench_skin);
criterion_main!(benches);
