//! Decoder throughput (bytes per second through the FoB and CyberGlove decoders) and the
//! cost of one anatomical conversion (6 birds on the adult template).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::collections::BTreeMap;
use std::sync::Arc;
use troupe_drivers::cyberglove::{GloveDecoder, GloveLayout};
use troupe_drivers::emulator::Motion;
use troupe_drivers::fob::{
    encode_record, pose_words, OutputFormat, PositionRange, RecordDecoder, RecordLayout,
};
use troupe_drivers::performer::{transmitter_to_world, AnatomicalConverter};

fn fob_stream(format: OutputFormat, records: usize) -> (RecordLayout, Vec<u8>) {
    let layout = RecordLayout {
        format,
        button: false,
        group: true,
        range: PositionRange::Inches36,
    };
    let mut bytes = Vec::new();
    for k in 0..records {
        let bird = (k % 6) as u8;
        let (p, q) = Motion::Synthetic.bird(k as f64 * 0.01, usize::from(bird));
        bytes.extend(encode_record(
            &layout,
            &pose_words(format, layout.range, p, q),
            0,
            bird + 1,
        ));
    }
    (layout, bytes)
}

fn decoders(c: &mut Criterion) {
    let mut g = c.benchmark_group("decode");
    for format in [
        OutputFormat::PositionAngles,
        OutputFormat::PositionQuaternion,
        OutputFormat::PositionMatrix,
    ] {
        let (layout, bytes) = fob_stream(format, 6000);
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(format!("fob {} (6000 group records)", format.name()), |b| {
            b.iter(|| {
                let mut d = RecordDecoder::new(layout, 1);
                let mut n = 0usize;
                d.feed(&bytes, |_| n += 1);
                assert_eq!(n, 6000);
            })
        });
    }
    let layout = GloveLayout {
        sensors: 22,
        status_byte: true,
    };
    let mut bytes = Vec::new();
    for k in 0..6000u32 {
        bytes.push(b'S');
        bytes.extend((0..22).map(|i| 1 + ((k * 7 + i * 13) % 254) as u8));
        bytes.push(3);
        bytes.push(0);
    }
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("cyberglove 22 sensors + status (6000 records)", |b| {
        b.iter(|| {
            let mut d = GloveDecoder::new(layout);
            let mut n = 0usize;
            d.feed(&bytes, |_| n += 1);
            assert_eq!(n, 6000);
        })
    });
    g.finish();
}

fn converter(c: &mut Criterion) {
    let t = troupe_body::template("adult").unwrap();
    let sk = Arc::new(
        t.instantiate(troupe_body::TemplateParams {
            height: t.default_height,
            mass: t.default_mass,
        })
        .unwrap(),
    );
    let names = [
        "pelvis",
        "vl5",
        "skullbase",
        "r_shoulder",
        "l_shoulder",
        "r_wrist",
    ];
    let map: Vec<(String, u8)> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.to_string(), i as u8 + 1))
        .collect();
    let joints: Vec<usize> = [
        "HumanoidRoot",
        "vl5",
        "skullbase",
        "r_shoulder",
        "l_shoulder",
        "r_wrist",
    ]
    .iter()
    .map(|n| sk.joint(n).unwrap())
    .collect();
    let frame = transmitter_to_world();
    let mut conv = AnatomicalConverter::new(sk.clone(), &map, frame).unwrap();
    // Bird poses of a body that really moves (arms, spine and head on sines), seen from a
    // transmitter 1 m behind the scene origin: the IK goals are reachable, as in a capture.
    let moving: Vec<usize> = [
        "r_shoulder_flexion",
        "r_elbow_flexion",
        "l_shoulder_flexion",
        "vl5_flexion",
        "skullbase_torsion",
    ]
    .iter()
    .filter_map(|n| sk.dof(n).ok())
    .collect();
    let poses = |time: f64| -> BTreeMap<u8, _> {
        let mut q = vec![0.0; sk.dof_count()];
        for (k, &d) in moving.iter().enumerate() {
            q[d] = sk.dofs()[d].clamp(0.4 * (time * (1.0 + 0.3 * k as f64)).sin());
        }
        let mut g = vec![troupe_body::transform::Transform::IDENTITY; sk.joints().len()];
        troupe_body::kinematics::forward_kinematics(&sk, &q, &mut g);
        joints
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                let p = frame.inverse() * (g[j].translation + troupe_body::glam::DVec3::Z);
                let r = frame.inverse() * g[j].rotation * frame;
                (i as u8 + 1, (p, r))
            })
            .collect()
    };
    conv.calibrate(&vec![0.0; sk.dof_count()], &poses(0.0))
        .unwrap();
    // Consecutive 100 Hz frames: each conversion starts its IK from the previous one.
    let frames: Vec<_> = (0..100).map(|k| poses(1.3 + 0.01 * k as f64)).collect();
    let mut q = vec![0.0; sk.dof_count()];
    let mut mask = vec![false; sk.dof_count()];
    let mut k = 0;
    c.bench_function(
        "anatomical conversion, 6 birds (IK for the arms), consecutive frames",
        |b| {
            b.iter(|| {
                conv.convert(&frames[k % frames.len()], &mut q, &mut mask);
                k += 1;
            })
        },
    );
}

criterion_group!(benches, decoders, converter);
criterion_main!(benches);
