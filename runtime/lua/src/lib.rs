//! The Lua bridge: a scene is a Lua file; each autonomous actor's behavior is a coroutine
//! that starts actions and waits for them.
//!
//! The [`Director`] owns the Lua state and is the script phase of a
//! [`troupe_scene::Session`]: the session owns the [`Scene`] and lends it to the director
//! for the phase (it is kept in the Lua state's app data meanwhile, so that API calls reach
//! it). In its phase the director runs the script hooks other crates installed, calls the
//! event handlers for the previous tick's events, then resumes, in creation order, every
//! behavior whose wait condition holds. Every resume runs under an instruction budget and
//! a memory allowance; a behavior that errors or exceeds them fails alone.

#![warn(missing_docs)]

pub mod api;
pub mod args;
mod dynamics;
pub mod error;
mod error_value;
mod handles;
pub mod kinds;
mod messages;
pub mod modules;
pub mod patterns;
pub mod reference;
mod sandbox;
pub mod settings;
mod space;
mod stage;

use crate::args::lua_err;
pub use crate::error::{Error, Result};
use crate::handles::{ActionRef, Pins};
pub use crate::sandbox::ScriptLimits;
use crate::sandbox::{clean_message, thread_location, Failure, Sandbox};
pub use crate::stage::{actor_skeletons, scene_dir};
use crate::stage::{add_behavior, BehaviorState, Stage, Wait};
use kinds::ActionKinds;
use mlua::{FromLuaMulti, Function, Lua, LuaOptions, MultiValue, StdLib, Value};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use troupe_scene::action::{ActionId, Event, Status};
use troupe_scene::scene::{Scene, SceneConfig};
use troupe_scene::session::{Script, Session};

/// How a behavior ended, for summaries.
#[derive(Clone, Debug, PartialEq)]
pub struct BehaviorReport {
    /// The actor's name (`test` for a test body).
    pub actor: String,
    /// `running`, `done`, `failed` or `stopped`.
    pub status: &'static str,
    /// The error with its location and traceback, when it failed.
    pub error: Option<String>,
    /// Whether a script waited for it (`handle:wait()`), taking charge of its outcome.
    pub awaited: bool,
}

/// Runs Lua scenes: owns the Lua state, and directs a session's scene in its script phase.
pub struct Director {
    lua: Lua,
    sandbox: Arc<Sandbox>,
    hooks: Vec<ScriptHook>,
}

/// A session directed by Lua behaviors.
pub type LuaSession = Session<Director>;

/// Lua work another crate installs at the start of every script phase, before the event
/// handlers and behaviors (e.g. calling the gesture handlers of a performer's glove, whose
/// samples the session's input phase drained). The scene is the session's, lent for the
/// phase. An error is logged and the phase goes on.
pub type ScriptHook = Box<dyn FnMut(&Lua) -> mlua::Result<()> + Send>;

/// Ended actions no handle refers to are forgotten this long after they ended.
const ENDED_RETENTION_SECONDS: f64 = 10.0;
/// How often (in ticks) forgotten actions are pruned.
const PRUNE_EVERY_TICKS: u64 = 100;

impl Director {
    /// A director for scenes of `config` (its seed seeds `math.random`), with the
    /// sandboxed standard library, the troupe API and the given action kinds.
    pub fn new(config: SceneConfig, kinds: ActionKinds, limits: ScriptLimits) -> Result<Director> {
        // Holds the stage's place while no scene is lent.
        let scene = Scene::new(config)?;
        let libs = StdLib::COROUTINE | StdLib::TABLE | StdLib::STRING | StdLib::UTF8 | StdLib::MATH;
        let lua =
            Lua::new_with(libs, LuaOptions::new()).map_err(|e| Error::Invalid(e.to_string()))?;
        let sandbox = Sandbox::install(&lua, limits).map_err(|e| Error::Invalid(e.to_string()))?;
        patterns::guard(&lua, &sandbox).map_err(|e| Error::Invalid(e.to_string()))?;
        let director = Director {
            lua,
            sandbox,
            hooks: Vec::new(),
        };
        director
            .setup(scene, kinds)
            .map_err(|e| Error::Invalid(format!("setting up Lua: {e}")))?;
        Ok(director)
    }

