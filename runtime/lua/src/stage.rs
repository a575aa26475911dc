//! What the Lua callbacks reach: the stage (the lent scene, the behaviors, the handlers)
//! kept in the Lua state's app data, and the ways to borrow it.

use mlua::{Function, Lua, Thread};
use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::Arc;
use troupe_motion::sequence::Sequence;
use troupe_scene::action::{ActionId, Event};
use troupe_scene::scene::Scene;

/// What a behavior waits for.
#[derive(Clone, Debug)]
pub(crate) enum Wait {
    /// Resume on the next tick (just created, or yielded without a condition).
    NextTick,
    /// Resume once scene time reaches this.
    Time(f64),
    /// Resume with the action's final status once it ends.
    Action(ActionId),
    /// Resume once all these have ended.
    All(Vec<ActionId>),
    /// Resume with the first of these that ends.
    Any(Vec<ActionId>),
    /// Resume with `true` once the predicate holds, `false` at the deadline.
    Until(Function, Option<f64>),
    /// Resume with the behavior's final status and error once it has ended.
    Behavior(usize),
}

/// Where a behavior is.
#[derive(Clone, Debug)]
pub(crate) enum BehaviorState {
    Waiting(Wait),
    Done,
    Failed(String),
    /// Stopped by its handle's `:stop()`.
    Stopped,
}

impl BehaviorState {
    /// The name scripts and reports see: `running`, `done`, `failed` or `stopped`.
    pub(crate) fn name(&self) -> &'static str {
        match self {
            BehaviorState::Waiting(_) => "running",
            BehaviorState::Done => "done",
            BehaviorState::Failed(_) => "failed",
            BehaviorState::Stopped => "stopped",
        }
    }

    /// The error of a failed behavior.
    pub(crate) fn error(&self) -> Option<&str> {
        match self {
            BehaviorState::Failed(e) => Some(e),
            _ => None,
        }
    }
}

/// An event handler registered with `actor:on(event, fn)`.
#[derive(Clone)]
pub(crate) struct Handler {
    /// Its number, which its handle's `:off()` names.
    pub id: u64,
    pub actor: usize,
    pub event: String,
    pub function: Function,
}

pub(crate) struct Behavior {
    pub actor: Option<usize>,
    /// The coroutine, until the behavior ends (then dropped, so that what it held can
    /// be collected).
    pub thread: Option<Thread>,
    pub state: BehaviorState,
    /// Whether the coroutine has been resumed once (its first resume passes `self`).
    pub started: bool,
    /// Whether its wait on actions has been checked against the scene once; after that,
    /// only an action ending can make it due (see [`Stage::ended_last_step`]).
    pub checked: bool,
    /// Whether another behavior (or the test) has waited for this one with
    /// `handle:wait()`: its failure is then the waiter's to judge (a test expecting it
    /// does not fail because of it).
    pub awaited: bool,
}

/// Everything Lua callbacks reach: kept in the Lua state's app data.
pub(crate) struct Stage {
    /// The session's scene while it is lent to the director (the script phase, loading a
    /// file); an empty scene of the same configuration otherwise.
    pub scene: Scene,
    /// Whether `scene` is the session's (lent for a load or a script phase).
    pub lent: bool,
    pub behaviors: Vec<Behavior>,
    pub handlers: Vec<Handler>,
    /// The number the next handler gets.
    pub next_handler: u64,
    pub pending_events: Vec<Event>,
    /// Actions that ended in the scene steps since the behaviors last ran. Every end of
    /// an action is such an event, so a behavior waiting on actions needs looking at only
    /// when one of its actions is here: with 1,000 behaviors, looking up every awaited
    /// action on every tick cost 5 % of the tick in cache misses.
    pub ended_last_step: HashSet<ActionId>,
    pub base_dir: PathBuf,
    pub current_actor: Option<usize>,
    /// Loaded sequences by path (and skeleton, for retargeted BVH).
    pub sequences: HashMap<(PathBuf, Option<usize>), Arc<Sequence>>,
    /// The sequences of `.trk` files read for one actor's part (a recording of several
    /// actors: see [`crate::api::load_part`]), by path.
    pub recordings: HashMap<PathBuf, Arc<Vec<Arc<Sequence>>>>,
    /// `test(name, fn[, { timeout }])` calls, in order: the name, the function and the
    /// test's own timeout (simulated seconds), if it gave one.
    pub tests: Vec<(String, Function, Option<f64>)>,
    pub handler_failures: Vec<(usize, String)>,
    /// `troupe.subscribe` calls, in order: the key expression and the function to call.
    pub subscriptions: Vec<(String, Function)>,
    /// Every file the scene read (the scene, its modules, its motion files), in order.
    pub loaded_files: Vec<PathBuf>,
}

