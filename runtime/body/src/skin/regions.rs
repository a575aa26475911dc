//! Where the edges between the skin's regions fall between vertices.
//!
//! Each vertex has one [`Region`] (bare skin, shirt, trousers, shoes, eye white, pupil),
//! that of the volume nearest to it; coloured by vertex, the edges between regions
//! (sleeves, waistband, collar, shoes, eyes) follow the simplified triangles, zigzag a
//! triangle wide, and blur across it. The rule itself is smooth: the region is the one
//! whose volumes are nearest. So each vertex also keeps how far it lies from each
//! region's volumes ([`RegionDistances`]); interpolated across a triangle, the region
//! nearest at each pixel gives an edge that runs through the triangles along the
//! volumes' own boundary. The viewer colours the skin so; for files, which colour by
//! vertex, the surface is cut along the same edges ([`CutSkin`]).

use super::volumes::{Form, Join, Region, Volume};
use glam::DVec3;

/// How far a vertex lies from each region's volumes (m): the nearest region is the
/// vertex's own, and between vertices the interpolated distances say where the edge
/// runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RegionDistances {
    /// From the nearest volume of bare skin, shirt, trousers and shoes, in that order
    /// (the order of [`Region`]).
    pub cloth: [f32; 4],
    /// From the nearest eyeball.
    pub eye: f32,
    /// Where the vertex lies from that eyeball's centre, in its radii (a point of its
    /// surface is a unit vector): the pupil is the front, beyond [`PUPIL_EDGE`] along z.
    pub on_eye: [f32; 3],
}

impl RegionDistances {
    /// The region these distances make nearest: the same rule as the vertex's own region
    /// before the regions are smoothed.
    pub fn region(&self) -> Region {
        let (cloth, nearest) = self
            .cloth
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, &d)| (i, d))
            .expect("four distances");
        if self.eye < nearest {
            if self.on_eye[2] as f64 > PUPIL_EDGE {
                Region::Pupil
            } else {
                Region::Eye
            }
        } else {
            [Region::Skin, Region::Shirt, Region::Trousers, Region::Shoes][cloth]
        }
    }

    /// The distances at this vertex's mirror image across the sagittal plane: the same,
    /// but for the side of the eyeball it lies on.
    pub(crate) fn mirrored(&self) -> RegionDistances {
        let [x, y, z] = self.on_eye;
        RegionDistances {
            on_eye: [-x, y, z],
            ..*self
        }
    }
}

/// The pupil covers an eyeball's front beyond this fraction of its depth (its edge a
/// circle 41° from the front).
pub const PUPIL_EDGE: f64 = 0.75;

/// How far `p` lies from each region's `volumes` (carved volumes, the eye sockets, do
/// not count).
pub(crate) fn distances_at(p: DVec3, volumes: &[Volume]) -> RegionDistances {
    let mut cloth = [f64::INFINITY; 4];
    let (mut eye, mut on_eye) = (f64::INFINITY, DVec3::splat(-1e3));
    for v in volumes.iter().filter(|v| v.join != Join::Carve) {
        let d = v.form.distance(p).abs();
        match v.region {
            Region::Eye | Region::Pupil => {
                if d < eye {
                    eye = d;
                    if let Form::Ellipsoid { center, radii, .. } = v.form {
                        on_eye = (p - center) / radii;
                    }
                }
            }
            region => {
                let slot = &mut cloth[region as usize];
                *slot = slot.min(d);
            }
        }
    }
    // A body without one of the regions: far, but finite for the GPU.
    let finite = |d: f64| d.min(1e3) as f32;
    RegionDistances {
        cloth: cloth.map(finite),
        eye: finite(eye),
        on_eye: on_eye.as_vec3().to_array(),
    }
}

