//! Hand sphere sensors (thesis 4.3.1, figure 4-4): one sphere at each finger joint and
//! fingertip plus one in the palm, each with a radius fitted to its segment, and their
//! distance to scene objects and to other actors' body solids.
//!
//! When a sensor touches, only the DOFs *above* it in the finger (the DOFs that move it,
//! [`HandSensor::stops`]) stop; the others keep closing (4.3.4).

use crate::error::{Error, Result};
use crate::jacobian::ancestor_dofs;
use crate::object::Object;
use crate::scope::Scope;
use crate::self_collision::signed_distance;
use crate::skeleton::Skeleton;
use crate::transform::Transform;
use glam::DVec3;

/// The five digits, in the order sensors and patterns use.
pub const FINGERS: [&str; 5] = ["thumb", "index", "middle", "ring", "pinky"];

/// Which hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// The left hand (`l_` joints).
    Left,
    /// The right hand (`r_` joints).
    Right,
}

impl Side {
    /// The joint-name prefix (`l_` or `r_`).
    pub fn prefix(self) -> &'static str {
        match self {
            Side::Left => "l_",
            Side::Right => "r_",
        }
    }
    /// The side of a joint named with a side's prefix (`l_wrist`), if it is one's.
    pub fn of_joint(name: &str) -> Option<Side> {
        [Side::Left, Side::Right]
            .into_iter()
            .find(|side| name.starts_with(side.prefix()))
    }
    /// `left` or `right`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
    /// Parses `left` or `right`.
    pub fn parse(name: &str) -> Result<Side> {
        match name {
            "left" => Ok(Side::Left),
            "right" => Ok(Side::Right),
            other => Err(Error::Invalid(format!(
                "unknown hand `{other}` (expected \"left\" or \"right\")"
            ))),
        }
    }
    /// The other hand.
    pub fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

/// One sphere sensor of a hand.
#[derive(Clone, Debug, PartialEq)]
pub struct HandSensor {
    /// `r_index2`, `r_index_tip`, `r_palm`, …
    pub name: String,
    /// Index into [`FINGERS`], or `None` for the palm sensor.
    pub finger: Option<usize>,
    /// The joint the sensor moves with.
    pub joint: usize,
    /// Centre in that joint's frame.
    pub point: DVec3,
    /// Radius in metres, fitted to the segment.
    pub radius: f64,
    /// The finger DOFs that move the sensor: they stop when it touches (4.3.4).
    pub stops: Scope,
}

/// A finger: its name and the DOFs a hand pattern closes.
#[derive(Clone, Debug, PartialEq)]
pub struct Finger {
    /// `thumb`, `index`, …
    pub name: &'static str,
    /// Its DOFs in skeleton order.
    pub dofs: Vec<usize>,
}

/// The sensor set of one hand of a humanoid skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct HandSensors {
    /// Which hand.
    pub side: Side,
    /// The wrist joint (the hand's frame).
    pub wrist: usize,
    /// Every sensor; fingers first (knuckle to tip), the palm last.
    pub sensors: Vec<HandSensor>,
    /// The five fingers in [`FINGERS`] order.
    pub fingers: Vec<Finger>,
    /// Every finger DOF of the hand.
    pub scope: Scope,
    /// The palm centre in the wrist frame.
    pub palm: DVec3,
    /// Unit normal out of the palm, in the wrist frame.
    pub palm_normal: DVec3,
    /// Unit direction from the wrist toward the fingertips, in the wrist frame.
    pub finger_direction: DVec3,
}

impl HandSensors {
    /// The sensors of `side`'s hand; an error if the skeleton has no such hand.
    pub fn new(skeleton: &Skeleton, side: Side) -> Result<HandSensors> {
        let s = side.prefix();
        let wrist = skeleton.joint(&format!("{s}wrist"))?;
        let scope = skeleton.scope(&format!("{}_hand", side.name()))?;
        let joints = skeleton.joints();
        let mut sensors = Vec::new();
        let mut fingers = Vec::new();
        let stops_of = |j: usize| ancestor_dofs(skeleton, j).intersection(&scope);
        // Segment length from a joint to its child (or end site): the sensor fits it.
        let end_site = |j: usize| {
            skeleton
                .end_sites()
                .iter()
                .find(|(k, _)| *k == j)
                .map(|(_, o)| *o)
        };
        for (f, name) in FINGERS.iter().enumerate() {
            let chain: Vec<usize> = (1..=3)
                .map(|i| skeleton.joint(&format!("{s}{name}{i}")))
                .collect::<Result<_>>()?;
            let mut dofs: Vec<usize> = Vec::new();
            if *name != "thumb" {
                if let Ok(base) = skeleton.joint(&format!("{s}{name}0")) {
                    dofs.extend(joints[base].dofs.clone());
                }
            }
            for &j in &chain {
                dofs.extend(joints[j].dofs.clone());
            }
            fingers.push(Finger { name, dofs });
            for (k, &j) in chain.iter().enumerate() {
                let next = match chain.get(k + 1) {
                    Some(&c) => joints[c].offset,
                    None => end_site(j).ok_or_else(|| {
                        Error::Invalid(format!(
                            "hand sensors: `{}` has no end site",
                            joints[j].name
                        ))
                    })?,
                };
                let length = next.length();
                let radius = (0.3 * length).clamp(0.006, 0.010);
                // A sphere at the segment's middle: it moves with joint j, so touching
                // stops j's DOFs and those above it in the finger.
                sensors.push(HandSensor {
                    name: joints[j].name.clone(),
                    finger: Some(f),
                    joint: j,
                    point: next * 0.5,
                    radius,
                    stops: stops_of(j),
                });
                if k + 1 == chain.len() {
                    // The fingertip, pulled in by its radius so the sphere ends at the tip.
                    let tip = next - next.normalize_or_zero() * radius;
                    sensors.push(HandSensor {
                        name: format!("{s}{name}_tip"),
                        finger: Some(f),
                        joint: j,
                        point: tip,
                        radius,
                        stops: stops_of(j),
                    });
                }
            }
        }
        // Palm centre: the mean of the finger bases (index..pinky knuckles) and the wrist.
        let mut palm = DVec3::ZERO;
        let mut n = 1.0;
        for name in &FINGERS[1..] {
            let j1 = skeleton.joint(&format!("{s}{name}1"))?;
            // Knuckle in the wrist frame at rest = base offset + knuckle offset.
            let mut p = joints[j1].offset;
            if let Some(base) = joints[j1].parent.filter(|&b| b != wrist) {
                p += joints[base].offset;
            }
            palm += p;
            n += 1.0;
        }
        palm /= n;
        let finger_direction = palm.normalize_or_zero();
        // At rest the palm faces the body's midline: -X for the left hand, +X for the right.
        let palm_normal = match side {
            Side::Left => -DVec3::X,
            Side::Right => DVec3::X,
        };
        let palm_radius = (0.35 * palm.length()).clamp(0.015, 0.03);
        sensors.push(HandSensor {
            name: format!("{s}palm"),
            finger: None,
            joint: wrist,
            point: palm,
            radius: palm_radius,
            stops: Scope::EMPTY,
        });
        Ok(HandSensors {
            side,
            wrist,
            sensors,
            fingers,
            scope,
            palm,
            palm_normal,
            finger_direction,
        })
    }

