//! Channels and rotation orders: the vocabulary of a BVH hierarchy's `CHANNELS` lines.

use crate::error::{Error, Result};
use glam::{DMat3, DQuat, DVec3, EulerRot};
use std::fmt;
use std::str::FromStr;

/// Most channels a single joint may declare (three positions and three rotations).
pub const MAX_JOINT_CHANNELS: usize = 6;

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// The X axis.
    X,
    /// The Y axis.
    Y,
    /// The Z axis.
    Z,
}

impl Axis {
    /// The axis as an index (X = 0, Y = 1, Z = 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// The unit vector along the axis.
    pub fn unit(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }

    fn letter(self) -> char {
        match self {
            Axis::X => 'X',
            Axis::Y => 'Y',
            Axis::Z => 'Z',
        }
    }
}

/// One BVH channel: a translation along or a rotation (degrees) about an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// `Xposition`, `Yposition` or `Zposition`.
    Position(Axis),
    /// `Xrotation`, `Yrotation` or `Zrotation` (degrees in the file).
    Rotation(Axis),
}

impl Channel {
    /// Parses a channel name (case-insensitive, as some exporters vary the case).
    pub fn parse(name: &str) -> Option<Channel> {
        let lower = name.to_ascii_lowercase();
        let axis = match lower.chars().next()? {
            'x' => Axis::X,
            'y' => Axis::Y,
            'z' => Axis::Z,
            _ => return None,
        };
        match &lower[1..] {
            "position" => Some(Channel::Position(axis)),
            "rotation" => Some(Channel::Rotation(axis)),
            _ => None,
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Channel::Position(a) => write!(f, "{}position", a.letter()),
            Channel::Rotation(a) => write!(f, "{}rotation", a.letter()),
        }
    }
}

/// An order of three distinct rotation axes, composed intrinsically (`ZXY` = `Rz·Rx·Ry`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RotationOrder(pub [Axis; 3]);

impl RotationOrder {
    /// Every Tait–Bryan order.
    pub const ALL: [RotationOrder; 6] = [
        RotationOrder([Axis::X, Axis::Y, Axis::Z]),
        RotationOrder([Axis::X, Axis::Z, Axis::Y]),
        RotationOrder([Axis::Y, Axis::X, Axis::Z]),
        RotationOrder([Axis::Y, Axis::Z, Axis::X]),
        RotationOrder([Axis::Z, Axis::X, Axis::Y]),
        RotationOrder([Axis::Z, Axis::Y, Axis::X]),
    ];

    fn euler(self) -> EulerRot {
        use Axis::*;
        match self.0 {
            [X, Y, Z] => EulerRot::XYZ,
            [X, Z, Y] => EulerRot::XZY,
            [Y, X, Z] => EulerRot::YXZ,
            [Y, Z, X] => EulerRot::YZX,
            [Z, X, Y] => EulerRot::ZXY,
            _ => EulerRot::ZYX,
        }
    }

    /// The angles (radians, in this order's axis order) of rotation `q`.
    pub fn decompose(self, q: DQuat) -> [f64; 3] {
        let (a, b, c) = DMat3::from_quat(q.normalize()).to_euler(self.euler());
        [a, b, c]
    }

    /// The rotation of angles (radians) about this order's axes, composed intrinsically.
    pub fn compose(self, angles: [f64; 3]) -> DQuat {
        let mut q = DQuat::IDENTITY;
        for (axis, angle) in self.0.iter().zip(angles) {
            q *= DQuat::from_axis_angle(axis.unit(), angle);
        }
        q
    }
}

impl FromStr for RotationOrder {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let axes: Vec<Axis> = s
            .trim()
            .chars()
            .map(|c| match c.to_ascii_uppercase() {
                'X' => Some(Axis::X),
                'Y' => Some(Axis::Y),
                'Z' => Some(Axis::Z),
                _ => None,
            })
            .collect::<Option<_>>()
            .ok_or_else(|| Error::RotationOrder(s.to_string()))?;
        RotationOrder::ALL
            .into_iter()
            .find(|o| o.0[..] == axes[..])
            .ok_or_else(|| Error::RotationOrder(s.to_string()))
    }
}

impl fmt::Display for RotationOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for a in self.0 {
            write!(f, "{}", a.letter())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_order_decomposes_and_composes_back() {
        let q = DQuat::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), 1.9);
        for o in RotationOrder::ALL {
            let back = o.compose(o.decompose(q));
            assert!(back.dot(q).abs() > 1.0 - 1e-14, "{o}");
            assert_eq!(o.to_string().parse::<RotationOrder>().unwrap(), o);
        }
        assert!("XXY".parse::<RotationOrder>().is_err());
    }
}
