//! Tangential relaxation: evens out the triangles' shapes without changing the surface.
//!
//! Simplification and the tiny-edge collapse leave some thin triangles (a vertex almost on
//! the opposite edge). Skinning moves a triangle's three vertices by slightly different
//! blends of the joints' matrices, and a thin triangle turns over at the slightest
//! difference (its third vertex crosses the opposite edge) where a well-shaped one only
//! stretches: on the 1.75 m adult, triangles of quality under 0.3 (see
//! [`super::flips::quality`]) were 8 % of the mesh but a third of the triangles that
//! turned over at the skin test's postures, and nearly all of those at a quarter of the
//! joint ranges. Each vertex is moved
//! towards the mean of its neighbours, along its tangent plane only, then back onto the
//! body's field; a move is kept only when it raises the worst quality of the triangles
//! around the vertex and turns none of them over, so no triangle gets worse.

use super::flips::quality;
use super::surface::Field;
use glam::DVec3;

/// How far towards its neighbours' mean a vertex moves in one round.
const STEP: f64 = 0.5;

/// Relaxes the vertices of the closed mesh `indices` over `rounds` rounds, keeping them
/// on `field`'s zero level set.
pub(crate) fn relax(positions: &mut [DVec3], indices: &[u32], field: &Field, rounds: usize) {
    let mut around: Vec<Vec<[u32; 3]>> = vec![Vec::new(); positions.len()];
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); positions.len()];
    for t in indices.chunks_exact(3) {
        let t = [t[0], t[1], t[2]];
        for k in 0..3 {
            around[t[k] as usize].push(t);
            neighbours[t[k] as usize].push(t[(k + 1) % 3]);
        }
    }
    let normal = |p: &[DVec3], [a, b, c]: [u32; 3]| {
        (p[b as usize] - p[a as usize]).cross(p[c as usize] - p[a as usize])
    };
    let worst = |p: &[DVec3], ring: &[[u32; 3]]| {
        ring.iter()
            .map(|&[a, b, c]| quality(p[a as usize], p[b as usize], p[c as usize]))
            .fold(f64::INFINITY, f64::min)
    };
    for _ in 0..rounds {
        for v in 0..positions.len() {
            let ring = &around[v];
            let n = ring
                .iter()
                .map(|&t| normal(positions, t))
                .sum::<DVec3>()
                .normalize_or_zero();
            let mean = neighbours[v]
                .iter()
                .map(|&u| positions[u as usize])
                .sum::<DVec3>()
                / neighbours[v].len() as f64;
            let here = positions[v];
            let towards = mean - here;
            let moved = field.project(here + (towards - n * towards.dot(n)) * STEP);
            let before = worst(positions, ring);
            let normals_before: Vec<DVec3> = ring.iter().map(|&t| normal(positions, t)).collect();
            positions[v] = moved;
            let turned = ring
                .iter()
                .zip(&normals_before)
                .any(|(&t, n)| normal(positions, t).dot(*n) <= 0.0);
            if turned || worst(positions, ring) <= before {
                positions[v] = here;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skin::surface::sampled_sphere;

    #[test]
    fn relaxing_a_sphere_keeps_it_on_its_surface_and_improves_its_worst_triangle() {
        let radius = 0.1;
        let cell = 0.01;
        let field = sampled_sphere(radius, cell);
        let (mut positions, indices) = field.triangulate();
        let quality_of = |p: &[DVec3]| {
            indices
                .chunks_exact(3)
                .map(|t| quality(p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]))
                .fold(f64::INFINITY, f64::min)
        };
        let before = quality_of(&positions);
        relax(&mut positions, &indices, &field, 10);
        let after = quality_of(&positions);
        assert!(after > before, "worst quality {before} became {after}");
        for p in &positions {
            let off = (p.length() - radius).abs();
            assert!(off < 0.1 * cell, "vertex {p:?} is {off} m off the sphere");
        }
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| positions[t[k] as usize]);
            assert!(
                (b - a).cross(c - a).dot(a + b + c) > 0.0,
                "triangle {t:?} faces inwards"
            );
        }
    }
}
