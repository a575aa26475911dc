//! Observers that write a run's outputs to files: what `--record`, `--record-torques` and
//! `--trace` attach to a session. The gathering lives in the runtime (the posture
//! recorder, the torque log, the timeline); writing files by format is the command line's.

use std::path::{Path, PathBuf};
use troupe_actions::dynamics::TorqueRecorder;
use troupe_scene::record::PostureRecorder;
use troupe_scene::timeline::TimelineRecorder;
use troupe_scene::{Event, Observer, Result, Scene};

/// `--record FILE`: every actor's postures and every object's pose and holders, written
/// at the end as `.trk`, `.bvh` or `.gltf` (one file per actor for the last two).
pub struct RecordFile {
    recorder: PostureRecorder,
    path: PathBuf,
}

impl RecordFile {
    /// Records to `path`.
    pub fn new(path: &Path) -> Self {
        RecordFile {
            recorder: PostureRecorder::new(),
            path: path.to_path_buf(),
        }
    }
}

impl Observer for RecordFile {
    fn name(&self) -> String {
        format!("--record {}", self.path.display())
    }

    fn start(&mut self, scene: &Scene) -> Result<()> {
        self.recorder.start(scene)
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()> {
        self.recorder.publish(scene, events)
    }

    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        // `.trk` holds every actor and object; `.bvh`, `.gltf` and `.glb` one actor each
        // (`NAME.ACTOR.EXT`), glTF with the objects, BVH with a file per object.
        // An actor dressed with `look = FILE` is written as that character in glTF.
        let written = troupe_formats::save_dressed_recording(
            &self.path,
            &self.recorder.sequences(scene),
            &self.recorder.objects(scene),
            scene
                .actors()
                .iter()
                .enumerate()
                .map(|(i, a)| (a.name.as_str(), &*a.skeleton, scene.look(i).map(|d| &**d))),
        )
        .map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        let list: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        Ok(Some(format!(
            "recorded {} ticks of postures{} to {}",
            self.recorder.len(),
            match scene.objects().len() {
                0 => String::new(),
                n => format!(" and {n} object(s)"),
            },
            list.join(", ")
        )))
    }
}

/// `--record-torques FILE.trk`: the joint torques of the dynamics actions, written at the
/// end.
pub struct TorqueFile {
    log: TorqueRecorder,
    path: PathBuf,
}

impl TorqueFile {
    /// Writes the torques of the run to `path`.
    pub fn new(path: &Path) -> Self {
        TorqueFile {
            log: TorqueRecorder::new(),
            path: path.to_path_buf(),
        }
    }
}

impl Observer for TorqueFile {
    fn name(&self) -> String {
        format!("--record-torques {}", self.path.display())
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()> {
        self.log.publish(scene, events)
    }

    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        let set = self.log.sequences(scene);
        if set.is_empty() {
            return Ok(Some(format!(
                "no dynamics action ran: no torques to record to {}",
                self.path.display()
            )));
        }
        troupe_formats::trk::write_trk(&self.path, &set)
            .map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        Ok(Some(format!(
            "recorded {} joint torques ({} actor(s)) to {}",
            self.log.len(),
            set.len(),
            self.path.display()
        )))
    }
}

/// `--trace FILE.json`: the action timeline as Chrome trace-event JSON.
pub struct TraceFile {
    timeline: TimelineRecorder,
    path: PathBuf,
}

impl TraceFile {
    /// Writes the timeline to `path`.
    pub fn new(path: &Path) -> Self {
        TraceFile {
            timeline: TimelineRecorder::new(),
            path: path.to_path_buf(),
        }
    }
}

impl Observer for TraceFile {
    fn name(&self) -> String {
        format!("--trace {}", self.path.display())
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()> {
        self.timeline.publish(scene, events)
    }

    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        let json = self.timeline.to_json(scene).to_string();
        std::fs::write(&self.path, json)
            .map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        Ok(Some(format!(
            "wrote the action timeline to {} (open in Perfetto or chrome://tracing)",
            self.path.display()
        )))
    }
}
