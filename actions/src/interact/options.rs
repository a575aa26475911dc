//! The options of the interactions: `give` (which starts the receiver's `receive` too),
//! `receive`, and `hold_hand` / `shake_hands` (which start the other's `follow_hand`).

use super::device_hand::{offer_to_hand, receive};
use super::offer::Grip;
use super::{facing_angle, FollowHand, Give, HoldHand, TURN_TO_TAKE};
use crate::error::{ActionError, OptionError, Result};
use crate::grasp::action::{check_duration, grasp_scope, holding_side, reach_scope, Grasp};
use crate::grasp::body::BodyReach;
use crate::grasp::close::HandModel;
use crate::grasp::plan::{HandChoice, PlanOptions};
use crate::walk::goal::Goal;
use crate::walk::{Walk, WalkOptions};
use troupe_body::glam::DVec2;
use troupe_body::sensors::Side;
use troupe_body::{Scope, Skeleton};
use troupe_scene::{ActionSpec, Generator, Scene};

/// Refuses `other` when it is the actor itself.
fn another(option: &'static str, other: usize, actor: usize) -> Result<(), OptionError> {
    if other == actor {
        return Err(OptionError::refused(
            option,
            format!("`{option}` must be another actor"),
        ));
    }
    Ok(())
}

/// The options of a give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GiveOptions {
    /// The held object's index in the scene.
    pub object: usize,
    /// The receiver's index.
    pub to: usize,
    /// The receiver's hand(s).
    pub hand: HandChoice,
    /// Seconds the giver waits for the receiver; `None`: [`super::GIVE_TIMEOUT`].
    pub timeout: Option<f64>,
    /// Whether the giver's and the receiver's arms bend round other bodies and obstacles
    /// (temporary goals, thesis 4.6.3; see [`crate::reach::arm_detour`]).
    pub detour: bool,
}

impl GiveOptions {
    /// `giver` gives `object` to `to`, who takes it with the hand(s) its plan picks.
    pub fn new(object: usize, to: usize) -> GiveOptions {
        GiveOptions {
            object,
            to,
            hand: HandChoice::Auto,
            timeout: None,
            detour: true,
        }
    }

    /// Checks the options for `giver`: another actor receives, a timeout is positive.
    pub fn validate(&self, giver: usize) -> Result<(), OptionError> {
        another("to", self.to, giver)?;
        if let Some(s) = self.timeout {
            if !(s.is_finite() && s > 0.0) {
                return Err(OptionError::invalid("timeout", "seconds > 0", s));
            }
        }
        Ok(())
    }

    /// Makes `giver`'s action, the DOFs it drives and the part of them it yields (the
    /// lean and crouch it may take to reach the meeting point: an
    /// [`ActionSpec::yields`], so that during a walk it gives with the arm alone). A
    /// receiver whose hand a person drives (declared on the scene's blackboard) takes the
    /// object when its glove closes; any other receiver gets a `receive` action started on
    /// `scene` now, `delay` seconds ahead like the give, which waits for the object to
    /// arrive. Pass the returned generator to [`Scene::start_action`]: the receiver learns
    /// of the give's end from it (also when `start_action` refuses it).
    pub fn start(
        &self,
        scene: &mut Scene,
        giver: usize,
        delay: f64,
    ) -> Result<(Box<dyn Generator>, Scope, Scope)> {
        self.validate(giver)?;
        in_scene(scene, &[giver, self.to], &[self.object])?;
        let side = holding_side(scene, giver, self.object).unwrap_or(Side::Right);
        let scope = grasp_scope(&scene.actors()[giver].skeleton, &[side])?;
        // Hands driven by a person (a performer's glove, 4.7) neither reach nor carry.
        let board = scene.blackboard();
        let (mine, theirs) = (board.device_hand(giver), board.device_hand(self.to));
        if mine.is_some() {
            return Err(ActionError::Unfit(
                "a performer gives by holding the object out: let the receiver take it with \
                 receiver:receive{object = …, from = performer}, then open the glove"
                    .into(),
            ));
        }
        if let Some(hand) = theirs {
            let giver =
                offer_to_hand(scene, self.object, giver, side, self.to, hand, self.timeout)?;
            return Ok((Box::new(giver), scope, Scope::EMPTY));
        }
        // The giver may lean or crouch to bring the object to the meeting point, as a grasp
        // does: the body is a yieldable part of its scope.
        let body = BodyReach::body_scope(&scene.actors()[giver].skeleton)?;
        let scope = scope.union(&body);
        let (arrived, ended) = (scene.new_signal(), scene.new_signal());
        let gave_up = scene.new_signal();
        let mut give = Give::new(self.object, self.to, side, arrived, ended)
            .watching(gave_up)
            .detouring(self.detour);
        if let Some(t) = self.timeout {
            give = give.with_timeout(t);
        }
        turn_to_face(scene, self.to, giver, delay)?;
        // The receiver: a grasp that waits for the object to arrive and may take it from
        // the giver.
        let sides = self.hand.sides();
        let (rx_scope, rx_body) = reach_scope(&scene.actors()[self.to].skeleton, &sides)?;
        let plan = PlanOptions {
            hand: self.hand,
            from: Some(giver),
            ..PlanOptions::default()
        };
        let take = Grasp::new(self.object, plan, sides, 1.0)?
            .gated(arrived)
            .abandoned_by(give.ended())
            .reporting(gave_up)
            .detouring(self.detour);
        let mut rx_spec = ActionSpec::new("receive", rx_scope);
        rx_spec.yields = rx_body;
        // Its lean comes back after a walk of the receiver's (its turn round) has ended.
        rx_spec.takes_back = true;
        rx_spec.delay = delay;
        scene.start_action(self.to, rx_spec, Box::new(take))?;
        Ok((Box::new(give), scope, body))
    }
}

