//! How many triangles of the generated skin turn over, counted over many random
//! postures: the measure to judge a change to the skin's weights or helpers by.
//!
//! The skin test (`tests/skin.rs`) bounds the folds over one fixed draw of postures,
//! and weights tuned against one draw learn its postures: the 50 full-range postures the
//! test once had were folded by 0-1 triangles per size, five other draws of 50 by 2-46.
//! This counts them over ten draws of 50 postures within the whole joint ranges for every
//! template at three sizes, split into five draws to choose a change by and five held
//! out to check it on, over ten draws within three quarters of the ranges, where few
//! should, and over ten within half, where none should. A triangle is inverted as in
//! the test: its skinned normal points against its rest normal turned by the rotations
//! skinning blends for it.
//!
//! `cargo run --release -p troupe-body --example skin_folds`

use std::collections::BTreeMap;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::{templates, Skeleton, Skin, TemplateParams, Transform};

#[path = "../tests/support/postures.rs"]
mod postures;
use postures::{counted_at, inverted, posture};

/// The draws chosen by, and those held out.
const CHOOSE_BY: std::ops::Range<u64> = 8..13;
const HELD_OUT: std::ops::Range<u64> = 13..18;
/// Postures per draw.
const POSTURES: usize = 50;

/// The name of the joint that moves each inverted triangle of `skin` most, at posture
/// `q`.
fn inverted_at(skeleton: &Skeleton, skin: &Skin, q: &[f64]) -> Vec<String> {
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, q, &mut globals);
    let posed = skin.deform(&globals);
    let frames = skin.frames(&globals);
    inverted(skin, &posed, &frames)
        .map(|t| skeleton.joints()[counted_at(skin, t)].name.clone())
        .collect()
}

fn main() {
    let mut by_joint: BTreeMap<String, usize> = BTreeMap::new();
    let (mut chosen_by, mut held_out, mut at_three_quarters, mut at_half) = (0, 0, 0, 0);
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
                    // Draws of their own for each part of the ranges (the half's
                    // were the first, at 100 on).
                    let mut rng = troupe_body::math::draws(draw + (200.0 * (1.0 - part)) as u64);
                    for _ in 0..POSTURES {
                        let q = posture(&skeleton, &mut rng, part);
                        for joint in inverted_at(&skeleton, &skin, &q) {
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
            let three_quarters = count(CHOOSE_BY.start..HELD_OUT.end, 0.75, false);
            let half = count(CHOOSE_BY.start..HELD_OUT.end, 0.5, false);
            println!(
                "{} {:.2} m: {a} + {b} inverted over the full ranges' draws (chosen by + held out), {three_quarters} within three quarters, {half} within half the ranges",
                t.name, params.height
            );
            (chosen_by, held_out) = (chosen_by + a, held_out + b);
            (at_three_quarters, at_half) = (at_three_quarters + three_quarters, at_half + half);
        }
    }
    let mut by_joint: Vec<_> = by_joint.into_iter().collect();
    by_joint.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let postures = 6 * 10 * POSTURES;
    println!(
        "all: {} inverted over the full ranges ({chosen_by} chosen by + {held_out} held out), {at_three_quarters} within three quarters, {at_half} within half the ranges ({postures} postures each)",
        chosen_by + held_out,
    );
    println!("by joint: {by_joint:?}");
}
