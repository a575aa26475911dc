//! A session owns a [`Scene`] and runs each tick in four phases, with no Lua in it:
//!
//! 1. **input**: the messages the script published last tick become this tick's inbox
//!    ([`crate::Mailbox`]); every [`Input`] (device sources, network streams, replays)
//!    drains what arrived into the scene, in the order they were added;
//! 2. **script**: the session's [`Script`] (the Lua director, or none) borrows the scene
//!    to start, cancel and query actions;
//! 3. **step**: the scheduler advances every actor one tick ([`Scene::step`]);
//! 4. **publish**: every [`Observer`] sees the new scene and the tick's events, in the
//!    order they were added (recorders, the timeline, OSC out, frames, pacing).
//!
//! Every command builds a session and attaches what it needs, so a windowed run records
//! and traces like a headless one, and a Rust program runs a scene without Lua.
//! A failing input is reported and the tick goes on; a failing observer ends the run
//! (its output would be incomplete) but every observer is still finished, so nothing
//! already recorded is lost.

use crate::action::Event;
use crate::error::{Error, Result};
use crate::scene::Scene;
use std::any::Any;
use std::marker::PhantomData;
use std::time::{Duration, Instant};

/// A source of input drained at the start of every tick (a device, a stream, a replay).
pub trait Input: Send {
    /// A short name for messages (`glove of pat`, `spacemouse`).
    fn name(&self) -> String;
    /// Moves what arrived since the last tick into the scene (performer targets, object
    /// poses). An error is reported with the input's name; the tick goes on.
    fn poll(&mut self, scene: &mut Scene) -> Result<()>;
}

/// The script phase of a tick: the one part of a session that decides what actors do.
pub trait Script: Send {
    /// Runs the phase: may add actors and objects, start, cancel and query actions.
    fn run(&mut self, scene: &mut Scene);
    /// Sees the events of every scene step, also of steps run without a script phase
    /// (so a behavior waiting on an action never misses its end).
    fn stepped(&mut self, scene: &mut Scene, events: &[Event]) {
        let _ = (scene, events);
    }
    /// Whether nothing is left for the script to do (every behavior has ended).
    fn is_idle(&self) -> bool {
        true
    }
}

/// No script: actions are started from Rust between ticks.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoScript;

impl Script for NoScript {
    fn run(&mut self, _scene: &mut Scene) {}
}

/// Sees the scene after every tick.
pub trait Observer: Any + Send {
    /// A short name for messages (`--record out.trk`).
    fn name(&self) -> String;
    /// Sees the scene before the first tick of the run.
    fn start(&mut self, scene: &Scene) -> Result<()> {
        let _ = scene;
        Ok(())
    }
    /// Sees the scene after a tick, with that tick's events.
    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()>;
    /// The run is over: writes what was gathered and returns what to tell the user.
    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        let _ = scene;
        Ok(None)
    }
}

/// A typed reference to an observer added to a session, to read it back after a run.
#[derive(Debug)]
pub struct ObserverHandle<T> {
    index: usize,
    kind: PhantomData<fn() -> T>,
}

impl<T> Clone for ObserverHandle<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for ObserverHandle<T> {}

/// When a run stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunLimit {
    /// At most this many ticks.
    pub ticks: u64,
    /// Also stop once the script is idle and no action is left.
    pub until_idle: bool,
}

impl RunLimit {
    /// Whether a run that has done `ticks` ticks, in a session that is `idle` or not,
    /// stops here (a run always ticks once before it looks at idleness).
    pub fn reached(&self, ticks: u64, idle: bool) -> bool {
        ticks >= self.ticks || (self.until_idle && ticks > 0 && idle)
    }
}

/// Wall-clock time spent in each phase since the last [`Session::take_phase_times`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Draining inputs.
    pub input: Duration,
    /// The script phase.
    pub script: Duration,
    /// The scene step.
    pub step: Duration,
    /// The observers.
    pub publish: Duration,
    /// Ticks measured.
    pub ticks: u64,
}

/// A scene with its inputs, its script and its observers; [`Session::tick`] runs one tick.
pub struct Session<S: Script = NoScript> {
    scene: Scene,
    script: S,
    inputs: Vec<Box<dyn Input>>,
    input_failures: Vec<u64>,
    observers: Vec<Box<dyn Observer>>,
    started: bool,
    finished: bool,
    /// An observer added after the start that failed to start: reported by the next tick.
    late_start_error: Option<Error>,
    timing: bool,
    times: PhaseTimes,
}

