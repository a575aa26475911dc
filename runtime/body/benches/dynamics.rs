//! Dynamics per call on the adult template (107 DOFs): inverse dynamics (RNEA), forward
//! dynamics (ABA), and one second of a falling actor with floor contact.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use troupe_body::dynamics::{Control, Dynamics, ExternalForces, SimParams, Simulation};
use troupe_body::template;

fn state(n: usize, seed: f64) -> Vec<f64> {
    (0..n)
        .map(|i| ((i as f64 + seed) * 0.37).sin() * 0.4)
        .collect()
}

fn per_call(c: &mut Criterion) {
    let t = template("adult").unwrap();
    let skeleton = t.instantiate(t.default_params()).unwrap();
    let n = skeleton.dof_count();
    let (q, qd, qdd) = (state(n, 0.0), state(n, 1.0), state(n, 2.0));
    let ext = ExternalForces::new(&skeleton);
    let mut d = Dynamics::new(&skeleton).unwrap();
    let mut out = vec![0.0; n];
    c.bench_function("inverse_dynamics/adult (107 DOFs)", |b| {
        b.iter(|| d.inverse_dynamics(black_box(&q), &qd, &qdd, &ext, false, &mut out))
    });
    let tau = state(n, 3.0);
    c.bench_function("forward_dynamics/adult (107 DOFs)", |b| {
        b.iter(|| {
            d.forward_dynamics(black_box(&q), &qd, &tau, &ext, false, &mut out)
                .unwrap()
        })
    });
}

fn falling(c: &mut Criterion) {
    let t = template("adult").unwrap();
    let skeleton = t.instantiate(t.default_params()).unwrap();
    let n = skeleton.dof_count();
    let mut q = vec![0.0; n];
    q[skeleton.dof("root_pitch").unwrap()] = 0.1;
    let params = SimParams {
        damping: 2.0,
        ..SimParams::default()
    };
    let mut group = c.benchmark_group("simulate");
    group.sample_size(10);
    group.bench_function("falling actor, 1 s simulated at 1 ms, floor contact", |b| {
        b.iter(|| {
            let mut sim =
                Simulation::new(&skeleton, &q, &vec![0.0; n], &vec![true; n], params).unwrap();
            for _ in 0..100 {
                sim.advance(0.01, &Control::Passive).unwrap();
            }
            black_box(sim.q()[1])
        })
    });
    group.finish();
}

criterion_group!(benches, per_call, falling);
criterion_main!(benches);
