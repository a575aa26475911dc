//! Where the edges between the skin's regions fall between vertices.
//!
//! Each vertex has one [`Region`] (bare skin, shirt, trousers, shoes, eye white, pupil),
//! that of the volume nearest to it; coloured by vertex, the edges between regions
//! (sleeves, waistband, collar, shoes, eyes) follow the simplified triangles, zigzag a
//! triangle wide, and blur across it. The rule itself is smooth: the region is the one
//! whose volumes are nearest. So each vertex also keeps how far it lies from each
//! region's volumes ([`RegionDistances`]); interpolated across a triangle, the region
//! nearest at each pixel gives an edge that runs through the triangles along the
//! volumes' own boundary. The viewer colours the skin so; glTF files keep the vertex
//! colours, which carry no more than one region per vertex.

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
