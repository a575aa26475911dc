//! Micro-benchmarks of the runtime's kernels: forward kinematics and Hermite evaluation.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use troupe_runtime::kinematics::forward_kinematics;
use troupe_runtime::{template, Key, Track, Transform};

fn fk(c: &mut Criterion) {
    let t = template("adult").unwrap();
    let skeleton = t.instantiate(t.default_params()).unwrap();
    let q: Vec<f64> = (0..skeleton.dof_count())
        .map(|i| (i as f64 * 0.37).sin() * 0.3)
        .collect();
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    c.bench_function("forward_kinematics/adult (107 DOFs, 66 joints)", |b| {
        b.iter(|| forward_kinematics(&skeleton, black_box(&q), &mut globals))
    });
}

fn hermite(c: &mut Criterion) {
    let keys: Vec<Key> = (0..100)
        .map(|i| Key::new(i as f64 * 0.1, (i as f64).sin()))
        .collect();
    let track = Track::new("x", keys).unwrap();
    c.bench_function("hermite/value_at sequential (100 keys)", |b| {
        let mut cursor = 0;
        let mut t = 0.0;
        b.iter(|| {
            t = if t > 9.9 { 0.0 } else { t + 0.01 };
            track.value_at(black_box(t), &mut cursor)
        })
    });
}

criterion_group!(benches, fk, hermite);
criterion_main!(benches);