/// Turns `receiver` on the spot to face `giver` (a walk to where it stands, `delay`
/// seconds ahead) when its back is to the giver, it stands and nothing else drives its
/// legs: a person turns round to take something rather than reach behind the back (the
/// arm twisted 80° and raised backwards). The give waits for the turn as for any walk.
fn turn_to_face(scene: &mut Scene, receiver: usize, giver: usize, delay: f64) -> Result<()> {
    let skeleton = scene.actors()[receiver].skeleton.clone();
    let Ok(x) = skeleton.dof("root_x") else {
        return Ok(());
    };
    let states = scene.states();
    let (me, them) = (&states[receiver], &states[giver]);
    let at = me.globals[0].translation;
    let to_giver = DVec2::new(
        them.globals[0].translation.x - at.x,
        them.globals[0].translation.z - at.z,
    );
    let standing = !super::walking(&scene.world(), &[receiver]);
    let legs_busy = scene
        .actions_of(receiver)
        .iter()
        .any(|a| !a.status.is_final() && a.scope.contains(x));
    if facing_angle(me, to_giver) <= TURN_TO_TAKE || !standing || legs_busy {
        return Ok(());
    }
    let options = WalkOptions {
        heading: Some(to_giver.x.atan2(to_giver.y)),
        ..WalkOptions::default()
    };
    let walk = Walk::navigate(
        &skeleton,
        Goal::Through(vec![DVec2::new(at.x, at.z)]),
        options,
    )?;
    let mut spec = ActionSpec::new("walk", walk.scope());
    spec.yields = walk.yields().intersection(&spec.scope);
    spec.takes_back = true;
    spec.delay = delay;
    scene.start_action(receiver, spec, Box::new(walk))?;
    Ok(())
}

/// The options of a receive: take an object out of another actor's hand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReceiveOptions {
    /// The object's index in the scene.
    pub object: usize,
    /// The actor holding it out.
    pub from: usize,
    /// The receiving hand(s).
    pub hand: HandChoice,
    /// Seconds to reach it.
    pub duration: f64,
    /// Whether the arm bends round other bodies and obstacles (as a grasp's).
    pub detour: bool,
}

impl ReceiveOptions {
    /// Checks the options for `receiver`: another actor gives, the reach time is
    /// positive.
    pub fn validate(&self, receiver: usize) -> Result<(), OptionError> {
        another("from", self.from, receiver)?;
        check_duration(self.duration)
    }

    /// The receiving grasp for `receiver` (built on `skeleton`) and the DOFs it drives.
    pub fn receive(&self, skeleton: &Skeleton, receiver: usize) -> Result<(Grasp, Scope)> {
        self.validate(receiver)?;
        let sides = self.hand.sides();
        let (grasp, scope) = receive(
            skeleton,
            self.object,
            self.from,
            self.hand,
            sides,
            self.duration,
        )?;
        Ok((grasp.detouring(self.detour), scope))
    }
}

/// The options of `hold_hand` and `shake_hands`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoldHandOptions {
    /// The other actor.
    pub other: usize,
    /// The acting actor's hand.
    pub hand: Side,
    /// The other actor's hand.
    pub other_hand: Side,
    /// Shake the held hand and let go (`shake_hands`), instead of holding it on.
    pub shake: bool,
}

impl HoldHandOptions {
    /// Takes `other`'s hand with `hand`: its opposite hand to hold hands side by side,
    /// its same hand to shake hands.
    pub fn new(other: usize, hand: Side, shake: bool) -> HoldHandOptions {
        HoldHandOptions {
            other,
            hand,
            other_hand: if shake { Side::Right } else { hand.other() },
            shake,
        }
    }

