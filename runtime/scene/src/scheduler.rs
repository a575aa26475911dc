//! The per-actor scheduler: admission of pending actions by priority mode, status
//! transitions, stepping the generators and blending their output.
//!
//! One tick of one actor at scene time `t` runs these phases in order:
//!
//! 1. **Admission.** Pending actions are considered in creation order. A cancel request
//!    on a pending action cancels it. An action whose begin time (creation + `delay`) has
//!    come is admitted if its mode allows: `default` only when no running action and no
//!    earlier pending action of the actor overlaps its scope (so it starts on the tick
//!    after the last conflicting action stopped); `weighted` always; `exclusive` always,
//!    pre-empting every running action that overlaps it; `clearing` always, pre-empting
//!    every running action of the actor and cancelling every earlier pending one. A
//!    pre-empted action eases out over its own `ease_out` and ends `cancelled`.
//!    Admission moves an action to `initiating` (or straight to `active` without
//!    ease-in) and calls its generator's `start`.
//! 2. **Transitions.** Cancel requests start the ease-out; `initiating` becomes `active`
//!    once `ease_in` has passed; an action with a `duration` starts terminating at
//!    `start + duration − ease_out`; a terminating action whose ease-out is over ends
//!    (it contributes nothing on that tick). An action that takes back what it yields
//!    gets the DOFs whose takers have let go of them (see [`ActionSpec::takes_back`]).
//! 3. **Generators.** Every running action's generator is stepped with the previous
//!    tick's snapshot and writes its scope; its output enters the blend with weight ×
//!    ease factor. A generator reporting `Finished` starts the ease-out (or completes at
//!    once, its last output counted); `Failed` ends the action at once, output discarded.
//! 4. **Blend and kinematics**: [`crate::blend`], then forward kinematics.
//!
//! Each actor's tick reads only the previous tick's world and writes only its own state,
//! so actors are stepped in parallel and the result does not depend on the thread count.

use crate::action::{
    ActionId, ActionInfo, ActionSpec, DofWriter, Ending, Event, Generator, GeneratorContext, Mode,
    Status, Step,
};
use crate::blackboard::{Note, Notes};
use crate::blend::ease;
use crate::blend::{ease_factor, Accumulator};
use crate::profile::{ActorPhases, PhaseClock};
use crate::world::World;
use troupe_body::scope::Scope;
use troupe_body::skeleton::Skeleton;
use troupe_body::state::ActorState;

/// The least time (s) over which DOFs an action gets back ease in: a swinging arm that
/// comes back at once would jump from where the taker left it.
pub const TAKE_BACK_EASE: f64 = 0.3;

/// An action owned by the scheduler.
pub(crate) struct Action {
    pub id: ActionId,
    pub spec: ActionSpec,
    pub status: Status,
    pub begin: f64,
    pub started_at: Option<f64>,
    pub terminate_at: Option<f64>,
    pub ended_at: Option<f64>,
    /// The status the action takes when its ease-out ends.
    pub ending: Status,
    pub reason: Option<String>,
    pub cancel_requested: bool,
    /// `:stop()` was asked and not yet acted on.
    pub stop_requested: bool,
    /// The generator accepted to finish by itself ([`Generator::stop`]): the action keeps
    /// full weight until it reports `Finished`, then ends with `ending`.
    pub winding_down: bool,
    /// A `:stop()` found its purpose undone ([`Generator::unfinished`]) and made it end
    /// cancelled: asked again when the ease-out is over, as the generator works on.
    pub stopped_undone: bool,
    /// The scope the action was created with (its scope shrinks when it is narrowed).
    pub original: Scope,
    /// DOFs given up to other actions, each set with the time it was given up: they fade
    /// out over `ease_out` while the taker eases in.
    pub releasing: Vec<(Scope, f64)>,
    /// DOFs given up to other actions that come back when the taker ends (with
    /// `spec.takes_back`), each set with the taker's id.
    pub lent: Vec<(ActionId, Scope)>,
    /// DOFs given back, each set with the time it came back: they ease in over
    /// [`Action::return_time`] from the posture the taker left.
    pub returning: Vec<(Scope, f64)>,
    /// The last tick the generator was started or stepped (0: never).
    pub last_run: u64,
    pub generator: Box<dyn Generator>,
}

