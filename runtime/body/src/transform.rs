//! Rigid transforms (rotation + translation), the DIT "REF" frames of Appendix C.

use glam::{DQuat, DVec3};

/// A rigid transform: `p ↦ rotation * p + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Orientation of the frame in its parent.
    pub rotation: DQuat,
    /// Origin of the frame in its parent.
    pub translation: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// The identity transform.
    pub const IDENTITY: Transform = Transform {
        rotation: DQuat::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// A pure translation.
    #[inline]
    pub fn from_translation(translation: DVec3) -> Self {
        Transform {
            rotation: DQuat::IDENTITY,
            translation,
        }
    }

    /// A rotation and a translation.
    #[inline]
    pub fn new(rotation: DQuat, translation: DVec3) -> Self {
        Transform {
            rotation,
            translation,
        }
    }

    /// `self ∘ other`: first `other`, then `self`.
    #[inline]
    pub fn mul(&self, other: &Transform) -> Transform {
        Transform {
            rotation: self.rotation * other.rotation,
            translation: self.translation + self.rotation * other.translation,
        }
    }

    /// Maps a point from this frame into the parent frame.
    #[inline]
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.translation + self.rotation * p
    }

    /// Maps a direction from this frame into the parent frame.
    #[inline]
    pub fn transform_vector(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }

    /// The inverse transform (the "inv" of the DIT convention).
    #[inline]
    pub fn inverse(&self) -> Transform {
        let rotation = self.rotation.inverse();
        Transform {
            rotation,
            translation: -(rotation * self.translation),
        }
    }
}