    /// The kind of action: `hold_hand` or `shake_hands`.
    pub fn kind(&self) -> &'static str {
        if self.shake {
            "shake_hands"
        } else {
            "hold_hand"
        }
    }

    /// Checks the options for `actor`: the other is another actor.
    pub fn validate(&self, actor: usize) -> Result<(), OptionError> {
        another("other", self.other, actor)
    }

    /// Makes `actor`'s action and the DOFs it drives, and starts the other's
    /// `follow_hand` on `scene` now, `delay` seconds ahead and lasting `duration` like
    /// the hold.
    pub fn start(
        &self,
        scene: &mut Scene,
        actor: usize,
        delay: f64,
        duration: Option<f64>,
    ) -> Result<(HoldHand, Scope)> {
        self.validate(actor)?;
        in_scene(scene, &[actor, self.other], &[])?;
        let (held, finished, gave_up) =
            (scene.new_signal(), scene.new_signal(), scene.new_signal());
        let mut active = HoldHand::new(
            self.other,
            (self.hand, self.other_hand),
            self.shake,
            (held, finished, gave_up),
        );
        let skeleton = scene.actors()[actor].skeleton.clone();
        let scope = grasp_scope(&skeleton, &[self.hand])?;
        let wrist = skeleton.joint(&format!("{}wrist", self.hand.prefix()))?;
        let follow_scope = scene.actors()[self.other]
            .skeleton
            .scope(&format!("{}_arm", self.other_hand.name()))?;
        let mut follow =
            FollowHand::new((actor, wrist), self.other_hand, (held, finished, gave_up));
        if self.shake {
            // The other holds its hand out for a handshake, and is reached there.
            active = active.to_offered_hand();
            follow = follow.offering(Grip::Shake, self.hand);
        } else if hangs_lower(scene, (self.other, self.other_hand), (actor, self.hand))? {
            // A shorter other lifts its hand to the taller's, who cannot reach below its
            // own hanging hand.
            active = active.to_offered_hand();
            follow = follow.offering(Grip::Hold, self.hand);
        }
        let mut follow_spec = ActionSpec::new("follow_hand", follow_scope);
        follow_spec.delay = delay;
        follow_spec.duration = duration;
        scene.start_action(self.other, follow_spec, Box::new(follow))?;
        Ok((active, scope))
    }
}

/// How far (m) below the other's hanging hand one's may hang and still be reached there.
const REACHED_BELOW: f64 = 0.01;

/// Whether actor `a`'s hand `a_side` hangs lower than `b`'s hand `b_side` (their palms,
/// as they stand) by more than [`REACHED_BELOW`].
fn hangs_lower(
    scene: &Scene,
    (a, a_side): (usize, Side),
    (b, b_side): (usize, Side),
) -> Result<bool> {
    let palm = |actor: usize, side: Side| -> Result<f64> {
        let model = HandModel::new(&scene.actors()[actor].skeleton, side)?;
        let wrist = scene.states()[actor].globals[model.sensors.wrist];
        Ok(wrist.transform_point(model.sensors.palm).y)
    };
    Ok(palm(a, a_side)? < palm(b, b_side)? - REACHED_BELOW)
}

/// Refuses actor and object indices the scene does not have.
fn in_scene(scene: &Scene, actors: &[usize], objects: &[usize]) -> Result<()> {
    if let Some(a) = actors.iter().find(|&&a| a >= scene.actors().len()) {
        return Err(troupe_scene::Error::UnknownActor(format!("#{a}")).into());
    }
    if let Some(o) = objects.iter().find(|&&o| o >= scene.objects().len()) {
        return Err(troupe_scene::Error::UnknownObject(format!("#{o}")).into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn good_options_pass() {
        GiveOptions::new(0, 1).validate(0).unwrap();
        let receive = ReceiveOptions {
            object: 0,
            from: 1,
            hand: HandChoice::Right,
            duration: 1.0,
            detour: true,
        };
        receive.validate(0).unwrap();
        let hold = HoldHandOptions::new(1, Side::Right, false);
        hold.validate(0).unwrap();
        assert_eq!(hold.other_hand, Side::Left);
        assert_eq!(
            HoldHandOptions::new(1, Side::Left, true).other_hand,
            Side::Right
        );
    }

    #[test]
    fn each_bad_option_is_named() {
        GiveOptions::new(0, 0)
            .validate(0)
            .unwrap_err()
            .assert_names("to");
        let slow = GiveOptions {
            timeout: Some(0.0),
            ..GiveOptions::new(0, 1)
        };
        slow.validate(0).unwrap_err().assert_names("timeout");
        let receive = ReceiveOptions {
            object: 0,
            from: 0,
            hand: HandChoice::Auto,
            duration: 1.0,
            detour: true,
        };
        receive.validate(0).unwrap_err().assert_names("from");
        let hasty = ReceiveOptions {
            from: 1,
            duration: f64::NAN,
            ..receive
        };
        hasty.validate(0).unwrap_err().assert_names("duration");
        let alone = HoldHandOptions::new(0, Side::Right, true);
        alone.validate(0).unwrap_err().assert_names("other");
    }
}
