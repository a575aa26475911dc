//! The keyframe generator: plays a [`Sequence`] of Hermite tracks on a scope.

#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;

pub use options::KeyframeOptions;

use crate::error::{track_dofs, Result};
use std::sync::Arc;
use troupe_body::{Scope, Skeleton};
use troupe_motion::Sequence;
use troupe_scene::{ActionId, ActionSpec, DofWriter, Generator, GeneratorContext, Scene, Step};

/// Plays a sequence's tracks on the DOFs they name, from the sequence's first key time.
/// Actors playing the same sequence share its keys.
pub struct Keyframe {
    sequence: Arc<Sequence>,
    /// (DOF index, track index in the sequence, evaluation cursor)
    tracks: Vec<(usize, usize, usize)>,
    start: f64,
    length: f64,
    looping: bool,
    /// Seconds of the sequence it plays ahead of its own clock (see [`Keyframe::ahead`]);
    /// `None`: one tick for a recording from a run's start ([`recorded_from_the_start`]),
    /// else none.
    lead: Option<f64>,
    /// Whether the sequence is a recording of an actor from a run's start.
    recorded: bool,
    /// Whether every bound track has the same key times (sampled motion such as BVH):
    /// then the segment is found once per tick for all of them.
    shared_times: bool,
}

impl Keyframe {
    /// Binds `sequence` to `skeleton`. Tracks of DOFs outside `scope` are left out; every
    /// track must name a DOF of the skeleton. `looping` overrides the sequence's default.
    pub fn new(
        skeleton: &Skeleton,
        sequence: &Sequence,
        scope: Option<Scope>,
        looping: Option<bool>,
    ) -> Result<Keyframe> {
        Keyframe::shared(skeleton, Arc::new(sequence.clone()), scope, looping)
    }

    /// Like [`Keyframe::new`], sharing the sequence instead of copying it.
    pub fn shared(
        skeleton: &Skeleton,
        sequence: Arc<Sequence>,
        scope: Option<Scope>,
        looping: Option<bool>,
    ) -> Result<Keyframe> {
        let mut tracks = Vec::new();
        for (i, dof) in track_dofs(skeleton, &sequence, "sequence")?
            .into_iter()
            .enumerate()
        {
            if scope.is_none_or(|s| s.contains(dof)) {
                tracks.push((dof, i, 0));
            }
        }
        if tracks.is_empty() {
            return Err(options::no_track(&sequence).into());
        }
        let first = tracks.first().map(|&(_, i, _)| &sequence.tracks()[i]);
        let shared_times = first.is_some_and(|f| {
            tracks
                .iter()
                .all(|&(_, i, _)| sequence.tracks()[i].same_times(f))
        });
        Ok(Keyframe {
            shared_times,
            tracks,
            start: sequence.start(),
            length: sequence.duration(),
            looping: looping.unwrap_or(sequence.looping),
            lead: None,
            recorded: recorded_from_the_start(&sequence),
            sequence,
        })
    }

    /// The DOFs the sequence drives (the natural scope of the action).
    pub fn scope(&self) -> Scope {
        self.tracks.iter().map(|(d, _, _)| *d).collect()
    }

    /// The sequence's length in seconds.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Plays `seconds` ahead: its first tick shows the sequence at `seconds` past its
    /// first key (see [`replay`]), in place of the tick a recording is played ahead by.
    pub fn ahead(mut self, seconds: f64) -> Keyframe {
        self.lead = Some(seconds);
        self
    }
}

/// Whether `sequence` is a recording (`troupe run --record`) of an actor there from the
/// run's start: its first key, at time 0, is the posture before the run's first tick, and
/// each later key the posture a tick made. A keyframe action shows its sequence's first
/// key on its first tick, so it plays such a recording one tick ahead: each tick then
/// shows what the same tick of the recorded run made, not the tick before. (An actor
/// added during a run is first recorded after its first tick: its recording plays in step
/// as it is.)
fn recorded_from_the_start(sequence: &Sequence) -> bool {
    sequence
        .meta
        .get("source")
        .is_some_and(|s| s == "troupe run")
        && sequence.start() == 0.0
}

