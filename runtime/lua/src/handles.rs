//! The handles a script holds: actors, objects, actions, behaviors, event handlers and
//! sequences as Lua values. Their
//! methods are the API ([`crate::api`]); an action handle pins its action's final record
//! while it lives.

use mlua::Lua;
use std::sync::Arc;
use troupe_motion::sequence::Sequence;
use troupe_scene::action::ActionId;

/// A Lua handle on an actor.
#[derive(Clone, Copy, Debug)]
pub struct ActorRef(pub usize);
/// A Lua handle on a behavior (what `actor:behave` returns): its index in the director.
#[derive(Clone, Copy, Debug)]
pub struct BehaviorRef(pub usize);
/// A Lua handle on an event handler (what `actor:on` returns): its number.
#[derive(Clone, Copy, Debug)]
pub struct HandlerRef(pub u64);
/// A Lua handle on an object.
#[derive(Clone, Copy, Debug)]
pub struct ObjectRef(pub usize);
/// A Lua handle on an action. While a handle is alive, the scene keeps the action's
/// final record (see [`Pins`]).
#[derive(Debug)]
pub struct ActionRef(pub ActionId, Arc<Pins>);

/// Counts the live Lua handles of each action, so that the records of ended actions no
/// script can see any more can be forgotten.
#[derive(Debug, Default)]
pub struct Pins(std::sync::Mutex<std::collections::HashMap<ActionId, u32>>);

impl Pins {
    fn add(&self, id: ActionId) {
        *self.lock().entry(id).or_insert(0) += 1;
    }
    fn release(&self, id: ActionId) {
        let mut map = self.lock();
        if let Some(n) = map.get_mut(&id) {
            *n -= 1;
            if *n == 0 {
                map.remove(&id);
            }
        }
    }
    /// Whether a live handle refers to `id`.
    pub fn is_pinned(&self, id: ActionId) -> bool {
        self.lock().contains_key(&id)
    }
    fn lock(&self) -> std::sync::MutexGuard<'_, std::collections::HashMap<ActionId, u32>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl ActionRef {
    /// A new handle on `id` (pinning its record).
    pub fn new(lua: &Lua, id: ActionId) -> mlua::Result<ActionRef> {
        let pins = lua
            .app_data_ref::<Arc<Pins>>()
            .ok_or_else(|| mlua::Error::runtime("troupe: no scene is loaded"))?
            .clone();
        pins.add(id);
        Ok(ActionRef(id, pins))
    }
}

impl Drop for ActionRef {
    fn drop(&mut self) {
        self.1.release(self.0);
    }
}
/// A loaded sequence.
#[derive(Clone, Debug)]
pub struct SequenceRef(pub Arc<Sequence>);
