//! VMC costs: one actor's frame (pose from the joint globals, bundle, encoding) and its
//! send over loopback, ten actors' frames as one 60 Hz step, and the receiving side (a
//! datagram read and retargeted onto the template).

use criterion::{criterion_group, criterion_main, Criterion};
use std::net::UdpSocket;
use std::sync::Arc;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::transform::Transform;
use troupe_drivers::vmc::rig::t_pose;
use troupe_drivers::vmc::{frame_bundle, read_datagram, VmcCounters, VmcRig};

fn bench(c: &mut Criterion) {
    let sk = Arc::new(troupe_body::template::default_skeleton("adult").unwrap());
    let rig = VmcRig::new(sk.clone()).unwrap();
    let mut q = t_pose(&sk);
    for (d, v) in q.iter_mut().enumerate() {
        *v += 0.1 * ((d as f64) * 0.7).sin();
    }
    let mut g = vec![Transform::IDENTITY; sk.joints().len()];
    forward_kinematics(&sk, &q, &mut g);
    let sink = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = sink.local_addr().unwrap();
    sink.set_nonblocking(true).unwrap();
    let out = UdpSocket::bind("127.0.0.1:0").unwrap();
    let frame = |t: f64| rosc::encoder::encode(&frame_bundle(&rig.pose(&g), t)).unwrap();
    let bytes = frame(0.0);
    println!("one actor's VMC frame: {} bytes", bytes.len());
    c.bench_function("vmc: one actor's frame (pose + bundle + encode)", |b| {
        b.iter(|| frame(1.0))
    });
    let mut buf = vec![0u8; 65_536];
    c.bench_function("vmc: ten actors sent (one 60 Hz step)", |b| {
        b.iter(|| {
            for _ in 0..10 {
                out.send_to(&frame(1.0), to).unwrap();
            }
            while sink.recv(&mut buf).is_ok() {}
        })
    });
    let mut counters = VmcCounters::default();
    c.bench_function("vmc: one frame received (read + retarget)", |b| {
        b.iter(|| {
            let p = read_datagram(&bytes, &mut counters);
            let (mut q2, mut mask) = (vec![0.0; sk.dof_count()], vec![false; sk.dof_count()]);
            rig.retarget(&p.pose, &Transform::IDENTITY, &mut q2, &mut mask);
            q2
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
