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
            let (w, d, a) = (
                0.4 + rng.next() * 1.6,
                0.4 + rng.next() * 1.6,
                rng.next() * std::f64::consts::PI,
            );
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
    let mut space = Space::default();
    space.floor = Some(troupe_nav::Floor {
        outline: vec![
            DVec2::new(-50.0, -50.0),
            DVec2::new(50.0, -50.0),
            DVec2::new(50.0, 50.0),
            DVec2::new(-50.0, 50.0),
        ],
        holes: Vec::new(),
    });
    let space = space;
    let radius = 0.28;
    let built = Instant::now();
    space.mesh(&obstacles, radius);
    println!(
        "mesh of 400 obstacles built in {:.1} ms",
        built.elapsed().as_secs_f64() * 1e3
    );
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

/// One walker's avoidance decision among 6 neighbours and 2 obstacles near by (a busy
/// spot of the crowd), and the crowd's grid rebuilt for 1,000 actors (once a tick).
fn avoidance(c: &mut Criterion) {
    use troupe_nav::{choose_velocity, Agent, Crowd};
    let mut rng = Rng(7);
    let me = Agent {
        position: DVec2::ZERO,
        velocity: DVec2::new(0.0, 1.2),
        radius: 0.28,
        feet: [DVec2::ZERO; 2],
    };
    let others: Vec<Agent> = (0..6)
        .map(|_| Agent {
            position: DVec2::new(rng.next() * 6.0 - 3.0, rng.next() * 6.0 - 1.0),
            velocity: DVec2::new(rng.next() * 2.0 - 1.0, rng.next() * 2.0 - 1.0),
            radius: 0.28,
            feet: [DVec2::ZERO; 2],
        })
        .collect();
    let boxes = obstacles(&mut rng);
    let near: Vec<&Footprint> = boxes.iter().take(2).collect();
    c.bench_function("avoidance decision, 6 neighbours, 2 obstacles", |b| {
        b.iter(|| choose_velocity(&me, DVec2::new(0.0, 1.2), &others, near.iter().copied()))
    });
    c.bench_function("avoidance decision, nobody near", |b| {
        b.iter(|| choose_velocity(&me, DVec2::new(0.0, 1.2), &[], []))
    });
    let mut crowd = Crowd::default();
    crowd.positions = (0..1000)
        .map(|_| DVec2::new(rng.next() * 63.0, rng.next() * 63.0))
        .collect();
    c.bench_function("crowd grid for 1000 actors", |b| b.iter(|| crowd.index()));
    let mut out = Vec::new();
    c.bench_function("neighbours of one actor among 1000", |b| {
        b.iter(|| {
            out.clear();
            crowd.near(DVec2::new(30.0, 30.0), &mut out);
            out.len()
        })
    });
}

criterion_group!(benches, path_queries, avoidance);
criterion_main!(benches);
