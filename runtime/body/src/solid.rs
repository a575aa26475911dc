//! Simple solids (thesis 3.1 and Appendix C's SOLID type): shapes, volume, centre of mass
//! and inertia of a uniform-density body.
//!
//! Every shape has a canonical frame: centred on the origin, with its axis of symmetry
//! (cylinder, frustum) along +Y.

use crate::error::{Error, Result};
use glam::{DMat3, DQuat, DVec3};
use std::f64::consts::PI;

/// A solid's shape in its canonical frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A box centred on the origin.
    Box {
        /// Half its size along X, Y, Z (m).
        half_extents: DVec3,
    },
    /// A sphere centred on the origin.
    Sphere {
        /// Its radius (m).
        radius: f64,
    },
    /// A cylinder along Y, centred on the origin.
    Cylinder {
        /// Its radius (m).
        radius: f64,
        /// Its length along Y (m).
        height: f64,
    },
    /// A truncated cone along Y, centred on the origin.
    Frustum {
        /// The radius at y = −height/2 (m).
        bottom_radius: f64,
        /// The radius at y = +height/2 (m).
        top_radius: f64,
        /// Its length along Y (m).
        height: f64,
    },
    /// An ellipsoid centred on the origin.
    Ellipsoid {
        /// Its semi-axes along X, Y, Z (m).
        radii: DVec3,
    },
}

/// Mass properties of a solid of unit mass in its canonical frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitMassProperties {
    /// Volume in m³.
    pub volume: f64,
    /// Centre of mass in the canonical frame.
    pub center_of_mass: DVec3,
    /// Principal moments of inertia about the centre of mass, per kilogram (kg·m² / kg).
    pub inertia_diagonal: DVec3,
}

impl Shape {
    /// The shape's name as used in scene files and the Lua API.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Sphere { .. } => "sphere",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Frustum { .. } => "frustum",
            Shape::Ellipsoid { .. } => "ellipsoid",
        }
    }

    /// Checks that every dimension is finite and positive (a frustum may end in a point).
    pub fn validate(&self) -> Result<()> {
        let positive = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid_value(
                    format!("{} {what}", self.kind_name()),
                    v,
                    "a finite length > 0 in metres",
                ))
            }
        };
        match *self {
            Shape::Box { half_extents: h } => {
                positive("half extent x", h.x)?;
                positive("half extent y", h.y)?;
                positive("half extent z", h.z)
            }
            Shape::Sphere { radius } => positive("radius", radius),
            Shape::Cylinder { radius, height } => {
                positive("radius", radius)?;
                positive("height", height)
            }
            Shape::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => {
                positive("height", height)?;
                if !(bottom_radius.is_finite() && top_radius.is_finite())
                    || bottom_radius < 0.0
                    || top_radius < 0.0
                    || bottom_radius + top_radius <= 0.0
                {
                    return Err(Error::invalid_value(
                        "frustum radius",
                        bottom_radius.min(top_radius),
                        "radii ≥ 0, not both 0",
                    ));
                }
                Ok(())
            }
            Shape::Ellipsoid { radii } => {
                positive("radius x", radii.x)?;
                positive("radius y", radii.y)?;
                positive("radius z", radii.z)
            }
        }
    }

    /// Volume, centre of mass and inertia per unit mass of the uniform solid.
    pub fn unit_mass_properties(&self) -> UnitMassProperties {
        match *self {
            Shape::Box { half_extents: h } => {
                let (a, b, c) = (2.0 * h.x, 2.0 * h.y, 2.0 * h.z);
                UnitMassProperties {
                    volume: a * b * c,
                    center_of_mass: DVec3::ZERO,
                    inertia_diagonal: DVec3::new(b * b + c * c, a * a + c * c, a * a + b * b)
                        / 12.0,
                }
            }
            Shape::Sphere { radius: r } => UnitMassProperties {
                volume: 4.0 / 3.0 * PI * r * r * r,
                center_of_mass: DVec3::ZERO,
                inertia_diagonal: DVec3::splat(0.4 * r * r),
            },
            Shape::Ellipsoid { radii: r } => UnitMassProperties {
                volume: 4.0 / 3.0 * PI * r.x * r.y * r.z,
                center_of_mass: DVec3::ZERO,
                inertia_diagonal: DVec3::new(
                    r.y * r.y + r.z * r.z,
                    r.x * r.x + r.z * r.z,
                    r.x * r.x + r.y * r.y,
                ) / 5.0,
            },
            Shape::Cylinder {
                radius: r,
                height: h,
            } => UnitMassProperties {
                volume: PI * r * r * h,
                center_of_mass: DVec3::ZERO,
                inertia_diagonal: DVec3::new(
                    (3.0 * r * r + h * h) / 12.0,
                    r * r / 2.0,
                    (3.0 * r * r + h * h) / 12.0,
                ),
            },
            Shape::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => frustum_properties(bottom_radius, top_radius, height),
        }
    }

    /// Whether the point `p` (in the canonical frame) lies inside or on the solid.
    pub fn contains(&self, p: DVec3) -> bool {
        match *self {
            Shape::Box { half_extents: h } => {
                p.x.abs() <= h.x && p.y.abs() <= h.y && p.z.abs() <= h.z
            }
            Shape::Sphere { radius } => p.length_squared() <= radius * radius,
            Shape::Ellipsoid { radii } => (p / radii).length_squared() <= 1.0,
            Shape::Cylinder { radius, height } => {
                p.y.abs() <= height / 2.0 && p.x * p.x + p.z * p.z <= radius * radius
            }
            Shape::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => {
                if p.y.abs() > height / 2.0 {
                    return false;
                }
                let s = p.y / height + 0.5;
                let r = bottom_radius + (top_radius - bottom_radius) * s;
                p.x * p.x + p.z * p.z <= r * r
            }
        }
    }
}

