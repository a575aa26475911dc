//! The skin's two sides, the right the mirror image of the left.
//!
//! The body is symmetric across its sagittal plane (x = 0), but a surface extracted on a
//! grid and then simplified, collapsed, flipped and relaxed vertex by vertex is not: each
//! step's order and tie-breaks differ between the sides. Over the 3,000 full-range
//! postures of `examples/skin_folds.rs` and their mirror images, so that each side met
//! the same postures, the left hip of the skin made that way turned 334 triangles over
//! and the right 526, the shoulders the other way round (228 and 158): the two sides of
//! one body folded differently, and no modeller's mirror tool could edit it.
//!
//! So the surface is made on the left side (x ≥ 0) only, its rim on the plane, and
//! mirrored: every vertex off the plane has a partner at its mirror image, the
//! vertices on the plane (the seam) are their own, and every triangle has its mirror
//! image among the triangles. The steps that work on the whole surface (those that need
//! the ring around a vertex on the seam) run over it and are then made symmetric
//! again from their left side ([`Mirror::symmetric`]), keeping to the seam
//! ([`Mirror::same_side`], [`Mirror::may_join`]) so that the left side they leave is
//! whole.

use glam::DVec3;

/// Which side of the sagittal plane a vertex is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    /// On the left (x > 0): made, and kept.
    Left,
    /// On the plane itself (x = 0): its own mirror image.
    Seam,
    /// On the right (x < 0): the mirror image of a vertex on the left.
    Right,
}

/// Which vertex of a symmetric mesh is whose mirror image.
#[derive(Clone, Debug)]
pub(crate) struct Mirror {
    side: Vec<Side>,
    partner: Vec<u32>,
}

/// A point's mirror image across the sagittal plane.
fn reflect(p: DVec3) -> DVec3 {
    DVec3::new(-p.x, p.y, p.z)
}

impl Mirror {
    /// The whole mesh from its left side: `positions` (x ≥ 0; the vertices with x = 0
    /// exactly are the seam) and `indices` (counter-clockwise seen from outside, the open
    /// rim on the seam). The mirrored vertices follow the given ones, in the same order.
    pub fn whole(positions: &[DVec3], indices: &[u32]) -> (Mirror, Vec<DVec3>, Vec<u32>) {
        let n = positions.len();
        let mut side: Vec<Side> = positions
            .iter()
            .map(|p| if p.x == 0.0 { Side::Seam } else { Side::Left })
            .collect();
        let mut partner: Vec<u32> = (0..n as u32).collect();
        let mut all = positions.to_vec();
        for v in 0..n {
            if side[v] == Side::Left {
                partner[v] = all.len() as u32;
                partner.push(v as u32);
                side.push(Side::Right);
                all.push(reflect(positions[v]));
            }
        }
        let mirror = Mirror { side, partner };
        let indices = mirror.with_mirror_image(indices);
        (mirror, all, indices)
    }

    /// `left` (triangles on the left side and the seam) and their mirror images,
    /// wound the other way so that they still face out.
    pub fn with_mirror_image(&self, left: &[u32]) -> Vec<u32> {
        let mut out = left.to_vec();
        for t in left.chunks_exact(3) {
            out.extend([t[0], t[2], t[1]].map(|v| self.partner[v as usize]));
        }
        out
    }

    /// The triangles of `indices` with no vertex on the right.
    pub fn left_of(&self, indices: &[u32]) -> Vec<u32> {
        indices
            .chunks_exact(3)
            .filter(|t| t.iter().all(|&v| self.side[v as usize] != Side::Right))
            .flatten()
            .copied()
            .collect()
    }

    /// Makes the mesh symmetric again after a step over the whole of it: its triangles
    /// on the left and their mirror images, the right's vertices at the mirror images of
    /// the left's, the seam's on the plane.
    pub fn symmetric(&self, positions: &mut [DVec3], indices: &mut Vec<u32>) {
        *indices = self.with_mirror_image(&self.left_of(indices));
        self.symmetric_positions(positions);
    }

    /// The right's vertices moved to the mirror images of the left's, the seam's back
    /// onto the plane.
    pub fn symmetric_positions(&self, positions: &mut [DVec3]) {
        for v in 0..positions.len() {
            match self.side[v] {
                Side::Left => {}
                Side::Seam => positions[v].x = 0.0,
                Side::Right => positions[v] = reflect(positions[self.partner[v] as usize]),
            }
        }
    }

    /// The right's `values` made the `image`s of their partners' (a value for each
    /// vertex).
    pub fn symmetric_values<T>(&self, values: &mut [T], image: impl Fn(&T) -> T) {
        for v in 0..values.len() {
            if self.side[v] == Side::Right {
                values[v] = image(&values[self.partner[v] as usize]);
            }
        }
    }