    /// World centre of sensor `i` for the joint globals `globals`.
    #[inline]
    pub fn center(&self, i: usize, globals: &[Transform]) -> DVec3 {
        let s = &self.sensors[i];
        globals[s.joint].transform_point(s.point)
    }

    /// Distance from sensor `i`'s sphere to `object`'s surface: negative when it
    /// penetrates by that much.
    pub fn distance_to_object(&self, i: usize, globals: &[Transform], object: &Object) -> f64 {
        object_distance(object, self.center(i, globals)) - self.sensors[i].radius
    }

    /// Distance from sensor `i`'s sphere to the nearest body solid of another actor
    /// (skeleton `other`, joint globals `other_globals`); negative when penetrating.
    pub fn distance_to_body(
        &self,
        i: usize,
        globals: &[Transform],
        other: &Skeleton,
        other_globals: &[Transform],
    ) -> f64 {
        let c = self.center(i, globals);
        other
            .solids()
            .iter()
            .map(|(j, solid)| solid_distance(solid, &other_globals[*j], c))
            .fold(f64::INFINITY, f64::min)
            - self.sensors[i].radius
    }
}

/// Signed distance from world point `p` to `object`'s surface (negative inside).
pub fn object_distance(object: &Object, p: DVec3) -> f64 {
    let local = object.rotation.inverse() * (p - object.position);
    signed_distance(&object.shape, local)
}

/// Signed distance from world point `p` to a body solid carried by a joint at `frame`.
pub fn solid_distance(solid: &crate::solid::Solid, frame: &Transform, p: DVec3) -> f64 {
    let in_joint = frame.inverse().transform_point(p);
    let local = solid.orientation.inverse() * (in_joint - solid.center);
    signed_distance(&solid.shape, local)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::Shape;
    use glam::DQuat;

    #[test]
    fn twenty_sensors_with_finger_stops() {
        let s = crate::template::default_skeleton("adult").unwrap();
        let h = HandSensors::new(&s, Side::Right).unwrap();
        // 5 fingers × (3 segments + tip) = 20, plus the palm.
        assert_eq!(h.sensors.len(), 21);
        let tip = h.sensors.iter().find(|x| x.name == "r_index_tip").unwrap();
        let knuckle = h.sensors.iter().find(|x| x.name == "r_index1").unwrap();
        // The tip is moved by every index DOF; the proximal sensor only by the base ones.
        assert!(tip.stops.contains_all(&knuckle.stops));
        assert!(tip.stops.len() > knuckle.stops.len());
        assert!(h
            .sensors
            .iter()
            .all(|x| x.radius >= 0.006 && x.radius <= 0.03));
    }

    #[test]
    fn object_distance_every_shape() {
        let shapes = [
            Shape::Box {
                half_extents: DVec3::new(0.1, 0.2, 0.3),
            },
            Shape::Sphere { radius: 0.1 },
            Shape::Cylinder {
                radius: 0.1,
                height: 0.4,
            },
            Shape::Frustum {
                bottom_radius: 0.1,
                top_radius: 0.1,
                height: 0.4,
            },
            Shape::Ellipsoid {
                radii: DVec3::new(0.1, 0.2, 0.1),
            },
        ];
        for shape in shapes {
            let o = Object {
                name: "o".into(),
                shape,
                position: DVec3::new(1.0, 1.0, 1.0),
                rotation: DQuat::from_rotation_y(0.3),
                mass: 1.0,
            };
            // A point 5 cm outside along the object's local X axis.
            let p = o.position + o.rotation * DVec3::new(0.15, 0.0, 0.0);
            let d = object_distance(&o, p);
            assert!((d - 0.05).abs() < 1e-9, "{shape:?}: {d}");
            assert!(object_distance(&o, o.position) < 0.0);
        }
    }
}
