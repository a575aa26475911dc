//! ACTIONS (thesis 6.4.3): what an actor does, on which SCOPE, with which priority, and the
//! motion generator that produces it.
//!
//! See [`crate::blend`] for how the contributions of concurrent actions are combined, and
//! [`crate::scheduler`] for admission and status transitions.

use crate::blackboard::{Note, Notes, SignalId};
use crate::error::{Error, Result};
use crate::world::World;
use std::fmt;
use troupe_body::scope::Scope;
use troupe_body::skeleton::Skeleton;
use troupe_body::state::ActorState;

/// Identifies an action within a scene; ids increase in creation order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ActionId(pub u64);

impl fmt::Display for ActionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// Priority mode: how an action relates to others on overlapping DOFs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Starts only once every earlier action of the actor sharing any of its DOFs has stopped.
    Default,
    /// Runs alongside others on shared DOFs; contributions blend by weight × ease.
    Weighted,
    /// Starts at its planned time and stops (eases out) the others on overlapping DOFs.
    Exclusive,
    /// Like exclusive, but stops every action of the actor, on any scope.
    Clearing,
}

impl Mode {
    /// Parses `default`, `weighted`, `exclusive` or `clearing`.
    pub fn parse(name: &str) -> Result<Mode> {
        match name {
            "default" => Ok(Mode::Default),
            "weighted" => Ok(Mode::Weighted),
            "exclusive" => Ok(Mode::Exclusive),
            "clearing" => Ok(Mode::Clearing),
            other => Err(Error::Invalid(format!(
                "unknown priority mode `{other}` (expected default, weighted, exclusive or clearing)"
            ))),
        }
    }

    /// The mode's name as written in scripts.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Default => "default",
            Mode::Weighted => "weighted",
            Mode::Exclusive => "exclusive",
            Mode::Clearing => "clearing",
        }
    }
}

/// Where an action is in its life: `pending → initiating → active → terminating →
/// completed`, or `cancelled` / `failed`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Status {
    /// Created, waiting for its begin time or for overlapping actions to stop.
    Pending,
    /// Running and easing in.
    Initiating,
    /// Running at full weight.
    Active,
    /// Running and easing out.
    Terminating,
    /// Ended normally.
    Completed,
    /// Stopped by a cancel request or pre-empted by another action.
    Cancelled,
    /// Ended because its generator failed.
    Failed,
}

impl Status {
    /// Whether the action has ended.
    pub fn is_final(self) -> bool {
        matches!(self, Status::Completed | Status::Cancelled | Status::Failed)
    }

    /// Whether the action is running (its generator is stepped).
    pub fn is_running(self) -> bool {
        matches!(
            self,
            Status::Initiating | Status::Active | Status::Terminating
        )
    }

    /// The status name as shown to scripts.
    pub fn name(self) -> &'static str {
        match self {
            Status::Pending => "pending",
            Status::Initiating => "initiating",
            Status::Active => "active",
            Status::Terminating => "terminating",
            Status::Completed => "completed",
            Status::Cancelled => "cancelled",
            Status::Failed => "failed",
        }
    }
}

/// What is asked of an action: kind, scope, priority and timing.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionSpec {
    /// The kind of motion (`keyframe`, `reach`, …), for display and events.
    pub kind: String,
    /// The DOFs the action may drive.
    pub scope: Scope,
    /// Priority mode.
    pub mode: Mode,
    /// Weight in [0, 1]; only weighted actions scale by it (others count 1).
    pub weight: f64,
    /// Seconds from creation to the planned begin.
    pub delay: f64,
    /// Total running time in seconds, ease-in and ease-out included; `None` lets the
    /// generator decide when it has finished.
    pub duration: Option<f64>,
    /// Seconds to ease in from zero to full weight ("full initial").
    pub ease_in: f64,
    /// Seconds to ease out from full weight to zero ("full termination").
    pub ease_out: f64,
    /// The part of `scope` the action can lose and keep running (a walk's arm swing): an
    /// action that needs only these DOFs takes them and *narrows* this one instead of
    /// stopping it. The rest of the scope is essential (see [`crate::scheduler`]).
    pub yields: Scope,
    /// Whether the DOFs it yields come back to it when the action that took them ends
    /// (a walk's arm after a wave or a grasp swings or carries again); otherwise they
    /// leave its scope for good.
    pub takes_back: bool,
}

impl ActionSpec {
    /// A default-mode action of `kind` on `scope`, starting now, with no easing.
    pub fn new(kind: impl Into<String>, scope: Scope) -> Self {
        ActionSpec {
            kind: kind.into(),
            scope,
            mode: Mode::Default,
            weight: 1.0,
            delay: 0.0,
            duration: None,
            ease_in: 0.0,
            ease_out: 0.0,
            yields: Scope::EMPTY,
            takes_back: false,
        }
    }

    /// The part of the scope the action cannot lose without stopping.
    pub fn essential(&self) -> Scope {
        self.scope.difference(&self.yields)
    }