/// Replays `sequence`, a recording of an actor (`troupe run --record`: its first key the
/// posture the run started from, then one key per tick), on `actor` of `scene` in step
/// with the run it recorded: the actor is posed at the first key now, and every tick then
/// shows the posture recorded at the same scene time. (A keyframe action started now plays
/// such a recording in step too, one tick ahead of its clock, but leaves the actor as
/// it is until the coming tick; any other sequence it starts at its first key there.)
/// Returns the action and the recording's length in seconds.
pub fn replay(
    scene: &mut Scene,
    actor: usize,
    sequence: &Sequence,
    looping: Option<bool>,
) -> Result<(ActionId, f64)> {
    let skeleton = scene
        .actors()
        .get(actor)
        .ok_or_else(|| troupe_scene::Error::UnknownActor(format!("#{actor}")))?
        .skeleton
        .clone();
    let keyframe = Keyframe::new(&skeleton, sequence, None, looping)?.ahead(scene.dt());
    let first: Vec<(usize, f64)> = keyframe
        .tracks
        .iter()
        .map(|&(d, i, _)| (d, sequence.tracks()[i].value(keyframe.start)))
        .collect();
    scene.set_dofs(actor, &first)?;
    let length = keyframe.length();
    let spec = ActionSpec::new("keyframe", keyframe.scope());
    Ok((scene.start_action(actor, spec, Box::new(keyframe))?, length))
}

