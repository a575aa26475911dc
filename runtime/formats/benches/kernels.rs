//! Micro-benchmarks of the runtime's kernels: forward kinematics, Hermite evaluation, BVH
//! parsing and the pyramid blend (the last two on the CMU walk in `../shared/data`).

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::{template, Transform};
use troupe_formats::bvh::parse_bvh;
use troupe_motion::offline::pyramid::pyramid_blend;
use troupe_motion::{Key, Track};

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

/// The CMU walk of the shared test data, if it is beside the repository.
fn cmu_walk() -> Option<(String, String)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/bvh/pybvhrepo_cmu_12_01_walk.bvh"
    );
    match std::fs::read_to_string(path) {
        Ok(text) => Some((path.to_string(), text)),
        Err(e) => {
            eprintln!("skipping the BVH benchmarks: {path}: {e}");
            None
        }
    }
}

fn bvh(c: &mut Criterion) {
    let Some((path, text)) = cmu_walk() else {
        return;
    };
    let frames = parse_bvh(&text, &path).unwrap().frame_count();
    let mut group = c.benchmark_group("bvh");
    group.throughput(Throughput::Bytes(text.len() as u64));
    group.bench_function(
        format!(
            "parse CMU 12_01 walk ({} KB, {frames} frames)",
            text.len() / 1000
        ),
        |b| b.iter(|| parse_bvh(black_box(&text), &path).unwrap()),
    );
    group.finish();
}

fn pyramid(c: &mut Criterion) {
    let Some((path, text)) = cmu_walk() else {
        return;
    };
    let walk = parse_bvh(&text, &path)
        .unwrap()
        .to_channel_sequence("walk", 1.0)
        .unwrap();
    let (start, end) = (walk.start(), walk.end());
    let tracks = walk.tracks().len();
    c.bench_function(
        &format!("pyramid_blend/CMU walk with itself ({tracks} tracks, 1 s transition, 5 levels)"),
        |b| {
            b.iter(|| {
                pyramid_blend(&walk, &walk, black_box(0.5 * (start + end)), 1.0, 5, 0.4).unwrap()
            })
        },
    );
}

criterion_group!(benches, fk, hermite, bvh, pyramid);
criterion_main!(benches);
