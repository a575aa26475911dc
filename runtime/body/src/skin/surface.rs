//! From volumes to one closed triangle mesh: the volumes are blended into a signed
//! distance field sampled on a grid, and the zero level set is extracted by marching
//! tetrahedra (each grid cube cut into six tetrahedra around its main diagonal, the Kuhn
//! triangulation, which neighbouring cubes share face by face). Unlike marching cubes
//! this has no ambiguous cases, so the surface is closed and every edge is shared by
//! exactly two triangles.

use super::volumes::{Join, Volume};
use glam::DVec3;
use std::collections::HashMap;

/// A blended signed distance field on a regular grid, with which volume dominates each
/// sample.
pub(crate) struct Field {
    origin: DVec3,
    cell: f64,
    dims: [usize; 3],
    values: Vec<f32>,
}

/// How far the samples are moved down and back (along y and z), in cells. Where the
/// samples fall decides which triangles straddle a crease, and the triangles turned over
/// at the ends of the joint ranges change with it as much as with the weights: over
/// `examples/skin_folds.rs`'s 3,000 full-range postures of six sizes, offsets of 0, ¼,
/// ½ and ¾ of a cell gave 1,241, 1,319, 1,032 and 1,415 (the same weights made on the
/// unmirrored surface: 1,146, 1,552, 2,356 and 1,629). Half a cell was chosen by the
/// draws chosen by (350 against 413-521) and held on the draws held out (682 against
/// 828-894); docs/skin-notes.md, "The two sides mirrored".
const GRID_OFFSET: f64 = 0.5;

/// Polynomial smooth minimum (Quilez): equals `min(a, b)` where they differ by more
/// than `k`, and rounds the crease within it.
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

