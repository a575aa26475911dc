//! The torque log: the joint torques the dynamics actions apply, tick by tick (thesis
//! fig. 3-9), kept for `troupe run --record-torques`.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use troupe_motion::sequence::{Key, Track as SeqTrack};
use troupe_motion::Sequence;
use troupe_scene::Scene;

/// Per-DOF joint torques of the dynamics actions, recorded tick by tick on request
/// (`troupe run --record-torques FILE.trk`, thesis fig. 3-9). Install it on a director's
/// Lua state before the scene starts its actions: every dynamics action built afterwards
/// logs, each tick, the joint forces it applied over the tick (their mean over the
/// sub-steps; see `Simulation::mean_torques`) on the DOFs it simulates. Thread-safe; the
/// result does not depend on the scheduler's thread count (entries are keyed by actor,
/// DOF and tick; when two dynamics actions drive one DOF in the same tick their torques
/// add).
#[derive(Clone, Debug, Default)]
pub struct TorqueLog(Arc<Mutex<TorqueEntries>>);

/// Per (actor, DOF), per tick: (time, torque).
type TorqueEntries = BTreeMap<(usize, usize), BTreeMap<u64, (f64, f64)>>;

impl TorqueLog {
    /// An empty log.
    pub fn new() -> TorqueLog {
        TorqueLog::default()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, TorqueEntries> {
        // A panic while holding the lock leaves plain data: keep using it.
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds `torque` (N·m, or N for a translation) on DOF `dof` of actor `actor` at tick
    /// `tick` (scene time `time`).
    pub fn record(&self, actor: usize, dof: usize, tick: u64, time: f64, torque: f64) {
        let mut entries = self.lock();
        let e = entries
            .entry((actor, dof))
            .or_default()
            .entry(tick)
            .or_insert((time, 0.0));
        e.1 += torque;
    }

    /// Whether nothing was logged.
    pub fn is_empty(&self) -> bool {
        self.lock().is_empty()
    }

    /// Number of (actor, DOF, tick) entries.
    pub fn len(&self) -> usize {
        self.lock().values().map(|t| t.len()).sum()
    }

    /// One sequence per actor that has torques (named after the actor, in actor order),
    /// one track per DOF named after it, one key per tick: values in N·m (N for a
    /// translation), `meta quantity torque`.
    pub fn sequences(&self, scene: &Scene) -> Vec<Sequence> {
        let entries = self.lock();
        let mut set: Vec<Sequence> = Vec::new();
        let mut current: Option<usize> = None;
        for (&(actor, dof), ticks) in entries.iter() {
            let Some(info) = scene.actors().get(actor) else {
                continue;
            };
            if current != Some(actor) {
                current = Some(actor);
                let mut seq = Sequence::new(info.name.clone());
                seq.meta.insert("quantity".into(), "torque".into());
                seq.meta.insert(
                    "units".into(),
                    "N·m for rotation DOFs, N for translation DOFs".into(),
                );
                seq.meta
                    .insert("rate".into(), scene.config().rate.to_string());
                seq.meta.insert("template".into(), info.template.clone());
                seq.meta
                    .insert("source".into(), "troupe run --record-torques".into());
                set.push(seq);
            }
            let keys: Vec<Key> = ticks.values().map(|&(t, v)| Key::new(t, v)).collect();
            let name = info.skeleton.dofs()[dof].name.clone();
            if let (Ok(track), Some(seq)) = (SeqTrack::new(name, keys), set.last_mut()) {
                // One track per DOF: adding cannot clash.
                let _ = seq.add_track(track);
            }
        }
        set
    }
}