impl Action {
    /// A pending action, as [`crate::Scene::start_action`] creates it.
    pub(crate) fn new(
        id: ActionId,
        spec: ActionSpec,
        begin: f64,
        generator: Box<dyn Generator>,
    ) -> Action {
        Action {
            id,
            original: spec.scope,
            spec,
            status: Status::Pending,
            begin,
            started_at: None,
            terminate_at: None,
            ended_at: None,
            ending: Status::Completed,
            reason: None,
            cancel_requested: false,
            stop_requested: false,
            winding_down: false,
            stopped_undone: false,
            releasing: Vec::new(),
            lent: Vec::new(),
            returning: Vec::new(),
            last_run: 0,
            generator,
        }
    }

    /// The DOFs its generator may still write: its scope and what it is still releasing.
    fn writable(&self) -> Scope {
        self.releasing
            .iter()
            .fold(self.spec.scope, |s, (r, _)| s.union(r))
    }

    /// How much of its weight the action still has on DOF `d` that it gave up at `since`.
    fn release_fade(&self, since: f64, time: f64) -> f64 {
        if self.spec.ease_out > 0.0 {
            1.0 - ease((time - since) / self.spec.ease_out)
        } else {
            0.0
        }
    }

    /// Seconds over which DOFs given back ease in: its own ease-in, at least
    /// [`TAKE_BACK_EASE`].
    fn return_time(&self) -> f64 {
        self.spec.ease_in.max(TAKE_BACK_EASE)
    }

    /// How much of its weight the action has on DOFs given back to it at `since`.
    fn return_fade(&self, since: f64, time: f64) -> f64 {
        ease((time - since) / self.return_time())
    }

    /// Whether it no longer holds what it took at full weight: ended, or easing out.
    fn lets_go(&self) -> bool {
        self.status.is_final() || (self.status == Status::Terminating && !self.winding_down)
    }

    pub(crate) fn info(&self, actor: usize) -> ActionInfo {
        ActionInfo {
            id: self.id,
            actor,
            kind: self.spec.kind.clone(),
            scope: self.spec.scope,
            yielded: self.original.difference(&self.spec.scope),
            mode: self.spec.mode,
            weight: self.spec.weight,
            status: self.status,
            reason: self.reason.clone(),
            started_at: self.started_at,
            ended_at: self.ended_at,
            detours: self.generator.detours(),
        }
    }
}

/// Everything the scheduler keeps for one actor between ticks.
#[derive(Default)]
pub struct ActorRuntime {
    pub(crate) actions: Vec<Action>,
    /// Actions that ended during the last tick, for the scene's records.
    pub(crate) ended: Vec<ActionInfo>,
    /// Status changes of the last tick.
    pub(crate) events: Vec<Event>,
    /// Generator writes refused because they fell outside the action's scope.
    pub(crate) refused_writes: u64,
    /// Time spent per phase since the scene last collected it (when profiling).
    pub(crate) phases: ActorPhases,
    /// Attach/release requests of the last tick, in emission order (see [`crate::holding`]).
    pub(crate) hold_requests: Vec<crate::holding::HoldRequest>,
    /// Blackboard notes of the last tick, in emission order (see [`crate::blackboard`]).
    pub(crate) notes: Vec<Note>,
    /// Notes of generators whose action ended in the last tick, with the tick each is
    /// stamped with (see [`Generator::end`]).
    pub(crate) end_notes: Vec<(u64, Note)>,
    scratch: Vec<f64>,
    accumulator: Accumulator,
}

/// The clock of one tick.
#[derive(Clone, Copy)]
pub(crate) struct TickClock {
    pub tick: u64,
    pub time: f64,
    pub dt: f64,
    /// Whether to time the phases.
    pub profile: bool,
}

struct Transitions<'a> {
    actor: usize,
    clock: TickClock,
    events: &'a mut Vec<Event>,
}

