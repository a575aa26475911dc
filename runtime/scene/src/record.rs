//! Recording postures tick by tick into sequences (one per actor), and objects' poses
//! and holders into [`ObjectMotion`]s, for `.trk` (and glTF) output.

use crate::action::Event;
use crate::error::Result;
use crate::scene::Scene;
use crate::session::Observer;
use troupe_body::glam::{DQuat, DVec3};
use troupe_motion::object_motion::{Hold, ObjectMotion};
use troupe_motion::sequence::{Key, Sequence, Track};

/// Collects every actor's DOF values and every object's pose and holder at every tick.
#[derive(Debug, Default)]
pub struct PostureRecorder {
    times: Vec<f64>,
    /// Per actor, per DOF, the values at each recorded time.
    values: Vec<Vec<Vec<f64>>>,
    /// Per object, its pose at each recorded time since it appeared.
    poses: Vec<Vec<(DVec3, DQuat)>>,
    /// Per object, who held it (actor, joint) at each recorded time since it appeared.
    holders: Vec<Vec<Option<(usize, usize)>>>,
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
        for (o, object) in scene.objects().iter().enumerate() {
            if self.poses.len() <= o {
                // An object added mid-run starts its tracks now.
                self.poses.push(Vec::new());
                self.holders.push(Vec::new());
            }
            self.poses[o].push((object.position, object.rotation));
            self.holders[o].push(scene.holder(o).map(|h| (h.actor, h.joint)));
        }
    }

    /// One [`ObjectMotion`] per object: its pose tracks and the spans during which an
    /// actor held it (a span still open at the end closes at the last recorded time).
    pub fn objects(&self, scene: &Scene) -> Vec<ObjectMotion> {
        let mut out = Vec::new();
        for (o, poses) in self.poses.iter().enumerate() {
            let object = &scene.objects()[o];
            let times = &self.times[self.times.len() - poses.len()..];
            let Ok(mut motion) =
                ObjectMotion::from_samples(&object.name, object.shape, object.mass, times, poses)
            else {
                continue; // cannot happen: one pose per time, at least one
            };
            let holders = &self.holders[o];
            let mut i = 0;
            while i < holders.len() {
                let Some((actor, joint)) = holders[i] else {
                    i += 1;
                    continue;
                };
                let start = i;
                while i < holders.len() && holders[i] == Some((actor, joint)) {
                    i += 1;
                }
                let info = &scene.actors()[actor];
                motion.holds.push(Hold {
                    from: times[start],
                    to: times[i.min(holders.len() - 1)],
                    actor: info.name.clone(),
                    joint: info.skeleton.joints()[joint].name.clone(),
                });
            }
            out.push(motion);
        }
        out
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
