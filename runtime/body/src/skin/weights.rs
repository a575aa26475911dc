//! Skin weights: how much each joint moves each vertex. A vertex belongs to the volume
//! it is nearest to; that volume's joint and the joints next to it (parent and children)
//! share the vertex by how close their volumes come, fading out over each volume's
//! reach. So an elbow vertex is shared by the upper arm and the forearm, blended over a
//! few centimetres on either side, while a hand hanging by the hip takes nothing from
//! the pelvis. At most four joints keep a weight; the weights sum to one.

use super::volumes::{Join, Volume};
use glam::DVec3;

/// Up to four joints and their weights, heaviest first; unused slots hold joint 0 with
/// weight 0 (glTF's convention).
pub type Influences = ([u16; 4], [f32; 4]);

/// The weights of a vertex at rest position `p`.
pub(crate) fn influences(
    p: DVec3,
    volumes: &[Volume],
    neighbours: &impl Fn(usize, usize) -> bool,
) -> Influences {
    let distances: Vec<f64> = volumes
        .iter()
        .map(|v| match v.join {
            // A carved volume moves nothing; the skin it leaves follows the head.
            Join::Carve => f64::INFINITY,
            // Unsigned: a vertex on an eyeball lies inside the head's ellipsoid, and
            // belongs to the eyeball, whose surface it is on.
            _ => v.form.distance(p).abs(),
        })
        .collect();
    let owner = (0..volumes.len())
        .min_by(|&a, &b| distances[a].total_cmp(&distances[b]))
        .expect("a body has volumes");
    let home = volumes[owner].joint;
    let nearest = distances[owner];
    // Each joint's weight is the largest of its volumes' weights.
    let mut per_joint: Vec<(usize, f64)> = Vec::new();
    for (v, &d) in volumes.iter().zip(&distances) {
        if !d.is_finite() || !neighbours(home, v.joint) {
            continue;
        }
        // A smooth step of the distance beyond the nearest volume's: it depends on the
        // vertex's position only (not on which volume owns it), so neighbouring vertices
        // get neighbouring weights and the skin does not crease where ownership changes.
        let x = ((d - nearest) / v.reach).clamp(0.0, 1.0);
        let w = (1.0 - x) * (1.0 - x) * (1.0 + 2.0 * x);
        if w <= 0.0 {
            continue;
        }
        match per_joint.iter_mut().find(|(j, _)| *j == v.joint) {
            Some((_, old)) => *old = old.max(w),
            None => per_joint.push((v.joint, w)),
        }
    }
    // Heaviest first; ties by joint index so the order never depends on anything else.
    per_joint.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    per_joint.truncate(4);
    let total: f64 = per_joint.iter().map(|(_, w)| w).sum();
    let mut joints = [0u16; 4];
    let mut weights = [0.0f32; 4];
    for (slot, (j, w)) in per_joint.iter().enumerate() {
        joints[slot] = *j as u16;
        weights[slot] = (*w / total) as f32;
    }
    // Rounding to f32 can leave the sum a hair off one: give the rest to the heaviest.
    let sum: f32 = weights[1..].iter().sum();
    weights[0] = 1.0 - sum;
    (joints, weights)
}