impl Transitions<'_> {
    fn set(&mut self, action: &mut Action, status: Status) {
        action.status = status;
        if status.is_final() {
            action.ended_at = Some(self.clock.time);
        }
        let reason = if status.is_final() {
            action.reason.clone()
        } else {
            None
        };
        self.event(action, reason, None);
    }

    /// Publishes `action`'s current status (with `reason`), or its narrowing by `narrowed`.
    fn event(&mut self, action: &Action, reason: Option<String>, narrowed: Option<Scope>) {
        self.events.push(Event {
            tick: self.clock.tick,
            time: self.clock.time,
            actor: self.actor,
            action: action.id,
            kind: action.spec.kind.clone(),
            status: action.status,
            reason,
            narrowed,
        });
    }

    /// Asks `action` to end gracefully toward `ending` (a stop, a cancel, a pre-emption):
    /// a generator that can finish by itself winds down at full weight (the action is
    /// `terminating` until it reports `Finished`); any other eases out.
    fn stop(&mut self, action: &mut Action, ending: Status, reason: Option<String>) {
        if action.winding_down || action.status == Status::Terminating {
            if ending == Status::Cancelled {
                action.ending = ending;
                action.reason = reason;
            }
            return;
        }
        if action.generator.stop() {
            action.winding_down = true;
            action.ending = ending;
            action.reason = reason;
            self.set(action, Status::Terminating);
        } else {
            self.terminate(action, ending, reason);
        }
    }

    /// Takes `taken` out of `action`'s scope (a running action's contribution there fades
    /// out over its `ease_out`); with `report`, publishes the narrowing as an event.
    fn narrow(&mut self, action: &mut Action, taken: Scope, report: bool) {
        if taken.is_empty() {
            return;
        }
        action.spec.scope = action.spec.scope.difference(&taken);
        action.spec.yields = action.spec.yields.difference(&taken);
        without(&mut action.returning, &taken);
        if action.status.is_running() {
            action.releasing.push((taken, self.clock.time));
        }
        if report {
            self.event(action, None, Some(taken));
        }
    }

    /// Takes `taken` out of `action`'s scope for `taker` (see [`Transitions::narrow`]); an
    /// action that takes back what it yields gets it back when `taker` lets go of it.
    fn lend(&mut self, action: &mut Action, taken: Scope, taker: ActionId) {
        if action.spec.takes_back && !taken.is_empty() {
            action.lent.push((taker, taken));
        }
        self.narrow(action, taken, true);
    }

    /// Gives `back` to `action` again: its scope and its yieldable part, eased in from
    /// where the taker left it.
    fn give_back(&mut self, action: &mut Action, back: Scope) {
        action.spec.scope = action.spec.scope.union(&back);
        action.spec.yields = action.spec.yields.union(&back);
        without(&mut action.releasing, &back);
        action.returning.push((back, self.clock.time));
    }

    /// Starts the ease-out toward `ending`, or ends at once without one.
    fn terminate(&mut self, action: &mut Action, ending: Status, reason: Option<String>) {
        if action.status == Status::Terminating {
            if ending == Status::Cancelled {
                action.ending = ending;
                action.reason = reason;
            }
            return;
        }
        action.ending = ending;
        action.reason = reason;
        if action.spec.ease_out > 0.0 {
            action.terminate_at = Some(self.clock.time);
            self.set(action, Status::Terminating);
        } else {
            self.set(action, ending);
        }
    }
}

impl ActorRuntime {
    pub(crate) fn push(&mut self, action: Action) {
        self.actions.push(action);
    }