/// The skin's surface cut along the edges between its regions, for files that colour by
/// vertex: every triangle lies in one region, and the edges run through the old
/// triangles where the volumes put them (as the viewer draws them per pixel) instead of
/// along their sides. A vertex on an edge is there twice, once per region, at the same
/// place.
#[derive(Clone, Debug, Default)]
pub struct CutSkin {
    /// Bind-pose positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit normals.
    pub normals: Vec<[f32; 3]>,
    /// Skinning slots, as [`Skin::joints`](super::Skin::joints).
    pub joints: Vec<[u16; 4]>,
    /// Their weights, summing to one.
    pub weights: Vec<[f32; 4]>,
    /// Each vertex's region.
    pub regions: Vec<Region>,
    /// Triangles, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

/// Where between regions `a` and `b` a vertex at `d` lies: negative nearer `a`, positive
/// nearer `b` (the rule of [`RegionDistances::region`]).
fn gap(d: &RegionDistances, a: Region, b: Region) -> f64 {
    let eyes = |r: Region| matches!(r, Region::Eye | Region::Pupil);
    let distance = |r: Region| {
        if eyes(r) {
            d.eye
        } else {
            d.cloth[r as usize]
        }
    };
    if eyes(a) && eyes(b) {
        // White against pupil: the pupil is the front.
        let front = d.on_eye[2] as f64 - PUPIL_EDGE;
        return if a == Region::Pupil { -front } else { front };
    }
    (distance(a) - distance(b)) as f64
}

impl CutSkin {
    /// Cuts `skin`'s full-detail surface along the edges between regions. A triangle
    /// touching three regions (where three meet) is cut into three, one piece per
    /// corner meeting at its centroid.
    pub fn new(skin: &super::Skin) -> CutSkin {
        Self::cutting(skin, &skin.indices)
    }

    /// Cuts `skin`'s coarse level of detail (its [`far_indices`](super::Skin::far_indices))
    /// the same way, so that drawn coloured by vertex its edges between regions stay
    /// sharp (across its triangles, several centimetres wide, they blurred).
    pub fn far(skin: &super::Skin) -> CutSkin {
        Self::cutting(skin, &skin.far_indices)
    }

    /// Cuts `skin`'s coarsest level of detail (its
    /// [`farthest_indices`](super::Skin::farthest_indices)) the same way.
    pub fn farthest(skin: &super::Skin) -> CutSkin {
        Self::cutting(skin, &skin.farthest_indices)
    }

    /// Cuts the surface of `skin`'s vertices made by `triangles`.
    fn cutting(skin: &super::Skin, triangles: &[u32]) -> CutSkin {
        let regions: Vec<Region> = skin.region_distances.iter().map(|d| d.region()).collect();
        let mut cut = CutSkin::default();
        // Each skin vertex's copy in each region it is used in, and each edge's cut point
        // per region: neighbouring triangles share them.
        let mut copies: std::collections::HashMap<(u32, Region), u32> = Default::default();
        let mut points: std::collections::HashMap<(u32, u32, Region), u32> = Default::default();
        let corner = |cut: &mut CutSkin,
                      copies: &mut std::collections::HashMap<(u32, Region), u32>,
                      v: u32,
                      region: Region| {
            *copies.entry((v, region)).or_insert_with(|| {
                let i = v as usize;
                cut.push(
                    skin.positions[i],
                    skin.normals[i],
                    (skin.joints[i], skin.weights[i]),
                    region,
                )
            })
        };
        // The point on the edge from skin vertex `a` to `b` where the interpolated gap
        // between their regions is zero, as its copy in `region`: made once per edge
        // and region, from the edge's lower-numbered end, so that the triangles on both
        // sides of the edge share it.
        let mut cross = |cut: &mut CutSkin, a: u32, b: u32, region: Region| {
            let (a, b) = (a.min(b), a.max(b));
            *points.entry((a, b, region)).or_insert_with(|| {
                let (ra, rb) = (regions[a as usize], regions[b as usize]);
                let (ga, gb) = (
                    gap(&skin.region_distances[a as usize], ra, rb),
                    gap(&skin.region_distances[b as usize], ra, rb),
                );
                let s = (ga / (ga - gb)).clamp(0.0, 1.0) as f32;
                cut.push_blend(skin, &[(a as usize, 1.0 - s), (b as usize, s)], region)
            })
        };
        for t in triangles.chunks_exact(3) {
            let t = [t[0], t[1], t[2]];
            let r = t.map(|v| regions[v as usize]);
            if r[0] == r[1] && r[1] == r[2] {
                for k in 0..3 {
                    let v = corner(&mut cut, &mut copies, t[k], r[k]);
                    cut.indices.push(v);
                }
                continue;
            }
            let lone = (0..3).find(|&k| r[(k + 1) % 3] == r[(k + 2) % 3]);
            let Some(k) = lone else {
                // Three regions: each corner's piece runs from it along its two edges
                // to their cut points and the centroid, where the three meet.
                let centre = |cut: &mut CutSkin, region: Region| {
                    let third = 1.0 / 3.0;
                    let blend = t.map(|v| (v as usize, third));
                    cut.push_blend(skin, &blend, region)
                };
                for k in 0..3 {
                    let [o, p, q] = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
                    let region = r[k];
                    let (op, oq) = (cross(&mut cut, o, p, region), cross(&mut cut, o, q, region));
                    let m = centre(&mut cut, region);
                    let o = corner(&mut cut, &mut copies, o, region);
                    cut.indices.extend([o, op, m, o, m, oq]);
                }
                continue;
            };
            // Vertex `k` alone in its region, the other two in another: the edge crosses
            // the two sides from `k`.
            let (alone, rest) = (r[k], r[(k + 1) % 3]);
            let [o, p, q] = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
            let (op_a, oq_a) = (cross(&mut cut, o, p, alone), cross(&mut cut, o, q, alone));
            let (op_b, oq_b) = (cross(&mut cut, o, p, rest), cross(&mut cut, o, q, rest));
            let o = corner(&mut cut, &mut copies, o, alone);
            let (p, q) = (
                corner(&mut cut, &mut copies, p, rest),
                corner(&mut cut, &mut copies, q, rest),
            );
            // The corner's triangle, and the quad on the other side in two along its
            // shorter diagonal: a rule of the quad's shape alone, so that the mirror
            // image of a cut is cut the same way (by the corners' order, the two sides
            // of the skin were cut along different diagonals in 876 of 24,874 triangles).
            let at = |v: u32| glam::Vec3::from(cut.positions[v as usize]);
            let quad = if at(op_b).distance(at(q)) <= at(p).distance(at(oq_b)) {
                [op_b, p, q, op_b, q, oq_b]
            } else {
                [op_b, p, oq_b, p, q, oq_b]
            };
            cut.indices.extend([o, op_a, oq_a]);
            cut.indices.extend(quad);
        }
        cut
    }

