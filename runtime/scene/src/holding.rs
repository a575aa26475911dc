//! Attachments (thesis 4.4): an object held by a hand follows the hand's joint.
//!
//! Generators cannot touch the scene, so a grasp generator *asks* for an attachment through
//! its [`crate::DofWriter`] ([`crate::DofWriter::request`]). After every actor has been
//! stepped and its forward kinematics done (tick step 6), the scene applies the requests
//! in actor order, then in the order each actor's actions emitted them, and finally moves
//! every held object to `joint global · grip`. Requests are applied serially after the
//! parallel step, so the outcome does not depend on the thread count.
//!
//! Rules, checked when a request is applied:
//! - `Attach` succeeds when the object is free, already held by the same actor (a
//!   re-grip), or held by the actor named in `from` (a hand-over, `actor:give`);
//!   otherwise it is ignored and the requester sees the true holder in the next snapshot.
//! - `Release` only releases an object the requesting actor holds.
//! - `Place` sets the object's pose and frees it, if the requester holds it or nobody does.

use glam::{DQuat, DVec3};
use troupe_body::object::Object;
use troupe_body::state::ActorState;
use troupe_body::transform::Transform;

/// Who holds an object and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Holder {
    /// Index of the holding actor.
    pub actor: usize,
    /// The joint the object is rigidly attached to (a wrist).
    pub joint: usize,
    /// The object's pose in that joint's frame, fixed at attachment.
    pub grip: Transform,
    /// The other wrist of a two-handed hold: its hand grips the object too, though the
    /// object follows `joint` alone.
    pub also: Option<usize>,
}

impl Holder {
    /// Whether `wrist` of the holding actor holds the object, alone or with the other hand.
    pub fn held_by(&self, wrist: usize) -> bool {
        self.joint == wrist || self.also == Some(wrist)
    }

    /// The wrists that hold the object: `joint`, then `also` if the hold is two-handed.
    pub fn wrists(&self) -> impl Iterator<Item = usize> {
        std::iter::once(self.joint).chain(self.also)
    }
}

/// What a generator asks of the scene about objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HoldRequest {
    /// Attach `object` to `joint` of the requesting actor, keeping its current world pose.
    Attach {
        /// Object index.
        object: usize,
        /// Joint of the requesting actor.
        joint: usize,
        /// The other wrist of a two-handed hold (see [`Holder::also`]).
        also: Option<usize>,
        /// Accept the object from this actor's hand (a hand-over).
        from: Option<usize>,
    },
    /// Let go of `object` (it stays where it is).
    Release {
        /// Object index.
        object: usize,
    },
    /// Let go of `object` and put it at this pose.
    Place {
        /// Object index.
        object: usize,
        /// World position of the object's centre.
        position: DVec3,
        /// World orientation.
        rotation: DQuat,
    },
}

/// Applies one request of `actor`; returns whether it took effect.
pub(crate) fn apply(
    actor: usize,
    request: HoldRequest,
    holders: &mut [Option<Holder>],
    objects: &mut [Object],
    states: &[ActorState],
) -> bool {
    match request {
        HoldRequest::Attach {
            object,
            joint,
            also,
            from,
        } => {
            let (Some(slot), Some(obj)) = (holders.get(object), objects.get(object)) else {
                return false;
            };
            let allowed = match slot {
                None => true,
                Some(h) => h.actor == actor || from == Some(h.actor),
            };
            let Some(frame) = states.get(actor).and_then(|s| s.globals.get(joint)) else {
                return false;
            };
            if !allowed {
                return false;
            }
            // The grip is taken from this tick's posture, so the object does not jump.
            let grip = frame
                .inverse()
                .mul(&Transform::new(obj.rotation, obj.position));
            holders[object] = Some(Holder {
                actor,
                joint,
                grip,
                also,
            });
            true
        }
        HoldRequest::Release { object } => match holders.get(object) {
            Some(Some(h)) if h.actor == actor => {
                holders[object] = None;
                true
            }
            _ => false,
        },
        HoldRequest::Place {
            object,
            position,
            rotation,
        } => {
            let free = match holders.get(object) {
                Some(None) => true,
                Some(Some(h)) => h.actor == actor,
                None => false,
            };
            if !free || !position.is_finite() || !rotation.is_finite() {
                return false;
            }
            holders[object] = None;
            objects[object].position = position;
            objects[object].rotation = rotation.normalize();
            true
        }
    }
}

/// Lists in `out` (its contents dropped) the objects `holders` says are held, in object
/// order, each with its holder: a walk asks each tick what its hands hold, and looking
/// through every object's holder for it cost the crowd benchmark 6 % of its instructions.
pub(crate) fn list_held(holders: &[Option<Holder>], out: &mut Vec<(usize, Holder)>) {
    out.clear();
    out.extend(
        holders
            .iter()
            .enumerate()
            .filter_map(|(object, holder)| holder.map(|h| (object, h))),
    );
}

/// Moves every held object to its holder's joint frame composed with its grip.
pub(crate) fn follow(holders: &[Option<Holder>], objects: &mut [Object], states: &[ActorState]) {
    for (object, holder) in objects.iter_mut().zip(holders) {
        let Some(h) = holder else { continue };
        let Some(frame) = states.get(h.actor).and_then(|s| s.globals.get(h.joint)) else {
            continue;
        };
        let pose = frame.mul(&h.grip);
        object.position = pose.translation;
        object.rotation = pose.rotation.normalize();
    }
}