    /// Runs one tick of this actor: admission, transitions, generators, blend, FK.
    pub(crate) fn tick(
        &mut self,
        actor: usize,
        skeleton: &Skeleton,
        world: &World,
        previous: &ActorState,
        next: &mut ActorState,
        clock: TickClock,
    ) {
        let mut stopwatch = PhaseClock::start(clock.profile);
        self.events.clear();
        self.ended.clear();
        self.hold_requests.clear();
        self.notes.clear();
        self.end_notes.clear();
        let mut tr = Transitions {
            actor,
            clock,
            events: &mut self.events,
        };
        admit(&mut self.actions, &mut tr, actor, skeleton, world, previous);
        advance(&mut self.actions, &mut tr);
        take_back(&mut self.actions, &mut tr);
        stopwatch.lap(&mut self.phases.scheduling);

        // Generators and blend.
        let n = skeleton.dof_count();
        self.accumulator.reset(n);
        self.scratch.resize(n, 0.0);
        for action in self.actions.iter_mut() {
            if !action.status.is_running() {
                continue;
            }
            let start = action.started_at.unwrap_or(clock.time);
            // What it may write: its scope and what it is still fading out of.
            let writable = action.writable();
            let ctx = GeneratorContext {
                time: clock.time,
                dt: clock.dt,
                tick: clock.tick,
                local_time: clock.time - start,
                actor,
                skeleton,
                posture: previous,
                world,
                scope: writable,
            };
            let mut out = DofWriter::narrowed(
                writable,
                action.original.difference(&writable),
                &mut self.scratch,
            );
            action.last_run = clock.tick;
            let step = action.generator.step(&ctx, &mut out);
            let (written, refused) = (out.written(), out.refused());
            let requests = out.take_requests();
            // Notes stand even when the step fails: a signal raised is a fact.
            self.notes.extend(out.take_notes());
            if refused > 0 {
                if self.refused_writes == 0 {
                    tracing::warn!(actor, action = %action.id, kind = %action.spec.kind,
                        "generator wrote DOFs outside its scope; the writes were ignored");
                }
                self.refused_writes += refused as u64;
            }
            if let Step::Failed(reason) = step {
                action.reason = Some(reason);
                tr.set(action, Status::Failed);
                continue;
            }
            self.hold_requests.extend(requests);
            let w = action.spec.base_weight()
                * ease_factor(
                    clock.time,
                    start,
                    action.spec.ease_in,
                    action.terminate_at,
                    action.spec.ease_out,
                );
            if w > 0.0 {
                let returning = action
                    .returning
                    .iter()
                    .fold(Scope::EMPTY, |s, (r, _)| s.union(r));
                let full = action.spec.scope.difference(&returning);
                for d in written.intersection(&full).iter() {
                    self.accumulator.add(d, self.scratch[d], w);
                }
                // What comes back eases in, what was given up fades out.
                let t = clock.time;
                let easing = (action.returning.iter())
                    .map(|&(part, since)| (part, action.return_fade(since, t)))
                    .chain(
                        (action.releasing.iter())
                            .map(|&(part, since)| (part, action.release_fade(since, t))),
                    );
                for (part, fade) in easing {
                    let fade = w * fade;
                    if fade > 0.0 {
                        for d in written.intersection(&part).iter() {
                            self.accumulator.add(d, self.scratch[d], fade);
                        }
                    }
                }
            }
            let time = clock.time;
            let faded: Vec<bool> = action
                .releasing
                .iter()
                .map(|&(_, since)| action.release_fade(since, time) <= 0.0)
                .collect();
            let mut faded = faded.into_iter();
            action.releasing.retain(|_| !faded.next().unwrap_or(false));
            let back = action.return_time();
            action.returning.retain(|&(_, since)| time - since < back);
            if step == Step::Finished {
                if action.winding_down {
                    // Wound down: it stands where it stopped, so it ends without easing.
                    let ending = action.ending;
                    tr.set(action, ending);
                } else {
                    tr.terminate(action, Status::Completed, None);
                }
            }
        }

        stopwatch.lap(&mut self.phases.generators);
        next.held.copy_from_slice(&previous.held);
        let limits = skeleton.limits();
        self.accumulator
            .resolve(&mut next.held, &mut next.q, |d, v| {
                let (min, max) = limits[d];
                v.clamp(min, max)
            });
        for d in 0..n {
            next.qd[d] = (next.q[d] - previous.q[d]) / clock.dt;
        }
        next.update_kinematics(skeleton);
        stopwatch.lap(&mut self.phases.blend_fk);

        // Retire ended actions, keeping their final record.
        let mut i = 0;
        while i < self.actions.len() {
            if self.actions[i].status.is_final() {
                let mut a = self.actions.remove(i);
                let mut notes = Notes::default();
                let ending = Ending {
                    status: a.status,
                    reason: a.reason.as_deref(),
                };
                a.generator.end(&ending, &mut notes);
                // An end is stamped the tick after the generator last ran (its partner sees
                // it the tick after that), except a failure in this tick's step, stamped
                // like the step's own notes (its partner learns it on the next tick); an
                // action that never ran ends now.
                let failed_in_step = a.status == Status::Failed && a.last_run == clock.tick;
                let stamp = if a.last_run > 0 && !failed_in_step {
                    a.last_run + 1
                } else {
                    clock.tick
                };
                self.end_notes
                    .extend(notes.take().into_iter().map(|n| (stamp, n)));
                self.ended.push(a.info(actor));
            } else {
                i += 1;
            }
        }
        stopwatch.lap(&mut self.phases.scheduling);
    }
}