impl Field {
    /// Samples the union of `volumes` with cells of `cell` metres. Two volumes blend
    /// smoothly only when `neighbours` says their joints are adjacent: an arm hanging
    /// beside the torso stays apart from it, while the shoulder blends into the chest.
    pub fn sample(
        volumes: &[Volume],
        cell: f64,
        neighbours: impl Fn(usize, usize) -> bool,
    ) -> Field {
        let margin = cell * 3.0;
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for v in volumes {
            let (a, b) = v.form.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let mut origin = lo - DVec3::splat(margin * 2.0);
        // A whole number of cells left of x = 0, so that the sagittal plane is a plane of
        // samples and the left side can be extracted alone (`triangulate_left`).
        origin.x = (origin.x / cell).floor() * cell;
        origin.y -= GRID_OFFSET * cell;
        origin.z -= GRID_OFFSET * cell;
        let size = hi + DVec3::splat(margin * 2.0) - origin;
        let dims = [0, 1, 2].map(|i| (size[i] / cell).ceil() as usize + 1);
        let far = (margin * 2.0) as f32;
        let n = dims[0] * dims[1] * dims[2];
        let mut values = vec![far; n];
        // Which volume each sample is nearest to (u16::MAX: none yet).
        let mut owner = vec![u16::MAX; n];
        let index = |i: usize, j: usize, k: usize| (k * dims[1] + j) * dims[0] + i;
        for join in [Join::Add, Join::Carve, Join::Insert] {
            for (vi, v) in volumes.iter().enumerate().filter(|(_, v)| v.join == join) {
                let (a, b) = v.form.bounds();
                let reach = margin + v.blend;
                let from = ((a - DVec3::splat(reach) - origin) / cell)
                    .floor()
                    .max(DVec3::ZERO);
                let to = ((b + DVec3::splat(reach) - origin) / cell).ceil();
                for k in from.z as usize..=(to.z as usize).min(dims[2] - 1) {
                    for j in from.y as usize..=(to.y as usize).min(dims[1] - 1) {
                        for i in from.x as usize..=(to.x as usize).min(dims[0] - 1) {
                            let p = origin + DVec3::new(i as f64, j as f64, k as f64) * cell;
                            let d = v.form.distance(p);
                            let at = index(i, j, k);
                            let old = values[at] as f64;
                            let new = match join {
                                Join::Add => {
                                    let o = owner[at];
                                    let k = if o != u16::MAX
                                        && neighbours(volumes[o as usize].joint, v.joint)
                                    {
                                        v.blend.max(volumes[o as usize].blend)
                                    } else {
                                        0.0
                                    };
                                    if d < old {
                                        owner[at] = vi as u16;
                                    }
                                    smooth_min(old, d, k)
                                }
                                Join::Carve => -smooth_min(-old, d, v.blend),
                                Join::Insert => old.min(d),
                            };
                            values[at] = new.clamp(-far as f64, far as f64) as f32;
                        }
                    }
                }
            }
        }
        Field {
            origin,
            cell,
            dims,
            values,
        }
    }

    /// The field at `p`, interpolated trilinearly between the samples (the far value
    /// outside the grid).
    pub fn value_at(&self, p: DVec3) -> f64 {
        let g = (p - self.origin) / self.cell;
        let [nx, ny, nz] = self.dims;
        if g.min_element() < 0.0
            || g.x >= (nx - 1) as f64
            || g.y >= (ny - 1) as f64
            || g.z >= (nz - 1) as f64
        {
            return self.values[0] as f64;
        }
        let (i, j, k) = (g.x as usize, g.y as usize, g.z as usize);
        let f = g - DVec3::new(i as f64, j as f64, k as f64);
        let at = |di: usize, dj: usize, dk: usize| {
            self.values[((k + dk) * ny + j + dj) * nx + i + di] as f64
        };
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f.x);
        let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f.x);
        let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f.x);
        let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f.x);
        lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z)
    }

    /// The field's gradient at `p` by central differences half a cell apart: outwards,
    /// the surface's normal there (not normalised).
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let h = self.cell * 0.5;
        let d =
            |axis: DVec3| (self.value_at(p + axis * h) - self.value_at(p - axis * h)) / (2.0 * h);
        DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z))
    }

    /// `p` moved onto the zero level set along the field's gradient (two Newton steps;
    /// `p` itself where the gradient vanishes).
    pub fn project(&self, p: DVec3) -> DVec3 {
        let mut p = p;
        for _ in 0..2 {
            let gradient = self.gradient(p);
            let g2 = gradient.length_squared();
            if g2 < 1e-6 {
                return p;
            }
            p -= gradient * (self.value_at(p) / g2);
        }
        p
    }

    /// Extracts the zero level set: vertex positions and counter-clockwise triangles
    /// (seen from outside).
    #[cfg(test)]
    pub fn triangulate(&self) -> (Vec<DVec3>, Vec<u32>) {
        self.triangulate_from(0)
    }

    /// Extracts the zero level set on the left of the sagittal plane (x ≥ 0): an open
    /// surface whose rim lies on the plane, its vertices there at x = 0 exactly, to be
    /// mirrored (`mirror`). Empty when the field does not reach the plane.
    pub fn triangulate_left(&self) -> (Vec<DVec3>, Vec<u32>) {
        let plane = (-self.origin.x / self.cell).round();
        if plane < 0.0 || plane as usize >= self.dims[0] {
            return (Vec::new(), Vec::new());
        }
        self.triangulate_from(plane as usize)
    }

    /// The zero level set over the cells from column `first` on (along x).
    fn triangulate_from(&self, first: usize) -> (Vec<DVec3>, Vec<u32>) {
        let [nx, ny, nz] = self.dims;
        let index = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
        // Samples within a twentieth of a cell of the level set are pushed off it (one on
        // it counts as outside), so that no crossing lands on or next to a grid point,
        // where neighbouring crossings would make needle-thin triangles.
        let near = (self.cell * 0.05) as f32;
        let value = |at: usize| {
            let v = self.values[at];
            if v.abs() >= near {
                v
            } else if v < 0.0 {
                -near
            } else {
                near
            }
        };
        let position = |at: usize| {
            let i = at % nx;
            let j = (at / nx) % ny;
            let k = at / (nx * ny);
            self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.cell
        };
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut on_edge: HashMap<(u32, u32), u32> = HashMap::new();
        let mut crossing = |a: usize, b: usize, vertices: &mut Vec<DVec3>| -> u32 {
            let key = if a < b {
                (a as u32, b as u32)
            } else {
                (b as u32, a as u32)
            };
            *on_edge.entry(key).or_insert_with(|| {
                let (va, vb) = (value(a) as f64, value(b) as f64);
                let t = va / (va - vb);
                vertices.push(position(a).lerp(position(b), t));
                (vertices.len() - 1) as u32
            })
        };
        // The six tetrahedra of the Kuhn triangulation: from corner 0 to corner 7 along
        // each ordering of the axes. Corner bits: 1 = +x, 2 = +y, 4 = +z.
        const TETS: [[usize; 4]; 6] = [
            [0, 1, 3, 7],
            [0, 1, 5, 7],
            [0, 2, 3, 7],
            [0, 2, 6, 7],
            [0, 4, 5, 7],
            [0, 4, 6, 7],
        ];
        let mut corners = [0usize; 8];
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in first..nx - 1 {
                    for (c, slot) in corners.iter_mut().enumerate() {
                        *slot = index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                    }
                    let inside = corners.iter().filter(|&&c| value(c) < 0.0).count();
                    if inside == 0 || inside == 8 {
                        continue;
                    }
                    for tet in TETS {
                        let t = tet.map(|c| corners[c]);
                        let (ins, outs): (Vec<usize>, Vec<usize>) =
                            t.iter().partition(|&&c| value(c) < 0.0);
                        let tris: Vec<[u32; 3]> = match (ins.len(), outs.len()) {
                            (1, 3) | (3, 1) => {
                                let (one, three) = if ins.len() == 1 {
                                    (&ins, &outs)
                                } else {
                                    (&outs, &ins)
                                };
                                vec![[0, 1, 2].map(|m| crossing(one[0], three[m], &mut vertices))]
                            }
                            (2, 2) => {
                                let a = crossing(ins[0], outs[0], &mut vertices);
                                let b = crossing(ins[0], outs[1], &mut vertices);
                                let c = crossing(ins[1], outs[1], &mut vertices);
                                let d = crossing(ins[1], outs[0], &mut vertices);
                                vec![[a, b, c], [a, c, d]]
                            }
                            _ => continue,
                        };
                        // Orient each triangle so that its normal points from the inside
                        // corners to the outside ones.
                        let centroid = |cs: &[usize]| {
                            cs.iter().map(|&c| position(c)).sum::<DVec3>() / cs.len() as f64
                        };
                        let outward = centroid(&outs) - centroid(&ins);
                        for [a, b, c] in tris {
                            let (pa, pb, pc) = (
                                vertices[a as usize],
                                vertices[b as usize],
                                vertices[c as usize],
                            );
                            if (pb - pa).cross(pc - pa).dot(outward) >= 0.0 {
                                indices.extend_from_slice(&[a, b, c]);
                            } else {
                                indices.extend_from_slice(&[a, c, b]);
                            }
                        }
                    }
                }
            }
        }
        (vertices, indices)
    }
}

/// A sphere of `radius` about the origin sampled with cells of `cell` metres: the field
/// the tests of the mesh's smoothing passes work on.
#[cfg(test)]
pub(crate) fn sampled_sphere(radius: f64, cell: f64) -> Field {
    use super::volumes::{Form, Region};
    let sphere = Volume {
        form: Form::Ellipsoid {
            center: DVec3::ZERO,
            radii: DVec3::splat(radius),
            rotation: glam::DQuat::IDENTITY,
        },
        joint: 0,
        region: Region::Skin,
        join: Join::Add,
        blend: 0.0,
        reach: 0.01,
    };
    Field::sample(&[sphere], cell, |_, _| false)
}
