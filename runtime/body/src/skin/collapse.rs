//! Tiny-edge removal. Where the simplification had to keep the dense surface (vertices
//! locked around a spot that would otherwise pinch: an armpit, a fingertip), the marching
//! tetrahedra's smallest triangles survive, with edges of a fraction of a millimetre.
//! Skinning moves their vertices by nearly the same amount, and the small difference
//! left turns them over at the slightest bend. Each such edge is collapsed to its
//! midpoint when that keeps the surface closed and manifold (the link condition: the two
//! ends share no neighbour but the two triangles' third vertices) and turns no triangle
//! around it over.

use glam::DVec3;

/// Collapses every edge shorter than `shortest` that can go (see the module note) and
/// whose ends `may_merge` allows, moving the kept vertex to the edge's midpoint and
/// dropping the two triangles on the edge; the other vertex is left unused.
pub(crate) fn collapse_short_edges(
    positions: &mut [DVec3],
    indices: &mut Vec<u32>,
    shortest: f64,
    may_merge: impl Fn(u32, u32) -> bool,
) {
    let n = positions.len();
    let mut triangles: Vec<Option<[u32; 3]>> = indices
        .chunks_exact(3)
        .map(|t| Some([t[0], t[1], t[2]]))
        .collect();
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, t) in triangles.iter().enumerate() {
        for &v in t.iter().flatten() {
            around[v as usize].push(i);
        }
    }
    let normal = |p: &[DVec3], [a, b, c]: [u32; 3]| {
        (p[b as usize] - p[a as usize]).cross(p[c as usize] - p[a as usize])
    };
    for _ in 0..8 {
        let mut changed = false;
        for t in 0..triangles.len() {
            let Some(tri) = triangles[t] else { continue };
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if (positions[a as usize] - positions[b as usize]).length() >= shortest
                    || !may_merge(a, b)
                {
                    continue;
                }
                if collapse(positions, &mut triangles, &mut around, a, b, &normal) {
                    changed = true;
                    break;
                }
            }
        }
        if !changed {
            break;
        }
    }
    indices.clear();
    indices.extend(triangles.iter().flatten().flatten());
}