    /// Vertices along the seam of the left side `left` (its open rim: each edge that no
    /// other triangle has the other way round) about `spacing` m apart, from each loop's
    /// lowest-numbered vertex on: the seam's vertices a simplification keeps, so that
    /// its edges are as long as the others. Meshoptimizer, which collapses a rim vertex
    /// only along the rim, let the seam's edges grow to 1.7 times the others' (1.8
    /// against 1.0 cm on a 1.40 m adult), and the crotch, on the seam, folded.
    pub fn along_seam(left: &[u32], positions: &[DVec3], spacing: f64) -> Vec<u32> {
        let mut edges: std::collections::HashSet<(u32, u32)> = Default::default();
        for t in left.chunks_exact(3) {
            edges.extend([(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]);
        }
        let mut next: std::collections::BTreeMap<u32, u32> = edges
            .iter()
            .filter(|&&(a, b)| !edges.contains(&(b, a)))
            .map(|&(a, b)| (a, b))
            .collect();
        let mut out = Vec::new();
        while let Some((&start, _)) = next.iter().next() {
            let (mut at, mut since) = (start, f64::INFINITY);
            while let Some(to) = next.remove(&at) {
                if since >= spacing {
                    out.push(at);
                    since = 0.0;
                }
                since += positions[at as usize].distance(positions[to as usize]);
                at = to;
            }
        }
        out
    }

    /// Vertex `v` if it is on the left or the seam, else its mirror image: the vertex of
    /// the pair that the left side has.
    pub fn on_left(&self, v: u32) -> u32 {
        match self.side[v as usize] {
            Side::Right => self.partner[v as usize],
            Side::Left | Side::Seam => v,
        }
    }

    /// Whether `a` and `b` lie on the same side (or both on the seam): an edge between
    /// them may be collapsed without taking a seam vertex off the plane.
    pub fn same_side(&self, a: u32, b: u32) -> bool {
        self.side[a as usize] == self.side[b as usize]
    }

    /// Whether an edge flip may join `a` and `b`: not across the plane (one on the left,
    /// the other on the right), nor along it (both on the seam, where the edge and its
    /// mirror image would be one edge of four triangles).
    pub fn may_join(&self, a: u32, b: u32) -> bool {
        !matches!(
            (self.side[a as usize], self.side[b as usize]),
            (Side::Left, Side::Right) | (Side::Right, Side::Left) | (Side::Seam, Side::Seam)
        )
    }

    /// The same mirror for the vertices renumbered by `renumber` (`u32::MAX` for a vertex
    /// dropped) into `count` vertices; a vertex is dropped with its partner, as the
    /// vertices a symmetric mesh's triangles use are.
    pub fn renumbered(&self, renumber: &[u32], count: usize) -> Mirror {
        let mut side = vec![Side::Seam; count];
        let mut partner: Vec<u32> = (0..count as u32).collect();
        for (v, &to) in renumber.iter().enumerate() {
            if to != u32::MAX {
                side[to as usize] = self.side[v];
                partner[to as usize] = renumber[self.partner[v] as usize];
            }
        }
        Mirror { side, partner }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half a square pyramid's surface, x ≥ 0: apex on the seam, base corners two on the
    /// seam and two on the left, a triangle of the base's left half closing it below.
    fn half_pyramid() -> (Vec<DVec3>, Vec<u32>) {
        let positions = vec![
            DVec3::new(0.0, 1.0, 0.0),  // 0 apex (seam)
            DVec3::new(0.0, 0.0, 1.0),  // 1 front (seam)
            DVec3::new(1.0, 0.0, 0.0),  // 2 left
            DVec3::new(0.0, 0.0, -1.0), // 3 back (seam)
        ];
        // Outward: the front-left face and the back-left face, and the base below.
        let indices = vec![0, 1, 2, 0, 2, 3, 1, 3, 2];
        (positions, indices)
    }

    #[test]
    fn a_half_mirrored_is_closed_and_faces_out() {
        let (half, left) = half_pyramid();
        let (mirror, positions, indices) = Mirror::whole(&half, &left);
        assert_eq!(positions.len(), 5, "one vertex off the seam, one partner");
        assert_eq!(positions[4], DVec3::new(-1.0, 0.0, 0.0));
        assert_eq!((mirror.partner[2], mirror.partner[4]), (4, 2));
        assert_eq!(mirror.partner[0], 0);
        assert_eq!((mirror.on_left(4), mirror.on_left(2)), (2, 2));
        let mut edges = std::collections::HashMap::new();
        for t in indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a, b)).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used once each way");
            assert_eq!(
                edges.get(&(b, a)),
                Some(&1),
                "edge {a}-{b} has its opposite"
            );
        }
        let centre = positions.iter().sum::<DVec3>() / positions.len() as f64;
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| positions[v as usize]);
            let normal = (b - a).cross(c - a);
            assert!(
                normal.dot((a + b + c) / 3.0 - centre) > 0.0,
                "{t:?} faces out"
            );
        }
    }

    #[test]
    fn a_step_over_the_whole_is_undone_on_the_right_and_the_seam() {
        let (half, left) = half_pyramid();
        let (mirror, mut positions, mut indices) = Mirror::whole(&half, &left);
        positions[4].y = 0.3;
        positions[0].x = 0.01;
        positions[2].z = 0.2;
        indices.truncate(indices.len() - 3);
        mirror.symmetric(&mut positions, &mut indices);
        assert_eq!(positions[4], DVec3::new(-1.0, 0.0, 0.2));
        assert_eq!(positions[0].x, 0.0);
        assert_eq!(
            indices.len(),
            18,
            "the right's triangles made again from the left"
        );
        assert!(!mirror.may_join(2, 4) && !mirror.may_join(0, 1) && mirror.may_join(0, 4));
        assert!(mirror.same_side(0, 1) && !mirror.same_side(0, 2));
    }
}