    /// Checks every field; the error names the offending one.
    pub fn validate(&self) -> Result<()> {
        if self.scope.is_empty() {
            return Err(Error::Invalid(format!(
                "{} action: scope is empty",
                self.kind
            )));
        }
        if !(0.0..=1.0).contains(&self.weight) {
            return Err(Error::invalid_value(
                "weight",
                self.weight,
                "a number in [0, 1]",
            ));
        }
        for (what, v) in [
            ("delay", self.delay),
            ("ease_in", self.ease_in),
            ("ease_out", self.ease_out),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid_value(
                    what,
                    v,
                    "a finite number of seconds ≥ 0",
                ));
            }
        }
        if let Some(d) = self.duration {
            if !(d.is_finite() && d > 0.0) {
                return Err(Error::invalid_value(
                    "duration",
                    d,
                    "a finite number of seconds > 0",
                ));
            }
            if self.ease_in + self.ease_out > d + 1e-12 {
                return Err(Error::invalid_value(
                    "ease_in + ease_out",
                    self.ease_in + self.ease_out,
                    format!("at most the duration ({d} s)"),
                ));
            }
        }
        Ok(())
    }

    /// The weight an action of this mode contributes at full ease.
    pub fn base_weight(&self) -> f64 {
        match self.mode {
            Mode::Weighted => self.weight,
            _ => 1.0,
        }
    }
}

/// What a generator reports after a step.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Still producing motion.
    Running,
    /// Done: the action ends (after its ease-out, if any).
    Finished,
    /// Cannot go on: the action ends `failed` with this reason.
    Failed(String),
}

/// Read-only view a generator gets each tick: its own posture and the whole scene as they
/// were at the end of the previous tick, and the clock.
pub struct GeneratorContext<'a> {
    /// Scene time of this tick, in seconds.
    pub time: f64,
    /// Tick period in seconds.
    pub dt: f64,
    /// Tick number.
    pub tick: u64,
    /// Seconds since the action started.
    pub local_time: f64,
    /// The actor's index in the scene.
    pub actor: usize,
    /// The actor's skeleton.
    pub skeleton: &'a Skeleton,
    /// The actor's posture at the end of the previous tick.
    pub posture: &'a ActorState,
    /// The whole scene at the end of the previous tick.
    pub world: &'a World<'a>,
    /// The action's own scope (narrowed when others took parts of it; the parts it is
    /// still fading out of count until they have faded).
    pub scope: Scope,
}

/// Where a generator writes desired DOF values; writes outside the scope are refused.
pub struct DofWriter<'a> {
    scope: Scope,
    /// DOFs the action has yielded to others: writes there are dropped without complaint.
    yielded: Scope,
    values: &'a mut [f64],
    written: Scope,
    refused: usize,
    requests: Vec<crate::holding::HoldRequest>,
    notes: Notes,
}

impl<'a> DofWriter<'a> {
    /// A writer over `values` (indexed by DOF) restricted to `scope`.
    pub fn new(scope: Scope, values: &'a mut [f64]) -> Self {
        DofWriter {
            scope,
            yielded: Scope::EMPTY,
            values,
            written: Scope::EMPTY,
            refused: 0,
            requests: Vec::new(),
            notes: Notes::default(),
        }
    }

    /// A writer that also drops, silently, writes to `yielded`: DOFs the action had and
    /// gave up to another action (its generator need not know it was narrowed).
    pub fn narrowed(scope: Scope, yielded: Scope, values: &'a mut [f64]) -> Self {
        DofWriter {
            yielded,
            ..DofWriter::new(scope, values)
        }
    }

    /// Sets the desired value of DOF `dof`. Returns false (and writes nothing) when the
    /// DOF is outside the action's scope or the value is not finite; a write to a DOF the
    /// action yielded is dropped without counting as refused.
    #[inline]
    pub fn set(&mut self, dof: usize, value: f64) -> bool {
        if self.scope.contains(dof) && dof < self.values.len() && value.is_finite() {
            self.values[dof] = value;
            self.written.insert(dof);
            true
        } else {
            if !self.yielded.contains(dof) {
                self.refused += 1;
            }
            false
        }
    }

    /// The scope the writer accepts.
    pub fn scope(&self) -> Scope {
        self.scope
    }

    /// The DOFs written so far.
    pub fn written(&self) -> Scope {
        self.written
    }

    /// How many writes were refused.
    pub fn refused(&self) -> usize {
        self.refused
    }

    /// Asks the scene to attach, release or place an object after this tick's kinematics
    /// (see [`crate::holding`]); ignored when the step fails.
    pub fn request(&mut self, request: crate::holding::HoldRequest) {
        self.requests.push(request);
    }

    /// Takes the requests made so far.
    pub fn take_requests(&mut self) -> Vec<crate::holding::HoldRequest> {
        std::mem::take(&mut self.requests)
    }

    /// Raises `signal` on the blackboard (every generator sees it from the next tick on;
    /// see [`crate::blackboard`]).
    pub fn raise(&mut self, signal: SignalId) {
        self.notes.raise(signal);
    }

