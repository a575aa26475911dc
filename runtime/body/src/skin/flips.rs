//! Sliver removal by edge flips. Simplification on nearly flat skin can leave slivers,
//! triangles whose third vertex lies almost on their longest edge; flipping that edge
//! (swapping the diagonal of the two triangles that share it) turns them into two
//! well-shaped triangles without moving a vertex or changing the surface's topology.

use glam::DVec3;
use std::collections::HashMap;

/// Twice the area over the longest edge squared: 0 for a flat triangle, √3/2 for an
/// equilateral one.
pub(crate) fn quality(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    if longest <= 0.0 {
        return 0.0;
    }
    (b - a).cross(c - a).length() / longest
}

/// Flips the longest edge of every triangle of quality under `poor` when that makes both
/// triangles of the pair better and turns neither over, and `may_join` allows the new
/// edge between the pair's third vertices; repeats until nothing changes.
pub(crate) fn flip_slivers(
    positions: &[DVec3],
    indices: &mut [u32],
    poor: f64,
    may_join: impl Fn(u32, u32) -> bool,
) {
    let tri = |indices: &[u32], t: usize| [indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]];
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for t in 0..indices.len() / 3 {
        let [a, b, c] = tri(indices, t);
        for e in [(a, b), (b, c), (c, a)] {
            edges.insert(e, t);
        }
    }
    let p = |v: u32| positions[v as usize];
    let normal = |[a, b, c]: [u32; 3]| (p(b) - p(a)).cross(p(c) - p(a));
    for _ in 0..16 {
        let mut flipped = false;
        for t in 0..indices.len() / 3 {
            let [x, y, z] = tri(indices, t);
            if quality(p(x), p(y), p(z)) >= poor {
                continue;
            }
            // Rotate so that (a, b) is the longest edge and c the vertex opposite it.
            let rotations = [[x, y, z], [y, z, x], [z, x, y]];
            let [a, b, c] = rotations
                .into_iter()
                .max_by(|r, s| {
                    (p(r[1]) - p(r[0]))
                        .length_squared()
                        .total_cmp(&(p(s[1]) - p(s[0])).length_squared())
                })
                .expect("three rotations");
            let Some(&u) = edges.get(&(b, a)) else {
                continue;
            };
            let ut = tri(indices, u);
            let d = ut
                .into_iter()
                .find(|&v| v != a && v != b)
                .expect("a triangle has a third vertex");
            if c == d
                || edges.contains_key(&(c, d))
                || edges.contains_key(&(d, c))
                || !may_join(c, d)
            {
                continue;
            }
            let (n1, n2) = ([c, a, d], [d, b, c]);
            let old = quality(p(a), p(b), p(c)).min(quality(p(b), p(a), p(d)));
            let new = quality(p(c), p(a), p(d)).min(quality(p(d), p(b), p(c)));
            let before = normal([a, b, c]) + normal([b, a, d]);
            if new <= old || normal(n1).dot(before) <= 0.0 || normal(n2).dot(before) <= 0.0 {
                continue;
            }
            for e in [(a, b), (b, c), (c, a), (b, a), (a, d), (d, b)] {
                edges.remove(&e);
            }
            indices[3 * t..3 * t + 3].copy_from_slice(&n1);
            indices[3 * u..3 * u + 3].copy_from_slice(&n2);
            for (tt, [i, j, k]) in [(t, n1), (u, n2)] {
                for e in [(i, j), (j, k), (k, i)] {
                    edges.insert(e, tt);
                }
            }
            flipped = true;
        }
        if !flipped {
            break;
        }
    }
}
