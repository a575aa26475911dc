//! A rigid object: a shape placed in the world, with a mass. Sensors measure distances
//! to objects; the scene moves them and lets hands hold them.

use crate::solid::Shape;
use glam::{DQuat, DVec3};

/// A rigid object: a shape at a pose, with a mass.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Unique name in the scene.
    pub name: String,
    /// Its shape (canonical frame centred on the position).
    pub shape: Shape,
    /// World position of the shape's centre.
    pub position: DVec3,
    /// World orientation.
    pub rotation: DQuat,
    /// Mass in kilograms.
    pub mass: f64,
}
