//! The blackboard: what actions tell one another, and tell the observers, tick by tick.
//!
//! Two actors' actions cooperate (a give and its receive, the two hands of a handshake, a
//! performer's glove taking an offered object) and a dynamics action reports its torques.
//! None of them shares mutable state with another: a generator *posts* [`Note`]s through
//! its [`DofWriter`](crate::DofWriter) during a tick, the scene applies every actor's notes
//! after the tick, serially in actor order, and the next tick's [`World`](crate::World)
//! shows the board to every generator. A note is never seen in the tick that posted it,
//! so what a generator reads does not depend on which thread stepped which actor first.
//!
//! Signals are stamped with the tick that raised them; [`Blackboard::before`] believes a
//! stamp from an earlier tick only. Observers read the board after each tick (the
//! torques of that tick).

use std::collections::{BTreeMap, HashMap};
use troupe_body::sensors::Side;

/// A one-way signal between actions (`the object is at the meeting point`, `the give has
/// ended`): made by [`crate::Scene::new_signal`], raised once, never lowered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SignalId(pub u64);

/// An object a giver holds out to a device-driven hand: the receiver may take it from
/// the giver while `arrived` is raised and `closed` is not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Offer {
    /// Object index.
    pub object: usize,
    /// The giving actor.
    pub giver: usize,
    /// The receiving actor.
    pub receiver: usize,
    /// Raised when the object is at the offer point.
    pub arrived: SignalId,
    /// Raised when the give is over (completed, failed or cancelled).
    pub closed: SignalId,
}

/// The grasping automaton's states of a device-driven hand (thesis 4.7: pale skin, blue,
/// green in the thesis' display).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandState {
    /// Nothing touched.
    FreeHand,
    /// Some finger touches object `.0`, not yet a secure grasp.
    GraspingInProgress(usize),
    /// Thumb and another finger hold object `.0`: it is attached to the hand.
    SecureGrasp(usize),
}

impl HandState {
    /// `FREE_HAND`, `GRASPING_IN_PROGRESS` or `SECURE_GRASP`.
    pub fn name(self) -> &'static str {
        match self {
            HandState::FreeHand => "FREE_HAND",
            HandState::GraspingInProgress(_) => "GRASPING_IN_PROGRESS",
            HandState::SecureGrasp(_) => "SECURE_GRASP",
        }
    }

    /// The object touched or held, if any.
    pub fn object(self) -> Option<usize> {
        match self {
            HandState::FreeHand => None,
            HandState::GraspingInProgress(o) | HandState::SecureGrasp(o) => Some(o),
        }
    }
}

/// One joint torque of a tick, from a dynamics action.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Torque {
    /// The actor.
    pub actor: usize,
    /// The DOF.
    pub dof: usize,
    /// N·m, or N for a translation; two dynamics actions on one DOF add up.
    pub torque: f64,
}

/// What a generator posts.
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// Raises a signal (the first raise's tick stays).
    Raise(SignalId),
    /// Raises a signal that says something failed, with why (the first raise's tick and
    /// reason stay): a giver learns why its receiver gave up, and the other way round.
    Fail(SignalId, String),
    /// The grasping automaton's state of the posting actor's device-driven hand after
    /// this tick (a performer's `capture`).
    Hand(HandState),
    /// The posting actor's joint torque on `dof` this tick (N·m, or N for a translation).
    Torque {
        /// The DOF.
        dof: usize,
        /// The torque.
        torque: f64,
    },
    /// The posting actor's hand is on its way to object `.0` (a grasp reaching for it):
    /// the first actor to claim an object keeps it until it lets go (see
    /// [`Blackboard::claimed_by`]).
    Claim(usize),
    /// The posting actor's hand no longer goes for object `.0`.
    Unclaim(usize),
}

/// Notes a generator posts in one step, or when its action ends.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Notes(Vec<Note>);

impl Notes {
    /// Raises `signal` (seen by every generator from the next tick on).
    pub fn raise(&mut self, signal: SignalId) {
        self.0.push(Note::Raise(signal));
    }

    /// Raises `signal` as a failure, with `reason` (see [`Blackboard::failure`]).
    pub fn fail(&mut self, signal: SignalId, reason: impl Into<String>) {
        self.0.push(Note::Fail(signal, reason.into()));
    }

    /// Posts `note`.
    pub fn post(&mut self, note: Note) {
        self.0.push(note);
    }

    /// Takes the notes posted so far.
    pub fn take(&mut self) -> Vec<Note> {
        std::mem::take(&mut self.0)
    }
}

