//! Pleats: triangles that face into the body at rest, smoothed out.
//!
//! Simplification and the tiny-edge collapse leave a few small pleats, where the surface
//! folds back on itself over a millimetre or two and a triangle faces into the body
//! between neighbours that face out (3-6 on each size of the skin test, in the creases:
//! the root of the neck, the crotch, the lower back). The relaxation keeps them, since
//! it turns no triangle over, the ones that would untangle included. Skinning moves a
//! pleat's vertices by slightly different blends and the pleat opens or closes: at the
//! skin test's full-range postures those few triangles and their neighbours made 60-80
//! of the 394 counted as turned over (one triangle on the 2.01 m adult's neck in 21 of
//! the 50 postures). Each vertex of a pleat is moved to the mean of its neighbours
//! (across the surface as well as along it, which unfolds the pleat) and back onto the
//! body's field; a move is kept when fewer triangles around the vertex face into the
//! body (or stand nearly edge-on to it, [`EDGE_ON`]), judged by the field's gradient, or
//! as many and better shaped.

use super::flips::quality;
use super::surface::Field;
use glam::DVec3;

/// Rounds of moves; a pleat of a few triangles unfolds in one or two.
const ROUNDS: usize = 8;

/// A triangle whose normal makes less than this cosine with the field's gradient (turned
/// more than about 75° from the surface's normal, nearly edge-on to it) counts as part
/// of a pleat: the start of one, in the deep creases between the fingers and at the
/// crotch. Counting only the triangles turned past 90° (0) left 174 inverted triangles
/// over the skin test's full-range postures, 0.2 and 0.3 left 167, 0.4 170, 0.6 182.
const EDGE_ON: f64 = 0.25;

/// Unfolds the pleats of the closed mesh `indices` (see the module's note), keeping its
/// vertices on `field`'s zero level set; returns how many triangles still face inwards
/// or stand edge-on (0-3 on the skin test's sizes, none facing inwards).
pub(crate) fn unfold(positions: &mut [DVec3], indices: &[u32], field: &Field) -> usize {
    let mut around: Vec<Vec<[u32; 3]>> = vec![Vec::new(); positions.len()];
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); positions.len()];
    for t in indices.chunks_exact(3) {
        let t = [t[0], t[1], t[2]];
        for k in 0..3 {
            around[t[k] as usize].push(t);
            neighbours[t[k] as usize].push(t[(k + 1) % 3]);
        }
    }
    // Inwards (or nearly edge-on): against the field's gradient at the triangle's centre.
    let inwards = |p: &[DVec3], [a, b, c]: [u32; 3]| {
        let [a, b, c] = [a, b, c].map(|v| p[v as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        normal.dot(field.gradient((a + b + c) / 3.0).normalize_or_zero()) <= EDGE_ON
    };
    let count = |p: &[DVec3], ring: &[[u32; 3]]| ring.iter().filter(|&&t| inwards(p, t)).count();
    let worst = |p: &[DVec3], ring: &[[u32; 3]]| {
        ring.iter()
            .map(|&[a, b, c]| quality(p[a as usize], p[b as usize], p[c as usize]))
            .fold(f64::INFINITY, f64::min)
    };
    for _ in 0..ROUNDS {
        let mut pleated: Vec<u32> = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .filter(|&t| inwards(positions, t))
            .flatten()
            .collect();
        if pleated.is_empty() {
            break;
        }
        pleated.sort_unstable();
        pleated.dedup();
        let mut moved_any = false;
        for v in pleated {
            let v = v as usize;
            let ring = &around[v];
            let mean = neighbours[v]
                .iter()
                .map(|&u| positions[u as usize])
                .sum::<DVec3>()
                / neighbours[v].len() as f64;
            let here = positions[v];
            let (before, quality_before) = (count(positions, ring), worst(positions, ring));
            positions[v] = field.project(mean);
            let after = count(positions, ring);
            // Fewer facing in; or as many, and better shaped (so a pleat of two
            // triangles can move on when one vertex alone cannot unfold it).
            if after < before || (after == before && worst(positions, ring) > quality_before) {
                moved_any = true;
            } else {
                positions[v] = here;
            }
        }
        if !moved_any {
            break;
        }
    }
    indices
        .chunks_exact(3)
        .filter(|t| inwards(positions, [t[0], t[1], t[2]]))
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skin::surface::sampled_sphere;

    #[test]
    fn a_pleat_pushed_into_a_sphere_is_unfolded_onto_its_surface() {
        let radius = 0.1;
        let cell = 0.01;
        let field = sampled_sphere(radius, cell);
        let (mut positions, indices) = field.triangulate();
        let facing_in = |p: &[DVec3]| {
            indices
                .chunks_exact(3)
                .filter(|t| {
                    let [a, b, c] = [0, 1, 2].map(|k| p[t[k] as usize]);
                    (b - a).cross(c - a).dot(a + b + c) <= 0.0
                })
                .count()
        };
        assert_eq!(facing_in(&positions), 0);
        // A pleat: one vertex slid along the surface past a neighbour, twice as far from
        // where it was as that neighbour is.
        let (v, u) = (indices[0] as usize, indices[1] as usize);
        positions[v] = field.project(positions[v] + (positions[u] - positions[v]) * 2.0);
        assert!(facing_in(&positions) > 0);
        assert_eq!(unfold(&mut positions, &indices, &field), 0);
        assert_eq!(facing_in(&positions), 0);
        for p in &positions {
            let off = (p.length() - radius).abs();
            assert!(off < 0.1 * cell, "vertex {p:?} is {off} m off the sphere");
        }
    }
}
