//! The torque recorder: the joint torques the dynamics actions apply, tick by tick (thesis
//! fig. 3-9), kept for `troupe run --record-torques`.

use std::collections::BTreeMap;
use troupe_motion::sequence::{Key, Track as SeqTrack};
use troupe_motion::Sequence;
use troupe_scene::{Event, Observer, Result, Scene};

/// Per-DOF joint torques of the dynamics actions, gathered from the scene's blackboard
/// after every tick (`troupe run --record-torques FILE.trk`, thesis fig. 3-9): each
/// dynamics action posts the joint forces it applied over the tick (their mean over the
/// sub-steps; see `Simulation::mean_torques`) on the DOFs it simulates, and two actions
/// on one DOF add up. The blackboard is filled serially in actor order, so the record does
/// not depend on the scheduler's thread count.
#[derive(Clone, Debug, Default)]
pub struct TorqueRecorder {
    entries: TorqueEntries,
}

/// Per (actor, DOF), per tick: (time, torque).
type TorqueEntries = BTreeMap<(usize, usize), BTreeMap<u64, (f64, f64)>>;

impl TorqueRecorder {
    /// An empty record.
    pub fn new() -> TorqueRecorder {
        TorqueRecorder::default()
    }

    /// Adds the torques of the tick `scene` has just stepped.
    pub fn sample(&mut self, scene: &Scene) {
        let (tick, time) = (scene.tick(), scene.time());
        for t in scene.blackboard().torques() {
            self.entries
                .entry((t.actor, t.dof))
                .or_default()
                .insert(tick, (time, t.torque));
        }
    }

    /// Whether nothing was logged.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Number of (actor, DOF, tick) entries.
    pub fn len(&self) -> usize {
        self.entries.values().map(|t| t.len()).sum()
    }

    /// One sequence per actor that has torques (named after the actor, in actor order),
    /// one track per DOF named after it, one key per tick: values in N·m (N for a
    /// translation), `meta quantity torque`.
    pub fn sequences(&self, scene: &Scene) -> Vec<Sequence> {
        let entries = &self.entries;
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

impl Observer for TorqueRecorder {
    fn name(&self) -> String {
        "torque recorder".into()
    }

    fn publish(&mut self, scene: &Scene, _events: &[Event]) -> Result<()> {
        self.sample(scene);
        Ok(())
    }
}