/// A frustum integrated slice by slice. The integrands are polynomials of degree ≤ 4 in y,
/// so three-point Gauss–Legendre quadrature is exact.
fn frustum_properties(r0: f64, r1: f64, h: f64) -> UnitMassProperties {
    let nodes = [-(0.6f64.sqrt()), 0.0, 0.6f64.sqrt()];
    let weights = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let (mut volume, mut first_moment, mut axial, mut transverse) = (0.0, 0.0, 0.0, 0.0);
    for (x, w) in nodes.iter().zip(weights) {
        let y = x * h / 2.0;
        let r = r0 + (r1 - r0) * (y / h + 0.5);
        let dv = w * h / 2.0 * PI * r * r; // volume of the slice per unit of quadrature
        volume += dv;
        first_moment += dv * y;
        axial += dv * r * r / 2.0;
        transverse += dv * (r * r / 4.0 + y * y);
    }
    let cy = first_moment / volume;
    UnitMassProperties {
        volume,
        center_of_mass: DVec3::new(0.0, cy, 0.0),
        // Parallel-axis theorem moves the transverse moment from the origin to the COM.
        inertia_diagonal: DVec3::new(
            transverse / volume - cy * cy,
            axial / volume,
            transverse / volume - cy * cy,
        ),
    }
}

/// A solid placed in a parent frame (a joint, or the world for objects), with its mass.
#[derive(Clone, Debug, PartialEq)]
pub struct Solid {
    /// Name of the solid (`up_torso`, `r_thigh`, …).
    pub name: String,
    /// Shape in its canonical frame.
    pub shape: Shape,
    /// Position of the canonical frame's origin in the parent frame.
    pub center: DVec3,
    /// Orientation of the canonical frame in the parent frame.
    pub orientation: DQuat,
    /// Mass in kilograms.
    pub mass: f64,
    /// Centre of mass in the parent frame.
    pub center_of_mass: DVec3,
    /// Inertia tensor about the centre of mass, in the parent frame's axes (kg·m²).
    pub inertia: DMat3,
}

impl Solid {
    /// Places a uniform solid of the given mass and derives its COM and inertia.
    pub fn new(
        name: impl Into<String>,
        shape: Shape,
        center: DVec3,
        orientation: DQuat,
        mass: f64,
    ) -> Solid {
        let unit = shape.unit_mass_properties();
        let rot = DMat3::from_quat(orientation);
        let inertia = rot * DMat3::from_diagonal(unit.inertia_diagonal * mass) * rot.transpose();
        Solid {
            name: name.into(),
            shape,
            center,
            orientation,
            mass,
            center_of_mass: center + orientation * unit.center_of_mass,
            inertia,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn frustum_with_equal_radii_is_a_cylinder() {
        let f = Shape::Frustum {
            bottom_radius: 0.1,
            top_radius: 0.1,
            height: 0.5,
        }
        .unit_mass_properties();
        let c = Shape::Cylinder {
            radius: 0.1,
            height: 0.5,
        }
        .unit_mass_properties();
        assert!(close(f.volume, c.volume));
        assert!(f.center_of_mass.length() < 1e-15);
        assert!(close(f.inertia_diagonal.x, c.inertia_diagonal.x));
        assert!(close(f.inertia_diagonal.y, c.inertia_diagonal.y));
    }

    #[test]
    fn cone_matches_closed_form() {
        // A cone (top radius 0) of height h, base radius r: COM at h/4 above the base,
        // I_axis = 3/10 m r², I_transverse (about COM) = 3/20 m r² + 3/80 m h².
        let (r, h) = (0.2, 0.6);
        let p = Shape::Frustum {
            bottom_radius: r,
            top_radius: 0.0,
            height: h,
        }
        .unit_mass_properties();
        assert!(close(p.volume, PI * r * r * h / 3.0));
        assert!(close(p.center_of_mass.y, -h / 2.0 + h / 4.0));
        assert!(close(p.inertia_diagonal.y, 0.3 * r * r));
        assert!(close(
            p.inertia_diagonal.x,
            0.15 * r * r + 3.0 / 80.0 * h * h
        ));
    }

    #[test]
    fn placed_solid_rotates_inertia() {
        let s = Solid::new(
            "rod",
            Shape::Cylinder {
                radius: 0.01,
                height: 1.0,
            },
            DVec3::new(0.0, 0.0, 0.5),
            DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2),
            2.0,
        );
        // The rod now lies along Z: the small moment is about Z.
        assert!(s.inertia.z_axis.z < s.inertia.x_axis.x / 100.0);
        assert_eq!(s.center_of_mass, DVec3::new(0.0, 0.0, 0.5));
    }

    #[test]
    fn containment() {
        let f = Shape::Frustum {
            bottom_radius: 0.2,
            top_radius: 0.1,
            height: 1.0,
        };
        assert!(f.contains(DVec3::new(0.19, -0.5, 0.0)));
        assert!(!f.contains(DVec3::new(0.19, 0.5, 0.0)));
        assert!(Shape::Ellipsoid {
            radii: DVec3::new(1.0, 2.0, 3.0)
        }
        .contains(DVec3::new(0.0, 1.9, 0.0)));
    }

    #[test]
    fn bad_dimensions_are_errors() {
        assert!(Shape::Sphere { radius: -1.0 }.validate().is_err());
        assert!(Shape::Cylinder {
            radius: f64::NAN,
            height: 1.0
        }
        .validate()
        .is_err());
        assert!(Shape::Frustum {
            bottom_radius: 0.0,
            top_radius: 0.1,
            height: 1.0
        }
        .validate()
        .is_ok());
    }
}
