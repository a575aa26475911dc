//! A face on every head: two eyes and a nose, so that where an actor looks shows in a
//! picture whatever the body style. The eyes sit in front of the eyeball joints (they
//! turn with `*_eyeball_pan` and `*_eyeball_tilt`); the nose on the front of the head
//! solid.

use crate::frame::ActorFrame;
use glam::{DVec3, Quat, Vec3};
use troupe_body::Shape;

/// The eyes' colour (linear RGB, before shading).
const EYE: [f32; 3] = [0.06, 0.06, 0.08];
/// How much darker than the skin the nose is, so that it shows against the face.
const NOSE_SHADE: f32 = 0.8;

/// One feature of a face: a sphere placed, turned and scaled in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Feature {
    /// Centre.
    pub center: Vec3,
    /// Orientation of the sphere's axes.
    pub rotation: Quat,
    /// Radii along its axes.
    pub radii: Vec3,
    /// Linear RGB colour, before shading.
    pub color: [f32; 3],
}

/// The eyes and nose of `actor`, sized by its head solid (`head_neck`); none for a body
/// without one (e.g. a BVH rig).
pub(crate) fn features(actor: &ActorFrame, skin: [f32; 3]) -> Vec<Feature> {
    let sk = &actor.skeleton;
    let Some((joint, head)) = sk.solids().iter().find(|(_, s)| s.name == "head_neck") else {
        return Vec::new();
    };
    let (Shape::Ellipsoid { radii }, Some(g)) = (&head.shape, actor.globals.get(*joint)) else {
        return Vec::new();
    };
    let mut out = Vec::with_capacity(3);
    for eye in ["l_eyeball_joint", "r_eyeball_joint"] {
        let Some(e) = sk.joint(eye).ok().and_then(|j| actor.globals.get(j)) else {
            continue;
        };
        out.push(Feature {
            center: e
                .transform_point(DVec3::new(0.0, 0.0, radii.z * 0.25))
                .as_vec3(),
            rotation: e.rotation.as_quat(),
            radii: Vec3::splat((radii.x * 0.2) as f32),
            color: EYE,
        });
    }
    let head_frame = g.rotation * head.orientation;
    let tip = head.center + head.orientation * DVec3::new(0.0, -0.15 * radii.y, 0.95 * radii.z);
    out.push(Feature {
        center: g.transform_point(tip).as_vec3(),
        rotation: head_frame.as_quat(),
        radii: Vec3::new(
            (radii.x * 0.16) as f32,
            (radii.y * 0.2) as f32,
            (radii.z * 0.3) as f32,
        ),
        color: skin.map(|c| c * NOSE_SHADE),
    });
    out
}
