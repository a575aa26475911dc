//! How many triangles of the generated skin turn over, counted over many random
//! postures: the measure to judge a change to the skin's weights or helpers by.
//!
//! The skin test (`tests/skin.rs`) bounds the folds over one fixed draw of postures,
//! and weights tuned against one draw learn its postures: the 50 full-range postures the
//! test once had were folded by 0-1 triangles per size, five other draws of 50 by 2-46.
//! This counts them over ten draws of 50 postures within the whole joint ranges for every
//! template at three sizes, split into five draws to choose a change by and five held
//! out to check it on, and over ten draws within half the ranges, where no triangle
//! should turn over. A triangle is inverted as in the test: its skinned normal points
//! against its rest normal turned by the rotations skinning blends for it.
//!
//! `cargo run --release -p troupe-body --example skin_folds`

use std::collections::BTreeMap;
use troupe_body::glam::DVec3;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::{templates, Skeleton, Skin, TemplateParams, Transform};

/// The draws chosen by, and those held out.
const CHOOSE_BY: std::ops::Range<u64> = 8..13;
const HELD_OUT: std::ops::Range<u64> = 13..18;
/// Postures per draw.
const POSTURES: usize = 50;

/// A small deterministic generator (64-bit LCG), the skin test's.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A random posture within `part` of every joint's range around zero.
fn posture(skeleton: &Skeleton, rng: &mut Lcg, part: f64) -> Vec<f64> {
    skeleton
        .dofs()
        .iter()
        .map(|d| {
            if d.min.is_finite() && d.max.is_finite() {
                (d.min + (d.max - d.min) * rng.next()) * part
            } else {
                0.0
            }
        })
        .collect()
}

/// The name of the joint that moves each inverted triangle of `skin` most, at posture
/// `q`.
fn inverted(skeleton: &Skeleton, skin: &Skin, q: &[f64]) -> Vec<String> {
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, q, &mut globals);
    let posed = skin.deform(&globals);
    let frames = skin.frames(&globals);
    let rest = |i: usize| DVec3::from(skin.positions[i].map(f64::from));
    let mut out = Vec::new();
    for t in skin.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
        let rest_n = (rest(b) - rest(a)).cross(rest(c) - rest(a));
        let posed_n = (posed[b] - posed[a]).cross(posed[c] - posed[a]);
        let turned: DVec3 = [a, b, c]
            .iter()
            .flat_map(|&v| skin.joints[v].iter().zip(&skin.weights[v]))
            .map(|(&j, &w)| {
                let j = j as usize;
                frames[j].rotation * skin.rest[j].rotation.inverse() * rest_n * w as f64
            })
            .sum();
        if posed_n.dot(turned) <= 0.0 {
            let joint = skin.slot_joint(skin.joints[a][0] as usize);
            out.push(skeleton.joints()[joint].name.clone());
        }
    }
    out
}

fn main() {
    let mut by_joint: BTreeMap<String, usize> = BTreeMap::new();
    let (mut chosen_by, mut held_out, mut at_half) = (0, 0, 0);
    for t in templates() {
        for scale in [0.8, 1.0, 1.15] {
            let params = TemplateParams {
                height: t.default_height * scale,
                mass: t.default_mass * scale.powi(3),
            };
            let skeleton = t.instantiate(params).expect("a template's skeleton");
            let skin = Skin::build(&skeleton).expect("a template's skin");
            let mut count = |draws: std::ops::Range<u64>, part: f64, tally: bool| -> usize {
                let mut n = 0;
                for draw in draws {
                    let mut rng = Lcg(draw + if part < 1.0 { 100 } else { 0 });
                    for _ in 0..POSTURES {
                        let q = posture(&skeleton, &mut rng, part);
                        for joint in inverted(&skeleton, &skin, &q) {
                            n += 1;
                            if tally {
                                *by_joint.entry(joint).or_default() += 1;
                            }
                        }
                    }
                }
                n
            };
            let (a, b) = (count(CHOOSE_BY, 1.0, true), count(HELD_OUT, 1.0, true));
            let half = count(CHOOSE_BY.start..HELD_OUT.end, 0.5, false);
            println!(
                "{} {:.2} m: {a} + {b} inverted over the full ranges' draws (chosen by + held out), {half} within half the ranges",
                t.name, params.height
            );
            (chosen_by, held_out, at_half) = (chosen_by + a, held_out + b, at_half + half);
        }
    }
    let mut by_joint: Vec<_> = by_joint.into_iter().collect();
    by_joint.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    println!(
        "all: {} inverted over the full ranges ({chosen_by} chosen by + {held_out} held out, {} postures), {at_half} within half the ranges ({} postures)",
        chosen_by + held_out,
        6 * 10 * POSTURES,
        6 * 10 * POSTURES
    );
    println!("by joint: {by_joint:?}");
}
