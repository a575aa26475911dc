//! Giving into, and receiving from, a hand that a person drives (a performer's data glove,
//! thesis 4.7 with 4.5): the giver brings the object to the [`offer_point`](crate::grasp::handover::offer_point) of the open
//! hand and waits for the grasping automaton to attach it; a synthetic actor takes an
//! object from such a hand only while its holder offers it on the [`HandBoard`](crate::grasp::handover::HandBoard).

use crate::grasp::action::{grasp_scope, Grasp, Signal};
use crate::grasp::handover::{Offer, SharedHandBoard};
use crate::grasp::plan::{HandChoice, PlanOptions};
use crate::interact::Give;
use std::sync::Arc;
use troupe_body::sensors::Side;
use troupe_scene::{DofWriter, Generator, GeneratorContext, Step};

/// The giver's side of a give to a device-driven hand: a [`Give`] into the hand, and the
/// offer closed when it ends in any way.
pub struct Offering {
    give: Give,
    closed: Arc<Signal>,
    last_tick: u64,
}

impl Drop for Offering {
    /// Closes the offer the tick after the last step (the scheduler drops a generator on
    /// the tick its action ends), seen by the receiver from the next tick on.
    fn drop(&mut self) {
        // Never stepped (cancelled while pending): closed at once.
        self.closed.raise(self.last_tick + 1);
    }
}

impl Generator for Offering {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), String> {
        let r = self.give.start(ctx);
        if r.is_err() {
            self.closed.raise(ctx.tick);
        }
        r
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        self.last_tick = ctx.tick;
        self.give.step(ctx, out)
    }
}

/// Builds the giver's action of a give from `giver` (holding `object` in `side`) to
/// `receiver`'s device-driven hand `hand`, and opens the offer on `board`.
pub fn offer_to_hand(
    board: &SharedHandBoard,
    object: usize,
    giver: usize,
    side: Side,
    receiver: usize,
    hand: Side,
    timeout: Option<f64>,
) -> crate::error::Result<Offering> {
    let arrived = Arc::new(Signal::default());
    let closed = Arc::new(Signal::default());
    let mut give = Give::new(object, receiver, side, arrived.clone()).into_hand(hand);
    if let Some(t) = timeout {
        give = give.with_timeout(t);
    }
    board
        .0
        .lock()
        .map_err(|_| crate::error::ActionError::Poisoned("hand board"))?
        .offer(Offer {
            object,
            giver,
            receiver,
            arrived,
            closed: closed.clone(),
        });
    Ok(Offering {
        give,
        closed,
        last_tick: 0,
    })
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
    let scope = grasp_scope(skeleton, &sides)?;
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
