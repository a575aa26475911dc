//! Measures the sequence pipeline on the CMU walk (run with `--release`):
//! BVH import + FK over every frame (MB/s, frames/s), spline and pyramid compression
//! (time per DOF-second), weighted and pyramid blends.
//!
//! `cargo run --release -p troupe-formats --example seq_perf [FILE.bvh]`

use std::time::Instant;
use troupe_body::Transform;
use troupe_formats::bvh::parse_bvh;
use troupe_motion::offline::blend::blend;
use troupe_motion::offline::compress::{compress_pyramid, compress_spline, SplineOptions};
use troupe_motion::offline::pyramid::{pyramid_blend, DEFAULT_A};

fn main() {
    let path = std::env::args().nth(1).unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/bvh/pybvhrepo_cmu_12_01_walk.bvh"
        )
        .into()
    });
    let text = std::fs::read_to_string(&path).expect("read the BVH file");
    let mb = text.len() as f64 / 1e6;

    // Import + FK of every frame, repeated.
    let reps = 50;
    let start = Instant::now();
    let mut frames = 0usize;
    let mut check = 0.0;
    for _ in 0..reps {
        let b = parse_bvh(&text, &path).expect("parse");
        let mut g = vec![Transform::IDENTITY; b.joints().len()];
        for k in 0..b.frame_count() {
            b.global_transforms(k, &mut g);
            check += g[g.len() - 1].translation.x;
        }
        frames += b.frame_count();
    }
    let s = start.elapsed().as_secs_f64();
    println!(
        "import+FK: {:.1} MB/s, {:.0} frames/s ({} reps of {:.3} MB, {:.2} ms each; checksum {check:.3})",
        mb * reps as f64 / s,
        frames as f64 / s,
        reps,
        mb,
        s * 1e3 / reps as f64
    );
    let b = parse_bvh(&text, &path).expect("parse");
    let start = Instant::now();
    let mut g = vec![Transform::IDENTITY; b.joints().len()];
    for _ in 0..reps {
        for k in 0..b.frame_count() {
            b.global_transforms(k, &mut g);
        }
    }
    let s = start.elapsed().as_secs_f64();
    println!(
        "FK alone: {:.0} frames/s ({} joints)",
        (reps * b.frame_count()) as f64 / s,
        b.joints().len()
    );

    let seq = b.to_channel_sequence("walk", 0.01).expect("sequence");
    let dof_seconds = seq.tracks().len() as f64 * seq.duration();
    for tol in [1e-3, 1e-2] {
        let start = Instant::now();
        let (_, r) = compress_spline(&seq, &SplineOptions::new(tol)).expect("compress");
        let s = start.elapsed().as_secs_f64();
        println!(
            "spline compression tol {tol}: {} -> {} keys ({:.1} %), max error {:.2e}, {:.1} ms = {:.1} µs per DOF-second",
            r.keys_before,
            r.keys_after,
            100.0 * r.keys_after as f64 / r.keys_before as f64,
            r.max_error,
            s * 1e3,
            s * 1e6 / dof_seconds
        );
        let start = Instant::now();
        let (_, r) = compress_pyramid(&seq, tol, DEFAULT_A).expect("compress");
        let s = start.elapsed().as_secs_f64();
        println!(
            "pyramid compression tol {tol}: {} -> {} keys ({:.1} %), max error {:.2e}, {:.1} ms = {:.1} µs per DOF-second",
            r.keys_before,
            r.keys_after,
            100.0 * r.keys_after as f64 / r.keys_before as f64,
            r.max_error,
            s * 1e3,
            s * 1e6 / dof_seconds
        );
    }
    let start = Instant::now();
    let w = blend(&seq, &seq, 2.0, 0.5, None).expect("blend");
    let s = start.elapsed().as_secs_f64();
    println!(
        "weighted blend: {} tracks, {:.2} s result, {:.1} ms",
        w.tracks().len(),
        w.duration(),
        s * 1e3
    );
    for levels in [4, 6] {
        let start = Instant::now();
        let p = pyramid_blend(&seq, &seq, 2.0, 0.5, levels, DEFAULT_A).expect("blend");
        let s = start.elapsed().as_secs_f64();
        println!(
            "pyramid blend ({levels} levels): {} tracks, {:.2} s result, {:.1} ms",
            p.tracks().len(),
            p.duration(),
            s * 1e3
        );
    }
}