impl Session<NoScript> {
    /// A session without a script: a Rust program starts the actions.
    pub fn new(scene: Scene) -> Self {
        Session::with_script(scene, NoScript)
    }
}

impl<S: Script> Session<S> {
    /// A session whose script phase is `script`.
    pub fn with_script(scene: Scene, script: S) -> Self {
        Session {
            scene,
            script,
            inputs: Vec::new(),
            input_failures: Vec::new(),
            observers: Vec::new(),
            started: false,
            finished: false,
            late_start_error: None,
            timing: false,
            times: PhaseTimes::default(),
        }
    }

    /// The scene as of the last tick.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene itself, between ticks (to add actors, start actions, configure it).
    /// Step it through [`Session::tick`] only: a step behind the session's back is seen
    /// by neither the script nor the observers.
    pub fn scene_mut(&mut self) -> &mut Scene {
        &mut self.scene
    }

    /// The script.
    pub fn script(&self) -> &S {
        &self.script
    }

    /// The script and the scene together, between ticks (a director loads a scene file
    /// into the scene).
    pub fn script_and_scene(&mut self) -> (&mut S, &mut Scene) {
        (&mut self.script, &mut self.scene)
    }

    /// Adds an input, drained after those added before it.
    pub fn add_input(&mut self, input: Box<dyn Input>) {
        self.inputs.push(input);
        self.input_failures.push(0);
    }

    /// Adds an input drained before all others: one that brings what other inputs read
    /// (a leader's stream, which a follower's replayed devices take from).
    pub fn add_input_first(&mut self, input: Box<dyn Input>) {
        self.inputs.insert(0, input);
        self.input_failures.insert(0, 0);
    }

    /// How often each input has failed, by name, in the order they were added.
    pub fn input_failures(&self) -> Vec<(String, u64)> {
        self.inputs
            .iter()
            .zip(&self.input_failures)
            .map(|(i, &n)| (i.name(), n))
            .collect()
    }

    /// Adds an observer, published after those added before it; the handle reads it
    /// back. One added after the run started is started at once (an error is returned by
    /// the next tick).
    pub fn observe<T: Observer>(&mut self, mut observer: T) -> ObserverHandle<T> {
        if self.started {
            if let Err(e) = observer.start(&self.scene) {
                let e = observer_error(&observer, e);
                self.late_start_error.get_or_insert(e);
            }
        }
        self.observers.push(Box::new(observer));
        ObserverHandle {
            index: self.observers.len() - 1,
            kind: PhantomData,
        }
    }

    /// The observer behind `handle`.
    pub fn observer<T: Observer>(&self, handle: ObserverHandle<T>) -> &T {
        let any: &dyn Any = self.observers[handle.index].as_ref();
        any.downcast_ref().expect("a handle names its own observer")
    }

    /// The observer behind `handle`, mutably.
    pub fn observer_mut<T: Observer>(&mut self, handle: ObserverHandle<T>) -> &mut T {
        let any: &mut dyn Any = self.observers[handle.index].as_mut();
        any.downcast_mut().expect("a handle names its own observer")
    }

    /// Switches per-phase timing on or off (off by default: it reads the clock 5 times
    /// per tick).
    pub fn set_phase_timing(&mut self, on: bool) {
        self.timing = on;
    }

    /// The phase times gathered since the last call, which resets them.
    pub fn take_phase_times(&mut self) -> PhaseTimes {
        std::mem::take(&mut self.times)
    }

    /// Shows every observer the scene before the first tick. [`Session::tick`] calls it
    /// when nobody did.
    pub fn start(&mut self) -> Result<()> {
        if self.started {
            return Ok(());
        }
        self.started = true;
        for o in &mut self.observers {
            o.start(&self.scene)
                .map_err(|e| observer_error(o.as_ref(), e))?;
        }
        Ok(())
    }

    /// Runs one tick: input, script, step, publish. Returns the tick's events; an error
    /// names the observer that failed (the tick itself has happened).
    pub fn tick(&mut self) -> Result<Vec<Event>> {
        self.start()?;
        if let Some(e) = self.late_start_error.take() {
            return Err(e);
        }
        let t0 = self.timing.then(Instant::now);
        // Last tick's messages are delivered now, before what inputs bring.
        self.scene.mailbox_mut().begin_tick();
        self.poll_inputs();
        let t1 = self.timing.then(Instant::now);
        self.script.run(&mut self.scene);
        let t2 = self.timing.then(Instant::now);
        let events = self.step();
        let t3 = self.timing.then(Instant::now);
        let published = self.publish(&events);
        if let (Some(t0), Some(t1), Some(t2), Some(t3)) = (t0, t1, t2, t3) {
            self.times.input += t1 - t0;
            self.times.script += t2 - t1;
            self.times.step += t3 - t2;
            self.times.publish += t3.elapsed();
            self.times.ticks += 1;
        }
        published.map(|()| events)
    }

