//! Tessellated unit meshes for every [`Shape`]. A shape is drawn as a unit mesh with a
//! per-instance non-uniform scale: boxes as a cube, spheres and ellipsoids as a sphere,
//! cylinders and frustums as a frustum of the right radius ratio.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::f32::consts::TAU;
use troupe_body::Shape;

/// A mesh vertex: position and unit normal in the unit mesh's frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct Vertex {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
}

/// Which unit mesh a shape uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum MeshKey {
    /// The cube [-1, 1]³.
    Cube,
    /// The unit sphere.
    Sphere,
    /// A coarse unit sphere for small parts (joints of bones and fingers).
    SphereLow,
    /// A coarse unit cylinder (y from −1 to 1) for bones and fingers.
    CylinderLow,
    /// A frustum along Y from y = −1 to 1 with bottom and top radii in thousandths (the
    /// larger one is 1000).
    Frustum(u16, u16),
}

/// A unit mesh and the scale that turns it into `shape`.
pub(crate) fn shape_mesh(shape: &Shape) -> (MeshKey, Vec3) {
    match *shape {
        Shape::Box { half_extents } => (MeshKey::Cube, half_extents.as_vec3()),
        Shape::Sphere { radius } => (MeshKey::Sphere, Vec3::splat(radius as f32)),
        Shape::Ellipsoid { radii } => (MeshKey::Sphere, radii.as_vec3()),
        Shape::Cylinder { radius, height } => (
            MeshKey::Frustum(1000, 1000),
            Vec3::new(radius as f32, height as f32 * 0.5, radius as f32),
        ),
        Shape::Frustum {
            bottom_radius,
            top_radius,
            height,
        } => {
            let m = bottom_radius.max(top_radius).max(1e-9);
            let q = |r: f64| ((r / m) * 1000.0).round().clamp(0.0, 1000.0) as u16;
            (
                MeshKey::Frustum(q(bottom_radius), q(top_radius)),
                Vec3::new(m as f32, height as f32 * 0.5, m as f32),
            )
        }
    }
}

/// Builds the vertices and triangle indices of a unit mesh.
pub(crate) fn build(key: MeshKey) -> (Vec<Vertex>, Vec<u32>) {
    match key {
        MeshKey::Cube => cube(),
        MeshKey::Sphere => sphere(12, 20),
        MeshKey::SphereLow => sphere(5, 8),
        MeshKey::CylinderLow => frustum(1.0, 1.0, 8),
        MeshKey::Frustum(b, t) => frustum(b as f32 / 1000.0, t as f32 / 1000.0, 24),
    }
}

fn cube() -> (Vec<Vertex>, Vec<u32>) {
    let mut v = Vec::with_capacity(24);
    let mut i = Vec::with_capacity(36);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = v.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[u] = a;
                p[w] = b * sign;
                v.push(Vertex { pos: p, normal: n });
            }
            i.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    (v, i)
}

fn sphere(rings: u32, segments: u32) -> (Vec<Vertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut i = Vec::new();
    for r in 0..=rings {
        let phi = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let theta = TAU * s as f32 / segments as f32;
            let n = [phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin()];
            v.push(Vertex { pos: n, normal: n });
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let b = a + row;
            // At a pole one side of the quad is a single point: only its other triangle
            // has an area (the bottom pole's points differ by rounding, so the lost one
            // would be a needle turned either way, and culled or not at random).
            if r > 0 {
                i.extend_from_slice(&[a, a + 1, b]);
            }
            if r + 1 < rings {
                i.extend_from_slice(&[a + 1, b + 1, b]);
            }
        }
    }
    (v, i)
}

fn frustum(bottom: f32, top: f32, segments: u32) -> (Vec<Vertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut i = Vec::new();
    // Side: radius goes from `bottom` at y = -1 to `top` at y = 1.
    let ny = (bottom - top) * 0.5;
    for s in 0..=segments {
        let theta = TAU * s as f32 / segments as f32;
        let (c, sn) = (theta.cos(), theta.sin());
        let n = Vec3::new(c, ny, sn).normalize();
        for (r, y) in [(bottom, -1.0), (top, 1.0)] {
            v.push(Vertex {
                pos: [r * c, y, r * sn],
                normal: n.to_array(),
            });
        }
    }
    for s in 0..segments {
        let a = 2 * s;
        i.extend_from_slice(&[a, a + 1, a + 2, a + 1, a + 3, a + 2]);
    }
    // Caps.
    for (r, y) in [(bottom, -1.0f32), (top, 1.0)] {
        if r <= 0.0 {
            continue;
        }
        let n = [0.0, y.signum(), 0.0];
        let center = v.len() as u32;
        v.push(Vertex {
            pos: [0.0, y, 0.0],
            normal: n,
        });
        for s in 0..=segments {
            let theta = TAU * s as f32 / segments as f32;
            v.push(Vertex {
                pos: [r * theta.cos(), y, r * theta.sin()],
                normal: n,
            });
        }
        for s in 0..segments {
            // Counter-clockwise seen from outside: below the bottom cap, above the top one.
            let (p, q) = (center + 1 + s, center + 2 + s);
            if y < 0.0 {
                i.extend_from_slice(&[center, p, q]);
            } else {
                i.extend_from_slice(&[center, q, p]);
            }
        }
    }
    (v, i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn meshes_are_closed_and_normals_point_out() {
        for key in [
            MeshKey::Cube,
            MeshKey::Sphere,
            MeshKey::SphereLow,
            MeshKey::CylinderLow,
            MeshKey::Frustum(1000, 1000),
            MeshKey::Frustum(1000, 0),
            MeshKey::Frustum(600, 1000),
        ] {
            let (v, i) = build(key);
            assert_eq!(i.len() % 3, 0);
            assert!(i.iter().all(|&k| (k as usize) < v.len()));
            for vert in &v {
                let p = Vec3::from(vert.pos);
                let n = Vec3::from(vert.normal);
                assert!((n.length() - 1.0).abs() < 1e-4, "{key:?}");
                // Every vertex of these convex meshes sits at or past the origin along its normal.
                assert!(p.dot(n) >= -1e-5, "{key:?} {p} {n}");
            }
            // Wound counter-clockwise seen from outside, as back-face culling needs:
            // each triangle's normal by its winding points away from the origin.
            for t in i.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|k| Vec3::from(v[k as usize].pos));
                let n = (b - a).cross(c - a);
                assert!(
                    n.length() < 1e-9 || n.dot(a + b + c) > 0.0,
                    "{key:?}: triangle {t:?} faces inwards"
                );
            }
        }
    }

    #[test]
    fn shapes_map_to_scaled_unit_meshes() {
        let (k, s) = shape_mesh(&Shape::Frustum {
            bottom_radius: 0.05,
            top_radius: 0.1,
            height: 0.4,
        });
        assert_eq!(k, MeshKey::Frustum(500, 1000));
        assert!((s - Vec3::new(0.1, 0.2, 0.1)).length() < 1e-6);
        let (k, s) = shape_mesh(&Shape::Box {
            half_extents: DVec3::new(0.1, 0.2, 0.3),
        });
        assert_eq!(k, MeshKey::Cube);
        assert!((s - Vec3::new(0.1, 0.2, 0.3)).length() < 1e-6);
    }
}