/// The stage of the Lua state `lua`, mutably (for a callback; never across a Lua call).
pub(crate) fn stage(lua: &Lua) -> mlua::Result<mlua::AppDataRefMut<'_, Stage>> {
    let stage = lua
        .app_data_mut::<Stage>()
        .ok_or_else(|| mlua::Error::runtime("troupe: no scene is loaded"))?;
    if stage.lent {
        Ok(stage)
    } else {
        Err(not_lent())
    }
}

/// The error of a call that needs the scene while none is lent to the director.
fn not_lent() -> mlua::Error {
    mlua::Error::runtime(
        "troupe: no scene is lent to the script (scene calls work while a scene loads and \
         in a session's script phase)",
    )
}

/// Adds a behavior: a coroutine of `f`, resumed on the next tick with its actor as `self`.
/// Returns its index (behaviors are never removed, so it names it for good).
pub(crate) fn add_behavior(lua: &Lua, actor: Option<usize>, f: Function) -> mlua::Result<usize> {
    let thread = lua.create_thread(f.clone())?;
    // Its waits are the director's to answer (see the prelude's `must_yield`).
    let own: Function = lua.named_registry_value("troupe.own_thread")?;
    own.call::<()>(&thread)?;
    let mut st = lua
        .app_data_mut::<Stage>()
        .ok_or_else(|| mlua::Error::runtime("troupe: no scene is loaded"))?;
    // The behavior receives its actor as `self`.
    st.behaviors.push(Behavior {
        actor,
        thread: Some(thread),
        state: BehaviorState::Waiting(Wait::NextTick),
        started: false,
        checked: false,
        awaited: false,
    });
    Ok(st.behaviors.len() - 1)
}

/// Reads the scene of the Lua state `lua` (for functions registered with
/// [`ActionKinds::register_function`](crate::kinds::ActionKinds::register_function)).
/// Do not call Lua from inside `f`.
pub fn with_scene<R>(lua: &Lua, f: impl FnOnce(&Scene) -> R) -> mlua::Result<R> {
    let stage = lua
        .app_data_ref::<Stage>()
        .ok_or_else(|| mlua::Error::runtime("troupe: no scene is loaded"))?;
    if !stage.lent {
        return Err(not_lent());
    }
    Ok(f(&stage.scene))
}

/// Changes the scene of the Lua state `lua`. Do not call Lua from inside `f`.
pub fn with_scene_mut<R>(lua: &Lua, f: impl FnOnce(&mut Scene) -> R) -> mlua::Result<R> {
    let mut stage = stage(lua)?;
    Ok(f(&mut stage.scene))
}

/// Skeletons of the scene's actors, by index: for crates that extend the Lua API (e.g.
/// performers) and need an actor's body while a script runs. `None` outside a director.
pub fn actor_skeletons(lua: &Lua) -> Option<Vec<Arc<troupe_body::skeleton::Skeleton>>> {
    let st = lua.app_data_ref::<Stage>().filter(|st| st.lent)?;
    Some(
        st.scene
            .actors()
            .iter()
            .map(|a| a.skeleton.clone())
            .collect(),
    )
}

/// The folder of the scene file being run (relative paths in scripts resolve against it).
pub fn scene_dir(lua: &Lua) -> Option<PathBuf> {
    Some(lua.app_data_ref::<Stage>()?.base_dir.clone())
}
