//! The same scene gives bit-identical postures whatever the number of worker threads.

use troupe_actions::Keyframe;
use troupe_motion::{Key, Sequence, Track};
use troupe_scene::{ActionSpec, ActorDesc, Mode, Scene, SceneConfig};

/// A small deterministic pseudo-random generator (SplitMix64) for the test scene.
struct Mix(u64);
impl Mix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn sequence(rng: &mut Mix, dofs: &[&str], length: f64) -> Sequence {
    let mut seq = Sequence::new("random");
    for dof in dofs {
        let keys = (0..6)
            .map(|i| Key::new(i as f64 * length / 5.0, rng.next() - 0.5))
            .collect();
        seq.add_track(Track::new(*dof, keys).unwrap()).unwrap();
    }
    seq
}

fn run(threads: usize) -> Vec<Vec<u64>> {
    let mut scene = Scene::new(SceneConfig {
        threads,
        ..SceneConfig::default()
    })
    .unwrap();
    let mut rng = Mix(42);
    let arm = [
        "r_shoulder_flexion",
        "r_shoulder_abduction",
        "r_elbow_flexion",
        "r_wrist_flexion",
    ];
    let body = [
        "vl5_flexion",
        "vt12_torsion",
        "r_shoulder_flexion",
        "l_hip_flexion",
        "l_knee_flexion",
        "skullbase_flexion",
    ];
    for i in 0..50 {
        let a = scene
            .add_actor(&ActorDesc {
                template: if i % 3 == 0 {
                    "child".into()
                } else {
                    "adult".into()
                },
                at: troupe_body::glam::DVec3::new(i as f64, 0.0, 0.0),
                ..ActorDesc::new(format!("actor{i}"))
            })
            .unwrap();
        let skel = scene.actors()[a].skeleton.clone();
        // Overlapping actions in every mode, with easing, delays and loops.
        let plans = [
            (&body[..], Mode::Default, 1.0, 0.0, None),
            (&arm[..], Mode::Weighted, 0.6, 0.5, None),
            (&arm[..], Mode::Weighted, 0.3, 1.0, Some(4.0)),
            (&body[..], Mode::Exclusive, 1.0, 3.0 + rng.next(), Some(3.0)),
            (&arm[..], Mode::Default, 1.0, 2.0, Some(2.0)),
            (&body[..], Mode::Clearing, 1.0, 7.5, Some(1.5)),
        ];
        for (dofs, mode, weight, delay, duration) in plans {
            let length = 1.0 + 2.0 * rng.next();
            let seq = sequence(&mut rng, dofs, length);
            let gen = Keyframe::new(&skel, &seq, None, Some(rng.next() < 0.5)).unwrap();
            let spec = ActionSpec {
                mode,
                weight,
                delay,
                duration,
                ease_in: 0.2,
                ease_out: 0.3,
                ..ActionSpec::new("keyframe", gen.scope())
            };
            scene.start_action(a, spec, Box::new(gen)).unwrap();
        }
    }
    let mut trace = Vec::new();
    for tick in 0..1000 {
        scene.step();
        if tick % 50 == 49 {
            let mut bits = Vec::new();
            for state in scene.states() {
                bits.extend(state.q.iter().map(|v| v.to_bits()));
                for g in &state.globals {
                    bits.extend(g.translation.to_array().iter().map(|v| v.to_bits()));
                    bits.extend(g.rotation.to_array().iter().map(|v| v.to_bits()));
                }
            }
            trace.push(bits);
        }
    }
    trace
}

#[test]
fn fifty_actors_are_bit_identical_with_one_and_two_threads() {
    let one = run(1);
    let two = run(2);
    assert_eq!(one.len(), 20);
    assert!(one == two, "postures differ between 1 and 2 threads");
    // The scene really moved.
    assert_ne!(one[0], one[19]);
}
