//! Hand-overs with a hand that a person drives (a performer's data glove, thesis 4.7 with
//! 4.5): the point where a giver brings an object into such a hand. Which hands a device
//! drives, and the open offers to them, are on the scene's blackboard
//! ([`troupe_scene::Blackboard`]); the actions that use them (giving into such a hand,
//! receiving from it) are in `crate::interact::device_hand`.
//!
//! A synthetic receiver plans, reaches and closes by itself (`give` starts its `receive`);
//! a performer's hand cannot be moved by the scene, so the giver brings the object into
//! the performer's open hand ([`offer_point`]) and the grasping automaton running in the
//! performer's `capture` action attaches it when the glove closes. Taking an object from
//! another actor's hand is allowed only while that actor offers it: the giver opens an
//! [`troupe_scene::Offer`] whose signals are stamped with ticks so that, as with every
//! note between actors, the outcome does not depend on which thread stepped which actor
//! first.

use troupe_body::glam::DVec3;
use troupe_body::sensors::{object_distance, HandSensors, Side};
use troupe_body::Transform;
use troupe_scene::{Object, World};

/// How far (metres) the object's surface stays from the open palm's sensor when it is
/// brought into a hand: close enough that closing fingers reach it at once.
pub const OFFER_GAP: f64 = 0.004;

/// The offset of an object's centre from the wrist of `side`'s hand, in the wrist frame,
/// for an object whose extent toward the palm is `extent`: in front of the palm, toward the
/// wrist and the thumb, where the thumb closing opposes the fingers (4.7: the automaton
/// needs the thumb and another finger on the object for a secure grasp).
fn offer_offset(hs: &HandSensors, rest_wrist: &Transform, extent: f64) -> DVec3 {
    let palm_r = hs.sensors.last().map(|s| s.radius).unwrap_or(0.0);
    // In the template's rest pose the arms hang with both thumbs pointing forward (+Z).
    let thumb = rest_wrist.rotation.inverse() * DVec3::Z;
    hs.palm + hs.palm_normal * (palm_r + extent + OFFER_GAP) - hs.finger_direction * 0.035
        + thumb * 0.03
}

/// Where a giver brings `object` so that `receiver`'s open hand `side` can close on it:
/// in front of that hand's palm (see `offer_offset`), from the last tick's posture.
pub fn offer_point(
    world: &World,
    receiver: usize,
    side: Side,
    object: usize,
) -> crate::error::Result<DVec3> {
    let info = world.actors.get(receiver).ok_or_else(|| {
        crate::error::ActionError::Unfit(format!("no actor #{receiver} to give to"))
    })?;
    let obj = world
        .objects
        .get(object)
        .ok_or_else(|| crate::error::ActionError::Unfit(format!("no object #{object}")))?;
    let hs = HandSensors::new(&info.skeleton, side)?;
    let sk = &info.skeleton;
    let mut globals = vec![Transform::IDENTITY; sk.joints().len()];
    troupe_body::kinematics::forward_kinematics(sk, &vec![0.0; sk.dof_count()], &mut globals);
    let wrist = world.states[receiver].globals[hs.wrist];
    // The object's extent along the palm normal: a point 1 m out along it is
    // `1 − extent` from the surface.
    let n = wrist.rotation * hs.palm_normal;
    let centred = Object {
        position: DVec3::ZERO,
        ..obj.clone()
    };
    let extent = (1.0 - object_distance(&centred, n)).max(0.0);
    let local = offer_offset(&hs, &globals[hs.wrist], extent);
    Ok(wrist.transform_point(local))
}
