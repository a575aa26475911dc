//! Giving into, and receiving from, a hand that a person drives (a performer's data glove,
//! thesis 4.7 with 4.5): the giver brings the object to the [`offer_point`](crate::grasp::handover::offer_point) of the open
//! hand and waits for the grasping automaton to attach it; a synthetic actor takes an
//! object from such a hand only while its holder offers it ([`troupe_scene::Offer`] on the
//! scene's blackboard).

use crate::grasp::action::{reach_scope, Grasp};
use crate::grasp::plan::{HandChoice, PlanOptions};
use crate::interact::Give;
use troupe_body::sensors::Side;
use troupe_scene::{
    DofWriter, Ending, Generator, GeneratorContext, Notes, Offer, Scene, SignalId, StartError, Step,
};

/// The giver's side of a give to a device-driven hand: a [`Give`] into the hand, and the
/// offer closed when it ends in any way.
pub struct Offering {
    give: Give,
    closed: SignalId,
}

impl Generator for Offering {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        self.give.start(ctx)
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        self.give.step(ctx, out)
    }

    /// Closes the offer (seen by the receiver from the next tick on) and ends the give.
    fn end(&mut self, ending: &Ending, notes: &mut Notes) {
        notes.raise(self.closed);
        self.give.end(ending, notes);
    }
}

/// Builds the giver's action of a give from `giver` (holding `object` in `side`) to
/// `receiver`'s device-driven hand `hand`, and opens the offer on the scene's blackboard.
pub fn offer_to_hand(
    scene: &mut Scene,
    object: usize,
    giver: usize,
    side: Side,
    receiver: usize,
    hand: Side,
    timeout: Option<f64>,
) -> crate::error::Result<Offering> {
    let (arrived, closed, ended) = (scene.new_signal(), scene.new_signal(), scene.new_signal());
    // Into a hand a person drives, the carry stays the planned interpolation: taking the
    // hand's straight path instead brushes the object past the glove's sensors on the
    // way (its automaton then flickers to GRASPING_IN_PROGRESS and back).
    let mut give = Give::new(object, receiver, side, arrived, ended)
        .into_hand(hand)
        .detouring(false);
    if let Some(t) = timeout {
        give = give.with_timeout(t);
    }
    scene.open_offer(Offer {
        object,
        giver,
        receiver,
        arrived,
        closed,
    })?;
    Ok(Offering { give, closed })
}

/// `actor:receive{object = OBJ, from = ACTOR, hand = …}`: a grasp allowed to take `object`
/// out of `from`'s hand (how a synthetic actor takes an object a performer holds out; the
/// performer then opens the glove).
pub fn receive(
    skeleton: &troupe_body::Skeleton,
    object: usize,
    from: usize,
    hand: HandChoice,
    sides: Vec<Side>,
    reach_seconds: f64,
) -> crate::error::Result<(Grasp, troupe_body::Scope)> {
    let (scope, _) = reach_scope(skeleton, &sides)?;
    let g = Grasp::new(
        object,
        PlanOptions {
            hand,
            from: Some(from),
            ..PlanOptions::default()
        },
        sides,
        reach_seconds,
    )?;
    Ok((g, scope))
}
