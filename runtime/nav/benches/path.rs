//! Path queries on a 100 m × 100 m floor with 400 obstacles (issue 18): 1,000 random
//! pairs of free points, for an adult's radius. Reports the mean and p99 per query on
//! top of criterion's own figures, and the time to build the mesh.
//!
//! `cargo bench -p troupe-nav --bench path`

use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Instant;
use troupe_body::glam::DVec2;
use troupe_nav::{Footprint, Space};

/// A small deterministic generator (xorshift), so every run asks the same queries.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// 400 boxes from 0.4 to 2 m a side, turned at random, on a 100 m square.
fn obstacles(rng: &mut Rng) -> Vec<Footprint> {
    (0..400)
        .map(|i| {
            let c = DVec2::new(rng.next() * 96.0 - 48.0, rng.next() * 96.0 - 48.0);
            let (w, d, a) = (0.4 + rng.next() * 1.6, 0.4 + rng.next() * 1.6, rng.next() * 3.14);
            let (s, k) = f64::sin_cos(a);
            let corner = |x: f64, z: f64| c + DVec2::new(x * k - z * s, x * s + z * k);
            Footprint::hull(
                format!("box {i}"),
                &[corner(-w, -d), corner(w, -d), corner(w, d), corner(-w, d)],
            )
        })
        .collect()
}

fn path_queries(c: &mut Criterion) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let obstacles = obstacles(&mut rng);
    let space = Space {
        floor: Some(troupe_nav::Floor {
            outline: vec![
                DVec2::new(-50.0, -50.0),
                DVec2::new(50.0, -50.0),
                DVec2::new(50.0, 50.0),
                DVec2::new(-50.0, 50.0),
            ],
            holes: Vec::new(),
        }),
        ..Space::default()
    };
    let radius = 0.28;
    let built = Instant::now();
    space.mesh(&obstacles, radius);
    println!("mesh of 400 obstacles built in {:.1} ms", built.elapsed().as_secs_f64() * 1e3);
    // 1,000 pairs of points clear of every inflated obstacle.
    let clear = |p: DVec2| obstacles.iter().all(|o| o.distance(p) > radius + 0.1);
    let mut pairs = Vec::new();
    while pairs.len() < 1000 {
        let a = DVec2::new(rng.next() * 96.0 - 48.0, rng.next() * 96.0 - 48.0);
        let b = DVec2::new(rng.next() * 96.0 - 48.0, rng.next() * 96.0 - 48.0);
        if clear(a) && clear(b) {
            pairs.push((a, b));
        }
    }
    let mut times: Vec<f64> = Vec::with_capacity(pairs.len());
    let mut found = 0;
    for &(a, b) in &pairs {
        let t = Instant::now();
        if space.path(&obstacles, a, b, radius).is_ok() {
            found += 1;
        }
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    println!(
        "1000 path queries ({found} found): mean {:.1} µs, p99 {:.1} µs",
        mean * 1e6,
        times[times.len() * 99 / 100] * 1e6
    );
    let mut k = 0;
    c.bench_function("path query, 100 m floor, 400 obstacles", |bench| {
        bench.iter(|| {
            let (a, b) = pairs[k % pairs.len()];
            k += 1;
            space.path(&obstacles, a, b, radius)
        })
    });
}

criterion_group!(benches, path_queries);
criterion_main!(benches);