/// The board itself: signals, device-driven hands, open offers and the last tick's
/// torques.
#[derive(Clone, Debug, Default)]
pub struct Blackboard {
    stamps: HashMap<SignalId, u64>,
    failures: HashMap<SignalId, String>,
    next_signal: u64,
    device_hands: Vec<(usize, Side)>,
    hand_states: BTreeMap<usize, HandState>,
    offers: Vec<Offer>,
    torques: BTreeMap<(usize, usize), f64>,
    /// Per object, the actor whose hand is on its way to it.
    claims: BTreeMap<usize, usize>,
}

impl Blackboard {
    /// Whether `signal` was raised before `tick`.
    pub fn before(&self, signal: SignalId, tick: u64) -> bool {
        self.stamps.get(&signal).is_some_and(|&t| t < tick)
    }

    /// Why `signal` was raised as a failure, if it was, before `tick`.
    pub fn failure(&self, signal: SignalId, tick: u64) -> Option<&str> {
        if self.before(signal, tick) {
            self.failures.get(&signal).map(String::as_str)
        } else {
            None
        }
    }

    /// Whether `signal` has been raised at all.
    pub fn is_raised(&self, signal: SignalId) -> bool {
        self.stamps.contains_key(&signal)
    }

    /// The device-driven hand of `actor` (a performer's glove), if it has one.
    pub fn device_hand(&self, actor: usize) -> Option<Side> {
        self.device_hands.iter().find(|h| h.0 == actor).map(|h| h.1)
    }

    /// The grasping automaton's state of `actor`'s device-driven hand after the last tick
    /// (`FreeHand` until its `capture` reports), if it has one.
    pub fn hand_state(&self, actor: usize) -> Option<(Side, HandState)> {
        let side = self.device_hand(actor)?;
        let state = self
            .hand_states
            .get(&actor)
            .copied()
            .unwrap_or(HandState::FreeHand);
        Some((side, state))
    }

    /// Whether `receiver` may take `object` from `holder` at `tick`: `holder` offers it to
    /// `receiver`, the offer arrived, and was not closed, before this tick.
    pub fn may_take(&self, object: usize, receiver: usize, holder: usize, tick: u64) -> bool {
        self.offers.iter().any(|o| {
            o.object == object
                && o.receiver == receiver
                && o.giver == holder
                && self.before(o.arrived, tick)
                && !self.before(o.closed, tick)
        })
    }

    /// The actor whose hand is on its way to `object` (its grasp claimed it first: claims
    /// of one tick are applied in actor order, so the lower index wins a tie), if any.
    pub fn claimed_by(&self, object: usize) -> Option<usize> {
        self.claims.get(&object).copied()
    }

    /// The offers, oldest first (closed ones are forgotten when the next one opens).
    pub fn offers(&self) -> &[Offer] {
        &self.offers
    }