fn admit(
    actions: &mut [Action],
    tr: &mut Transitions,
    actor: usize,
    skeleton: &Skeleton,
    world: &World,
    posture: &ActorState,
) {
    let time = tr.clock.time;
    for i in 0..actions.len() {
        if actions[i].status != Status::Pending {
            continue;
        }
        if actions[i].cancel_requested || actions[i].stop_requested {
            actions[i].reason = Some(if actions[i].cancel_requested {
                "cancelled".into()
            } else {
                "stopped before it began".into()
            });
            tr.set(&mut actions[i], Status::Cancelled);
            continue;
        }
        if actions[i].begin > time + 1e-9 {
            continue;
        }
        // An action being admitted first gives up the yieldable part of its own scope
        // that others hold: whatever running actions drive and, for a `default` one,
        // whatever earlier pending actions wait for (a grasp's optional lean and crouch
        // during a walk: the walk keeps its legs and its spine).
        let mode = actions[i].spec.mode;
        if !actions[i].spec.yields.is_empty() {
            let holds = |j: usize, other: &Action| {
                j != i
                    && (other.status.is_running()
                        || (other.status == Status::Pending && j < i && mode == Mode::Default))
            };
            let held = actions
                .iter()
                .enumerate()
                .filter(|&(j, other)| holds(j, other))
                .fold(Scope::EMPTY, |held, (_, other)| {
                    held.union(&other.spec.scope)
                });
            let own = actions[i].spec.yields.intersection(&held);
            if actions[i].spec.takes_back {
                // Lent to those that hold it, as counted above: not to a later pending
                // action, which may wait for this one to end.
                let lenders: Vec<_> = actions
                    .iter()
                    .enumerate()
                    .filter(|&(j, other)| holds(j, other))
                    .map(|(_, other)| (other.id, own.intersection(&other.spec.scope)))
                    .filter(|(_, part)| !part.is_empty())
                    .collect();
                actions[i].lent.extend(lenders);
            }
            tr.narrow(&mut actions[i], own, true);
        }
        let scope = actions[i].spec.scope;
        let id = actions[i].id;
        let admitted = match actions[i].spec.mode {
            Mode::Default => {
                // Waits for what it cannot take: an essential part of a running action,
                // or any part of an earlier pending one.
                let blocked = actions.iter().enumerate().any(|(j, other)| {
                    j != i
                        && ((other.status.is_running() && other.spec.essential().overlaps(&scope))
                            || (other.status == Status::Pending
                                && j < i
                                && other.spec.scope.overlaps(&scope)))
                });
                if !blocked {
                    for (j, other) in actions.iter_mut().enumerate() {
                        if j != i && other.status.is_running() {
                            let taken = other.spec.scope.intersection(&scope);
                            tr.lend(other, taken, id);
                        }
                    }
                }
                !blocked
            }
            Mode::Weighted => true,
            Mode::Exclusive | Mode::Clearing => {
                let clearing = actions[i].spec.mode == Mode::Clearing;
                for (j, other) in actions.iter_mut().enumerate() {
                    if j == i || other.status.is_final() {
                        continue;
                    }
                    let reason = Some(format!("pre-empted by action {id}"));
                    if other.status.is_running() {
                        let taken = other.spec.scope.intersection(&scope);
                        let loses_essential = other.spec.essential().overlaps(&scope);
                        if clearing || loses_essential {
                            pre_empt(tr, other, taken, reason);
                        } else {
                            tr.lend(other, taken, id);
                        }
                    } else if clearing && other.status == Status::Pending && j < i {
                        other.reason = reason;
                        tr.set(other, Status::Cancelled);
                    }
                }
                true
            }
        };
        if !admitted {
            continue;
        }
        let action = &mut actions[i];
        action.started_at = Some(time);
        let ctx = GeneratorContext {
            time,
            dt: tr.clock.dt,
            tick: tr.clock.tick,
            local_time: 0.0,
            actor,
            skeleton,
            posture,
            world,
            scope,
        };
        let first = if action.spec.ease_in > 0.0 {
            Status::Initiating
        } else {
            Status::Active
        };
        tr.set(action, first);
        action.last_run = tr.clock.tick;
        if let Err(e) = action.generator.start(&ctx) {
            action.reason = Some(e.reason);
            tr.set(action, Status::Failed);
        }
    }
}