    /// The step phase: the scene advances, and the script sees what happened.
    fn step(&mut self) -> Vec<Event> {
        let events = self.scene.step().to_vec();
        self.script.stepped(&mut self.scene, &events);
        events
    }

    /// Whether the script is idle and no action is pending or running.
    pub fn is_idle(&self) -> bool {
        self.script.is_idle() && !self.scene.has_unfinished_actions()
    }

    /// Ticks until `limit`; returns how many ran. Stops at the first observer error.
    /// Observers are started even when no tick runs (a recording of 0 ticks holds the
    /// starting postures).
    pub fn run(&mut self, limit: RunLimit) -> Result<u64> {
        self.run_while(limit, || true)
    }

    /// Ticks until `limit` or until `go_on`, asked before each tick, says no (a user's
    /// Ctrl-C): the run then stops between two ticks, and [`Session::finish`] writes
    /// everything as at its end. Returns how many ticks ran.
    pub fn run_while(&mut self, limit: RunLimit, mut go_on: impl FnMut() -> bool) -> Result<u64> {
        self.start()?;
        let mut ticks = 0;
        while !limit.reached(ticks, self.is_idle()) && go_on() {
            self.tick()?;
            ticks += 1;
        }
        Ok(ticks)
    }

    /// Ends the run: every observer writes what it gathered, even when another fails.
    /// Returns their messages for the user, or the first error. Observers that were
    /// never started are started first; a second call does nothing.
    pub fn finish(&mut self) -> Result<Vec<String>> {
        if self.finished {
            return Ok(Vec::new());
        }
        let started = self.start();
        self.finished = true;
        let mut lines = Vec::new();
        let mut first_error = None;
        for o in &mut self.observers {
            match o.finish(&self.scene) {
                Ok(Some(line)) => lines.push(line),
                Ok(None) => {}
                Err(e) => {
                    let e = observer_error(o.as_ref(), e);
                    tracing::error!("{e}");
                    first_error.get_or_insert(e);
                }
            }
        }
        match started.err().or(first_error) {
            Some(e) => Err(e),
            None => Ok(lines),
        }
    }

    fn poll_inputs(&mut self) {
        for (input, failures) in self.inputs.iter_mut().zip(&mut self.input_failures) {
            if let Err(e) = input.poll(&mut self.scene) {
                // Say so once, then at powers of two: a vanished device must not flood
                // the log at 100 Hz, nor stall the tick.
                *failures += 1;
                if failures.is_power_of_two() {
                    tracing::error!(failures = *failures, "input {}: {e}", input.name());
                }
            }
        }
    }

    fn publish(&mut self, events: &[Event]) -> Result<()> {
        for o in &mut self.observers {
            o.publish(&self.scene, events)
                .map_err(|e| observer_error(o.as_ref(), e))?;
        }
        Ok(())
    }
}