    fn setup(&self, scene: Scene, kinds: ActionKinds) -> mlua::Result<()> {
        let lua = &self.lua;
        let functions = kinds.functions().to_vec();
        let seed = scene.config().seed;
        lua.set_app_data(Arc::new(Pins::default()));
        // The kinds live apart from the stage: a method lookup needs nothing else.
        lua.set_app_data(kinds);
        lua.set_app_data(Stage {
            scene,
            lent: false,
            behaviors: Vec::new(),
            handlers: Vec::new(),
            next_handler: 0,
            pending_events: Vec::new(),
            ended_last_step: HashSet::new(),
            base_dir: PathBuf::from("."),
            current_actor: None,
            sequences: HashMap::new(),
            recordings: HashMap::new(),
            tests: Vec::new(),
            handler_failures: Vec::new(),
            subscriptions: Vec::new(),
            loaded_files: Vec::new(),
        });
        let globals = lua.globals();
        for name in ["dofile", "loadfile", "load", "require", "collectgarbage"] {
            globals.raw_set(name, Value::Nil)?;
        }
        // Deterministic random numbers: seeded from the scene seed.
        lua.load(format!("math.randomseed({seed})")).exec()?;
        globals.set(
            "print",
            lua.create_function(|lua, args: MultiValue| {
                let text = args
                    .iter()
                    .map(|v| {
                        v.to_string()
                            .unwrap_or_else(|_| format!("<{}>", v.type_name()))
                    })
                    .collect::<Vec<_>>()
                    .join("\t");
                tracing::info!(target: "lua", actor = %speaker(lua), "{text}");
                Ok(())
            })?,
        )?;
        // Lua's own `warn` wrote to stderr once turned on with "@on", which no scene saw:
        // here a warning goes to the log as print's lines do, at the warning level.
        globals.set(
            "warn",
            lua.create_function(|lua, args: MultiValue| {
                if args.is_empty() {
                    return Err(lua_err("warn: a message is required (strings or numbers)"));
                }
                let mut text = String::new();
                for (i, v) in args.iter().enumerate() {
                    match v {
                        Value::String(s) => text.push_str(&s.to_string_lossy()),
                        Value::Integer(_) | Value::Number(_) => text.push_str(&v.to_string()?),
                        other => {
                            return Err(lua_err(format!(
                                "warn: argument {} must be a string, got {}",
                                i + 1,
                                other.type_name()
                            )))
                        }
                    }
                }
                // Lua's control messages ("@on", "@off") have nothing to switch here.
                if args.len() == 1 && text.starts_with('@') {
                    return Ok(());
                }
                tracing::warn!(target: "lua", actor = %speaker(lua), "{text}");
                Ok(())
            })?,
        )?;
        globals.set("require", lua.create_function(modules::require)?)?;
        globals.set(
            "test",
            lua.create_function(
                |lua, (name, f, opts): (String, Function, Option<mlua::Table>)| {
                    let timeout = test_timeout(&name, opts)?;
                    let mut st = lua
                        .app_data_mut::<Stage>()
                        .ok_or_else(|| lua_err("no scene"))?;
                    st.tests.push((name, f, timeout));
                    Ok(())
                },
            )?,
        )?;
        api::install(lua)?;
        let troupe: mlua::Table = globals.get("troupe")?;
        for (name, make) in functions {
            troupe.set(name, make(lua)?)?;
        }
        // For the prelude's wait_all and wait_any, which check their arguments.
        globals.set(
            "__troupe_is_action",
            lua.create_function(|_, v: Value| {
                Ok(matches!(v, Value::UserData(u) if u.is::<handles::ActionRef>()))
            })?,
        )?;
        globals.set(
            "__troupe_value_name",
            lua.create_function(|_, v: Value| Ok(args::value_name(&v)))?,
        )?;
        error_value::install(lua)?;
        lua.load(include_str!("prelude.lua"))
            .set_name("=prelude")
            .exec()?;
        globals.raw_set("__troupe_is_action", Value::Nil)?;
        globals.raw_set("__troupe_value_name", Value::Nil)?;
        let wait: Function = globals.get("__troupe_action_wait")?;
        lua.set_named_registry_value("troupe.action_wait", wait)?;
        globals.raw_set("__troupe_action_wait", Value::Nil)?;
        let wait: Function = globals.get("__troupe_behavior_wait")?;
        lua.set_named_registry_value("troupe.behavior_wait", wait)?;
        globals.raw_set("__troupe_behavior_wait", Value::Nil)?;
        globals.raw_set("__troupe_limit", Value::Nil)?;
        let own: Function = globals.get("__troupe_own_thread")?;
        lua.set_named_registry_value("troupe.own_thread", own)?;
        globals.raw_set("__troupe_own_thread", Value::Nil)?;
        lua.set_named_registry_value("troupe.modules", lua.create_table()?)?;

        Ok(())
    }

