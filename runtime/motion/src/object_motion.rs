//! An object's recorded motion: its shape and mass, its pose over time, and who held it
//! when — what `troupe run --record` keeps of each object beside the actors' postures.

use crate::error::{Error, Result};
use crate::sequence::{Interpolation, Key, Sequence, Track};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::solid::Shape;

/// The names of an object's pose tracks: its centre (m) and its orientation as a unit
/// quaternion, world axes.
pub const POSE_TRACKS: [&str; 7] = ["x", "y", "z", "qx", "qy", "qz", "qw"];

/// A time span during which an actor held the object.
#[derive(Clone, Debug, PartialEq)]
pub struct Hold {
    /// When the actor took it (s).
    pub from: f64,
    /// When it let go (s); the end of the recording if it never did.
    pub to: f64,
    /// The holding actor's name.
    pub actor: String,
    /// The joint the object was attached to (a wrist).
    pub joint: String,
}

/// One object's motion over a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectMotion {
    /// The object's name in the scene.
    pub name: String,
    /// Its shape (canonical frame centred on its position).
    pub shape: Shape,
    /// Its mass (kg).
    pub mass: f64,
    /// The pose tracks [`POSE_TRACKS`] on the recording's time base.
    pub pose: Sequence,
    /// Who held it, in time order, spans not overlapping.
    pub holds: Vec<Hold>,
}

impl ObjectMotion {
    /// An object's motion from its poses at `times` (positions and unit quaternions,
    /// one each per time). Keys inside a run of equal values are dropped, as for
    /// actors; the tracks interpolate linearly (a recording is sampled every tick).
    pub fn from_samples(
        name: impl Into<String>,
        shape: Shape,
        mass: f64,
        times: &[f64],
        poses: &[(DVec3, DQuat)],
    ) -> Result<ObjectMotion> {
        let name = name.into();
        if times.len() != poses.len() || times.is_empty() {
            return Err(Error::Invalid(format!(
                "object `{name}`: {} times for {} poses",
                times.len(),
                poses.len()
            )));
        }
        let mut pose = Sequence::new(name.clone());
        for (c, dof) in POSE_TRACKS.iter().enumerate() {
            let values: Vec<f64> = poses
                .iter()
                .map(|(p, q)| match c {
                    0..=2 => p[c],
                    _ => q.to_array()[c - 3],
                })
                .collect();
            let keys = (0..values.len())
                .filter(|&i| {
                    i == 0
                        || i + 1 == values.len()
                        || values[i] != values[i - 1]
                        || values[i] != values[i + 1]
                })
                .map(|i| Key::new(times[i], values[i]))
                .collect();
            pose.add_track(Track::new(*dof, keys)?.with_interpolation(Interpolation::Linear))?;
        }
        Ok(ObjectMotion {
            name,
            shape,
            mass,
            pose,
            holds: Vec::new(),
        })
    }

    /// Checks that every pose track is present.
    pub fn validate(&self) -> Result<()> {
        for dof in POSE_TRACKS {
            if self.pose.track(dof).is_none() {
                return Err(Error::Invalid(format!(
                    "object `{}` has no `{dof}` track (needs x, y, z, qx, qy, qz, qw)",
                    self.name
                )));
            }
        }
        Ok(())
    }

    /// The pose at time `t` (the quaternion renormalized; identity if it degenerates).
    /// A missing track reads as zero (`qw` as one).
    pub fn pose_at(&self, t: f64) -> (DVec3, DQuat) {
        let v = |dof: &str, default: f64| self.pose.track(dof).map_or(default, |tr| tr.value(t));
        let p = DVec3::new(v("x", 0.0), v("y", 0.0), v("z", 0.0));
        let q = DQuat::from_xyzw(v("qx", 0.0), v("qy", 0.0), v("qz", 0.0), v("qw", 1.0));
        let len = q.length();
        let q = if len.is_finite() && len > 1e-12 {
            q / len
        } else {
            DQuat::IDENTITY
        };
        (p, q)
    }

    /// Who held the object at time `t`, if anyone.
    pub fn holder_at(&self, t: f64) -> Option<&Hold> {
        self.holds.iter().find(|h| h.from <= t && t < h.to)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_are_kept_and_interpolated() {
        let shape = Shape::Sphere { radius: 0.05 };
        let times = [0.0, 0.01, 0.02, 0.03];
        let turn = DQuat::from_rotation_y(0.2);
        let poses = [
            (DVec3::new(0.0, 1.0, 0.0), DQuat::IDENTITY),
            (DVec3::new(0.0, 1.0, 0.0), DQuat::IDENTITY),
            (DVec3::new(0.1, 1.0, 0.0), turn),
            (DVec3::new(0.2, 1.0, 0.0), turn),
        ];
        let mut o = ObjectMotion::from_samples("ball", shape, 0.3, &times, &poses).unwrap();
        o.validate().unwrap();
        for (t, (p, q)) in times.iter().zip(&poses) {
            let (pp, qq) = o.pose_at(*t);
            assert!((pp - *p).length() < 1e-12 && qq.dot(*q).abs() > 1.0 - 1e-12);
        }
        // Linear between samples: halfway from 0.1 to 0.2.
        assert!((o.pose_at(0.025).0.x - 0.15).abs() < 1e-12);
        // y never changes: two keys hold it.
        assert_eq!(o.pose.track("y").unwrap().keys().len(), 2);
        o.holds.push(Hold {
            from: 0.01,
            to: 0.03,
            actor: "ann".into(),
            joint: "r_wrist".into(),
        });
        assert_eq!(o.holder_at(0.02).map(|h| h.actor.as_str()), Some("ann"));
        assert!(o.holder_at(0.0).is_none() && o.holder_at(0.03).is_none());
        assert!(ObjectMotion::from_samples("x", shape, 1.0, &[0.0], &[]).is_err());
    }
}