/// Collapses edge `a`-`b` into `a` at its midpoint if the surface stays closed and
/// manifold and no triangle turns over; returns whether it did.
fn collapse(
    positions: &mut [DVec3],
    triangles: &mut [Option<[u32; 3]>],
    around: &mut [Vec<usize>],
    a: u32,
    b: u32,
    normal: &impl Fn(&[DVec3], [u32; 3]) -> DVec3,
) -> bool {
    let live = |v: u32, triangles: &[Option<[u32; 3]>]| -> Vec<usize> {
        around[v as usize]
            .iter()
            .copied()
            .filter(|&t| triangles[t].is_some_and(|tri| tri.contains(&v)))
            .collect()
    };
    let (at_a, at_b) = (live(a, triangles), live(b, triangles));
    let shared: Vec<usize> = at_a.iter().copied().filter(|t| at_b.contains(t)).collect();
    if shared.len() != 2 {
        return false;
    }
    let ring = |list: &[usize], v: u32| -> Vec<u32> {
        let mut r: Vec<u32> = list
            .iter()
            .flat_map(|&t| triangles[t].expect("live"))
            .filter(|&u| u != v)
            .collect();
        r.sort_unstable();
        r.dedup();
        r
    };
    let (ring_a, ring_b) = (ring(&at_a, a), ring(&at_b, b));
    let opposite: Vec<u32> = shared
        .iter()
        .flat_map(|&t| triangles[t].expect("live"))
        .filter(|&u| u != a && u != b)
        .collect();
    let common: Vec<u32> = ring_a
        .iter()
        .copied()
        .filter(|u| *u != b && ring_b.contains(u))
        .collect();
    // The link condition, and no vertex left with fewer than three triangles.
    if common.len() != 2
        || !common.iter().all(|u| opposite.contains(u))
        || ring_a.len() + ring_b.len() < 10
        || opposite.iter().any(|&u| live(u, triangles).len() < 4)
    {
        return false;
    }
    let mid = (positions[a as usize] + positions[b as usize]) / 2.0;
    let old = [positions[a as usize], positions[b as usize]];
    let moved: Vec<usize> = at_a
        .iter()
        .chain(&at_b)
        .copied()
        .filter(|t| !shared.contains(t))
        .collect();
    let before: Vec<DVec3> = moved
        .iter()
        .map(|&t| normal(positions, triangles[t].expect("live")))
        .collect();
    positions[a as usize] = mid;
    positions[b as usize] = mid;
    let turns_over = moved.iter().zip(&before).any(|(&t, was)| {
        let tri = triangles[t]
            .expect("live")
            .map(|v| if v == b { a } else { v });
        let now = normal(positions, tri);
        now.dot(*was) <= 0.25 * now.length() * was.length()
    });
    if turns_over {
        positions[a as usize] = old[0];
        positions[b as usize] = old[1];
        return false;
    }
    for &t in &shared {
        triangles[t] = None;
    }
    for &t in &at_b {
        if let Some(tri) = triangles[t].as_mut() {
            for v in tri.iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            around[a as usize].push(t);
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// An octahedron split twice (every triangle into four) and pushed onto the unit
    /// sphere: a closed surface of genus 0 with 128 triangles.
    fn sphere() -> (Vec<DVec3>, Vec<u32>) {
        let mut positions = vec![
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ];
        let mut indices = vec![
            0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
        ];
        for _ in 0..2 {
            let mut middles: HashMap<(u32, u32), u32> = HashMap::new();
            let mut middle = |a: u32, b: u32, positions: &mut Vec<DVec3>| {
                *middles.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let m = (positions[a as usize] + positions[b as usize]).normalize();
                    positions.push(m);
                    positions.len() as u32 - 1
                })
            };
            let mut next = Vec::new();
            for t in indices.chunks_exact(3) {
                let (a, b, c) = (t[0], t[1], t[2]);
                let ab = middle(a, b, &mut positions);
                let bc = middle(b, c, &mut positions);
                let ca = middle(c, a, &mut positions);
                next.extend([a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
            }
            indices = next;
        }
        (positions, indices)
    }

    #[test]
    fn a_tiny_edge_goes_and_the_surface_stays_closed_and_outward() {
        let (mut positions, mut indices) = sphere();
        // Pull a vertex next to its neighbour along one edge.
        let (a, b) = (indices[0] as usize, indices[1] as usize);
        positions[b] = (positions[a] * 0.999 + positions[b] * 0.001).normalize();
        let shortest = 0.01;
        let (pa, pb) = (positions[a], positions[b]);
        collapse_short_edges(&mut positions, &mut indices, shortest, |_, _| true);
        assert_eq!(
            indices.len() / 3,
            126,
            "one edge collapsed, two triangles gone"
        );
        assert!(
            !indices.contains(&(b as u32)),
            "the pulled vertex merged into its neighbour"
        );
        assert_eq!(positions[a], (pa + pb) / 2.0, "at the edge's midpoint");
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in indices.chunks_exact(3) {
            for (x, y) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((x, y)).or_default() += 1;
                assert!((positions[x as usize] - positions[y as usize]).length() >= shortest);
            }
            let [p, q, r] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            assert!(
                (q - p).cross(r - p).dot(p + q + r) > 0.0,
                "a triangle turned over"
            );
        }
        assert!(edges
            .iter()
            .all(|(&(x, y), &n)| n == 1 && edges.get(&(y, x)) == Some(&1)));
        let used: std::collections::HashSet<u32> = indices.iter().copied().collect();
        let chi = used.len() as i64 - (edges.len() / 2) as i64 + (indices.len() / 3) as i64;
        assert_eq!(chi, 2);
    }
}