    /// A session of an empty scene of `config`, directed by a new director.
    pub fn session(
        config: SceneConfig,
        kinds: ActionKinds,
        limits: ScriptLimits,
    ) -> Result<LuaSession> {
        let director = Director::new(config, kinds, limits)?;
        Ok(Session::with_script(Scene::new(config)?, director))
    }

    /// Lends `scene` to the Lua callbacks while `f` runs. The scene goes back to its
    /// owner however `f` ends, a panic included.
    fn lend<R>(&mut self, scene: &mut Scene, f: impl FnOnce(&mut Director) -> R) -> R {
        /// Gives the scene back when dropped.
        struct Loan<'a> {
            lua: Lua,
            scene: &'a mut Scene,
        }
        impl Drop for Loan<'_> {
            fn drop(&mut self) {
                if let Some(mut stage) = self.lua.app_data_mut::<Stage>() {
                    std::mem::swap(&mut stage.scene, self.scene);
                    stage.lent = false;
                }
            }
        }
        {
            let mut stage = self.stage_mut();
            std::mem::swap(&mut stage.scene, scene);
            stage.lent = true;
        }
        let _loan = Loan {
            lua: self.lua.clone(),
            scene,
        };
        f(self)
    }

    /// Runs a scene file on `scene`: it creates actors and objects and registers
    /// behaviors.
    pub fn load_file(&mut self, scene: &mut Scene, path: &Path) -> Result<()> {
        let code = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let dir = if dir.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            dir
        };
        {
            let mut st = self.stage_mut();
            st.base_dir = dir;
            st.loaded_files.push(path.to_path_buf());
        }
        self.load_str(scene, &code, &path.display().to_string())
    }

    /// Runs scene code given as text on `scene`; `name` appears in error locations.
    pub fn load_str(&mut self, scene: &mut Scene, code: &str, name: &str) -> Result<()> {
        self.lend(scene, |d| {
            let chunk = d.lua.load(code).set_name(format!("@{name}"));
            d.guarded(|| chunk.exec())
                .map_err(|e| Error::Script(e.message()))
        })
    }

    /// Evaluates a Lua expression or chunk against `scene` between ticks (for tests, tools
    /// and embedding programs that ask the script what it knows), under the same limits
    /// as a resume.
    pub fn eval<R: FromLuaMulti>(&mut self, scene: &mut Scene, code: &str) -> Result<R> {
        self.lend(scene, |d| {
            let chunk = d.lua.load(code).set_name("=eval");
            d.guarded(|| chunk.eval::<R>())
                .map_err(|e| Error::Script(e.message()))
        })
    }

    /// Runs `f` under the sandbox's limits (see [`Sandbox::guarded`]).
    fn guarded<R>(&self, f: impl FnOnce() -> mlua::Result<R>) -> Result<R, Failure> {
        self.sandbox.guarded(&self.lua, f)
    }

    /// The scene lent for the phase or the load under way.
    fn scene(&self) -> SceneRef<'_> {
        SceneRef(
            self.lua
                .app_data_ref::<Stage>()
                .expect("the stage is installed at creation"),
        )
    }

    fn stage_mut(&self) -> mlua::AppDataRefMut<'_, Stage> {
        self.lua
            .app_data_mut::<Stage>()
            .expect("the stage is installed at creation")
    }

    /// The Lua state (for tests and embedding).
    pub fn lua(&self) -> &Lua {
        &self.lua
    }

    /// Every file the scene has read so far: the scene file, the modules it required from
    /// its folder, the motion files it loaded (what a hot reload watches).
    pub fn loaded_files(&self) -> Vec<PathBuf> {
        self.stage_mut().loaded_files.clone()
    }

    /// The tests registered by `test(name, fn)` calls so far.
    pub fn test_names(&self) -> Vec<String> {
        self.stage_mut()
            .tests
            .iter()
            .map(|(n, _, _)| n.clone())
            .collect()
    }

    /// Starts registered test number `index` as a behavior without an actor; returns the
    /// test's own timeout (simulated seconds), if it gave one.
    pub fn start_test(&mut self, index: usize) -> Result<Option<f64>> {
        let (f, timeout) = self
            .stage_mut()
            .tests
            .get(index)
            .map(|(_, f, timeout)| (f.clone(), *timeout))
            .ok_or_else(|| Error::Invalid(format!("no test #{index}")))?;
        add_behavior(&self.lua, None, f)
            .map(|_| timeout)
            .map_err(|e| Error::Invalid(e.to_string()))
    }

    /// Reports of every behavior, in creation order; `scene` is the one directed (it names
    /// the actors).
    pub fn behaviors(&self, scene: &Scene) -> Vec<BehaviorReport> {
        let st = self.stage_mut();
        st.behaviors
            .iter()
            .map(|b| BehaviorReport {
                actor: b
                    .actor
                    .map(|a| scene.actors()[a].name.clone())
                    .unwrap_or_else(|| "test".into()),
                status: b.state.name(),
                error: b.state.error().map(String::from),
                awaited: b.awaited,
            })
            .chain(st.handler_failures.iter().map(|(a, e)| BehaviorReport {
                actor: scene.actors()[*a].name.clone(),
                status: "failed",
                error: Some(format!("in an event handler: {e}")),
                awaited: false,
            }))
            .collect()
    }

    /// Adds Lua work run at the start of every script phase (see [`ScriptHook`]), in the
    /// order added.
    pub fn add_script_hook(&mut self, hook: ScriptHook) {
        self.hooks.push(hook);
    }

    fn run_hooks(&mut self) {
        if self.hooks.is_empty() {
            return;
        }
        let mut hooks = std::mem::take(&mut self.hooks);
        for hook in hooks.iter_mut() {
            if let Err(e) = self.guarded(|| hook(&self.lua)) {
                tracing::error!("script hook failed: {}", e.message());
            }
        }
        self.hooks = hooks;
    }

    /// Notes a step's events: handlers see them in the next phase, and behaviors waiting on
    /// an action that ended are looked at then. Every so often, forgets the records of
    /// actions that ended long ago and that no Lua handle refers to.
    fn note_step(&mut self, scene: &mut Scene, events: &[Event]) {
        if scene.tick().is_multiple_of(PRUNE_EVERY_TICKS) {
            let pins = self.lua.app_data_ref::<Arc<api::Pins>>().map(|p| p.clone());
            let before = scene.time() - ENDED_RETENTION_SECONDS;
            scene.forget_ended_actions(before, |id| pins.as_ref().is_some_and(|p| p.is_pinned(id)));
        }
        let mut st = self.stage_mut();
        st.pending_events.extend(events.iter().cloned());
        for e in events {
            if e.status.is_final() {
                st.ended_last_step.insert(e.action);
            }
        }
    }

    /// Hands this tick's messages to the subscribers whose key expression matches, in
    /// the mailbox's order, each subscriber in the order it subscribed.
    fn run_messages(&mut self) {
        let (inbox, subscriptions) = {
            let mut st = self.stage_mut();
            let inbox = st.scene.mailbox_mut().take_inbox();
            if inbox.is_empty() || st.subscriptions.is_empty() {
                return;
            }
            (inbox, st.subscriptions.clone())
        };
        for message in inbox {
            for (expr, f) in &subscriptions {
                if !troupe_scene::mailbox::key_matches(expr, &message.key) {
                    continue;
                }
                let result = self.guarded(|| {
                    let value = messages::to_lua(&self.lua, &message.value)?;
                    f.call::<()>((value, message.key.as_str()))
                });
                if let Err(e) = result {
                    let msg = e.message();
                    tracing::error!("subscriber of {expr} failed on {}: {msg}", message.key);
                }
            }
        }
    }

    fn run_handlers(&mut self) {
        let (events, handlers) = {
            let mut st = self.stage_mut();
            if st.pending_events.is_empty() || st.handlers.is_empty() {
                st.pending_events.clear();
                return;
            }
            (std::mem::take(&mut st.pending_events), st.handlers.clone())
        };
        for event in events {
            let name = match event.status {
                _ if event.narrowed.is_some() => "action_narrowed",
                Status::Completed => "action_completed",
                Status::Failed => "action_failed",
                Status::Cancelled => "action_cancelled",
                _ => "action_started",
            };
            if name == "action_started" && !self.is_first_start(&event) {
                continue;
            }
            for handler in handlers.iter() {
                if handler.actor != event.actor || handler.event != name {
                    continue;
                }
                // A handler an earlier one took off (`:off()`) is not called.
                if !self.stage_mut().handlers.iter().any(|h| h.id == handler.id) {
                    continue;
                }
                let actor = handler.actor;
                self.stage_mut().current_actor = Some(actor);
                let result = self.guarded(|| {
                    handler
                        .function
                        .call::<()>(ActionRef::new(&self.lua, event.action)?)
                });
                if let Err(e) = result {
                    let msg = e.message();
                    tracing::error!(actor = %self.scene().actors()[actor].name, "event handler failed: {msg}");
                    self.stage_mut().handler_failures.push((actor, msg));
                }
            }
        }
        self.stage_mut().current_actor = None;
    }

    /// `action_started` fires once: on `initiating`, or on `active` for an action without
    /// ease-in (whose `active` event comes at its start time).
    fn is_first_start(&self, event: &Event) -> bool {
        match event.status {
            Status::Initiating => true,
            Status::Active => self
                .scene()
                .action(event.action)
                .is_some_and(|a| a.started_at == Some(event.time)),
            _ => false,
        }
    }

    fn run_behaviors(&mut self) {
        let count = self.stage_mut().behaviors.len();
        for i in 0..count {
            let Some(args) = self.due(i) else { continue };
            let (thread, actor) = {
                let mut st = self.stage_mut();
                st.behaviors[i].started = true;
                (st.behaviors[i].thread.clone(), st.behaviors[i].actor)
            };
            let Some(thread) = thread else { continue };
            self.stage_mut().current_actor = actor;
            let args = match (args, actor) {
                // First resume: pass the actor as `self`.
                (Resume::Start, Some(a)) => MultiValue::from_vec(vec![Value::UserData(match self
                    .lua
                    .create_userdata(api::ActorRef(a))
                {
                    Ok(u) => u,
                    Err(e) => {
                        self.fail(i, e.to_string());
                        continue;
                    }
                })]),
                (Resume::Start, None) => MultiValue::new(),
                (Resume::With(values), _) => values,
            };
            let result = self.guarded(|| thread.resume::<MultiValue>(args));
            let state = match result {
                Err(e) => BehaviorState::Failed(e.located(thread_location(&thread))),
                Ok(_) if thread.status() != mlua::prelude::LuaThreadStatus::Resumable => {
                    BehaviorState::Done
                }
                Ok(yielded) => match self.parse_wait(yielded) {
                    Ok(w) => BehaviorState::Waiting(w),
                    Err(e) => BehaviorState::Failed(clean_message(&e)),
                },
            };
            if let BehaviorState::Failed(msg) = &state {
                let who = actor
                    .map(|a| self.scene().actors()[a].name.clone())
                    .unwrap_or_else(|| "test".into());
                tracing::error!(actor = %who, "behavior failed: {msg}");
            }
            let mut st = self.stage_mut();
            // A behavior that stopped itself (`:stop()` on its own handle) ends at the
            // wait that follows.
            if !matches!(st.behaviors[i].state, BehaviorState::Stopped) {
                st.behaviors[i].state = state;
            }
            if !matches!(st.behaviors[i].state, BehaviorState::Waiting(_)) {
                st.behaviors[i].thread = None;
            }
            st.behaviors[i].checked = false;
        }
        let mut st = self.stage_mut();
        st.current_actor = None;
        // Every waiting behavior has seen these ends now; steps run before the next
        // script phase add theirs.
        st.ended_last_step.clear();
    }

    fn fail(&mut self, i: usize, msg: String) {
        self.stage_mut().behaviors[i].state = BehaviorState::Failed(msg);
    }

    /// Whether behavior `i` should be resumed now, and with what.
    fn due(&mut self, i: usize) -> Option<Resume> {
        /// What the scene says about a wait, decided under one borrow of the stage (this
        /// runs for every waiting behavior on every tick).
        enum Ready {
            Start,
            Empty,
            Ended(Status),
            First(ActionId),
            Ask(Function, Option<f64>, f64),
            Behavior(&'static str, Option<String>),
        }
        let ready = {
            let mut st = self.stage_mut();
            let st = &mut *st;
            let awaited_behavior = match st.behaviors[i].state {
                BehaviorState::Waiting(Wait::Behavior(j)) if j == i => {
                    st.behaviors[i].state = BehaviorState::Failed(
                        "wait: a behavior cannot wait for itself (it would never resume)".into(),
                    );
                    return None;
                }
                BehaviorState::Waiting(Wait::Behavior(j)) => {
                    let other = &st.behaviors[j].state;
                    if matches!(other, BehaviorState::Waiting(_)) {
                        return None;
                    }
                    Some(Ready::Behavior(
                        other.name(),
                        other.error().map(String::from),
                    ))
                }
                _ => None,
            };
            let behavior = &mut st.behaviors[i];
            let BehaviorState::Waiting(wait) = &behavior.state else {
                return None;
            };
            let awaited: &[ActionId] = match wait {
                Wait::Action(id) => std::slice::from_ref(id),
                Wait::All(ids) | Wait::Any(ids) => ids,
                _ => &[],
            };
            if !awaited.is_empty() {
                if behavior.checked && !awaited.iter().any(|id| st.ended_last_step.contains(id)) {
                    return None;
                }
                behavior.checked = true;
            }
            let scene = &st.scene;
            let ended = |id: ActionId| scene.action_status(id).filter(|s| s.is_final());
            match wait {
                Wait::NextTick if !behavior.started => Ready::Start,
                Wait::NextTick => Ready::Empty,
                Wait::Time(until) => {
                    if scene.time() < until - 1e-9 {
                        return None;
                    }
                    Ready::Empty
                }
                Wait::Action(id) => Ready::Ended(ended(*id)?),
                Wait::All(ids) => {
                    if !ids.iter().all(|id| ended(*id).is_some()) {
                        return None;
                    }
                    Ready::Empty
                }
                Wait::Any(ids) => {
                    Ready::First(ids.iter().copied().find(|id| ended(*id).is_some())?)
                }
                Wait::Until(pred, deadline) => Ready::Ask(pred.clone(), *deadline, scene.time()),
                Wait::Behavior(_) => awaited_behavior?,
            }
        };
        match ready {
            Ready::Start => Some(Resume::Start),
            Ready::Empty => Some(Resume::With(MultiValue::new())),
            Ready::Ended(status) => {
                let s = self.lua.create_string(status.name()).ok()?;
                Some(Resume::With(MultiValue::from_vec(vec![Value::String(s)])))
            }
            Ready::Behavior(status, error) => {
                let status = Value::String(self.lua.create_string(status).ok()?);
                let error = match error {
                    Some(e) => Value::String(self.lua.create_string(e).ok()?),
                    None => Value::Nil,
                };
                Some(Resume::With(MultiValue::from_vec(vec![status, error])))
            }
            Ready::First(id) => {
                let u = self
                    .lua
                    .create_userdata(ActionRef::new(&self.lua, id).ok()?)
                    .ok()?;
                Some(Resume::With(MultiValue::from_vec(vec![Value::UserData(u)])))
            }
            Ready::Ask(pred, deadline, time) => {
                let actor = self.stage_mut().behaviors[i].actor;
                self.stage_mut().current_actor = actor;
                match self.guarded(|| pred.call::<Value>(())) {
                    Ok(v) if !matches!(v, Value::Nil | Value::Boolean(false)) => Some(
                        Resume::With(MultiValue::from_vec(vec![Value::Boolean(true)])),
                    ),
                    Ok(_) if deadline.is_some_and(|d| time >= d - 1e-9) => Some(Resume::With(
                        MultiValue::from_vec(vec![Value::Boolean(false)]),
                    )),
                    Ok(_) => None,
                    Err(e) => {
                        self.fail(i, format!("in a wait_until condition: {}", e.message()));
                        None
                    }
                }
            }
        }
    }

    /// Reads what a behavior yielded into its next wait.
    fn parse_wait(&self, yielded: MultiValue) -> mlua::Result<Wait> {
        let time = self.scene().time();
        let mut values = yielded.into_iter();
        let kind = match values.next() {
            Some(Value::String(s)) => s.to_str()?.to_string(),
            // A bare coroutine.yield() waits one tick.
            _ => return Ok(Wait::NextTick),
        };
        let ids = |v: Option<Value>| -> mlua::Result<Vec<ActionId>> {
            let Some(Value::Table(t)) = v else {
                return Err(lua_err("expected a list of actions"));
            };
            t.sequence_values::<mlua::UserDataRef<ActionRef>>()
                .map(|a| {
                    a.map(|a| a.0)
                        .map_err(|_| lua_err("wait_all/wait_any: every argument must be an action"))
                })
                .collect()
        };
        Ok(match kind.as_str() {
            "time" => match values.next() {
                Some(Value::Number(s)) => Wait::Time(time + s),
                Some(Value::Integer(s)) => Wait::Time(time + s as f64),
                _ => Wait::NextTick,
            },
            "action" => match values.next() {
                Some(Value::UserData(u)) => Wait::Action(u.borrow::<ActionRef>()?.0),
                _ => return Err(lua_err("wait: not an action")),
            },
            "behavior" => match values.next() {
                Some(Value::UserData(u)) => {
                    let j = u.borrow::<api::BehaviorRef>()?.0;
                    self.stage_mut().behaviors[j].awaited = true;
                    Wait::Behavior(j)
                }
                _ => return Err(lua_err("wait: not a behavior")),
            },
            "all" => Wait::All(ids(values.next())?),
            "any" => Wait::Any(ids(values.next())?),
            "until" => {
                let f = match values.next() {
                    Some(Value::Function(f)) => f,
                    _ => return Err(lua_err("wait_until: not a function")),
                };
                let deadline = match values.next() {
                    Some(Value::Number(t)) => Some(time + t),
                    Some(Value::Integer(t)) => Some(time + t as f64),
                    _ => None,
                };
                Wait::Until(f, deadline)
            }
            _ => Wait::NextTick,
        })
    }
}