    /// The torques the dynamics actions posted in the last tick, by actor then DOF (what
    /// observers read after the tick, and generators during the next).
    pub fn torques(&self) -> impl Iterator<Item = Torque> + '_ {
        self.torques
            .iter()
            .map(|(&(actor, dof), &torque)| Torque { actor, dof, torque })
    }

    /// A new signal, not raised.
    pub(crate) fn new_signal(&mut self) -> SignalId {
        self.next_signal += 1;
        SignalId(self.next_signal)
    }

    /// Stamps `signal` with `tick` unless it was raised already.
    pub(crate) fn raise(&mut self, signal: SignalId, tick: u64) {
        self.stamps.entry(signal).or_insert(tick);
    }

    /// Declares `actor`'s hand `side` driven by a device.
    pub(crate) fn add_device_hand(&mut self, actor: usize, side: Side) {
        if !self.device_hands.contains(&(actor, side)) {
            self.device_hands.push((actor, side));
        }
    }

    /// Opens an offer, forgetting the offers already closed.
    pub(crate) fn open_offer(&mut self, offer: Offer) {
        let stamps = &self.stamps;
        self.offers.retain(|o| !stamps.contains_key(&o.closed));
        self.offers.push(offer);
    }

    /// Starts applying a tick's notes: the previous tick's torques give way to this one's.
    pub(crate) fn begin_tick(&mut self) {
        self.torques.clear();
    }

    /// Applies the notes `actor` posted at `tick`.
    pub(crate) fn apply(&mut self, actor: usize, tick: u64, notes: Vec<Note>) {
        for note in notes {
            match note {
                Note::Raise(signal) => self.raise(signal, tick),
                Note::Fail(signal, reason) => {
                    if !self.stamps.contains_key(&signal) {
                        self.failures.insert(signal, reason);
                    }
                    self.raise(signal, tick);
                }
                Note::Hand(state) => {
                    self.hand_states.insert(actor, state);
                }
                Note::Torque { dof, torque } => {
                    *self.torques.entry((actor, dof)).or_insert(0.0) += torque;
                }
                Note::Claim(object) => {
                    self.claims.entry(object).or_insert(actor);
                }
                Note::Unclaim(object) => {
                    if self.claims.get(&object) == Some(&actor) {
                        self.claims.remove(&object);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_claim_of_an_object_stays_until_its_claimant_lets_go() {
        let mut b = Blackboard::default();
        // One tick's notes are applied in actor order: actor 1 before actor 4.
        b.apply(1, 7, vec![Note::Claim(3)]);
        b.apply(4, 7, vec![Note::Claim(3)]);
        assert_eq!(b.claimed_by(3), Some(1));
        b.apply(4, 8, vec![Note::Unclaim(3)]);
        assert_eq!(b.claimed_by(3), Some(1), "only the claimant lets go");
        b.apply(1, 9, vec![Note::Unclaim(3)]);
        assert_eq!(b.claimed_by(3), None);
        b.apply(4, 10, vec![Note::Claim(3)]);
        assert_eq!(b.claimed_by(3), Some(4));
    }

    #[test]
    fn a_signal_is_believed_from_the_tick_after_its_stamp_and_the_first_stamp_stays() {
        let mut b = Blackboard::default();
        let s = b.new_signal();
        assert!(!b.is_raised(s) && !b.before(s, u64::MAX));
        b.apply(0, 10, vec![Note::Raise(s)]);
        b.apply(1, 20, vec![Note::Raise(s)]);
        assert!(!b.before(s, 10));
        assert!(b.before(s, 11));
        assert_ne!(b.new_signal(), s);
    }

    #[test]
    fn a_failure_carries_its_first_reason_from_the_tick_after_its_stamp() {
        let mut b = Blackboard::default();
        let s = b.new_signal();
        b.apply(0, 10, vec![Note::Fail(s, "misses by 0.2 m".into())]);
        b.apply(1, 11, vec![Note::Fail(s, "later".into()), Note::Raise(s)]);
        assert_eq!(b.failure(s, 10), None);
        assert_eq!(b.failure(s, 11), Some("misses by 0.2 m"));
        let plain = b.new_signal();
        b.apply(0, 10, vec![Note::Raise(plain)]);
        assert_eq!(b.failure(plain, 11), None);
    }

    #[test]
    fn an_offer_may_be_taken_between_arrival_and_close_and_closed_ones_are_forgotten() {
        let mut b = Blackboard::default();
        let (arrived, closed) = (b.new_signal(), b.new_signal());
        let offer = Offer {
            object: 3,
            giver: 0,
            receiver: 1,
            arrived,
            closed,
        };
        b.open_offer(offer);
        assert!(!b.may_take(3, 1, 0, 5));
        b.raise(arrived, 5);
        assert!(!b.may_take(3, 1, 0, 5));
        assert!(b.may_take(3, 1, 0, 6));
        assert!(!b.may_take(3, 2, 0, 6), "only the receiver");
        assert!(!b.may_take(3, 1, 2, 6), "only from the giver");
        b.raise(closed, 8);
        assert!(b.may_take(3, 1, 0, 8));
        assert!(!b.may_take(3, 1, 0, 9));
        let again = Offer {
            closed: b.new_signal(),
            ..offer
        };
        b.open_offer(again);
        assert_eq!(b.offers(), &[again]);
    }

    #[test]
    fn torques_of_one_dof_add_up_and_last_one_tick() {
        let mut b = Blackboard::default();
        b.apply(
            0,
            1,
            vec![Note::Torque {
                dof: 4,
                torque: 1.5,
            }],
        );
        b.apply(
            0,
            1,
            vec![Note::Torque {
                dof: 4,
                torque: 0.5,
            }],
        );
        b.apply(
            1,
            1,
            vec![Note::Torque {
                dof: 4,
                torque: 2.0,
            }],
        );
        assert_eq!(
            b.torques().collect::<Vec<_>>(),
            [
                Torque {
                    actor: 0,
                    dof: 4,
                    torque: 2.0
                },
                Torque {
                    actor: 1,
                    dof: 4,
                    torque: 2.0
                }
            ]
        );
        b.begin_tick();
        assert_eq!(b.torques().count(), 0);
    }
}