    /// Posts `note` on the blackboard, applied after this tick.
    pub fn post(&mut self, note: Note) {
        self.notes.post(note);
    }

    /// Takes the notes posted so far.
    pub fn take_notes(&mut self) -> Vec<Note> {
        self.notes.take()
    }
}

/// Why a generator could not start (`the object is out of reach`, `` `bob` holds it ``):
/// the action fails with this as its reason, which scripts read as `action.error`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{reason}")]
pub struct StartError {
    /// The reason, for people.
    pub reason: String,
}

impl StartError {
    /// A start refused for `reason`.
    pub fn new(reason: impl Into<String>) -> Self {
        StartError {
            reason: reason.into(),
        }
    }
}

impl From<String> for StartError {
    fn from(reason: String) -> Self {
        StartError { reason }
    }
}

impl From<&str> for StartError {
    fn from(reason: &str) -> Self {
        StartError::new(reason)
    }
}

/// A motion generator: each tick it reads the context and writes desired values for DOFs
/// of its scope. It never touches the actor directly.
pub trait Generator: Send {
    /// Called once when the action is admitted; an error fails the action.
    fn start(&mut self, _ctx: &GeneratorContext) -> Result<(), StartError> {
        Ok(())
    }

    /// Produces this tick's desired values.
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step;

    /// Asked to finish gracefully (`:stop()`, a cancel, a pre-emption): a generator that
    /// can end its motion by itself (a walk decelerates and puts both feet down) starts
    /// doing so, returns true, and later reports [`Step::Finished`]; the action keeps its
    /// full weight until then. The default returns false: the action eases out instead.
    fn stop(&mut self) -> bool {
        false
    }

    /// Why ending now would leave the action's purpose undone (a grasp whose hand holds
    /// nothing yet, a give whose object has not changed hands): a `:stop()` then ends it
    /// `cancelled` with this reason instead of `completed`. `None` (the default): a stop
    /// completes it.
    fn unfinished(&self) -> Option<String> {
        None
    }

    /// Called once when the action ends, however it ends (completed, failed, cancelled,
    /// pre-empted, or never admitted), with how it ended: a partner waiting on this action
    /// learns it (and why) from the notes posted here, applied after the tick like a
    /// step's.
    fn end(&mut self, _ending: &Ending, _notes: &mut Notes) {}

    /// What a walking generator plans and chose on its last tick, for drawing it
    /// (`--debug nav`); read-only, it changes nothing. The default has none.
    fn navigation(&self) -> Option<crate::space::Navigation> {
        None
    }

    /// How many temporary goals the motion's path took round other actors' bodies and
    /// obstacles (a reach bending round someone, thesis 4.6.3); 0 by default.
    fn detours(&self) -> usize {
        0
    }
}

/// How an action ended, as its generator's [`Generator::end`] learns it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ending<'a> {
    /// The final status: completed, cancelled or failed.
    pub status: Status,
    /// Why it was cancelled or failed.
    pub reason: Option<&'a str>,
}

impl Ending<'_> {
    /// For an action that did not complete, its status and why (`cancelled: pre-empted
    /// by action #2`), as it tells an action that waits on it; `None` when it completed.
    pub fn failure(&self) -> Option<String> {
        (self.status != Status::Completed).then(|| {
            let why = self.reason.unwrap_or("no reason given");
            format!("{}: {why}", self.status.name())
        })
    }
}

/// A snapshot of one action for queries and listings.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionInfo {
    /// The action's id.
    pub id: ActionId,
    /// Index of the actor that runs it.
    pub actor: usize,
    /// The kind of motion.
    pub kind: String,
    /// Its scope (narrowed when other actions took parts of it).
    pub scope: Scope,
    /// The DOFs it gave up to other actions (see [`ActionSpec::yields`]).
    pub yielded: Scope,
    /// Its priority mode.
    pub mode: Mode,
    /// Its weight.
    pub weight: f64,
    /// Where it is in its life.
    pub status: Status,
    /// Why it was cancelled or failed.
    pub reason: Option<String>,
    /// When it started running.
    pub started_at: Option<f64>,
    /// When it ended.
    pub ended_at: Option<f64>,
    /// How many temporary goals its path took round other bodies and obstacles (see
    /// [`Generator::detours`]).
    pub detours: usize,
}

/// A status change, published after each tick.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// Tick at which it happened.
    pub tick: u64,
    /// Scene time at which it happened.
    pub time: f64,
    /// Actor index.
    pub actor: usize,
    /// The action.
    pub action: ActionId,
    /// The action's kind.
    pub kind: String,
    /// The status it moved to.
    pub status: Status,
    /// The reason, for cancellations and failures.
    pub reason: Option<String>,
    /// Set when the action was *narrowed* rather than changing status: the DOFs it
    /// yielded to another action (`status` is then its unchanged status).
    pub narrowed: Option<Scope>,
}