fn advance(actions: &mut [Action], tr: &mut Transitions) {
    let time = tr.clock.time;
    for action in actions.iter_mut() {
        if !action.status.is_running() {
            continue;
        }
        let start = action.started_at.unwrap_or(time);
        if action.cancel_requested {
            // A cancel stands, whatever a stop before it found.
            action.stopped_undone = false;
        }
        if action.cancel_requested && action.ending != Status::Cancelled {
            tr.stop(action, Status::Cancelled, Some("cancelled".into()));
            if action.status.is_final() {
                continue;
            }
        }
        if action.stop_requested {
            action.stop_requested = false;
            let (ending, reason) = match action.generator.unfinished() {
                Some(why) => (Status::Cancelled, Some(why)),
                None => (Status::Completed, None),
            };
            action.stopped_undone = ending == Status::Cancelled;
            tr.stop(action, ending, reason);
            if action.status.is_final() {
                continue;
            }
        }
        if action.status == Status::Initiating && time - start >= action.spec.ease_in - 1e-9 {
            tr.set(action, Status::Active);
        }
        if let Some(duration) = action.spec.duration {
            if action.status != Status::Terminating
                && time - start >= duration - action.spec.ease_out - 1e-9
            {
                tr.terminate(action, Status::Completed, None);
                if action.status.is_final() {
                    continue;
                }
            }
        }
        if action.status == Status::Terminating && !action.winding_down {
            let t0 = action.terminate_at.unwrap_or(time);
            if time - t0 >= action.spec.ease_out - 1e-9 {
                // Its purpose done during the ease-out after all (a grasp that attached
                // as it eased out): a stop completes it.
                if action.stopped_undone && action.generator.unfinished().is_none() {
                    action.ending = Status::Completed;
                    action.reason = None;
                }
                let ending = action.ending;
                tr.set(action, ending);
            }
        }
    }
}

/// Gives each action that takes back what it yields the DOFs whose takers have let go of
/// them (ended, or easing out), except those another running action now drives, which it
/// waits for in turn.
fn take_back(actions: &mut [Action], tr: &mut Transitions) {
    for i in 0..actions.len() {
        if actions[i].lent.is_empty() || !actions[i].status.is_running() {
            continue;
        }
        let holds = |id: ActionId| actions.iter().any(|a| a.id == id && !a.lets_go());
        let (kept, freed): (Vec<_>, Vec<_>) = actions[i]
            .lent
            .iter()
            .partition(|&&(taker, _)| holds(taker));
        if freed.is_empty() {
            continue;
        }
        let still = kept.iter().fold(Scope::EMPTY, |s, (_, part)| s.union(part));
        let mut back = freed
            .iter()
            .fold(Scope::EMPTY, |s, (_, part)| s.union(part))
            .difference(&still);
        let mut lent = kept;
        // What another action took meanwhile stays lent to it.
        for other in actions.iter() {
            let drives = other.id != actions[i].id
                && other.status.is_running()
                && !other.lets_go()
                && other.spec.mode != Mode::Weighted;
            let part = back.intersection(&other.spec.scope);
            if drives && !part.is_empty() {
                lent.push((other.id, part));
                back = back.difference(&part);
            }
        }
        actions[i].lent = lent;
        if !back.is_empty() {
            tr.give_back(&mut actions[i], back);
        }
    }
}

/// Takes `scope` out of each set of `sets`, dropping those left empty.
fn without(sets: &mut Vec<(Scope, f64)>, scope: &Scope) {
    for (set, _) in sets.iter_mut() {
        *set = set.difference(scope);
    }
    sets.retain(|(set, _)| !set.is_empty());
}

/// `other` loses an essential part (or is cleared): it stops gracefully. If its generator
/// winds down by itself, it gives up `taken` at once and keeps the rest until it has
/// finished; otherwise the whole action eases out, as before.
fn pre_empt(tr: &mut Transitions, other: &mut Action, taken: Scope, reason: Option<String>) {
    other.stopped_undone = false;
    tr.stop(other, Status::Cancelled, reason);
    if other.winding_down {
        tr.narrow(other, taken, false);
    }
}
