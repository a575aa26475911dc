//! Floor contact (thesis 3.6, fig. 3-6): a penalty force field on the body solids. Each
//! solid offers its lowest points (the support points of a sphere or ellipsoid; for each
//! end rim of a cylinder or frustum its lowest point and two more at ±120° around the rim,
//! so that a flat end rests on a tripod; a box's corners). A point below the floor gets a
//! normal force `k·depth − c·v_n` (never pulling) and a friction force opposing its
//! sliding velocity, `μ·F_n` once it slides faster than `slip_speed` (regularized
//! Coulomb friction).

use super::model::{Data, Model};
use super::spatial::Force;
use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use crate::solid::Shape;
use glam::{DQuat, DVec3};

/// Parameters of the floor's force field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Height of the floor plane (m).
    pub height: f64,
    /// Normal stiffness per contact point (N/m).
    pub stiffness: f64,
    /// Damping ratio of a point's normal spring, relative to the mass of its solid shared
    /// among the solid's contact features.
    pub damping_ratio: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Sliding speed (m/s) at which friction reaches `friction × F_n`; below it friction
    /// grows linearly with speed.
    pub slip_speed: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams {
            height: 0.0,
            stiffness: 1e5,
            damping_ratio: 0.7,
            friction: 0.8,
            slip_speed: 0.02,
        }
    }
}

impl ContactParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [
            ("contact stiffness", self.stiffness),
            ("contact damping ratio", self.damping_ratio),
            ("friction", self.friction),
            ("slip speed", self.slip_speed),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid_value(what, v, "a finite number ≥ 0"));
            }
        }
        if !(self.slip_speed > 0.0 && self.height.is_finite()) {
            return Err(Error::invalid_value(
                "slip speed",
                self.slip_speed,
                "> 0 (and a finite floor height)",
            ));
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug)]
enum Feature {
    /// A sphere or ellipsoid: centre, orientation (link frame) and semi-axes.
    Round {
        center: DVec3,
        rotation: DQuat,
        radii: DVec3,
    },
    /// A circular rim: centre, unit axis (link frame) and radius.
    Rim {
        center: DVec3,
        axis: DVec3,
        radius: f64,
    },
    /// A fixed point (box corner, cone apex) in the link frame.
    Point(DVec3),
}

#[derive(Clone, Copy, Debug)]
struct ContactFeature {
    link: usize,
    feature: Feature,
    damping: f64,
}

/// The contact features of a body and the floor's parameters.
#[derive(Clone, Debug)]
pub struct Floor {
    params: ContactParams,
    features: Vec<ContactFeature>,
}

impl Floor {
    /// The contact features of every solid of `skeleton` (as placed by `model`).
    pub fn new(model: &Model, skeleton: &Skeleton, params: ContactParams) -> Result<Floor> {
        params.validate()?;
        let mut features = Vec::new();
        for (j, solid) in skeleton.solids() {
            let Some((link, fixed)) = model.joint_link[*j] else {
                continue;
            };
            let place = fixed.mul(&crate::transform::Transform::new(
                solid.orientation,
                solid.center,
            ));
            let mut list = Vec::new();
            let y = place.rotation * DVec3::Y;
            match solid.shape {
                Shape::Sphere { radius } => list.push(Feature::Round {
                    center: place.translation,
                    rotation: place.rotation,
                    radii: DVec3::splat(radius),
                }),
                Shape::Ellipsoid { radii } => list.push(Feature::Round {
                    center: place.translation,
                    rotation: place.rotation,
                    radii,
                }),
                Shape::Cylinder { radius, height } => {
                    for s in [-0.5, 0.5] {
                        list.push(Feature::Rim {
                            center: place.translation + y * (s * height),
                            axis: y,
                            radius,
                        });
                    }
                }
                Shape::Frustum {
                    bottom_radius,
                    top_radius,
                    height,
                } => {
                    for (s, r) in [(-0.5, bottom_radius), (0.5, top_radius)] {
                        let center = place.translation + y * (s * height);
                        list.push(if r > 0.0 {
                            Feature::Rim {
                                center,
                                axis: y,
                                radius: r,
                            }
                        } else {
                            Feature::Point(center)
                        });
                    }
                }
                Shape::Box { half_extents: h } => {
                    for i in 0..8 {
                        let c = DVec3::new(
                            if i & 1 == 0 { -h.x } else { h.x },
                            if i & 2 == 0 { -h.y } else { h.y },
                            if i & 4 == 0 { -h.z } else { h.z },
                        );
                        list.push(Feature::Point(place.transform_point(c)));
                    }
                }
            }
            let share = solid.mass / list.len() as f64;
            let damping = 2.0 * params.damping_ratio * (params.stiffness * share).sqrt();
            features.extend(list.into_iter().map(|feature| ContactFeature {
                link,
                feature,
                damping,
            }));
        }
        Ok(Floor { params, features })
    }

    /// The floor's parameters.
    pub fn params(&self) -> &ContactParams {
        &self.params
    }

    /// Adds the floor's forces to `data.ext` for the state in `data` (after kinematics
    /// and velocities); returns the deepest penetration (m, 0 when nothing touches).
    pub(crate) fn apply(&self, data: &mut Data) -> f64 {
        let mut deepest: f64 = 0.0;
        let p = &self.params;
        for cf in &self.features {
            let (r, t) = (data.rot[cf.link], data.pos[cf.link]);
            let mut touch = |point: DVec3, data: &mut Data| {
                let depth = p.height - point.y;
                if depth <= 0.0 {
                    return;
                }
                deepest = deepest.max(depth);
                let v = data.v[cf.link];
                let vel = v.v + v.w.cross(point);
                let normal = p.stiffness * depth - cf.damping * vel.y;
                if normal <= 0.0 {
                    return;
                }
                let slide = DVec3::new(vel.x, 0.0, vel.z);
                let friction = slide * (-p.friction * normal / slide.length().max(p.slip_speed));
                data.ext[cf.link] += Force::at_point(
                    point,
                    DVec3::new(friction.x, normal, friction.z),
                    DVec3::ZERO,
                );
            };
            match cf.feature {
                Feature::Point(local) => touch(t + r * local, data),
                Feature::Round {
                    center,
                    rotation,
                    radii,
                } => {
                    let rot = r * rotation;
                    let u = rot.inverse() * DVec3::NEG_Y;
                    let r2u = radii * radii * u;
                    let local = r2u / r2u.dot(u).sqrt();
                    touch(t + r * center + rot * local, data);
                }
                Feature::Rim {
                    center,
                    axis,
                    radius,
                } => {
                    let c = t + r * center;
                    if c.y - radius > p.height {
                        continue; // the whole rim is above the floor
                    }
                    let n = r * axis;
                    let down = DVec3::NEG_Y - n * n.dot(DVec3::NEG_Y);
                    let w = if down.length_squared() > 1e-12 {
                        down.normalize()
                    } else {
                        n.any_orthonormal_vector()
                    };
                    let side = n.cross(w);
                    let (s, co) = (2.0 * std::f64::consts::FRAC_PI_3).sin_cos();
                    touch(c + w * radius, data);
                    touch(c + (w * co + side * s) * radius, data);
                    touch(c + (w * co - side * s) * radius, data);
                }
            }
        }
        deepest
    }
}