/// A borrow of the scene lent to the director.
struct SceneRef<'a>(mlua::AppDataRef<'a, Stage>);

impl std::ops::Deref for SceneRef<'_> {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.0.scene
    }
}

enum Resume {
    Start,
    With(MultiValue),
}

impl Script for Director {
    /// The script phase: hooks, event handlers for the previous tick's events, then every
    /// behavior whose wait condition holds, in creation order.
    fn run(&mut self, scene: &mut Scene) {
        let _span = tracing::trace_span!("scripts").entered();
        self.lend(scene, |d| {
            d.run_hooks();
            d.run_messages();
            d.run_handlers();
            d.run_behaviors();
        });
    }

    fn stepped(&mut self, scene: &mut Scene, events: &[Event]) {
        self.note_step(scene, events);
    }

    fn is_idle(&self) -> bool {
        self.stage_mut()
            .behaviors
            .iter()
            .all(|b| !matches!(b.state, BehaviorState::Waiting(_)))
    }
}

/// Scene files and reports on a [`LuaSession`], without taking its director and scene
/// apart by hand.
pub trait LuaSessionExt {
    /// Runs a scene file on the session's scene (see [`Director::load_file`]).
    fn load_file(&mut self, path: &Path) -> Result<()>;
    /// Runs scene code given as text (see [`Director::load_str`]).
    fn load_str(&mut self, code: &str, name: &str) -> Result<()>;
    /// Evaluates Lua code against the session's scene (see [`Director::eval`]).
    fn eval<R: FromLuaMulti>(&mut self, code: &str) -> Result<R>;
    /// Reports of every behavior, in creation order.
    fn behaviors(&self) -> Vec<BehaviorReport>;
    /// The Lua state (for tests and embedding).
    fn lua(&self) -> &Lua;
}

