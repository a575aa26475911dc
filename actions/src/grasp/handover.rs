//! Hand-overs with a hand that a person drives (a performer's data glove, thesis 4.7 with
//! 4.5): the board of device-driven hands and of open offers, and the point where a giver
//! brings an object into such a hand. The actions that use them (giving into such a hand,
//! receiving from it) are in `crate::interact::device_hand`.
//!
//! A synthetic receiver plans, reaches and closes by itself (`give` starts its `receive`);
//! a performer's hand cannot be moved by the scene, so the giver brings the object into
//! the performer's open hand ([`offer_point`]) and the grasping automaton running in the
//! performer's `capture` action attaches it when the glove closes. Taking an object from
//! another actor's hand is allowed only while that actor offers it: the giver registers an
//! [`Offer`] on the [`HandBoard`], stamped with ticks so that, as with every signal between
//! actors, the outcome does not depend on which thread stepped which actor first.

use super::action::Signal;
use std::sync::{Arc, Mutex};
use troupe_body::glam::DVec3;
use troupe_body::sensors::{object_distance, HandSensors, Side};
use troupe_body::Transform;
use troupe_scene::{Object, World};

/// How far (metres) the object's surface stays from the open palm's sensor when it is
/// brought into a hand: close enough that closing fingers reach it at once.
pub const OFFER_GAP: f64 = 0.004;

/// An object offered by `giver` to `receiver`'s device-driven hand.
#[derive(Clone, Debug)]
pub struct Offer {
    /// Object index.
    pub object: usize,
    /// The giving actor.
    pub giver: usize,
    /// The receiving actor.
    pub receiver: usize,
    /// Raised when the object is at the offer point.
    pub arrived: Arc<Signal>,
    /// Raised when the give is over (completed, failed or cancelled).
    pub closed: Arc<Signal>,
}

/// The hands driven by devices, and the open offers to them.
#[derive(Debug, Default)]
pub struct HandBoard {
    hands: Vec<(usize, Side)>,
    offers: Vec<Offer>,
}

impl HandBoard {
    /// Declares that `actor`'s hand `side` is driven by a device (a glove).
    pub fn add_hand(&mut self, actor: usize, side: Side) {
        if !self.hands.contains(&(actor, side)) {
            self.hands.push((actor, side));
        }
    }

    /// The device-driven hand of `actor`, if it has one.
    pub fn hand(&self, actor: usize) -> Option<Side> {
        self.hands.iter().find(|h| h.0 == actor).map(|h| h.1)
    }

    /// Opens an offer (and forgets the offers already closed: the board is only touched
    /// between ticks here, the same way with any thread count).
    pub fn offer(&mut self, offer: Offer) {
        self.offers.retain(|o| !o.closed.before(u64::MAX));
        self.offers.push(offer);
    }

    /// Whether `receiver` may take `object` from `holder` at `tick`: an offer of it from
    /// `holder` to `receiver` arrived, and was not closed, before this tick.
    pub fn may_take(&self, object: usize, receiver: usize, holder: usize, tick: u64) -> bool {
        self.offers.iter().any(|o| {
            o.object == object
                && o.receiver == receiver
                && o.giver == holder
                && o.arrived.before(tick)
                && !o.closed.before(tick)
        })
    }

    /// Forgets the offers closed before `tick`.
    pub fn prune(&mut self, tick: u64) {
        self.offers.retain(|o| !o.closed.before(tick));
    }
}

/// The scene's board, shared by the Lua builders (app data) and the performers' capture
/// generators.
#[derive(Clone, Debug, Default)]
pub struct SharedHandBoard(pub Arc<Mutex<HandBoard>>);

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
/// in front of that hand's palm (see [`offer_offset`]), from the last tick's posture.
pub fn offer_point(
    world: &World,
    receiver: usize,
    side: Side,
    object: usize,
) -> Result<DVec3, String> {
    let info = world
        .actors
        .get(receiver)
        .ok_or_else(|| format!("no actor #{receiver} to give to"))?;
    let obj = world
        .objects
        .get(object)
        .ok_or_else(|| format!("no object #{object}"))?;
    let hs = HandSensors::new(&info.skeleton, side).map_err(|e| e.to_string())?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offers_are_seen_from_the_tick_after_arrival_until_closed() {
        let mut b = HandBoard::default();
        let arrived = Arc::new(Signal::default());
        let closed = Arc::new(Signal::default());
        b.offer(Offer {
            object: 2,
            giver: 0,
            receiver: 1,
            arrived: arrived.clone(),
            closed: closed.clone(),
        });
        assert!(!b.may_take(2, 1, 0, 10), "not arrived yet");
        arrived.raise(10);
        assert!(
            !b.may_take(2, 1, 0, 10),
            "raised this tick: not believed yet"
        );
        assert!(b.may_take(2, 1, 0, 11));
        assert!(!b.may_take(2, 3, 0, 11), "another receiver");
        assert!(!b.may_take(2, 1, 4, 11), "another holder");
        assert!(!b.may_take(1, 1, 0, 11), "another object");
        closed.raise(20);
        assert!(b.may_take(2, 1, 0, 20) && !b.may_take(2, 1, 0, 21));
        b.prune(21);
        assert!(!b.may_take(2, 1, 0, 11), "pruned");
        // A new offer forgets closed ones.
        let again = Offer {
            object: 2,
            giver: 0,
            receiver: 1,
            arrived: Arc::new(Signal::default()),
            closed: Arc::new(Signal::default()),
        };
        b.offer(again.clone());
        b.offer(Offer {
            object: 3,
            closed: Arc::new(Signal::default()),
            ..again.clone()
        });
        let objects = |b: &HandBoard| b.offers.iter().map(|o| o.object).collect::<Vec<_>>();
        assert_eq!(objects(&b), vec![2, 3], "open offers stay");
        again.closed.raise(30);
        b.offer(Offer {
            object: 4,
            closed: Arc::new(Signal::default()),
            ..again
        });
        assert_eq!(objects(&b), vec![3, 4], "the closed one is forgotten");
    }
}