impl Generator for Keyframe {
    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let lead = match self.lead {
            Some(seconds) => seconds,
            None if self.recorded => ctx.dt,
            None => 0.0,
        };
        let mut t = ctx.local_time + lead;
        let finished = !self.looping && t >= self.length;
        if self.looping && self.length > 0.0 {
            t = t.rem_euclid(self.length);
        }
        let t = self.start + t.min(self.length);
        let tracks = self.sequence.tracks();
        if self.shared_times {
            let (_, first, cursor) = &mut self.tracks[0];
            let segment = tracks[*first].locate(t, cursor);
            for (dof, track, _) in self.tracks.iter() {
                out.set(*dof, tracks[*track].value_in(segment));
            }
        } else {
            for (dof, track, cursor) in self.tracks.iter_mut() {
                out.set(*dof, tracks[*track].value_at(t, cursor));
            }
        }
        if finished {
            Step::Finished
        } else {
            Step::Running
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_motion::{Key, Track};
    use troupe_scene::{ActionSpec, ActorDesc, Scene, SceneConfig};

    /// Plays `seq` and checks every tick against direct evaluation of its tracks.
    fn plays_exactly(seq: Sequence, shared: bool) {
        let mut scene = Scene::new(SceneConfig::default()).unwrap();
        let a = scene.add_actor(&ActorDesc::new("ann")).unwrap();
        let skel = scene.actors()[a].skeleton.clone();
        let gen = Keyframe::new(&skel, &seq, None, Some(false)).unwrap();
        assert_eq!(gen.shared_times, shared);
        scene
            .start_action(a, ActionSpec::new("keyframe", gen.scope()), Box::new(gen))
            .unwrap();
        for tick in 1..=130 {
            scene.step();
            let local = (tick - 1) as f64 * scene.dt();
            for track in seq.tracks() {
                let d = skel.dof(track.dof()).unwrap();
                let expected = track.value(local.min(seq.end()));
                let got = scene.states()[a].q[d];
                // Scene time and local time may differ in the last bit, and so the values.
                assert!(
                    (got - expected).abs() < 1e-12,
                    "{} at {local}: {got} vs {expected}",
                    track.dof()
                );
            }
        }
    }

    fn track(dof: &str, times: &[f64], scale: f64) -> Track {
        let keys = times
            .iter()
            .enumerate()
            .map(|(i, &t)| Key::new(t, ((i as f64) * 0.7).sin() * scale))
            .collect();
        Track::new(dof, keys).unwrap()
    }

    #[test]
    fn tracks_on_one_time_base_share_the_segment_search() {
        let times = [0.0, 0.3, 0.55, 0.9, 1.2];
        let mut seq = Sequence::new("shared");
        seq.add_track(track("r_elbow_flexion", &times, 0.5))
            .unwrap();
        seq.add_track(track("r_shoulder_flexion", &times, 0.4))
            .unwrap();
        seq.add_track(track("vl5_flexion", &times, 0.2)).unwrap();
        plays_exactly(seq, true);
    }

    /// Adds actor `name` to `scene`, playing `seq` once from the coming tick.
    fn add_playing(scene: &mut Scene, name: &str, seq: &Sequence) {
        let a = scene.add_actor(&ActorDesc::new(name)).unwrap();
        let skel = scene.actors()[a].skeleton.clone();
        let gen = Keyframe::new(&skel, seq, None, Some(false)).unwrap();
        let spec = ActionSpec::new("keyframe", gen.scope());
        scene.start_action(a, spec, Box::new(gen)).unwrap();
    }

    /// `ann` waves from the start and `cid`, added after `late` ticks, from then on, for
    /// `ticks` ticks: their recordings (`troupe run --record`) and, per tick, each one's
    /// elbow as it was (`None` before `cid` is there).
    fn recorded_waves(ticks: usize, late: usize) -> (Vec<Sequence>, Vec<[Option<f64>; 2]>) {
        let mut wave = Sequence::new("wave");
        let times = [0.0, 0.1, 0.25, 0.4, 0.6];
        wave.add_track(track("r_elbow_flexion", &times, 0.8))
            .unwrap();
        let mut scene = Scene::new(SceneConfig::default()).unwrap();
        let mut recorder = troupe_scene::record::PostureRecorder::new();
        add_playing(&mut scene, "ann", &wave);
        recorder.sample(&scene);
        let elbow = scene.actors()[0].skeleton.dof("r_elbow_flexion").unwrap();
        let mut seen = Vec::new();
        for tick in 0..ticks {
            if tick == late {
                add_playing(&mut scene, "cid", &wave);
            }
            scene.step();
            recorder.sample(&scene);
            let q = |a: usize| scene.states().get(a).map(|s| s.q[elbow]);
            seen.push([q(0), q(1)]);
        }
        (recorder.sequences(&scene), seen)
    }

    #[test]
    fn a_recording_plays_in_step_with_the_run_it_recorded() {
        let (ticks, late) = (40, 15);
        let (recorded, seen) = recorded_waves(ticks, late);
        let mut scene = Scene::new(SceneConfig::default()).unwrap();
        // bob plays ann's part from the start; dee, added when cid was, plays cid's.
        add_playing(&mut scene, "bob", &recorded[0]);
        let elbow = scene.actors()[0].skeleton.dof("r_elbow_flexion").unwrap();
        for (tick, was) in seen.iter().enumerate() {
            if tick == late {
                add_playing(&mut scene, "dee", &recorded[1]);
            }
            scene.step();
            for (a, was) in was.iter().enumerate() {
                let now = scene.states().get(a).map(|s| s.q[elbow]);
                let (Some(was), Some(now)) = (was, now) else {
                    assert_eq!(was.is_some(), now.is_some(), "tick {tick}: actor {a}");
                    continue;
                };
                // It was a tick behind: the first tick showed the posture before the
                // recorded run's first tick.
                assert!(
                    (now - was).abs() < 1e-9,
                    "tick {} ({} s), actor {a}: played {now}, recorded {was}",
                    tick + 1,
                    scene.time()
                );
            }
        }
    }

    #[test]
    fn tracks_on_different_times_are_searched_one_by_one() {
        let mut seq = Sequence::new("mixed");
        seq.add_track(track("r_elbow_flexion", &[0.0, 0.4, 1.0], 0.5))
            .unwrap();
        seq.add_track(track("vl5_flexion", &[0.0, 0.3, 0.6, 1.2], 0.2))
            .unwrap();
        plays_exactly(seq, false);
    }
}
