//! Recording postures tick by tick into sequences (one per actor), for `.trk` output.

use crate::action::Event;
use crate::error::Result;
use crate::scene::Scene;
use crate::session::Observer;
use troupe_motion::sequence::{Key, Sequence, Track};

/// Collects every actor's DOF values at every tick.
#[derive(Debug, Default)]
pub struct PostureRecorder {
    times: Vec<f64>,
    /// Per actor, per DOF, the values at each recorded time.
    values: Vec<Vec<Vec<f64>>>,
}

impl PostureRecorder {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records the scene's current postures.
    pub fn sample(&mut self, scene: &Scene) {
        self.times.push(scene.time());
        for (a, state) in scene.states().iter().enumerate() {
            if self.values.len() <= a {
                // An actor added mid-run starts its tracks now.
                self.values.push(vec![Vec::new(); state.q.len()]);
            }
            for (d, v) in state.q.iter().enumerate() {
                self.values[a][d].push(*v);
            }
        }
    }

    /// Number of samples taken.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// One sequence per actor (named after it), one track per DOF. Keys inside a run of
    /// equal values are dropped: the run's first and last keys hold it exactly.
    pub fn sequences(&self, scene: &Scene) -> Vec<Sequence> {
        let mut set = Vec::new();
        for (a, dofs) in self.values.iter().enumerate() {
            let info = &scene.actors()[a];
            let mut seq = Sequence::new(info.name.clone());
            seq.meta
                .insert("rate".into(), scene.config().rate.to_string());
            seq.meta.insert("template".into(), info.template.clone());
            seq.meta
                .insert("height".into(), info.params.height.to_string());
            seq.meta.insert("source".into(), "troupe run".into());
            let offset = self.times.len() - dofs[0].len();
            let times = &self.times[offset..];
            for (d, values) in dofs.iter().enumerate() {
                let keys: Vec<Key> = (0..values.len())
                    .filter(|&i| {
                        i == 0
                            || i + 1 == values.len()
                            || values[i] != values[i - 1]
                            || values[i] != values[i + 1]
                    })
                    .map(|i| Key::new(times[i], values[i]))
                    .collect();
                if let Ok(track) = Track::new(info.skeleton.dofs()[d].name.clone(), keys) {
                    // Names are unique per skeleton, so adding cannot clash.
                    let _ = seq.add_track(track);
                }
            }
            set.push(seq);
        }
        set
    }
}

impl Observer for PostureRecorder {
    fn name(&self) -> String {
        "posture recorder".into()
    }

    /// Records the postures the run starts from.
    fn start(&mut self, scene: &Scene) -> Result<()> {
        self.sample(scene);
        Ok(())
    }

    fn publish(&mut self, scene: &Scene, _events: &[Event]) -> Result<()> {
        self.sample(scene);
        Ok(())
    }
}