    /// Appends a vertex; returns its index.
    fn push(
        &mut self,
        position: [f32; 3],
        normal: [f32; 3],
        (joints, weights): ([u16; 4], [f32; 4]),
        region: Region,
    ) -> u32 {
        self.positions.push(position);
        self.normals.push(normal);
        self.joints.push(joints);
        self.weights.push(weights);
        self.regions.push(region);
        (self.positions.len() - 1) as u32
    }

    /// Appends the blend of skin vertices `shares` (each vertex with its share, the
    /// shares summing to one), its weights the four heaviest of theirs blended and
    /// normalised; returns its index.
    fn push_blend(&mut self, skin: &super::Skin, shares: &[(usize, f32)], region: Region) -> u32 {
        let mix = |of: &[[f32; 3]]| {
            let mut out = [0.0f32; 3];
            for &(v, share) in shares {
                for (o, x) in out.iter_mut().zip(of[v]) {
                    *o += x * share;
                }
            }
            out
        };
        let normal = glam::Vec3::from(mix(&skin.normals))
            .normalize_or_zero()
            .to_array();
        let mut blend: Vec<(u16, f32)> = Vec::with_capacity(12);
        for &(v, share) in shares {
            for (&j, &w) in skin.joints[v].iter().zip(&skin.weights[v]) {
                match blend.iter_mut().find(|(k, _)| *k == j) {
                    Some((_, total)) => *total += w * share,
                    None => blend.push((j, w * share)),
                }
            }
        }
        blend.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
        blend.truncate(4);
        let sum: f32 = blend.iter().map(|(_, w)| w).sum();
        let (mut joints, mut weights) = ([0u16; 4], [0f32; 4]);
        // Unused slots are joint 0 with weight 0, as in the skin.
        for (i, (j, w)) in blend.into_iter().filter(|(_, w)| *w > 0.0).enumerate() {
            joints[i] = j;
            weights[i] = w / sum;
        }
        self.push(mix(&skin.positions), normal, (joints, weights), region)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    fn volume(form: Form, region: Region) -> Volume {
        Volume {
            form,
            joint: 0,
            region,
            join: Join::Add,
            blend: 0.0,
            reach: 0.01,
        }
    }

    #[test]
    fn the_nearest_regions_volume_wins_and_the_edge_lies_between_vertices() {
        // A bare forearm along -x meeting a sleeve along +x at x = 0.
        let arm = |a: f64, b: f64, region| {
            volume(
                Form::Cone {
                    a: DVec3::new(a, 0.0, 0.0),
                    b: DVec3::new(b, 0.0, 0.0),
                    ra: 0.05,
                    rb: 0.05,
                },
                region,
            )
        };
        let volumes = [arm(-0.3, 0.0, Region::Skin), arm(0.0, 0.3, Region::Shirt)];
        let at = |x: f64| distances_at(DVec3::new(x, 0.05, 0.0), &volumes);
        assert_eq!(at(-0.1).region(), Region::Skin);
        assert_eq!(at(0.1).region(), Region::Shirt);
        // Two vertices 3 cm apart, 1 cm and 2 cm either side of the edge: the
        // interpolated distances cross between them, near where the volumes meet (the
        // distances are not linear across the span: 4 mm off here).
        let (a, b) = (at(-0.01), at(0.02));
        let gap = |d: &RegionDistances| (d.cloth[1] - d.cloth[0]) as f64;
        let t = gap(&a) / (gap(&a) - gap(&b));
        let crossing = -0.01 + 0.03 * t;
        assert!(
            (0.0..1.0).contains(&t) && crossing.abs() < 0.005,
            "edge drawn at x = {crossing}"
        );
        // Regions the body lacks are far, not infinite.
        assert!(a.cloth[2] > 1.0 && a.cloth[2].is_finite() && a.eye.is_finite());
    }

    #[test]
    fn a_triangle_where_three_regions_meet_is_cut_in_three_and_the_cut_stays_closed() {
        use crate::transform::Transform;
        // A tetrahedron with a corner in each of three regions on two faces and in two
        // regions on the other two, whose cuts share the first two's edges' points.
        let corners = [
            ([0.0, 0.0, 1.0], Region::Skin),
            ([1.0, 0.0, 0.0], Region::Shirt),
            ([0.0, 1.0, 0.0], Region::Trousers),
            ([0.0, 0.0, 0.0], Region::Skin),
        ];
        let distances = |own: Region| RegionDistances {
            cloth: [0, 1, 2, 3].map(|r| if r == own as usize { 0.0 } else { 0.02 }),
            eye: 1.0,
            on_eye: [0.0; 3],
        };
        let skin = crate::skin::Skin {
            positions: corners.map(|(p, _)| p).to_vec(),
            normals: vec![[0.0, 1.0, 0.0]; 4],
            joints: vec![[0; 4]; 4],
            weights: vec![[1.0, 0.0, 0.0, 0.0]; 4],
            regions: corners.map(|(_, r)| r).to_vec(),
            region_distances: corners.map(|(_, r)| distances(r)).to_vec(),
            // Counter-clockwise seen from outside.
            indices: vec![0, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0],
            far_indices: Vec::new(),
            farthest_indices: Vec::new(),
            rest: vec![Transform::IDENTITY],
            made: vec![Transform::IDENTITY],
            helpers: Vec::new(),
        };
        let cut = CutSkin::new(&skin);
        for t in cut.indices.chunks_exact(3) {
            let r = t
                .iter()
                .map(|&v| cut.regions[v as usize])
                .collect::<Vec<_>>();
            assert!(r[0] == r[1] && r[1] == r[2], "triangle {t:?} in {r:?}");
        }
        assert_eq!(
            cut.indices.len() / 3,
            2 * 6 + 2 * 3,
            "a face of three regions in three pieces of two triangles, of two in three"
        );
        let area = |positions: &[[f32; 3]], indices: &[u32]| -> f32 {
            indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [0, 1, 2].map(|k| glam::Vec3::from(positions[t[k] as usize]));
                    (b - a).cross(c - a).length() / 2.0
                })
                .sum()
        };
        let (before, after) = (
            area(&skin.positions, &skin.indices),
            area(&cut.positions, &cut.indices),
        );
        assert!(
            (before - after).abs() < 1e-5,
            "area {before} became {after}"
        );
        // Welded by position, every edge is there once each way.
        let mut welded: std::collections::HashMap<[u32; 3], u32> = Default::default();
        let id: Vec<u32> = cut
            .positions
            .iter()
            .map(|p| {
                let n = welded.len() as u32;
                *welded.entry(p.map(f32::to_bits)).or_insert(n)
            })
            .collect();
        let mut edges: std::collections::HashMap<(u32, u32), u32> = Default::default();
        for t in cut.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((id[a as usize], id[b as usize])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} open");
        }
    }

    #[test]
    fn an_eyeballs_front_is_its_pupil() {
        let eye = volume(
            Form::Ellipsoid {
                center: DVec3::ZERO,
                radii: DVec3::splat(0.012),
                rotation: DQuat::IDENTITY,
            },
            Region::Eye,
        );
        let skin = volume(
            Form::Ellipsoid {
                center: DVec3::new(0.0, 0.0, -0.05),
                radii: DVec3::splat(0.05),
                rotation: DQuat::IDENTITY,
            },
            Region::Skin,
        );
        let volumes = [skin, eye];
        let front = distances_at(DVec3::new(0.0, 0.0, 0.012), &volumes);
        let side = distances_at(DVec3::new(0.012, 0.0, 0.0), &volumes);
        assert_eq!(front.region(), Region::Pupil);
        assert_eq!(side.region(), Region::Eye);
        assert!(front.on_eye[2] > 0.99 && side.on_eye[0] > 0.99);
    }
}
