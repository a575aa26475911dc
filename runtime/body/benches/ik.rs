//! IK benchmarks: Jacobian of a 7-DOF arm, and IK solves for the 7-DOF arm and the arm
//! plus the spine (19 DOFs). Besides criterion's figures, each solve benchmark first times
//! 1,000 random reachable targets one by one and prints the median and p99.
//!
//! Run: `cargo bench -p troupe-body --bench ik`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use std::time::Instant;
use troupe_body::glam::DVec3;
use troupe_body::ik::{IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::{chain_dofs, jacobian, Effector};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::math::draws;
use troupe_body::{template, Skeleton, Transform};

fn adult() -> Skeleton {
    let t = template("adult").unwrap();
    t.instantiate(t.default_params()).unwrap()
}

fn hand(s: &Skeleton) -> Effector {
    Effector {
        joint: s.joint("r_wrist").unwrap(),
        point: DVec3::new(0.0, -0.0735, 0.005),
    }
}

/// The 7-DOF arm: shoulder (3), elbow (2), wrist (2).
fn arm7(s: &Skeleton) -> Vec<usize> {
    chain_dofs(
        s,
        s.joint("r_shoulder").unwrap(),
        s.joint("r_wrist").unwrap(),
    )
    .unwrap()
}

/// The arm plus the spine (vl5 … vt1): 7 + 12 DOFs.
fn arm_spine(s: &Skeleton) -> Vec<usize> {
    let mut d = arm7(s);
    d.extend(s.scope("spine").unwrap().iter());
    d
}

/// Reachable position goals: the hand at random postures of `dofs`.
fn targets(s: &Skeleton, dofs: &[usize], n: usize) -> Vec<DVec3> {
    let mut draw = draws(5);
    let e = hand(s);
    let mut g = vec![Transform::IDENTITY; s.joints().len()];
    (0..n)
        .map(|_| {
            let mut q = vec![0.0; s.dof_count()];
            for &d in dofs {
                let dof = &s.dofs()[d];
                q[d] = dof.min + (dof.max - dof.min) * draw();
            }
            forward_kinematics(s, &q, &mut g);
            e.position(&g)
        })
        .collect()
}

fn percentiles(what: &str, s: &Skeleton, dofs: &[usize]) {
    let mut solver = IkSolver::new(s, dofs.to_vec(), IkOptions::default()).unwrap();
    let e = hand(s);
    let mut times = Vec::new();
    let mut iterations = Vec::new();
    let mut misses = 0;
    for goal in targets(s, dofs, 1000) {
        let mut q = vec![0.0; s.dof_count()];
        let t0 = Instant::now();
        let r = solver
            .solve_with_restarts(s, &mut q, &[IkTask::position(e, goal)], 16)
            .unwrap();
        times.push(t0.elapsed().as_secs_f64() * 1e6);
        iterations.push(r.iterations);
        misses += usize::from(r.position_error > 1e-3);
    }
    times.sort_by(f64::total_cmp);
    iterations.sort_unstable();
    println!(
        "{what}: 1000 random reachable goals from rest: median {:.1} µs, p99 {:.1} µs, worst {:.1} µs; iterations median {}, p99 {}, worst {}; {misses} missed by > 1 mm",
        times[500], times[990], times[999], iterations[500], iterations[990], iterations[999]
    );
}

fn bench_jacobian(c: &mut Criterion) {
    let s = adult();
    let dofs = arm7(&s);
    let q: Vec<f64> = (0..s.dof_count())
        .map(|i| (i as f64 * 0.37).sin() * 0.3)
        .collect();
    let e = hand(&s);
    c.bench_function(
        "jacobian/7-DOF arm, position + orientation (incl. FK)",
        |b| b.iter(|| jacobian(&s, black_box(&q), &dofs, &e, true).unwrap()),
    );
}

fn bench_solve(c: &mut Criterion) {
    let s = adult();
    for (name, dofs) in [
        ("7-DOF arm", arm7(&s)),
        ("arm + spine (19 DOFs)", arm_spine(&s)),
    ] {
        percentiles(&format!("ik/{name}"), &s, &dofs);
        let goals = targets(&s, &dofs, 64);
        let mut solver = IkSolver::new(&s, dofs.clone(), IkOptions::default()).unwrap();
        let e = hand(&s);
        c.bench_function(&format!("ik/solve from rest, {name}"), |b| {
            let mut k = 0;
            b.iter(|| {
                k = (k + 1) % goals.len();
                let mut q = vec![0.0; s.dof_count()];
                solver
                    .solve_with_restarts(&s, &mut q, &[IkTask::position(e, goals[k])], 16)
                    .unwrap()
            })
        });
        // Tracking: one tick of a reach, the goal 1 cm from a solved posture.
        let mut q0 = vec![0.0; s.dof_count()];
        let start = DVec3::new(-0.25, 1.2, 0.35);
        solver
            .solve(&s, &mut q0, &[IkTask::position(e, start)], None, None)
            .unwrap();
        c.bench_function(&format!("ik/track 1 cm, {name}"), |b| {
            let mut q = q0.clone();
            let mut k = 0u32;
            b.iter(|| {
                k += 1;
                q.copy_from_slice(&q0);
                let goal =
                    start + DVec3::new(0.01 * (k as f64).sin(), 0.01 * (k as f64).cos(), 0.0);
                solver
                    .solve(&s, &mut q, &[IkTask::position(e, goal)], None, None)
                    .unwrap()
            })
        });
    }
}

criterion_group!(benches, bench_jacobian, bench_solve);
criterion_main!(benches);
