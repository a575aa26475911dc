//! The action timeline in Chrome trace-event JSON (Perfetto, chrome://tracing): one track
//! per actor, one span per action phase.

use crate::action::{ActionId, Event, Status};
use crate::error::Result;
use crate::scene::Scene;
use crate::session::Observer;
use serde_json::{json, Value};
use std::collections::HashMap;

/// Builds spans from the scheduler's events.
#[derive(Debug, Default)]
pub struct TimelineRecorder {
    open: HashMap<ActionId, (Status, f64)>,
    spans: Vec<Value>,
}

impl TimelineRecorder {
    /// An empty timeline.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a tick's events.
    pub fn record(&mut self, scene: &Scene, events: &[Event]) {
        for e in events {
            if let Some(taken) = e.narrowed {
                self.narrowed(scene, e, taken);
                continue;
            }
            if let Some((phase, since)) = self.open.remove(&e.action) {
                self.span(scene, e, phase, since);
            }
            if e.status.is_running() {
                self.open.insert(e.action, (e.status, e.time));
            }
        }
    }

    /// An instant event on the actor's track: the action gave up `taken` to another.
    fn narrowed(&mut self, scene: &Scene, e: &Event, taken: troupe_body::scope::Scope) {
        self.spans.push(json!({
            "name": format!("{} narrowed", e.kind),
            "cat": e.kind,
            "ph": "i",
            "s": "t",
            "pid": 1,
            "tid": e.actor,
            "ts": e.time * 1e6,
            "args": { "action": e.action.0, "yielded": scope_name(scene, e.actor, taken) },
        }));
    }

    fn span(&mut self, scene: &Scene, e: &Event, phase: Status, since: f64) {
        let info = scene.action(e.action);
        let (scope, mode) = info
            .map(|a| (scope_name(scene, e.actor, a.scope), a.mode.name()))
            .unwrap_or_default();
        self.spans.push(json!({
            "name": format!("{} {}", e.kind, phase.name()),
            "cat": e.kind,
            "ph": "X",
            "pid": 1,
            "tid": e.actor,
            "ts": since * 1e6,
            "dur": (e.time - since) * 1e6,
            "args": { "action": e.action.0, "scope": scope, "mode": mode, "phase": phase.name(),
                      "ended_as": if e.status.is_final() { e.status.name() } else { "" } },
        }));
    }

    /// The trace as JSON; actions still running are closed at the scene's current time.
    pub fn to_json(&mut self, scene: &Scene) -> Value {
        let mut open: Vec<_> = self.open.drain().collect();
        open.sort_by_key(|(id, _)| *id);
        for (id, (phase, since)) in open {
            if let Some(info) = scene.action(id) {
                let e = Event {
                    tick: scene.tick(),
                    time: scene.time(),
                    actor: info.actor,
                    action: id,
                    kind: info.kind.clone(),
                    status: info.status,
                    reason: None,
                    narrowed: None,
                };
                self.span(scene, &e, phase, since);
            }
        }
        let mut events: Vec<Value> = scene
            .actors()
            .iter()
            .enumerate()
            .map(|(i, a)| json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": i, "args": {"name": a.name}}))
            .collect();
        events.push(
            json!({"name": "process_name", "ph": "M", "pid": 1, "args": {"name": "troupe scene"}}),
        );
        events.extend(self.spans.iter().cloned());
        json!({ "traceEvents": events, "displayTimeUnit": "ms" })
    }
}

/// The name of `scope` among the actor's named scopes, or its size.
fn scope_name(scene: &Scene, actor: usize, scope: troupe_body::scope::Scope) -> String {
    scene.actors()[actor]
        .skeleton
        .scopes()
        .iter()
        .find(|(_, s)| **s == scope)
        .map(|(n, _)| n.clone())
        .unwrap_or_else(|| format!("{} DOFs", scope.len()))
}

impl Observer for TimelineRecorder {
    fn name(&self) -> String {
        "action timeline".into()
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()> {
        self.record(scene, events);
        Ok(())
    }
}
