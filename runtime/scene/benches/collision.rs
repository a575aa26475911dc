//! Detection of solid interpenetration between actors and with obstacles
//! (`World::deepest_interpenetration`, issue 18 item 5), per actor-tick: crowds of
//! adults standing on a grid, turned every which way, with a box every fourth cell:
//! 0.6 m apart (a dense crowd: the boxes around neighbouring bodies overlap, so their
//! capsule pairs are tested) and 1.0 m apart (a loose one); and the one-body part a
//! walker or a reach pays for each neighbour each tick (placing one body's 17 capsules).
//!
//! Run: `cargo bench -p troupe-scene --bench collision`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use troupe_body::collision::{BodyVolumes, Capsule};
use troupe_body::glam::DVec3;
use troupe_body::{Shape, Transform};
use troupe_scene::{ActorDesc, Object, Scene, SceneConfig};

/// `n × n` adults on a grid `spacing` apart, each turned a little, and a box every
/// fourth cell.
fn crowd(n: usize, spacing: f64) -> Scene {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    for i in 0..n {
        for j in 0..n {
            let mut desc = ActorDesc::new(format!("a{i}_{j}"));
            desc.at = DVec3::new(i as f64 * spacing, 0.0, j as f64 * spacing);
            desc.facing_degrees = ((i * 7 + j * 13) % 360) as f64;
            scene.add_actor(&desc).unwrap();
            if (i + j) % 4 == 0 && i + 1 < n {
                scene
                    .add_object(Object {
                        name: format!("box{i}_{j}"),
                        shape: Shape::Box {
                            half_extents: DVec3::new(0.1, 0.4, 0.1),
                        },
                        position: DVec3::new((i as f64 + 0.5) * spacing, 0.4, j as f64 * spacing),
                        rotation: Default::default(),
                        mass: 5.0,
                    })
                    .unwrap();
            }
        }
    }
    scene
}

fn detection(c: &mut Criterion) {
    for (n, spacing) in [(10usize, 0.6), (20, 0.6), (20, 1.0)] {
        let scene = crowd(n, spacing);
        let actors = (n * n) as u64;
        let mut g = c.benchmark_group(format!(
            "deepest_interpenetration/{actors}_actors_{spacing}_m_apart"
        ));
        g.throughput(criterion::Throughput::Elements(actors));
        g.bench_function("scene", |b| {
            b.iter(|| black_box(scene.deepest_interpenetration()))
        });
        g.finish();
    }
    let scene = crowd(1, 1.0);
    let skeleton = scene.actors()[0].skeleton.clone();
    let globals: Vec<Transform> = scene.states()[0].globals.clone();
    let volumes = BodyVolumes::new(&skeleton);
    let mut out: Vec<Capsule> = Vec::new();
    c.bench_function("body capsules: build and place (one body)", |b| {
        b.iter(|| {
            BodyVolumes::new(black_box(&skeleton)).place(&globals, &mut out);
            black_box(out.len())
        })
    });
    c.bench_function("body capsules: place (one body)", |b| {
        b.iter(|| {
            volumes.place(black_box(&globals), &mut out);
            black_box(out.len())
        })
    });
}

criterion_group!(benches, detection);
criterion_main!(benches);
