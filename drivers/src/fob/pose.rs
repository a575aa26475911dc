//! A bird record as a pose in the scene's math types, and back: the Flock's Euler angles
//! (azimuth, elevation, roll) and the data words of each output format.
//!
//! Facts from `shared/reference/devices.md`, section "Ascension Flock of Birds (RS-232)".

use crate::fob::commands::{OutputFormat, PositionRange};
use crate::fob::decoder::{angle_word, position_word, unit_word, BirdRecord};
use glam::{DMat3, DQuat, DVec3, EulerRot};

/// The pose a bird record describes (orientation from whichever field the format has).
/// An all-zero quaternion or matrix gives a non-finite rotation: callers check.
pub fn bird_pose(b: &BirdRecord) -> (DVec3, DQuat) {
    let p = b.position.map(DVec3::from_array).unwrap_or(DVec3::ZERO);
    let q = if let Some([w, x, y, z]) = b.quaternion {
        DQuat::from_xyzw(x, y, z, w).normalize()
    } else if let Some(a) = b.angles {
        angles_to_quat(a)
    } else if let Some(m) = b.matrix {
        DQuat::from_mat3(&DMat3::from_cols_array(&m)).normalize()
    } else {
        DQuat::IDENTITY
    };
    (p, q)
}

/// Orientation from azimuth (about Z), elevation (about Y), roll (about X), in degrees,
/// applied in that order as the Flock defines its Euler angles.
pub fn angles_to_quat(a: [f64; 3]) -> DQuat {
    DQuat::from_euler(
        EulerRot::ZYX,
        a[0].to_radians(),
        a[1].to_radians(),
        a[2].to_radians(),
    )
}

/// Azimuth, elevation, roll (degrees) of an orientation.
pub fn quat_to_angles(q: DQuat) -> [f64; 3] {
    let (z, y, x) = q.to_euler(EulerRot::ZYX);
    [z.to_degrees(), y.to_degrees(), x.to_degrees()]
}

/// The words of one bird record in a format, from a pose.
pub fn pose_words(format: OutputFormat, range: PositionRange, p: DVec3, q: DQuat) -> Vec<i16> {
    let mut w = Vec::with_capacity(12);
    let pos = [p.x, p.y, p.z].map(|v| position_word(v, range));
    let with_pos = matches!(
        format,
        OutputFormat::Position
            | OutputFormat::PositionAngles
            | OutputFormat::PositionMatrix
            | OutputFormat::PositionQuaternion
    );
    if with_pos {
        w.extend_from_slice(&pos);
    }
    match format {
        OutputFormat::Angles | OutputFormat::PositionAngles => {
            w.extend(quat_to_angles(q).map(angle_word));
        }
        OutputFormat::Quaternion | OutputFormat::PositionQuaternion => {
            w.extend([q.w, q.x, q.y, q.z].map(unit_word));
        }
        OutputFormat::Matrix | OutputFormat::PositionMatrix => {
            w.extend(DMat3::from_quat(q).to_cols_array().map(unit_word));
        }
        OutputFormat::Position => {}
    }
    w
}