impl LuaSessionExt for LuaSession {
    fn load_file(&mut self, path: &Path) -> Result<()> {
        let (director, scene) = self.script_and_scene();
        director.load_file(scene, path)
    }

    fn load_str(&mut self, code: &str, name: &str) -> Result<()> {
        let (director, scene) = self.script_and_scene();
        director.load_str(scene, code, name)
    }

    fn eval<R: FromLuaMulti>(&mut self, code: &str) -> Result<R> {
        let (director, scene) = self.script_and_scene();
        director.eval(scene, code)
    }

    fn behaviors(&self) -> Vec<BehaviorReport> {
        self.script().behaviors(self.scene())
    }

    fn lua(&self) -> &Lua {
        self.script().lua()
    }
}

/// Who a line of `print` or `warn` comes from: the actor whose behavior or handler runs,
/// else the scene.
fn speaker(lua: &Lua) -> String {
    lua.app_data_ref::<Stage>()
        .and_then(|st| st.current_actor.map(|a| st.scene.actors()[a].name.clone()))
        .unwrap_or_else(|| "scene".into())
}

/// The `timeout` of `test(name, fn, { timeout = seconds })`: a positive number of
/// simulated seconds, or none.
fn test_timeout(name: &str, opts: Option<mlua::Table>) -> mlua::Result<Option<f64>> {
    let Some(opts) = opts else {
        return Ok(None);
    };
    let what = format!("test {name:?}");
    args::check_keys(&opts, &what, &["timeout"])?;
    match args::opt_number(&opts, &what, "timeout")? {
        Some(t) if t <= 0.0 => Err(args::err(
            &what,
            format!("timeout must be a positive number of simulated seconds, got {t}"),
        )),
        t => Ok(t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session() -> LuaSession {
        Director::session(
            SceneConfig::default(),
            ActionKinds::default(),
            ScriptLimits::default(),
        )
        .unwrap()
    }

    #[test]
    fn the_scene_goes_back_to_the_session_when_a_script_fails_or_panics() {
        let mut s = session();
        let err = s
            .load_str("troupe.actor{ name = 'ann' }\nerror('boom')", "t")
            .unwrap_err();
        assert!(err.to_string().contains("boom"), "{err}");
        assert_eq!(
            s.scene().actors().len(),
            1,
            "ann stays in the session's scene"
        );
        // A panic while the scene is lent (a bug in a callback) still gives it back.
        let (director, scene) = s.script_and_scene();
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            director.lend(scene, |_| panic!("a callback bug"))
        }));
        assert!(caught.is_err());
        assert_eq!(s.scene().actors().len(), 1);
        assert_eq!(s.scene().actors()[0].name, "ann");
    }

    fn session_with(limits: ScriptLimits) -> LuaSession {
        Director::session(SceneConfig::default(), ActionKinds::default(), limits).unwrap()
    }

    #[test]
    fn a_runaway_top_level_or_handler_is_stopped_even_under_pcall() {
        let mut s = session();
        let err = s
            .load_str(
                "while true do pcall(function() while true do end end) end",
                "top",
            )
            .unwrap_err()
            .to_string();
        assert!(err.contains("top:1: instruction budget exceeded"), "{err}");
        let err = s
            .eval::<()>("local ok = pcall(string.rep, 'x', 1 << 30); return ok")
            .unwrap_err()
            .to_string();
        assert!(err.contains("memory limit exceeded"), "{err}");
    }

    #[test]
    fn a_slow_leak_fills_the_scene_heap_and_fails_while_the_scene_goes_on() {
        let mut s = session_with(ScriptLimits {
            heap: 8 << 20,
            ..ScriptLimits::default()
        });
        s.load_str(
            "keep = {}
             troupe.actor{ name = 'leak' }:behave(function()
               while true do keep[#keep + 1] = string.rep('x', 256 * 1024) .. troupe.tick(); wait(0) end
             end)
             ticks = 0
             troupe.actor{ name = 'calm' }:behave(function()
               while true do ticks = ticks + 1; wait(0) end
             end)",
            "leak",
        )
        .unwrap();
        for _ in 0..100 {
            s.tick().unwrap();
        }
        let reports = s.behaviors();
        let leak = reports[0].error.clone().expect("the leak failed");
        assert!(leak.contains("Lua heap full"), "{leak}");
        assert!(leak.contains("--lua-memory"), "{leak}");
        // The leak kept its memory in a global: the calm behavior may fail too once the
        // heap is full, but the scene itself ticks on.
        assert_eq!(s.scene().tick(), 100);
    }

    #[test]
    fn a_table_raised_with_error_is_reported_with_its_place_and_fields() {
        let mut s = session();
        let err = s
            .load_str(
                "local x = 1\nerror({ msg = 'shut', code = 'blocked' })",
                "top",
            )
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("top:2: {code = \"blocked\", msg = \"shut\"}\nstack traceback:"),
            "{err}"
        );
        s.load_str(
            "troupe.actor{ name = 'ann' }:behave(function()
               wait(0)
               error({ 'a', n = 1.5, t = { 1 } })
             end)
             troupe.actor{ name = 'bob' }:behave(function() error(42) end)",
            "scene",
        )
        .unwrap();
        for _ in 0..3 {
            s.tick().unwrap();
        }
        let reports = s.behaviors();
        let ann = reports[0].error.clone().expect("ann failed");
        assert!(
            ann.starts_with("scene:3: {\"a\", n = 1.5, t = {1}}\nstack traceback:"),
            "{ann}"
        );
        assert!(ann.contains("[C]: in function 'error'"), "{ann}");
        // Any other value is Lua's text of it, as before.
        let bob = reports[1].error.clone().expect("bob failed");
        assert!(bob.starts_with("42\nstack traceback:"), "{bob}");
    }

    #[test]
    fn outside_a_phase_the_api_refuses_to_touch_a_scene() {
        let mut s = session();
        s.load_str("troupe.actor{ name = 'ann' }", "t").unwrap();
        let e = s
            .lua()
            .load("troupe.actor{ name = 'bob' }")
            .exec()
            .unwrap_err();
        assert!(e.to_string().contains("no scene is lent"), "{e}");
        assert_eq!(s.scene().actors().len(), 1);
        assert!(actor_skeletons(s.lua()).is_none());
        // Through the session it works.
        s.eval::<()>("troupe.actor{ name = 'bob' }").unwrap();
        assert_eq!(s.scene().actors().len(), 2);
    }
}
