//! What the skin test (`tests/skin.rs`) and `examples/skin_folds.rs` share: random
//! postures within the joint ranges, and which triangles of a posed skin are inverted.

use troupe_body::glam::DVec3;
use troupe_body::{Skeleton, Skin, Transform};

/// A random posture within `part` of every joint's range around zero (DOFs without
/// finite limits at zero).
pub fn posture(skeleton: &Skeleton, draw: &mut impl FnMut() -> f64, part: f64) -> Vec<f64> {
    skeleton
        .dofs()
        .iter()
        .map(|d| {
            if d.min.is_finite() && d.max.is_finite() {
                (d.min + (d.max - d.min) * draw()) * part
            } else {
                0.0
            }
        })
        .collect()
}

/// The triangles of `skin` (by index) inverted when it is deformed to `posed` by the slot
/// frames `frames` (`Skin::frames`): a triangle whose skinned normal points against its
/// rest normal turned by the rotations of its three vertices' joints (and helpers),
/// blended by their weights (the rotation skinning gives the triangle), beyond 90°.
pub fn inverted<'a>(
    skin: &'a Skin,
    posed: &'a [DVec3],
    frames: &'a [Transform],
) -> impl Iterator<Item = usize> + 'a {
    let rest = |i: usize| DVec3::from(skin.positions[i].map(f64::from));
    skin.indices
        .chunks_exact(3)
        .enumerate()
        .filter(move |(_, t)| {
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
            posed_n.dot(turned) <= 0.0
        })
        .map(|(t, _)| t)
}

/// The joint an inverted triangle `t` of `skin` is counted at: the one that moves its first
/// vertex most (a helper's joint for a helper).
pub fn counted_at(skin: &Skin, t: usize) -> usize {
    let first = skin.indices[3 * t] as usize;
    skin.slot_joint(skin.joints[first][0] as usize)
}