fn observer_error(o: &dyn Observer, e: Error) -> Error {
    match e {
        Error::Observer { .. } => e,
        other => Error::Observer {
            observer: o.name(),
            message: other.to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::action::{ActionSpec, DofWriter, Generator, GeneratorContext, Step};
    use crate::scene::{ActorDesc, SceneConfig};

    /// Drives one DOF towards 1 for half a second.
    struct Raise;
    impl Generator for Raise {
        fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
            for d in ctx.scope.iter() {
                out.set(d, ctx.local_time);
            }
            if ctx.local_time >= 0.5 {
                Step::Finished
            } else {
                Step::Running
            }
        }
    }

    /// Counts what it sees.
    #[derive(Default)]
    struct Counter {
        started: u32,
        ticks: u32,
        events: usize,
        fail_at: Option<u32>,
    }
    impl Observer for Counter {
        fn name(&self) -> String {
            "counter".into()
        }
        fn start(&mut self, _: &Scene) -> Result<()> {
            self.started += 1;
            Ok(())
        }
        fn publish(&mut self, _: &Scene, events: &[Event]) -> Result<()> {
            self.ticks += 1;
            self.events += events.len();
            if self.fail_at == Some(self.ticks) {
                return Err(Error::Invalid("disk full".into()));
            }
            Ok(())
        }
        fn finish(&mut self, _: &Scene) -> Result<Option<String>> {
            Ok(Some(format!("saw {} ticks", self.ticks)))
        }
    }

    /// An input that moves the first object up by 1 cm a tick, failing every third tick.
    struct Lift(u32);
    impl Input for Lift {
        fn name(&self) -> String {
            "lift".into()
        }
        fn poll(&mut self, scene: &mut Scene) -> Result<()> {
            self.0 += 1;
            if self.0.is_multiple_of(3) {
                return Err(Error::Invalid("unplugged".into()));
            }
            scene.objects_mut()[0].position.y += 0.01;
            Ok(())
        }
    }

    fn scene() -> Scene {
        let mut scene = Scene::new(SceneConfig::default()).unwrap();
        scene.add_actor(&ActorDesc::new("ann")).unwrap();
        let ball = Scene::object(
            "ball",
            troupe_body::Shape::Sphere { radius: 0.1 },
            glam::DVec3::new(0.0, 1.0, 1.0),
            0.5,
        );
        scene.add_object(ball).unwrap();
        scene
    }

    #[test]
    fn phases_run_in_order_and_observers_see_every_tick() {
        let mut session = Session::new(scene());
        let skeleton = session.scene().actors()[0].skeleton.clone();
        let scope = skeleton.scope("right_arm").unwrap();
        let spec = ActionSpec::new("raise", scope);
        session
            .scene_mut()
            .start_action(0, spec, Box::new(Raise))
            .unwrap();
        let counter = session.observe(Counter::default());
        session.add_input(Box::new(Lift(0)));
        let ran = session
            .run(RunLimit {
                ticks: 1000,
                until_idle: true,
            })
            .unwrap();
        assert!((50..60).contains(&ran), "ran {ran} ticks");
        let seen = session.observer(counter);
        assert_eq!(seen.started, 1);
        assert_eq!(seen.ticks as u64, ran);
        // At least its start and its completion.
        assert!(seen.events >= 2, "{} events", seen.events);
        // The input ran every tick; one in three failed and the tick went on.
        let lifted = session.scene().objects()[0].position.y - 1.0;
        let expected = (ran - ran / 3) as f64 * 0.01;
        assert!((lifted - expected).abs() < 1e-9, "lifted {lifted}");
        assert_eq!(session.input_failures(), vec![("lift".into(), ran / 3)]);
        assert_eq!(session.finish().unwrap(), vec![format!("saw {ran} ticks")]);
    }

    #[test]
    fn a_failing_observer_ends_the_run_and_the_others_still_finish() {
        let mut session = Session::new(scene());
        let first = session.observe(Counter {
            fail_at: Some(3),
            ..Counter::default()
        });
        let second = session.observe(Counter::default());
        let err = session
            .run(RunLimit {
                ticks: 10,
                until_idle: false,
            })
            .unwrap_err();
        assert_eq!(err.to_string(), "counter: disk full");
        assert_eq!(session.observer(first).ticks, 3);
        // The tick happened; the second observer was not shown it (publishing stopped).
        assert_eq!(session.scene().tick(), 3);
        assert_eq!(session.observer(second).ticks, 2);
        assert_eq!(
            session.finish().unwrap(),
            vec!["saw 3 ticks".to_string(), "saw 2 ticks".to_string()]
        );
    }

    #[test]
    fn observers_start_without_a_tick_and_finish_once() {
        let mut session = Session::new(scene());
        let early = session.observe(Counter::default());
        let ran = session
            .run(RunLimit {
                ticks: 0,
                until_idle: false,
            })
            .unwrap();
        assert_eq!(ran, 0);
        assert_eq!(
            session.observer(early).started,
            1,
            "a 0-tick run still starts"
        );
        // One added after the start is started at once.
        let late = session.observe(Counter::default());
        assert_eq!(session.observer(late).started, 1);
        session.tick().unwrap();
        assert_eq!(session.observer(early).started, 1);
        assert_eq!(session.finish().unwrap().len(), 2);
        assert!(session.finish().unwrap().is_empty(), "finished once");
    }

    #[test]
    fn a_run_limit_ticks_once_before_it_looks_at_idleness() {
        let limit = RunLimit {
            ticks: 10,
            until_idle: true,
        };
        assert!(!limit.reached(0, true));
        assert!(limit.reached(1, true));
        assert!(!limit.reached(9, false));
        assert!(limit.reached(10, false));
    }
}
